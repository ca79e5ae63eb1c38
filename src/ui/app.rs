//! The app shell: saved settings kept apart from runtime state, a top bar, a left navigation, one
//! panel at a time, a status line. Panels return actions; the app applies them once per frame.

use super::jobs::JobOutput;
use super::runtime::{Runtime, Target};
use super::{
    Action, actions, connection, device, monitor, presets, selftest, servo_bench, solar,
    status_bar, telemetry, tuning, tuya_console,
};
use crate::i18n::Lang;
use crate::link::LinkCommand;
use crate::profile::{PanelKind, Protocol};
use eframe::egui;
use serde::{Deserialize, Serialize};

/// The panels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum PanelId {
    /// Window cleaner parameters.
    Tuning,
    /// Live plots and telemetry.
    Telemetry,
    /// Frames sent and received.
    Monitor,
    /// Presets: save, compare, apply.
    Presets,
    /// The device's actions (motor, fan, spray…).
    Actions,
    /// MSP core commands: ping, version, power state.
    Device,
    /// The solar cleanbot's readouts and controls.
    Solar,
    /// The window cleaner's production self-test.
    SelfTest,
    /// Bus servos: scan, parameters, provisioning, motion.
    ServoBench,
    /// Tuya: the module side, data points, OTA.
    TuyaConsole,
}

impl PanelId {
    /// The panel a profile names.
    pub fn of(kind: PanelKind) -> PanelId {
        match kind {
            PanelKind::Device => PanelId::Device,
            PanelKind::Tuning => PanelId::Tuning,
            PanelKind::Telemetry => PanelId::Telemetry,
            PanelKind::Presets => PanelId::Presets,
            PanelKind::Actions => PanelId::Actions,
            PanelKind::Solar => PanelId::Solar,
            PanelKind::SelfTest => PanelId::SelfTest,
        }
    }

    /// The panel's name.
    pub fn name(self, lang: Lang) -> &'static str {
        match self {
            PanelId::Tuning => lang.tr("Tuning", "参数调校"),
            PanelId::Telemetry => lang.tr("Telemetry", "实时数据"),
            PanelId::Monitor => lang.tr("Packet monitor", "报文监视"),
            PanelId::Presets => lang.tr("Presets", "预设"),
            PanelId::Actions => lang.tr("Actions", "动作测试"),
            PanelId::Device => lang.tr("Device", "设备信息"),
            PanelId::Solar => lang.tr("Solar cleanbot", "光伏清扫机器人"),
            PanelId::SelfTest => lang.tr("Self-test", "产线自检"),
            PanelId::ServoBench => lang.tr("Servo bench", "舵机调试"),
            PanelId::TuyaConsole => lang.tr("Tuya console", "涂鸦控制台"),
        }
    }
}

/// What is kept between runs (eframe storage).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Saved {
    /// The last target.
    pub target: Target,
    /// The last baud rate.
    pub baud: u32,
    /// The last profile.
    pub profile: String,
    /// The panel shown.
    pub panel: PanelId,
    /// The UI language.
    pub lang: Lang,
    /// Telemetry: polls a second (`None`: as fast as the wire allows).
    pub poll_hz: Option<f64>,
    /// Telemetry: the plotted time window, seconds.
    pub window_secs: f64,
    /// The navigation is shown.
    pub nav_open: bool,
    /// How long the device may take to start answering, ms (`None`: the protocol's own).
    pub margin_ms: Option<u64>,
}

impl Default for Saved {
    fn default() -> Self {
        Self {
            target: Target::Demo("window-cleaner".into()),
            baud: 115_200,
            profile: "window-cleaner".into(),
            panel: PanelId::Tuning,
            lang: Lang::En,
            poll_hz: Some(50.0),
            window_secs: 60.0,
            nav_open: true,
            margin_ms: None,
        }
    }
}

/// The application.
pub struct App {
    /// Kept between runs.
    pub saved: Saved,
    /// Not kept.
    pub rt: Runtime,
    /// The tuning panel's edits.
    pub tuning: tuning::TuningPanel,
    /// The telemetry panel's view state.
    pub telemetry: telemetry::TelemetryPanel,
    /// The packet monitor's view state.
    pub monitor: monitor::MonitorPanel,
    /// The connection bar's fields.
    pub connection: connection::ConnectionBar,
    /// The presets panel.
    pub presets: presets::PresetsPanel,
    /// The actions panel.
    pub actions: actions::ActionsPanel,
    /// The device panel.
    pub device: device::DevicePanel,
    /// The solar cleanbot panel.
    pub solar: solar::SolarPanel,
    /// The self-test panel.
    pub selftest: selftest::SelfTestPanel,
    /// The servo bench.
    pub servo: servo_bench::ServoBenchPanel,
    /// The Tuya console.
    pub tuya: tuya_console::TuyaConsolePanel,
    /// The window title last set.
    title: String,
}

