//! The servo bench: bus scan, parameters, ID and baud provisioning, motion tests, production
//! provisioning. One sub-module per tab; this file holds the panel's frame: the "Stop all"
//! button (always there, even while a job runs), the selected servo, the running job's progress,
//! and the tabs.
//!
//! Everything that talks to servos is an operation of [`crate::ops::servo`] or
//! [`crate::ops::servo::provision`], run as a job; motion commands and "Stop all" go straight to the
//! link worker so that they never wait for a job.

mod motion;
mod param_answers;
mod param_preset;
mod params;
mod params_jobs;
mod provision;
mod scan;
mod setup;

use super::Action;
use super::jobs::{JobSink, LogError};
use super::station::{Notice, Station};
use crate::i18n::Lang;
use crate::i18n::Text;
use crate::link::{LinkCommand, ReplyTo, Request};
use crate::ops::servo::provision::{ProvisionState, Record};
use crate::ops::servo::{Location, ScanRow};
use crate::ops::{Check, OpError};
use eframe::egui;

pub use params::ParamsState;
pub use provision::ProvisionPanel;
pub use scan::ScanState;

/// A servo on the bus: its id and the rate it talks at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Servo {
    /// Its id.
    pub id: u8,
    /// Its baud rate.
    pub baud: u32,
}

/// The tabs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Tab {
    /// Bus scan.
    #[default]
    Scan,
    /// The selected servo's parameters.
    Params,
    /// ID and baud rate.
    Setup,
    /// Angle, wheel mode, damping, live angle.
    Motion,
    /// Production provisioning.
    Production,
}

impl Tab {
    /// Every tab, in the order shown.
    pub(crate) const ALL: [Tab; 5] = [
        Tab::Scan,
        Tab::Params,
        Tab::Setup,
        Tab::Motion,
        Tab::Production,
    ];

    fn name(self, lang: Lang) -> &'static str {
        match self {
            Tab::Scan => lang.tr("Bus scan", "总线扫描"),
            Tab::Params => lang.tr("Parameters", "参数"),
            Tab::Setup => lang.tr("ID & baud rate", "ID与波特率"),
            Tab::Motion => lang.tr("Motion", "运动测试"),
            Tab::Production => lang.tr("Production", "产线烧录"),
        }
    }
}

/// The panel's state.
#[derive(Default)]
pub struct ServoBenchPanel {
    /// The tab shown.
    pub tab: Tab,
    /// The servo being worked on.
    pub selected: Option<Servo>,
    /// The scan tab.
    pub scan: ScanState,
    /// The parameters tab.
    pub params: ParamsState,
    /// The ID and baud tab.
    pub setup: setup::SetupState,
    /// The motion tab.
    pub motion: motion::MotionState,
    /// The production tab.
    pub production: ProvisionPanel,
}

/// What this panel's jobs report.
#[derive(Debug, Clone)]
pub enum Output {
    /// A scan found a servo (or a possible duplicate).
    Found(ScanRow),
    /// A scan ended: every row, or why it stopped.
    Scanned(Result<crate::ops::servo::ScanReport, OpError>),
    /// One id was scanned again at one rate: what answers there now.
    Rescanned {
        /// Where.
        at: Servo,
        /// What answers (empty: nothing), or why the scan failed.
        rows: Result<crate::ops::servo::ScanReport, OpError>,
    },
    /// Parameters read from a servo: raw values by `data_id`, or why not.
    Values {
        /// Which servo.
        servo: Servo,
        /// The values.
        values: Vec<(u8, Result<i64, OpError>)>,
    },
    /// Parameters written and read back, by `data_id`.
    Written {
        /// Which servo.
        servo: Servo,
        /// The checks, or why the write failed.
        checks: Vec<(u8, Result<Check, OpError>)>,
    },
    /// "Reset user data" ended: where the servo is now, or why not.
    Reset {
        /// The servo as it was.
        servo: Servo,
        /// Its factory location, verified, or why not.
        result: Result<Location, OpError>,
    },
    /// An id change ended.
    IdSet {
        /// The servo as it was.
        servo: Servo,
        /// The id given.
        new: u8,
        /// Verified at the new id, or why not.
        result: Result<(), OpError>,
    },
    /// A baud change ended.
    BaudSet {
        /// The servo as it was.
        servo: Servo,
        /// Verified at this rate, or why not.
        result: Result<u32, OpError>,
        /// Where the servo was found when the change could not be verified.
        found: Option<u32>,
    },
    /// One servo was provisioned (or failed).
    Provisioned {
        /// What happened.
        record: Record,
        /// The session's state afterwards (ids given out).
        state: ProvisionState,
        /// Why the record could not be logged, if it could not.
        log_error: Option<LogError>,
    },
}

