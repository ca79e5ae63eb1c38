//! The MSP core commands: ping (with its round trip), version (hardware, firmware, API, build date
//! and time, capability flags by name) and power state. Nothing is shown before a reply brings it.

use super::Action;
use super::jobs::Job;
use super::station::{Answering, Station};
use crate::i18n::Lang;
use crate::i18n::Text;
use crate::link::{DeviceInfo, LinkCommand, capabilities};
use crate::ops::Device;
use crate::ops::OpError;
use crate::ops::device as ops;
use crate::profile::Profile;
use crate::protocol::hex;
use crate::ui::zh::Zh;
use eframe::egui;
use std::time::Duration;

/// The panel's state: what the last replies said.
#[derive(Default)]
pub struct DevicePanel {
    /// The last ping: its round trip, or why it failed.
    pub ping: Option<Result<Duration, OpError>>,
    /// The last power-state read: the raw bytes, or why it failed.
    pub power: Option<Result<Vec<u8>, OpError>>,
    /// The last version read by this panel (the session's own is the device model's `info`).
    pub version: Option<Result<DeviceInfo, OpError>>,
    /// The spell the values were read in (the device model's `epoch`): another connection, a
    /// lost link or a device that answers again after silence clears them.
    epoch: Option<u64>,
    /// Version and power state have been asked on this connection.
    asked: bool,
}

/// What this panel's jobs report.
#[derive(Debug, Clone)]
pub enum Output {
    /// A ping's round trip, or why it failed.
    Ping(Result<Duration, OpError>),
    /// CMD_VERSION with CMD_BUILD_INFO, or why it failed.
    Version(Result<DeviceInfo, OpError>),
    /// CMD_GET_POWER_STATE's raw answer, or why it failed.
    Power(Result<Vec<u8>, OpError>),
}

/// Reads CMD_VERSION, CMD_BUILD_INFO and the power state.
fn read_job(profile: &std::sync::Arc<Profile>) -> Action {
    let p = profile.clone();
    Action::StartJob(Job::new(
        Text::new("version", "版本"),
        move |client, cancel, sink| {
            let v = ops::identify(client);
            sink.panel(Output::Version(v.clone()));
            if cancel.is_cancelled() {
                return Err(OpError::Cancelled.into());
            }
            let pw = ops::power_state(Device::new(client, &p));
            sink.panel(Output::Power(pw.clone()));
            v?;
            pw?;
            Ok(Text::new(
                "version and power state read",
                "已读取版本与电源状态",
            ))
        },
    ))
}

impl DevicePanel {
    /// The ping's round trip and the raw power state, as last read.
    fn readings(&self, ui: &mut egui::Ui, lang: Lang) {
        egui::Grid::new("device-core")
            .num_columns(2)
            .striped(true)
            .show(ui, |ui| {
                ui.label(lang.tr("Ping round trip", "通讯往返时间"));
                match &self.ping {
                    Some(Ok(d)) => {
                        ui.monospace(format!("{:.1} ms", d.as_secs_f64() * 1e3));
                    }
                    Some(Err(e)) => {
                        ui.colored_label(egui::Color32::RED, e.in_lang(lang));
                    }
                    None => {
                        ui.weak(lang.tr("not pinged yet", "尚未检测"));
                    }
                }
                ui.end_row();
                ui.label(lang.tr("Power state (raw)", "电源状态(原始数据)"))
                    .on_hover_text(lang.tr(
                        "No layout is published for this answer: its bytes are shown as sent.",
                        "此应答的格式未公开:按原始字节显示。",
                    ));
                match &self.power {
                    Some(Ok(b)) if b.is_empty() => {
                        ui.monospace(lang.tr("(empty answer)", "(空应答)"));
                    }
                    Some(Ok(b)) => {
                        ui.monospace(hex::format(b));
                    }
                    Some(Err(e)) => {
                        ui.colored_label(egui::Color32::RED, e.in_lang(lang));
                    }
                    None => {
                        ui.weak(lang.tr("not read yet", "尚未读取"));
                    }
                }
                ui.end_row();
            });
    }

