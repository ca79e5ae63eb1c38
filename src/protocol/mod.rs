//! Pure protocol codecs: bytes in, frames out, and back. No I/O, no threads, no panics.
//!
//! Each protocol has an encoder on its frame types and a streaming [`Decoder`] that takes bytes
//! in any chunking and yields frames or typed [`FrameError`]s.

pub mod hex;
pub mod msp;
pub mod servo;
mod stream;
pub mod tuya;

pub use stream::{Decoder, Framing, JUNK_SAMPLE, Scan};

use serde::Serialize;

/// Which way a frame travels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Direction {
    /// From botbench (the host, or the Wi-Fi module for Tuya) to the device.
    HostToDevice,
    /// From the device to botbench.
    DeviceToHost,
}

impl Direction {
    /// A short arrow for logs: `>>` out, `<<` in.
    pub fn arrow(self) -> &'static str {
        match self {
            Direction::HostToDevice => ">>",
            Direction::DeviceToHost => "<<",
        }
    }
}

/// What a decoder reports instead of a frame.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FrameError {
    /// A complete frame whose checksum does not match its bytes.
    #[error("bad checksum: expected {expected:#04x}, got {actual:#04x}")]
    Checksum {
        /// The checksum computed over the frame's bytes.
        expected: u8,
        /// The checksum byte the frame carries.
        actual: u8,
        /// The whole bad frame.
        bytes: Vec<u8>,
    },
    /// A header whose length field exceeds the decoder's cap.
    #[error("frame length {len} is over the cap of {cap} bytes")]
    TooLong {
        /// The length the header announced.
        len: usize,
        /// The largest length this decoder accepts.
        cap: usize,
        /// The header bytes.
        bytes: Vec<u8>,
    },
    /// A recognised header with a field that no frame of this protocol carries.
    #[error("unknown {what} {value:#04x} in a frame header")]
    UnknownHeader {
        /// The header field (e.g. "version").
        what: &'static str,
        /// Its value.
        value: u8,
        /// The header bytes.
        bytes: Vec<u8>,
    },
    /// Bytes that belong to no frame.
    #[error("{len} junk byte(s) skipped")]
    Junk {
        /// How many bytes were skipped.
        len: usize,
        /// The first of them (at most [`JUNK_SAMPLE`]).
        sample: Vec<u8>,
    },
    /// The stream ended inside a frame.
    #[error("truncated frame: {have} byte(s) of {}", need.map_or("an unknown length".to_string(), |n| n.to_string()))]
    Truncated {
        /// Bytes present.
        have: usize,
        /// The whole frame's length, where the header got that far.
        need: Option<usize>,
        /// The bytes present.
        bytes: Vec<u8>,
    },
}

impl FrameError {
    /// How many stream bytes this error covers.
    pub fn span(&self) -> usize {
        match self {
            FrameError::Checksum { bytes, .. }
            | FrameError::TooLong { bytes, .. }
            | FrameError::UnknownHeader { bytes, .. }
            | FrameError::Truncated { bytes, .. } => bytes.len(),
            FrameError::Junk { len, .. } => *len,
        }
    }

    /// The raw bytes behind the error (for junk, a sample of them).
    pub fn bytes(&self) -> &[u8] {
        match self {
            FrameError::Checksum { bytes, .. }
            | FrameError::TooLong { bytes, .. }
            | FrameError::UnknownHeader { bytes, .. }
            | FrameError::Truncated { bytes, .. } => bytes,
            FrameError::Junk { sample, .. } => sample,
        }
    }

    /// A stable machine name for the error kind.
    pub fn kind(&self) -> &'static str {
        match self {
            FrameError::Checksum { .. } => "checksum",
            FrameError::TooLong { .. } => "too_long",
            FrameError::UnknownHeader { .. } => "unknown_header",
            FrameError::Junk { .. } => "junk",
            FrameError::Truncated { .. } => "truncated",
        }
    }
}

/// Why a frame could not be built.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum EncodeError {
    /// The payload does not fit the frame's length field.
    #[error("payload of {len} bytes is over the protocol's maximum of {max}")]
    PayloadTooLong {
        /// The payload's length.
        len: usize,
        /// The largest payload the frame can carry.
        max: usize,
    },
}

/// The sum of `bytes` modulo 256 (servo and Tuya checksums).
pub fn sum8(bytes: &[u8]) -> u8 {
    bytes.iter().fold(0u8, |acc, &b| acc.wrapping_add(b))
}

/// The XOR of `bytes` (MSP crc).
pub fn xor8(bytes: &[u8]) -> u8 {
    bytes.iter().fold(0u8, |acc, &b| acc ^ b)
}
