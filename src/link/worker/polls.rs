//! Telemetry polling: the poll list in turn, each at its interval or as fast as the wire allows,
//! and for MSP two requests in flight at once (the next request crosses the line while the
//! device still sends the last answer).

use super::Worker;
use super::wait::{Outcome, Waited};
use crate::link::request::{ExchangeError, Match, ReplySpec, Request};
use crate::link::{LinkEvent, Poll, wire_time};
use crate::packet::Packet;
use std::collections::VecDeque;
use std::time::{Duration, Instant};

/// A polled request whose answer has not come yet.
pub(super) struct InFlight {
    /// Its place in the poll list when it was sent.
    index: usize,
    request: Request,
    sent: Instant,
    /// When its answer is due at the latest, counted from its own write.
    deadline: Instant,
    /// The request's own wire time.
    on_wire: Duration,
}

/// The polls of one link: what is polled and when each is due, whose turn it is, and the polls
/// sent ahead of their answers.
#[derive(Default)]
pub(super) struct Polls {
    /// The polled commands and when each is due.
    list: Vec<(Poll, Instant)>,
    /// The poll to look at first (polls take turns).
    cursor: usize,
    /// Polls sent ahead of their answers (MSP polls at the wire's maximum), oldest first.
    in_flight: VecDeque<InFlight>,
}

impl Polls {
    /// Replaces the poll list; each is due now.
    pub(super) fn set(&mut self, polls: Vec<Poll>) {
        let now = Instant::now();
        self.list = polls.into_iter().map(|p| (p, now)).collect();
        self.cursor = 0;
    }

    /// The first poll due at `now`, in turn.
    pub(super) fn due(&self, now: Instant) -> Option<usize> {
        let n = self.list.len();
        (0..n)
            .map(|k| (self.cursor + k) % n)
            .find(|&i| self.list[i].1 <= now)
    }

    /// When the next poll is due.
    pub(super) fn next_due(&self) -> Option<Instant> {
        self.list.iter().map(|(_, d)| *d).min()
    }

    /// Whether polls are in flight.
    pub(super) fn in_flight(&self) -> bool {
        !self.in_flight.is_empty()
    }

    /// Poll `i` is sent now: the next poll's turn.
    fn sent(&mut self, i: usize) {
        self.cursor = (i + 1) % self.list.len().max(1);
    }

    /// Poll `i` (still `request`) was answered, or gave up, at `at`: it is due again at once,
    /// or after its interval from when it was last due.
    fn done(&mut self, i: usize, request: &Request, at: Instant) {
        if let Some((poll, due)) = self.list.get_mut(i)
            && poll.request == *request
        {
            *due = match poll.interval {
                Some(iv) => (*due + iv).max(at),
                None => at,
            };
        }
    }

    /// Whether poll `i` can go out ahead of the answers still to come: it is polled at the
    /// wire's maximum (no interval) and waits for a required answer.
    fn pipelinable(&self, i: usize) -> bool {
        let poll = &self.list[i].0;
        poll.interval.is_none() && matches!(poll.request.reply, ReplySpec::Required(_))
    }
}

impl Worker {
    /// Runs poll `i` when it is due: ahead of the answers still to come when it may
    /// ([`Self::pipelined`]), else after them, one exchange.
    pub(super) fn poll(&mut self, i: usize) {
        if self.pipelined(i) {
            self.send_poll_ahead(i);
        } else {
            self.settle_polls();
            self.run_poll(i);
        }
    }

    /// Whether poll `i` is sent ahead of the answers still to come: MSP polls at the wire's
    /// maximum, while fewer than [`crate::link::LinkOptions::poll_pipeline`] are in flight. The
    /// request of the next poll then crosses the host-to-device line while the device is still
    /// sending the previous answer (full duplex), so that the device-to-host line never waits
    /// for the host.
    fn pipelined(&self, i: usize) -> bool {
        self.session.pipelines_polls() && self.opts.poll_pipeline > 1 && self.polls.pipelinable(i)
    }

    /// Sends poll `i` without waiting for its answer; waits for the oldest answer once the
    /// pipeline is full.
    fn send_poll_ahead(&mut self, i: usize) {
        if self.polls.in_flight.len() >= self.opts.poll_pipeline {
            self.await_oldest_poll();
            return;
        }
        let request = self.polls.list[i].0.request.clone();
        let owed = match &request.reply {
            ReplySpec::Required(m) => self.timing.owed.overlaps(m).is_some(),
            _ => false,
        };
        let Ok((bytes, sent)) = self.session.encode(&request) else {
            // Not encodable: report it as the sequential path would.
            self.run_poll(i);
            return;
        };
        if owed {
            // An answer to an earlier poll is owed and could be taken for this one's: the
            // sequential path fences it off first.
            self.settle_polls();
            self.run_poll(i);
            return;
        }
        self.polls.sent(i);
        // As in an exchange: what has already arrived is dealt with before sending.
        if !self.polls.in_flight() && self.take_arrived().is_err() {
            return;
        }
        let margin = self.timing.margin(&request);
        let t0 = Instant::now();
        if self.write(&bytes, sent).is_err() {
            return;
        }
        let baud = self.wire.baud();
        self.polls.in_flight.push_back(InFlight {
            index: i,
            deadline: t0 + wire_time(bytes.len() + 1, baud) + margin,
            on_wire: wire_time(bytes.len(), baud),
            request,
            sent: t0,
        });
    }