/// Sends a panel output from a job.
pub(crate) fn send(sink: &JobSink, out: Output) {
    sink.panel(out);
}

/// The rate the port is at now.
pub(crate) fn port_baud(rt: &Station) -> Option<u32> {
    rt.link.baud()
}

/// A request (built by [`crate::ops::servo`]) for the worker, bypassing the job queue (the
/// answer, if any, is not awaited).
pub(crate) fn direct(request: Request) -> Action {
    Action::Link(LinkCommand::Request {
        request,
        reply_to: ReplyTo::Event(0),
    })
}

/// Switches the port to `baud` unless it is there already.
pub(crate) fn follow(rt: &Station, baud: u32) -> Option<Action> {
    (port_baud(rt) != Some(baud)).then_some(Action::Link(LinkCommand::SetBaud { baud, ack: None }))
}

/// A red error line.
pub(crate) fn error_label(ui: &mut egui::Ui, text: impl Into<egui::RichText>) {
    ui.colored_label(egui::Color32::from_rgb(210, 40, 40), text);
}

/// A green confirmation line.
pub(crate) fn ok_label(ui: &mut egui::Ui, text: impl Into<egui::RichText>) {
    ui.colored_label(egui::Color32::from_rgb(40, 150, 60), text);
}

/// The selected servo, or a hint to select one first.
fn selection_or_hint(ui: &mut egui::Ui, lang: Lang, selected: Option<Servo>) -> Option<Servo> {
    if selected.is_none() {
        ui.weak(lang.tr(
            "Select a servo in the bus scan first.",
            "请先在总线扫描中选择一个舵机。",
        ));
    }
    selected
}

impl ServoBenchPanel {
    /// Forgets what was found on the bus (a new connection): scan rows, the selection, the
    /// parameters read and the angle plot. What the technician typed and chose is kept.
    pub fn forget_bus(&mut self) {
        self.selected = None;
        self.scan.rows.clear();
        self.scan.outcome = None;
        self.params.values.clear();
        self.params.edits.clear();
        self.params.marks.clear();
        self.params.message = None;
        self.motion.series.clear();
    }

    /// Draws the panel.
    fn draw(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &Station) -> Vec<Action> {
        let mut actions = Vec::new();
        self.header(ui, lang, rt, &mut actions);
        ui.separator();
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
        let busy = rt.job_progress().is_some();
        egui::ScrollArea::vertical()
            .auto_shrink(false)
            .show(ui, |ui| match self.tab {
                Tab::Scan => {
                    let (picked, asked) = self.scan.show(ui, lang, rt, busy, self.selected);
                    actions.extend(asked);
                    if let Some(s) = picked {
                        actions.extend(self.select(Some(s), rt));
                    }
                }
                Tab::Params => {
                    actions.extend(self.params.show(ui, lang, rt, busy, self.selected));
                }
                Tab::Setup => {
                    actions.extend(
                        self.setup
                            .show(ui, lang, rt, busy, self.selected, &self.scan),
                    );
                }
                Tab::Motion => {
                    actions.extend(self.motion.show(ui, lang, rt, busy, self.selected));
                }
                Tab::Production => actions.extend(self.production.show(ui, lang, rt, busy)),
            });
        // Live polling stops when a job starts: the job may take the port to other rates.
        if actions.iter().any(|a| matches!(a, Action::StartJob(_))) && self.motion.live {
            self.motion.live = false;
            actions.insert(0, Action::Link(LinkCommand::SetPolls(Vec::new())));
        }
        actions
    }

