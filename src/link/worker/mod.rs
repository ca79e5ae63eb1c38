//! The worker thread: owns the transport and the protocol session, takes commands in order,
//! and reports events. The loop is here; exchanges, polling and the port have a file each, and
//! the protocol sessions it drives live in [`crate::link::session`].

mod exchange;
mod polls;
mod port;
mod sweep;
mod timing;

pub use exchange::default_margin;
use polls::InFlight;
use timing::{AnswerTiming, OwedAnswers};

use super::decoder::AnyDecoder;
use super::request::{ExchangeError, Reply, Request};
use super::session::{Precedence, ProtocolSession};
use super::{
    LinkCommand, LinkError, LinkEvent, LinkOptions, LinkState, LinkStats, LogEntry, Opener, Poll,
    ReplyTo, Sweep, SweepReply, Transport, Waker,
};
use crate::packet::Packet;
use crate::profile::Profile;
use crate::protocol::{Direction, FrameError};
use crossbeam_channel::{Receiver, RecvTimeoutError, Sender, TrySendError};
use std::collections::VecDeque;
use std::sync::Arc;
use std::time::{Duration, Instant, SystemTime};

/// How long the idle loop waits for a command before looking at the port again.
const IDLE_SLICE: Duration = Duration::from_millis(5);
/// How often changed counters are reported.
const STATS_EVERY: Duration = Duration::from_millis(250);

/// The worker of one link (one per open port, on the thread `botbench-link`).
pub(super) struct Worker {
    /// The port; `None` while it is lost.
    transport: Option<Box<dyn Transport>>,
    /// Reopens the port after a loss.
    opener: Opener,
    opts: LinkOptions,
    cmds: Receiver<LinkCommand>,
    events: Sender<LinkEvent>,
    waker: Option<Waker>,
    decoder: AnyDecoder,
    /// What the protocol does beyond callers' exchanges (MSP identify, the Tuya module side).
    session: ProtocolSession,
    /// Callers' exchanges and baud changes, in order.
    queue: VecDeque<Queued>,
    /// Commands that came during an exchange, taken after it.
    deferred: VecDeque<LinkCommand>,
    /// The polled commands and when each is due.
    polls: Vec<(Poll, Instant)>,
    /// The poll to look at first (polls take turns).
    poll_cursor: usize,
    /// Polls sent ahead of their answers (MSP polls at the wire's maximum), oldest first.
    in_flight: VecDeque<InFlight>,
    /// The port's rate, in baud.
    baud: u32,
    /// When the bytes written so far have crossed the wire (at the rate they were sent at).
    sent_until: Instant,
    /// How late answers come on this connection (the automatic margin).
    timing: AnswerTiming,
    /// Answers still owed to attempts that went unanswered.
    owed: OwedAnswers,
    /// Servo frames read between sweeps that answered nothing: the next sweep's strays.
    unclaimed: sweep::Unclaimed,
    stats: LinkStats,
    stats_reported: LinkStats,
    stats_at: Instant,
    /// When the idle loop last checked that the port is there.
    checked_at: Instant,
    shutdown: bool,
    /// Events were sent since the UI was last woken.
    wake: bool,
}

/// Asks the OS to wake this thread on time (Linux: a timer slack of 1 ns instead of the default
/// 50 µs): a sweep sleeps to the bus's pace, request after request, and a servo scan would
/// otherwise pay the slack 255 times. Where it cannot be set, the thread wakes a little late.
fn precise_timers() {
    #[cfg(target_os = "linux")]
    let _ = nix::sys::prctl::set_timerslack(1);
}

/// Work done in order.
enum Queued {
    Exchange(Request, ReplyTo),
    Baud(u32, Option<Sender<Result<(), LinkError>>>),
    Sweep(Sweep, Sender<Result<SweepReply, ExchangeError>>),
}

impl Worker {
    pub(super) fn new(
        transport: Box<dyn Transport>,
        opener: Opener,
        profile: Arc<Profile>,
        opts: LinkOptions,
        cmds: Receiver<LinkCommand>,
        events: Sender<LinkEvent>,
        waker: Option<Waker>,
    ) -> Self {
        let now = Instant::now();
        let baud = transport.baud();
        let timing = AnswerTiming::new(transport.latency_timer());
        Self {
            decoder: AnyDecoder::new(profile.protocol),
            session: ProtocolSession::new(profile, &opts, now),
            transport: Some(transport),
            opener,
            opts,
            cmds,
            events,
            waker,
            queue: VecDeque::new(),
            deferred: VecDeque::new(),
            polls: Vec::new(),
            poll_cursor: 0,
            in_flight: VecDeque::new(),
            sent_until: now,
            timing,
            owed: OwedAnswers::default(),
            unclaimed: sweep::Unclaimed::default(),
            baud,
            stats: LinkStats::default(),
            stats_reported: LinkStats::default(),
            stats_at: now,
            checked_at: now,
            shutdown: false,
            wake: false,
        }
    }