impl App {
    /// An app with `saved` settings, connected to its target.
    pub fn new(ctx: &egui::Context, saved: Saved) -> Result<Self, String> {
        crate::i18n::install_cjk_font(ctx);
        let rt = Runtime::new(ctx, &saved.profile)?;
        let mut app = Self {
            connection: connection::ConnectionBar::new(&saved),
            saved,
            rt,
            tuning: tuning::TuningPanel::default(),
            telemetry: telemetry::TelemetryPanel::default(),
            monitor: monitor::MonitorPanel::default(),
            presets: presets::PresetsPanel::default(),
            actions: actions::ActionsPanel::default(),
            device: device::DevicePanel::default(),
            solar: solar::SolarPanel::default(),
            selftest: selftest::SelfTestPanel::default(),
            servo: servo_bench::ServoBenchPanel::default(),
            tuya: tuya_console::TuyaConsolePanel::default(),
            title: String::new(),
        };
        let (target, baud, profile) = (
            app.saved.target.clone(),
            app.saved.baud,
            app.saved.profile.clone(),
        );
        app.apply(Action::Connect {
            target,
            baud,
            profile,
        });
        Ok(app)
    }

    /// Work that is not drawing: worker events (within a time budget) and job output.
    pub fn logic(&mut self, ctx: &egui::Context) {
        if self.rt.drain_events() {
            ctx.request_repaint();
        }
        for out in self.rt.drain_job() {
            match out {
                JobOutput::Servo(o) => self.servo.on_output(o),
                JobOutput::Tuya(o) => self.tuya.on_output(o),
                JobOutput::Device(o) => self.device.on_output(o),
                JobOutput::SelfTest(o) => {
                    // An operator prompt is answered on the self-test panel.
                    if o.is_prompt() {
                        self.saved.panel = PanelId::SelfTest;
                    }
                    self.selftest.on_output(o)
                }
                JobOutput::Solar(o) => self.solar.on_output(o),
                _ => {}
            }
        }
        self.rt.refresh_ports();
        // The app leaves a panel the device turns out not to support.
        let panels = self.panels();
        if !panels.contains(&self.saved.panel) {
            self.saved.panel = panels[0];
        }
        // The solar panel's STOP-on-reconnect and dead-man run whichever panel is shown.
        for a in self.solar.tick(&self.rt) {
            self.apply(a);
        }
        if std::mem::take(&mut self.rt.just_connected) && self.panels().contains(&PanelId::Tuning) {
            // What the device holds is shown as soon as it is known; nothing is shown before.
            let gets: Vec<u8> = self
                .rt
                .profile
                .commands
                .iter()
                .filter(|c| c.kind == crate::profile::CommandKind::Get && c.pair.is_some())
                .map(|c| c.id)
                .collect();
            self.apply(Action::Job(super::JobSpec::Read(gets)));
        }
        let title = match &self.rt.conn {
            Some(c) => format!(
                "botbench — {} — {}",
                c.target.label(),
                self.rt.profile.name.en
            ),
            None => "botbench — not connected".to_string(),
        };
        // Only on a change: a viewport command every frame would keep the window repainting.
        if self.title != title {
            ctx.send_viewport_cmd(egui::ViewportCommand::Title(title.clone()));
            self.title = title;
        }
        // Repaint while a plot follows live data or a job runs; otherwise only on events.
        let live = matches!(self.saved.panel, PanelId::Telemetry | PanelId::Solar)
            && !self.rt.paused
            && self.rt.connected();
        if live || self.rt.job_progress().is_some() {
            ctx.request_repaint_after(std::time::Duration::from_millis(33));
        }
    }

