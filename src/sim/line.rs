//! The line between a simulated device and the host as the field has it (PROTOCOL_NOTES §4): a
//! USB adapter that hands received bytes to the host only when its latency timer expires, a
//! reply split across two bursts, a slow host that sees bytes late, a one-wire bus that echoes
//! every request, a half-duplex bus where a reply still on the wire collides with the next
//! request, and a port that vanishes in the middle of an operation.
//!
//! Bus time and host time are kept apart: a frame crosses the bus when the device sends it (and
//! collides there), and the host sees its bytes when the adapter and the host get to them.

use std::time::{Duration, Instant};

/// A reply cut in two: the host sees the first `after_bytes` bytes, the rest `gap` later (a
/// latency tick falling inside the frame).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Split {
    /// Bytes in the first burst.
    pub after_bytes: usize,
    /// How much later the rest is seen.
    pub gap: Duration,
}

/// How the line misbehaves. `Default` is a clean line: every byte is seen as it arrives.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Line {
    /// A USB adapter's latency timer (FTDI: 16 ms by default): bytes that reached the adapter
    /// are handed to the host only at ticks of this period.
    pub latency_timer: Option<Duration>,
    /// Every frame longer than the split point reaches the host in two bursts.
    pub split: Option<Split>,
    /// A slow host: each frame is seen up to this much later than it arrived (random, seeded by
    /// the faults' seed, never out of order).
    pub host_delay: Option<Duration>,
    /// A one-wire bus (TX and RX tied): the host reads back every byte it sends.
    pub echo: bool,
    /// A half-duplex bus: a reply still on the wire when the next request starts collides with
    /// it, and both arrive garbled (the servo bus is one). Modelled where the simulator knows
    /// when the host wrote (in process); a plain pty learns of the host's bytes only when the
    /// operating system hands them over, too late to tell.
    pub half_duplex: bool,
    /// The port vanishes (an adapter unplugged) once this many bytes have come from the host.
    pub vanish_after_bytes: Option<u64>,
}

impl Line {
    /// Checks the periods are above zero.
    pub fn check(&self) -> Result<(), String> {
        if self.latency_timer == Some(Duration::ZERO) {
            return Err("a latency timer of 0 ms: give 1 ms or more, or none".into());
        }
        if let Some(s) = self.split
            && s.after_bytes == 0
        {
            return Err("a split after 0 bytes: give 1 byte or more".into());
        }
        Ok(())
    }

    /// Whether the host sees bytes later than they arrive.
    pub(crate) fn delays(&self) -> bool {
        self.latency_timer.is_some() || self.split.is_some() || self.host_delay.is_some()
    }

    /// When the host sees the bytes of a frame that starts now: drawn once a frame (the host's
    /// delay), and never before the frame before it was seen (`not_before`).
    pub(crate) fn seen(
        &self,
        epoch: Instant,
        not_before: Instant,
        rng: &mut fastrand::Rng,
    ) -> Seen {
        let host_delay = self.host_delay.map_or(Duration::ZERO, |d| {
            Duration::from_nanos(rng.u64(0..=d.as_nanos() as u64))
        });
        Seen {
            split: self.split,
            tick: self.latency_timer.map(|p| (epoch, p)),
            host_delay,
            not_before,
        }
    }
}

/// When the bytes of one frame are seen by the host.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Seen {
    split: Option<Split>,
    /// The adapter's tick: its epoch and period.
    tick: Option<(Instant, Duration)>,
    host_delay: Duration,
    not_before: Instant,
}

impl Seen {
    /// Seen as it arrives (a clean line).
    pub(crate) fn at_once() -> Self {
        Self {
            split: None,
            tick: None,
            host_delay: Duration::ZERO,
            not_before: Instant::now() - Duration::from_secs(1),
        }
    }

    /// Not seen before `t` (a frame that went out on the wire before this one, seen later).
    pub(crate) fn raise_not_before(&mut self, t: Instant) {
        self.not_before = self.not_before.max(t);
    }

