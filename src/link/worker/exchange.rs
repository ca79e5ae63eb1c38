//! Exchanges: encode a request, write it, wait for its answer until its deadline ([`super::wait`]),
//! retry a bounded number of times, and say why nothing answered (a garbled frame, an answer to
//! something else, or silence). After the last attempt an in-order device is given the grace to
//! answer late, and what it still owes is remembered ([`super::timing`]). Frames that answer no
//! request are passed on here too.

use super::Worker;
use super::wait::{BurstEnd, Outcome};
use crate::link::request::{ExchangeError, HOST_LATE, Match, Reply, ReplySpec, Request};
use crate::link::session::Unasked;
use crate::link::{LinkError, LinkEvent, NoAnswer, wire_time};
use crate::packet::{Header, Packet};
use crate::profile::Protocol;
use crate::protocol::{Direction, FrameError};
use log::debug;
use std::time::{Duration, Instant, SystemTime};

/// The default answer margin of a protocol: how long the device may think before its first byte
/// (the seeds' and the field's figures: MSP 20 ms, servo 1.5 ms, Tuya 300 ms).
pub fn default_margin(protocol: Protocol) -> Duration {
    match protocol {
        Protocol::Msp => Duration::from_millis(20),
        Protocol::Servo => Duration::from_micros(1500),
        Protocol::Tuya => Duration::from_millis(300),
    }
}

/// An exchange under way: the request, its bytes, and what its attempts have seen.
struct Exchange<'r> {
    req: &'r Request,
    bytes: Vec<u8>,
    /// The frame the bytes are, for the packet log.
    sent: Packet,
    /// What an answer looks like (`None`: the request waits for none).
    each: Option<Match>,
    margin: Duration,
    /// The request's own wire time.
    on_wire: Duration,
    /// The device answers in order, and this request waits for a required answer: a late
    /// answer is its own, and an unanswered attempt's answer is owed.
    in_order: bool,
    /// When each attempt was written.
    sends: Vec<Instant>,
    frame_err: Option<FrameError>,
    mismatch: Option<(u8, Option<u8>)>,
}

/// How one attempt ended.
enum Tried {
    /// With the exchange's result: an answer, or none awaited.
    Done(Reply),
    /// Unanswered, and why.
    Unanswered(ExchangeError),
}

impl Worker {
    /// Writes `bytes` (the frame `sent`, for the packet log); a failed write loses the port.
    pub(super) fn write(&mut self, bytes: &[u8], sent: Packet) -> Result<(), ExchangeError> {
        self.wire.write(bytes).map_err(|e| self.lost_in(e))?;
        if let Some(ev) = self.session.wrote(&sent) {
            self.events.emit(ev);
        }
        self.events.tap(Direction::HostToDevice, Ok(sent), None);
        Ok(())
    }

    /// When a request asked for at `asked`, whose write of `bytes` bytes returned at `written`,
    /// counts as sent: `written` when the host was held up in the write for longer than
    /// [`HOST_LATE`] beyond the bytes' own wire time (counted in the link's counters), else
    /// `asked`.
    pub(super) fn host_was_late_by(
        &mut self,
        asked: Instant,
        written: Instant,
        bytes: usize,
    ) -> Instant {
        let late = written
            .saturating_duration_since(asked)
            .saturating_sub(wire_time(bytes, self.wire.baud()));
        if late <= HOST_LATE {
            return asked;
        }
        self.host_late(late);
        written
    }

    /// When a request asked for at `asked`, whose `bytes` bytes were just written, counts as
    /// sent: when the port says its write went out ([`crate::link::Transport::written_at`]),
    /// else as [`Self::host_was_late_by`] reckons it.
    pub(super) fn sent_at(&mut self, asked: Instant, bytes: usize) -> Instant {
        let reckoned = self.host_was_late_by(asked, Instant::now(), bytes);
        self.wire.written_at().unwrap_or(reckoned)
    }

    /// The host ran `late` behind a deadline it had set: counted, the worst kept (for the
    /// link, and for the exchange under way: [`Self::watching_late`]).
    pub(super) fn host_late(&mut self, late: Duration) {
        self.late_seen = self.late_seen.max(late);
        let stats = &mut self.wire.stats;
        stats.host_late += 1;
        stats.host_late_max = stats.host_late_max.max(late);
        debug!(
            "the host ran {:.1} ms behind a deadline (a loaded computer)",
            late.as_secs_f64() * 1e3
        );
    }

