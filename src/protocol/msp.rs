//! The framed "MSP" serial protocol of the window cleaner and the solar cleanbot (seed 000).
//!
//! Request: `FF, option, device, command, size, data[size], crc` with
//! `crc = device ^ command ^ size ^ data...`.
//! Reply: `FF, kind, command, size, data[size], crc` with `crc = command ^ size ^ data...`;
//! `kind` is 0xFF for a reply or ack and 0xFE for an unsolicited (async) message.
//! Multi-byte fields are little-endian (the field codec in `profile` handles them).

use super::{Decoder, EncodeError, FrameError, Framing, Scan, xor8};
use serde::Serialize;

/// The first byte of every frame.
pub const PREAMBLE: u8 = 0xFF;
/// Request option: act and answer (bit 0 set).
pub const OPTION_ANSWER: u8 = 0xFF;
/// Request option: act without answering.
pub const OPTION_SILENT: u8 = 0xFE;
/// The largest payload a frame can carry (the size field is one byte).
pub const MAX_DATA: usize = 255;
/// The device code of the core commands (`CMD_VERSION` is sent with it).
pub const DEVICE_CORE: u8 = 0x00;

/// Core command: ping.
pub const CMD_PING: u8 = 0x01;
/// Core command: version (hw, firmware, API, capability flags).
pub const CMD_VERSION: u8 = 0x02;
/// Core command: power state.
pub const CMD_GET_POWER_STATE: u8 = 0x03;
/// Core command: build date and time.
pub const CMD_BUILD_INFO: u8 = 0x05;

/// A reply's kind byte.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ReplyKind {
    /// 0xFF: the answer to a request (a "simple response" when it carries no data).
    Reply,
    /// 0xFE: a message the device sends on its own.
    Async,
}

impl ReplyKind {
    /// The byte on the wire.
    pub fn byte(self) -> u8 {
        match self {
            ReplyKind::Reply => 0xFF,
            ReplyKind::Async => 0xFE,
        }
    }

    /// The kind for a byte, if it is one.
    pub fn from_byte(byte: u8) -> Option<Self> {
        match byte {
            0xFF => Some(ReplyKind::Reply),
            0xFE => Some(ReplyKind::Async),
            _ => None,
        }
    }
}

/// A frame from the host to the device.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Request {
    /// 0xFF to get an answer, 0xFE to act silently.
    pub option: u8,
    /// The device code.
    pub device: u8,
    /// The command number.
    pub command: u8,
    /// The payload.
    pub data: Vec<u8>,
}

impl Request {
    /// A request that asks for an answer.
    pub fn new(device: u8, command: u8, data: Vec<u8>) -> Self {
        Self {
            option: OPTION_ANSWER,
            device,
            command,
            data,
        }
    }

    /// Whether the device is asked to answer.
    pub fn wants_answer(&self) -> bool {
        self.option & 1 == 1
    }

    /// The frame's bytes.
    pub fn encode(&self) -> Result<Vec<u8>, EncodeError> {
        let size = data_len(&self.data)?;
        let mut out = Vec::with_capacity(self.data.len() + 6);
        out.extend_from_slice(&[PREAMBLE, self.option, self.device, self.command, size]);
        out.extend_from_slice(&self.data);
        out.push(request_crc(self.device, self.command, &self.data));
        Ok(out)
    }

    /// The frame's length on the wire.
    pub fn wire_len(&self) -> usize {
        self.data.len() + 6
    }
}

/// A frame from the device to the host.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Reply {
    /// Reply or async message.
    pub kind: ReplyKind,
    /// The command number.
    pub command: u8,
    /// The payload (empty for a simple response).
    pub data: Vec<u8>,
}

impl Reply {
    /// A reply (kind 0xFF).
    pub fn new(command: u8, data: Vec<u8>) -> Self {
        Self {
            kind: ReplyKind::Reply,
            command,
            data,
        }
    }

    /// The frame's bytes.
    pub fn encode(&self) -> Result<Vec<u8>, EncodeError> {
        let size = data_len(&self.data)?;
        let mut out = Vec::with_capacity(self.data.len() + 5);
        out.extend_from_slice(&[PREAMBLE, self.kind.byte(), self.command, size]);
        out.extend_from_slice(&self.data);
        out.push(reply_crc(self.command, &self.data));
        Ok(out)
    }

    /// The frame's length on the wire.
    pub fn wire_len(&self) -> usize {
        self.data.len() + 5
    }
}

fn data_len(data: &[u8]) -> Result<u8, EncodeError> {
    u8::try_from(data.len()).map_err(|_| EncodeError::PayloadTooLong {
        len: data.len(),
        max: MAX_DATA,
    })
}

