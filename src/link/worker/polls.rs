//! Telemetry polling: the poll list in turn, each at its interval or as fast as the wire allows,
//! and for MSP two requests in flight at once (the next request crosses the line while the
//! device still sends the last answer).

use super::Worker;
use super::exchange::{Outcome, Waited};
use super::timing::Owed;
use crate::link::request::{ExchangeError, ReplySpec, Request};
use crate::link::{LinkEvent, wire_time};
use std::time::Instant;

/// A polled request whose answer has not come yet.
pub(super) struct InFlight {
    /// Its place in the poll list when it was sent.
    index: usize,
    request: Request,
    sent: Instant,
    /// When its answer is due at the latest, counted from its own write.
    deadline: Instant,
    /// The request's own wire time.
    on_wire: std::time::Duration,
}

impl Worker {
    pub(super) fn due_poll(&self) -> Option<usize> {
        let now = Instant::now();
        let n = self.polls.len();
        (0..n)
            .map(|k| (self.poll_cursor + k) % n)
            .find(|&i| self.polls[i].1 <= now)
    }

    /// Whether poll `i` is sent ahead of the answers still to come: MSP polls at the wire's
    /// maximum, while fewer than [`crate::link::LinkOptions::poll_pipeline`] are in flight. The
    /// request of the next poll then crosses the host-to-device line while the device is still
    /// sending the previous answer (full duplex), so that the device-to-host line never waits
    /// for the host.
    pub(super) fn pipelined(&self, i: usize) -> bool {
        self.session.pipelines_polls()
            && self.opts.poll_pipeline > 1
            && self.polls[i].0.interval.is_none()
            && matches!(self.polls[i].0.request.reply, ReplySpec::Required(_))
    }

    /// Sends poll `i` without waiting for its answer; waits for the oldest answer once the
    /// pipeline is full.
    pub(super) fn send_poll_ahead(&mut self, i: usize) {
        if self.in_flight.len() >= self.opts.poll_pipeline {
            self.await_oldest_poll();
            return;
        }
        let request = self.polls[i].0.request.clone();
        let owed = match &request.reply {
            ReplySpec::Required(m) => self.owed.overlaps(m).is_some(),
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
        self.poll_cursor = (i + 1) % self.polls.len().max(1);
        if self.in_flight.is_empty() {
            // As in an exchange: what has already arrived is dealt with before sending.
            if self.read_some(Instant::now()).is_err() {
                return;
            }
            self.drain_unsolicited();
        }
        let margin = self.margin(&request);
        let t0 = Instant::now();
        if self.write(&bytes, sent).is_err() {
            return;
        }
        self.in_flight.push_back(InFlight {
            index: i,
            deadline: t0 + wire_time(bytes.len() + 1, self.baud) + margin,
            on_wire: wire_time(bytes.len(), self.baud),
            request,
            sent: t0,
        });
    }

    /// Waits for every poll in flight.
    pub(super) fn settle_polls(&mut self) {
        while !self.in_flight.is_empty() && self.transport.is_some() {
            self.await_oldest_poll();
        }
    }

    /// Waits for the answer to the oldest poll in flight and reports it. The device answers in
    /// order, so the answer can come no sooner than the ones before it: its deadline runs at
    /// least one device margin from now.
    pub(super) fn await_oldest_poll(&mut self) {
        let Some(f) = self.in_flight.pop_front() else {
            return;
        };
        let ReplySpec::Required(each) = f.request.reply.clone() else {
            return;
        };
        let margin = self.margin(&f.request);
        let deadline = f.deadline.max(Instant::now() + margin);
        let baud = self.baud;
        let mut answered_other = false;
        let result = match self.wait_for(&each, None, deadline, baud) {
            Err(e) => Err(e),
            Ok(Waited {
                outcome: Outcome::Answered { packets, .. },
                ..
            }) => {
                let rtt = f.sent.elapsed();
                self.stats.rtt = Some(rtt);
                let answer = packets.first().map_or(0, |p| p.wire.len());
                self.timing
                    .observe(rtt.saturating_sub(f.on_wire + wire_time(answer, baud)));
                packets.into_iter().next().ok_or(ExchangeError::Timeout {
                    command: f.request.command,
                    attempts: 1,
                    waited_ms: 0,
                })
            }
            Ok(w) => {
                answered_other = w.mismatch.is_some();
                // Its answer may still come: owed, never taken for the next poll's.
                let expires = Instant::now() + self.timing.late_limit(margin);
                self.owed.push(Owed {
                    answer: each.clone(),
                    sent: f.sent + f.on_wire,
                    expires,
                });
                Err(self.unanswered(
                    f.request.command,
                    each.command,
                    w.frame_err,
                    w.mismatch,
                    1,
                    f.sent,
                ))
            }
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
        if answered_other {
            // The device answers in order: this poll's answer was lost, and what came instead
            // answered a later poll, whose answer is now gone too. The polls still in flight
            // are reported unanswered, so that the next answer awaited is the next one sent;
            // otherwise every later poll would wait out its deadline for an answer already
            // taken.
            for f in std::mem::take(&mut self.in_flight) {
                let waited_ms = f.sent.elapsed().as_millis() as u64;
                self.emit(LinkEvent::Telemetry {
                    command: f.request.command,
                    at: Instant::now(),
                    result: Err(ExchangeError::Timeout {
                        command: f.request.command,
                        attempts: 1,
                        waited_ms,
                    }),
                });
            }
        }
    }

    pub(super) fn run_poll(&mut self, i: usize) {
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

    /// The port went away: every poll in flight is reported as lost with it.
    pub(super) fn fail_polls_in_flight(&mut self, reason: &str) {
        for f in std::mem::take(&mut self.in_flight) {
            self.emit(LinkEvent::Telemetry {
                command: f.request.command,
                at: Instant::now(),
                result: Err(ExchangeError::Disconnected(reason.to_string())),
            });
        }
    }
}
