//! A frame of any of the three protocols as a person reads it: direction, command, its profile
//! name and decoded fields, or the frame error. The frame tool and the packet monitor share it.

use crate::profile::{Command, Decoded, FieldError, Profile, Protocol};
use crate::protocol::{self, Direction, FrameError, hex, msp, servo, tuya};
use serde::Serialize;

/// Protocol-specific header bytes of a frame.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(tag = "protocol", rename_all = "snake_case")]
pub enum Header {
    /// An MSP request.
    MspRequest {
        /// 0xFF answer, 0xFE silent.
        option: u8,
        /// The device code.
        device: u8,
    },
    /// An MSP reply.
    MspReply {
        /// Reply or async.
        kind: msp::ReplyKind,
    },
    /// A servo frame.
    Servo,
    /// A Tuya frame.
    Tuya {
        /// 0x00 module; 0x03 MCU by the document, 0x01 or 0x00 from some MCUs.
        version: u8,
    },
}

/// A valid frame of any protocol.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Packet {
    /// Which way it went.
    pub direction: Direction,
    /// The command number.
    pub command: u8,
    /// Header bytes beyond command and length.
    pub header: Header,
    /// The payload.
    #[serde(serialize_with = "ser_hex")]
    pub payload: Vec<u8>,
    /// The whole frame as on the wire.
    #[serde(serialize_with = "ser_hex")]
    pub wire: Vec<u8>,
}

fn ser_hex<S: serde::Serializer>(bytes: &[u8], s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(&hex::format(bytes))
}

impl Packet {
    /// From an MSP request.
    pub fn msp_request(r: msp::Request) -> Self {
        let wire = r.encode().unwrap_or_default();
        Self {
            direction: Direction::HostToDevice,
            command: r.command,
            header: Header::MspRequest {
                option: r.option,
                device: r.device,
            },
            payload: r.data,
            wire,
        }
    }

    /// From an MSP reply.
    pub fn msp_reply(r: msp::Reply) -> Self {
        let wire = r.encode().unwrap_or_default();
        Self {
            direction: Direction::DeviceToHost,
            command: r.command,
            header: Header::MspReply { kind: r.kind },
            payload: r.data,
            wire,
        }
    }

    /// From a servo frame.
    pub fn servo(f: servo::Frame) -> Self {
        let wire = f.encode().unwrap_or_default();
        Self {
            direction: f.direction,
            command: f.command,
            header: Header::Servo,
            payload: f.content,
            wire,
        }
    }

    /// From a Tuya frame.
    pub fn tuya(f: tuya::Frame) -> Self {
        let wire = f.encode().unwrap_or_default();
        Self {
            direction: f.direction(),
            command: f.command,
            header: Header::Tuya { version: f.version },
            payload: f.data,
            wire,
        }
    }

    /// From a Tuya frame the host read from the port: from the MCU whatever its version byte
    /// (the link tells the module's own echoed frames by what it sent).
    pub fn tuya_received(f: tuya::Frame) -> Self {
        Self {
            direction: Direction::DeviceToHost,
            ..Self::tuya(f)
        }
    }

