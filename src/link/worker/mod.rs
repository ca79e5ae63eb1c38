//! The worker thread: owns the port and the protocol session, takes commands in order, and
//! reports events. Its state is split by what it is:
//!
//! - [`wire::Wire`]: the port, the decoder, the rate, the bytes sent and the counters;
//! - [`timing::Timing`]: the answer timing (margins, what was measured, answers still owed);
//! - [`queue::Queue`] (callers' work in order), [`polls::Polls`] (telemetry polling) and the
//!   protocol session ([`crate::link::session`]);
//! - [`liveness::Liveness`]: whether the device answers, reported as
//!   [`crate::link::DeviceEvent`];
//! - [`events::Events`]: what goes out (events, the packet tap, the UI's waker).
//!
//! The loop is here; exchanges ([`exchange`], [`wait`]), polling, bus-paced sweeps ([`sweep`])
//! and the port's loss and reconnect ([`port`]) have a file each.

mod events;
mod exchange;
mod liveness;
mod polls;
mod port;
mod queue;
mod sweep;
#[cfg(test)]
mod tests;
mod timing;
mod wait;
mod wire;

pub use exchange::default_margin;

use super::request::{ExchangeError, Reply};
use super::session::{Precedence, ProtocolSession};
use super::{
    LinkCommand, LinkError, LinkEvent, LinkOptions, LinkState, LinkStats, Opener, ReplyTo,
    Transport, Waker,
};
use crate::profile::Profile;
use crossbeam_channel::{Receiver, RecvTimeoutError, Sender};
use events::Events;
use polls::Polls;
use queue::{Queue, Queued};
use std::sync::Arc;
use std::time::{Duration, Instant};
use timing::Timing;
use wire::Wire;

/// How long the idle loop waits for a command before looking at the port again.
const IDLE_SLICE: Duration = Duration::from_millis(5);
/// How often changed counters are reported.
const STATS_EVERY: Duration = Duration::from_millis(250);

/// The worker of one link (one per open port, on the thread `botbench-link`).
pub(super) struct Worker {
    /// The port and its bytes.
    wire: Wire,
    /// How long answers may take, and those still owed.
    timing: Timing,
    /// What the protocol does beyond callers' exchanges (MSP identify, the Tuya module side).
    session: ProtocolSession,
    /// Callers' exchanges, baud changes and sweeps, in order.
    queue: Queue,
    /// The polled commands.
    polls: Polls,
    /// Servo frames read between sweeps that answered nothing: the next sweep's strays.
    unclaimed: sweep::Unclaimed,
    /// Whether the device answers.
    liveness: liveness::Liveness,
    /// What goes out.
    events: Events,
    cmds: Receiver<LinkCommand>,
    opts: LinkOptions,
    /// The counters last reported, and when.
    stats_reported: (LinkStats, Instant),
    /// The most the host ran behind a deadline it had set since the watch under way began
    /// ([`Worker::watching_late`]).
    late_seen: Duration,
    shutdown: bool,
}

