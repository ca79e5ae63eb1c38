//! The start-up handshake step by step, where it stopped and that it retries, the heartbeat,
//! MCU restarts, and the Wi-Fi state reported to the MCU.

use super::{Action, Station, clock, fire, wifi_state_name};
use crate::i18n::Lang;
use crate::link::session::tuya::HandshakeStep;
use crate::link::{LinkCommand, TuyaModuleOptions};

use eframe::egui;

const GREEN: egui::Color32 = egui::Color32::from_rgb(40, 160, 60);
const ORANGE: egui::Color32 = egui::Color32::from_rgb(220, 150, 0);

fn step_name(step: HandshakeStep, lang: Lang) -> &'static str {
    match step {
        HandshakeStep::Heartbeat => lang.tr("Heartbeat (0x00)", "心跳检测 (0x00)"),
        HandshakeStep::ProductInfo => lang.tr("Product info (0x01)", "产品信息 (0x01)"),
        HandshakeStep::WorkMode => lang.tr("Working mode (0x02)", "工作模式 (0x02)"),
        HandshakeStep::WifiState => lang.tr("Wi-Fi state (0x03)", "WiFi状态 (0x03)"),
        HandshakeStep::QueryStatus => lang.tr("Initial status (0x08)", "初始状态 (0x08)"),
    }
}

fn config_mode(mode: i64, lang: Lang) -> String {
    let name = match mode {
        0 => lang.tr("default", "默认配网"),
        1 => lang.tr("low power", "低功耗"),
        2 => lang.tr("special", "特殊配网"),
        _ => lang.tr("unknown", "未知"),
    };
    format!("{mode} ({name})")
}

/// One line above the sections: the handshake's state, the last heartbeat, the product.
pub fn summary(ui: &mut egui::Ui, lang: Lang, rt: &Station) {
    let s = &rt.device.tuya;
    crate::ui::layout::toolbar(ui, |ui| {
        if !rt.connected() {
            ui.weak(lang.tr("not connected", "未连接"));
        } else if let Some(t) = &s.done_at {
            ui.colored_label(
                GREEN,
                format!(
                    "{} {}",
                    lang.tr("Handshake complete at", "握手完成于"),
                    clock(t)
                ),
            );
        } else if let Some((step, r)) = &s.stopped {
            // The device's detail may be long: it wraps.
            let text = format!(
                "{} {}: {} ({} {})",
                lang.tr("Handshake stopped at", "握手停在"),
                step_name(*step, lang),
                r.detail.get(lang),
                lang.tr("retrying, attempt", "正在重试,第"),
                s.attempts
            );
            ui.add(egui::Label::new(egui::RichText::new(text).color(egui::Color32::RED)).wrap());
        } else if s.attempts > 0 {
            ui.colored_label(ORANGE, lang.tr("Handshake running…", "正在握手…"));
        } else {
            ui.weak(lang.tr("Waiting for the MCU…", "等待MCU…"));
        }
        ui.separator();
        match &s.last_heartbeat {
            Some((t, _)) => ui.label(format!(
                "{} {}",
                lang.tr("Last heartbeat:", "最近心跳:"),
                clock(t)
            )),
            None => ui.weak(lang.tr("no heartbeat answered yet", "尚无心跳应答")),
        };
        if let Some(pid) = s.product.as_ref().and_then(|p| p.pid.as_deref()) {
            ui.separator();
            ui.label(format!("PID {pid}"));
        }
    });
}

/// The handshake section.
pub fn show(
    ui: &mut egui::Ui,
    lang: Lang,
    rt: &Station,
    opts: &mut TuyaModuleOptions,
) -> Vec<Action> {
    let mut actions = Vec::new();
    let s = &rt.device.tuya;
    ui.horizontal(|ui| {
        if ui
            .add_enabled(
                rt.connected(),
                egui::Button::new(lang.tr("Run handshake again", "重新握手")),
            )
            .clicked()
        {
            actions.push(Action::Link(LinkCommand::Handshake));
        }
        ui.weak(lang.tr(
            "After the handshake, a heartbeat every 15 s; an MCU restart runs it again.",
            "握手完成后每15秒发送心跳;MCU重启后自动重新握手。",
        ));
    });
    ui.add_space(4.0);
    steps_table(ui, lang, rt);
    if let Some((step, r)) = &s.stopped {
        ui.colored_label(
            egui::Color32::RED,
            format!(
                "{} {} {} {}: {}. {} {}.",
                lang.tr("The last attempt stopped at", "上次尝试停在"),
                step_name(*step, lang),
                lang.tr("at", "于"),
                clock(&r.at),
                r.detail.get(lang),
                lang.tr(
                    "The handshake is tried again every second; attempts so far:",
                    "每秒重试一次握手;已尝试次数:"
                ),
                s.attempts
            ),
        );
    }
    ui.separator();
    facts(ui, lang, rt);
    ui.separator();
    actions.extend(wifi_state(ui, lang, rt, opts));
    actions
}

