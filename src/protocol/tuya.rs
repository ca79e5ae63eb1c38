//! The Tuya MCU serial protocol (seed 003), as the Wi-Fi module sees it.
//!
//! Frame: `55 AA, version, command, length u16 BE, data[length], checksum`; the checksum is the
//! sum of every byte before it, mod 256. The module sends version 0x00; the MCU 0x03 by the
//! protocol document, but MCU SDKs before v2.5 send 0x01 and some firmware 0x00, so a frame of
//! any version byte is read (PROTOCOL_NOTES §4), and the version is kept in [`Frame::version`].
//! Data points (commands 0x06 and 0x07) are in [`dp`].

pub mod dp;

use super::{Decoder, Direction, EncodeError, FrameError, Framing, Scan, sum8};
use serde::Serialize;

/// The frame header.
pub const HEADER: [u8; 2] = [0x55, 0xAA];
/// The version byte of frames from the module (botbench).
pub const VERSION_MODULE: u8 = 0x00;
/// The version byte of frames from the MCU, as the protocol document (and MCU SDK v2.5) gives
/// it. MCUs in the field also send 0x01 (MCU SDK v2.3) and 0x00.
pub const VERSION_MCU: u8 = 0x03;
/// The largest data length a decoder accepts by default: the protocol's largest frame, an OTA
/// packet of 1024 bytes with its 4-byte offset (1035 bytes on the wire). A Wi-Fi module's UART
/// buffer holds at least 1024 bytes on every chip but the ESP8266 (256), and the MCU SDK's
/// buffers are far smaller (TUYA_FIELD_NOTES §6); a longer frame is refused as
/// [`super::FrameError::TooLong`] and the decoder resynchronises on the next `55 AA`. Tuya gives
/// no rule for a module that receives a longer frame (UNCONFIRMED): this is botbench's choice,
/// above every frame of the protocol and of the vacuum's data points.
pub const DEFAULT_MAX_DATA: usize = 1028;
/// The largest data length the length field can carry.
pub const MAX_DATA: usize = u16::MAX as usize;

/// Command words of seed 003 and PROTOCOL_NOTES §3.
pub mod cmd {
    /// Heartbeat (the MCU answers 0 after a restart, 1 later).
    pub const HEARTBEAT: u8 = 0x00;
    /// Product info (JSON).
    pub const PRODUCT_INFO: u8 = 0x01;
    /// Working mode: who drives the Wi-Fi LED.
    pub const WORK_MODE: u8 = 0x02;
    /// Report the Wi-Fi state (0-6) to the MCU.
    pub const WIFI_STATE: u8 = 0x03;
    /// The MCU asks to reset the Wi-Fi.
    pub const RESET_WIFI: u8 = 0x04;
    /// The MCU asks to reset the Wi-Fi into a mode.
    pub const RESET_WIFI_MODE: u8 = 0x05;
    /// Data-point command from the module.
    pub const DP_COMMAND: u8 = 0x06;
    /// Data-point report from the MCU.
    pub const DP_REPORT: u8 = 0x07;
    /// Query all data points.
    pub const QUERY_STATUS: u8 = 0x08;
    /// OTA start: the image size.
    pub const OTA_START: u8 = 0x0A;
    /// OTA packet: offset and data.
    pub const OTA_PACKET: u8 = 0x0B;
    /// The MCU asks for the GMT (UTC) time: answered `ok, yy, MM, dd, hh, mm, ss` (7 bytes).
    pub const UTC_TIME: u8 = 0x0C;
    /// Wi-Fi production test.
    pub const WIFI_TEST: u8 = 0x0E;
    /// The MCU asks for the module's free memory: answered with 4 bytes.
    pub const FREE_MEMORY: u8 = 0x0F;
    /// Local time.
    pub const LOCAL_TIME: u8 = 0x1C;
    /// The MCU asks for weather data (`w.<param>` items); not a bench service.
    pub const WEATHER_OPEN: u8 = 0x20;
    /// Weather data from the module.
    pub const WEATHER_DATA: u8 = 0x21;
    /// A data-point report the MCU wants acknowledged (synchronous report, as 0x07 data).
    pub const DP_REPORT_SYNC: u8 = 0x22;
    /// The module's result of a synchronous report: `01` success, `00` failure.
    pub const DP_REPORT_SYNC_RESULT: u8 = 0x23;
    /// The MCU asks for the Wi-Fi signal strength: answered with one signed byte, dBm.
    pub const WIFI_RSSI: u8 = 0x24;
    /// The MCU tells the module to stop its heartbeat: acknowledged with an empty 0x25.
    pub const HEARTBEAT_STOP: u8 = 0x25;
    /// Stream (map) data from the MCU: answered with one result byte.
    pub const STREAM: u8 = 0x28;
    /// Network status.
    pub const NET_STATUS: u8 = 0x2B;
    /// Wi-Fi test: join the router named in the JSON data; answered `01` received.
    pub const WIFI_CONNECT_TEST: u8 = 0x2C;
    /// MAC address.
    pub const MAC: u8 = 0x2D;
    /// Multi-map stream data from the MCU: answered with one result byte.
    pub const MAPS_STREAM: u8 = 0x30;
    /// Extended services: the sub-command is the first data byte.
    pub const EXTENDED: u8 = 0x34;
    /// "New function" settings (sub-command 0x00 with JSON): answered `00, result`.
    pub const NEW_FUNC: u8 = 0x37;
}

