//! The MCU's own requests: what the module answers (local time from the host clock or a chosen
//! time, the Wi-Fi production test's result and signal, the network status, the MAC), and each
//! request answered, reset-Wi-Fi acks shown clearly.

use super::{Action, Station, clock, wifi_state_name};
use crate::i18n::Lang;
use crate::link::TuyaModuleOptions;
use crate::protocol::tuya::cmd;
use crate::sim::tuya_mcu::McuRequest;
use chrono::{Datelike, NaiveDateTime};
use eframe::egui;

const ORANGE: egui::Color32 = egui::Color32::from_rgb(220, 150, 0);
const TIME_FORMAT: &str = "%Y-%m-%d %H:%M:%S";

/// The settings being typed.
#[derive(Debug, Default)]
pub struct RequestsView {
    /// The chosen local time as typed (`2026-11-22 08:30:15`).
    pub time_text: String,
    /// The MAC as typed (`02:b0:7b:00:00:01`).
    pub mac_text: Option<String>,
}

/// Why a typed time or MAC cannot be answered.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EntryError {
    /// Not a time in the format.
    #[error("'{text}': {error}; use YYYY-MM-DD HH:MM:SS")]
    Time {
        /// What was typed.
        text: String,
        /// Why it does not read.
        error: chrono::ParseError,
    },
    /// A year the answer's year byte cannot hold.
    #[error("year {0} is outside 2000-2255")]
    Year(i32),
    /// Not six hex bytes.
    #[error("'{0}': expected six hex bytes such as 02:b0:7b:00:00:01")]
    Mac(String),
}

/// Reads a chosen local time; the answer's year byte holds 2000-2255.
pub fn parse_time(text: &str) -> Result<NaiveDateTime, EntryError> {
    let t = NaiveDateTime::parse_from_str(text.trim(), TIME_FORMAT).map_err(|error| {
        EntryError::Time {
            text: text.trim().to_string(),
            error,
        }
    })?;
    if !(2000..=2255).contains(&t.year()) {
        return Err(EntryError::Year(t.year()));
    }
    Ok(t)
}

/// Reads a MAC address: six hex bytes separated by `:` or `-`.
pub fn parse_mac(text: &str) -> Result<[u8; 6], EntryError> {
    let parts: Vec<&str> = text.trim().split([':', '-']).collect();
    let bytes: Vec<u8> = parts
        .iter()
        .filter_map(|p| {
            (p.len() == 2)
                .then(|| u8::from_str_radix(p, 16).ok())
                .flatten()
        })
        .collect();
    <[u8; 6]>::try_from(bytes.as_slice())
        .ok()
        .filter(|_| parts.len() == 6)
        .ok_or_else(|| EntryError::Mac(text.trim().to_string()))
}

/// The name of one of the MCU's own requests, for its button.
fn request_name(r: McuRequest, lang: Lang) -> &'static str {
    match r {
        McuRequest::LocalTime => lang.tr("Ask the local time (0x1c)", "请求本地时间 (0x1c)"),
        McuRequest::WifiTest => lang.tr("Start the Wi-Fi test (0x0e)", "发起WiFi功能产测 (0x0e)"),
        McuRequest::ResetWifi => lang.tr("Ask to reset the Wi-Fi (0x04)", "请求重置WiFi (0x04)"),
        McuRequest::ResetWifiMode(_) => lang.tr(
            "Ask to reset the Wi-Fi into AP mode (0x05)",
            "请求重置WiFi进入AP模式 (0x05)",
        ),
        McuRequest::NetStatus => lang.tr("Ask the network status (0x2b)", "查询联网状态 (0x2b)"),
        McuRequest::Mac => lang.tr("Ask the module's MAC (0x2d)", "获取模块MAC (0x2d)"),
        McuRequest::UtcTime => lang.tr("Ask the GMT time (0x0c)", "请求格林尼治时间 (0x0c)"),
        McuRequest::Rssi => lang.tr("Ask the signal strength (0x24)", "获取WiFi信号强度 (0x24)"),
        McuRequest::StopHeartbeat => lang.tr("Stop the heartbeat (0x25)", "关闭模块心跳 (0x25)"),
        McuRequest::Extended(_) => lang.tr(
            "Ask the module information (0x34 07)",
            "获取模块信息 (0x34 07)",
        ),
    }
}

