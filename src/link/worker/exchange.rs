//! Exchanges: encode a request, write it, wait for its answer until its deadline, take only a
//! frame that matches, and say why nothing answered (a garbled frame, an answer to something
//! else, or silence). Frames that answer no request are passed on here too.

use super::Worker;
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
pub(super) fn default_margin(protocol: Protocol) -> Duration {
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
    /// The answer (one frame, or the frames of a burst).
    Answered(Vec<Packet>),
    /// Nothing that answers the request.
    Nothing,
}

impl Worker {
    /// How long the device may take to start answering `req`, beyond the wire time: the
    /// request's own margin, else the link's, else the protocol's default.
    pub(super) fn margin(&self, req: &Request) -> Duration {
        req.margin
            .or(self.opts.margin)
            .unwrap_or(default_margin(self.session.protocol()))
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
        self.log(Direction::HostToDevice, Ok(sent));
        Ok(())
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

    /// Takes every frame already decoded as one that answers no request.
    pub(super) fn drain_unsolicited(&mut self) {
        while let Some(item) = self.decoder.next_packet() {
            match item {
                Ok(p) => {
                    self.stats.received += 1;
                    self.log(Direction::DeviceToHost, Ok(p.clone()));
                    let unasked = self.session.unasked(&p);
                    let _ = self.take_unasked(p, unasked);
                }
                Err(e) => {
                    self.stats.frame_errors += 1;
                    self.log(Direction::DeviceToHost, Err(e));
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
    /// answer; a frame that answers something else is never taken for it.
    pub(super) fn exchange(&mut self, req: &Request) -> Result<Reply, ExchangeError> {
        let (bytes, sent) = self.session.encode(req)?;
        let margin = self.margin(req);
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
    pub(super) fn wait_for(
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
        // How far the last read that found nothing looked.
        let mut looked_to: Option<Instant> = None;
        loop {
            while let Some(item) = self.decoder.next_packet() {
                match item {
                    Ok(p) => {
                        self.stats.received += 1;
                        self.log(Direction::DeviceToHost, Ok(p.clone()));
                        if each.accepts(&p) {
                            if self.session.answer_is_report(&p) {
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
                        self.log(Direction::DeviceToHost, Err(e.clone()));
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
                        let more = Instant::now() + wire_time(8, baud) + INTER_BYTE_SLACK;
                        deadline = deadline.max(more);
                    }
                    continue;
                }
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
            } else {
                looked_to = Some(slice);
            }
        }
    }
}
