//! The link: one named worker thread per open port owns the transport and a protocol session.
//! Callers never block on I/O: [`LinkCommand`]s go in and [`LinkEvent`]s come out over
//! crossbeam channels, and a waker callback tells the UI to repaint. Threads that may block (the
//! command line, long jobs) use a [`Client`], whose requests carry their own reply channel.

mod decoder;
pub mod lines;
pub mod request;
pub mod serial;
pub mod session;
pub mod silent;
pub mod transport;
pub mod watch;
mod worker;
pub use worker::default_margin;

pub use lines::{BOOT_WAIT_MS, LineLevel, MARGIN_MS, PortSetup, ms_within};
pub use request::{
    CommandName, ExchangeError, HELD_UP, HOST_LATE, Match, Reply, ReplySpec, Request,
};
pub use serial::PortOpener;
pub use session::tuya::{HandshakeStep, ProductInfo, StepResult, TuyaEvent, TuyaModuleOptions};
pub use session::{Capability, DeviceInfo, capabilities};
pub use transport::{LinkError, Transport, wire_time};
pub use watch::{Watch, Watched};

use crate::packet::Packet;
use crate::profile::Profile;
use crate::protocol::{Direction, FrameError};
use crossbeam_channel::{Receiver, Sender};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant, SystemTime};

/// Opens (and, after a loss, reopens) the transport.
pub type Opener = Box<dyn FnMut() -> Result<Box<dyn Transport>, LinkError> + Send>;

/// Called after events are sent, to wake the UI.
pub type Waker = Arc<dyn Fn() + Send + Sync>;

/// Where a request's result goes.
#[derive(Debug, Clone)]
pub enum ReplyTo {
    /// As a [`LinkEvent::Reply`] with this id.
    Event(u64),
    /// Into this channel (blocking callers).
    Channel(Sender<Result<Reply, ExchangeError>>),
}

/// A telemetry command the worker polls on its own.
#[derive(Debug, Clone, PartialEq)]
pub struct Poll {
    /// What to send.
    pub request: Request,
    /// How often; `None` for as fast as the wire allows.
    pub interval: Option<Duration>,
}

/// What the worker is told.
#[derive(Debug, Clone)]
pub enum LinkCommand {
    /// One exchange.
    Request {
        /// The request.
        request: Request,
        /// Where its result goes.
        reply_to: ReplyTo,
    },
    /// Replaces the set of polled telemetry commands (empty: stop polling).
    SetPolls(Vec<Poll>),
    /// Switches the port's baud rate, in order with the requests around it.
    SetBaud {
        /// The new rate.
        baud: u32,
        /// Told when the port has switched (or could not).
        ack: Option<Sender<Result<(), LinkError>>>,
    },
    /// MSP: identifies the device again (CMD_VERSION, then CMD_BUILD_INFO) before any request
    /// still queued; [`LinkEvent::Identified`] tells the result.
    Identify,
    /// MSP: this connection's identification, into `reply`: at once when it is known, else when
    /// the identification under way (or started now, or tried again after it failed) ends.
    /// [`Client::device_info`] waits for it.
    DeviceInfo {
        /// Gets the identification, or why there is none: [`ExchangeError::Disconnected`] when
        /// the port is or goes away first, [`ExchangeError::NotInProtocol`] on a servo or Tuya
        /// link, [`ExchangeError::Cancelled`] when the link closes, or what the identify's
        /// exchange failed with.
        reply: Sender<Result<DeviceInfo, ExchangeError>>,
    },
    /// Requests sent at the pace of the bus, each answer taken for its request whenever it
    /// comes ([`Sweep`]); in order with the requests around it.
    Sweep {
        /// The requests.
        sweep: Sweep,
        /// Gets what came.
        reply: Sender<Result<SweepReply, ExchangeError>>,
    },
    /// Tuya: runs the start-up handshake again.
    Handshake,
    /// Tuya: changes what the module answers the MCU.
    TuyaOptions(TuyaModuleOptions),
    /// Starts a watch ([`Client::watch`]): what the worker reads and says goes into this
    /// channel too, from now until its receiver is dropped.
    Watch(Sender<Watched>),
    /// Closes the port and ends the worker.
    Shutdown,
}

