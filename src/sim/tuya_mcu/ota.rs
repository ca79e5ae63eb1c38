//! The MCU's side of a firmware update (OTA, PROTOCOL_NOTES §3): 0x0a announces the size and
//! is answered with the packet size accepted; each 0x0b packet `offset u32 BE + data` is acked
//! with an empty 0x0b; the last packet has `offset == size` and no data. A packet larger than
//! agreed, or out of order, aborts the update silently, as the MCU SDK does.

use super::OtaPacketAnswer;

/// Where an OTA update stands.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum OtaState {
    /// No update started.
    Idle,
    /// Receiving packets.
    Receiving {
        /// The image size announced.
        size: u32,
        /// Bytes received so far.
        received: u32,
        /// The packet size agreed.
        packet: usize,
    },
    /// The last packet came and the image is whole.
    Complete {
        /// Its size.
        size: u32,
        /// Its CRC-32 (IEEE).
        crc32: u32,
    },
    /// Given up, silently, as the SDK does.
    Aborted {
        /// Why.
        reason: String,
    },
}

/// CRC-32 (IEEE 802.3, as zlib), to check an OTA image.
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = 0xFFFF_FFFFu32;
    for &b in bytes {
        crc ^= b as u32;
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// An update in progress and the image received.
#[derive(Debug)]
pub(super) struct Ota {
    pub(super) state: OtaState,
    pub(super) image: Vec<u8>,
    /// The MCU stopped acking (the `stop_acking_at` fault).
    stalled: bool,
}

impl Default for Ota {
    fn default() -> Self {
        Self {
            state: OtaState::Idle,
            image: Vec::new(),
            stalled: false,
        }
    }
}

impl Ota {
    /// A restart loses an update in progress.
    pub(super) fn restart(&mut self) {
        if matches!(self.state, OtaState::Receiving { .. }) {
            self.state = OtaState::Idle;
            self.image.clear();
        }
        self.stalled = false;
    }

    /// 0x0a with the image size: the answer's data (the packet size option), or `None` for a
    /// frame that is not 4 bytes.
    pub(super) fn start(&mut self, data: &[u8], answer: OtaPacketAnswer) -> Option<Vec<u8>> {
        let &[a, b, c, d] = data else {
            return None;
        };
        self.state = OtaState::Receiving {
            size: u32::from_be_bytes([a, b, c, d]),
            received: 0,
            packet: answer.size(),
        };
        self.image.clear();
        self.stalled = false;
        Some(match answer {
            OtaPacketAnswer::Option(o) => vec![o],
            OtaPacketAnswer::Empty => Vec::new(),
        })
    }

    fn abort(&mut self, reason: String) {
        self.state = OtaState::Aborted { reason };
    }

    /// 0x0b: whether to ack it (an empty 0x0b). `stop_acking_at`: stop once a packet at or
    /// past that offset arrives.
    pub(super) fn packet(&mut self, data: &[u8], stop_acking_at: Option<u32>) -> bool {
        let Some((head, chunk)) = data.split_first_chunk::<4>() else {
            return false;
        };
        let offset = u32::from_be_bytes(*head);
        let OtaState::Receiving {
            size,
            received,
            packet,
        } = self.state
        else {
            return false;
        };
        if stop_acking_at.is_some_and(|n| offset >= n) {
            self.stalled = true;
        }
        if self.stalled {
            return false;
        }
        if chunk.len() > packet {
            self.abort(format!(
                "packet of {} bytes at offset {offset}, over the agreed {packet}",
                chunk.len()
            ));
            return false;
        }
        let len = chunk.len() as u32;
        if chunk.is_empty() && offset >= size {
            if received != size {
                self.abort(format!("image ended at {received} of {size} bytes"));
                return false;
            }
            self.state = OtaState::Complete {
                size,
                crc32: crc32(&self.image),
            };
        } else if offset == received && received.saturating_add(len) <= size {
            self.image.extend_from_slice(chunk);
            self.state = OtaState::Receiving {
                size,
                received: received + len,
                packet,
            };
        } else if offset.checked_add(len) == Some(received)
            && self.image.get(offset as usize..) == Some(chunk)
        {
            // The module resent the last packet (our ack was lost): ack it again.
        } else {
            self.abort(format!(
                "packet at offset {offset} of {len} bytes, expected offset {received} (size {size})"
            ));
            return false;
        }
        true
    }
}