/// Buttons that make the built-in simulated MCU send its own requests, as a real MCU does when
/// it wants the time or a factory test.
fn demo_buttons(ui: &mut egui::Ui, lang: Lang, rt: &Station, actions: &mut Vec<Action>) {
    ui.strong(lang.tr(
        "Make the built-in MCU ask the module",
        "让内置模拟MCU向模块发出请求",
    ));
    crate::ui::layout::toolbar(ui, |ui| {
        for r in McuRequest::ALL {
            if ui
                .add_enabled(rt.connected(), egui::Button::new(request_name(r, lang)))
                .clicked()
            {
                actions.push(Action::DemoMcuRequest(r));
            }
        }
    });
}

fn mac_text(mac: &[u8]) -> String {
    mac.iter()
        .map(|b| format!("{b:02x}"))
        .collect::<Vec<_>>()
        .join(":")
}

fn weekday(n: u8, lang: Lang) -> &'static str {
    match n {
        1 => lang.tr("Monday", "星期一"),
        2 => lang.tr("Tuesday", "星期二"),
        3 => lang.tr("Wednesday", "星期三"),
        4 => lang.tr("Thursday", "星期四"),
        5 => lang.tr("Friday", "星期五"),
        6 => lang.tr("Saturday", "星期六"),
        7 => lang.tr("Sunday", "星期日"),
        _ => "?",
    }
}

fn test_failure(reason: u8, lang: Lang) -> &'static str {
    match reason {
        0 => lang.tr("test SSID not found", "未扫描到测试路由"),
        _ => lang.tr("the module has no licence key", "模块未授权"),
    }
}

/// The module's answer, as a person reads it.
fn answer_text(rt: &Station, lang: Lang, command: u8, answer: &[u8]) -> String {
    match (command, answer) {
        (cmd::RESET_WIFI | cmd::RESET_WIFI_MODE, _) => {
            lang.tr("acknowledged", "已应答确认").to_string()
        }
        (cmd::LOCAL_TIME, [ok, y, mo, d, h, mi, s, wd]) => format!(
            "{} 20{y:02}-{mo:02}-{d:02} {h:02}:{mi:02}:{s:02}, {}",
            if *ok == 1 {
                lang.tr("time", "时间")
            } else {
                lang.tr("no time", "无时间")
            },
            weekday(*wd, lang)
        ),
        (cmd::WIFI_TEST, [1, rssi]) => format!(
            "{}, {} {rssi} %",
            lang.tr("passed", "通过"),
            lang.tr("signal", "信号强度")
        ),
        (cmd::WIFI_TEST, [_, reason]) => format!(
            "{}: {}",
            lang.tr("failed", "失败"),
            test_failure(*reason, lang)
        ),
        (cmd::NET_STATUS, [s]) => wifi_state_name(rt, lang, *s),
        (cmd::MAC, [ok, mac @ ..]) if mac.len() == 6 => {
            let t = mac_text(mac);
            if *ok == 0 {
                t
            } else {
                format!("{t} (flag {ok})")
            }
        }
        _ => crate::protocol::hex::format(answer),
    }
}

impl RequestsView {
    /// The module's MAC (0x2d): typed as hex, used once it parses.
    fn mac_row(&mut self, ui: &mut egui::Ui, lang: Lang, opts: &mut TuyaModuleOptions) {
        let label = ui.label(lang.tr("Module MAC (0x2d)", "模块MAC (0x2d)"));
        ui.horizontal(|ui| {
            let text = self.mac_text.get_or_insert_with(|| mac_text(&opts.mac));
            let parsed = parse_mac(text);
            let mut edit = egui::TextEdit::singleline(text).desired_width(160.0);
            if parsed.is_err() {
                edit = edit.text_color(egui::Color32::RED);
            }
            ui.add(edit).labelled_by(label.id);
            match parse_mac(text) {
                Ok(mac) => opts.mac = mac,
                Err(e) => {
                    ui.colored_label(
                        egui::Color32::RED,
                        format!("× {}: {e}", lang.tr("not used", "未采用")),
                    );
                }
            }
        });
        ui.end_row();
    }

