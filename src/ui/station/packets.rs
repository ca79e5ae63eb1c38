//! The packet log: every frame sent and received, and each request's attempt that went
//! unanswered, bounded, for the packet monitor. Each row kept has a sequence number that never changes (the first frame ever kept is 0), so that a
//! view can hold on to a frame while older ones are dropped under it, and keeps the profile it
//! came under: after a change of device the earlier frames still read as what they were (a
//! window cleaner's MSP frames are not decoded with a servo's commands), for a report.

use crate::capture::Tap;
use crate::link::{LogEntry, NoAnswer};
use crate::profile::Profile;
use std::collections::VecDeque;
use std::sync::Arc;

/// How many frames the packet monitor keeps.
pub const LOG_CAPACITY: usize = 20_000;

/// A row of the packet log: a frame, or an attempt no frame answered.
#[derive(Debug, Clone)]
pub enum LogRow {
    /// A frame sent or received (or the bytes of a damaged one).
    Frame(LogEntry),
    /// A request's attempt that went unanswered (the link's typed account of it).
    NoAnswer(NoAnswer),
}

impl LogRow {
    /// When: the frame crossed the line, or the attempt's window ended.
    pub fn at(&self) -> std::time::SystemTime {
        match self {
            LogRow::Frame(e) => e.at,
            LogRow::NoAnswer(n) => n.at,
        }
    }

    /// The frame, when the row is one.
    pub fn frame(&self) -> Option<&LogEntry> {
        match self {
            LogRow::Frame(e) => Some(e),
            LogRow::NoAnswer(_) => None,
        }
    }
}

/// A row kept, with the profile in use when it came (its commands name it).
#[derive(Debug, Clone)]
pub struct Logged {
    /// The frame, or the attempt unanswered.
    pub row: LogRow,
    /// The profile of the connection it came on.
    pub profile: Arc<Profile>,
}

impl Logged {
    /// The frame, when the row is one.
    pub fn frame(&self) -> Option<&LogEntry> {
        self.row.frame()
    }
}

/// The frames, oldest first.
pub struct PacketLog {
    /// The frames kept, oldest first (at most [`Self::capacity`]).
    pub entries: VecDeque<Logged>,
    /// The most frames kept ([`LOG_CAPACITY`] unless changed).
    pub capacity: usize,
    /// The log is frozen: frames that come are counted, not kept.
    pub paused: bool,
    /// Frames not kept because the log was frozen.
    pub dropped: u64,
    /// Frames ever kept: the next frame's sequence number.
    kept: u64,
    /// Records the link's bytes while a capture is set (the monitor's Record button).
    pub tap: Tap,
    /// A capture file opened for viewing, shown instead of the live frames.
    pub offline: Option<OfflineCapture>,
}

impl Default for PacketLog {
    fn default() -> Self {
        Self {
            entries: VecDeque::new(),
            capacity: LOG_CAPACITY,
            paused: false,
            dropped: 0,
            kept: 0,
            tap: Tap::default(),
            offline: None,
        }
    }
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
    /// Keeps a frame that came under `profile` (dropping the oldest when full), or counts it
    /// while frozen.
    pub fn push(&mut self, entry: LogEntry, profile: &Arc<Profile>) {
        self.push_row(LogRow::Frame(entry), profile);
    }

    /// Keeps an attempt that went unanswered under `profile`, as [`Self::push`] keeps a frame.
    pub fn push_no_answer(&mut self, no_answer: NoAnswer, profile: &Arc<Profile>) {
        self.push_row(LogRow::NoAnswer(no_answer), profile);
    }

    fn push_row(&mut self, row: LogRow, profile: &Arc<Profile>) {
        if self.paused {
            self.dropped += 1;
            return;
        }
        while self.entries.len() >= self.capacity.max(1) {
            self.entries.pop_front();
        }
        self.entries.push_back(Logged {
            row,
            profile: profile.clone(),
        });
        self.kept += 1;
    }

    /// The sequence number of the oldest frame kept (of the next frame when none is kept).
    pub fn first_seq(&self) -> u64 {
        self.kept - self.entries.len() as u64
    }

    /// The frames kept with their sequence numbers, oldest first.
    pub fn numbered(&self) -> impl DoubleEndedIterator<Item = (u64, &Logged)> + '_ {
        let first = self.first_seq();
        self.entries
            .iter()
            .enumerate()
            .map(move |(i, e)| (first + i as u64, e))
    }

    /// Forgets every frame and the count of those not kept (sequence numbers go on).
    pub fn clear(&mut self) {
        self.entries.clear();
        self.dropped = 0;
    }
}