    /// The loop, until [`LinkCommand::Shutdown`] or the link is dropped: a lost port is
    /// reopened; otherwise, in this order, the session's work that comes first (MSP learns the
    /// device before anything else is sent to it), callers' requests, the session's other work
    /// (Tuya's handshake and heartbeat), polls, and reading the idle line.
    pub(super) fn run(mut self) {
        precise_timers();
        self.emit_connected();
        while !self.shutdown {
            if self.transport.is_none() {
                self.reconnect();
                continue;
            }
            self.take_commands();
            if self.shutdown {
                break;
            }
            if self.session.due(Instant::now()) == Some(Precedence::BeforeRequests) {
                self.run_session();
            } else if let Some(item) = self.queue.pop_front() {
                // Polls in flight are answered first: no answer can be taken for another's.
                self.settle_polls();
                match item {
                    Queued::Exchange(req, to) => {
                        let result = self.exchange(&req);
                        self.deliver(to, result);
                    }
                    Queued::Baud(baud, ack) => self.switch_baud(baud, ack),
                    Queued::Sweep(sweep, reply) => {
                        let result = self.run_sweep(&sweep);
                        let _ = reply.send(result);
                    }
                }
            } else if self.session.due(Instant::now()).is_some() {
                self.run_session();
            } else if let Some(i) = self.due_poll() {
                if self.pipelined(i) {
                    self.send_poll_ahead(i);
                } else {
                    self.settle_polls();
                    self.run_poll(i);
                }
            } else if !self.in_flight.is_empty() {
                self.settle_polls();
            } else {
                self.idle();
            }
            self.housekeeping();
        }
        self.fail_queue(|| ExchangeError::Cancelled);
        self.session.closed();
        self.emit(LinkEvent::State(LinkState::Closed));
        self.flush_wake();
    }

    /// Runs the session's requests due now: one, or a whole sequence (an identification, a
    /// handshake) with no caller's request in between.
    fn run_session(&mut self) {
        self.settle_polls();
        let mut events = Vec::new();
        while let Some(request) = self.session.next_request(Instant::now()) {
            let result = self.exchange(&request);
            let more = self.session.on_answer(result, Instant::now(), &mut events);
            for ev in events.drain(..) {
                self.emit(ev);
            }
            self.flush_wake();
            if !more {
                break;
            }
        }
    }

    // ---- commands -------------------------------------------------------------------------

    fn take_commands(&mut self) {
        while let Some(c) = self.deferred.pop_front() {
            self.handle(c);
        }
        while let Ok(c) = self.cmds.try_recv() {
            self.handle(c);
        }
    }

    fn handle(&mut self, cmd: LinkCommand) {
        match cmd {
            LinkCommand::Request { request, reply_to } => {
                if self.transport.is_none() {
                    self.deliver(
                        reply_to,
                        Err(ExchangeError::Disconnected("port lost".into())),
                    );
                } else {
                    self.queue.push_back(Queued::Exchange(request, reply_to));
                }
            }
            LinkCommand::SetPolls(polls) => {
                let now = Instant::now();
                self.polls = polls.into_iter().map(|p| (p, now)).collect();
                self.poll_cursor = 0;
            }
            LinkCommand::SetBaud { baud, ack } => {
                if self.transport.is_none() {
                    // A lost port: nobody would ever take this from the queue.
                    if let Some(ack) = ack {
                        let _ = ack.send(Err(LinkError::Disconnected("port lost".into())));
                    }
                } else {
                    self.queue.push_back(Queued::Baud(baud, ack));
                }
            }
            LinkCommand::Sweep { sweep, reply } => {
                if self.transport.is_none() {
                    let _ = reply.send(Err(ExchangeError::Disconnected("port lost".into())));
                } else {
                    self.queue.push_back(Queued::Sweep(sweep, reply));
                }
            }
            LinkCommand::Identify => self.session.identify_again(),
            LinkCommand::DeviceInfo { reply } => {
                if self.transport.is_none() {
                    let _ = reply.send(Err(ExchangeError::Disconnected("port lost".into())));
                } else {
                    self.session.want_device_info(reply);
                }
            }
            LinkCommand::Handshake => self.session.handshake_again(Instant::now()),
            LinkCommand::TuyaOptions(o) => self.session.set_tuya_options(o),
            LinkCommand::Shutdown => self.shutdown = true,
        }
    }

