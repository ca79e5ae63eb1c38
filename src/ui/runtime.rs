//! What the window knows at run time (never saved): the link, the device's values as its replies
//! brought them, telemetry, the packet log, the running job.

use super::jobs::{Job, JobOutput};
use crate::link::{
    DeviceInfo, Link, LinkCommand, LinkEvent, LinkOptions, LinkState, LinkStats, LogEntry, Opener,
    Poll, Request,
    serial::{self, PortInfo},
};
use crate::ops::msp::Check;
use crate::packet::Packet;
use crate::profile::{Profile, Registry, Value};
use crate::series::SeriesSet;
use crate::sim::{Faults, SimKind, SimOptions, SimTransport};
use std::collections::{HashMap, VecDeque};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How many frames the packet monitor keeps.
pub const LOG_CAPACITY: usize = 20_000;
/// The longest the UI thread spends draining link events in one frame.
pub const EVENT_BUDGET: Duration = Duration::from_millis(4);

/// What to connect to.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Target {
    /// A simulator inside botbench.
    Demo(String),
    /// A serial port (or pseudo-terminal) by path.
    Port(String),
}

impl Target {
    /// A label for the port picker and the title.
    pub fn label(&self) -> String {
        match self {
            Target::Demo(kind) => format!("built-in simulated {kind}"),
            Target::Port(p) => p.clone(),
        }
    }
}

/// The link and what it is connected to.
pub struct Conn {
    /// The worker.
    pub link: Link,
    /// What it talks to.
    pub target: Target,
}

/// A reading of one command: the values its reply brought, or why there are none.
#[derive(Debug, Clone, PartialEq)]
pub enum Reading {
    /// Values, raw, in wire order, and when they came.
    Values(Vec<(String, Value)>, Instant),
    /// The read failed.
    Failed(String),
}

/// What a field shows after a write.
#[derive(Debug, Clone, PartialEq)]
pub enum Mark {
    /// The device holds what was written.
    Verified,
    /// The device holds something else.
    Mismatch(Value),
}

/// A status-bar message.
#[derive(Debug, Clone)]
pub struct Status {
    /// The text.
    pub text: String,
    /// An error (shown red).
    pub error: bool,
    /// When.
    pub at: Instant,
}

/// The runtime state.
pub struct Runtime {
    /// Every profile.
    pub registry: Registry,
    /// The profile in use.
    pub profile: Arc<Profile>,
    /// The open link, if any.
    pub conn: Option<Conn>,
    /// The link's state as last reported (`None`: not connected).
    pub state: Option<LinkState>,
    /// The link's counters.
    pub stats: LinkStats,
    /// MSP: what CMD_VERSION said.
    pub info: Option<Result<DeviceInfo, String>>,
    /// The latest reading of each command, by command id.
    pub readings: HashMap<u8, Reading>,
    /// Marks left by the last write, by (Get command id, field ident).
    pub marks: HashMap<(u8, String), Mark>,
    /// Plotted telemetry, by plot id.
    pub plots: HashMap<String, SeriesSet>,
    /// When plotting started (t = 0 of the series).
    pub t0: Instant,
    /// Telemetry polling is paused.
    pub paused: bool,
    /// The packet log, oldest first.
    pub log: VecDeque<LogEntry>,
    /// The packet log is frozen.
    pub log_paused: bool,
    /// Frames dropped from the log because it was full or frozen.
    pub log_dropped: u64,
    /// Reports the device sent on its own (Tuya data points, MSP async).
    pub reports: VecDeque<(Instant, Packet)>,
    /// The running job.
    pub job: Option<Job>,
    /// The status line.
    pub status: Option<Status>,
    /// Serial ports, refreshed every second.
    pub ports: Vec<PortInfo>,
    ports_at: Option<Instant>,
    /// Wakes the UI from the worker.
    pub ctx: eframe::egui::Context,
    /// The link has just come up (first connect or a reconnect): the app reads the device.
    pub just_connected: bool,
    /// Tuya: what the module session has reported (handshake, data points, MCU requests).
    pub tuya: super::tuya_console::Session,
    /// Results of requests sent with `ReplyTo::Event(id)` (see [`Runtime::request_id`]), by id;
    /// the oldest are dropped beyond 256.
    pub replies: HashMap<u64, Result<crate::link::Reply, String>>,
    /// How links are opened (answer margin, reconnect), as `--margin-ms` on the command line.
    pub link_options: LinkOptions,
}

