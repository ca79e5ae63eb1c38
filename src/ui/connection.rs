//! The top bar: port picker, baud, profile, answer margin, connect/disconnect, link state,
//! language. Its content keeps its width, so that the panels below never move.

use super::Action;
use super::settings::Settings;
use super::state::{AppState, Target};
use crate::i18n::Lang;
use crate::link::LinkState;
use crate::sim::SimKind;
use eframe::egui;

/// Answer margins offered, ms (`None`: the protocol's own).
const MARGINS: [Option<u64>; 8] = [
    None,
    Some(2),
    Some(5),
    Some(10),
    Some(20),
    Some(50),
    Some(100),
    Some(300),
];

const BAUDS: [u32; 11] = [
    9600, 19_200, 38_400, 57_600, 115_200, 230_400, 250_000, 460_800, 500_000, 921_600, 1_000_000,
];

/// The bar's fields before Connect is pressed.
pub struct ConnectionBar {
    target: Target,
    baud: u32,
    profile: String,
    /// How long the device may take to start answering, ms (`None`: the protocol's own).
    margin_ms: Option<u64>,
    /// A path typed by hand (a pseudo-terminal is not listed by the OS).
    typed: String,
}

impl ConnectionBar {
    /// Fields from the saved settings.
    pub fn new(saved: &Settings) -> Self {
        Self {
            target: saved.target.clone(),
            baud: saved.baud,
            profile: saved.profile.clone(),
            margin_ms: saved.margin_ms,
            typed: match &saved.target {
                Target::Port(p) => p.clone(),
                Target::Demo(_) => String::new(),
            },
        }
    }

    /// Draws the bar.
    pub fn show(&mut self, ui: &mut egui::Ui, saved: &Settings, rt: &AppState) -> Vec<Action> {
        let lang = saved.lang;
        let mut actions = Vec::new();
        ui.horizontal_wrapped(|ui| {
            let port_label = ui.label(lang.tr("Port", "端口"));
            egui::ComboBox::from_id_salt("port")
                .width(220.0)
                .selected_text(self.target.label())
                .show_ui(ui, |ui| {
                    for kind in SimKind::ALL {
                        let t = Target::Demo(kind.name().to_string());
                        let label = format!("{} ({})", lang.tr("Demo", "演示"), kind.describe());
                        if ui.selectable_label(self.target == t, label).clicked() {
                            self.profile = kind.profile_id().to_string();
                            self.baud = kind.default_baud();
                            self.target = t;
                        }
                    }
                    ui.separator();
                    if rt.link.ports.is_empty() {
                        ui.weak(lang.tr("no serial ports found", "未找到串口"));
                    }
                    for p in &rt.link.ports {
                        let t = Target::Port(p.path.clone());
                        if ui.selectable_label(self.target == t, p.label()).clicked() {
                            self.typed = p.path.clone();
                            self.target = t;
                        }
                    }
                })
                .response
                .labelled_by(port_label.id);
            let typed = ui
                .add(
                    egui::TextEdit::singleline(&mut self.typed)
                        .hint_text(
                            lang.tr("or a path, e.g. /dev/pts/3", "或输入路径,如 /dev/pts/3"),
                        )
                        .desired_width(150.0),
                )
                .labelled_by(port_label.id);
            if typed.changed() && !self.typed.trim().is_empty() {
                self.target = Target::Port(self.typed.trim().to_string());
            }
            let baud_label = ui.label(lang.tr("Baud", "波特率"));
            egui::ComboBox::from_id_salt("baud")
                .selected_text(self.baud.to_string())
                .show_ui(ui, |ui| {
                    for b in BAUDS {
                        ui.selectable_value(&mut self.baud, b, b.to_string());
                    }
                })
                .response
                .labelled_by(baud_label.id);
            let profile_label = ui.label(lang.tr("Profile", "设备配置"));
            egui::ComboBox::from_id_salt("profile")
                .selected_text(&self.profile)
                .show_ui(ui, |ui| {
                    for (p, _) in rt.registry.iter() {
                        let label = format!("{} — {}", p.id, lang.tr(&p.name.en, &p.name.zh));
                        ui.selectable_value(&mut self.profile, p.id.clone(), label);
                    }
                })
                .response
                .labelled_by(profile_label.id);
            let margin_label = ui
                .label(lang.tr("Margin", "应答余量"))
                .on_hover_text(lang.tr(
                    "How long the device may take to start answering, beyond the bytes' wire time. \
                 Auto: the device's own (MSP 20 ms, servo 1.5 ms, Tuya 300 ms) plus the USB \
                 adapter's latency timer where the system tells it, or the answer latency \
                 measured on this connection, whichever is more.",
                    "设备开始应答前允许的时间(不含字节在线路上的传输时间)。自动: 设备自身的余量\
                 (MSP 20 ms, 舵机 1.5 ms, 涂鸦 300 ms)加上系统给出的 USB 适配器延迟定时器,\
                 或本次连接实测的应答延迟, 取较大者。",
                ));
            let shown = |m: Option<u64>| match m {
                None => lang.tr("auto", "自动").to_string(),
                Some(ms) => format!("{ms} ms"),
            };
            egui::ComboBox::from_id_salt("margin")
                .selected_text(shown(self.margin_ms))
                .show_ui(ui, |ui| {
                    for m in MARGINS {
                        ui.selectable_value(&mut self.margin_ms, m, shown(m));
                    }
                })
                .response
                .labelled_by(margin_label.id);
            let connect = || Action::Connect {
                target: self.target.clone(),
                baud: self.baud,
                profile: self.profile.clone(),
                margin_ms: self.margin_ms,
            };
            let open = rt.link.connection.is_some();
            if open {
                if ui.button(lang.tr("Disconnect", "断开")).clicked() {
                    actions.push(Action::Disconnect);
                }
            } else if ui.button(lang.tr("Connect", "连接")).clicked() {
                actions.push(connect());
            }
            if open
                && (self.target != saved.target
                    || self.baud != saved.baud
                    || self.profile != saved.profile
                    || self.margin_ms != saved.margin_ms)
                && ui.button(lang.tr("Reconnect", "重新连接")).clicked()
            {
                actions.push(connect());
            }
            ui.separator();
            state_badge(ui, lang, rt);
            if rt.link.connection.is_some() {
                timing(ui, lang, rt, &mut actions);
            }
            ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                let next = match lang {
                    Lang::En => Lang::Zh,
                    Lang::Zh => Lang::En,
                };
                let label = match lang {
                    Lang::En => "中文",
                    Lang::Zh => "English",
                };
                if ui.button(label).on_hover_text("Language / 语言").clicked() {
                    actions.push(Action::SetLanguage(next));
                }
            });
        });
        actions
    }
}

