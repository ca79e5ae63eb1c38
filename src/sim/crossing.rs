//! The host's bytes on their way through a pseudo-terminal, checked against what was written.
//!
//! In lockstep ([`super::lockstep`]) the simulated device hears the host's bytes from the
//! host's stamped writes, so that a loaded machine's late hand-over inside the pty never holds
//! the device up. The copy that crossed the pty is still read by the simulator's side, and
//! compared here with what the host wrote: a port left in a terminal's cooked mode (a newline
//! sent as CR LF, a 0x11 taken as XON, a byte's top bit cleared) changes the bytes on a real
//! wire too, and must fail the test that meets it rather than pass because the device heard the
//! intended bytes. Order is kept on both sides; either side may be ahead of the other.

use std::collections::VecDeque;

/// How many bytes either side may be ahead before the comparison gives up (a simulator that
/// stopped reading its side, or a host whose writes never crossed): the check then stops, it
/// never grows without bound.
const AHEAD_LIMIT: usize = 1 << 20;

/// The comparison of the bytes the host wrote with those the pty delivered.
#[derive(Debug, Default)]
pub(crate) struct Crossing {
    /// Written by the host, not yet seen at the simulator's side.
    written: VecDeque<u8>,
    /// Seen at the simulator's side before the host's write was recorded.
    seen: VecDeque<u8>,
    /// Bytes compared equal so far.
    matched: u64,
    /// The first difference, said once; the check stops there.
    changed: Option<String>,
    /// Too far apart to compare: the check stopped.
    gave_up: bool,
}

impl Crossing {
    /// The host wrote `bytes` (after its port took them).
    pub(crate) fn host_wrote(&mut self, bytes: &[u8]) {
        self.written.extend(bytes);
        self.compare();
    }

    /// The simulator's side of the pty delivered `bytes`.
    pub(crate) fn pty_delivered(&mut self, bytes: &[u8]) {
        self.seen.extend(bytes);
        self.compare();
    }

    /// The first difference between what the host wrote and what crossed, in words: the offset,
    /// the bytes written from there and the bytes delivered. `None` while they agree.
    pub(crate) fn changed(&self) -> Option<&str> {
        self.changed.as_deref()
    }

    fn compare(&mut self) {
        if self.changed.is_some() || self.gave_up {
            return;
        }
        while let (Some(&w), Some(&s)) = (self.written.front(), self.seen.front()) {
            if w != s {
                let take = |q: &VecDeque<u8>| q.iter().take(8).copied().collect::<Vec<u8>>();
                self.changed = Some(format!(
                    "the pty changed the host's bytes on their way to the device (is the port \
                     in raw mode?): at byte {} the host wrote {:02x?}, the device's side read \
                     {:02x?}",
                    self.matched,
                    take(&self.written),
                    take(&self.seen)
                ));
                return;
            }
            self.written.pop_front();
            self.seen.pop_front();
            self.matched += 1;
        }
        if self.written.len() > AHEAD_LIMIT || self.seen.len() > AHEAD_LIMIT {
            self.gave_up = true;
            self.written.clear();
            self.seen.clear();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Crossing;

    #[test]
    fn bytes_that_cross_unchanged_agree_whichever_side_comes_first() {
        let mut c = Crossing::default();
        c.host_wrote(&[0x24, 0x4d, 0x3c]);
        c.pty_delivered(&[0x24]);
        c.pty_delivered(&[0x4d, 0x3c, 0x00]);
        c.host_wrote(&[0x00, 0x0a]);
        c.pty_delivered(&[0x0a]);
        assert_eq!(c.changed(), None);
        assert_eq!(c.matched, 5);
    }

    #[test]
    fn a_newline_sent_as_cr_lf_is_a_difference_named_with_its_offset() {
        let mut c = Crossing::default();
        c.pty_delivered(&[0x55, 0xaa, 0x0d]);
        c.host_wrote(&[0x55, 0xaa, 0x0a, 0x01]);
        c.pty_delivered(&[0x0a, 0x01]);
        let said = c.changed().expect("a difference");
        assert!(said.contains("at byte 2"), "{said}");
        assert!(said.contains("[0a, 01]"), "{said}");
        assert!(said.contains("read [0d]"), "{said}");
    }

    #[test]
    fn a_side_far_ahead_stops_the_check_instead_of_growing() {
        let mut c = Crossing::default();
        c.host_wrote(&vec![0u8; super::AHEAD_LIMIT + 1]);
        assert!(c.gave_up);
        assert!(c.written.is_empty());
        c.pty_delivered(&[1]);
        assert_eq!(c.changed(), None);
    }
}