/// Requests sent one after another at the pace of the bus rather than of the host (a servo
/// scan): the next goes out once the last one's answer can have ended on the wire, and each
/// answer is taken for its request whenever it reaches the host (a USB adapter may hold it back
/// for its latency timer). Every request must wait for a [`ReplySpec::Required`] answer that
/// tells it from the others (a servo's answer names its id).
#[derive(Debug, Clone)]
pub struct Sweep {
    /// The requests, in order.
    pub requests: Vec<Request>,
    /// The longest answer, in bytes on the wire.
    pub answer_bytes: usize,
    /// The longest a device takes on the bus before it answers.
    pub device_latency: Duration,
    /// Also listen for the answers earlier requests still owe: the sweep ends no sooner than
    /// the grace an unanswered exchange is given after it began, and what comes meanwhile that
    /// answers none of its requests is in [`SweepReply::strays`]. A sweep of no request always
    /// listens (it is there to collect what is still on its way).
    pub listen: bool,
}

/// An answer a sweep brought.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SweepAnswer {
    /// The answer.
    pub packet: Packet,
    /// It came after its request's window (the margin): the automatic margin has widened.
    pub late: bool,
}

/// A damaged frame a sweep read, and where it can have come from.
#[derive(Debug, Clone, PartialEq)]
pub struct Damaged {
    /// What is wrong with it.
    pub error: FrameError,
    /// The sweep's requests (indices) it can have come from or destroyed (on a half-duplex bus a
    /// collision garbles the answer and the request it met): those still unanswered that were
    /// sent after the last clean answer before it and before it came.
    pub candidates: Vec<usize>,
    /// No clean answer to the sweep came before it: it can also be a late answer to a request
    /// sent before the sweep (the devices answer in order, so not once one of the sweep's came).
    pub maybe_earlier: bool,
}

/// What a sweep brought.
#[derive(Debug, Clone)]
pub struct SweepReply {
    /// For each request, in order: its answer, if one came.
    pub answers: Vec<Option<SweepAnswer>>,
    /// Each damaged frame, in the order they came.
    pub garbled: Vec<Damaged>,
    /// Answers to none of the sweep's requests (late answers to earlier ones): the servo frames
    /// read since the sweep before it that answered no request of their own (late answers to
    /// earlier exchanges included; the latest 64), then those that came while it ran.
    pub strays: Vec<Packet>,
    /// The margin the sweep waited with.
    pub margin: Duration,
    /// The most this computer ran behind a deadline the sweep had set, when [`HELD_UP`] or
    /// more (a loaded computer: an id without an answer may have answered with nobody
    /// there in time); `None`: on time throughout.
    pub host_late: Option<Duration>,
}

/// The state of the link.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LinkState {
    /// Open and working.
    Connected {
        /// The port (or simulator) description.
        port: String,
        /// Its baud rate.
        baud: u32,
    },
    /// The port went away.
    Lost {
        /// Why.
        reason: String,
    },
    /// Trying to reopen a lost port.
    Reconnecting {
        /// Attempts so far.
        attempt: u32,
    },
    /// Closed for good.
    Closed,
}

/// One frame sent or received, for the packet monitor.
#[derive(Debug, Clone)]
pub struct LogEntry {
    /// When.
    pub at: SystemTime,
    /// Out or in.
    pub direction: Direction,
    /// The frame, or what was wrong with the bytes.
    pub frame: Result<Packet, FrameError>,
    /// What the link took it for, when that is not plain: `late answer to an earlier request`.
    pub note: Option<String>,
}

/// A request's attempt that went unanswered in its window (no frame came for it), for the
/// packet monitor: typed here, put in words by whoever shows it.
#[derive(Debug, Clone, PartialEq)]
pub struct NoAnswer {
    /// When its window ended, on the wall clock.
    pub at: SystemTime,
    /// The request's command.
    pub command: u8,
    /// Which attempt this was, from 1.
    pub attempt: u8,
    /// The attempts the request is given.
    pub attempts: u8,
    /// How long its answer was waited for, from when it was written.
    pub waited: Duration,
    /// How far this computer ran behind a deadline during the exchange, when
    /// [`HELD_UP`] or more ([`request::held_up_by`]): the answer may have come while it was.
    pub host_late: Option<Duration>,
}

