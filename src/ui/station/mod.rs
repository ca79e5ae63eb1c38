//! A station: everything the window holds about one connected device, as one value, never
//! saved: its link and the link's status, the device model as replies brought it (the Tuya
//! module model in it), the packet log and capture, the running job and its output, the status
//! line. Panels read the station they show; it changes only through the app (link events, job
//! output, actions), once per frame.
//!
//! Nothing in a station refers to another station or to a process-wide value: two stations in
//! one process connect, run jobs, lose their port and reconnect independently (the line station
//! holds several). What they share is read-only or made for sharing: the profiles, the egui
//! context that wakes the window, whether a file dialog can open, and the production records.

mod capture;
mod frame;
mod job;
mod link;
mod model;
mod packets;
mod running;
mod tuya;
mod verdicts;

pub use link::{Answering, Connection, LastAnswer, LinkStatus, PortLister, SILENT_AFTER, Target};
pub use model::{DeviceModel, Mark, Reading, ReadingError};
pub use packets::{LOG_CAPACITY, LogRow, Logged, OfflineCapture, PacketLog};
pub use running::{Running, RunningSet};
pub use tuya::{
    DpState, LOG_CAPACITY as REPORT_LOG_CAPACITY, LogLine, RequestLine, StepResult, TuyaModel,
};
pub use verdicts::{Verdict, Verdicts};

use super::Action;
use super::jobs::RunningJob;
use super::panel::{Forget, Panels};
use super::stop::StopControl;
use crate::i18n::Text;
use crate::link::{Link, LinkCommand, LinkEvent, LinkState, LinkStats, Opener};
use crate::profile::{ProfileError, Registry};
use crate::sim::{Faults, SharedDevice, SimKind, SimOptions, SimTransport};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The longest the UI thread spends draining link events in one frame.
pub const EVENT_BUDGET: Duration = Duration::from_millis(4);

/// A status-line message, in both languages (every message the window shows is said in
/// each: see [`crate::ui::zh::Zh`] for errors).
#[derive(Debug, Clone, PartialEq)]
pub struct Notice {
    /// The text, in English.
    pub text: String,
    /// The text in Chinese.
    pub zh: String,
    /// An error (shown red).
    pub error: bool,
    /// When.
    pub at: Instant,
}

impl Notice {
    /// A message that something happened.
    pub fn info(said: Text) -> Self {
        Self {
            text: said.en,
            zh: said.zh,
            error: false,
            at: Instant::now(),
        }
    }

    /// A message that something went wrong.
    pub fn error(said: Text) -> Self {
        Self {
            error: true,
            ..Self::info(said)
        }
    }

    /// The text in `lang`.
    pub fn text_in(&self, lang: crate::i18n::Lang) -> &str {
        match lang {
            crate::i18n::Lang::En => &self.text,
            crate::i18n::Lang::Zh => &self.zh,
        }
    }
}