    /// Draws the section; changes to what the module answers go into `opts`. With the
    /// built-in simulated MCU, buttons ask it to send its requests.
    pub fn show(
        &mut self,
        ui: &mut egui::Ui,
        lang: Lang,
        rt: &Station,
        opts: &mut TuyaModuleOptions,
    ) -> Vec<Action> {
        let mut actions = Vec::new();
        if rt.link.demo_tuya().is_some() {
            demo_buttons(ui, lang, rt, &mut actions);
            ui.separator();
        }
        ui.strong(lang.tr("What the module answers", "模块的应答"));
        egui::Grid::new("tuya-answers")
            .num_columns(2)
            .striped(true)
            .show(ui, |ui| {
                self.time_row(ui, lang, opts);
                ui.end_row();
                wifi_test_row(ui, lang, opts);
                net_status_row(ui, lang, rt, opts);
                self.mac_row(ui, lang, opts);
            });
        ui.separator();
        let s = &rt.device.tuya;
        if let (n, Some(last)) = &s.resets {
            let mode = match (
                last.command,
                rt.device.profile.command_by_id(cmd::RESET_WIFI_MODE),
            ) {
                (cmd::RESET_WIFI_MODE, Some(_)) => {
                    format!(" ({})", lang.tr("into a pairing mode", "进入配网模式"))
                }
                _ => String::new(),
            };
            ui.colored_label(
                ORANGE,
                egui::RichText::new(format!(
                    "{} {n}; {} {}{mode}: {}",
                    lang.tr(
                        "The MCU asked to reset the Wi-Fi, times:",
                        "MCU请求重置WiFi,次数:"
                    ),
                    lang.tr("last at", "最近一次于"),
                    clock(&last.clock),
                    lang.tr("acknowledged", "已应答确认"),
                ))
                .strong(),
            );
        }
        if let Some(t) = &s.heartbeat_stopped {
            ui.colored_label(
                ORANGE,
                format!(
                    "{} {} {}",
                    lang.tr("The MCU asked for no heartbeats (0x25) at", "MCU于"),
                    clock(t),
                    lang.tr(
                        "(acknowledged): none is sent until the next handshake, so a restart is not seen.",
                        "请求关闭心跳(0x25),已应答:下次握手前不再发送心跳,MCU重启将无法察觉。"
                    ),
                ),
            );
        }
        unknown_commands(ui, lang, rt);
        ui.strong(format!(
            "{} ({})",
            lang.tr("Requests answered", "已应答的请求"),
            s.requests.len()
        ));
        if s.requests.is_empty() {
            ui.weak(lang.tr("The MCU has asked nothing yet.", "MCU尚未发出请求。"));
            return actions;
        }
        crate::ui::layout::table(ui, egui::Grid::new("tuya-requests"), &[
                        lang.tr("Time", "时间"),
                        lang.tr("Request", "请求"),
                        lang.tr("Answer", "应答"),
                    ], |ui| {
                for r in s.requests.iter().rev() {
                    ui.monospace(clock(&r.clock));
                    let name = rt
                        .device
                        .profile
                        .command_by_id(r.command)
                        .map_or(r.name.as_str(), |c| lang.tr(&c.name.en, &c.name.zh));
                    ui.label(format!("{name} ({:#04x})", r.command));
                    let text = answer_text(rt, lang, r.command, &r.answer);
                    if matches!(r.command, cmd::RESET_WIFI | cmd::RESET_WIFI_MODE) {
                        ui.colored_label(ORANGE, egui::RichText::new(text).strong());
                    } else {
                        ui.label(text);
                    }
                    ui.end_row();
                }
            });
        actions
    }

    fn time_row(&mut self, ui: &mut egui::Ui, lang: Lang, opts: &mut TuyaModuleOptions) {
        let label = ui.label(lang.tr("Local time (0x1c)", "本地时间 (0x1c)"));
        ui.horizontal(|ui| {
            let mut fixed = opts.fixed_time.is_some();
            ui.radio_value(&mut fixed, false, lang.tr("host clock", "电脑时钟"));
            ui.radio_value(&mut fixed, true, lang.tr("chosen time", "指定时间"));
            if self.time_text.is_empty() {
                self.time_text = chrono::Local::now().format(TIME_FORMAT).to_string();
            }
            let parsed = parse_time(&self.time_text);
            let mut edit = egui::TextEdit::singleline(&mut self.time_text)
                .desired_width(160.0)
                .hint_text("2026-11-22 08:30:15");
            if parsed.is_err() {
                edit = edit.text_color(egui::Color32::RED);
            }
            ui.add_enabled(fixed, edit).labelled_by(label.id);
            match (fixed, parse_time(&self.time_text)) {
                (false, _) => opts.fixed_time = None,
                (true, Ok(t)) => opts.fixed_time = Some(t),
                (true, Err(e)) => {
                    // The last valid choice stays in force until the text is valid again.
                    ui.colored_label(
                        egui::Color32::RED,
                        format!("× {}: {e}", lang.tr("not used", "未采用")),
                    );
                    if opts.fixed_time.is_none() {
                        ui.colored_label(
                            egui::Color32::RED,
                            lang.tr("(answering the host clock)", "(仍按电脑时钟应答)"),
                        );
                    }
                }
            }
        });
    }
}

