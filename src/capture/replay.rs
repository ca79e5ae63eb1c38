//! Replay: a capture served as a simulated device ([`ReplayDevice`], a [`crate::sim::Device`]),
//! on a pseudo-terminal (`botbench sim replay FILE`, [`crate::sim::PtyServer`]) or in process
//! ([`crate::sim::SimTransport`]).
//!
//! The capture is cut into exchanges: each chunk botbench wrote is a request, and the chunks the
//! device sent until botbench's next write are its answer. When the host writes a request that
//! the capture holds, the device answers what it answered to that request the n-th time it was
//! sent (then the last answer again once the capture's run out; requests written after the
//! device's last bytes were cut by the end of the recording and are not taken for a device's
//! silence), chunk by chunk, each chunk
//! leaving so that its last byte arrives as long after the request as it did in the capture
//! (wire time at the capture's baud subtracted: the simulator's wire adds it back).
//! What the device sent before botbench's first write is sent once, when serving starts.
//! A request the capture does not hold gets no answer (a silent device), and is counted.
//!
//! Limits: an answer is tied to the last write before it, so a capture taken with requests
//! pipelined (`--poll-pipeline 2`) replays each answer after the request that followed it.

use super::CaptureError;
use super::format::{CaptureFile, Chunk};
use crate::link::wire_time;
use crate::protocol::Direction;
use crate::sim::{Device, Outgoing};
use std::collections::HashMap;
use std::time::{Duration, Instant};

/// One chunk of an answer.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AnswerChunk {
    /// How long after the request was written the chunk had fully arrived, in the capture.
    pub after_request: Duration,
    /// The bytes.
    pub bytes: Vec<u8>,
}

/// What the replay has done, for tests and the operator.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ReplayStats {
    /// Requests answered from the capture.
    pub answered: u64,
    /// Requests answered with an answer already used (the capture's run out).
    pub repeated: u64,
    /// Bytes from the host that match no recorded request.
    pub unknown_bytes: u64,
}

#[derive(Debug, Clone, Default)]
struct Answers {
    /// The answers in capture order.
    list: Vec<Vec<AnswerChunk>>,
    /// The next one to use.
    next: usize,
}

/// A device that answers as a capture says. Build it with [`ReplayDevice::new`].
#[derive(Debug, Clone)]
pub struct ReplayDevice {
    baud: u32,
    by_request: HashMap<Vec<u8>, Answers>,
    /// The longest recorded request, in bytes (how much the host may write before a match).
    longest: usize,
    /// Sent once on the first tick.
    prelude: Vec<AnswerChunk>,
    prelude_sent: bool,
    pending: Vec<u8>,
    stats: ReplayStats,
}

impl ReplayDevice {
    /// The device recorded in `capture`. Errors: the capture holds no chunk at all.
    pub fn new(capture: &CaptureFile) -> Result<Self, CaptureError> {
        if capture.chunks.is_empty() {
            return Err(CaptureError::Format(
                "the capture holds no bytes: nothing to replay".into(),
            ));
        }
        let mut exchanges: Vec<(Vec<u8>, Vec<AnswerChunk>)> = Vec::new();
        let mut prelude = Vec::new();
        let first_at = capture.chunks.first().map_or(0, |c| c.at_us);
        // (the request's bytes, when it was written, its answer so far)
        let mut open: Option<(Vec<u8>, u64, Vec<AnswerChunk>)> = None;
        let mut close = |open: Option<(Vec<u8>, u64, Vec<AnswerChunk>)>| {
            if let Some((req, _, answer)) = open {
                exchanges.push((req, answer));
            }
        };
        for Chunk {
            at_us,
            direction,
            bytes,
            ..
        } in &capture.chunks
        {
            match direction {
                Direction::HostToDevice => {
                    close(open.take());
                    open = Some((bytes.clone(), *at_us, Vec::new()));
                }
                Direction::DeviceToHost => {
                    let (since, list) = match &mut open {
                        Some((_, t, answer)) => (*t, answer),
                        None => (first_at, &mut prelude),
                    };
                    list.push(AnswerChunk {
                        after_request: Duration::from_micros(at_us.saturating_sub(since)),
                        bytes: bytes.clone(),
                    });
                }
            }
        }
        close(open.take());
        // The requests after the device's last bytes were cut by the end of the recording (it
        // stopped before their answers could come): no answer of the device's, not silence.
        while exchanges
            .last()
            .is_some_and(|(_, answer)| answer.is_empty())
        {
            exchanges.pop();
        }
        let mut by_request: HashMap<Vec<u8>, Answers> = HashMap::new();
        for (req, answer) in exchanges {
            by_request.entry(req).or_default().list.push(answer);
        }
        let longest = by_request.keys().map(Vec::len).max().unwrap_or(0);
        Ok(Self {
            baud: capture.info.baud.max(1),
            by_request,
            longest,
            prelude,
            prelude_sent: false,
            pending: Vec::new(),
            stats: ReplayStats::default(),
        })
    }

    /// What the replay has done so far.
    pub fn stats(&self) -> ReplayStats {
        self.stats.clone()
    }

    /// How many distinct requests the capture holds.
    pub fn requests(&self) -> usize {
        self.by_request.len()
    }

