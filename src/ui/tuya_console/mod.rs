//! The Tuya console: botbench as the Wi-Fi module. The handshake step by step, the data points
//! generated from the profile, the MCU's own requests and the module's answers, and the MCU
//! firmware update (OTA). What the link reported is kept by the device model
//! ([`super::station::TuyaModel`]); this panel keeps only what the technician chose and typed.

mod conform;
mod dps;
mod handshake;
mod mcu_requests;
mod ota;

pub use ota::FirmwareFileError;

use super::Action;
use super::jobs::JobError;
use super::station::Station;
use crate::i18n::Lang;
use crate::link::{LinkCommand, ReplyTo, Request, TuyaModuleOptions};
use crate::ops::tuya::OtaReport;
use chrono::{DateTime, Local};
use eframe::egui;

/// The console's sections.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Tab {
    /// Start-up handshake, heartbeat, Wi-Fi state.
    #[default]
    Handshake,
    /// Data points.
    DataPoints,
    /// The MCU's own requests.
    Requests,
    /// Firmware update.
    Ota,
    /// The conformance grade of the MCU's firmware.
    Conform,
}

impl Tab {
    /// Every tab, in the order shown.
    pub(crate) const ALL: [Tab; 5] = [
        Tab::Handshake,
        Tab::DataPoints,
        Tab::Requests,
        Tab::Ota,
        Tab::Conform,
    ];

    fn name(self, lang: Lang) -> &'static str {
        match self {
            Tab::Handshake => lang.tr("Handshake", "握手"),
            Tab::DataPoints => lang.tr("Data points", "数据点"),
            Tab::Requests => lang.tr("MCU requests", "MCU请求"),
            Tab::Ota => lang.tr("Firmware update", "固件升级"),
            Tab::Conform => lang.tr("Conformance", "协议一致性"),
        }
    }
}

/// The panel's state.
#[derive(Default)]
pub struct TuyaConsolePanel {
    /// The section shown.
    pub tab: Tab,
    /// What the module answers the MCU (sent to the worker on each change and on connecting).
    pub opts: TuyaModuleOptions,
    /// The connection (session generation) the options were last sent to; `None` sends them
    /// again on the next frame.
    pub synced: Option<u64>,
    /// The data points' edits and sends.
    pub dps: dps::DpView,
    /// The MCU-request settings being typed.
    pub requests: mcu_requests::RequestsView,
    /// The firmware update.
    pub ota: ota::OtaView,
    /// The conformance grade.
    pub conform: conform::ConformView,
}

/// What this panel's jobs report.
#[derive(Debug, Clone)]
pub enum Output {
    /// How far the firmware update is.
    OtaProgress(ota::OtaProgress),
    /// The firmware update ended.
    OtaDone(Result<OtaReport, JobError>),
    /// A conformance check ended.
    ConformCheck(crate::ops::tuya::conform::Check),
    /// The conformance grade ended.
    ConformDone(Result<crate::ops::tuya::conform::Conformance, JobError>),
}

/// A time as shown: `12:03:04.512`.
pub(crate) fn clock(t: &DateTime<Local>) -> String {
    t.format("%H:%M:%S%.3f").to_string()
}

/// A request (built by [`crate::ops::tuya`]) for the worker, whose answer nobody waits for: what
/// it brings is seen in the device model (reports, acks).
pub(crate) fn fire(request: Request) -> Action {
    Action::Link(LinkCommand::Request {
        request,
        reply_to: ReplyTo::Event(0),
    })
}

/// The label of a state 0-6 (Wi-Fi state, network status), from the profile's Wi-Fi command.
pub(crate) fn wifi_state_name(rt: &Station, lang: Lang, state: u8) -> String {
    rt.device
        .profile
        .command_by_id(crate::protocol::tuya::cmd::WIFI_STATE)
        .and_then(|c| c.request.first())
        .and_then(|f| f.label(i64::from(state)))
        .map_or_else(
            || format!("{state}"),
            |l| format!("{state}: {}", lang.tr(&l.name.en, &l.name.zh)),
        )
}

impl TuyaConsolePanel {
    /// Draws the panel.
    fn draw(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &Station) -> Vec<Action> {
        let mut actions = Vec::new();
        // A new connection has a new worker with default answers: give it ours.
        if rt.connected() && self.synced != Some(rt.device.tuya.generation) {
            self.synced = Some(rt.device.tuya.generation);
            actions.push(Action::Link(LinkCommand::TuyaOptions(self.opts.clone())));
        }
        handshake::summary(ui, lang, rt);
        ui.horizontal(|ui| {
            for tab in Tab::ALL {
                if ui
                    .selectable_label(self.tab == tab, tab.name(lang))
                    .clicked()
                {
                    self.tab = tab;
                }
            }
        });
        ui.separator();
        let before = self.opts.clone();
        egui::ScrollArea::vertical()
            .auto_shrink(false)
            .show(ui, |ui| match self.tab {
                Tab::Handshake => actions.extend(handshake::show(ui, lang, rt, &mut self.opts)),
                Tab::DataPoints => actions.extend(self.dps.show(ui, lang, rt, self.ota.active(rt))),
                Tab::Requests => actions.extend(self.requests.show(ui, lang, rt, &mut self.opts)),
                Tab::Ota => actions.extend(self.ota.show(ui, lang, rt)),
                Tab::Conform => actions.extend(self.conform.show(ui, lang, rt)),
            });
        if self.opts != before {
            // Options go before anything the section asked for (the Wi-Fi state report).
            actions.insert(0, Action::Link(LinkCommand::TuyaOptions(self.opts.clone())));
        }
        actions
    }

}

impl crate::ui::PanelId {
    /// Tuya: the module side, data points, the MCU's requests, OTA.
    pub const TUYA_CONSOLE: crate::ui::PanelId = crate::ui::PanelId::new("TuyaConsole");
}

impl crate::ui::Panel for TuyaConsolePanel {
    fn id(&self) -> crate::ui::PanelId {
        crate::ui::PanelId::TUYA_CONSOLE
    }

    fn name(&self, lang: Lang) -> &'static str {
        lang.tr("Tuya console", "涂鸦控制台")
    }

    fn kind(&self) -> Option<crate::profile::PanelKind> {
        Some(crate::profile::PanelKind::TuyaConsole)
    }

    fn show(&mut self, ui: &mut egui::Ui, cx: &crate::ui::panel::Cx<'_>) -> Vec<Action> {
        self.draw(ui, cx.lang, cx.station)
    }

    fn on_output(&mut self, out: crate::ui::panel::PanelOutput, _station: &Station) -> Vec<Action> {
        match out.take::<Output>() {
            Some(out @ (Output::OtaProgress(_) | Output::OtaDone(_))) => self.ota.on_output(out),
            Some(out) => self.conform.on_output(out),
            None => {}
        }
        Vec::new()
    }

    /// The firmware image last used.
    fn restore(&mut self, settings: &crate::ui::Settings) {
        if let Some(p) = settings.file(crate::ui::settings::FileKind::Firmware) {
            self.ota.path = p.to_string();
        }
    }

    /// Its tabs.
    fn parts(&self, _station: &Station) -> Vec<String> {
        Tab::ALL.iter().map(|t| format!("{t:?}")).collect()
    }

    fn show_part(&mut self, part: usize, _station: &Station) {
        if let Some(&tab) = Tab::ALL.get(part) {
            self.tab = tab;
        }
    }
}
