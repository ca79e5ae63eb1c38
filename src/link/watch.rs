//! A watch on what the worker reads, for an operation that must not lose what comes between
//! its own exchanges: a slow Tuya MCU's reports that arrive after a status query's answer
//! ended and before the next query, a frame refused as too long, the session's word that the
//! MCU restarted after a firmware update. The window has the same from the event channel; a
//! blocking caller (the command line, a job) asks its [`crate::link::Client`] for a [`Watch`].

use super::TuyaEvent;
use crate::packet::Packet;
use crate::profile::Protocol;
use crate::protocol::tuya::cmd;
use crate::protocol::{Direction, FrameError};
use crossbeam_channel::{Receiver, Sender, TrySendError};
use std::time::Duration;

/// The most items a watch holds unread: far more than a status query's burst; past it the
/// oldest are kept and the newest dropped.
const CAPACITY: usize = 4096;

/// What a watch sees, in the order the worker read or said it.
#[derive(Debug, Clone, PartialEq)]
pub enum Watched {
    /// A Tuya data-point report (0x07, or 0x22 synchronous), whether it answered a request or
    /// came on its own.
    Report(Packet),
    /// A frame that was refused: too long, a bad checksum, cut short (junk between frames is
    /// not watched).
    Refused(FrameError),
    /// What the Tuya session said: a handshake step, an MCU restart, the product info.
    Tuya(TuyaEvent),
}

/// The receiving end of a watch; dropping it ends the watch (the worker forgets it at its next
/// item).
#[derive(Debug)]
pub struct Watch {
    rx: Receiver<Watched>,
}

impl Watch {
    /// Everything seen so far and not yet taken, without waiting.
    pub fn take(&self) -> Vec<Watched> {
        self.rx.try_iter().collect()
    }

    /// The next item, waiting at most `wait`; `None` when nothing came (or the link closed).
    pub fn next(&self, wait: Duration) -> Option<Watched> {
        self.rx.recv_timeout(wait).ok()
    }
}

/// A new watch: the worker's end and the caller's.
pub(crate) fn channel() -> (Sender<Watched>, Watch) {
    let (tx, rx) = crossbeam_channel::bounded(CAPACITY);
    (tx, Watch { rx })
}

/// The worker's watches.
#[derive(Debug, Default)]
pub(crate) struct Watchers {
    senders: Vec<Sender<Watched>>,
}

impl Watchers {
    /// Adds a watch.
    pub(crate) fn add(&mut self, tx: Sender<Watched>) {
        self.senders.push(tx);
    }

    /// Sends `item` to every watch; one whose receiver is gone is forgotten, one that is full
    /// misses it.
    fn send(&mut self, item: &Watched) {
        self.senders.retain(|tx| {
            !matches!(
                tx.try_send(item.clone()),
                Err(TrySendError::Disconnected(_))
            )
        });
    }

    /// A frame (or frame error) read from the device: reports and refused frames are watched.
    pub(crate) fn frame(&mut self, protocol: Protocol, frame: &Result<Packet, FrameError>) {
        if self.senders.is_empty() || protocol != Protocol::Tuya {
            return;
        }
        match frame {
            Ok(p)
                if p.direction == Direction::DeviceToHost
                    && (p.command == cmd::DP_REPORT || p.command == cmd::DP_REPORT_SYNC) =>
            {
                self.send(&Watched::Report(p.clone()));
            }
            Ok(_) => {}
            // Junk between frames (the rest of a refused frame, line noise) is no frame.
            Err(FrameError::Junk { .. }) => {}
            Err(e) => self.send(&Watched::Refused(e.clone())),
        }
    }

    /// What the Tuya session said.
    pub(crate) fn tuya(&mut self, ev: &TuyaEvent) {
        if !self.senders.is_empty() {
            self.send(&Watched::Tuya(ev.clone()));
        }
    }
}