    /// Draws the window and applies what the panels asked for.
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        let lang = self.saved.lang;
        let mut actions = Vec::new();
        egui::Panel::top("connection").show(ui, |ui| {
            actions.extend(self.connection.show(ui, &mut self.saved, &self.rt));
        });
        egui::Panel::bottom("status").show(ui, |ui| {
            actions.extend(status_bar::show(ui, lang, &self.rt));
        });
        egui::Panel::left("nav").resizable(false).show(ui, |ui| {
            ui.add_space(4.0);
            for panel in self.panels() {
                if ui
                    .selectable_label(self.saved.panel == panel, panel.name(lang))
                    .clicked()
                {
                    self.saved.panel = panel;
                }
            }
            // The solar cleanbot's STOP is on every panel.
            if self.saved.panel != PanelId::Solar && self.panels().contains(&PanelId::Solar) {
                ui.separator();
                actions.extend(self.solar.stop_button(ui, lang, &self.rt));
            }
        });
        egui::CentralPanel::default().show(ui, |ui| match self.saved.panel {
            PanelId::Tuning => actions.extend(self.tuning.show(ui, lang, &self.rt)),
            PanelId::Telemetry => {
                actions.extend(self.telemetry.show(ui, &mut self.saved, &self.rt))
            }
            PanelId::Monitor => actions.extend(self.monitor.show(ui, lang, &mut self.rt)),
            PanelId::Presets => actions.extend(self.presets.show(ui, lang, &self.rt)),
            PanelId::Actions => actions.extend(self.actions.show(ui, lang, &self.rt)),
            PanelId::Device => actions.extend(self.device.show(ui, lang, &self.rt)),
            PanelId::Solar => actions.extend(self.solar.show(ui, lang, &self.rt)),
            PanelId::SelfTest => actions.extend(self.selftest.show(ui, lang, &self.rt)),
            PanelId::ServoBench => actions.extend(self.servo.show(ui, lang, &self.rt)),
            PanelId::TuyaConsole => actions.extend(self.tuya.show(ui, lang, &self.rt)),
        });
        for a in actions {
            self.apply(a);
        }
    }

    /// The panels the profile has.
    pub fn panels(&self) -> Vec<PanelId> {
        let mut v = Vec::new();
        match self.rt.profile.protocol {
            Protocol::Servo => return vec![PanelId::ServoBench, PanelId::Monitor],
            Protocol::Tuya => return vec![PanelId::TuyaConsole, PanelId::Monitor],
            Protocol::Msp => v.push(PanelId::Device),
        }
        if self.rt.profile.protocol == Protocol::Msp
            && self
                .rt
                .profile
                .commands
                .iter()
                .any(|c| c.kind == crate::profile::CommandKind::Set)
        {
            v.push(PanelId::Tuning);
        }
        if !self.rt.profile.plots.is_empty() {
            v.push(PanelId::Telemetry);
        }
        if !crate::preset::preset_commands(&self.rt.profile).is_empty() {
            v.push(PanelId::Presets);
        }
        if self.rt.profile.protocol == Protocol::Msp
            && self
                .rt
                .profile
                .commands
                .iter()
                .any(|c| c.kind == crate::profile::CommandKind::Action)
        {
            v.push(PanelId::Actions);
        }
        for rule in &self.rt.profile.panels {
            match rule.panel {
                PanelKind::Solar => v.push(PanelId::Solar),
                PanelKind::SelfTest => v.push(PanelId::SelfTest),
                _ => {}
            }
        }
        v.push(PanelId::Monitor);
        // A panel whose capability bit the device reports clear is hidden (nothing is hidden
        // before the device has answered CMD_VERSION).
        if let Some(Ok(info)) = &self.rt.info {
            v.retain(|p| {
                self.rt.profile.panels.iter().all(|r| {
                    r.flag
                        .is_none_or(|bit| PanelId::of(r.panel) != *p || info.supports(bit))
                })
            });
        }
        v
    }

    /// Carries out one action.
    pub fn apply(&mut self, action: Action) {
        match action {
            Action::Connect {
                target,
                baud,
                profile,
            } => self.connect(target, baud, profile),
            Action::Disconnect => {
                self.rt.disconnect();
                self.rt.say("disconnected", false);
            }
            Action::Job(job) => job.start(&mut self.rt),
            Action::SetPollRate(hz) => {
                self.saved.poll_hz = hz;
                self.restart_polls();
            }
            Action::PausePolling(paused) => {
                self.rt.paused = paused;
                self.restart_polls();
            }
            Action::CancelJob => {
                if let Some(j) = &self.rt.job {
                    j.cancel.cancel();
                }
            }
            Action::Say(text, error) => self.rt.say(text, error),
            Action::Link(cmd) => self.rt.send(cmd),
            Action::StartJob(job) => self.rt.start_job(&job.title, job.work),
        }
    }

    fn connect(&mut self, target: Target, baud: u32, profile: String) {
        self.rt.link_options.margin = self.saved.margin_ms.map(std::time::Duration::from_millis);
        if let Err(e) = self.rt.connect(target.clone(), baud, &profile) {
            self.rt.say(format!("cannot connect: {e}"), true);
            return;
        }
        self.saved.target = target;
        self.saved.baud = baud;
        self.saved.profile = profile;
        self.tuning = tuning::TuningPanel::default();
        // What was found on another connection is not on this one.
        self.servo.forget_bus();
        if !self.panels().contains(&self.saved.panel) {
            self.saved.panel = self.panels()[0];
        }
        self.restart_polls();
    }

    fn restart_polls(&mut self) {
        let polls = if self.rt.paused {
            Vec::new()
        } else {
            self.rt.polls(self.saved.poll_hz)
        };
        self.rt.send(LinkCommand::SetPolls(polls));
    }
}

impl eframe::App for App {
    fn logic(&mut self, ctx: &egui::Context, _frame: &mut eframe::Frame) {
        App::logic(self, ctx);
    }

    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        App::ui(self, ui);
    }

    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        eframe::set_value(storage, eframe::APP_KEY, &self.saved);
    }
}
