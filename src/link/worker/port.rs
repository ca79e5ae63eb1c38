//! The port: a baud change in order with the requests, a lost port (everything waiting is told),
//! reopening it with backoff, and the idle check that it is still there.

use super::{BACKOFF_MAX, BACKOFF_MIN, Worker};
use crate::link::request::ExchangeError;
use crate::link::{LinkError, LinkEvent, LinkState};
use crossbeam_channel::{RecvTimeoutError, Sender};
use std::time::Instant;

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
        self.tuya.handshake_done = false;
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
}
