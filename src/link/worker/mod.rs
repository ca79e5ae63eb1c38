//! The worker thread: owns the transport, runs exchanges, polls telemetry, answers the device's
//! own requests, and reconnects a lost port.

use super::decoder::AnyDecoder;
use super::request::{ExchangeError, Match, Reply, ReplySpec, Request};
use super::session::tuya::{self as tuya_module, HandshakeStep, TuyaEvent, TuyaModuleOptions};
use super::session::{self, DeviceInfo};
use super::{
    LinkCommand, LinkEvent, LinkOptions, LinkState, LinkStats, LogEntry, Opener, Poll, ReplyTo,
    Transport, Waker, wire_time,
};
use crate::packet::{Header, Packet};
use crate::profile::{DeviceCode, Profile, Protocol};
use crate::protocol::{Direction, FrameError, msp, servo, tuya};
use crossbeam_channel::{Receiver, RecvTimeoutError, Sender, TrySendError};
use std::collections::VecDeque;
use std::sync::Arc;
use std::time::{Duration, Instant, SystemTime};

/// Extra time allowed between the bytes of one frame (scheduler jitter on a loaded machine).
const INTER_BYTE_SLACK: Duration = Duration::from_millis(5);
/// How long the idle loop waits for a command before looking at the port again.
const IDLE_SLICE: Duration = Duration::from_millis(5);
/// How often an idle worker checks that the port is still there.
const PORT_CHECK: Duration = Duration::from_millis(500);
/// How often changed counters are reported.
const STATS_EVERY: Duration = Duration::from_millis(250);
/// Reconnect backoff bounds.
const BACKOFF_MIN: Duration = Duration::from_millis(100);
const BACKOFF_MAX: Duration = Duration::from_secs(2);
/// Tuya: how soon a failed handshake is tried again, and how soon a missed heartbeat.
const HANDSHAKE_RETRY: Duration = Duration::from_secs(1);
const HEARTBEAT_RETRY: Duration = Duration::from_secs(3);

/// The default answer margin of a protocol: how long the device may think before its first byte.
pub fn default_margin(protocol: Protocol) -> Duration {
    match protocol {
        Protocol::Msp => Duration::from_millis(20),
        Protocol::Servo => Duration::from_micros(1500),
        Protocol::Tuya => Duration::from_millis(300),
    }
}

struct TuyaState {
    opts: TuyaModuleOptions,
    handshake_done: bool,
    next_heartbeat: Instant,
    next_handshake: Option<Instant>,
}

pub(super) struct Worker {
    transport: Option<Box<dyn Transport>>,
    opener: Opener,
    profile: Arc<Profile>,
    opts: LinkOptions,
    cmds: Receiver<LinkCommand>,
    events: Sender<LinkEvent>,
    waker: Option<Waker>,
    decoder: AnyDecoder,
    queue: VecDeque<Queued>,
    deferred: VecDeque<LinkCommand>,
    polls: Vec<(Poll, Instant)>,
    poll_cursor: usize,
    /// Polls sent ahead of their answers (MSP polls at the wire's maximum), oldest first.
    in_flight: VecDeque<InFlight>,
    device_code: u8,
    baud: u32,
    /// When the bytes written so far have crossed the wire (at the rate they were sent at).
    sent_until: Instant,
    stats: LinkStats,
    stats_reported: LinkStats,
    stats_at: Instant,
    checked_at: Instant,
    tuya: TuyaState,
    identify_pending: bool,
    shutdown: bool,
    wake: bool,
}

/// A polled request whose answer has not come yet.
struct InFlight {
    /// Its place in the poll list when it was sent.
    index: usize,
    request: Request,
    sent: Instant,
    /// When its answer is due at the latest, counted from its own write.
    deadline: Instant,
}

/// Work done in order.
enum Queued {
    Exchange(Request, ReplyTo),
    Baud(u32, Option<Sender<Result<(), super::LinkError>>>),
}