fn state_badge(ui: &mut egui::Ui, lang: Lang, rt: &AppState) {
    let (text, color) = match (&rt.link.connection, &rt.link.state) {
        (None, _) => (
            lang.tr("not connected", "未连接").to_string(),
            egui::Color32::GRAY,
        ),
        (Some(_), Some(LinkState::Connected { .. })) => (
            lang.tr("● connected", "● 已连接").to_string(),
            egui::Color32::from_rgb(40, 160, 60),
        ),
        (Some(_), Some(LinkState::Reconnecting { attempt })) => (
            format!("{} ({attempt})", lang.tr("● reconnecting", "● 重连中")),
            egui::Color32::from_rgb(220, 150, 0),
        ),
        (Some(_), Some(LinkState::Lost { .. })) => (
            lang.tr("● lost", "● 连接丢失").to_string(),
            egui::Color32::RED,
        ),
        (Some(_), Some(LinkState::Closed)) => {
            (lang.tr("closed", "已关闭").to_string(), egui::Color32::GRAY)
        }
        (Some(_), None) => (
            lang.tr("opening…", "打开中…").to_string(),
            egui::Color32::GRAY,
        ),
    };
    ui.colored_label(color, text);
}

/// The margin in use, the answer latency measured, and the USB adapter's latency timer with a
/// button to set it to 1 ms where the system lets us.
fn timing(ui: &mut egui::Ui, lang: Lang, rt: &AppState, actions: &mut Vec<Action>) {
    let stats = &rt.link.stats;
    let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3;
    if let Some(m) = stats.margin {
        let mut text = format!("{} {:.1} ms", lang.tr("margin", "余量"), ms(m));
        if let Some(l) = stats.answer_latency {
            text.push_str(&format!(
                " ({} {:.1} ms)",
                lang.tr("measured", "实测"),
                ms(l)
            ));
        }
        ui.weak(text).on_hover_text(format!(
            "{}: {}",
            lang.tr("late answers", "迟到应答"),
            stats.late_answers
        ));
    }
    let Some((port, adapter)) = rt.link.adapter() else {
        return;
    };
    match adapter.latency_timer_ms {
        Some(t) => {
            let color = if t > 1 {
                egui::Color32::from_rgb(220, 150, 0)
            } else {
                ui.visuals().weak_text_color()
            };
            ui.colored_label(
                color,
                format!("{} {t} ms", lang.tr("latency timer", "延迟定时器")),
            )
            .on_hover_text(adapter.summary());
            if t > 1 {
                let set = ui
                    .add_enabled(
                        adapter.latency_timer_writable,
                        egui::Button::new(lang.tr("Set to 1 ms", "设为 1 ms")),
                    )
                    .on_hover_text(lang.tr(
                        "Answers reach botbench up to 1 ms after they arrive instead of 16",
                        "应答到达后最多 1 ms 即交给 botbench, 而不是 16 ms",
                    ))
                    .on_disabled_hover_text(format!(
                        "{} sudo botbench ports --set-latency-timer {port} 1",
                        lang.tr(
                            "The file is writable by root only: run",
                            "该文件仅 root 可写, 请运行"
                        )
                    ));
                if set.clicked() {
                    actions.push(Action::SetLatencyTimer {
                        port: port.to_string(),
                        ms: 1,
                    });
                }
            }
        }
        None => {
            if let Some(note) = &adapter.note {
                ui.weak(lang.tr("no latency timer", "无延迟定时器"))
                    .on_hover_text(note);
            }
        }
    }
}
