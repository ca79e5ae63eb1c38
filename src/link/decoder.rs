//! The link's decoder of what the device sends: one of the three protocols' decoders, yielding
//! [`Packet`]s.

use crate::packet::Packet;
use crate::profile::Protocol;
use crate::protocol::{FrameError, msp, servo, tuya};

/// Decodes what the device sends.
#[derive(Debug, Clone)]
pub enum AnyDecoder {
    /// MSP replies (the host never reads requests).
    Msp(msp::ReplyDecoder),
    /// Servo frames (replies, and echoes of our own requests on a one-wire adapter).
    Servo(servo::ServoDecoder),
    /// Tuya frames, all taken as the MCU's whatever their version byte (the session tells the
    /// module's own echoed frames by what was sent).
    Tuya(tuya::TuyaDecoder),
}

impl AnyDecoder {
    /// The decoder for a protocol.
    pub fn new(protocol: Protocol) -> Self {
        match protocol {
            Protocol::Msp => AnyDecoder::Msp(msp::ReplyDecoder::new()),
            Protocol::Servo => AnyDecoder::Servo(servo::ServoDecoder::new()),
            Protocol::Tuya => AnyDecoder::Tuya(tuya::TuyaDecoder::new()),
        }
    }

    /// Appends received bytes.
    pub fn push(&mut self, bytes: &[u8]) {
        match self {
            AnyDecoder::Msp(d) => d.push(bytes),
            AnyDecoder::Servo(d) => d.push(bytes),
            AnyDecoder::Tuya(d) => d.push(bytes),
        }
    }

    /// The next frame or frame error.
    pub fn next_packet(&mut self) -> Option<Result<Packet, FrameError>> {
        match self {
            AnyDecoder::Msp(d) => d.next().map(|r| r.map(Packet::msp_reply)),
            AnyDecoder::Servo(d) => d.next().map(|r| r.map(Packet::servo)),
            AnyDecoder::Tuya(d) => d.next().map(|r| r.map(Packet::tuya_received)),
        }
    }

    /// The line went quiet: give up on a partial frame at the head.
    pub fn flush(&mut self) {
        match self {
            AnyDecoder::Msp(d) => d.flush(),
            AnyDecoder::Servo(d) => d.flush(),
            AnyDecoder::Tuya(d) => d.flush(),
        }
    }

    /// Bytes held, not yet a frame.
    pub fn buffered(&self) -> usize {
        match self {
            AnyDecoder::Msp(d) => d.buffered(),
            AnyDecoder::Servo(d) => d.buffered(),
            AnyDecoder::Tuya(d) => d.buffered(),
        }
    }

    /// Drops what is buffered (after a baud change or a reconnect).
    pub fn clear(&mut self) {
        match self {
            AnyDecoder::Msp(d) => d.clear(),
            AnyDecoder::Servo(d) => d.clear(),
            AnyDecoder::Tuya(d) => d.clear(),
        }
    }
}