/// What a wait for an answer saw.
struct Waited {
    outcome: Outcome,
    /// The last frame error.
    frame_err: Option<FrameError>,
    /// The last frame that answered something else: its command, and its servo id.
    mismatch: Option<(u8, Option<u8>)>,
}

enum Outcome {
    Answered(Vec<Packet>),
    Nothing,
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
        let device_code = profile
            .device_code
            .map_or(msp::DEVICE_CORE, DeviceCode::initial);
        let baud = transport.baud();
        let start = opts.start_session;
        Self {
            decoder: AnyDecoder::new(profile.protocol),
            transport: Some(transport),
            opener,
            tuya: TuyaState {
                opts: opts.tuya.clone(),
                handshake_done: false,
                next_heartbeat: now,
                next_handshake: start.then_some(now),
            },
            profile,
            opts,
            cmds,
            events,
            waker,
            queue: VecDeque::new(),
            deferred: VecDeque::new(),
            polls: Vec::new(),
            poll_cursor: 0,
            in_flight: VecDeque::new(),
            sent_until: Instant::now(),
            device_code,
            baud,
            stats: LinkStats::default(),
            stats_reported: LinkStats::default(),
            stats_at: now,
            checked_at: now,
            identify_pending: start,
            shutdown: false,
            wake: false,
        }
    }

    pub(super) fn run(mut self) {
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
            // The session learns the device before anything else is sent to it.
            if self.identify_pending && self.profile.protocol == Protocol::Msp {
                self.identify_pending = false;
                self.settle_polls();
                self.identify();
            } else if let Some(item) = self.queue.pop_front() {
                // Polls in flight are answered first: no answer can be taken for another's.
                self.settle_polls();
                match item {
                    Queued::Exchange(req, to) => {
                        let result = self.exchange(&req);
                        self.deliver(to, result);
                    }
                    Queued::Baud(baud, ack) => self.switch_baud(baud, ack),
                }
            } else if self.tuya_due() {
                self.tuya_tick();
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
        self.emit(LinkEvent::State(LinkState::Closed));
        self.flush_wake();
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
            LinkCommand::SetBaud { baud, ack } => self.queue.push_back(Queued::Baud(baud, ack)),
            LinkCommand::Identify => self.identify_pending = true,
            LinkCommand::Handshake => {
                self.tuya.handshake_done = false;
                self.tuya.next_handshake = Some(Instant::now());
            }
            LinkCommand::TuyaOptions(o) => self.tuya.opts = o,
            LinkCommand::Shutdown => self.shutdown = true,
        }
    }

    fn switch_baud(&mut self, baud: u32, ack: Option<Sender<Result<(), super::LinkError>>>) {
        // A frame still crossing the wire (a broadcast nobody answers) would be cut off by the
        // new rate: it goes out whole first.
        let now = Instant::now();
        if self.sent_until > now {
            std::thread::sleep(self.sent_until - now);
        }
        self.baud = baud;
        let result = match self.transport.as_mut() {
            Some(t) => t.set_baud(baud).map(|()| {
                let _ = t.clear_input();
            }),
            None => Err(super::LinkError::Disconnected("port lost".into())),
        };
        match &result {
            Ok(()) => {
                self.decoder.clear();
                self.emit_connected();
            }
            Err(e) => self.emit(LinkEvent::State(LinkState::Lost {
                reason: e.to_string(),
            })),
        }
        if let Some(tx) = ack {
            let _ = tx.send(result);
        }
    }

    fn fail_queue(&mut self, err: impl Fn() -> ExchangeError) {
        for item in std::mem::take(&mut self.queue) {
            match item {
                Queued::Exchange(_, to) => self.deliver(to, Err(err())),
                Queued::Baud(_, Some(tx)) => {
                    let _ = tx.send(Err(super::LinkError::Disconnected(err().to_string())));
                }
                Queued::Baud(_, None) => {}
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
                LinkCommand::TuyaOptions(o) => self.tuya.opts = o,
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
        if now.duration_since(self.stats_at) >= STATS_EVERY && self.stats != self.stats_reported {
            self.stats_at = now;
            self.stats_reported = self.stats.clone();
            self.emit(LinkEvent::Stats(self.stats.clone()));
        }
        self.flush_wake();
    }

    fn log(&mut self, direction: Direction, frame: Result<Packet, FrameError>) {
        self.emit(LinkEvent::Frame(LogEntry {
            at: SystemTime::now(),
            direction,
            frame,
        }));
    }

    // ---- the port -------------------------------------------------------------------------

    fn lost(&mut self, reason: String) {
        self.transport = None;
        self.decoder.clear();
        for f in std::mem::take(&mut self.in_flight) {
            self.emit(LinkEvent::Telemetry {
                command: f.request.command,
                at: Instant::now(),
                result: Err(ExchangeError::Disconnected(reason.clone())),
            });
        }
        self.tuya.handshake_done = false;
        self.emit(LinkEvent::State(LinkState::Lost {
            reason: reason.clone(),
        }));
        self.fail_queue(|| ExchangeError::Disconnected(reason.clone()));
        self.flush_wake();
    }

    fn reconnect(&mut self) {
        let mut backoff = BACKOFF_MIN;
        let mut attempt = 0u32;
        while !self.shutdown {
            // Wait out the backoff while still answering commands.
            let until = Instant::now() + backoff;
            while !self.shutdown {
                let left = until.saturating_duration_since(Instant::now());
                if left.is_zero() {
                    break;
                }
                match self.cmds.recv_timeout(left) {
                    Ok(c) => self.handle(c),
                    Err(RecvTimeoutError::Timeout) => break,
                    Err(RecvTimeoutError::Disconnected) => self.shutdown = true,
                }
                self.flush_wake();
            }
            if self.shutdown || !self.opts.reconnect {
                if !self.opts.reconnect {
                    backoff = BACKOFF_MAX;
                    continue;
                }
                return;
            }
            attempt += 1;
            self.emit(LinkEvent::State(LinkState::Reconnecting { attempt }));
            self.flush_wake();
            match (self.opener)() {
                Ok(mut t) => {
                    if t.baud() != self.baud {
                        let _ = t.set_baud(self.baud);
                    }
                    self.transport = Some(t);
                    self.decoder.clear();
                    self.emit_connected();
                    self.identify_pending = self.opts.start_session;
                    if self.opts.start_session {
                        self.tuya.next_handshake = Some(Instant::now());
                    }
                    return;
                }
                Err(_) => backoff = (backoff * 2).min(BACKOFF_MAX),
            }
        }
    }

    fn write(&mut self, bytes: &[u8], sent: Packet) -> Result<(), ExchangeError> {
        let Some(t) = self.transport.as_mut() else {
            return Err(ExchangeError::Disconnected("port lost".into()));
        };
        if let Err(e) = t.write(bytes) {
            let reason = e.to_string();
            self.lost(reason.clone());
            return Err(ExchangeError::Disconnected(reason));
        }
        let now = Instant::now();
        self.sent_until = self.sent_until.max(now) + wire_time(bytes.len(), self.baud);
        self.stats.sent += 1;
        self.log(Direction::HostToDevice, Ok(sent));
        Ok(())
    }

    /// Reads what arrives before `deadline` into the decoder.
    fn read_some(&mut self, deadline: Instant) -> Result<usize, ExchangeError> {
        let Some(t) = self.transport.as_mut() else {
            return Err(ExchangeError::Disconnected("port lost".into()));
        };
        let mut buf = [0u8; 4096];
        match t.read(&mut buf, deadline) {
            Ok(n) => {
                self.decoder.push(&buf[..n]);
                Ok(n)
            }
            Err(e) => {
                let reason = e.to_string();
                self.lost(reason.clone());
                Err(ExchangeError::Disconnected(reason))
            }
        }
    }

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
        if now.duration_since(self.checked_at) >= PORT_CHECK {
            self.checked_at = now;
            if let Some(t) = self.transport.as_mut()
                && let Err(e) = t.check()
            {
                self.lost(e.to_string());
            }
        }
    }

    fn drain_unsolicited(&mut self) {
        while let Some(item) = self.decoder.next_packet() {
            match item {
                Ok(p) => {
                    self.stats.received += 1;
                    self.log(Direction::DeviceToHost, Ok(p.clone()));
                    let _ = self.on_incoming(p);
                }
                Err(e) => {
                    self.stats.frame_errors += 1;
                    self.log(Direction::DeviceToHost, Err(e));
                }
            }
        }
    }

    /// A frame that answers no request: the device's own requests are answered, reports passed on.
    fn on_incoming(&mut self, p: Packet) -> Result<(), ExchangeError> {
        if p.direction != Direction::DeviceToHost {
            return Ok(()); // an echo of our own request on a one-wire bus
        }
        match (&p.header, self.profile.protocol) {
            (Header::Tuya { .. }, _) => {
                if let Some((name, answer)) =
                    tuya_module::answer_mcu_request(&self.tuya.opts, p.command)
                {
                    let frame = tuya::Frame::from_module(p.command, answer.clone());
                    let bytes = frame
                        .encode()
                        .map_err(|e| ExchangeError::Encode(e.to_string()))?;
                    self.write(&bytes, Packet::tuya(frame))?;
                    self.emit(LinkEvent::Tuya(TuyaEvent::McuRequest {
                        command: p.command,
                        name: name.to_string(),
                        answer,
                    }));
                } else if p.command == tuya::cmd::DP_REPORT {
                    self.emit(LinkEvent::Report(p));
                }
            }
            (
                Header::MspReply {
                    kind: msp::ReplyKind::Async,
                },
                _,
            ) => self.emit(LinkEvent::Report(p)),
            (Header::Servo, _) => self.emit(LinkEvent::Report(p)),
            _ => {}
        }
        Ok(())
    }

    // ---- exchanges ------------------------------------------------------------------------

    fn encode(&self, req: &Request) -> Result<(Vec<u8>, Packet), ExchangeError> {
        let enc = |e: crate::protocol::EncodeError| ExchangeError::Encode(e.to_string());
        Ok(match self.profile.protocol {
            Protocol::Msp => {
                let mut r = msp::Request::new(
                    req.device.unwrap_or(self.device_code),
                    req.command,
                    req.payload.clone(),
                );
                if req.reply == ReplySpec::None {
                    r.option = msp::OPTION_SILENT;
                }
                (r.encode().map_err(enc)?, Packet::msp_request(r))
            }
            Protocol::Servo => {
                let f = servo::Frame::request(req.command, req.payload.clone());
                (f.encode().map_err(enc)?, Packet::servo(f))
            }
            Protocol::Tuya => {
                let f = tuya::Frame::from_module(req.command, req.payload.clone());
                (f.encode().map_err(enc)?, Packet::tuya(f))
            }
        })
    }

    /// Sends `req` and waits for its answer, with bounded attempts. Returns at the first valid
    /// answer; a frame that answers something else is never taken for it.
    fn exchange(&mut self, req: &Request) -> Result<Reply, ExchangeError> {
        let (bytes, sent) = self.encode(req)?;
        let margin = req
            .margin
            .or(self.opts.margin)
            .unwrap_or(default_margin(self.profile.protocol));
        let attempts = req.attempts.max(1);
        // What has already arrived (a late answer to an earlier request) is dealt with before
        // this request is sent, so that it cannot be taken for this request's answer.
        self.read_some(Instant::now())?;
        self.drain_unsolicited();
        let mut last = ExchangeError::Timeout {
            command: req.command,
            attempts,
            waited_ms: 0,
        };
        for attempt in 1..=attempts {
            if attempt > 1 {
                self.stats.retries += 1;
            }
            let t0 = Instant::now();
            self.write(&bytes, sent.clone())?;
            let (each, burst) = match &req.reply {
                ReplySpec::None => {
                    return Ok(Reply {
                        packets: Vec::new(),
                        rtt: Duration::ZERO,
                        attempts: attempt,
                    });
                }
                ReplySpec::Required(m) | ReplySpec::Optional(m) => (m.clone(), None),
                ReplySpec::Burst { each, quiet } => (each.clone(), Some(*quiet)),
            };
            let baud = self.baud;
            let first = t0 + wire_time(bytes.len() + 1, baud) + margin;
            let Waited {
                outcome,
                frame_err,
                mismatch,
            } = self.wait_for(&each, burst, first, baud)?;
            match outcome {
                Outcome::Answered(packets) => {
                    let rtt = t0.elapsed();
                    self.stats.rtt = Some(rtt);
                    return Ok(Reply {
                        packets,
                        rtt,
                        attempts: attempt,
                    });
                }
                Outcome::Nothing => {}
            }
            if matches!(req.reply, ReplySpec::Optional(_)) && frame_err.is_none() {
                return Ok(Reply {
                    packets: Vec::new(),
                    rtt: t0.elapsed(),
                    attempts: attempt,
                });
            }
            last = self.unanswered(req.command, each.command, frame_err, mismatch, attempts, t0);
        }
        Err(last)
    }

    /// Why a request sent at `sent` got no answer: a garbled frame, an answer to something
    /// else, or nothing at all.
    fn unanswered(
        &mut self,
        command: u8,
        expected: u8,
        frame_err: Option<FrameError>,
        mismatch: Option<(u8, Option<u8>)>,
        attempts: u8,
        sent: Instant,
    ) -> ExchangeError {
        if let Some(error) = frame_err {
            ExchangeError::Garbled { command, error }
        } else if let Some((got, from)) = mismatch {
            ExchangeError::Mismatch {
                expected,
                got,
                from,
            }
        } else {
            self.stats.timeouts += 1;
            ExchangeError::Timeout {
                command,
                attempts,
                waited_ms: sent.elapsed().as_millis() as u64,
            }
        }
    }

    /// Reads until the answer (or the end of a burst) or the deadline. Returns what came, the
    /// last frame error and the last mismatching command seen (with the servo id it came from).
    fn wait_for(
        &mut self,
        each: &Match,
        burst: Option<Duration>,
        first_deadline: Instant,
        baud: u32,
    ) -> Result<Waited, ExchangeError> {
        let mut deadline = first_deadline;
        let mut got: Vec<Packet> = Vec::new();
        let mut frame_err = None;
        let mut mismatch = None;
        let mut flushed = false;
        loop {
            while let Some(item) = self.decoder.next_packet() {
                match item {
                    Ok(p) => {
                        self.stats.received += 1;
                        self.log(Direction::DeviceToHost, Ok(p.clone()));
                        if each.accepts(&p) {
                            if self.profile.protocol == Protocol::Tuya
                                && p.command == tuya::cmd::DP_REPORT
                            {
                                self.emit(LinkEvent::Report(p.clone()));
                            }
                            match burst {
                                Some(quiet) => {
                                    got.push(p);
                                    deadline = Instant::now() + quiet;
                                }
                                None => {
                                    return Ok(Waited {
                                        outcome: Outcome::Answered(vec![p]),
                                        frame_err: None,
                                        mismatch: None,
                                    });
                                }
                            }
                        } else {
                            let answers_other = p.direction == Direction::DeviceToHost
                                && !matches!(
                                    p.header,
                                    Header::MspReply {
                                        kind: msp::ReplyKind::Async
                                    }
                                )
                                && tuya_module::answer_mcu_request(&self.tuya.opts, p.command)
                                    .is_none()
                                && !(matches!(p.header, Header::Tuya { .. })
                                    && p.command == tuya::cmd::DP_REPORT);
                            if answers_other {
                                let from = matches!(p.header, Header::Servo)
                                    .then(|| p.payload.first().copied())
                                    .flatten();
                                mismatch = Some((p.command, from));
                            }
                            self.on_incoming(p)?;
                        }
                    }
                    Err(e) => {
                        self.stats.frame_errors += 1;
                        self.log(Direction::DeviceToHost, Err(e.clone()));
                        frame_err = Some(e);
                    }
                }
            }
            let now = Instant::now();
            if now >= deadline {
                if self.decoder.buffered() > 0 && !flushed {
                    self.decoder.flush();
                    flushed = true;
                    continue;
                }
                let outcome = if got.is_empty() {
                    Outcome::Nothing
                } else {
                    Outcome::Answered(got)
                };
                return Ok(Waited {
                    outcome,
                    frame_err,
                    mismatch,
                });
            }
            self.commands_during_exchange()?;
            let slice = deadline.min(now + Duration::from_millis(50));
            if self.read_some(slice)? > 0 {
                flushed = false;
                let more = Instant::now() + wire_time(8, baud) + INTER_BYTE_SLACK;
                deadline = deadline.max(more);
            }
        }
    }

    // ---- polling --------------------------------------------------------------------------

    fn due_poll(&self) -> Option<usize> {
        let now = Instant::now();
        let n = self.polls.len();
        (0..n)
            .map(|k| (self.poll_cursor + k) % n)
            .find(|&i| self.polls[i].1 <= now)
    }

    /// Whether poll `i` is sent ahead of the answers still to come: MSP polls at the wire's
    /// maximum, while fewer than [`super::LinkOptions::poll_pipeline`] are in flight. The
    /// request of the next poll then crosses the host-to-device line while the device is still
    /// sending the previous answer (full duplex), so that the device-to-host line never waits
    /// for the host.
    fn pipelined(&self, i: usize) -> bool {
        self.profile.protocol == Protocol::Msp
            && self.opts.poll_pipeline > 1
            && self.polls[i].0.interval.is_none()
            && matches!(self.polls[i].0.request.reply, ReplySpec::Required(_))
    }

    /// Sends poll `i` without waiting for its answer; waits for the oldest answer once the
    /// pipeline is full.
    fn send_poll_ahead(&mut self, i: usize) {
        if self.in_flight.len() >= self.opts.poll_pipeline {
            self.await_oldest_poll();
            return;
        }
        let request = self.polls[i].0.request.clone();
        self.poll_cursor = (i + 1) % self.polls.len().max(1);
        let Ok((bytes, sent)) = self.encode(&request) else {
            // Not encodable: report it as the sequential path would.
            self.run_poll(i);
            return;
        };
        if self.in_flight.is_empty() {
            // As in an exchange: what has already arrived is dealt with before sending.
            if self.read_some(Instant::now()).is_err() {
                return;
            }
            self.drain_unsolicited();
        }
        let margin = request
            .margin
            .or(self.opts.margin)
            .unwrap_or(default_margin(self.profile.protocol));
        let t0 = Instant::now();
        if self.write(&bytes, sent).is_err() {
            return;
        }
        self.in_flight.push_back(InFlight {
            index: i,
            deadline: t0 + wire_time(bytes.len() + 1, self.baud) + margin,
            request,
            sent: t0,
        });
    }

    /// Waits for every poll in flight.
    fn settle_polls(&mut self) {
        while !self.in_flight.is_empty() && self.transport.is_some() {
            self.await_oldest_poll();
        }
    }

    /// Waits for the answer to the oldest poll in flight and reports it. The device answers in
    /// order, so the answer can come no sooner than the ones before it: its deadline runs at
    /// least one device margin from now.
    fn await_oldest_poll(&mut self) {
        let Some(f) = self.in_flight.pop_front() else {
            return;
        };
        let ReplySpec::Required(each) = f.request.reply.clone() else {
            return;
        };
        let margin = f
            .request
            .margin
            .or(self.opts.margin)
            .unwrap_or(default_margin(self.profile.protocol));
        let deadline = f.deadline.max(Instant::now() + margin);
        let baud = self.baud;
        let result = match self.wait_for(&each, None, deadline, baud) {
            Err(e) => Err(e),
            Ok(Waited {
                outcome: Outcome::Answered(packets),
                ..
            }) => {
                self.stats.rtt = Some(f.sent.elapsed());
                packets.into_iter().next().ok_or(ExchangeError::Timeout {
                    command: f.request.command,
                    attempts: 1,
                    waited_ms: 0,
                })
            }
            Ok(w) => Err(self.unanswered(
                f.request.command,
                each.command,
                w.frame_err,
                w.mismatch,
                1,
                f.sent,
            )),
        };
        let at = Instant::now();
        if let Some(slot) = self.polls.get_mut(f.index)
            && slot.0.request == f.request
        {
            slot.1 = at;
        }
        self.emit(LinkEvent::Telemetry {
            command: f.request.command,
            at,
            result,
        });
    }

    fn run_poll(&mut self, i: usize) {
        let (poll, _) = self.polls[i].clone();
        self.poll_cursor = (i + 1) % self.polls.len().max(1);
        let result = self.exchange(&poll.request);
        let at = Instant::now();
        if let Some(slot) = self.polls.get_mut(i) {
            slot.1 = match poll.interval {
                Some(iv) => (slot.1 + iv).max(at),
                None => at,
            };
        }
        let result = result.and_then(|r| {
            r.packets.into_iter().next().ok_or(ExchangeError::Timeout {
                command: poll.request.command,
                attempts: 1,
                waited_ms: 0,
            })
        });
        self.emit(LinkEvent::Telemetry {
            command: poll.request.command,
            at,
            result,
        });
    }

    // ---- MSP session ----------------------------------------------------------------------

    fn identify(&mut self) {
        let req = Request::new(msp::CMD_VERSION, Vec::new())
            .device(msp::DEVICE_CORE)
            .attempts(2);
        let result = self.exchange(&req).and_then(|r| {
            DeviceInfo::from_version(&self.profile, r.payload().unwrap_or_default())
                .map_err(|e| ExchangeError::Encode(format!("bad CMD_VERSION answer: {e}")))
        });
        let result = result.map(|mut info| {
            if let Some(DeviceCode::Auto(_)) = self.profile.device_code {
                self.device_code = info.hw;
            }
            let build = Request::new(msp::CMD_BUILD_INFO, Vec::new()).attempts(1);
            if let Ok(r) = self.exchange(&build) {
                info.build_date = session::build_date(r.payload().unwrap_or_default());
            }
            info
        });
        self.emit(LinkEvent::Identified(result));
    }

    // ---- Tuya session ---------------------------------------------------------------------

    fn tuya_due(&self) -> bool {
        if self.profile.protocol != Protocol::Tuya {
            return false;
        }
        let now = Instant::now();
        match self.tuya.next_handshake {
            Some(t) => t <= now,
            None => self.tuya.handshake_done && self.tuya.next_heartbeat <= now,
        }
    }

    fn tuya_tick(&mut self) {
        if self.tuya.next_handshake.is_some() {
            self.handshake();
            return;
        }
        let hb = Request::new(tuya::cmd::HEARTBEAT, Vec::new()).attempts(2);
        match self.exchange(&hb) {
            Ok(r) if r.payload() == Some(&[0][..]) => {
                self.emit(LinkEvent::Tuya(TuyaEvent::McuRestarted));
                self.tuya.handshake_done = false;
                self.tuya.next_handshake = Some(Instant::now());
            }
            Ok(_) => self.tuya.next_heartbeat = Instant::now() + self.tuya.opts.heartbeat,
            Err(ExchangeError::Disconnected(_)) => {}
            Err(_) => {
                self.emit(LinkEvent::Tuya(TuyaEvent::HeartbeatLost));
                self.tuya.next_heartbeat = Instant::now() + HEARTBEAT_RETRY;
            }
        }
    }

    fn step(&mut self, step: HandshakeStep, ok: bool, detail: String) {
        self.emit(LinkEvent::Tuya(TuyaEvent::Step { step, ok, detail }));
        self.flush_wake();
    }

    /// The module's start-up sequence; on a failed step it stops there and tries again later.
    fn handshake(&mut self) {
        self.tuya.next_handshake = None;
        let fail = |w: &mut Self, step, e: ExchangeError| {
            w.step(step, false, e.to_string());
            w.tuya.next_handshake = Some(Instant::now() + HANDSHAKE_RETRY);
        };
        let hb = Request::new(tuya::cmd::HEARTBEAT, Vec::new()).attempts(2);
        match self.exchange(&hb) {
            Ok(r) => {
                let first = r.payload() == Some(&[0][..]);
                let detail = if first {
                    "answered 0: first since the MCU started"
                } else {
                    "answered 1"
                };
                self.step(HandshakeStep::Heartbeat, true, detail.into());
            }
            Err(e) => return fail(self, HandshakeStep::Heartbeat, e),
        }
        match self.exchange(&Request::new(tuya::cmd::PRODUCT_INFO, Vec::new())) {
            Ok(r) => {
                let info = tuya_module::parse_product_info(r.payload().unwrap_or_default());
                let detail = match &info.error {
                    None => format!(
                        "PID {}, MCU {}, mode {}",
                        info.pid.as_deref().unwrap_or("?"),
                        info.version.as_deref().unwrap_or("?"),
                        info.mode.map_or("?".to_string(), |m| m.to_string())
                    ),
                    Some(e) => format!("not valid JSON ({e}); shown raw: {}", info.raw),
                };
                let ok = info.error.is_none();
                self.emit(LinkEvent::Tuya(TuyaEvent::ProductInfo(info)));
                self.step(HandshakeStep::ProductInfo, ok, detail);
            }
            Err(e) => return fail(self, HandshakeStep::ProductInfo, e),
        }
        let gpio = match self.exchange(&Request::new(tuya::cmd::WORK_MODE, Vec::new())) {
            Ok(r) => {
                let gpio = match r.payload().unwrap_or_default() {
                    [led, reset, ..] => Some((*led, *reset)),
                    _ => None,
                };
                self.emit(LinkEvent::Tuya(TuyaEvent::WorkMode { gpio }));
                let detail = match gpio {
                    None => "the MCU drives the Wi-Fi LED".to_string(),
                    Some((l, r)) => format!("the module drives the LED (GPIO {l}, reset GPIO {r})"),
                };
                self.step(HandshakeStep::WorkMode, true, detail);
                gpio
            }
            Err(e) => return fail(self, HandshakeStep::WorkMode, e),
        };
        if gpio.is_none() {
            let state = self.tuya.opts.wifi_state;
            match self.exchange(&Request::new(tuya::cmd::WIFI_STATE, vec![state])) {
                Ok(_) => self.step(
                    HandshakeStep::WifiState,
                    true,
                    format!("reported state {state}"),
                ),
                Err(e) => return fail(self, HandshakeStep::WifiState, e),
            }
        } else {
            self.step(
                HandshakeStep::WifiState,
                true,
                "not needed: the module drives the LED".into(),
            );
        }
        let query = Request::new(tuya::cmd::QUERY_STATUS, Vec::new()).reply(ReplySpec::Burst {
            each: Match::command(tuya::cmd::DP_REPORT),
            quiet: Duration::from_millis(300).max(wire_time(64, self.baud)),
        });
        match self.exchange(&query) {
            Ok(r) => self.step(
                HandshakeStep::QueryStatus,
                true,
                format!("{} report(s)", r.packets.len()),
            ),
            Err(e) => return fail(self, HandshakeStep::QueryStatus, e),
        }
        self.tuya.handshake_done = true;
        self.tuya.next_heartbeat = Instant::now() + self.tuya.opts.heartbeat;
        self.emit(LinkEvent::Tuya(TuyaEvent::HandshakeDone));
    }
}