    /// Draws the panel.
    fn draw(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &Station) -> Vec<Action> {
        let mut actions = Vec::new();
        if self.epoch != Some(rt.device.epoch) {
            // Values of another connection (maybe another device) are never shown.
            *self = Self {
                epoch: Some(rt.device.epoch),
                ..Self::default()
            };
        }
        let ready = rt.connected() && rt.job_progress().is_none();
        let profile = rt.device.profile.clone();
        if ready && !self.asked {
            // Read once on each connection, as soon as the link is free.
            self.asked = true;
            actions.push(read_job(&profile));
        }
        actions.extend(buttons(ui, lang, rt, ready));
        ui.separator();
        // Scrolls where the window is too low for it (800×500).
        egui::ScrollArea::vertical()
            .auto_shrink(false)
            .show(ui, |ui| {
                silent(ui, lang, rt);
                self.readings(ui, lang);
                ui.separator();
                ui.strong(lang.tr("Version", "版本信息"));
                // This panel's own read wins; until then, what the session learned on connect.
                let info = self.version.as_ref().or(rt.device.info.as_ref());
                match info {
                    Some(Ok(info)) => self.show_info(ui, lang, &profile, info),
                    Some(Err(e)) => {
                        ui.colored_label(egui::Color32::RED, e.in_lang(lang));
                        super::tuning::unidentified_warning(ui, lang, rt);
                    }
                    None => {
                        ui.weak(lang.tr(
                            "the device has not answered CMD_VERSION yet",
                            "设备尚未应答版本查询",
                        ));
                    }
                }
                last_answer(ui, lang, rt);
            });
        actions
    }

    fn show_info(&self, ui: &mut egui::Ui, lang: Lang, profile: &Profile, info: &DeviceInfo) {
        egui::Grid::new("device-version")
            .num_columns(2)
            .striped(true)
            .show(ui, |ui| {
                let row = |ui: &mut egui::Ui, name: &str, value: String| {
                    ui.label(name);
                    ui.monospace(value);
                    ui.end_row();
                };
                row(
                    ui,
                    lang.tr("Hardware (device code)", "硬件版本(设备码)"),
                    format!("{:#04x}", info.hw),
                );
                row(ui, lang.tr("Firmware", "固件版本"), info.firmware.clone());
                row(ui, lang.tr("API", "接口版本"), info.api.clone());
                row(
                    ui,
                    lang.tr("Build number", "构建号"),
                    info.build.to_string(),
                );
                row(
                    ui,
                    lang.tr("Build date and time", "编译日期与时间"),
                    info.build_date
                        .clone()
                        .unwrap_or_else(|| lang.tr("not answered", "设备未应答").to_string()),
                );
            });
        ui.add_space(6.0);
        ui.strong(lang.tr("Capabilities", "功能支持标志"));
        match info.flags {
            None => {
                ui.label(lang.tr(
                    "The firmware sends no capability byte (7-byte version): every panel is shown.",
                    "固件未发送功能标志字节(7 字节版本应答):显示全部页面。",
                ));
            }
            Some(flags) => {
                ui.monospace(format!("{flags:#04x} = {flags:#010b}"));
                egui::Grid::new("device-flags")
                    .num_columns(3)
                    .striped(true)
                    .show(ui, |ui| {
                        for c in capabilities(profile, flags) {
                            ui.monospace(format!("{} {}", lang.tr("bit", "位"), c.bit));
                            ui.label(lang.tr(&c.name.en, &c.name.zh));
                            if c.set {
                                ui.colored_label(
                                    egui::Color32::from_rgb(0, 150, 60),
                                    lang.tr("supported", "支持"),
                                );
                            } else {
                                ui.colored_label(
                                    egui::Color32::GRAY,
                                    lang.tr("not supported", "不支持"),
                                );
                            }
                            ui.end_row();
                        }
                    });
                let hidden: Vec<String> = profile
                    .panels
                    .iter()
                    .filter(|r| r.flag.is_some_and(|b| !info.supports(b)))
                    .filter_map(|r| panel_name(r.panel, lang))
                    .collect();
                if !hidden.is_empty() {
                    ui.label(format!(
                        "{}: {}",
                        lang.tr(
                            "Hidden (not supported by this device)",
                            "已隐藏(设备不支持)"
                        ),
                        hidden.join(", ")
                    ));
                }
            }
        }
    }

