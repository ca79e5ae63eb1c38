//! Exchanges: encode a request, write it, wait for its answer until its deadline, take only a
//! frame that matches, and say why nothing answered (a garbled frame, an answer to something
//! else, or silence). Frames that answer no request are passed on here too.

use super::Worker;
use super::timing::Owed;
use crate::link::request::{ExchangeError, Match, Reply, ReplySpec, Request};
use crate::link::session::Unasked;
use crate::link::{LinkEvent, wire_time};
use crate::packet::{Header, Packet};
use crate::profile::Protocol;
use crate::protocol::{Direction, FrameError};
use std::time::{Duration, Instant};

/// Extra time allowed between the bytes of one frame (scheduler jitter on a loaded machine).
const INTER_BYTE_SLACK: Duration = Duration::from_millis(5);

/// The default answer margin of a protocol: how long the device may think before its first byte
/// (the seeds' and the field's figures: MSP 20 ms, servo 1.5 ms, Tuya 300 ms).
pub fn default_margin(protocol: Protocol) -> Duration {
    match protocol {
        Protocol::Msp => Duration::from_millis(20),
        Protocol::Servo => Duration::from_micros(1500),
        Protocol::Tuya => Duration::from_millis(300),
    }
}

/// What a wait for an answer saw.
pub(super) struct Waited {
    pub(super) outcome: Outcome,
    /// The last frame error.
    pub(super) frame_err: Option<FrameError>,
    /// The last frame that answered something else: its command, and its servo id.
    pub(super) mismatch: Option<(u8, Option<u8>)>,
}

/// Whether an answer came.
pub(super) enum Outcome {
    /// The answer (one frame, or the frames of a burst), and when its first and last frames
    /// were read.
    Answered {
        packets: Vec<Packet>,
        first: Instant,
        last: Instant,
    },
    /// Nothing that answers the request.
    Nothing,
}

/// How a burst of answering frames ends.
pub(super) enum BurstEnd {
    /// When the line has been quiet this long.
    Quiet(Duration),
    /// When each of these Tuya data points has been reported, or at `until` at the latest.
    Reported { ids: Vec<u8>, until: Instant },
}

impl BurstEnd {
    /// Whether `got` completes the burst.
    fn complete(&self, got: &[Packet]) -> bool {
        match self {
            BurstEnd::Quiet(_) => false,
            BurstEnd::Reported { ids, .. } => {
                let reported = crate::link::session::tuya::reported_ids(got);
                ids.iter().all(|id| reported.contains(id))
            }
        }
    }
}

impl Worker {
    /// How long the device may take to start answering `req`, beyond the wire time: the
    /// request's own margin, else the link's, else the protocol's default.
    pub(super) fn margin(&self, req: &Request) -> Duration {
        req.margin.unwrap_or_else(|| self.auto_margin())
    }

    /// The link's margin: `--margin-ms`, else the automatic one (the protocol's default, the
    /// adapter's latency timer, the answer latency measured on this connection).
    pub(super) fn auto_margin(&self) -> Duration {
        self.opts
            .margin
            .unwrap_or_else(|| self.timing.margin(default_margin(self.session.protocol())))
    }

    /// Writes `bytes` (the frame `sent`, for the packet log); a failed write loses the port.
    pub(super) fn write(&mut self, bytes: &[u8], sent: Packet) -> Result<(), ExchangeError> {
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
        self.session.wrote(&sent);
        self.log(Direction::HostToDevice, Ok(sent), None);
        Ok(())
    }

    /// The next frame (or frame error) the decoder holds, as the session sorts it: a Tuya
    /// frame that repeats what the module sent is its own echo.
    pub(super) fn next_frame(&mut self) -> Option<Result<Packet, FrameError>> {
        let item = self.decoder.next_packet()?;
        Some(item.map(|p| self.session.received(p)))
    }

