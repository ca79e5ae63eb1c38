//! Bytes on their way through a pseudo-terminal, checked against what was sent.
//!
//! In lockstep ([`super::lockstep`]) neither end waits on the pty: the simulated device hears
//! the host's bytes from the host's stamped writes, and the host reads the device's bytes from
//! what the simulator recorded as written, so that a loaded machine's late hand-over inside the
//! pty never holds either up. The copies that crossed the pty are still read, by a thread at
//! each side, and compared here with what was sent, one [`Crossing`] each way: a port left in a
//! terminal's cooked mode (a newline sent as CR LF, a 0x11 taken as XON, a byte's top bit
//! cleared) changes the bytes on a real wire too, and must fail the test that meets it rather
//! than pass because each end got the intended bytes. Order is kept on both sides; either side
//! may be ahead of the other.

use std::collections::VecDeque;

/// How many bytes either side may be ahead before the comparison gives up (a simulator that
/// stopped reading its side, or a host whose writes never crossed): the check then stops, it
/// never grows without bound.
const AHEAD_LIMIT: usize = 1 << 20;

/// Which way bytes cross the pty.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Way {
    /// The host's writes, read at the pty's master side.
    #[default]
    ToDevice,
    /// The simulator's writes, read at the pty's slave side (the host's port).
    ToHost,
}

/// The comparison of the bytes one end sent with those the pty delivered to the other.
#[derive(Debug, Default)]
pub(crate) struct Crossing {
    way: Way,
    /// Sent, not yet seen at the other side.
    written: VecDeque<u8>,
    /// Seen at the other side before the sending was recorded.
    seen: VecDeque<u8>,
    /// Bytes compared equal so far.
    matched: u64,
    /// The first difference, said once; the check stops there.
    changed: Option<String>,
    /// Too far apart to compare: the check stopped.
    gave_up: bool,
}

impl Crossing {
    /// The comparison of the bytes crossing `way`.
    pub(crate) fn new(way: Way) -> Self {
        Self {
            way,
            ..Self::default()
        }
    }

    /// The sending end wrote `bytes` to the pty (after the pty took them).
    pub(crate) fn sent(&mut self, bytes: &[u8]) {
        self.written.extend(bytes);
        self.compare();
    }

    /// The other side of the pty delivered `bytes`.
    pub(crate) fn delivered(&mut self, bytes: &[u8]) {
        self.seen.extend(bytes);
        self.compare();
    }

    /// Bytes were sent that the pty never took (no room): from here on the two sides cannot be
    /// compared, and the check stops.
    pub(crate) fn give_up(&mut self) {
        self.gave_up = true;
        self.written.clear();
        self.seen.clear();
    }

    /// The receiving side's port is not in raw mode (`flags`: the terminal settings that are
    /// on, e.g. `ICANON ICRNL`): bytes may be changed or held back (a cooked port hands bytes
    /// over a line at a time), which a comparison of what came through cannot always see.
    pub(crate) fn not_raw(&mut self, flags: &str) {
        if self.changed.is_none() {
            self.changed = Some(format!(
                "the {} port is not in raw mode ({flags} on): the pty changes or holds back \
                 the bytes on their way to the {}",
                self.receiver_port(),
                self.receiver()
            ));
        }
    }

    /// How many bytes have crossed unchanged.
    #[cfg(test)]
    pub(crate) fn matched(&self) -> u64 {
        self.matched
    }

    /// The first difference between what was sent and what crossed, in words: the offset,
    /// the bytes sent from there and the bytes delivered. `None` while they agree.
    pub(crate) fn changed(&self) -> Option<&str> {
        self.changed.as_deref()
    }

    fn sender(&self) -> &'static str {
        match self.way {
            Way::ToDevice => "host",
            Way::ToHost => "device",
        }
    }

    fn receiver(&self) -> &'static str {
        match self.way {
            Way::ToDevice => "device",
            Way::ToHost => "host",
        }
    }

    fn receiver_port(&self) -> &'static str {
        match self.way {
            Way::ToDevice => "simulator's",
            Way::ToHost => "host's",
        }
    }

    fn compare(&mut self) {
        if self.changed.is_some() || self.gave_up {
            return;
        }
        while let (Some(&w), Some(&s)) = (self.written.front(), self.seen.front()) {
            if w != s {
                let (sender, receiver) = (self.sender(), self.receiver());
                let take = |q: &VecDeque<u8>| q.iter().take(8).copied().collect::<Vec<u8>>();
                self.changed = Some(format!(
                    "the pty changed the {sender}'s bytes on their way to the {receiver} (is the \
                     port in raw mode?): at byte {} the {sender} wrote {:02x?}, the \
                     {receiver}'s side read {:02x?}",
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
            self.give_up();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Crossing;

    #[test]
    fn bytes_that_cross_unchanged_agree_whichever_side_comes_first() {
        let mut c = Crossing::default();
        c.sent(&[0x24, 0x4d, 0x3c]);
        c.delivered(&[0x24]);
        c.delivered(&[0x4d, 0x3c, 0x00]);
        c.sent(&[0x00, 0x0a]);
        c.delivered(&[0x0a]);
        assert_eq!(c.changed(), None);
        assert_eq!(c.matched, 5);
    }

    #[test]
    fn a_newline_sent_as_cr_lf_is_a_difference_named_with_its_offset() {
        let mut c = Crossing::default();
        c.delivered(&[0x55, 0xaa, 0x0d]);
        c.sent(&[0x55, 0xaa, 0x0a, 0x01]);
        c.delivered(&[0x0a, 0x01]);
        let said = c.changed().expect("a difference");
        assert!(said.contains("at byte 2"), "{said}");
        assert!(said.contains("[0a, 01]"), "{said}");
        assert!(said.contains("read [0d]"), "{said}");
    }

    #[test]
    fn a_cr_turned_into_a_newline_on_the_way_to_the_host_names_the_device_as_the_sender() {
        let mut c = Crossing::new(super::Way::ToHost);
        c.sent(&[0x55, 0xaa, 0x0d]);
        c.delivered(&[0x55, 0xaa, 0x0a]);
        let said = c.changed().expect("a difference");
        assert!(
            said.contains("the device's bytes on their way to the host"),
            "{said}"
        );
        assert!(said.contains("the device wrote [0d]"), "{said}");
    }

    #[test]
    fn a_port_out_of_raw_mode_is_said_once_with_its_flags() {
        let mut c = Crossing::new(super::Way::ToHost);
        c.not_raw("ICANON ICRNL");
        c.not_raw("ECHO");
        let said = c.changed().expect("said");
        assert!(
            said.contains("host's port is not in raw mode (ICANON ICRNL on)"),
            "{said}"
        );
    }

    #[test]
    fn a_side_far_ahead_stops_the_check_instead_of_growing() {
        let mut c = Crossing::default();
        c.sent(&vec![0u8; super::AHEAD_LIMIT + 1]);
        assert!(c.gave_up);
        assert!(c.written.is_empty());
        c.delivered(&[1]);
        assert_eq!(c.changed(), None);
    }
}