    /// A read until `deadline` found nothing, so it returned at its deadline: later than
    /// [`HOST_LATE`] after it is a late host, counted ([`Self::host_late`]).
    pub(super) fn woke_after(&mut self, deadline: Instant) {
        let woke = Instant::now().saturating_duration_since(deadline);
        if woke > HOST_LATE {
            self.host_late(woke);
        }
    }

    /// Runs `f` (an exchange, a poll's wait, a sweep) and returns what it gave with the most the
    /// host ran behind a deadline during it (zero: on time throughout). Watches nest: an
    /// exchange within one (a fence) counts for both.
    pub(super) fn watching_late<T>(&mut self, f: impl FnOnce(&mut Self) -> T) -> (T, Duration) {
        let outer = std::mem::take(&mut self.late_seen);
        let result = f(self);
        let late = self.late_seen;
        self.late_seen = outer.max(late);
        (result, late)
    }

    /// Reads what arrives before `deadline` into the decoder; a failed read loses the port.
    pub(super) fn read_some(&mut self, deadline: Instant) -> Result<usize, ExchangeError> {
        self.wire.read_some(deadline).map_err(|e| self.lost_in(e))
    }

    /// The port failed with `e` during an exchange: it is lost, and the exchange ends with
    /// [`ExchangeError::Disconnected`].
    pub(super) fn lost_in(&mut self, e: LinkError) -> ExchangeError {
        let reason = e.to_string();
        self.lost(reason.clone());
        ExchangeError::Disconnected(reason)
    }

    /// The next frame (or frame error) decoded, as the session sorts it: a Tuya frame that
    /// repeats what the module sent is its own echo.
    pub(super) fn next_frame(&mut self) -> Option<Result<Packet, FrameError>> {
        let item = self.wire.next_frame()?;
        Some(item.map(|p| {
            let (p, event) = self.session.received(p);
            if let Some(ev) = event {
                self.events.emit(ev);
            }
            p
        }))
    }

    /// Counts a frame read (or a frame error); one from the device tells that it answers.
    pub(super) fn count(&mut self, frame: &Result<Packet, FrameError>) {
        match frame {
            Ok(p) => {
                self.wire.stats.received += 1;
                if p.direction == Direction::DeviceToHost
                    && let Some(ev) = self.liveness.answered()
                {
                    self.events.emit(LinkEvent::Device(ev));
                }
            }
            Err(_) => self.wire.stats.frame_errors += 1,
        }
    }

    /// Reads what has already arrived and takes it as answering no request: done before a
    /// request is sent, so that it cannot be taken for that request's answer.
    pub(super) fn take_arrived(&mut self) -> Result<(), ExchangeError> {
        self.read_some(Instant::now())?;
        self.drain_unsolicited();
        Ok(())
    }

    /// Takes every frame already decoded as one that answers no request (a servo's is kept for
    /// the next sweep: it may answer a request of the last one).
    pub(super) fn drain_unsolicited(&mut self) {
        while let Some(item) = self.next_frame() {
            self.count(&item);
            self.keep_unclaimed(item.as_ref());
            match item {
                Ok(p) => {
                    if self.late_answer(&p) {
                        continue;
                    }
                    self.events.tap_in(Ok(p.clone()), None);
                    let unasked = self.session.unasked(&p);
                    let _ = self.take_unasked(p, unasked);
                }
                Err(e) => self.events.tap_in(Err(e), None),
            }
        }
    }

    /// A frame that answers no request, as the session sorted it: reports are passed on, the
    /// MCU's own requests answered, the rest dropped.
    pub(super) fn take_unasked(
        &mut self,
        p: Packet,
        unasked: Unasked,
    ) -> Result<(), ExchangeError> {
        match unasked {
            Unasked::Echo | Unasked::Stale => {}
            Unasked::Report | Unasked::LateReply => self.events.emit(LinkEvent::Report(p)),
            Unasked::McuRequest {
                reply,
                events,
                report,
            } => {
                if report {
                    self.events.emit(LinkEvent::Report(p));
                }
                if let Some(reply) = reply {
                    let bytes = reply
                        .encode()
                        .map_err(|e| ExchangeError::Encode(e.to_string()))?;
                    self.write(&bytes, Packet::tuya(reply))?;
                }
                for ev in events {
                    self.events.emit(LinkEvent::Tuya(ev));
                }
            }
            Unasked::Ignored(event) => self.events.emit(LinkEvent::Tuya(event)),
        }
        Ok(())
    }

