//! The port: a baud change in order with the requests, a lost port (everything waiting is told),
//! reopening it with backoff, and the idle check that it is still there.

use super::Worker;
use crate::link::request::ExchangeError;
use crate::link::{LinkError, LinkEvent, LinkState};
use crossbeam_channel::{RecvTimeoutError, Sender};
use log::debug;
use std::time::{Duration, Instant};

/// Reconnect backoff bounds: the first wait, doubled after each failed attempt up to the last.
const BACKOFF_MIN: Duration = Duration::from_millis(100);
const BACKOFF_MAX: Duration = Duration::from_secs(2);

impl Worker {
    /// Switches the port to `baud` once the bytes written have crossed the wire (a frame still
    /// crossing, a broadcast nobody answers, would be cut off by the new rate); `ack` is told
    /// how it went.
    pub(super) fn switch_baud(&mut self, baud: u32, ack: Option<Sender<Result<(), LinkError>>>) {
        let result = self.wire.set_baud(baud);
        match &result {
            Ok(()) => {
                // An answer owed to a request sent at the old rate can never come clean: were it
                // kept, the same answer at the new rate (a ping of the same id) would be taken
                // for the old request's.
                self.timing.owed.clear();
                self.emit_connected();
            }
            Err(e) => self.events.emit(LinkEvent::State(LinkState::Lost {
                reason: e.to_string(),
            })),
        }
        if let Some(tx) = ack {
            let _ = tx.send(result);
        }
    }

    /// The port went away (`reason`): closed, and everything waiting for it told.
    pub(super) fn lost(&mut self, reason: String) {
        debug!("port lost: {reason}");
        self.wire.lose(&reason);
        self.liveness.forget();
        self.fail_polls_in_flight(&reason);
        self.session.lost(&reason);
        self.events.emit(LinkEvent::State(LinkState::Lost {
            reason: reason.clone(),
        }));
        self.fail_queue(|| ExchangeError::Disconnected(reason.clone()));
        self.events.flush_wake();
    }

    /// Reopens the lost port, with backoff, answering commands meanwhile; returns once it is
    /// open again, or the link shuts down. Without [`crate::link::LinkOptions::reconnect`] it
    /// only waits (answering commands) until the link shuts down.
    pub(super) fn reconnect(&mut self) {
        let mut backoff = BACKOFF_MIN;
        let mut attempt = 0u32;
        while !self.shutdown {
            self.wait_answering_commands(backoff);
            if self.shutdown {
                return;
            }
            if !self.opts.reconnect {
                backoff = BACKOFF_MAX;
                continue;
            }
            attempt += 1;
            self.events
                .emit(LinkEvent::State(LinkState::Reconnecting { attempt }));
            self.events.flush_wake();
            match self.wire.reopen() {
                Ok(()) => {
                    debug!("reconnected after {attempt} attempt(s)");
                    self.timing.connected(self.wire.latency_timer());
                    self.liveness.forget();
                    self.emit_connected();
                    self.settle_after_open();
                    self.session.connected(Instant::now());
                    return;
                }
                Err(e) => {
                    debug!("reconnect attempt {attempt} failed: {e}");
                    backoff = (backoff * 2).min(BACKOFF_MAX);
                }
            }
        }
    }

    /// The port has just opened: sends nothing for the setup's boot wait (a board that reboots
    /// when the port opens hears nothing then), taking commands meanwhile (requests queue; a
    /// shutdown ends the wait at once), then drops what the booting board said (a boot banner,
    /// at another rate).
    pub(super) fn settle_after_open(&mut self) {
        let wait = self.opts.setup.boot_wait;
        if wait.is_zero() {
            return;
        }
        debug!("boot wait of {wait:?} after open");
        self.wait_answering_commands(wait);
        if !self.shutdown
            && let Err(e) = self.wire.clear_input()
        {
            self.lost(e.to_string());
        }
    }

    /// Waits `wait`, taking the commands that come meanwhile.
    fn wait_answering_commands(&mut self, wait: Duration) {
        let until = Instant::now() + wait;
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
            self.events.flush_wake();
        }
    }

    /// While idle: is the port still there (a USB adapter unplugged)?
    pub(super) fn check_port(&mut self, now: Instant) {
        if let Err(e) = self.wire.check(now) {
            self.lost(e.to_string());
        }
    }
}