/// Asks the OS to wake this thread on time (Linux: a timer slack of 1 ns instead of the default
/// 50 µs): a sweep sleeps to the bus's pace, request after request, and a servo scan would
/// otherwise pay the slack 255 times. Where it cannot be set, the thread wakes a little late.
fn precise_timers() {
    #[cfg(target_os = "linux")]
    let _ = nix::sys::prctl::set_timerslack(1);
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
        let protocol = profile.protocol;
        let timing = Timing::new(
            opts.margin,
            default_margin(protocol),
            transport.latency_timer(),
        );
        Self {
            wire: Wire::new(transport, opener, protocol),
            timing,
            session: ProtocolSession::new(profile.clone(), &opts, now),
            queue: Queue::default(),
            polls: Polls::default(),
            unclaimed: sweep::Unclaimed::default(),
            liveness: liveness::Liveness::default(),
            events: Events::new(events, waker, profile),
            cmds,
            opts,
            stats_reported: (LinkStats::default(), now),
            late_seen: Duration::ZERO,
            shutdown: false,
        }
    }

    /// The count of bytes the worker reads from the port, for the link's clients.
    pub(super) fn heard(&self) -> std::sync::Arc<std::sync::atomic::AtomicU64> {
        self.wire.heard()
    }

    /// The loop, until [`LinkCommand::Shutdown`] or the link is dropped: a lost port is
    /// reopened; otherwise, in this order, the session's work that comes first (MSP learns the
    /// device before anything else is sent to it), callers' requests, the session's other work
    /// (Tuya's handshake and heartbeat), polls, and reading the idle line.
    pub(super) fn run(mut self) {
        precise_timers();
        self.emit_connected();
        self.settle_after_open();
        while !self.shutdown {
            if !self.wire.is_open() {
                self.reconnect();
                continue;
            }
            self.take_commands();
            if self.shutdown {
                break;
            }
            self.step();
            self.housekeeping();
        }
        self.fail_queue(|| ExchangeError::Cancelled);
        self.session.closed();
        self.events.emit(LinkEvent::State(LinkState::Closed));
        self.events.flush_wake();
    }

    /// One turn of the loop: the work that comes first now.
    fn step(&mut self) {
        let now = Instant::now();
        if self.session.due(now) == Some(Precedence::BeforeRequests) {
            self.run_session();
        } else if let Some(item) = self.queue.pop() {
            // Polls in flight are answered first: no answer can be taken for another's.
            self.settle_polls();
            self.run_queued(item);
        } else if self.session.due(now).is_some() {
            self.run_session();
        } else if let Some(i) = self.polls.due(now) {
            self.poll(i);
        } else if self.polls.in_flight() {
            self.settle_polls();
        } else {
            self.idle();
        }
    }

    /// Does one item of callers' work.
    fn run_queued(&mut self, item: Queued) {
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
                self.events.emit(ev);
            }
            self.events.flush_wake();
            if !more {
                break;
            }
        }
    }

    // ---- commands -------------------------------------------------------------------------

    fn take_commands(&mut self) {
        while let Some(c) = self.queue.next_deferred() {
            self.handle(c);
        }
        while let Ok(c) = self.cmds.try_recv() {
            self.handle(c);
        }
    }

    fn handle(&mut self, cmd: LinkCommand) {
        let open = self.wire.is_open();
        let why = self.wire.why_lost();
        let lost = || why.clone();
        match cmd {
            LinkCommand::Request { request, reply_to } if open => {
                self.queue.push(Queued::Exchange(request, reply_to));
            }
            LinkCommand::Request { reply_to, .. } => {
                self.deliver(reply_to, Err(ExchangeError::Disconnected(lost())));
            }
            LinkCommand::SetBaud { baud, ack } if open => {
                self.queue.push(Queued::Baud(baud, ack));
            }
            // A lost port: nobody would ever take this from the queue.
            LinkCommand::SetBaud { ack, .. } => {
                if let Some(ack) = ack {
                    let _ = ack.send(Err(LinkError::Disconnected(lost())));
                }
            }
            LinkCommand::Sweep { sweep, reply } if open => {
                self.queue.push(Queued::Sweep(sweep, reply));
            }
            LinkCommand::Sweep { reply, .. } => {
                let _ = reply.send(Err(ExchangeError::Disconnected(lost())));
            }
            LinkCommand::DeviceInfo { reply } if open => self.session.want_device_info(reply),
            LinkCommand::DeviceInfo { reply } => {
                let _ = reply.send(Err(ExchangeError::Disconnected(lost())));
            }
            LinkCommand::SetPolls(polls) => self.polls.set(polls),
            LinkCommand::Identify => self.session.identify_again(),
            LinkCommand::Handshake => self.session.handshake_again(Instant::now()),
            LinkCommand::TuyaOptions(o) => self.session.set_tuya_options(o),
            LinkCommand::Watch(tx) => self.events.watchers.add(tx),
            LinkCommand::Shutdown => self.shutdown = true,
        }
    }

    fn fail_queue(&mut self, err: impl Fn() -> ExchangeError) {
        for item in self.queue.take_all() {
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
                // A watch starts at once: what the exchange under way reads is watched.
                LinkCommand::Watch(tx) => self.events.watchers.add(tx),
                other => self.queue.defer(other),
            }
        }
        Ok(())
    }

    fn deliver(&mut self, to: ReplyTo, result: Result<Reply, ExchangeError>) {
        match to {
            ReplyTo::Event(id) => self.events.emit(LinkEvent::Reply { id, result }),
            ReplyTo::Channel(tx) => {
                let _ = tx.send(result);
            }
        }
    }

    // ---- events ---------------------------------------------------------------------------

    fn emit_connected(&mut self) {
        if let Some(state) = self.wire.connected_state() {
            self.events.emit(LinkEvent::State(state));
        }
    }

    /// Reports the counters when they changed, at most every [`STATS_EVERY`], and wakes the UI.
    fn housekeeping(&mut self) {
        let now = Instant::now();
        let stats = &mut self.wire.stats;
        stats.margin = Some(self.timing.auto_margin());
        stats.answer_latency = self.timing.learned.measured();
        stats.latency_timer = self.timing.learned.latency_timer;
        stats.dropped_events = self.events.dropped();
        let (reported, at) = &self.stats_reported;
        if now.duration_since(*at) >= STATS_EVERY && stats != reported {
            self.stats_reported = (stats.clone(), now);
            self.events.emit(LinkEvent::Stats(stats.clone()));
        }
        self.events.flush_wake();
    }

    // ---- idle ---------------------------------------------------------------------------------

    /// Nothing to do: waits a little for a command, reads what the device sends on its own, and
    /// now and then checks that the port is still there.
    fn idle(&mut self) {
        let now = Instant::now();
        let mut wait = IDLE_SLICE;
        if let Some(due) = self.polls.next_due() {
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
        if !self.wire.is_open() || self.shutdown {
            return;
        }
        let before = self.wire.buffered();
        match self.read_some(Instant::now()) {
            Ok(0) if before > 0 => {
                // The line is quiet with a partial frame held: it will not complete.
                self.wire.flush();
                self.drain_unsolicited();
            }
            Ok(_) => self.drain_unsolicited(),
            Err(_) => return,
        }
        self.check_port(now);
    }
}