    /// Stop all, the selected servo, the port's rate and the running job.
    fn header(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &Station, actions: &mut Vec<Action>) {
        ui.horizontal(|ui| {
            let stop = egui::Button::new(
                egui::RichText::new(lang.tr("STOP ALL", "全部停止"))
                    .strong()
                    .size(18.0)
                    .color(egui::Color32::WHITE),
            )
            .fill(egui::Color32::from_rgb(190, 30, 30))
            .min_size(egui::vec2(140.0, 34.0));
            if ui
                .add_enabled(rt.connected(), stop)
                .on_hover_text(lang.tr(
                    "Broadcast: damping, then stop and hold. Sent at once, even while a job runs (then at the port's baud rate only); otherwise at the port's rate and at every rate where the scan found servos.",
                    "广播: 先阻尼, 再停止并保持锁力。即使有任务在运行也会立即发送(此时仅在当前波特率); 否则在当前波特率及扫描到舵机的所有波特率下发送。",
                ))
                .clicked()
            {
                actions.extend(self.stop_all(rt));
            }
            ui.separator();
            match self.selected {
                Some(s) => {
                    ui.label(format!(
                        "{} {} @ {} {}",
                        lang.tr("Selected servo", "当前舵机"),
                        s.id,
                        s.baud,
                        lang.tr("baud", "波特")
                    ));
                }
                None => {
                    ui.weak(lang.tr(
                        "No servo selected: scan the bus and select one",
                        "未选择舵机: 请先扫描总线并选择",
                    ));
                }
            }
            ui.separator();
            match port_baud(rt) {
                Some(b) => ui.label(format!("{} {b}", lang.tr("Port at", "端口波特率"))),
                None => ui.weak(lang.tr("not connected", "未连接")),
            };
            if let Some((title, fraction, msg)) = rt.job_progress() {
                ui.separator();
                ui.label(title.get(lang));
                ui.add(
                    egui::ProgressBar::new(fraction)
                        .desired_width(180.0)
                        .show_percentage(),
                );
                ui.weak(msg.get(lang));
                if ui.button(lang.tr("Cancel job", "取消任务")).clicked() {
                    actions.push(Action::CancelJob);
                }
            }
        });
    }

    /// The broadcasts of "Stop all": at the port's rate at once; with no job running, also at
    /// every other rate where the scan found servos, and the port then returns to its rate.
    fn stop_all(&self, rt: &Station) -> Vec<Action> {
        let requests = crate::ops::servo::stop_all_requests(&rt.device.profile);
        let mut out: Vec<Action> = requests.iter().cloned().map(direct).collect();
        let here = port_baud(rt);
        let mut rates: Vec<u32> = Vec::new();
        if rt.job_progress().is_none() {
            for r in &self.scan.rows {
                if Some(r.baud) != here && !rates.contains(&r.baud) {
                    rates.push(r.baud);
                }
            }
        }
        for &b in &rates {
            out.push(Action::Link(LinkCommand::SetBaud { baud: b, ack: None }));
            out.extend(requests.iter().cloned().map(direct));
        }
        if let (Some(h), false) = (here, rates.is_empty()) {
            out.push(Action::Link(LinkCommand::SetBaud { baud: h, ack: None }));
        }
        let mut all: Vec<String> = here
            .into_iter()
            .chain(rates)
            .map(|b| b.to_string())
            .collect();
        all.dedup();
        out.push(Action::Notify(Notice::info(Text::new(
            format!("stop all broadcast at {} baud", all.join(", ")),
            format!("已在 {} 波特广播全部停止", all.join(", ")),
        ))));
        out
    }

    /// Works on `servo` from now on: the port follows it; what was read of another servo goes.
    fn select(&mut self, servo: Option<Servo>, rt: &Station) -> Vec<Action> {
        let mut actions = Vec::new();
        if self.selected != servo {
            self.params = ParamsState {
                preset_path: std::mem::take(&mut self.params.preset_path),
                ..ParamsState::default()
            };
            if self.motion.live {
                self.motion.live = false;
                actions.push(Action::Link(LinkCommand::SetPolls(Vec::new())));
            }
            self.motion.clear_plot();
        }
        self.selected = servo;
        if let Some(s) = servo
            && let Some(a) = follow(rt, s.baud)
        {
            actions.push(a);
        }
        actions
    }

    /// The servo moved (new id, new rate, reset): the selection and the scan table follow it;
    /// what was read stays valid only for parameters the move did not touch.
    fn moved(&mut self, from: Servo, to: Servo) {
        for row in &mut self.scan.rows {
            if row.id == from.id && row.baud == from.baud {
                row.id = to.id;
                row.baud = to.baud;
            }
        }
        if self.selected == Some(from) {
            self.selected = Some(to);
        }
    }