    /// Sends `req` and waits for its answer, with bounded attempts. Returns at the first valid
    /// answer; a frame that answers something else is never taken for it, nor is an answer owed
    /// to an earlier request. After the last attempt, an in-order device (MSP, servo) is given
    /// the grace period to answer late; attempts left unanswered are owed.
    ///
    /// A timeout during which the host ran behind one of the exchange's deadlines by
    /// [`crate::link::HELD_UP`] or more says so ([`ExchangeError::Timeout::host_late`]).
    pub(super) fn exchange(&mut self, req: &Request) -> Result<Reply, ExchangeError> {
        self.exchange_with(req, true)
    }

    fn exchange_with(&mut self, req: &Request, fence: bool) -> Result<Reply, ExchangeError> {
        let (result, late) = self.watching_late(|w| w.exchange_once(req, fence));
        result.map_err(|e| e.late_host(late))
    }

    fn exchange_once(&mut self, req: &Request, fence: bool) -> Result<Reply, ExchangeError> {
        let (mut bytes, mut sent) = self.session.encode(req)?;
        if req.bad_checksum
            && let Some(last) = bytes.last_mut()
        {
            *last = last.wrapping_add(1);
            sent.wire.clone_from(&bytes);
        }
        // What has already arrived (a late answer to an earlier request) is dealt with before
        // this request is sent, so that it cannot be taken for this request's answer.
        self.take_arrived()?;
        let each = req.reply.each().cloned();
        let in_order = self.session.in_order() && matches!(req.reply, ReplySpec::Required(_));
        if fence
            && in_order
            && let Some(m) = &each
        {
            self.fence(m)?;
        }
        let mut x = Exchange {
            on_wire: wire_time(bytes.len(), self.wire.baud()),
            margin: self.timing.margin(req),
            req,
            bytes,
            sent,
            each,
            in_order,
            sends: Vec::new(),
            frame_err: None,
            mismatch: None,
        };
        let attempts = req.attempts.max(1);
        let mut last = ExchangeError::Timeout {
            command: req.command.into(),
            attempts,
            waited_ms: 0,
            host_late: None,
        };
        for attempt in 1..=attempts {
            match self.attempt(&mut x, attempt)? {
                Tried::Done(reply) => return Ok(reply),
                Tried::Unanswered(e) => last = e,
            }
        }
        self.after_attempts(&x, last)
    }

    /// Attempt number `attempt` of `x`: written, and its answer awaited.
    fn attempt(&mut self, x: &mut Exchange<'_>, attempt: u8) -> Result<Tried, ExchangeError> {
        if attempt > 1 {
            self.wire.stats.retries += 1;
        }
        let t0 = Instant::now();
        self.write(&x.bytes, x.sent.clone())?;
        // The answer is due after the request has left: a host thread held up in the write (a
        // loaded computer) does not shorten the device's time to answer. The round trip still
        // counts from `t0`.
        let due_from = self.sent_at(t0, x.bytes.len());
        x.sends.push(t0);
        let Some(each) = x.each.clone() else {
            return Ok(Tried::Done(Reply {
                packets: Vec::new(),
                rtt: Duration::ZERO,
                attempts: attempt,
            }));
        };
        let baud = self.wire.baud();
        let burst = burst_end(&x.req.reply, due_from, x.bytes.len(), baud, x.margin);
        let first = due_from + wire_time(x.bytes.len() + 1, baud) + x.margin;
        let waited = self.wait_for(&each, burst, first)?;
        x.frame_err = waited.frame_err.or(x.frame_err.take());
        x.mismatch = waited.mismatch.or(x.mismatch);
        if let Outcome::Answered {
            packets,
            first,
            last,
        } = waited.outcome
        {
            return Ok(Tried::Done(self.answered(packets, (first, last), x, &each)));
        }
        if matches!(x.req.reply, ReplySpec::Optional(_)) && x.frame_err.is_none() {
            // No answer, so no round trip: how long this thread waited for none (a stopped or
            // starved process included) is no device's answer time.
            return Ok(Tried::Done(Reply {
                packets: Vec::new(),
                rtt: Duration::ZERO,
                attempts: attempt,
            }));
        }
        let attempts = x.req.attempts.max(1);
        let e = self.unanswered(
            x.req.command,
            each.command,
            x.frame_err.clone(),
            x.mismatch,
            (attempt, attempts),
            t0,
        );
        Ok(Tried::Unanswered(e))
    }

