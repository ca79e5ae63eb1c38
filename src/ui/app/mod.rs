//! The app shell: saved settings kept apart from run-time state, a top bar, a left navigation,
//! one panel at a time, a status line. Each frame the app takes the link's events and the
//! running job's output (each routed once, to the state or the panel it concerns), lets the
//! panels draw, and applies the actions they returned.

use super::jobs::{self, JobOutput};
use super::settings::{self, FileKind, Settings};
use super::station::{Notice, Station, Target};
use super::{
    Action, actions, connection, demo_hint, device, files, layout, monitor, presets, repaint,
    selftest, servo_bench, solar, status_bar, stop, telemetry, tour, tuning, tuya_console,
};
use crate::i18n::Lang;
use crate::i18n::Text;
use crate::link::{LinkCommand, PortOpener};
use crate::profile::{PanelKind, ProfileError, Registry};
use crate::ui::zh::Zh;
use eframe::egui;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// The start of the window's title: `botbench 0.1.0`.
pub const TITLE: &str = concat!("botbench ", env!("CARGO_PKG_VERSION"));

/// The panels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
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
    /// Production records: yield, failing steps, measurements.
    Yield,
}

impl PanelId {
    /// Every panel.
    pub const ALL: [PanelId; 11] = [
        PanelId::Device,
        PanelId::Tuning,
        PanelId::Telemetry,
        PanelId::Presets,
        PanelId::Actions,
        PanelId::Solar,
        PanelId::SelfTest,
        PanelId::ServoBench,
        PanelId::TuyaConsole,
        PanelId::Monitor,
        PanelId::Yield,
    ];

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
            PanelKind::ServoBench => PanelId::ServoBench,
            PanelKind::TuyaConsole => PanelId::TuyaConsole,
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
            PanelId::Yield => lang.tr("Yield", "良率"),
        }
    }
}

/// The window's run-time state (never saved): its stations, one today, each everything the
/// window holds about one connected device, and the profiles they share.
pub struct AppState {
    /// Every profile (each station holds the same, shared).
    pub registry: Arc<Registry>,
    /// Never empty: [`Self::new`] makes the first.
    stations: Vec<Station>,
    /// The index of the station the panels show.
    shown: usize,
}

impl AppState {
    /// The state of a window with one station, `first`, shown.
    pub fn new(registry: Arc<Registry>, first: Station) -> Self {
        Self {
            registry,
            stations: vec![first],
            shown: 0,
        }
    }

    /// The station the panels show.
    pub fn station(&self) -> &Station {
        &self.stations[self.shown]
    }

    /// The station the panels show, to change.
    pub fn station_mut(&mut self) -> &mut Station {
        &mut self.stations[self.shown]
    }

    /// Every station, in the order they were added.
    pub fn stations(&self) -> &[Station] {
        &self.stations
    }
}

/// The application.
pub struct App {
    /// Kept between runs.
    pub settings: Settings,
    /// Not kept: the stations (link status, device model, packet log, job, status line).
    pub state: AppState,
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
    /// The Yield view.
    pub yield_view: super::yield_view::YieldPanel,
    /// The screenshot tour, when the window was opened for one.
    pub tour: Option<tour::Tour>,
    /// STOP: on screen for every profile that names one.
    pub stop: stop::StopControl,
    /// The window title last set.
    title: String,
}

impl App {
    /// An app with `settings`, connected to its target; a port named by its path is opened with
    /// `ports` (the system's serial ports, [`PortOpener::system`], or a test's simulator).
    /// Errors: no profile loads ([`ProfileError`]).
    pub fn new(
        ctx: &egui::Context,
        settings: Settings,
        ports: PortOpener,
    ) -> Result<Self, ProfileError> {
        crate::i18n::install_cjk_font(ctx);
        // Scroll bars shown solid wherever a panel has more than its room (egui's floating
        // ones show only under the pointer: a technician does not see that more is below).
        ctx.all_styles_mut(|s| s.spacing.scroll = egui::style::ScrollStyle::solid());
        let registry = Arc::new(Registry::load()?);
        let mut station = Station::new(ctx, registry.clone(), &settings.profile)?;
        station.link.port_opener = ports;
        let state = AppState::new(registry, station);
        let (baud, margin_ms) = port_for(&settings, &state.registry, &settings.profile);
        let mut app = Self {
            connection: connection::ConnectionBar::new(&settings, baud),
            settings,
            state,
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
            yield_view: super::yield_view::YieldPanel::default(),
            tour: None,
            stop: stop::StopControl::default(),
            title: String::new(),
        };
        app.restore_files();
        app.apply(Action::Connect {
            target: app.settings.target.clone(),
            baud,
            profile: app.settings.profile.clone(),
            margin_ms,
        });
        Ok(app)
    }