    /// When byte `i` of the frame, which reached the adapter at `arrived`, is seen by the host.
    pub(crate) fn at(&self, i: usize, arrived: Instant) -> Instant {
        let mut t = arrived;
        if let Some(s) = self.split
            && i >= s.after_bytes
        {
            t += s.gap;
        }
        if let Some((epoch, period)) = self.tick {
            t = next_tick(t, epoch, period);
        }
        (t + self.host_delay).max(self.not_before)
    }
}

/// The first tick at or after `t` of a clock ticking every `period` since `epoch`.
fn next_tick(t: Instant, epoch: Instant, period: Duration) -> Instant {
    let since = t.saturating_duration_since(epoch).as_nanos();
    let p = period.as_nanos().max(1);
    epoch + Duration::from_nanos((since.div_ceil(p) * p) as u64)
}

/// Two frames that overlap on a half-duplex bus: the bytes of `bytes` (on the bus from `start`,
/// one every `byte`) that overlap `[from, to)` are garbled. Returns whether any were.
pub(crate) fn garble_overlap(
    bytes: &mut [u8],
    start: Instant,
    byte: Duration,
    (from, to): (Instant, Instant),
    rng: &mut fastrand::Rng,
) -> bool {
    let byte_ns = byte.as_nanos().max(1);
    let end = start + byte * bytes.len() as u32;
    if to <= start || from >= end {
        return false;
    }
    let first = (from.saturating_duration_since(start).as_nanos() / byte_ns) as usize;
    let last = (to
        .saturating_duration_since(start)
        .as_nanos()
        .div_ceil(byte_ns) as usize)
        .min(bytes.len());
    let mut any = false;
    for b in &mut bytes[first.min(last)..last] {
        // Two drivers on one line, skewed by a few bits: the receiver's bytes are not either's.
        *b ^= rng.u8(1..);
        any = true;
    }
    any
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_are_seen_at_the_next_tick_and_a_split_frame_one_gap_later() {
        let epoch = Instant::now();
        let ms = Duration::from_millis;
        let line = Line {
            latency_timer: Some(ms(16)),
            ..Line::default()
        };
        let seen = line.seen(epoch, epoch, &mut fastrand::Rng::with_seed(1));
        assert_eq!(seen.at(0, epoch + ms(3)), epoch + ms(16));
        assert_eq!(seen.at(5, epoch + ms(16)), epoch + ms(16));
        assert_eq!(seen.at(5, epoch + ms(17)), epoch + ms(32));
        let split = Line {
            split: Some(Split {
                after_bytes: 4,
                gap: ms(16),
            }),
            ..Line::default()
        };
        let seen = split.seen(epoch, epoch, &mut fastrand::Rng::with_seed(1));
        assert_eq!(seen.at(3, epoch + ms(8)), epoch + ms(8));
        assert_eq!(seen.at(4, epoch + ms(8)), epoch + ms(24));
    }

    #[test]
    fn a_host_delay_keeps_the_order_and_stays_within_its_bound() {
        let epoch = Instant::now();
        let ms = Duration::from_millis;
        let line = Line {
            host_delay: Some(ms(10)),
            ..Line::default()
        };
        let mut rng = fastrand::Rng::with_seed(3);
        let mut before = epoch;
        for k in 0..50u64 {
            let arrived = epoch + ms(k);
            let seen = line.seen(epoch, before, &mut rng);
            let t = seen.at(0, arrived);
            assert!(t >= arrived && t >= before && t <= arrived.max(before) + ms(10));
            before = t;
        }
    }

    #[test]
    fn only_the_overlapping_bytes_are_garbled() {
        let start = Instant::now();
        let byte = Duration::from_micros(100);
        let mut bytes = vec![0x55; 10];
        let overlap = (
            start + Duration::from_micros(450),
            start + Duration::from_micros(700),
        );
        let mut rng = fastrand::Rng::with_seed(0);
        assert!(garble_overlap(&mut bytes, start, byte, overlap, &mut rng));
        assert_eq!(&bytes[..4], &[0x55; 4]);
        assert!(bytes[4..7].iter().all(|&b| b != 0x55));
        assert_eq!(&bytes[7..], &[0x55; 3]);
        let after = (
            start + Duration::from_millis(2),
            start + Duration::from_millis(3),
        );
        assert!(!garble_overlap(&mut bytes, start, byte, after, &mut rng));
    }
}
