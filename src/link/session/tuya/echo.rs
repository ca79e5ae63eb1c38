//! The module's own frames read back (a one-wire adapter echoes what it sends), told from the
//! MCU's by what was sent, never by the version byte: some MCUs send version 0x00 as the module
//! does (PROTOCOL_NOTES §4).

use crate::packet::Packet;
use crate::protocol::tuya::cmd;
use std::collections::VecDeque;

/// Frames sent whose echo may still come.
const KEPT: usize = 8;

/// Whether `got` answers a frame of command `sent`: the same command, or data-point reports
/// for a data-point command or a query.
fn answers(sent: u8, got: u8) -> bool {
    got == sent || (got == cmd::DP_REPORT && matches!(sent, cmd::DP_COMMAND | cmd::QUERY_STATUS))
}

/// What the module sent, to tell its echoes from the MCU's frames.
///
/// An echo arrives as the module's bytes cross the line, so it always comes before the MCU's
/// answer to that frame. A frame the same, byte for byte, as one sent and not yet echoed is
/// the echo; an answer that comes with no echo before it shows the line does not echo, and
/// from then on nothing is taken for an echo (an MCU with version 0x00 answers the working-mode
/// query with the very bytes of the query).
#[derive(Debug, Default)]
pub(crate) struct EchoFilter {
    /// Frames sent whose echo has not come, oldest first.
    sent: VecDeque<Vec<u8>>,
    /// Whether the line echoes: unknown until the first answer or echo.
    echoes: Option<bool>,
}

impl EchoFilter {
    /// A new connection: nothing is known of the line.
    pub(crate) fn connected(&mut self) {
        *self = Self::default();
    }

    /// Whether the line is known to echo the module's frames.
    #[cfg(test)]
    pub(crate) fn line_echoes(&self) -> Option<bool> {
        self.echoes
    }

    /// The module wrote `wire` (one frame).
    pub(crate) fn wrote(&mut self, wire: &[u8]) {
        if self.echoes == Some(false) {
            return;
        }
        if self.sent.len() >= KEPT {
            self.sent.pop_front();
        }
        self.sent.push_back(wire.to_vec());
    }

    /// Whether `p`, a frame read from the line, is the module's own frame echoed.
    pub(crate) fn is_echo(&mut self, p: &Packet) -> bool {
        if self.echoes == Some(false) {
            return false;
        }
        if let Some(i) = self.sent.iter().position(|s| *s == p.wire) {
            self.echoes = Some(true);
            // Frames sent before it have had their chance to echo.
            self.sent.drain(..=i);
            return true;
        }
        let answered = self
            .sent
            .front()
            .and_then(|s| s.get(3))
            .is_some_and(|sent| answers(*sent, p.command));
        if answered && self.echoes.is_none() {
            // The MCU's answer, and no echo of the frame before it: the line does not echo.
            self.echoes = Some(false);
            self.sent.clear();
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::tuya::Frame;

    fn sent(command: u8, data: &[u8]) -> Vec<u8> {
        Frame::from_module(command, data.to_vec()).encode().unwrap()
    }

    fn read(version: u8, command: u8, data: &[u8]) -> Packet {
        Packet::tuya_received(Frame {
            version,
            command,
            data: data.to_vec(),
        })
    }

    #[test]
    fn an_echoing_line_is_learnt_from_the_first_echo_and_each_frame_echoes_once() {
        let mut f = EchoFilter::default();
        f.wrote(&sent(cmd::HEARTBEAT, &[]));
        assert!(f.is_echo(&read(0, cmd::HEARTBEAT, &[])));
        assert_eq!(f.line_echoes(), Some(true));
        // The MCU (version 0x00) answers: not an echo.
        assert!(!f.is_echo(&read(0, cmd::HEARTBEAT, &[1])));
        // The working mode query and an answer of the same bytes: the first is the echo.
        f.wrote(&sent(cmd::WORK_MODE, &[]));
        assert!(f.is_echo(&read(0, cmd::WORK_MODE, &[])));
        assert!(!f.is_echo(&read(0, cmd::WORK_MODE, &[])));
    }

    #[test]
    fn a_line_that_does_not_echo_takes_every_frame_for_the_mcus() {
        let mut f = EchoFilter::default();
        f.wrote(&sent(cmd::HEARTBEAT, &[]));
        assert!(!f.is_echo(&read(0, cmd::HEARTBEAT, &[1])));
        assert_eq!(f.line_echoes(), Some(false));
        // An MCU of version 0x00 answers the working mode with the query's own bytes.
        f.wrote(&sent(cmd::WORK_MODE, &[]));
        assert!(!f.is_echo(&read(0, cmd::WORK_MODE, &[])));
        // The MCU asks to reset the Wi-Fi; the module's ack is the same bytes.
        assert!(!f.is_echo(&read(0, cmd::RESET_WIFI, &[])));
        f.wrote(&sent(cmd::RESET_WIFI, &[]));
        assert!(!f.is_echo(&read(0, cmd::RESET_WIFI, &[])));
    }
}