    /// Waits for every poll in flight.
    pub(super) fn settle_polls(&mut self) {
        while self.polls.in_flight() && self.wire.is_open() {
            self.await_oldest_poll();
        }
    }

    /// Waits for the answer to the oldest poll in flight and reports it. The device answers in
    /// order, so the answer can come no sooner than the ones before it: its deadline runs at
    /// least one device margin from now.
    fn await_oldest_poll(&mut self) {
        let Some(f) = self.polls.in_flight.pop_front() else {
            return;
        };
        let ReplySpec::Required(each) = f.request.reply.clone() else {
            return;
        };
        let margin = self.timing.margin(&f.request);
        let deadline = f.deadline.max(Instant::now() + margin);
        let (waited, late) = self.watching_late(|w| w.wait_for(&each, None, deadline));
        let answered_other = matches!(
            &waited,
            Ok(Waited {
                outcome: Outcome::Nothing,
                mismatch: Some(_),
                ..
            })
        );
        let result = match waited {
            Err(e) => Err(e),
            Ok(w) => self
                .poll_answer(&f, &each, w, margin)
                .map_err(|e| e.late_host(late)),
        };
        let at = Instant::now();
        self.polls.done(f.index, &f.request, at);
        self.events.emit(LinkEvent::Telemetry {
            command: f.request.command,
            at,
            result,
        });
        if answered_other {
            self.drop_polls_in_flight();
        }
    }

    /// What the wait for the answer to poll `f` brought: the answer (its latency learned), or
    /// why none came (the answer is then owed: it may still come, never taken for the next
    /// poll's).
    fn poll_answer(
        &mut self,
        f: &InFlight,
        each: &Match,
        waited: Waited,
        margin: Duration,
    ) -> Result<Packet, ExchangeError> {
        match waited.outcome {
            Outcome::Answered { packets, .. } => {
                let rtt = self.wire.arrived().saturating_duration_since(f.sent);
                self.wire.stats.rtt = Some(rtt);
                let answer = packets.first().map_or(0, |p| p.wire.len());
                let baud = self.wire.baud();
                self.timing
                    .observe(rtt.saturating_sub(f.on_wire + wire_time(answer, baud)));
                packets.into_iter().next().ok_or(ExchangeError::Timeout {
                    command: f.request.command.into(),
                    attempts: 1,
                    waited_ms: 0,
                    host_late: None,
                })
            }
            Outcome::Nothing => {
                self.timing.owe(each, f.sent + f.on_wire, margin);
                Err(self.unanswered(
                    f.request.command,
                    each.command,
                    waited.frame_err,
                    waited.mismatch,
                    (1, 1),
                    f.sent,
                ))
            }
        }
    }

    /// A poll's answer was lost and what came instead answered a later poll (the device answers
    /// in order), whose answer is now gone too: the polls still in flight are reported
    /// unanswered, so that the next answer awaited is the next one sent; otherwise every later
    /// poll would wait out its deadline for an answer already taken.
    fn drop_polls_in_flight(&mut self) {
        for f in std::mem::take(&mut self.polls.in_flight) {
            let waited_ms = f.sent.elapsed().as_millis() as u64;
            self.events.emit(LinkEvent::Telemetry {
                command: f.request.command,
                at: Instant::now(),
                result: Err(ExchangeError::Timeout {
                    command: f.request.command.into(),
                    attempts: 1,
                    waited_ms,
                    host_late: None,
                }),
            });
        }
    }

    /// Runs poll `i` as one exchange and reports its answer.
    fn run_poll(&mut self, i: usize) {
        let poll = self.polls.list[i].0.clone();
        self.polls.sent(i);
        let result = self.exchange(&poll.request);
        let at = Instant::now();
        self.polls.done(i, &poll.request, at);
        let result = result.and_then(|r| {
            r.packets.into_iter().next().ok_or(ExchangeError::Timeout {
                command: poll.request.command.into(),
                attempts: 1,
                waited_ms: 0,
                host_late: None,
            })
        });
        self.events.emit(LinkEvent::Telemetry {
            command: poll.request.command,
            at,
            result,
        });
    }

    /// The port went away: every poll in flight is reported as lost with it.
    pub(super) fn fail_polls_in_flight(&mut self, reason: &str) {
        for f in std::mem::take(&mut self.polls.in_flight) {
            self.events.emit(LinkEvent::Telemetry {
                command: f.request.command,
                at: Instant::now(),
                result: Err(ExchangeError::Disconnected(reason.to_string())),
            });
        }
    }
}
