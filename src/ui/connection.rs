//! The top bar: port picker, baud, profile, answer margin, connect/disconnect, link state,
//! language. Its content keeps its width, so that the panels below never move.

use super::Action;
use super::settings::{PortSettings, Settings};
use super::station::{Answering, Station, Target};
use crate::i18n::{Key, Lang, Text};
use crate::link::LinkState;
use crate::link::silent::{self, SettingNames, SilentCheck};
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
    /// The port's other settings for this profile: margin, DTR, RTS, boot wait (its `baud` is
    /// `self.baud`, put in at Connect).
    options: PortSettings,
    /// The port options' number fields as typed, and why they are refused when they are.
    typed_options: super::port_options::Typed,
    /// A path typed by hand (a pseudo-terminal is not listed by the OS).
    typed: String,
    /// The rate the open port was last seen at ([`Station`]'s link, while connected): when the
    /// port moves to another rate (a servo's baud change, a search at several rates), the bar
    /// follows it, unless the technician has picked another rate to reconnect with.
    port_rate: Option<u32>,
}

/// A margin this many times the protocol's own is worth a warning: every request that goes
/// unanswered (each id a scan asks) waits that long.
const MARGIN_WARN_FACTOR: f64 = 4.0;

impl ConnectionBar {
    /// Fields from the saved settings, at `baud` (the profile's saved or usual rate).
    pub fn new(saved: &Settings, baud: u32) -> Self {
        Self {
            target: saved.target.clone(),
            baud,
            profile: saved.profile.clone(),
            options: saved.port_of(&saved.profile),
            typed_options: super::port_options::Typed::default(),
            typed: match &saved.target {
                Target::Port(p) => p.clone(),
                Target::Demo(_) => String::new(),
            },
            port_rate: None,
        }
    }

    /// Follows the port's rate: when the open port is at another rate than last seen, the bar
    /// shows it, unless the bar's rate was already another one (the technician picked a rate
    /// to reconnect with, which is kept). Forgotten when no link is open.
    fn follow_port(&mut self, rt: &Station) {
        if rt.link.connection.is_none() {
            self.port_rate = None;
            return;
        }
        let Some(now) = rt.link.baud() else {
            return;
        };
        if self.port_rate == Some(now) {
            return;
        }
        if self.port_rate.is_none_or(|was| was == self.baud) {
            self.baud = now;
        }
        self.port_rate = Some(now);
    }

    /// The profile the bar would connect with.
    pub fn profile(&self) -> &str {
        &self.profile
    }

    /// The port settings the bar would connect with (baud, margin, DTR, RTS, boot wait).
    pub fn port(&self) -> PortSettings {
        PortSettings {
            baud: Some(self.baud),
            ..self.options.clone()
        }
    }

    /// Another profile chosen: its own saved port settings (or its usual rate, auto margin).
    fn take_profile(&mut self, profile: &str, saved: &Settings, rt: &Station) {
        if self.profile == profile {
            return;
        }
        let port = saved.port_of(profile);
        let usual = rt.registry.get(profile).map_or(self.baud, |p| p.baud);
        self.profile = profile.to_string();
        self.baud = port.baud.unwrap_or(usual);
        self.options = port;
        self.typed_options = super::port_options::Typed::default();
    }

    /// Draws the bar.
    pub fn show(&mut self, ui: &mut egui::Ui, saved: &Settings, rt: &Station) -> Vec<Action> {
        let lang = saved.lang;
        let mut actions = Vec::new();
        self.follow_port(rt);
        // The language switch and the link's badge hold the right end at a fixed width, never
        // wrapped; the settings wrap in the room left, so that a Reconnect appearing, the
        // badge's text changing or the language switching moves nothing else.
        // Top-aligned, one row high to start with (as `horizontal_wrapped` does): the bar is
        // as high as its rows, and the switch and badge stay on the first.
        let row = egui::vec2(ui.available_width(), ui.spacing().interact_size.y);
        let rtl = egui::Layout::right_to_left(egui::Align::Min);
        ui.allocate_ui_with_layout(row, rtl, |ui| {
            let next = lang.toggled();
            let switch = egui::Button::new(next.native_name()).min_size(egui::vec2(72.0, 0.0));
            if ui.add(switch).on_hover_text("Language / 语言").clicked() {
                actions.push(Action::SetLanguage(next));
            }
            ui.separator();
            state_badge(ui, lang, rt);
            ui.separator();
            let ltr = egui::Layout::left_to_right(egui::Align::Center).with_main_wrap(true);
            let rest = egui::vec2(ui.available_width(), row.y);
            ui.allocate_ui_with_layout(rest, ltr, |ui| {
                super::layout::keep_words_whole(ui);
                actions.extend(self.settings_row(ui, saved, rt))
            });
        });
        actions
    }

