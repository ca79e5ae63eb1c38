//! The packet log: every frame sent and received, bounded, for the packet monitor.

use crate::capture::Tap;
use crate::link::LogEntry;
use crate::profile::Profile;
use std::collections::VecDeque;
use std::sync::Arc;

/// How many frames the packet monitor keeps.
pub const LOG_CAPACITY: usize = 20_000;

/// The frames, oldest first.
#[derive(Default)]
pub struct PacketLog {
    /// The frames kept, oldest first (at most [`LOG_CAPACITY`]).
    pub entries: VecDeque<LogEntry>,
    /// The log is frozen: frames that come are counted, not kept.
    pub paused: bool,
    /// Frames not kept because the log was frozen.
    pub dropped: u64,
    /// Records the link's bytes while a capture is set (the monitor's Record button).
    pub tap: Tap,
    /// A capture file opened for viewing, shown instead of the live frames.
    pub offline: Option<OfflineCapture>,
}

/// A capture file's frames, decoded with its profile, for the monitor.
pub struct OfflineCapture {
    /// The file's name.
    pub name: String,
    /// The profile it was decoded with.
    pub profile: Arc<Profile>,
    /// Its frames in order.
    pub entries: VecDeque<LogEntry>,
    /// Why the file ended early, if it did.
    pub truncated: Option<String>,
}

impl PacketLog {
    /// Keeps a frame (dropping the oldest when full), or counts it while frozen.
    pub fn push(&mut self, entry: LogEntry) {
        if self.paused {
            self.dropped += 1;
            return;
        }
        if self.entries.len() >= LOG_CAPACITY {
            self.entries.pop_front();
        }
        self.entries.push_back(entry);
    }

    /// Forgets every frame and the count of those not kept.
    pub fn clear(&mut self) {
        self.entries.clear();
        self.dropped = 0;
    }
}