/// Counters for the status bar.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LinkStats {
    /// Round trip of the last answered exchange.
    pub rtt: Option<Duration>,
    /// Frames sent.
    pub sent: u64,
    /// Valid frames received.
    pub received: u64,
    /// Exchanges that timed out (each attempt).
    pub timeouts: u64,
    /// Frame errors (bad checksums, junk, truncation).
    pub frame_errors: u64,
    /// Attempts beyond the first.
    pub retries: u64,
    /// Events dropped because nobody read them.
    pub dropped_events: u64,
    /// Answers that came after their attempt's window (taken for their own request, and the
    /// automatic margin widened).
    pub late_answers: u64,
    /// The margin in use now: `--margin-ms`, or the automatic one (the device's, the adapter's
    /// latency timer, the answer latency measured on this connection).
    pub margin: Option<Duration>,
    /// The largest recent answer latency measured on this connection (device, adapter and host
    /// together), from a request's last byte on the wire to its answer's first byte read.
    pub answer_latency: Option<Duration>,
    /// The USB adapter's latency timer, where the OS gives it.
    pub latency_timer: Option<Duration>,
    /// Reads that found the bytes the port said had arrived gone: another reader of the same
    /// port took them.
    pub taken_reads: u64,
    /// Times the link's thread ran more than 2 ms behind a deadline it had set (held up in a
    /// write, or woken late from a wait): a loaded computer. Its answers are still waited for,
    /// from when the thread got to them.
    pub host_late: u64,
    /// The most the link's thread ran behind a deadline.
    pub host_late_max: Duration,
}

/// Requests in a row without an answer after which the device counts as silent (and, when it
/// answers again, as possibly another unit on the same port).
pub const SILENT_AFTER: u64 = 3;

/// What the link finds of the device behind the port: an open port says nothing of it, the
/// device's frames and its silence do. Sent as [`LinkEvent::Device`] when it is news.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DeviceEvent {
    /// A frame came from the device: the first on this connection, or the first after it had
    /// been silent (`after_silence`: possibly another unit on the same port, a robot swapped on
    /// the fixture).
    Answered {
        /// At least [`SILENT_AFTER`] requests in a row had gone unanswered before it.
        after_silence: bool,
    },
    /// This many attempts in a row went unanswered (at least [`SILENT_AFTER`]; sent again at each
    /// one more, until a frame comes).
    Silent {
        /// Unanswered attempts in a row.
        unanswered: u64,
    },
}

/// What the worker reports.
#[derive(Debug, Clone)]
pub enum LinkEvent {
    /// The link's state changed.
    State(LinkState),
    /// The result of a request sent with [`ReplyTo::Event`].
    Reply {
        /// The request's id.
        id: u64,
        /// Its result.
        result: Result<Reply, ExchangeError>,
    },
    /// A polled telemetry answer (or why it failed).
    Telemetry {
        /// The command polled.
        command: u8,
        /// When the answer came.
        at: Instant,
        /// The answer.
        result: Result<Packet, ExchangeError>,
    },
    /// A frame the device sent on its own: an MSP async message, a Tuya data-point report (also
    /// every report that answers a query or a command), a servo reply that came late.
    Report(Packet),
    /// A frame for the packet monitor.
    Frame(LogEntry),
    /// A request's attempt that no frame answered in its window (each attempt, polls too; a
    /// sweep's requests, such as a scan's, are not said one by one), for the packet monitor.
    NoAnswer(NoAnswer),
    /// MSP: the device identified itself (CMD_VERSION, then CMD_BUILD_INFO), once per
    /// connection and again on [`LinkCommand::Identify`], or why it could not.
    Identified(Result<DeviceInfo, ExchangeError>),
    /// Tuya: handshake steps, heartbeats, the Wi-Fi state reported, status queries, MCU requests
    /// answered, restarts.
    Tuya(TuyaEvent),
    /// Whether the device answers: the first frame of a connection, silence, an answer after
    /// silence. Each new connection starts with nothing known.
    Device(DeviceEvent),
    /// Counters, sent when they change (at most a few times a second).
    Stats(LinkStats),
}