/// The handshake's steps in a table: each one's result, when it ended and how long it took
/// from its request, and what came back; the step the current attempt waits at.
fn steps_table(ui: &mut egui::Ui, lang: Lang, rt: &Station) {
    let s = &rt.device.tuya;
    // Where the current attempt is: the first step without a result, unless one failed.
    let failed = s.done_at.is_none()
        && HandshakeStep::ALL
            .iter()
            .zip(&s.steps)
            .any(|(step, r)| r.as_ref().is_some_and(|r| !r.ok && !s.shown_raw(*step)));
    let waiting_at = (!failed && s.done_at.is_none() && s.attempts > 0 && rt.connected())
        .then(|| s.steps.iter().position(Option::is_none))
        .flatten();
    crate::ui::layout::table(ui, egui::Grid::new("tuya-steps"), &[
                    lang.tr("Step", "步骤"),
                    lang.tr("Result", "结果"),
                    lang.tr("Time", "时间"),
                    lang.tr("Took", "用时"),
                    lang.tr("Detail", "详情"),
                ], |ui| {
            for (i, step) in HandshakeStep::ALL.iter().enumerate() {
                ui.label(step_name(*step, lang));
                match &s.steps[i] {
                    Some(r) if r.ok => {
                        ui.colored_label(GREEN, format!("✓ {}", lang.tr("ok", "成功")));
                    }
                    Some(_) if s.shown_raw(*step) => {
                        ui.colored_label(ORANGE, lang.tr("shown raw", "原样显示"));
                    }
                    Some(_) => {
                        ui.colored_label(
                            egui::Color32::RED,
                            format!("× {}", lang.tr("failed", "失败")),
                        );
                    }
                    None if waiting_at == Some(i) => {
                        ui.colored_label(ORANGE, lang.tr("waiting…", "等待中…"));
                    }
                    None => {
                        ui.weak("—");
                    }
                }
                match &s.steps[i] {
                    Some(r) => {
                        ui.monospace(clock(&r.at));
                        match r.took {
                            Some(d) => ui.monospace(format!("{:.0} ms", d.as_secs_f64() * 1e3)),
                            None => ui.weak("—"),
                        };
                        ui.label(r.detail.get(lang));
                    }
                    None => {
                        ui.label("");
                        ui.label("");
                        ui.label("");
                    }
                }
                ui.end_row();
            }
        });
}

/// What the handshake learned of the MCU: product, versions, modes, heartbeats, restarts.
fn facts(ui: &mut egui::Ui, lang: Lang, rt: &Station) {
    let s = &rt.device.tuya;
    egui::Grid::new("tuya-facts")
        .num_columns(2)
        .striped(true)
        .show(ui, |ui| {
            ui.label(lang.tr("Product ID (PID)", "产品ID (PID)"));
            match &s.product {
                Some(p) => ui.monospace(p.pid.as_deref().unwrap_or("?")),
                None => ui.weak(lang.tr("not received yet", "尚未收到")),
            };
            ui.end_row();
            ui.label(lang.tr("MCU version", "MCU版本"));
            match &s.product {
                Some(p) => ui.monospace(p.version.as_deref().unwrap_or("?")),
                None => ui.weak(lang.tr("not received yet", "尚未收到")),
            };
            ui.end_row();
            ui.label(lang.tr("MCU frame version", "MCU帧版本"));
            match s.frame_version {
                Some(v) if v == crate::protocol::tuya::VERSION_MCU => {
                    ui.monospace(format!("{v:#04x}"))
                }
                Some(v) => ui.colored_label(
                    ORANGE,
                    format!(
                        "{v:#04x} ({} {:#04x}; {})",
                        lang.tr("the protocol document says", "协议文档规定为"),
                        crate::protocol::tuya::VERSION_MCU,
                        lang.tr("accepted", "已接受")
                    ),
                ),
                None => ui.weak(lang.tr("not received yet", "尚未收到")),
            };
            ui.end_row();
            ui.label(lang.tr("Configuration mode", "配网模式"));
            match s.product.as_ref().map(|p| p.mode) {
                Some(Some(m)) => ui.monospace(config_mode(m, lang)),
                Some(None) => ui.monospace("?"),
                None => ui.weak(lang.tr("not received yet", "尚未收到")),
            };
            ui.end_row();
            if let Some(p) = &s.product
                && let Some(e) = &p.error
            {
                ui.label(lang.tr("Product info as received", "收到的产品信息"));
                ui.vertical(|ui| {
                    ui.colored_label(
                        egui::Color32::RED,
                        format!("{}: {e}", lang.tr("not valid JSON", "不是有效的JSON")),
                    );
                    ui.monospace(&p.raw);
                });
                ui.end_row();
            }
            ui.label(lang.tr("Working mode", "工作模式"));
            match &s.work_mode {
                Some(None) => ui.label(lang.tr(
                    "the MCU drives the Wi-Fi LED (the module reports the Wi-Fi state)",
                    "MCU控制WiFi指示灯(模块上报WiFi状态)",
                )),
                Some(Some((led, reset))) => ui.label(format!(
                    "{} {led}, {} {reset}",
                    lang.tr("the module drives the LED: GPIO", "模块自行处理:指示灯GPIO"),
                    lang.tr("reset key GPIO", "重置键GPIO")
                )),
                None => ui.weak(lang.tr("not received yet", "尚未收到")),
            };
            ui.end_row();
            heartbeat_rows(ui, lang, rt);
        });
}

