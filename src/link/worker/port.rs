//! The port: a baud change in order with the requests, a lost port (everything waiting is told),
//! reopening it with backoff, and the idle check that it is still there.

use super::Worker;
use crate::link::request::ExchangeError;
use crate::link::{LinkError, LinkEvent, LinkState};
use crossbeam_channel::{RecvTimeoutError, Sender};
use std::time::{Duration, Instant};

/// Reconnect backoff bounds: the first wait, doubled after each failed attempt up to the last.
const BACKOFF_MIN: Duration = Duration::from_millis(100);
const BACKOFF_MAX: Duration = Duration::from_secs(2);
/// How often an idle worker checks that the port is still there.
const PORT_CHECK: Duration = Duration::from_millis(500);

impl Worker {
    pub(super) fn switch_baud(&mut self, baud: u32, ack: Option<Sender<Result<(), LinkError>>>) {
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
            None => Err(LinkError::Disconnected("port lost".into())),
        };
        match &result {
            Ok(()) => {
                self.decoder.clear();
                // An answer owed to a request sent at the old rate can never come clean: were it
                // kept, the same answer at the new rate (a ping of the same id) would be taken
                // for the old request's.
                self.owed.clear();
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

    pub(super) fn lost(&mut self, reason: String) {
        self.transport = None;
        self.decoder.clear();
        self.fail_polls_in_flight(&reason);
        self.session.lost(&reason);
        self.emit(LinkEvent::State(LinkState::Lost {
            reason: reason.clone(),
        }));
        self.fail_queue(|| ExchangeError::Disconnected(reason.clone()));
        self.flush_wake();
    }

    pub(super) fn reconnect(&mut self) {
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
                    self.timing = super::timing::AnswerTiming::new(t.latency_timer());
                    self.owed.clear();
                    self.transport = Some(t);
                    self.decoder.clear();
                    self.emit_connected();
                    self.session.connected(Instant::now());
                    return;
                }
                Err(_) => backoff = (backoff * 2).min(BACKOFF_MAX),
            }
        }
    }

    /// While idle, every [`PORT_CHECK`]: is the port still there (a USB adapter unplugged)?
    pub(super) fn check_port(&mut self, now: Instant) {
        if now.duration_since(self.checked_at) >= PORT_CHECK {
            self.checked_at = now;
            if let Some(t) = self.transport.as_mut()
                && let Err(e) = t.check()
            {
                self.lost(e.to_string());
            }
        }
    }
}