/// How the link behaves.
#[derive(Debug, Clone)]
pub struct LinkOptions {
    /// How long the device may take to start answering, beyond the wire time. Default: MSP
    /// 20 ms, servo 1.5 ms, Tuya 300 ms.
    pub margin: Option<Duration>,
    /// Reopen a lost port, with backoff.
    pub reconnect: bool,
    /// Start the protocol session on every connection: MSP identifies the device (otherwise
    /// only when asked: [`LinkCommand::Identify`], [`Client::device_info`]), Tuya runs the
    /// handshake (otherwise only on [`LinkCommand::Handshake`]).
    pub start_session: bool,
    /// Tuya: what the module answers the MCU.
    pub tuya: TuyaModuleOptions,
    /// Capacity of the event channel.
    pub event_capacity: usize,
    /// MSP polls at the wire's maximum: how many requests may be in flight at once. With 2 the
    /// next request is sent while the device still answers the last one (the line is full
    /// duplex), so the device never waits for the host; 1 sends each request after the last
    /// answer, for firmware that cannot take a request while it answers.
    pub poll_pipeline: usize,
    /// What is done right after each open: DTR, RTS, and the settle time before anything is
    /// sent (a board that reboots when the port opens).
    pub setup: PortSetup,
}

impl Default for LinkOptions {
    fn default() -> Self {
        Self {
            margin: None,
            reconnect: true,
            start_session: true,
            tuya: TuyaModuleOptions::default(),
            event_capacity: 65_536,
            poll_pipeline: 2,
            setup: PortSetup::default(),
        }
    }
}

/// An open link: the worker thread and its channels. Dropping it closes the port.
pub struct Link {
    commands: Sender<LinkCommand>,
    /// Names the commands of the errors its clients hand on.
    profile: Arc<Profile>,
    events: Receiver<LinkEvent>,
    thread: Option<JoinHandle<()>>,
    /// Bytes the worker has read from the port, of any kind.
    heard: Arc<std::sync::atomic::AtomicU64>,
}

impl std::fmt::Debug for Link {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Link").finish_non_exhaustive()
    }
}

impl Link {
    /// Opens the transport now (so that a bad path, or a modem line the port refuses, is an
    /// immediate error), sets its lines ([`LinkOptions::setup`]), then starts the worker thread
    /// `botbench-link`, which waits the setup's boot wait before it sends anything.
    pub fn open(
        opener: Opener,
        profile: Arc<Profile>,
        options: LinkOptions,
        waker: Option<Waker>,
    ) -> Result<Self, LinkError> {
        let mut opener = options.setup.wrap(opener);
        let transport = opener()?;
        let (cmd_tx, cmd_rx) = crossbeam_channel::unbounded();
        let (ev_tx, ev_rx) = crossbeam_channel::bounded(options.event_capacity.max(16));
        let worker = worker::Worker::new(
            transport,
            opener,
            profile.clone(),
            options,
            cmd_rx,
            ev_tx,
            waker,
        );
        let heard = worker.heard();
        let thread = std::thread::Builder::new()
            .name("botbench-link".into())
            .spawn(move || worker.run())
            .map_err(|e| LinkError::Setting(format!("cannot start the link thread: {e}")))?;
        Ok(Self {
            commands: cmd_tx,
            profile,
            events: ev_rx,
            thread: Some(thread),
            heard,
        })
    }

    /// Sends a command to the worker.
    pub fn send(&self, cmd: LinkCommand) {
        let _ = self.commands.send(cmd);
    }

    /// The events the worker reports.
    pub fn events(&self) -> &Receiver<LinkEvent> {
        &self.events
    }

    /// A blocking client for another thread.
    pub fn client(&self) -> Client {
        Client {
            commands: self.commands.clone(),
            profile: self.profile.clone(),
            heard: self.heard.clone(),
        }
    }
}