    /// The port, baud, profile and margin, and Connect / Disconnect / Reconnect.
    fn settings_row(&mut self, ui: &mut egui::Ui, saved: &Settings, rt: &Station) -> Vec<Action> {
        let lang = saved.lang;
        let mut actions = Vec::new();
        // File > Open station: the line station in this window.
        ui.menu_button(lang.tr("File", "文件"), |ui| {
            if ui.button(lang.tr("Open station…", "打开工位…")).clicked() {
                actions.push(Action::OpenStation(None));
            }
        });
        self.port_choice(ui, saved, rt);
        self.path_box(ui, lang);
        self.baud_choice(ui, lang);
        self.profile_choice(ui, saved, rt);
        self.margin_choice(ui, lang, rt);
        super::port_options::menu(ui, lang, &mut self.options, &mut self.typed_options);
        actions.extend(self.connect_buttons(ui, saved, rt));
        actions
    }

    /// The port picker: the demo devices, then the serial ports listed.
    fn port_choice(&mut self, ui: &mut egui::Ui, saved: &Settings, rt: &Station) {
        let lang = saved.lang;
        super::layout::group(ui, "port", |ui| {
            let port_label = ui.label(lang.tr("Port", "端口"));
            egui::ComboBox::from_id_salt("port")
                .width(220.0)
                .selected_text(self.target.label_in(lang))
                .show_ui(ui, |ui| {
                    for kind in SimKind::ALL {
                        let t = Target::Demo(kind.name().to_string());
                        let label = format!(
                            "{} ({})",
                            lang.tr("Demo", "演示"),
                            kind.described().get(lang)
                        );
                        if ui.selectable_label(self.target == t, label).clicked() {
                            self.take_profile(kind.profile_id(), saved, rt);
                            if saved.port_of(kind.profile_id()).baud.is_none() {
                                self.baud = kind.default_baud();
                            }
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
        });
    }

    /// A port typed by its path (a pty, a port not listed).
    fn path_box(&mut self, ui: &mut egui::Ui, lang: Lang) {
        // The path box is a group of its own: at 800 px it takes the next row, whole.
        super::layout::group(ui, "path", |ui| {
            let hint = |l: Lang| l.tr("or a path, e.g. /dev/pts/3", "或输入路径,如 /dev/pts/3");
            // As wide as its hint in either language: the hint is whole, and switching the
            // language moves nothing.
            let width = Lang::ALL
                .iter()
                .map(|&l| super::layout::box_width_for(ui, hint(l)))
                .fold(150.0, f32::max);
            let typed = ui
                .add(
                    egui::TextEdit::singleline(&mut self.typed)
                        .hint_text(hint(lang))
                        .desired_width(width),
                )
                .on_hover_text(hint(lang));
            if typed.changed() && !self.typed.trim().is_empty() {
                self.target = Target::Port(self.typed.trim().to_string());
            }
        });
    }

    /// The baud rate.
    fn baud_choice(&mut self, ui: &mut egui::Ui, lang: Lang) {
        super::layout::group(ui, "baud", |ui| {
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
        });
    }

    /// The device profile, with its own port settings.
    fn profile_choice(&mut self, ui: &mut egui::Ui, saved: &Settings, rt: &Station) {
        let lang = saved.lang;
        let chosen = super::layout::group(ui, "profile", |ui| {
            let profile_label = ui.label(lang.tr("Profile", "设备配置"));
            let mut chosen = None;
            // In 中文 by its Chinese name (the id is English words); in English by its id.
            let shown = match lang {
                Lang::Zh => rt
                    .registry
                    .iter()
                    .find(|(p, _)| p.id == self.profile)
                    .map_or(self.profile.clone(), |(p, _)| p.name.zh.clone()),
                Lang::En => self.profile.clone(),
            };
            egui::ComboBox::from_id_salt("profile")
                .selected_text(shown)
                .show_ui(ui, |ui| {
                    for (p, _) in rt.registry.iter() {
                        let label = format!("{} — {}", p.id, lang.tr(&p.name.en, &p.name.zh));
                        if ui.selectable_label(self.profile == p.id, label).clicked() {
                            chosen = Some(p.id.clone());
                        }
                    }
                })
                .response
                .labelled_by(profile_label.id);
            chosen
        });
        if let Some(p) = chosen {
            self.take_profile(&p, saved, rt);
        }
    }

    /// The answer margin: auto, or one chosen, with a warning when far above the protocol's.
    fn margin_choice(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &Station) {
        super::layout::group(ui, "margin", |ui| {
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
                .selected_text(shown(self.options.margin_ms))
                .show_ui(ui, |ui| {
                    for m in MARGINS {
                        if ui
                            .selectable_value(&mut self.options.margin_ms, m, shown(m))
                            .clicked()
                        {
                            self.typed_options = super::port_options::Typed::default();
                        }
                    }
                })
                .response
                .labelled_by(margin_label.id);
            self.margin_warning(ui, lang, rt);
        });
    }

    /// Connect, or Disconnect and Reconnect (enabled once a setting differs).
    fn connect_buttons(&self, ui: &mut egui::Ui, saved: &Settings, rt: &Station) -> Vec<Action> {
        let lang = saved.lang;
        let mut actions = Vec::new();
        let connect = || Action::Connect {
            target: self.target.clone(),
            profile: self.profile.clone(),
            port: self.port(),
        };
        let open = rt.link.connection.is_some();
        if open {
            if ui.button(lang.tr("Disconnect", "断开")).clicked() {
                actions.push(Action::Disconnect);
            }
        } else if ui.button(lang.tr("Connect", "连接")).clicked() {
            actions.push(connect());
        }
        // The rate to compare with is the port's own while it is open (it may have moved).
        let mut now = saved.port_of(&saved.profile);
        now.baud = self.port_rate.or(now.baud);
        let changed =
            self.target != saved.target || self.profile != saved.profile || self.port() != now;
        // There while connected (enabled once a setting differs), so that nothing moves.
        if open
            && ui
                .add_enabled(changed, egui::Button::new(lang.tr("Reconnect", "重新连接")))
                .on_disabled_hover_text(lang.tr(
                    "change the port, baud, profile, margin or port options first",
                    "请先修改端口、波特率、设备配置、应答余量或端口选项",
                ))
                .clicked()
        {
            actions.push(connect());
        }
        actions
    }
}

impl ConnectionBar {
    /// A warning beside a margin far above the protocol's own.
    fn margin_warning(&self, ui: &mut egui::Ui, lang: Lang, rt: &Station) {
        let Some(ms) = self.options.margin_ms else {
            return;
        };
        let Ok(profile) = rt.registry.get(&self.profile) else {
            return;
        };
        let auto = crate::link::default_margin(profile.protocol).as_secs_f64() * 1e3;
        let factor = ms as f64 / auto;
        if factor < MARGIN_WARN_FACTOR {
            return;
        }
        ui.colored_label(
            egui::Color32::from_rgb(220, 150, 0),
            format!("⚠ {factor:.0}× {}", lang.tr("auto", "自动值")),
        )
        .on_hover_text(format!(
            "{ms} ms {} {factor:.0}× {} {auto} ms: {}",
            lang.tr("is", "是"),
            lang.tr("the automatic", "自动值"),
            lang.tr(
                "every request nobody answers (each id a scan asks) waits this long",
                "每个无人应答的请求(扫描的每个ID)都要等待这么久",
            )
        ));
    }
}

/// What to check when the device does not answer: the command line's checklist
/// ([`crate::link::silent`]), naming the window's fields; a board that reboots on open too when
/// the port was opened with no boot wait; led by the loaded computer when this computer was
/// held up during the last unanswered attempt (`LinkStatus::silent_held_up`).
pub fn silent_checklist(rt: &Station) -> Text {
    let options = Text::from(Key::PortOptions);
    let (dtr, rts, off, on) = (
        Text::from(Key::Dtr),
        Text::from(Key::Rts),
        Text::from(Key::LineOff),
        Text::from(Key::LineOn),
    );
    let names = SettingNames {
        baud: Text::new("the bar's Baud", "顶栏的“波特率”"),
        profile: Text::new("the bar's Profile", "顶栏的“设备配置”"),
        boot_wait: Text::new(
            format!("{} › {} 2000 ms", options.en, Key::BootWait.en()),
            format!("{} › {} 2000 ms", options.zh, Key::BootWait.zh()),
        ),
        lines: Text::new(
            format!(
                "{} › {} {}, {} {} (or {})",
                options.en, dtr.en, off.en, rts.en, off.en, on.en
            ),
            format!(
                "{} › {}{}、{}{}(或{})",
                options.zh, dtr.zh, off.zh, rts.zh, off.zh, on.zh
            ),
        ),
    };
    let waited = !rt.link.options.setup.boot_wait.is_zero();
    let checks = SilentCheck::list_after(waited, rt.link.silent_held_up());
    silent::checklist(&checks, &names)
}

fn state_badge(ui: &mut egui::Ui, lang: Lang, rt: &Station) {
    let (text, color) = match (&rt.link.connection, &rt.link.state) {
        (None, _) => (
            lang.tr("not connected", "未连接").to_string(),
            egui::Color32::GRAY,
        ),
        // An open port says nothing of the device behind it: green only once it answers. On a
        // servo bus silence is normal (a scan asks ids nobody has), so the port is all it says.
        (Some(_), Some(LinkState::Connected { .. }))
            if rt.device.profile.protocol == crate::profile::Protocol::Servo =>
        {
            (
                lang.tr("● port open", "● 端口已打开").to_string(),
                egui::Color32::from_rgb(60, 130, 200),
            )
        }
        (Some(_), Some(LinkState::Connected { .. })) => match rt.link.answering() {
            Answering::Yes => (
                lang.tr("● device answering", "● 设备应答中").to_string(),
                egui::Color32::from_rgb(40, 160, 60),
            ),
            Answering::NotYet => (
                lang.tr("● port open, no answer yet", "● 端口已打开,尚无应答")
                    .to_string(),
                egui::Color32::from_rgb(220, 150, 0),
            ),
            Answering::No(n) => (
                format!(
                    "{} ({n} {})",
                    lang.tr("● port open, device silent", "● 端口已打开,设备无应答"),
                    lang.tr("unanswered", "次未应答")
                ),
                egui::Color32::RED,
            ),
        },
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
    // A silent device's badge tells on hover what to check.
    let hover = match (rt.link.connected(), rt.link.answering()) {
        (true, Answering::No(_)) => format!("{text}\n{}", silent_checklist(rt).get(lang)),
        _ => text.clone(),
    };
    // A fixed width, on one line: a longer text is cut (whole on hover), never wrapped.
    let size = egui::vec2(BADGE_WIDTH, ui.spacing().interact_size.y);
    let ltr = egui::Layout::left_to_right(egui::Align::Center);
    ui.allocate_ui_with_layout(size, ltr, |ui| {
        ui.set_min_size(size);
        let label = egui::Label::new(egui::RichText::new(&text).color(color)).truncate();
        ui.add(label).on_hover_text(&hover);
    });
}

/// The link badge's width, points: its longest English text at the default size.
pub const BADGE_WIDTH: f32 = 290.0;

/// The margin in use, the answer latency measured, and the USB adapter's latency timer with a
/// button to set it to 1 ms where the system lets us.
/// Shown in the status bar, beside the round trip, so that the connection bar keeps one line.
pub(super) fn timing(ui: &mut egui::Ui, lang: Lang, rt: &Station, actions: &mut Vec<Action>) {
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
                    .on_hover_text(format!(
                        "{} {t} ms",
                        lang.tr(
                            "Answers reach botbench up to 1 ms after they arrive instead of",
                            "应答到达后最多 1 ms 即交给 botbench, 而不是",
                        )
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
