//! What the worker reports: events into a bounded channel (one dropped, and counted, when nobody
//! reads them), the packet tap (every frame sent and received, for the packet monitor), and the
//! waker that tells the UI to look.

use crate::link::watch::Watchers;
use crate::link::{LinkEvent, LogEntry, Waker};
use crate::packet::Packet;
use crate::protocol::{Direction, FrameError};
use crossbeam_channel::{Sender, TrySendError};
use log::debug;
use std::time::SystemTime;

/// The worker's side of the event channel.
pub(super) struct Events {
    tx: Sender<LinkEvent>,
    waker: Option<Waker>,
    /// Events were sent since the UI was last woken.
    wake: bool,
    /// Events dropped because the channel was full.
    dropped: u64,
    /// Blocking callers' watches ([`crate::link::Client::watch`]).
    pub(super) watchers: Watchers,
    /// The link's protocol (only Tuya reports are watched).
    protocol: crate::profile::Protocol,
    /// The link's profile: a polled command's error names its command by it.
    profile: std::sync::Arc<crate::profile::Profile>,
}

impl Events {
    /// Events into `tx`; `waker` wakes whoever reads them.
    pub(super) fn new(
        tx: Sender<LinkEvent>,
        waker: Option<Waker>,
        profile: std::sync::Arc<crate::profile::Profile>,
    ) -> Self {
        Self {
            tx,
            waker,
            wake: false,
            dropped: 0,
            watchers: Watchers::default(),
            protocol: profile.protocol,
            profile,
        }
    }

    /// `ev` with the command of the error it carries (a poll's, a handshake step's) named by
    /// the link's profile ([`ExchangeError::named`]).
    fn named(&self, ev: LinkEvent) -> LinkEvent {
        use crate::link::session::tuya::{StepResult, TuyaEvent};
        match ev {
            LinkEvent::Telemetry {
                command,
                at,
                result: Err(e),
            } => LinkEvent::Telemetry {
                command,
                at,
                result: Err(e.named(&self.profile)),
            },
            LinkEvent::Tuya(TuyaEvent::Step {
                step,
                result: StepResult::Failed(e),
                at,
                took,
            }) => LinkEvent::Tuya(TuyaEvent::Step {
                step,
                result: StepResult::Failed(e.named(&self.profile)),
                at,
                took,
            }),
            ev => ev,
        }
    }

    /// Sends `ev`, or drops and counts it when the channel is full (nobody reads it). What the
    /// Tuya session says goes to the watches too.
    pub(super) fn emit(&mut self, ev: LinkEvent) {
        let ev = self.named(ev);
        if let LinkEvent::Tuya(t) = &ev {
            self.watchers.tuya(t);
        }
        match self.tx.try_send(ev) {
            Ok(()) => self.wake = true,
            Err(TrySendError::Full(ev)) => {
                self.dropped += 1;
                // The first of a run of drops, then every thousandth: a reader that stopped
                // would otherwise fill the log.
                if self.dropped % 1000 == 1 {
                    debug!(
                        "event dropped, the channel is full ({} so far): {}",
                        self.dropped,
                        kind(&ev)
                    );
                }
            }
            Err(TrySendError::Disconnected(_)) => {}
        }
    }

    /// The packet tap: a frame (or a frame error) that crossed the line in `direction`, with a
    /// note on what the link took it for when that is not plain.
    pub(super) fn tap(
        &mut self,
        direction: Direction,
        frame: Result<Packet, FrameError>,
        note: Option<String>,
    ) {
        self.emit(LinkEvent::Frame(LogEntry {
            at: SystemTime::now(),
            direction,
            frame,
            note,
        }));
    }

    /// The packet tap of a frame (or frame error) from the device; reports and refused frames
    /// go to the watches too.
    pub(super) fn tap_in(&mut self, frame: Result<Packet, FrameError>, note: Option<String>) {
        self.watchers.frame(self.protocol, &frame);
        self.tap(Direction::DeviceToHost, frame, note);
    }

    /// Wakes the reader if events were sent since the last wake.
    pub(super) fn flush_wake(&mut self) {
        if std::mem::take(&mut self.wake)
            && let Some(w) = &self.waker
        {
            w();
        }
    }

    /// Events dropped so far.
    pub(super) fn dropped(&self) -> u64 {
        self.dropped
    }
}

/// What kind of event `ev` is, for the log.
fn kind(ev: &LinkEvent) -> &'static str {
    match ev {
        LinkEvent::State(_) => "state",
        LinkEvent::Reply { .. } => "reply",
        LinkEvent::Telemetry { .. } => "telemetry",
        LinkEvent::Report(_) => "report",
        LinkEvent::Frame(_) => "frame",
        LinkEvent::NoAnswer(_) => "no answer",
        LinkEvent::Identified(_) => "identified",
        LinkEvent::Tuya(_) => "tuya",
        LinkEvent::Device(_) => "device",
        LinkEvent::Stats(_) => "stats",
    }
}