impl Drop for Link {
    fn drop(&mut self) {
        let _ = self.commands.send(LinkCommand::Shutdown);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// A handle for threads that may block: each request waits for its own answer.
#[derive(Debug, Clone)]
pub struct Client {
    commands: Sender<LinkCommand>,
    /// The link's profile: the errors handed on name their commands by it.
    profile: Arc<Profile>,
    /// Bytes the worker has read from the port, of any kind.
    heard: Arc<std::sync::atomic::AtomicU64>,
}

impl Client {
    /// Bytes read from the port since the link opened, of any kind: answers, answers that came
    /// after their window, junk, frames the device sent on its own. Compared across a wait, it
    /// tells a silent wire (nothing there) from a device whose answers were late or garbled (a
    /// unit there, on a noisy line or behind a late host).
    pub fn bytes_heard(&self) -> u64 {
        self.heard.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Sends `request` and waits for its result.
    pub fn request(&self, request: Request) -> Result<Reply, ExchangeError> {
        let (tx, rx) = crossbeam_channel::bounded(1);
        self.commands
            .send(LinkCommand::Request {
                request,
                reply_to: ReplyTo::Channel(tx),
            })
            .map_err(|_| ExchangeError::Cancelled)?;
        rx.recv()
            .unwrap_or(Err(ExchangeError::Cancelled))
            .map_err(|e| e.named(&self.profile))
    }

    /// MSP: this connection's identification (hardware code, firmware, API, build, flags, build
    /// date), read once per connection by the link itself: no new exchange when it is known,
    /// else waits for the identification under way (started now when the link identifies on
    /// demand only, or tried again when it failed).
    ///
    /// Errors: [`ExchangeError::Disconnected`] when the port is or goes away first,
    /// [`ExchangeError::NotInProtocol`] on a servo or Tuya link, [`ExchangeError::Cancelled`]
    /// when the link closes, or what CMD_VERSION failed with (no answer, a garbled one,
    /// [`ExchangeError::Unreadable`]).
    pub fn device_info(&self) -> Result<DeviceInfo, ExchangeError> {
        let (tx, rx) = crossbeam_channel::bounded(1);
        self.commands
            .send(LinkCommand::DeviceInfo { reply: tx })
            .map_err(|_| ExchangeError::Cancelled)?;
        rx.recv()
            .unwrap_or(Err(ExchangeError::Cancelled))
            .map_err(|e| e.named(&self.profile))
    }

    /// MSP: identifies the device again (CMD_VERSION, then CMD_BUILD_INFO; before any request
    /// still queued, as on connect) and waits for the result, which [`Self::device_info`] gives from then on.
    /// Errors: as [`Self::device_info`].
    pub fn identify(&self) -> Result<DeviceInfo, ExchangeError> {
        self.send(LinkCommand::Identify);
        self.device_info()
    }

    /// Sends a [`Sweep`] and waits for what it brought.
    pub fn sweep(&self, sweep: Sweep) -> Result<SweepReply, ExchangeError> {
        let (tx, rx) = crossbeam_channel::bounded(1);
        self.commands
            .send(LinkCommand::Sweep { sweep, reply: tx })
            .map_err(|_| ExchangeError::Cancelled)?;
        rx.recv()
            .unwrap_or(Err(ExchangeError::Cancelled))
            .map_err(|e| e.named(&self.profile))
    }

    /// Switches the port's baud rate after the requests before it, and waits until it has.
    pub fn set_baud(&self, baud: u32) -> Result<(), LinkError> {
        let (tx, rx) = crossbeam_channel::bounded(1);
        self.commands
            .send(LinkCommand::SetBaud {
                baud,
                ack: Some(tx),
            })
            .map_err(|_| LinkError::Disconnected("link closed".into()))?;
        rx.recv()
            .unwrap_or(Err(LinkError::Disconnected("link closed".into())))
    }

    /// Starts a [`Watch`] on what the worker reads and says from now on (Tuya reports, refused
    /// frames, the session's events), including during the exchanges after it; it ends when
    /// dropped. A closed link gives a watch that sees nothing.
    pub fn watch(&self) -> Watch {
        let (tx, watch) = watch::channel();
        let _ = self.commands.send(LinkCommand::Watch(tx));
        watch
    }

    /// Sends a command without waiting.
    pub fn send(&self, cmd: LinkCommand) {
        let _ = self.commands.send(cmd);
    }
}