/// The last heartbeat answered, a heartbeat lost since, and the MCU restarts detected.
fn heartbeat_rows(ui: &mut egui::Ui, lang: Lang, rt: &Station) {
    let s = &rt.device.tuya;
    ui.label(lang.tr("Last heartbeat", "最近心跳"));
    match &s.last_heartbeat {
        Some((t, answer)) => ui.monospace(format!(
            "{} ({} {})",
            clock(t),
            lang.tr("answer", "应答"),
            answer.map_or("?".into(), |a| a.to_string())
        )),
        None => ui.weak(lang.tr("none yet", "暂无")),
    };
    ui.end_row();
    if let Some(lost) = &s.heartbeat_lost
        && s.last_heartbeat.as_ref().is_none_or(|(t, _)| t < lost)
    {
        ui.label("");
        ui.colored_label(
            egui::Color32::RED,
            format!(
                "{} {}; {}",
                lang.tr(
                    "The MCU stopped answering heartbeats at",
                    "MCU停止应答心跳于"
                ),
                clock(lost),
                lang.tr("retrying every 3 s", "每3秒重试")
            ),
        );
        ui.end_row();
    }
    ui.label(lang.tr("MCU restarts detected", "检测到MCU重启"));
    match &s.restarts {
        (0, _) => ui.label("0"),
        (n, Some(t)) => ui.colored_label(
            ORANGE,
            format!(
                "{n}, {} {}: {}",
                lang.tr("last at", "最近一次于"),
                clock(t),
                lang.tr(
                    "the heartbeat answered 0, so the handshake ran again",
                    "心跳应答为0,已重新握手"
                )
            ),
        ),
        (n, None) => ui.label(n.to_string()),
    };
    ui.end_row();
}

/// The Wi-Fi state selector: a choice is reported to the MCU at once (0x03) and used by later
/// handshakes.
fn wifi_state(
    ui: &mut egui::Ui,
    lang: Lang,
    rt: &Station,
    opts: &mut TuyaModuleOptions,
) -> Vec<Action> {
    let mut actions = Vec::new();
    crate::ui::layout::toolbar(ui, |ui| {
        let label = ui.label(lang.tr("Wi-Fi state reported to the MCU", "上报给MCU的WiFi状态"));
        let mut chosen = None;
        egui::ComboBox::from_id_salt("tuya-wifi-state")
            .selected_text(wifi_state_name(rt, lang, opts.wifi_state))
            .width(300.0)
            .show_ui(ui, |ui| {
                for state in 0..=6u8 {
                    if ui
                        .selectable_label(
                            opts.wifi_state == state,
                            wifi_state_name(rt, lang, state),
                        )
                        .clicked()
                    {
                        chosen = Some(state);
                    }
                }
            })
            .response
            .labelled_by(label.id);
        if let Some(state) = chosen
            && rt.connected()
        {
            opts.wifi_state = state;
            actions.push(fire(crate::ops::tuya::wifi_state_request(state)));
        }
    });
    match &rt.device.tuya.wifi_sent {
        Some((state, t)) => {
            let acked = rt.device.tuya.wifi_acked.as_ref().filter(|a| *a >= t);
            let text = format!(
                "{} {} {} {}; {}",
                lang.tr("Last reported:", "最近上报:"),
                wifi_state_name(rt, lang, *state),
                lang.tr("at", "于"),
                clock(t),
                match acked {
                    Some(a) =>
                        format!("{} {}", lang.tr("acknowledged at", "MCU已确认于"), clock(a)),
                    None => lang.tr("not acknowledged yet", "MCU尚未确认").to_string(),
                }
            );
            if acked.is_some() {
                ui.label(text);
            } else {
                ui.colored_label(ORANGE, text);
            }
        }
        None => {
            ui.weak(lang.tr("No Wi-Fi state reported yet.", "尚未上报WiFi状态。"));
        }
    }
    if matches!(rt.device.tuya.work_mode, Some(Some(_))) {
        ui.weak(lang.tr(
            "This MCU lets the module drive the LED: it does not need the Wi-Fi state.",
            "该MCU由模块自行处理指示灯,无需上报WiFi状态。",
        ));
    }
    actions
}