impl Runtime {
    /// A runtime with the profile `profile_id` and no link yet.
    pub fn new(ctx: &eframe::egui::Context, profile_id: &str) -> Result<Self, String> {
        let registry = Registry::load().map_err(|e| e.to_string())?;
        let profile = registry
            .get(profile_id)
            .or_else(|_| registry.get("window-cleaner"))
            .map_err(|e| e.to_string())?;
        Ok(Self {
            registry,
            profile,
            conn: None,
            state: None,
            stats: LinkStats::default(),
            info: None,
            readings: HashMap::new(),
            marks: HashMap::new(),
            plots: HashMap::new(),
            t0: Instant::now(),
            paused: false,
            log: VecDeque::with_capacity(1024),
            log_paused: false,
            log_dropped: 0,
            reports: VecDeque::new(),
            job: None,
            status: None,
            ports: Vec::new(),
            ports_at: None,
            ctx: ctx.clone(),
            just_connected: false,
            tuya: Default::default(),
            replies: HashMap::new(),
            link_options: LinkOptions::default(),
        })
    }

    /// A fresh id for a request whose result comes back as a `LinkEvent::Reply` (kept in
    /// [`Runtime::replies`]).
    pub fn request_id(&self) -> u64 {
        static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
        NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
    }

    /// Shows a message in the status bar.
    pub fn say(&mut self, text: impl Into<String>, error: bool) {
        self.status = Some(Status {
            text: text.into(),
            error,
            at: Instant::now(),
        });
    }

    /// Whether the link is up.
    pub fn connected(&self) -> bool {
        matches!(self.state, Some(LinkState::Connected { .. }))
    }

    /// Re-lists the serial ports at most once a second.
    pub fn refresh_ports(&mut self) {
        if self
            .ports_at
            .is_none_or(|t| t.elapsed() >= Duration::from_secs(1))
        {
            self.ports = serial::list_ports();
            self.ports_at = Some(Instant::now());
        }
    }

    /// Opens a link to `target` with `profile_id`, closing any other.
    pub fn connect(&mut self, target: Target, baud: u32, profile_id: &str) -> Result<(), String> {
        self.disconnect();
        let profile = self.registry.get(profile_id).map_err(|e| e.to_string())?;
        let opener: Opener = match &target {
            Target::Demo(kind) => {
                let kind: SimKind = kind.parse()?;
                let opts = SimOptions {
                    baud: Some(baud),
                    ..SimOptions::default()
                };
                Box::new(move || {
                    SimTransport::of_kind(kind, &opts, Faults::default())
                        .map(|t| Box::new(t) as Box<dyn crate::link::Transport>)
                        .map_err(|e| crate::link::LinkError::Open {
                            path: kind.to_string(),
                            reason: e,
                        })
                })
            }
            Target::Port(path) => serial::opener(path, baud),
        };
        let ctx = self.ctx.clone();
        // Background events (polled telemetry, the packet log) repaint at most 5 times a second;
        // a live plot asks for its own frame rate, and jobs wake the UI at once.
        let waker: crate::link::Waker =
            Arc::new(move || ctx.request_repaint_after(Duration::from_millis(200)));
        let link = Link::open(
            opener,
            profile.clone(),
            self.link_options.clone(),
            Some(waker),
        )
        .map_err(|e| e.to_string())?;
        self.profile = profile;
        self.readings.clear();
        self.marks.clear();
        self.plots.clear();
        self.info = None;
        self.tuya = self.tuya.next();
        self.t0 = Instant::now();
        self.conn = Some(Conn { link, target });
        self.state = None;
        Ok(())
    }

    /// Closes the link.
    pub fn disconnect(&mut self) {
        if let Some(job) = &self.job {
            job.cancel.cancel();
        }
        self.conn = None;
        self.state = None;
        self.stats = LinkStats::default();
    }

    /// Sends a command to the worker, if connected.
    pub fn send(&self, cmd: LinkCommand) {
        if let Some(c) = &self.conn {
            c.link.send(cmd);
        }
    }