/// A Tuya frame.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Frame {
    /// 0x00 from the module; 0x03 from the MCU by the document (0x01 or 0x00 from some).
    pub version: u8,
    /// The command word.
    pub command: u8,
    /// The data.
    pub data: Vec<u8>,
}

impl Frame {
    /// A frame from the module (botbench).
    pub fn from_module(command: u8, data: Vec<u8>) -> Self {
        Self {
            version: VERSION_MODULE,
            command,
            data,
        }
    }

    /// A frame from the MCU.
    pub fn from_mcu(command: u8, data: Vec<u8>) -> Self {
        Self {
            version: VERSION_MCU,
            command,
            data,
        }
    }

    /// Which way the frame goes, guessed from its version byte alone (a frame tool's guess:
    /// an MCU that sends version 0x00 is taken for the module). The link knows better: it
    /// tells the module's own frames by what it sent.
    pub fn direction(&self) -> Direction {
        if self.version == VERSION_MCU {
            Direction::DeviceToHost
        } else {
            Direction::HostToDevice
        }
    }

    /// The frame's bytes.
    pub fn encode(&self) -> Result<Vec<u8>, EncodeError> {
        let len = u16::try_from(self.data.len()).map_err(|_| EncodeError::PayloadTooLong {
            len: self.data.len(),
            max: MAX_DATA,
        })?;
        let mut out = Vec::with_capacity(self.data.len() + 7);
        out.extend_from_slice(&HEADER);
        out.push(self.version);
        out.push(self.command);
        out.extend_from_slice(&len.to_be_bytes());
        out.extend_from_slice(&self.data);
        out.push(sum8(&out));
        Ok(out)
    }

    /// The frame's length on the wire.
    pub fn wire_len(&self) -> usize {
        self.data.len() + 7
    }
}

/// Tuya framing with a cap on the data length.
#[derive(Debug, Clone, Copy)]
pub struct TuyaFraming {
    /// The largest data length accepted.
    pub max_data: usize,
}

impl Default for TuyaFraming {
    fn default() -> Self {
        Self {
            max_data: DEFAULT_MAX_DATA,
        }
    }
}

impl Framing for TuyaFraming {
    type Frame = Frame;

    fn is_start(&self, byte: u8) -> bool {
        byte == HEADER[0]
    }

    fn scan(&self, buf: &[u8]) -> Scan<Frame> {
        if buf.len() < 2 {
            return Scan::NeedMore { need: None };
        }
        if buf[1] != HEADER[1] {
            return Scan::NoHeader;
        }
        if buf.len() < 3 {
            return Scan::NeedMore { need: None };
        }
        // Any version byte: MCUs send 0x03, 0x01 or 0x00 (the checksum still guards the frame).
        let version = buf[2];
        if buf.len() < 6 {
            return Scan::NeedMore { need: None };
        }
        let len = u16::from_be_bytes([buf[4], buf[5]]) as usize;
        if len > self.max_data {
            return Scan::Bad(FrameError::TooLong {
                len,
                cap: self.max_data,
                bytes: buf[..6].to_vec(),
            });
        }
        let total = len + 7;
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
                version,
                command: buf[3],
                data: buf[6..total - 1].to_vec(),
            },
            total,
        )
    }
}

/// A streaming decoder of Tuya frames, both directions.
pub type TuyaDecoder = Decoder<TuyaFraming>;

impl TuyaDecoder {
    /// A new decoder with the default length cap.
    pub fn new() -> Self {
        Decoder::with_framing(TuyaFraming::default())
    }

    /// A new decoder that accepts data up to `max_data` bytes.
    pub fn with_max_data(max_data: usize) -> Self {
        Decoder::with_framing(TuyaFraming {
            max_data: max_data.min(MAX_DATA),
        })
    }
}

impl Default for TuyaDecoder {
    fn default() -> Self {
        Self::new()
    }
}
