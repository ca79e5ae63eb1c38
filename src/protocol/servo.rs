//! The UART bus-servo protocol (seed 002).
//!
//! Request: `12 4C, cmd_id, n, content[n], checksum`; reply: `05 1C, cmd_id, n, content[n],
//! checksum`; the checksum is the sum of every byte before it, mod 256. The first content byte is
//! the servo id (0-254; 255 is broadcast). Multi-byte fields are little-endian.
//!
//! One decoder reads both directions (a half-duplex adapter echoes the host's own requests), and
//! each frame says which way it went.

use super::{Decoder, Direction, EncodeError, FrameError, Framing, Scan, sum8};
use serde::Serialize;

/// The header of a request.
pub const REQUEST_HEADER: [u8; 2] = [0x12, 0x4C];
/// The header of a reply.
pub const REPLY_HEADER: [u8; 2] = [0x05, 0x1C];
/// The largest content a frame can carry (the length field is one byte).
pub const MAX_CONTENT: usize = 255;
/// The broadcast servo id.
pub const BROADCAST_ID: u8 = 0xFF;

/// Command ids of seed 002 and the vendor SDK's extensions (PROTOCOL_NOTES §2).
pub mod cmd {
    /// Is the servo there?
    pub const PING: u8 = 1;
    /// Reset the user parameters to their defaults.
    pub const RESET_USER_DATA: u8 = 2;
    /// Read one parameter.
    pub const READ_DATA: u8 = 3;
    /// Write one user parameter.
    pub const WRITE_DATA: u8 = 4;
    /// Read the 32-byte user block.
    pub const READ_BATCH_DATA: u8 = 5;
    /// Write the 32-byte user block.
    pub const WRITE_BATCH_DATA: u8 = 6;
    /// Wheel mode.
    pub const SPIN: u8 = 7;
    /// Angle mode: go to an angle over an interval.
    pub const ROTATE: u8 = 8;
    /// Damping mode: hold with a power.
    pub const DAMPING: u8 = 9;
    /// Read the angle.
    pub const READ_ANGLE: u8 = 10;
    /// Read all live values at once (newer servos).
    pub const MONITOR: u8 = 22;
    /// Stop: release, hold or damp (newer servos).
    pub const STOP: u8 = 24;
}

/// A servo frame of either direction.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Frame {
    /// Request (host to servo) or reply.
    pub direction: Direction,
    /// The command id.
    pub command: u8,
    /// The content; its first byte is the servo id.
    pub content: Vec<u8>,
}

impl Frame {
    /// A request from the host.
    pub fn request(command: u8, content: Vec<u8>) -> Self {
        Self {
            direction: Direction::HostToDevice,
            command,
            content,
        }
    }

    /// A reply from a servo.
    pub fn reply(command: u8, content: Vec<u8>) -> Self {
        Self {
            direction: Direction::DeviceToHost,
            command,
            content,
        }
    }

    /// The servo id: the first content byte, where there is one.
    pub fn servo_id(&self) -> Option<u8> {
        self.content.first().copied()
    }

    /// The header for this frame's direction.
    pub fn header(&self) -> [u8; 2] {
        match self.direction {
            Direction::HostToDevice => REQUEST_HEADER,
            Direction::DeviceToHost => REPLY_HEADER,
        }
    }

    /// The frame's bytes.
    pub fn encode(&self) -> Result<Vec<u8>, EncodeError> {
        let n = u8::try_from(self.content.len()).map_err(|_| EncodeError::PayloadTooLong {
            len: self.content.len(),
            max: MAX_CONTENT,
        })?;
        let mut out = Vec::with_capacity(self.content.len() + 5);
        out.extend_from_slice(&self.header());
        out.push(self.command);
        out.push(n);
        out.extend_from_slice(&self.content);
        out.push(sum8(&out));
        Ok(out)
    }

    /// The frame's length on the wire.
    pub fn wire_len(&self) -> usize {
        self.content.len() + 5
    }
}

/// Servo framing: both headers.
#[derive(Debug, Clone, Copy, Default)]
pub struct ServoFraming;

impl Framing for ServoFraming {
    type Frame = Frame;

    fn is_start(&self, byte: u8) -> bool {
        byte == REQUEST_HEADER[0] || byte == REPLY_HEADER[0]
    }

    fn scan(&self, buf: &[u8]) -> Scan<Frame> {
        if buf.len() < 2 {
            return Scan::NeedMore { need: None };
        }
        let direction = match [buf[0], buf[1]] {
            REQUEST_HEADER => Direction::HostToDevice,
            REPLY_HEADER => Direction::DeviceToHost,
            _ => return Scan::NoHeader,
        };
        if buf.len() < 4 {
            return Scan::NeedMore { need: None };
        }
        let n = buf[3] as usize;
        let total = n + 5;
        if buf.len() < total {
            return Scan::NeedMore { need: Some(total) };
        }
        let expected = sum8(&buf[..total - 1]);
        let actual = buf[total - 1];
        if expected != actual {
            return Scan::Bad(FrameError::Checksum {
                expected,
                actual,
                bytes: buf[..total].to_vec(),
            });
        }
        Scan::Frame(
            Frame {
                direction,
                command: buf[2],
                content: buf[4..4 + n].to_vec(),
            },
            total,
        )
    }
}

/// A streaming decoder of servo frames, both directions.
pub type ServoDecoder = Decoder<ServoFraming>;

impl ServoDecoder {
    /// A new decoder.
    pub fn new() -> Self {
        Decoder::with_framing(ServoFraming)
    }
}

impl Default for ServoDecoder {
    fn default() -> Self {
        Self::new()
    }
}