    /// Every attempt went unanswered (`last` says why): an in-order device is given the grace
    /// to answer any of them late; what it still does not answer is owed.
    fn after_attempts(
        &mut self,
        x: &Exchange<'_>,
        last: ExchangeError,
    ) -> Result<Reply, ExchangeError> {
        let Some(each) = x.each.as_ref().filter(|_| x.in_order) else {
            return Err(last);
        };
        // Counted from when the last attempt's answer was due, not from when this thread got to
        // it: a loaded host that wakes late gives no more grace than a punctual one.
        let due = x.sends.last().map_or_else(Instant::now, |&t0| {
            t0 + wire_time(x.bytes.len() + 1, self.wire.baud()) + x.margin
        });
        let grace = due + self.timing.learned.grace(x.margin);
        let waited = self.wait_for(each, None, grace)?;
        if let Outcome::Answered {
            packets,
            first,
            last,
        } = waited.outcome
        {
            self.wire.stats.late_answers += 1;
            debug!(
                "late answer to command {} within the grace, after {} attempt(s)",
                x.req.command,
                x.sends.len()
            );
            return Ok(self.answered(packets, (first, last), x, each));
        }
        for &t in &x.sends {
            self.timing.owe(each, t + x.on_wire, x.margin);
        }
        Err(last)
    }

    /// An answer came after the attempts of `x`: its latency is learned (counted from the first
    /// attempt: an in-order device answers the oldest first), and the later attempts' answers
    /// are owed.
    ///
    /// `read` is when the answer's first and last frames were read: the link's round trip is
    /// the first's, and a burst's reply lasts until its last frame (never until the end of the
    /// wait).
    fn answered(
        &mut self,
        packets: Vec<Packet>,
        read: (Instant, Instant),
        x: &Exchange<'_>,
        each: &Match,
    ) -> Reply {
        let sent = x.sends.first().copied().unwrap_or(read.0);
        let rtt = read.0.saturating_duration_since(sent);
        self.wire.stats.rtt = Some(rtt);
        if x.in_order {
            let baud = self.wire.baud();
            let answer_wire = packets
                .first()
                .map_or(Duration::ZERO, |p| wire_time(p.wire.len(), baud));
            self.timing
                .observe(rtt.saturating_sub(x.on_wire + answer_wire));
            let margin = self.timing.learned.margin(Duration::ZERO);
            for &t in x.sends.iter().skip(1) {
                self.timing.owe(each, t + x.on_wire, margin);
            }
        }
        Reply {
            packets,
            rtt: read.1.saturating_duration_since(sent),
            attempts: x.sends.len() as u8,
        }
    }

    /// Before a request whose answer an owed answer could be taken for: asks the device
    /// something else and waits for that answer. The device answers in order, so by then the
    /// owed answer has come (and was taken for its own request) or never will.
    fn fence(&mut self, answer: &Match) -> Result<(), ExchangeError> {
        self.timing.owed.expire(Instant::now());
        let Some(owed) = self.timing.owed.overlaps(answer) else {
            return Ok(());
        };
        let Some(fence) = self.session.fence_request(&owed.answer) else {
            return Ok(());
        };
        debug!(
            "fence: command {} before command {}, whose answer an owed one could be taken for",
            fence.command, answer.command
        );
        match self.exchange_with(&fence, false) {
            Ok(_) => self.timing.owed.clear(),
            Err(ExchangeError::Disconnected(r)) => return Err(ExchangeError::Disconnected(r)),
            Err(ExchangeError::Cancelled) => return Err(ExchangeError::Cancelled),
            // A device that answers nothing now: what is owed expires in time.
            Err(_) => {}
        }
        Ok(())
    }