/// The Wi-Fi production test's answer (0x0e): it passes with a signal strength, or fails with
/// a reason.
fn wifi_test_row(ui: &mut egui::Ui, lang: Lang, opts: &mut TuyaModuleOptions) {
    let label = ui.label(lang.tr("Wi-Fi production test (0x0e)", "WiFi功能产测 (0x0e)"));
    ui.horizontal(|ui| {
        ui.checkbox(&mut opts.wifi_test_ok, lang.tr("passes", "通过"))
            .labelled_by(label.id);
        if opts.wifi_test_ok {
            let l = ui.label(lang.tr("signal strength %", "信号强度 %"));
            ui.add(egui::Slider::new(&mut opts.wifi_test_rssi, 0..=100))
                .labelled_by(l.id);
        } else {
            let l = ui.label(lang.tr("failure", "失败原因"));
            opts.wifi_test_rssi = opts.wifi_test_rssi.min(1);
            egui::ComboBox::from_id_salt("tuya-test-failure")
                .selected_text(test_failure(opts.wifi_test_rssi, lang))
                .show_ui(ui, |ui| {
                    for r in 0..=1 {
                        ui.selectable_value(&mut opts.wifi_test_rssi, r, test_failure(r, lang));
                    }
                })
                .response
                .labelled_by(l.id);
        }
    });
    ui.end_row();
}

/// The network status the module reports (0x2b).
fn net_status_row(ui: &mut egui::Ui, lang: Lang, rt: &Station, opts: &mut TuyaModuleOptions) {
    let label = ui.label(lang.tr("Network status (0x2b)", "联网状态 (0x2b)"));
    egui::ComboBox::from_id_salt("tuya-net-status")
        .selected_text(wifi_state_name(rt, lang, opts.net_status))
        .width(300.0)
        .show_ui(ui, |ui| {
            for s in 0..=6u8 {
                ui.selectable_value(&mut opts.net_status, s, wifi_state_name(rt, lang, s));
            }
        })
        .response
        .labelled_by(label.id);
    ui.end_row();
}

/// Commands (and extended-service sub-commands) the MCU sent that the module does not know:
/// logged with their bytes and not answered, as a real module does.
fn unknown_commands(ui: &mut egui::Ui, lang: Lang, rt: &Station) {
    let list = &rt.device.tuya.unknown_commands;
    if list.is_empty() {
        return;
    }
    ui.strong(format!(
        "{} ({})",
        lang.tr("Unknown commands, not answered", "未知命令,未应答"),
        list.len()
    ));
    egui::Grid::new("tuya-unknown-commands")
        .num_columns(3)
        .striped(true)
        .show(ui, |ui| {
            for (t, _, what, data) in list.iter().rev() {
                ui.monospace(clock(t));
                ui.label(what);
                ui.monospace(crate::protocol::hex::format(data));
                ui.end_row();
            }
        });
    ui.separator();
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mac_needs_six_hex_bytes() {
        assert_eq!(
            parse_mac("02:B0:7b-00:00:01"),
            Ok([0x02, 0xb0, 0x7b, 0, 0, 1])
        );
        for bad in [
            "02:b0:7b:00:00",
            "02:b0:7b:00:00:01:02",
            "02:b0:7b:00:00:zz",
            "2:b0:7b:0:0:1",
        ] {
            assert!(parse_mac(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn a_chosen_time_must_fit_the_answer() {
        assert!(parse_time("2026-11-22 08:30:15").is_ok());
        assert!(parse_time("1999-12-31 23:59:59").is_err());
        assert!(parse_time("2026-13-01 00:00:00").is_err());
        assert!(parse_time("tomorrow").is_err());
    }
}