    /// The station the panels show.
    pub fn station(&self) -> &Station {
        self.state.station()
    }

    /// The station the panels show, to change.
    pub fn station_mut(&mut self) -> &mut Station {
        self.state.station_mut()
    }

    /// Work that is not drawing: worker events (within a time budget), job output, and what the
    /// app does on its own (the solar STOP and dead-man, reading a device that came up).
    pub fn logic(&mut self, ctx: &egui::Context) {
        if self.state.station_mut().drain_link_events() {
            ctx.request_repaint();
        }
        for out in self.state.station_mut().take_job_output() {
            self.route(out);
        }
        self.state.station_mut().link.refresh_ports();
        // The app leaves a panel the device turns out not to support.
        let panels = self.panels();
        if !panels.contains(&self.settings.panel) {
            self.settings.panel = panels[0];
        }
        // STOP-on-reconnect and the solar dead-man run whichever panel is shown.
        for a in self.stop.tick(self.state.station()) {
            self.apply(a);
        }
        for a in self.solar.tick(self.state.station()) {
            self.apply(a);
        }
        // A device that answers again after silence may be another unit on the same port (a
        // robot swapped on the fixture): what the last one showed is forgotten, and it is
        // identified and read again. A link that came back starts a new unit too.
        let fresh = std::mem::take(&mut self.state.station_mut().link.just_connected);
        let back = std::mem::take(&mut self.state.station_mut().link.device_back);
        if back {
            self.state.station_mut().device.forget_unit();
            self.state.station_mut().send(LinkCommand::Identify);
            self.state.station_mut().notify(Notice::info(Text::new(
                "the device answers again: identified and read again (it may be another unit)",
                "设备重新应答:已重新识别并读取(可能是另一台设备)",
            )));
        } else if fresh {
            self.state.station_mut().device.unit += 1;
        }
        self.selftest
            .forget_other_unit(self.state.station_mut().device.unit);
        if (fresh || back) && self.panels().contains(&PanelId::Tuning) {
            // What the device holds is shown as soon as it is known; nothing is shown before.
            let profile = self.station().device.profile.clone();
            let gets: Vec<u8> = profile
                .commands
                .iter()
                .filter(|c| c.kind == crate::profile::CommandKind::Get && c.pair.is_some())
                .map(|c| c.id)
                .collect();
            self.apply(Action::StartJob(jobs::read(&profile, gets)));
        }
        let title = match self.state.station_mut().link.target() {
            Some(t) => format!(
                "{TITLE} — {} — {}",
                t.label(),
                self.state.station_mut().device.profile.name.en
            ),
            None => format!("{TITLE} — not connected"),
        };
        // Only on a change: a viewport command every frame would keep the window repainting.
        if self.title != title {
            ctx.send_viewport_cmd(egui::ViewportCommand::Title(title.clone()));
            self.title = title;
        }
        if let Some(after) = self.repaint_after() {
            ctx.request_repaint_after(after);
        }
        if let Some(mut tour) = self.tour.take() {
            tour.step(ctx, self);
            self.tour = Some(tour);
        }
    }

    /// How soon the window redraws on its own: at [`repaint::LIVE`] while a live view is shown
    /// (a plot of polled telemetry, the packet monitor while frames are logged) or a job runs;
    /// `None` otherwise (idle, paused or disconnected: the window sleeps until input or a
    /// worker event).
    pub fn repaint_after(&self) -> Option<std::time::Duration> {
        let connected = self.state.station().connected();
        let live = match self.settings.panel {
            PanelId::Telemetry | PanelId::Solar => {
                connected && !self.state.station().link.polling_paused
            }
            PanelId::Monitor => connected && !self.state.station().packets.paused,
            _ => false,
        };
        (live || self.state.station().job_progress().is_some()).then_some(repaint::LIVE)
    }