    /// The profile's command for this frame, if it has one.
    pub fn command_in<'p>(&self, profile: &'p Profile) -> Option<&'p Command> {
        profile.command_by_id(self.command)
    }

    /// The payload decoded by the profile, strictly (a payload that does not fit the layout is
    /// [`FieldError::Misfit`]); `None` when the profile lacks the command.
    pub fn decode<'p>(&self, profile: &'p Profile) -> Option<Result<Decoded<'p>, FieldError>> {
        let cmd = self.command_in(profile)?;
        Some(profile.decode(cmd, self.direction, &self.payload))
    }

    /// As much of the payload as fits the profile's layout, and whether it did
    /// ([`Decoded::misfit`]); `None` when the profile lacks the command.
    pub fn decode_lenient<'p>(&self, profile: &'p Profile) -> Option<Decoded<'p>> {
        let cmd = self.command_in(profile)?;
        Some(profile.decode_lenient(cmd, self.direction, &self.payload))
    }

    /// Servo: who the frame is for (a request) or from (a reply); `None` for the other
    /// protocols. The first content byte is not a servo id in commands 18, 19 and 25.
    pub fn servo_target(&self) -> Option<servo::Target> {
        matches!(self.header, Header::Servo).then(|| {
            servo::Frame {
                direction: self.direction,
                command: self.command,
                content: self.payload.clone(),
            }
            .target()
        })
    }

    /// One line for a log: `MSP_GET_PWMVALUE pwmValue=85 %`.
    pub fn summary(&self, profile: &Profile) -> String {
        let Some(cmd) = self.command_in(profile) else {
            return format!(
                "command {} (not in profile) [{}]",
                self.command,
                hex::format(&self.payload)
            );
        };
        let mut s = cmd.ident.clone();
        if let Header::MspReply {
            kind: msp::ReplyKind::Async,
        } = self.header
        {
            s.push_str(" (unsolicited, kind 0xFE: answers nothing)");
        }
        let d = profile.decode_lenient(cmd, self.direction, &self.payload);
        for v in &d.values {
            s.push_str(&format!(" {}={}", v.ident, v.display()));
        }
        if let Some(m) = d.misfit() {
            s.push_str(&format!(
                " !{}-byte payload, layout {}: {} [{}]",
                m.payload.len(),
                m.expected_text(),
                m.fault,
                hex::format(&self.payload)
            ));
        }
        s
    }
}

/// Which MSP frames a byte stream holds (requests and replies share the 0xFF preamble).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MspDirection {
    /// Host-to-device requests.
    Requests,
    /// Device-to-host replies.
    Replies,
    /// Whichever reading finds more valid frames.
    Auto,
}

/// A frame or error found in a byte stream, at its stream offset.
#[derive(Debug, Clone)]
pub struct Item {
    /// Offset of its first byte.
    pub offset: u64,
    /// Bytes it covers.
    pub len: usize,
    /// The frame or the error.
    pub result: Result<Packet, FrameError>,
}

fn pull<F: protocol::Framing>(
    dec: &mut protocol::Decoder<F>,
    wrap: &impl Fn(F::Frame) -> Packet,
    out: &mut Vec<Item>,
) {
    // `while let` rather than `for`: each item's offset is read from the decoder as it comes.
    #[allow(clippy::while_let_on_iterator)]
    while let Some(r) = dec.next() {
        let offset = dec.last_start();
        out.push(match r {
            Ok(f) => {
                let p = wrap(f);
                Item {
                    offset,
                    len: p.wire.len(),
                    result: Ok(p),
                }
            }
            Err(e) => Item {
                offset,
                len: e.span(),
                result: Err(e),
            },
        });
    }
}

fn drain<F: protocol::Framing>(
    mut dec: protocol::Decoder<F>,
    bytes: &[u8],
    wrap: impl Fn(F::Frame) -> Packet,
) -> Vec<Item> {
    dec.push(bytes);
    let mut out = Vec::new();
    pull(&mut dec, &wrap, &mut out);
    // The input is complete: a partial frame at the end will not grow, so look behind it.
    dec.flush();
    pull(&mut dec, &wrap, &mut out);
    if let Some(e) = dec.finish() {
        out.push(Item {
            offset: dec.last_start(),
            len: e.span(),
            result: Err(e),
        });
    }
    out
}

/// Every frame and error in a complete byte buffer.
pub fn decode_all(protocol: Protocol, msp_dir: MspDirection, bytes: &[u8]) -> Vec<Item> {
    match protocol {
        Protocol::Servo => drain(servo::ServoDecoder::new(), bytes, Packet::servo),
        Protocol::Tuya => drain(tuya::TuyaDecoder::new(), bytes, Packet::tuya),
        Protocol::Msp => {
            let req = || drain(msp::RequestDecoder::new(), bytes, Packet::msp_request);
            let rep = || drain(msp::ReplyDecoder::new(), bytes, Packet::msp_reply);
            match msp_dir {
                MspDirection::Requests => req(),
                MspDirection::Replies => rep(),
                MspDirection::Auto => {
                    let good = |items: &[Item]| -> usize {
                        items
                            .iter()
                            .filter(|i| i.result.is_ok())
                            .map(|i| i.len)
                            .sum()
                    };
                    let (a, b) = (req(), rep());
                    if good(&a) > good(&b) { a } else { b }
                }
            }
        }
    }
}