/// Why a link could not be opened.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConnectError {
    /// The profile cannot be loaded.
    #[error(transparent)]
    Profile(#[from] ProfileError),
    /// The built-in simulator asked for does not exist.
    #[error("{0}")]
    Simulator(String),
    /// The worker could not start.
    #[error(transparent)]
    Link(#[from] crate::link::LinkError),
}

/// One connected device as the window holds it (see the module's documentation).
pub struct Station {
    /// Every profile (shared by the stations of a window, read-only).
    pub registry: Arc<Registry>,
    /// The link.
    pub link: LinkStatus,
    /// The device as its replies brought it.
    pub device: DeviceModel,
    /// Every frame sent and received.
    pub packets: PacketLog,
    /// The running (or last) job.
    pub job: Option<RunningJob>,
    /// The status line.
    pub notice: Option<Notice>,
    /// Wakes the UI from the worker and from jobs.
    pub ctx: eframe::egui::Context,
    /// Whether the system can show a file dialog (looked up once).
    pub dialogs: super::files::Dialogs,
    /// The production records: where they go, the recorder jobs save through, the report
    /// (one store for the window's stations, made for sharing).
    pub records: super::records::RecordsHandle,
    /// The verdicts on the unit now on the fixture.
    pub verdicts: Verdicts,
    /// STOP: what was sent, what answered, what waits for the link.
    pub stop: StopControl,
    /// The window's panels of this station, each with what it holds of this device (empty
    /// while one of them runs: see [`Self::with_panels`]).
    pub panels: Panels,
}

impl Station {
    /// A station with the profile `profile_id` from `registry` (the window cleaner's if it does
    /// not load) and no link yet; `ctx` is woken by its link and jobs.
    /// Errors: neither profile is in `registry`.
    pub fn new(
        ctx: &eframe::egui::Context,
        registry: Arc<Registry>,
        profile_id: &str,
    ) -> Result<Self, ProfileError> {
        let profile = registry
            .get(profile_id)
            .or_else(|_| registry.get("window-cleaner"))?;
        Ok(Self {
            registry,
            link: LinkStatus::default(),
            device: DeviceModel::new(profile),
            packets: PacketLog::default(),
            job: None,
            notice: None,
            ctx: ctx.clone(),
            dialogs: super::files::Dialogs::detect(),
            records: super::records::RecordsHandle::default(),
            verdicts: Verdicts::default(),
            stop: StopControl::default(),
            panels: Panels::default(),
        })
    }

    /// Whether the link is up.
    pub fn connected(&self) -> bool {
        self.link.connected()
    }

    /// Where a plot that follows the newest data ends, in plot time (seconds since the
    /// connection): now, or the moment polling was paused, so that paused data stays in view.
    pub fn plot_end(&self) -> f64 {
        let end = self.link.paused_at.unwrap_or_else(Instant::now);
        end.saturating_duration_since(self.device.t0).as_secs_f64()
    }

    /// Shows a message in the status line.
    pub fn notify(&mut self, notice: Notice) {
        self.notice = Some(notice);
    }

    /// Opens a link to `target` with `profile_id`, closing any other; the device model, STOP
    /// and what the panels showed start over. Returns what the panels ask for on the new
    /// connection. Errors: the profile, the built-in simulator or the worker.
    pub fn connect(
        &mut self,
        target: Target,
        baud: u32,
        profile_id: &str,
    ) -> Result<Vec<Action>, ConnectError> {
        self.disconnect();
        let profile = self.registry.get(profile_id)?;
        let (opener, demo_tuya) = match &target {
            Target::Demo(kind) => demo_opener(kind, baud)?,
            Target::Port(path) => (self.link.port_opener.open(path, baud), None),
        };
        let opener = self.packets.tap.wrap(opener);
        let ctx = self.ctx.clone();
        // Background events (polled telemetry, the packet log) repaint at most twice a second;
        // a live view asks for its own frame rate, and jobs wake the UI at once.
        let waker: crate::link::Waker =
            Arc::new(move || ctx.request_repaint_after(crate::ui::repaint::BACKGROUND));
        let link = Link::open(
            opener,
            profile.clone(),
            self.link.options.clone(),
            Some(waker),
        )?;
        self.device.reset(profile);
        self.link.connection = Some(Connection {
            link,
            target,
            demo_tuya,
        });
        self.link.state = None;
        self.stop = StopControl::default();
        Ok(self.with_panels(|p, st| p.forget(st, Forget::Connection)))
    }

    /// Closes the link (a running job is cancelled); what the device showed is forgotten.
    pub fn disconnect(&mut self) {
        self.stop_capture();
        if let Some(job) = &self.job {
            job.cancel.cancel();
        }
        if self.link.connection.take().is_some() {
            self.device.forget_values();
            self.device.running.clear();
        }
        self.link.state = None;
        self.link.stats = LinkStats::default();
        self.link.forget_answers();
    }

    /// Sends a command to the worker, if connected.
    pub fn send(&self, cmd: LinkCommand) {
        if let Some(c) = &self.link.connection {
            c.link.send(cmd);
        }
    }

    /// Drains worker events for at most [`EVENT_BUDGET`]; returns whether more are waiting.
    pub fn drain_link_events(&mut self) -> bool {
        let started = Instant::now();
        loop {
            let Some(conn) = &self.link.connection else {
                return false;
            };
            let Ok(ev) = conn.link.events().try_recv() else {
                return false;
            };
            self.on_link_event(ev);
            if started.elapsed() >= EVENT_BUDGET {
                return true;
            }
        }
    }

    /// Takes one worker event: each to the part of the state it concerns.
    fn on_link_event(&mut self, ev: LinkEvent) {
        match ev {
            LinkEvent::State(s) => {
                match &s {
                    LinkState::Lost { .. } | LinkState::Reconnecting { .. } | LinkState::Closed
                        if self.link.connected() =>
                    {
                        // The connection ended: what it showed is no longer known.
                        self.device.forget_values();
                        self.device.running.on_link_lost();
                        self.link.forget_answers();
                    }
                    _ => {}
                }
                match &s {
                    LinkState::Lost { reason } => self.notify(Notice::error(Text::new(
                        format!("link lost: {reason}"),
                        format!("连接丢失:{}", crate::ui::zh::lost_port(reason)),
                    ))),
                    LinkState::Connected { port, baud } => {
                        if !self.link.connected() {
                            self.link.just_connected = true;
                        }
                        let port = match self.link.target() {
                            Some(t) => t.port_said(port),
                            None => Text::same(port),
                        };
                        self.notify(Notice::info(Text::new(
                            format!("connected to {} at {baud} baud", port.en),
                            format!("已连接 {},波特率 {baud}", port.zh),
                        )))
                    }
                    _ => {}
                }
                self.link.state = Some(s);
            }
            LinkEvent::Stats(s) => self.link.on_stats(s),
            LinkEvent::Identified(r) => {
                if let Ok(info) = &r {
                    self.verdicts.identified(info);
                }
                self.device.info = Some(r.map_err(Into::into));
            }
            LinkEvent::Frame(entry) => {
                let profile = self.device.profile.clone();
                self.device.running.on_frame(&profile, &entry);
                self.packets.push(entry, &profile)
            }
            LinkEvent::NoAnswer(n) => {
                self.link.on_no_answer(&n);
                let profile = self.device.profile.clone();
                self.packets.push_no_answer(n, &profile)
            }
            LinkEvent::Report(p) => self.device.on_report(p),
            LinkEvent::Telemetry {
                command,
                at,
                result,
            } => {
                if result.is_ok() {
                    self.link.heard();
                }
                self.device.on_telemetry(command, at, result)
            }
            LinkEvent::Reply { id, result } => {
                if result.as_ref().is_ok_and(|r| !r.packets.is_empty()) {
                    self.link.heard();
                }
                self.device.on_reply(id, result)
            }
            LinkEvent::Tuya(ev) => self.device.tuya.on_event(ev),
            LinkEvent::Device(ev) => self.link.on_device(ev),
        }
    }
}

/// The opener of the built-in simulated device `kind` at `baud`: one device for the
/// connection, kept across reconnects; for the Tuya vacuum also its handle, through which the
/// window asks it to send its own requests.
fn demo_opener(kind: &str, baud: u32) -> Result<(Opener, DemoTuya), ConnectError> {
    let kind: SimKind = kind.parse().map_err(ConnectError::Simulator)?;
    let opts = SimOptions {
        baud: Some(baud),
        ..SimOptions::default()
    };
    let mut demo_tuya = None;
    let device: SharedDevice = if kind == SimKind::TuyaVacuum {
        let mcu = Arc::new(Mutex::new(crate::sim::tuya_mcu(&opts)));
        demo_tuya = Some(mcu.clone());
        mcu
    } else {
        crate::sim::build(kind, &opts).map_err(ConnectError::Simulator)?
    };
    let opener: Opener = Box::new(move || {
        let t = SimTransport::new(device.clone(), baud, Faults::default(), kind.describe());
        Ok(Box::new(t) as Box<dyn crate::link::Transport>)
    });
    Ok((opener, demo_tuya))
}

/// The built-in simulated Tuya MCU of a demo connection, if that is what it talks to.
type DemoTuya = Option<Arc<Mutex<crate::sim::tuya_mcu::TuyaMcu>>>;