    /// Why attempt `attempt.0` of `attempt.1` of a request sent at `sent` got no answer: a
    /// garbled frame, an answer to something else, or nothing at all (then said to the packet
    /// monitor as a row of its own, [`LinkEvent::NoAnswer`]).
    pub(super) fn unanswered(
        &mut self,
        command: u8,
        expected: u8,
        frame_err: Option<FrameError>,
        mismatch: Option<(u8, Option<u8>)>,
        (attempt, attempts): (u8, u8),
        sent: Instant,
    ) -> ExchangeError {
        if let Some(error) = frame_err {
            // Part of an answer taken by another reader reads as a damaged frame.
            match self.wire.taken_by() {
                Some((port, by)) => ExchangeError::Taken {
                    command: command.into(),
                    port,
                    by,
                },
                None => ExchangeError::Garbled {
                    command: command.into(),
                    error,
                },
            }
        } else if let Some((got, from)) = mismatch {
            ExchangeError::Mismatch {
                expected: expected.into(),
                got: got.into(),
                from,
            }
        } else if let Some((port, by)) = self.wire.taken_by() {
            self.wire.stats.timeouts += 1;
            ExchangeError::Taken {
                command: command.into(),
                port,
                by,
            }
        } else if let Err(e) = self.wire.check_now(Instant::now()) {
            // Nothing came because the port went (unplugged): a lost link, not a silent device.
            self.lost_in(e)
        } else {
            self.wire.stats.timeouts += 1;
            if let Some(ev) = self.liveness.unanswered() {
                self.events.emit(LinkEvent::Device(ev));
            }
            let waited = sent.elapsed();
            self.events.emit(LinkEvent::NoAnswer(NoAnswer {
                at: SystemTime::now(),
                command,
                attempt,
                attempts,
                waited,
                host_late: crate::link::request::held_up_by(self.late_seen),
            }));
            ExchangeError::Timeout {
                command: command.into(),
                attempts,
                waited_ms: waited.as_millis() as u64,
                host_late: None,
            }
        }
    }

    /// If `p` is an answer owed to an earlier request (MSP, servo), takes it for that request:
    /// its lateness is learned (the automatic margin widens), it is counted, and logged as a
    /// late answer; a servo's is passed on as a report. Never taken for another request.
    pub(super) fn late_answer(&mut self, p: &Packet) -> bool {
        if !self.session.in_order() {
            return false;
        }
        self.timing.owed.expire(Instant::now());
        let Some(sent) = self.timing.owed.take(p) else {
            return false;
        };
        let late = super::timing::Timing::latency_of(
            self.wire.arrived(),
            sent,
            p.wire.len(),
            self.wire.baud(),
        );
        self.timing.observe(late);
        self.wire.stats.late_answers += 1;
        debug!(
            "late answer: command {} {} ms after its request, taken for it",
            p.command,
            late.as_millis()
        );
        let note = format!(
            "late answer to an earlier request ({} ms after it)",
            late.as_millis()
        );
        self.events.tap_in(Ok(p.clone()), Some(note));
        if matches!(p.header, Header::Servo) {
            self.events.emit(LinkEvent::Report(p.clone()));
        }
        true
    }

    /// Keeps a servo's frame (never a request's echo), or a damaged one, read outside a sweep
    /// that answers no request of the exchange under way (a late answer to an earlier one
    /// included) for the next sweep: it may answer one of the last sweep's requests, or tell a
    /// scan that a servo it asked again is there after all.
    pub(super) fn keep_unclaimed(&mut self, frame: Result<&Packet, &FrameError>) {
        if self.session.protocol() != Protocol::Servo {
            return;
        }
        match frame {
            Ok(p) if p.direction == Direction::DeviceToHost => self.unclaimed.keep(Ok(p.clone())),
            Ok(_) => {}
            Err(e) => self.unclaimed.keep(Err(e.clone())),
        }
    }
}

/// How the answer to an attempt written at `t0` ends when it is a burst: when the line is quiet,
/// or when every data point has been reported, by the reports' wire time twice over after the
/// request and the margin at the latest, later while reports of data points not yet heard keep
/// coming within a margin of each other.
fn burst_end(
    reply: &ReplySpec,
    t0: Instant,
    request_bytes: usize,
    baud: u32,
    margin: Duration,
) -> Option<BurstEnd> {
    match reply {
        ReplySpec::Burst { quiet, .. } => Some(BurstEnd::Quiet(*quiet)),
        ReplySpec::Reports { ids, bytes, .. } => {
            let until = t0 + wire_time(request_bytes, baud) + wire_time(*bytes, baud) * 2 + margin;
            // A report of a data point not yet heard earns the next one the margin and a
            // report's wire time; all of them, at most.
            let gap = margin + wire_time(bytes / ids.len().max(1), baud);
            Some(BurstEnd::Reported {
                ids: ids.clone(),
                until,
                gap,
                hard: until + gap * ids.len() as u32,
            })
        }
        _ => None,
    }
}
