//! The UART bus-servo protocol (seed 002).
//!
//! Request: `12 4C, cmd_id, n, content[n], checksum`; reply: `05 1C, cmd_id, n, content[n],
//! checksum`; the checksum is the sum of every byte before it, mod 256. The first content byte is
//! the servo id (0-254; 255 is broadcast), except in the vendor SDK's bus-wide commands: 18 has
//! no content, 19's byte is a flag, and 25's first byte is a sub-command ([`Target`]).
//! Multi-byte fields are little-endian.
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
    /// Angle with acceleration and deceleration times.
    pub const ROTATE_BY_INTERVAL: u8 = 11;
    /// Angle by speed.
    pub const ROTATE_BY_VELOCITY: u8 = 12;
    /// Multi-turn angle.
    pub const ROTATE_MTURN: u8 = 13;
    /// Multi-turn angle over an interval, with acceleration and deceleration times.
    pub const ROTATE_MTURN_BY_INTERVAL: u8 = 14;
    /// Multi-turn angle by speed, with acceleration and deceleration times.
    pub const ROTATE_MTURN_BY_VELOCITY: u8 = 15;
    /// Read the multi-turn angle and turn count.
    pub const READ_ANGLE_MTURN: u8 = 16;
    /// Reset the turn count.
    pub const RESET_MTURN: u8 = 17;
    /// Every servo on the bus holds the motion commands that follow (no content).
    pub const BEGIN_ASYNC: u8 = 18;
    /// Run (0) or drop (1) the held motion commands (content: that flag).
    pub const END_ASYNC: u8 = 19;
    /// Read all live values at once (newer servos).
    pub const MONITOR: u8 = 22;
    /// Make the present position the origin.
    pub const SET_ORIGIN: u8 = 23;
    /// Stop: release, hold or damp (newer servos).
    pub const STOP: u8 = 24;
    /// One sub-command for several servos (content: sub-command, record length, count, records).
    pub const SYNC_COMMAND: u8 = 25;
}

/// Who a request is for.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Target {
    /// The servo with this id (the first content byte).
    Servo {
        /// Its id.
        id: u8,
    },
    /// Every servo, by the broadcast id 255; none answers.
    Broadcast,
    /// Every servo, by the command itself (18, 19; or a request without content): no servo
    /// id in the content; none answers.
    Bus,
    /// A synchronous command (25): the servos its records name, in order.
    Sync {
        /// The command each record is the request of.
        sub_command: u8,
        /// The records' servo ids, in order.
        ids: Vec<u8>,
    },
}

/// A synchronous command's content: `sub_command u8, record_len u8, count u8, records`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Sync<'a> {
    /// The command each record is the request of.
    pub sub_command: u8,
    /// Each record: that command's content for one servo, servo id first.
    pub records: Vec<&'a [u8]>,
}

/// Why a synchronous command's content cannot be read.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SyncError {
    /// Fewer than the three header bytes.
    #[error("a synchronous command needs 3 header bytes, got {0}")]
    Short(usize),
    /// The records do not fill the content exactly.
    #[error("{count} record(s) of {len} byte(s) need {need} bytes, the content has {have}")]
    Length {
        /// The record count.
        count: usize,
        /// The record length.
        len: usize,
        /// Bytes the records take.
        need: usize,
        /// Bytes after the header.
        have: usize,
    },
}

impl<'a> Sync<'a> {
    /// Reads a command 25 content.
    pub fn parse(content: &'a [u8]) -> Result<Self, SyncError> {
        let [sub_command, len, count, rest @ ..] = content else {
            return Err(SyncError::Short(content.len()));
        };
        let (len, count) = (*len as usize, *count as usize);
        if len * count != rest.len() || (len == 0 && count > 0) {
            return Err(SyncError::Length {
                count,
                len,
                need: len * count,
                have: rest.len(),
            });
        }
        Ok(Self {
            sub_command: *sub_command,
            records: if len == 0 {
                Vec::new()
            } else {
                rest.chunks(len).collect()
            },
        })
    }

    /// Builds a command 25 content from records of equal length.
    pub fn content(sub_command: u8, records: &[Vec<u8>]) -> Result<Vec<u8>, EncodeError> {
        let len = records.first().map_or(0, Vec::len);
        let too_long = EncodeError::PayloadTooLong {
            len: 3 + records.iter().map(Vec::len).sum::<usize>(),
            max: MAX_CONTENT,
        };
        if records.iter().any(|r| r.len() != len) {
            return Err(too_long);
        }
        let (Ok(l), Ok(n)) = (u8::try_from(len), u8::try_from(records.len())) else {
            return Err(too_long);
        };
        let mut out = vec![sub_command, l, n];
        for r in records {
            out.extend_from_slice(r);
        }
        Ok(out)
    }
}

/// A servo frame of either direction.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Frame {
    /// Request (host to servo) or reply.
    pub direction: Direction,
    /// The command id.
    pub command: u8,
    /// The content; its first byte is the servo id, except in commands 18, 19 and 25
    /// ([`Frame::target`]).
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

    /// The servo id: the first content byte, where the frame has one there (a reply, or a
    /// request for one servo or broadcast); `None` for commands 18, 19 and 25, whose first byte
    /// is something else.
    pub fn servo_id(&self) -> Option<u8> {
        if self.direction == Direction::HostToDevice
            && matches!(
                self.command,
                cmd::BEGIN_ASYNC | cmd::END_ASYNC | cmd::SYNC_COMMAND
            )
        {
            return None;
        }
        self.content.first().copied()
    }

    /// Who a request is for (a reply: the servo it came from).
    pub fn target(&self) -> Target {
        if self.direction == Direction::HostToDevice {
            match self.command {
                cmd::BEGIN_ASYNC | cmd::END_ASYNC => return Target::Bus,
                cmd::SYNC_COMMAND => {
                    let (sub_command, ids) = match Sync::parse(&self.content) {
                        Ok(s) => (
                            s.sub_command,
                            s.records
                                .iter()
                                .filter_map(|r| r.first().copied())
                                .collect(),
                        ),
                        Err(_) => (self.content.first().copied().unwrap_or(0), Vec::new()),
                    };
                    return Target::Sync { sub_command, ids };
                }
                _ => {}
            }
        }
        match self.content.first() {
            Some(&BROADCAST_ID) if self.direction == Direction::HostToDevice => Target::Broadcast,
            Some(&id) => Target::Servo { id },
            None => Target::Bus,
        }
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