    /// Takes what one of its jobs reported.
    fn take_output(&mut self, out: Output) {
        match out {
            Output::Ping(r) => self.ping = Some(r),
            Output::Version(r) => self.version = Some(r),
            Output::Power(r) => self.power = Some(r),
        }
    }
}

/// When the device last answered on the link (any answer: polls, jobs, its own frames), on the
/// wall clock and how long ago.
fn last_answer(ui: &mut egui::Ui, lang: Lang, rt: &Station) {
    if let Some(last) = rt.link.last_answer() {
        ui.weak(format!(
            "{} {} ({:.0} {})",
            lang.tr("last answer", "上次应答"),
            last.clock.format("%H:%M:%S%.3f"),
            last.at.elapsed().as_secs_f64(),
            lang.tr("s ago", "秒前")
        ));
        // The seconds ago move on their own.
        ui.ctx().request_repaint_after(Duration::from_secs(1));
    }
}

/// A silent device: what to check (the command line's checklist, in the window's words).
fn silent(ui: &mut egui::Ui, lang: Lang, rt: &Station) {
    if let (true, Answering::No(n)) = (rt.connected(), rt.link.answering()) {
        ui.add_space(6.0);
        ui.colored_label(
            egui::Color32::RED,
            format!(
                "{} ({n} {})",
                lang.tr("The device does not answer", "设备无应答"),
                lang.tr("requests unanswered in a row", "个请求连续未应答")
            ),
        );
        ui.add(egui::Label::new(super::connection::silent_checklist(rt).get(lang)).wrap());
        ui.separator();
    }
}

/// The name in `lang` of the panel the profile calls `kind`.
fn panel_name(kind: crate::profile::PanelKind, lang: Lang) -> Option<String> {
    super::panels()
        .iter()
        .find(|p| p.kind() == Some(kind))
        .map(|p| p.name(lang).to_string())
}

/// Ping, and Read version and power state.
fn buttons(ui: &mut egui::Ui, lang: Lang, rt: &Station, ready: bool) -> Vec<Action> {
    let mut actions = Vec::new();
    let profile = rt.device.profile.clone();
    crate::ui::layout::toolbar(ui, |ui| {
        if ui
            .add_enabled(ready, egui::Button::new(lang.tr("Ping", "通讯检测")))
            .clicked()
        {
            let p = profile.clone();
            actions.push(Action::StartJob(Job::new(
                Text::new("ping", "通讯检测"),
                move |client, _cancel, sink| {
                    let r = ops::ping(Device::new(client, &p)).map(|ping| ping.rtt);
                    sink.panel(Output::Ping(r.clone()));
                    let rtt = r?;
                    let ms = rtt.as_secs_f64() * 1e3;
                    Ok(Text::new(
                        format!("answered in {ms:.1} ms"),
                        format!("{ms:.1} ms 内应答"),
                    ))
                },
            )));
        }
        if ui
            .add_enabled(
                ready,
                egui::Button::new(lang.tr("Read version and power state", "读取版本与电源状态")),
            )
            .clicked()
        {
            // The session's own record (which panels are shown) is refreshed too.
            actions.push(Action::Link(LinkCommand::Identify));
            actions.push(read_job(&profile));
        }
        if !rt.connected() {
            ui.weak(lang.tr("not connected", "未连接"));
        }
    });
    actions
}

impl crate::ui::PanelId {
    /// MSP core commands: ping, version, power state.
    pub const DEVICE: crate::ui::PanelId = crate::ui::PanelId::new("Device");
}

impl crate::ui::Panel for DevicePanel {
    fn id(&self) -> crate::ui::PanelId {
        crate::ui::PanelId::DEVICE
    }

    fn name(&self, lang: Lang) -> &'static str {
        lang.tr("Device", "设备信息")
    }

    fn kind(&self) -> Option<crate::profile::PanelKind> {
        Some(crate::profile::PanelKind::Device)
    }

    fn show(&mut self, ui: &mut egui::Ui, cx: &crate::ui::panel::Cx<'_>) -> Vec<Action> {
        self.draw(ui, cx.lang, cx.station)
    }

    fn on_output(
        &mut self,
        out: crate::ui::panel::PanelOutput,
        _station: &Station,
    ) -> Vec<Action> {
        if let Some(out) = out.take::<Output>() {
            self.take_output(out);
        }
        Vec::new()
    }
}