    /// The telemetry commands to poll: the profile's plotted commands at `rate` Hz (`None`: as
    /// fast as the wire allows), and its other telemetry at 1 Hz, so that every value is live.
    pub fn polls(&self, rate: Option<f64>) -> Vec<Poll> {
        // Only MSP devices are polled from here. Tuya: the module session sends the heartbeat
        // itself and the MCU reports its data points; polling 0x00/0x01/0x08 would take the
        // restart heartbeat's 0 from the session. Servo commands name a servo: the servo bench
        // polls the servo it works on itself.
        if self.profile.protocol != crate::profile::Protocol::Msp {
            return Vec::new();
        }
        let mut plotted: Vec<u8> = Vec::new();
        for plot in &self.profile.plots {
            if let Some(cmd) = self.profile.command(&plot.command)
                && !plotted.contains(&cmd.id)
            {
                plotted.push(cmd.id);
            }
        }
        let poll = |cmd: &crate::profile::Command, interval| Poll {
            request: Request::for_command(&self.profile, cmd, Vec::new()).attempts(1),
            interval,
        };
        let plot_interval = rate.map(|r| Duration::from_secs_f64(1.0 / r.max(0.1)));
        let mut polls: Vec<Poll> = plotted
            .iter()
            .filter_map(|id| self.profile.command_by_id(*id))
            .map(|cmd| poll(cmd, plot_interval))
            .collect();
        // The other telemetry: commands that take no payload and answer values. MSP's core
        // commands (identity, power state) are read once by the session, not polled.
        let others = self.profile.commands.iter().filter(|c| {
            c.kind == crate::profile::CommandKind::Telemetry
                && c.request.is_empty()
                && !c.reply.is_empty()
                && !plotted.contains(&c.id)
                && !(self.profile.protocol == crate::profile::Protocol::Msp && c.id <= 9)
        });
        polls.extend(others.map(|cmd| poll(cmd, Some(Duration::from_secs(1)))));
        polls
    }

    /// Drains worker events for at most `EVENT_BUDGET`; returns whether more are waiting.
    pub fn drain_events(&mut self) -> bool {
        let started = Instant::now();
        loop {
            let Some(conn) = &self.conn else { return false };
            let Ok(ev) = conn.link.events().try_recv() else {
                return false;
            };
            self.on_event(ev);
            if started.elapsed() >= EVENT_BUDGET {
                return true;
            }
        }
    }

    fn on_event(&mut self, ev: LinkEvent) {
        match ev {
            LinkEvent::State(s) => {
                match &s {
                    LinkState::Lost { reason } => self.say(format!("link lost: {reason}"), true),
                    LinkState::Connected { port, baud } => {
                        if !self.connected() {
                            self.just_connected = true;
                        }
                        self.say(format!("connected to {port} at {baud} baud"), false)
                    }
                    _ => {}
                }
                self.state = Some(s);
            }
            LinkEvent::Stats(s) => self.stats = s,
            LinkEvent::Identified(r) => self.info = Some(r.map_err(|e| e.to_string())),
            LinkEvent::Frame(entry) => {
                self.tuya.on_frame(&entry);
                self.log_frame(entry)
            }
            LinkEvent::Report(p) => {
                self.tuya.on_report(&self.profile, &p);
                if self.reports.len() >= 2000 {
                    self.reports.pop_front();
                }
                self.reports.push_back((Instant::now(), p));
            }
            LinkEvent::Telemetry {
                command,
                at,
                result,
            } => match result {
                Ok(p) => self.on_telemetry(command, at, &p),
                Err(e) => {
                    self.readings
                        .insert(command, Reading::Failed(e.to_string()));
                }
            },
            LinkEvent::Reply { id, result } => {
                if self.replies.len() >= 256
                    && let Some(oldest) = self.replies.keys().min().copied()
                {
                    self.replies.remove(&oldest);
                }
                self.replies.insert(id, result.map_err(|e| e.to_string()));
            }
            LinkEvent::Tuya(ev) => self.tuya.on_event(ev),
        }
    }

    fn log_frame(&mut self, entry: LogEntry) {
        if self.log_paused {
            self.log_dropped += 1;
            return;
        }
        if self.log.len() >= LOG_CAPACITY {
            self.log.pop_front();
        }
        self.log.push_back(entry);
    }