/// A request's crc: `device ^ command ^ size ^ data...`. The size is `data.len() as u8`.
pub fn request_crc(device: u8, command: u8, data: &[u8]) -> u8 {
    device ^ command ^ (data.len() as u8) ^ xor8(data)
}

/// A reply's crc: `command ^ size ^ data...`.
pub fn reply_crc(command: u8, data: &[u8]) -> u8 {
    command ^ (data.len() as u8) ^ xor8(data)
}

/// Framing of requests (what a device, or a simulator, reads).
#[derive(Debug, Clone, Copy, Default)]
pub struct RequestFraming;

/// Framing of replies (what the host reads).
#[derive(Debug, Clone, Copy, Default)]
pub struct ReplyFraming;

impl Framing for RequestFraming {
    type Frame = Request;

    fn is_start(&self, byte: u8) -> bool {
        byte == PREAMBLE
    }

    fn scan(&self, buf: &[u8]) -> Scan<Request> {
        if buf.len() < 2 {
            return Scan::NeedMore { need: None };
        }
        let option = buf[1];
        if option != OPTION_ANSWER && option != OPTION_SILENT {
            return Scan::NoHeader;
        }
        if buf.len() < 5 {
            return Scan::NeedMore { need: None };
        }
        let size = buf[4] as usize;
        let total = size + 6;
        if buf.len() < total {
            return Scan::NeedMore { need: Some(total) };
        }
        let data = &buf[5..5 + size];
        let expected = request_crc(buf[2], buf[3], data);
        let actual = buf[total - 1];
        if expected != actual {
            return Scan::Bad(FrameError::Checksum {
                expected,
                actual,
                bytes: buf[..total].to_vec(),
            });
        }
        Scan::Frame(
            Request {
                option,
                device: buf[2],
                command: buf[3],
                data: data.to_vec(),
            },
            total,
        )
    }
}

impl Framing for ReplyFraming {
    type Frame = Reply;

    fn is_start(&self, byte: u8) -> bool {
        byte == PREAMBLE
    }

    fn scan(&self, buf: &[u8]) -> Scan<Reply> {
        if buf.len() < 2 {
            return Scan::NeedMore { need: None };
        }
        let Some(kind) = ReplyKind::from_byte(buf[1]) else {
            return Scan::NoHeader;
        };
        if buf.len() < 4 {
            return Scan::NeedMore { need: None };
        }
        let size = buf[3] as usize;
        let total = size + 5;
        if buf.len() < total {
            return Scan::NeedMore { need: Some(total) };
        }
        let data = &buf[4..4 + size];
        let expected = reply_crc(buf[2], data);
        let actual = buf[total - 1];
        if expected != actual {
            return Scan::Bad(FrameError::Checksum {
                expected,
                actual,
                bytes: buf[..total].to_vec(),
            });
        }
        Scan::Frame(
            Reply {
                kind,
                command: buf[2],
                data: data.to_vec(),
            },
            total,
        )
    }
}

/// A streaming decoder of requests.
pub type RequestDecoder = Decoder<RequestFraming>;
/// A streaming decoder of replies.
pub type ReplyDecoder = Decoder<ReplyFraming>;

impl RequestDecoder {
    /// A new request decoder.
    pub fn new() -> Self {
        Decoder::with_framing(RequestFraming)
    }
}

impl Default for RequestDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl ReplyDecoder {
    /// A new reply decoder.
    pub fn new() -> Self {
        Decoder::with_framing(ReplyFraming)
    }
}

impl Default for ReplyDecoder {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn request_crc_covers_device_through_data() {
        // Seed 000, MSP_SET_PWMVALUE 220 to device 0x03 with pwmValue 85.
        let bytes = Request::new(3, 220, vec![85]).encode().unwrap();
        assert_eq!(
            bytes,
            vec![0xFF, 0xFF, 0x03, 220, 0x01, 85, 3 ^ 220 ^ 1 ^ 85]
        );
    }

    #[test]
    fn reply_crc_has_no_device_byte() {
        let bytes = Reply::new(130, vec![85]).encode().unwrap();
        assert_eq!(bytes, vec![0xFF, 0xFF, 130, 0x01, 85, 130 ^ 1 ^ 85]);
    }

    #[test]
    fn oversize_payload_is_an_error_not_a_panic() {
        let err = Request::new(3, 1, vec![0; 256]).encode().unwrap_err();
        assert_eq!(err, EncodeError::PayloadTooLong { len: 256, max: 255 });
    }
}