    /// Routes one piece of job output: to the device model, the status line or its panel.
    fn route(&mut self, out: JobOutput) {
        match out {
            JobOutput::Progress(_) => {}
            JobOutput::Read(id, r) => self.state.station_mut().device.on_read(id, r),
            JobOutput::Wrote(set, r) => self.state.station_mut().device.on_written(set, r),
            JobOutput::Done(r) => self.state.station_mut().job_done(r),
            JobOutput::Servo(o) => self
                .servo
                .on_output(o, &self.state.station_mut().device.profile),
            JobOutput::Tuya(o) => self.tuya.on_output(o),
            JobOutput::Device(o) => self.device.on_output(o),
            JobOutput::SelfTest(o) => {
                // An operator prompt is answered on the self-test panel.
                if o.is_prompt() {
                    self.settings.panel = PanelId::SelfTest;
                }
                self.selftest
                    .on_output(o, self.state.station_mut().device.unit)
            }
        }
    }

    /// Draws the window and applies what the panels asked for.
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        let lang = self.settings.lang;
        let (settings, state) = (&self.settings, self.state.station());
        let mut actions = Vec::new();
        egui::Panel::top("connection").show(ui, |ui| {
            actions.extend(self.connection.show(ui, settings, state));
            demo_hint::show(ui, lang, state);
        });
        egui::Panel::bottom("status").show(ui, |ui| {
            actions.extend(status_bar::show(ui, lang, state));
        });
        let panels = self.panels();
        egui::Panel::left("nav")
            .resizable(false)
            .exact_size(nav_width(ui))
            .show(ui, |ui| {
                ui.add_space(4.0);
                ui.scope(|ui| {
                    layout::keep_words_whole(ui);
                    for &panel in &panels {
                        if ui
                            .selectable_label(settings.panel == panel, panel.name(lang))
                            .clicked()
                        {
                            actions.push(Action::ShowPanel(panel));
                        }
                    }
                });
                // STOP is on every panel of a robot whose profile names one (the solar panel
                // shows its own at the top), with what the robot may be doing.
                if !state.device.profile.stop.is_empty() {
                    ui.separator();
                    if settings.panel != PanelId::Solar {
                        actions.extend(self.stop.button(ui, lang, state));
                        self.stop.status(ui, lang);
                    }
                    stop::running(ui, lang, state);
                }
            });
        // Each panel's widgets have ids of their own: a scroll area of one panel keeps its own
        // place, not the place of the panel shown before it.
        let panel = settings.panel;
        egui::CentralPanel::default().show(ui, |ui| {
            ui.push_id(panel, |ui| match panel {
                PanelId::Tuning => actions.extend(self.tuning.show(ui, lang, state)),
                PanelId::Telemetry => actions.extend(self.telemetry.show(ui, settings, state)),
                PanelId::Monitor => actions.extend(self.monitor.show(ui, lang, state)),
                PanelId::Presets => actions.extend(self.presets.show(ui, lang, state)),
                PanelId::Actions => actions.extend(self.actions.show(ui, lang, state)),
                PanelId::Device => actions.extend(self.device.show(ui, lang, state)),
                PanelId::Solar => actions.extend(self.solar.show(ui, lang, state, &mut self.stop)),
                PanelId::SelfTest => actions.extend(self.selftest.show(ui, lang, state)),
                PanelId::ServoBench => actions.extend(self.servo.show(ui, lang, state)),
                PanelId::TuyaConsole => actions.extend(self.tuya.show(ui, lang, state)),
                PanelId::Yield => actions.extend(self.yield_view.show(ui, lang, state)),
            })
        });
        for a in actions {
            self.apply(a);
        }
        if let Some(tour) = &mut self.tour {
            tour.after_ui(ui.ctx());
        }
    }

    /// Connects to the built-in demo device `kind` at its own rate with its profile, as the
    /// port picker does (the connection bar shows it).
    pub fn connect_demo(&mut self, kind: crate::sim::SimKind) {
        self.apply(Action::Connect {
            target: Target::Demo(kind.name().to_string()),
            baud: kind.default_baud(),
            profile: kind.profile_id().to_string(),
            margin_ms: None,
        });
        let (baud, _) = port_for(&self.settings, &self.state.registry, &self.settings.profile);
        self.connection = connection::ConnectionBar::new(&self.settings, baud);
    }

    /// The window's title: `botbench 0.1.0 — built-in simulated window-cleaner — Window-cleaning
    /// robot`, or `botbench 0.1.0 — not connected`.
    pub fn title(&self) -> &str {
        &self.title
    }

    /// The panels the profile lists, then the packet monitor. A panel whose CMD_VERSION
    /// capability bit the device reports clear is hidden (nothing is hidden before the device
    /// has answered CMD_VERSION).
    pub fn panels(&self) -> Vec<PanelId> {
        let profile = &self.state.station().device.profile;
        let info = match &self.state.station().device.info {
            Some(Ok(info)) => Some(info),
            _ => None,
        };
        let mut v: Vec<PanelId> = profile
            .panels
            .iter()
            .filter(|r| {
                r.flag
                    .is_none_or(|bit| info.is_none_or(|i| i.supports(bit)))
            })
            .map(|r| PanelId::of(r.panel))
            .collect();
        v.push(PanelId::Monitor);
        v.push(PanelId::Yield);
        v
    }

    /// Carries out one action.
    pub fn apply(&mut self, action: Action) {
        match action {
            Action::Connect {
                target,
                baud,
                profile,
                margin_ms,
            } => self.connect(target, baud, profile, margin_ms),
            Action::Disconnect => {
                self.state.station_mut().disconnect();
                self.station_mut()
                    .notify(Notice::info(Text::new("disconnected", "已断开")));
            }
            Action::SetLatencyTimer { port, ms } => {
                match crate::system::adapter::set_latency_timer(&port, ms) {
                    Ok(now) => {
                        // The link reads the latency timer when it opens the port.
                        if self.state.station_mut().link.target()
                            == Some(&Target::Port(port.clone()))
                        {
                            let profile = self.settings.profile.clone();
                            let (baud, margin_ms) =
                                port_for(&self.settings, &self.state.registry, &profile);
                            self.connect(Target::Port(port.clone()), baud, profile, margin_ms);
                        }
                        self.state.station_mut().link.refresh_ports_now();
                        self.state.station_mut().notify(Notice::info(Text::new(
                            format!("{port}: latency timer set to {now} ms"),
                            format!("{port}:延迟定时器已设为 {now} ms"),
                        )));
                    }
                    Err(e) => self.state.station_mut().notify(Notice::error(Text::new(
                        format!("{port}: latency timer not set: {e}"),
                        format!("{port}:延迟定时器未设置:{e}"),
                    ))),
                }
            }
            Action::StartJob(job) => self.state.station_mut().start_job(job),
            Action::CancelJob => self.state.station_mut().cancel_job(),
            Action::SetPollRate(hz) => {
                self.settings.poll_hz = hz;
                self.restart_polls();
            }
            Action::PausePolling(paused) => {
                if paused != self.state.station_mut().link.polling_paused {
                    // Nothing is measured while paused: the plots break there.
                    self.state.station_mut().device.mark_gap();
                }
                self.state.station_mut().link.polling_paused = paused;
                self.state.station_mut().link.paused_at = paused.then(std::time::Instant::now);
                self.restart_polls();
            }
            Action::SetPlotWindow(secs) => self.settings.window_secs = secs,
            Action::ShowPanel(panel) => self.settings.panel = panel,
            Action::SetLanguage(lang) => self.settings.lang = lang,
            Action::PausePacketLog(paused) => self.state.station_mut().packets.paused = paused,
            Action::ClearPacketLog => self.state.station_mut().packets.clear(),
            Action::StartCapture(path) => self.state.station_mut().start_capture(&path),
            Action::StopCapture => self.state.station_mut().stop_capture(),
            Action::OpenCapture(path) => self.state.station_mut().open_capture(&path),
            Action::CloseCapture => self.state.station_mut().close_capture(),
            Action::Notify(n) => self.state.station_mut().notify(n),
            Action::DemoMcuRequest(r) => {
                if let Some(mcu) = self.state.station_mut().link.demo_tuya() {
                    mcu.lock().unwrap_or_else(|e| e.into_inner()).request(r);
                }
            }
            Action::RememberFile(kind, path) => {
                self.settings.files.insert(kind, path);
            }
            Action::Link(cmd) => self.state.station_mut().send(cmd),
            Action::Stop => {
                for a in self.stop.stop(self.state.station()) {
                    self.apply(a);
                }
            }
        }
    }

    /// The files last used, back in their boxes; the self-test and provisioning plans, when
    /// none was used yet, are the shipped ones (found wherever the binary runs, see
    /// [`files::shipped_in`]).
    fn restore_files(&mut self) {
        let file = |k| self.settings.file(k).map(str::to_string);
        if let Some(p) = file(FileKind::Packets) {
            self.monitor.save_path = p;
        }
        if let Some(p) = file(FileKind::TelemetryCsv) {
            self.telemetry.csv_path = p;
        }
        if let Some(p) = file(FileKind::Preset) {
            self.presets.path = p;
        }
        if let Some(p) = file(FileKind::SelfTestLog) {
            self.selftest.log_path = p;
        }
        if let Some(p) = file(FileKind::ServoPreset) {
            self.servo.params.preset_path = p;
        }
        if let Some(p) = file(FileKind::ProvisionLog) {
            self.servo.production.log_path = p;
        }
        if let Some(p) = file(FileKind::Firmware) {
            self.tuya.ota.path = p;
        }
        if let Some(p) = file(FileKind::Capture) {
            self.monitor.capture_path = p;
        }
        self.state
            .station_mut()
            .records
            .configure(file(FileKind::Records));
        let shipped = |name| {
            files::shipped_in(&files::shipped_dir(), name)
                .ok()
                .map(|p| p.display().to_string())
        };
        if let Some(p) =
            file(FileKind::SelfTestPlan).or_else(|| shipped("window-cleaner-selftest.ron"))
        {
            self.selftest.path = p;
        }
        if let Some(p) =
            file(FileKind::ProvisionPlan).or_else(|| shipped("servo-provision-plan.ron"))
        {
            self.servo.production.plan_path = p;
        }
    }

    fn connect(&mut self, target: Target, baud: u32, profile: String, margin_ms: Option<u64>) {
        self.state.station_mut().link.options.margin =
            margin_ms.map(std::time::Duration::from_millis);
        if let Err(e) = self
            .state
            .station_mut()
            .connect(target.clone(), baud, &profile)
        {
            self.state.station_mut().notify(Notice::error(
                Text::new("cannot connect", "无法连接").then(": ", &e.said()),
            ));
            return;
        }
        self.settings.target = target;
        self.settings.profile = profile;
        // Kept for this profile only: another device keeps its own.
        *self.settings.port_mut() = settings::PortSettings {
            baud: Some(baud),
            margin_ms,
        };
        self.tuning = tuning::TuningPanel::default();
        self.stop = stop::StopControl::default();
        // What was found on another connection is not on this one.
        self.servo.forget_bus();
        if !self.panels().contains(&self.settings.panel) {
            self.settings.panel = self.panels()[0];
        }
        self.restart_polls();
    }

    fn restart_polls(&mut self) {
        let polls = if self.state.station_mut().link.polling_paused {
            Vec::new()
        } else {
            crate::ops::telemetry::polls(
                &self.state.station_mut().device.profile,
                self.settings.poll_hz,
            )
        };
        self.state.station_mut().send(LinkCommand::SetPolls(polls));
    }
}