    fn on_telemetry(&mut self, command: u8, at: Instant, p: &Packet) {
        let Some(cmd) = self.profile.command_by_id(command) else {
            return;
        };
        // A payload that does not fit is shown as such: the fault, the values read before it
        // and the raw bytes (FieldError::Misfit), never as clean values.
        let d = match self.profile.decode(cmd, p.direction, &p.payload) {
            Ok(d) => d,
            Err(e) => {
                self.readings
                    .insert(command, Reading::Failed(e.to_string()));
                return;
            }
        };
        let values: Vec<(String, Value)> = d
            .values
            .iter()
            .map(|v| (v.ident.clone(), v.value.clone()))
            .collect();
        let t = at.saturating_duration_since(self.t0).as_secs_f64();
        for plot in &self.profile.plots {
            if !plot.command.eq_ignore_ascii_case(&cmd.ident) {
                continue;
            }
            let set = self.plots.entry(plot.id.clone()).or_default();
            for name in &plot.fields {
                if let Some(v) = d.values.iter().find(|v| v.ident.eq_ignore_ascii_case(name))
                    && let Value::Int(raw) = v.value
                {
                    let _ = set.push(name, t, raw as f64 * v.field.scale);
                }
            }
        }
        self.readings.insert(command, Reading::Values(values, at));
    }

    /// Starts a job unless one is running.
    pub fn start_job(
        &mut self,
        title: &str,
        work: impl FnOnce(
            &crate::link::Client,
            &crate::ops::Cancel,
            &super::jobs::JobSink,
        ) -> Result<String, String>
        + Send
        + 'static,
    ) {
        if self.job.as_ref().is_some_and(|j| !j.is_done()) {
            self.say("wait for the running job to finish, or cancel it", true);
            return;
        }
        let Some(conn) = &self.conn else {
            self.say("not connected", true);
            return;
        };
        match Job::spawn(title, conn.link.client(), &self.ctx, work) {
            Ok(job) => self.job = Some(job),
            Err(e) => self.say(e, true),
        }
    }

    /// Takes what the running job has reported; returns the output meant for a panel.
    pub fn drain_job(&mut self) -> Vec<JobOutput> {
        let mut for_panels = Vec::new();
        let Some(job) = &mut self.job else {
            return for_panels;
        };
        let title = job.title.clone();
        let outputs = job.drain();
        for out in outputs {
            match out {
                JobOutput::Read(id, Ok(values)) => {
                    self.readings
                        .insert(id, Reading::Values(values, Instant::now()));
                }
                JobOutput::Read(id, Err(e)) => {
                    self.readings.insert(id, Reading::Failed(e));
                }
                JobOutput::Wrote(set, result) => self.on_written(set, result),
                JobOutput::Note(n) => self.say(n, false),
                JobOutput::Done(Ok(summary)) => self.say(format!("{title}: {summary}"), false),
                JobOutput::Done(Err(e)) => self.say(format!("{title}: {e}"), true),
                JobOutput::Progress(_) => {}
                JobOutput::Servo(_)
                | JobOutput::Tuya(_)
                | JobOutput::Device(_)
                | JobOutput::SelfTest(_)
                | JobOutput::Solar(_) => for_panels.push(out),
            }
        }
        for_panels
    }

    fn on_written(&mut self, set: u8, result: Result<Vec<Check>, String>) {
        let Some(get) = self.profile.command_by_id(set).and_then(|s| s.pair) else {
            return;
        };
        match result {
            Ok(checks) => {
                let values: Vec<(String, Value)> = checks
                    .iter()
                    .map(|c| (c.field.clone(), c.read.clone()))
                    .collect();
                for c in &checks {
                    let mark = if c.ok() {
                        Mark::Verified
                    } else {
                        Mark::Mismatch(c.read.clone())
                    };
                    self.marks.insert((get, c.field.clone()), mark);
                }
                self.readings
                    .insert(get, Reading::Values(values, Instant::now()));
            }
            Err(e) => {
                // Nothing is known of what the device holds now: read it again before trusting it.
                self.readings.insert(
                    get,
                    Reading::Failed(format!("write failed: {e}; read again")),
                );
            }
        }
    }

    /// The running job's title and progress, if a job runs.
    pub fn job_progress(&self) -> Option<(&str, f32, String)> {
        let job = self.job.as_ref().filter(|j| !j.is_done())?;
        let (f, msg) = job
            .progress
            .as_ref()
            .map_or((0.0, String::new()), |p| (p.fraction(), p.message.clone()));
        Some((&job.title, f, msg))
    }
}
