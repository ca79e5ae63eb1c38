//! The worker thread: owns the transport, runs exchanges, polls telemetry, answers the device's
//! own requests, and reconnects a lost port.

mod exchange;
mod polls;
mod port;

use polls::InFlight;

use super::decoder::AnyDecoder;
use super::request::{ExchangeError, Match, Reply, ReplySpec, Request};
use super::session::tuya::{self as tuya_module, HandshakeStep, TuyaEvent, TuyaModuleOptions};
use super::session::{self, DeviceInfo};
use super::{
    LinkCommand, LinkEvent, LinkOptions, LinkState, LinkStats, LogEntry, Opener, Poll, ReplyTo,
    Transport, Waker, wire_time,
};
use crate::packet::Packet;
use crate::profile::{DeviceCode, Profile, Protocol};
use crate::protocol::{Direction, FrameError, msp, tuya};
use crossbeam_channel::{Receiver, RecvTimeoutError, Sender, TrySendError};
use std::collections::VecDeque;
use std::sync::Arc;
use std::time::{Duration, Instant, SystemTime};

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

/// Work done in order.
enum Queued {
    Exchange(Request, ReplyTo),
    Baud(u32, Option<Sender<Result<(), super::LinkError>>>),
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