    /// Reads what arrives before `deadline` into the decoder.
    pub(super) fn read_some(&mut self, deadline: Instant) -> Result<usize, ExchangeError> {
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

    /// Takes every frame already decoded as one that answers no request (a servo's is kept for
    /// the next sweep: it may answer a request of the last one).
    pub(super) fn drain_unsolicited(&mut self) {
        while let Some(item) = self.next_frame() {
            match item {
                Ok(p) => {
                    self.stats.received += 1;
                    self.keep_unclaimed(Ok(&p));
                    if self.late_answer(&p) {
                        continue;
                    }
                    self.log_in(Ok(p.clone()), None);
                    let unasked = self.session.unasked(&p);
                    let _ = self.take_unasked(p, unasked);
                }
                Err(e) => {
                    self.stats.frame_errors += 1;
                    self.keep_unclaimed(Err(&e));
                    self.log_in(Err(e), None);
                }
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
            Unasked::Report | Unasked::LateReply => self.emit(LinkEvent::Report(p)),
            Unasked::McuRequest { reply, event } => {
                let bytes = reply
                    .encode()
                    .map_err(|e| ExchangeError::Encode(e.to_string()))?;
                self.write(&bytes, Packet::tuya(reply))?;
                self.emit(LinkEvent::Tuya(event));
            }
        }
        Ok(())
    }

    /// Sends `req` and waits for its answer, with bounded attempts. Returns at the first valid
    /// answer; a frame that answers something else is never taken for it, nor is an answer owed
    /// to an earlier request. After the last attempt, an in-order device (MSP, servo) is given
    /// the grace period to answer late; attempts left unanswered are owed.
    pub(super) fn exchange(&mut self, req: &Request) -> Result<Reply, ExchangeError> {
        self.exchange_with(req, true)
    }

    fn exchange_with(&mut self, req: &Request, fence: bool) -> Result<Reply, ExchangeError> {
        let (bytes, sent) = self.session.encode(req)?;
        let margin = self.margin(req);
        let attempts = req.attempts.max(1);
        // What has already arrived (a late answer to an earlier request) is dealt with before
        // this request is sent, so that it cannot be taken for this request's answer.
        self.read_some(Instant::now())?;
        self.drain_unsolicited();
        let each = match &req.reply {
            ReplySpec::None => None,
            ReplySpec::Required(m) | ReplySpec::Optional(m) => Some(m.clone()),
            ReplySpec::Burst { each, .. } | ReplySpec::Reports { each, .. } => Some(each.clone()),
        };
        let in_order = self.session.in_order() && matches!(req.reply, ReplySpec::Required(_));
        if fence
            && in_order
            && let Some(m) = &each
        {
            self.fence(m)?;
        }
        let mut last = ExchangeError::Timeout {
            command: req.command,
            attempts,
            waited_ms: 0,
        };
        let baud = self.baud;
        let on_wire = wire_time(bytes.len(), baud);
        let mut sends: Vec<Instant> = Vec::new();
        let (mut frame_err, mut mismatch) = (None, None);
        for attempt in 1..=attempts {
            if attempt > 1 {
                self.stats.retries += 1;
            }
            let t0 = Instant::now();
            self.write(&bytes, sent.clone())?;
            sends.push(t0);
            let Some(each) = &each else {
                return Ok(Reply {
                    packets: Vec::new(),
                    rtt: Duration::ZERO,
                    attempts: attempt,
                });
            };
            let burst = match &req.reply {
                ReplySpec::Burst { quiet, .. } => Some(BurstEnd::Quiet(*quiet)),
                // The reports' wire time twice over, after the request and the margin.
                ReplySpec::Reports {
                    ids,
                    bytes: expected,
                    ..
                } => Some(BurstEnd::Reported {
                    ids: ids.clone(),
                    until: t0
                        + wire_time(bytes.len(), baud)
                        + wire_time(*expected, baud) * 2
                        + margin,
                }),
                _ => None,
            };
            let first = t0 + wire_time(bytes.len() + 1, baud) + margin;
            let waited = self.wait_for(each, burst, first, baud)?;
            frame_err = waited.frame_err.or(frame_err);
            mismatch = waited.mismatch.or(mismatch);
            if let Outcome::Answered {
                packets,
                first,
                last,
            } = waited.outcome
            {
                return Ok(self.answered(packets, (first, last), &sends, on_wire, in_order, each));
            }
            if matches!(req.reply, ReplySpec::Optional(_)) && frame_err.is_none() {
                return Ok(Reply {
                    packets: Vec::new(),
                    rtt: t0.elapsed(),
                    attempts: attempt,
                });
            }
            last = self.unanswered(
                req.command,
                each.command,
                frame_err.clone(),
                mismatch,
                attempts,
                t0,
            );
        }
        let Some(each) = &each else {
            return Err(last);
        };
        if in_order {
            // An answer to any attempt answers this request, however late within the grace.
            let grace = Instant::now() + self.timing.grace(margin);
            let waited = self.wait_for(each, None, grace, baud)?;
            if let Outcome::Answered {
                packets,
                first,
                last,
            } = waited.outcome
            {
                self.stats.late_answers += 1;
                return Ok(self.answered(packets, (first, last), &sends, on_wire, in_order, each));
            }
            let expires = Instant::now() + self.timing.late_limit(margin);
            for t in sends {
                self.owed.push(Owed {
                    answer: each.clone(),
                    sent: t + on_wire,
                    expires,
                });
            }
        }
        Err(last)
    }

    /// An answer came after the attempts sent at `sends`: its latency is learned (counted from
    /// the first attempt: an in-order device answers the oldest first), and the later attempts'
    /// answers are owed.
    ///
    /// `read` is when the answer's first and last frames were read: the link's round trip is
    /// the first's, and a burst's reply lasts until its last frame (never until the end of the
    /// wait).
    fn answered(
        &mut self,
        packets: Vec<Packet>,
        read: (Instant, Instant),
        sends: &[Instant],
        on_wire: Duration,
        in_order: bool,
        each: &Match,
    ) -> Reply {
        let sent = sends.first().copied().unwrap_or(read.0);
        let rtt = read.0.saturating_duration_since(sent);
        self.stats.rtt = Some(rtt);
        if in_order {
            let answer_wire = packets
                .first()
                .map_or(Duration::ZERO, |p| wire_time(p.wire.len(), self.baud));
            self.timing
                .observe(rtt.saturating_sub(on_wire + answer_wire));
            let expires =
                Instant::now() + self.timing.late_limit(self.timing.margin(Duration::ZERO));
            for &t in sends.iter().skip(1) {
                self.owed.push(Owed {
                    answer: each.clone(),
                    sent: t + on_wire,
                    expires,
                });
            }
        }
        Reply {
            packets,
            rtt: read.1.saturating_duration_since(sent),
            attempts: sends.len() as u8,
        }
    }

    /// Before a request whose answer an owed answer could be taken for: asks the device
    /// something else and waits for that answer. The device answers in order, so by then the
    /// owed answer has come (and was taken for its own request) or never will.
    fn fence(&mut self, answer: &Match) -> Result<(), ExchangeError> {
        self.owed.expire(Instant::now());
        let Some(owed) = self.owed.overlaps(answer) else {
            return Ok(());
        };
        let Some(fence) = self.session.fence_request(&owed.answer) else {
            return Ok(());
        };
        match self.exchange_with(&fence, false) {
            Ok(_) => self.owed.clear(),
            Err(ExchangeError::Disconnected(r)) => return Err(ExchangeError::Disconnected(r)),
            Err(ExchangeError::Cancelled) => return Err(ExchangeError::Cancelled),
            // A device that answers nothing now: what is owed expires in time.
            Err(_) => {}
        }
        Ok(())
    }

    /// Why a request sent at `sent` got no answer: a garbled frame, an answer to something
    /// else, or nothing at all.
    pub(super) fn unanswered(
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
    /// Once a frame has started, its rest is awaited for the frame gap (an adapter's bursts);
    /// at the deadline, what has arrived meanwhile is still read.
    pub(super) fn wait_for(
        &mut self,
        each: &Match,
        burst: Option<BurstEnd>,
        first_deadline: Instant,
        baud: u32,
    ) -> Result<Waited, ExchangeError> {
        let mut deadline = first_deadline;
        // A burst of reports ends by this time whatever comes (a chatty MCU is never quiet).
        let cap = match &burst {
            Some(BurstEnd::Reported { until, .. }) => *until,
            _ => first_deadline + Duration::from_secs(86_400),
        };
        let mut got: Vec<Packet> = Vec::new();
        let mut first_at: Option<Instant> = None;
        let mut last_at = first_deadline;
        let mut frame_err = None;
        let mut mismatch = None;
        let mut flushed = false;
        let gap = self.timing.frame_gap();
        // How far the last read that found nothing looked.
        let mut looked_to: Option<Instant> = None;
        loop {
            while let Some(item) = self.next_frame() {
                match item {
                    Ok(p) => {
                        self.stats.received += 1;
                        if self.late_answer(&p) {
                            self.keep_unclaimed(Ok(&p));
                            continue;
                        }
                        if each.accepts(&p) {
                            if self.session.in_order() {
                                // Nothing owed before this answer will come now.
                                self.owed.clear();
                            }
                            self.log_in(Ok(p.clone()), None);
                            if self.session.answer_is_report(&p) {
                                self.emit(LinkEvent::Report(p.clone()));
                            }
                            let now = Instant::now();
                            first_at.get_or_insert(now);
                            last_at = now;
                            got.push(p);
                            deadline = match &burst {
                                Some(BurstEnd::Quiet(quiet)) => now + *quiet,
                                Some(end @ BurstEnd::Reported { .. }) if !end.complete(&got) => cap,
                                _ => {
                                    return Ok(Waited {
                                        outcome: Outcome::Answered {
                                            packets: got,
                                            first: first_at.unwrap_or(now),
                                            last: now,
                                        },
                                        frame_err: None,
                                        mismatch: None,
                                    });
                                }
                            };
                        } else {
                            self.keep_unclaimed(Ok(&p));
                            self.log_in(Ok(p.clone()), None);
                            let unasked = self.session.unasked(&p);
                            if unasked.answers_other() {
                                let from = matches!(p.header, Header::Servo)
                                    .then(|| p.payload.first().copied())
                                    .flatten();
                                mismatch = Some((p.command, from));
                            }
                            self.take_unasked(p, unasked)?;
                        }
                    }
                    Err(e) => {
                        self.stats.frame_errors += 1;
                        self.keep_unclaimed(Err(&e));
                        self.log_in(Err(e.clone()), None);
                        frame_err = Some(e);
                    }
                }
            }
            let now = Instant::now();
            if now >= deadline {
                // A thread held up past the deadline (a loaded machine) looks once more before it
                // gives up: what arrived by the deadline is the answer, however late it is read.
                if looked_to.is_none_or(|t| t < deadline) {
                    looked_to = Some(deadline);
                    if self.read_some(deadline)? > 0 {
                        flushed = false;
                        deadline = self
                            .rest_deadline(deadline, baud, gap)
                            .min(cap.max(first_deadline));
                    }
                    continue;
                }
                if self.decoder.buffered() > 0 && !flushed {
                    self.decoder.flush();
                    flushed = true;
                    continue;
                }
                let outcome = match first_at {
                    None => Outcome::Nothing,
                    Some(first) => Outcome::Answered {
                        packets: got,
                        first,
                        last: last_at,
                    },
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
                deadline = self
                    .rest_deadline(deadline, baud, gap)
                    .min(cap.max(first_deadline));
            } else {
                looked_to = Some(slice);
            }
        }
    }

    /// The deadline after bytes came: a frame under way gets its rest, however the adapter
    /// splits it (the frame gap); a line that keeps talking, a little more.
    fn rest_deadline(&self, deadline: Instant, baud: u32, gap: Duration) -> Instant {
        let rest = if self.decoder.buffered() > 0 {
            gap
        } else {
            INTER_BYTE_SLACK
        };
        deadline.max(Instant::now() + wire_time(8, baud) + rest)
    }

    /// If `p` is an answer owed to an earlier request (MSP, servo), takes it for that request:
    /// its lateness is learned (the automatic margin widens), it is counted, and logged as a
    /// late answer; a servo's is passed on as a report. Never taken for another request.
    pub(super) fn late_answer(&mut self, p: &Packet) -> bool {
        if !self.session.in_order() {
            return false;
        }
        let now = Instant::now();
        self.owed.expire(now);
        let Some(sent) = self.owed.take(p) else {
            return false;
        };
        let late = now
            .saturating_duration_since(sent)
            .saturating_sub(wire_time(p.wire.len(), self.baud));
        self.timing.observe(late);
        self.stats.late_answers += 1;
        let note = format!(
            "late answer to an earlier request ({} ms after it)",
            late.as_millis()
        );
        self.log_in(Ok(p.clone()), Some(note));
        if matches!(p.header, Header::Servo) {
            self.emit(LinkEvent::Report(p.clone()));
        }
        true
    }

    /// Keeps a servo's frame (never a request's echo), or a damaged one, read outside a sweep
    /// that answers no request of the exchange under way (a late answer to an earlier one
    /// included) for the next sweep: it may answer one of the last sweep's requests, or tell a
    /// scan that a servo it asked again is there after all.
    fn keep_unclaimed(&mut self, frame: Result<&Packet, &FrameError>) {
        if self.session.protocol() != Protocol::Servo {
            return;
        }
        match frame {
            Ok(p) if p.direction == Direction::DeviceToHost => self.unclaimed.keep(Ok(p.clone())),
            Ok(_) => {}
            Err(e) => self.unclaimed.keep(Err(e.clone())),
        }
    }

    /// Logs a frame (or frame error) from the device, with a note on what it was taken for.
    pub(super) fn log_in(&mut self, frame: Result<Packet, FrameError>, note: Option<String>) {
        self.log(Direction::DeviceToHost, frame, note);
    }
}