    fn fail_queue(&mut self, err: impl Fn() -> ExchangeError) {
        for item in std::mem::take(&mut self.queue) {
            match item {
                Queued::Exchange(_, to) => self.deliver(to, Err(err())),
                Queued::Baud(_, Some(tx)) => {
                    let _ = tx.send(Err(LinkError::Disconnected(err().to_string())));
                }
                Queued::Baud(_, None) => {}
                Queued::Sweep(_, tx) => {
                    let _ = tx.send(Err(err()));
                }
            }
        }
    }

    /// During an exchange: keep commands for later, but stop at once on shutdown.
    fn commands_during_exchange(&mut self) -> Result<(), ExchangeError> {
        while let Ok(c) = self.cmds.try_recv() {
            match c {
                LinkCommand::Shutdown => {
                    self.shutdown = true;
                    return Err(ExchangeError::Cancelled);
                }
                // What the module answers the MCU takes effect at once: the MCU may ask while
                // an exchange is under way.
                LinkCommand::TuyaOptions(o) => self.session.set_tuya_options(o),
                other => self.deferred.push_back(other),
            }
        }
        Ok(())
    }

    fn deliver(&mut self, to: ReplyTo, result: Result<Reply, ExchangeError>) {
        match to {
            ReplyTo::Event(id) => self.emit(LinkEvent::Reply { id, result }),
            ReplyTo::Channel(tx) => {
                let _ = tx.send(result);
            }
        }
    }

    // ---- events ---------------------------------------------------------------------------

    fn emit(&mut self, ev: LinkEvent) {
        match self.events.try_send(ev) {
            Ok(()) => self.wake = true,
            Err(TrySendError::Full(_)) => self.stats.dropped_events += 1,
            Err(TrySendError::Disconnected(_)) => {}
        }
    }

    fn flush_wake(&mut self) {
        if std::mem::take(&mut self.wake)
            && let Some(w) = &self.waker
        {
            w();
        }
    }

    fn emit_connected(&mut self) {
        if let Some(t) = &self.transport {
            let state = LinkState::Connected {
                port: t.describe(),
                baud: t.baud(),
            };
            self.emit(LinkEvent::State(state));
        }
    }

    fn housekeeping(&mut self) {
        let now = Instant::now();
        self.stats.margin = Some(self.auto_margin());
        self.stats.answer_latency = self.timing.measured();
        self.stats.latency_timer = self.timing.latency_timer;
        if now.duration_since(self.stats_at) >= STATS_EVERY && self.stats != self.stats_reported {
            self.stats_at = now;
            self.stats_reported = self.stats.clone();
            self.emit(LinkEvent::Stats(self.stats.clone()));
        }
        self.flush_wake();
    }

    fn log(
        &mut self,
        direction: Direction,
        frame: Result<Packet, FrameError>,
        note: Option<String>,
    ) {
        self.emit(LinkEvent::Frame(LogEntry {
            at: SystemTime::now(),
            direction,
            frame,
            note,
        }));
    }

    // ---- idle ---------------------------------------------------------------------------------

    /// Nothing to do: waits a little for a command, reads what the device sends on its own, and
    /// now and then checks that the port is still there.
    fn idle(&mut self) {
        let now = Instant::now();
        let mut wait = IDLE_SLICE;
        if let Some(due) = self.polls.iter().map(|(_, d)| *d).min() {
            wait = wait.min(due.saturating_duration_since(now));
        }
        match self.cmds.recv_timeout(wait) {
            Ok(c) => {
                // Work arrived: do it first; the port is read while waiting for its answer.
                self.handle(c);
                return;
            }
            Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => self.shutdown = true,
        }
        if self.transport.is_none() || self.shutdown {
            return;
        }
        let before = self.decoder.buffered();
        match self.read_some(Instant::now()) {
            Ok(0) if before > 0 => {
                // The line is quiet with a partial frame held: it will not complete.
                self.decoder.flush();
                self.drain_unsolicited();
            }
            Ok(_) => self.drain_unsolicited(),
            Err(_) => return,
        }
        self.check_port(now);
    }
}