    /// Takes what one of its jobs reported; `profile` (the servo profile) says which
    /// parameters hold the id and the baud option.
    fn take_output(&mut self, out: Output, profile: &crate::profile::Profile) {
        match out {
            Output::Found(row) => self.scan.on_found(row),
            Output::Scanned(result) => {
                self.scan.on_scanned(result);
                // One clean servo on the bus: that is the one to work on.
                let present: Vec<&ScanRow> = self
                    .scan
                    .rows
                    .iter()
                    .filter(|r| r.presence == crate::ops::servo::Presence::Present)
                    .collect();
                if self.selected.is_none()
                    && let [only] = present.as_slice()
                {
                    self.selected = Some(Servo {
                        id: only.id,
                        baud: only.baud,
                    });
                }
            }
            Output::Rescanned { at, rows } => self.scan.on_rescanned(at, rows),
            Output::Values { servo, values } => {
                if self.selected == Some(servo) {
                    self.params.on_values(values);
                }
            }
            Output::Written { servo, checks } => {
                if self.selected == Some(servo) {
                    self.params.on_written(checks);
                }
            }
            Output::Reset { servo, result } => {
                if let Ok(at) = &result {
                    let to = Servo {
                        id: at.id,
                        baud: at.baud,
                    };
                    self.moved(servo, to);
                    self.params.values.clear();
                    self.params.marks.clear();
                }
                self.params.on_reset(result);
            }
            Output::IdSet { servo, new, result } => {
                if result.is_ok() {
                    let to = Servo { id: new, ..servo };
                    self.moved(servo, to);
                    if let Some(p) = profile.servo_id_param()
                        && let Some(v) = self.params.values.get_mut(&p.id)
                    {
                        *v = Ok(new.into());
                    }
                }
                self.setup.on_id(servo, new, result);
            }
            Output::BaudSet {
                servo,
                result,
                found,
            } => {
                let now = result.as_ref().ok().copied().or(found);
                if let Some(b) = now {
                    self.moved(servo, Servo { baud: b, ..servo });
                    if let Some(opt) = profile.option_of_baud(b)
                        && let Some((p, _)) = profile.baud_option_param()
                        && let Some(v) = self.params.values.get_mut(&p.id)
                    {
                        *v = Ok(opt.into());
                    }
                }
                self.setup.on_baud(servo, result, found);
            }
            Output::Provisioned {
                record,
                state,
                log_error,
            } => self.production.on_record(record, state, log_error),
        }
    }
}

impl crate::ui::PanelId {
    /// Bus servos: scan, parameters, id and baud, motion, provisioning.
    pub const SERVO_BENCH: crate::ui::PanelId = crate::ui::PanelId::new("ServoBench");
}

impl crate::ui::Panel for ServoBenchPanel {
    fn id(&self) -> crate::ui::PanelId {
        crate::ui::PanelId::SERVO_BENCH
    }

    fn name(&self, lang: Lang) -> &'static str {
        lang.tr("Servo bench", "舵机调试")
    }

    fn kind(&self) -> Option<crate::profile::PanelKind> {
        Some(crate::profile::PanelKind::ServoBench)
    }

    fn show(&mut self, ui: &mut egui::Ui, cx: &crate::ui::panel::Cx<'_>) -> Vec<Action> {
        self.draw(ui, cx.lang, cx.station)
    }

    /// What was found on another connection is not on this one.
    fn forget(&mut self, _station: &Station, why: crate::ui::panel::Forget) -> Vec<Action> {
        if why == crate::ui::panel::Forget::Connection {
            self.forget_bus();
        }
        Vec::new()
    }

    fn on_output(&mut self, out: crate::ui::panel::PanelOutput, station: &Station) -> Vec<Action> {
        if let Some(out) = out.take::<Output>() {
            self.take_output(out, &station.device.profile);
        }
        Vec::new()
    }

    /// The parameter preset, the provisioning log and plan last used; the shipped plan when
    /// none was used yet.
    fn restore(&mut self, settings: &crate::ui::Settings) {
        use crate::ui::settings::FileKind;
        if let Some(p) = settings.file(FileKind::ServoPreset) {
            self.params.preset_path = p.to_string();
        }
        if let Some(p) = settings.file(FileKind::ProvisionLog) {
            self.production.log_path = p.to_string();
        }
        if let Some(p) = crate::ui::app::file_or_shipped(
            settings,
            FileKind::ProvisionPlan,
            "servo-provision-plan.ron",
        ) {
            self.production.plan_path = p;
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