    /// The chunks of `answer` as the wire model wants them: each leaves the device so that it
    /// has fully arrived `after_request` after a request of `request_len` bytes was written.
    fn outgoing(&self, request_len: usize, answer: &[AnswerChunk]) -> Vec<Outgoing> {
        let request_wire = wire_time(request_len, self.baud);
        answer
            .iter()
            .map(|c| {
                let after = c
                    .after_request
                    .saturating_sub(request_wire)
                    .saturating_sub(wire_time(c.bytes.len(), self.baud));
                Outgoing::new(after, c.bytes.clone())
            })
            .collect()
    }

    /// The recorded request that `pending` starts with (the longest), if any.
    fn matching_request(&self) -> Option<Vec<u8>> {
        self.by_request
            .keys()
            .filter(|k| self.pending.starts_with(k))
            .max_by_key(|k| k.len())
            .cloned()
    }

    /// Whether `pending` may still grow into a recorded request.
    fn may_complete(&self) -> bool {
        self.pending.len() < self.longest
            && self.by_request.keys().any(|k| k.starts_with(&self.pending))
    }
}

impl Device for ReplayDevice {
    fn receive(&mut self, bytes: &[u8], _baud: u32, _now: Instant) -> Vec<Outgoing> {
        self.pending.extend_from_slice(bytes);
        let mut out = Vec::new();
        while !self.pending.is_empty() {
            if let Some(req) = self.matching_request() {
                self.pending.drain(..req.len());
                let Some(answers) = self.by_request.get_mut(&req) else {
                    continue;
                };
                let index = answers.next.min(answers.list.len().saturating_sub(1));
                if answers.next >= answers.list.len() {
                    self.stats.repeated += 1;
                } else {
                    answers.next += 1;
                }
                self.stats.answered += 1;
                let answer = answers.list.get(index).cloned().unwrap_or_default();
                out.extend(self.outgoing(req.len(), &answer));
            } else if self.may_complete() {
                break;
            } else {
                self.pending.remove(0);
                self.stats.unknown_bytes += 1;
            }
        }
        out
    }

    fn tick(&mut self, _now: Instant) -> Vec<Outgoing> {
        if std::mem::replace(&mut self.prelude_sent, true) {
            return Vec::new();
        }
        self.prelude
            .iter()
            .map(|c| Outgoing::new(c.after_request, c.bytes.clone()))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::capture::format::CaptureInfo;

    fn chunk(at_us: u64, direction: Direction, bytes: &[u8]) -> Chunk {
        Chunk {
            at_us,
            direction,
            bytes: bytes.to_vec(),
            baud: 115_200,
            dropped_before: 0,
        }
    }

    fn capture(chunks: Vec<Chunk>) -> CaptureFile {
        CaptureFile {
            info: CaptureInfo::new("test", 115_200, "window-cleaner", None),
            chunks,
            truncated: None,
        }
    }

    #[test]
    fn answers_in_order_then_repeats_the_last_and_ignores_unknown_requests() {
        use Direction::*;
        let cap = capture(vec![
            chunk(0, DeviceToHost, b"hello"),
            chunk(1_000, HostToDevice, b"AB"),
            chunk(3_000, DeviceToHost, b"1"),
            chunk(19_000, DeviceToHost, b"23"),
            chunk(30_000, HostToDevice, b"AB"),
            chunk(31_000, DeviceToHost, b"x"),
            chunk(40_000, HostToDevice, b"CD"),
            // The recording stopped before these were answered (a window's Stop mid-poll).
            chunk(45_000, HostToDevice, b"AB"),
        ]);
        let mut d = ReplayDevice::new(&cap).expect("replay");
        let now = Instant::now();
        let prelude = d.tick(now);
        assert_eq!(prelude.len(), 1);
        assert_eq!(prelude[0].bytes, b"hello");
        assert!(d.tick(now).is_empty(), "the prelude is sent once");
        // Split across two writes, with junk before it.
        assert!(d.receive(b"zA", 115_200, now).is_empty());
        let first = d.receive(b"B", 115_200, now);
        let bytes: Vec<&[u8]> = first.iter().map(|o| o.bytes.as_slice()).collect();
        assert_eq!(bytes, [b"1".as_slice(), b"23".as_slice()]);
        // The chunks keep their 16 ms spacing.
        let w = |n| wire_time(n, 115_200);
        assert_eq!(first[0].after, Duration::from_millis(2) - w(2) - w(1));
        assert_eq!(first[1].after, Duration::from_millis(18) - w(2) - w(2));
        let second = d.receive(b"AB", 115_200, now);
        assert_eq!(second[0].bytes, b"x");
        // Not the cut request's silence: the last answer the device gave, again.
        let third = d.receive(b"AB", 115_200, now);
        assert_eq!(third.len(), 1, "{third:?}");
        assert_eq!(third[0].bytes, b"x", "the last answer is repeated");
        assert!(
            d.receive(b"CD", 115_200, now).is_empty(),
            "no answer recorded: the recording ended before it"
        );
        assert!(d.receive(b"EF", 115_200, now).is_empty());
        assert_eq!(
            d.stats(),
            ReplayStats {
                answered: 3,
                repeated: 1,
                unknown_bytes: 5,
            }
        );
    }

    #[test]
    fn an_empty_capture_is_refused() {
        assert!(ReplayDevice::new(&capture(Vec::new())).is_err());
    }
}