/// The navigation's width, points: its longest panel name in either language on one line (so
/// that switching the language moves nothing), or the STOP button, whichever is wider.
fn nav_width(ui: &egui::Ui) -> f32 {
    let names = PanelId::ALL
        .iter()
        .flat_map(|p| Lang::ALL.map(|l| p.name(l)));
    let text = layout::text_width(ui, &layout::body_font(ui), names);
    let button = text + 2.0 * ui.spacing().button_padding.x;
    // The panel's frame: its inner margin on both sides, and a little air.
    let margin = 2.0 * 8.0 + 4.0;
    button.max(stop::BUTTON_WIDTH) + margin
}

/// The baud rate and margin to open `profile` with: its saved ones, or its usual rate and the
/// protocol's own margin.
fn port_for(saved: &Settings, registry: &Registry, profile: &str) -> (u32, Option<u64>) {
    let port = saved.port_of(profile);
    let usual = registry.get(profile).map_or(115_200, |p| p.baud);
    (port.baud.unwrap_or(usual), port.margin_ms)
}

impl eframe::App for App {
    fn logic(&mut self, ctx: &egui::Context, _frame: &mut eframe::Frame) {
        App::logic(self, ctx);
    }

    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        App::ui(self, ui);
    }

    fn raw_input_hook(&mut self, _ctx: &egui::Context, raw_input: &mut egui::RawInput) {
        // A screenshot tour shows each view as it is, not a hover text from wherever the X
        // server's pointer happens to rest over the window.
        if self.tour.is_some() {
            raw_input
                .events
                .retain(|e| !matches!(e, egui::Event::PointerMoved(_)));
            raw_input.events.push(egui::Event::PointerGone);
        }
    }

    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        // A screenshot tour's panels, sizes and languages are not the user's choice.
        if self.tour.is_none() {
            eframe::set_value(storage, eframe::APP_KEY, &self.settings);
        }
    }
}
