//! The capture file: pcapng (<https://www.ietf.org/archive/id/draft-ietf-opsawg-pcapng-03.html>)
//! written and read with the `pcap-file` crate, so that Wireshark and tshark open it.
//!
//! Layout:
//! - one Section Header Block: `shb_userappl` = `botbench <version>`;
//! - one Interface Description Block per port setting (a new one after each baud change):
//!   link type `LINKTYPE_USER0` (147: no dissector; Wireshark shows the bytes), snap length 0
//!   (no limit), `if_name` = the port, `if_speed` = the baud rate (bits per second),
//!   `if_tsresol` = 6 (microseconds), and an `opt_comment` with the session's settings as
//!   `key=value` lines after the line `botbench-capture 1` ([`CaptureInfo::to_comment`]);
//! - one Enhanced Packet Block per chunk of bytes exactly as one `write` sent it or one `read`
//!   returned it (the chunking an adapter's latency timer made is kept). Its `epb_flags`
//!   direction bits (0-1) say which way: `01` inbound (the device sent it to botbench), `10`
//!   outbound (botbench sent it). Its timestamp is when the write was called or the read
//!   returned, in microseconds since the Unix epoch. `epb_dropcount` is set when chunks were
//!   lost before this one because the disk could not keep up (see [`super::Capture`]).
//!
//! pcap-file 2.0 writes an EPB's raw timestamp as `Duration::as_nanos()` whatever `if_tsresol`
//! says (and reads it back the same way), so the microsecond count travels in that field as
//! "nanoseconds"; [`epb_timestamp`] and [`units_to_micros`] are the only places that know it.

use super::CaptureError;
use crate::protocol::Direction;
use pcap_file::DataLink;
use pcap_file::pcapng::blocks::enhanced_packet::{EnhancedPacketBlock, EnhancedPacketOption};
use pcap_file::pcapng::blocks::interface_description::{
    InterfaceDescriptionBlock, InterfaceDescriptionOption,
};
use pcap_file::pcapng::blocks::section_header::{SectionHeaderBlock, SectionHeaderOption};
use pcap_file::pcapng::{Block, PcapNgReader, PcapNgWriter};
use std::borrow::Cow;
use std::io::{Read, Write};
use std::time::Duration;

/// The pcapng link type of botbench captures: `LINKTYPE_USER0` (147), raw serial bytes.
pub const LINK_TYPE: u32 = 147;
/// `epb_flags` direction bits: inbound (device to botbench).
pub const FLAG_INBOUND: u32 = 0b01;
/// `epb_flags` direction bits: outbound (botbench to device).
pub const FLAG_OUTBOUND: u32 = 0b10;
/// The first line of the IDB comment that marks a botbench capture.
const COMMENT_MAGIC: &str = "botbench-capture 1";

/// The session a capture was recorded in.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct CaptureInfo {
    /// What recorded it: `botbench 0.1.0`.
    pub application: String,
    /// The port's path (or the simulator's description).
    pub port: String,
    /// The baud rate.
    pub baud: u32,
    /// The device profile's id (e.g. `window-cleaner`); empty when unknown.
    pub profile: String,
    /// The answer margin given with `--margin-ms`, if any (else the protocol's default).
    pub margin: Option<Duration>,
}

impl CaptureInfo {
    /// The session's settings for a capture by this botbench.
    pub fn new(port: &str, baud: u32, profile: &str, margin: Option<Duration>) -> Self {
        Self {
            application: format!("botbench {}", env!("CARGO_PKG_VERSION")),
            port: port.to_string(),
            baud,
            profile: profile.to_string(),
            margin,
        }
    }

    /// The IDB comment: `botbench-capture 1`, then `profile=…`, `baud=…`, `margin_us=…`,
    /// `application=…`, one a line.
    pub fn to_comment(&self) -> String {
        let mut s = format!(
            "{COMMENT_MAGIC}\nprofile={}\nbaud={}\napplication={}\n",
            self.profile, self.baud, self.application
        );
        if let Some(m) = self.margin {
            s.push_str(&format!("margin_us={}\n", m.as_micros()));
        }
        s
    }

    /// Reads what [`Self::to_comment`] wrote into `self` (unknown keys are ignored).
    fn apply_comment(&mut self, comment: &str) -> bool {
        let mut lines = comment.lines();
        if lines.next() != Some(COMMENT_MAGIC) {
            return false;
        }
        for line in lines {
            let Some((k, v)) = line.split_once('=') else {
                continue;
            };
            match k {
                "profile" => self.profile = v.to_string(),
                "baud" => self.baud = v.parse().unwrap_or(self.baud),
                "application" => self.application = v.to_string(),
                "margin_us" => self.margin = v.parse().ok().map(Duration::from_micros),
                _ => {}
            }
        }
        true
    }
}

/// One chunk of bytes as a read returned it or a write sent it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Chunk {
    /// Microseconds since the Unix epoch.
    pub at_us: u64,
    /// Which way.
    pub direction: Direction,
    /// The bytes.
    pub bytes: Vec<u8>,
    /// The baud rate the port was at.
    pub baud: u32,
    /// Chunks lost just before this one (the writer could not keep up).
    pub dropped_before: u64,
}

/// A whole capture, read back.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct CaptureFile {
    /// The session's settings (from the first interface).
    pub info: CaptureInfo,
    /// The chunks in file order.
    pub chunks: Vec<Chunk>,
    /// Why reading stopped early (a file cut off mid-block by a crash), with the chunks read
    /// before kept.
    pub truncated: Option<String>,
}

/// Writes the section header.
pub(crate) fn start<W: Write>(out: W, info: &CaptureInfo) -> Result<PcapNgWriter<W>, CaptureError> {
    let shb = SectionHeaderBlock {
        options: vec![SectionHeaderOption::UserApplication(Cow::Owned(
            info.application.clone(),
        ))],
        ..SectionHeaderBlock::default()
    };
    PcapNgWriter::with_section_header(out, shb).map_err(CaptureError::write)
}

/// Writes an interface block for the session at `baud`; returns the bytes written.
pub(crate) fn write_interface<W: Write>(
    w: &mut PcapNgWriter<W>,
    info: &CaptureInfo,
    baud: u32,
) -> Result<usize, CaptureError> {
    let info = CaptureInfo {
        baud,
        ..info.clone()
    };
    let idb = InterfaceDescriptionBlock {
        linktype: DataLink::from(LINK_TYPE),
        snaplen: 0,
        options: vec![
            InterfaceDescriptionOption::IfName(Cow::Owned(info.port.clone())),
            InterfaceDescriptionOption::IfDescription(Cow::Borrowed("botbench serial link")),
            InterfaceDescriptionOption::IfSpeed(u64::from(baud)),
            InterfaceDescriptionOption::IfTsResol(6),
            InterfaceDescriptionOption::Comment(Cow::Owned(info.to_comment())),
        ],
    };
    w.write_pcapng_block(idb).map_err(CaptureError::write)
}

/// The raw EPB timestamp for `at_us` microseconds (see the module's note on pcap-file 2.0).
fn epb_timestamp(at_us: u64) -> Duration {
    Duration::from_nanos(at_us)
}

/// Writes one chunk on interface `interface`; returns the bytes written.
pub(crate) fn write_chunk<W: Write>(
    w: &mut PcapNgWriter<W>,
    interface: u32,
    at_us: u64,
    direction: Direction,
    bytes: &[u8],
    dropped_before: u64,
) -> Result<usize, CaptureError> {
    let flags = match direction {
        Direction::DeviceToHost => FLAG_INBOUND,
        Direction::HostToDevice => FLAG_OUTBOUND,
    };
    let mut options = vec![EnhancedPacketOption::Flags(flags)];
    if dropped_before > 0 {
        options.push(EnhancedPacketOption::DropCount(dropped_before));
    }
    let epb = EnhancedPacketBlock {
        interface_id: interface,
        timestamp: epb_timestamp(at_us),
        original_len: bytes.len() as u32,
        data: Cow::Borrowed(bytes),
        options,
    };
    w.write_pcapng_block(epb).map_err(CaptureError::write)
}

/// Writes a whole capture at once, with the chunks' own times and bauds (a new interface at
/// each baud change): for captures built by hand (the field faults under `tests/captures`) and
/// for rewriting one. The live path is [`super::Capture`].
pub fn write_chunks(
    out: impl Write,
    info: &CaptureInfo,
    chunks: &[Chunk],
) -> Result<(), CaptureError> {
    let mut w = start(out, info)?;
    let mut baud = info.baud;
    let mut interface = 0;
    write_interface(&mut w, info, baud)?;
    for c in chunks {
        if c.baud != baud && c.baud != 0 {
            baud = c.baud;
            write_interface(&mut w, info, baud)?;
            interface += 1;
        }
        write_chunk(
            &mut w,
            interface,
            c.at_us,
            c.direction,
            &c.bytes,
            c.dropped_before,
        )?;
    }
    w.get_mut().flush().map_err(CaptureError::write)
}

/// Converts a raw EPB timestamp in the interface's units (`if_tsresol`: 10^-n or 2^-n seconds)
/// to microseconds.
fn units_to_micros(raw: u64, tsresol: u8) -> u64 {
    let raw = u128::from(raw);
    let per_second: u128 = if tsresol & 0x80 != 0 {
        1u128 << u32::from(tsresol & 0x7f).min(100)
    } else {
        10u128.saturating_pow(u32::from(tsresol))
    };
    (raw * 1_000_000 / per_second.max(1)).min(u128::from(u64::MAX)) as u64
}

/// An interface as read: its baud rate and timestamp resolution.
struct Interface {
    baud: u32,
    tsresol: u8,
}

/// Reads a capture. Any pcapng with `LINKTYPE_USER0` interfaces and direction flags is taken;
/// packets without a direction flag are refused (they cannot be replayed).
///
/// Errors: the file cannot be opened, is not pcapng, has another link type, or a packet has no
/// direction. A file cut off mid-block keeps what came before ([`CaptureFile::truncated`]).
pub fn read(source: impl Read) -> Result<CaptureFile, CaptureError> {
    let mut reader = PcapNgReader::new(source)
        .map_err(|e| CaptureError::Format(format!("not a pcapng file: {e}")))?;
    let mut file = CaptureFile::default();
    if let Some(SectionHeaderOption::UserApplication(a)) = reader
        .section()
        .options
        .iter()
        .find(|o| matches!(o, SectionHeaderOption::UserApplication(_)))
    {
        file.info.application = a.to_string();
    }
    let mut interfaces: Vec<Interface> = Vec::new();
    let mut index = 0usize;
    while let Some(block) = reader.next_block() {
        index += 1;
        let block = match block {
            Ok(b) => b,
            Err(e) => {
                file.truncated = Some(format!("block {index}: {e}"));
                break;
            }
        };
        match block {
            Block::InterfaceDescription(idb) => {
                let iface = interface(&idb, interfaces.len(), &mut file)?;
                interfaces.push(iface);
            }
            Block::EnhancedPacket(epb) => {
                let chunk = chunk(&epb, &interfaces, file.chunks.len() + 1)?;
                file.chunks.push(chunk);
            }
            _ => {}
        }
    }
    if interfaces.is_empty() {
        return Err(CaptureError::Format(
            "no interface description: not a botbench capture".into(),
        ));
    }
    Ok(file)
}

/// An interface description (the `n`th): its baud rate and timestamp resolution; the first
/// one's port, rate and comments (profile, margin) are the capture's.
fn interface(
    idb: &InterfaceDescriptionBlock<'_>,
    n: usize,
    file: &mut CaptureFile,
) -> Result<Interface, CaptureError> {
    let code = u32::from(idb.linktype);
    if code != LINK_TYPE {
        return Err(CaptureError::Format(format!(
            "interface {n} has link type {code}, not LINKTYPE_USER0 ({LINK_TYPE})"
        )));
    }
    let mut iface = Interface {
        baud: 0,
        tsresol: 6,
    };
    let mut info = file.info.clone();
    for o in &idb.options {
        match o {
            InterfaceDescriptionOption::IfSpeed(s) => {
                iface.baud = u32::try_from(*s).unwrap_or(u32::MAX);
            }
            InterfaceDescriptionOption::IfTsResol(r) => iface.tsresol = *r,
            InterfaceDescriptionOption::IfName(n) => info.port = n.to_string(),
            InterfaceDescriptionOption::Comment(c) => {
                info.apply_comment(c);
            }
            _ => {}
        }
    }
    if n == 0 {
        info.baud = iface.baud;
        file.info = info;
    }
    Ok(iface)
}

/// Packet `n` (counting from 1): its bytes, direction (from its flags: refused without one),
/// time and the rate of its interface.
fn chunk(
    epb: &EnhancedPacketBlock<'_>,
    interfaces: &[Interface],
    n: usize,
) -> Result<Chunk, CaptureError> {
    let Some(iface) = interfaces.get(epb.interface_id as usize) else {
        return Err(CaptureError::Format(format!(
            "packet {n} refers to interface {}, which the file does not describe",
            epb.interface_id
        )));
    };
    let mut direction = None;
    let mut dropped_before = 0;
    for o in &epb.options {
        match o {
            EnhancedPacketOption::Flags(f) => {
                direction = match f & 0b11 {
                    FLAG_INBOUND => Some(Direction::DeviceToHost),
                    FLAG_OUTBOUND => Some(Direction::HostToDevice),
                    _ => None,
                }
            }
            EnhancedPacketOption::DropCount(n) => dropped_before = *n,
            _ => {}
        }
    }
    let Some(direction) = direction else {
        return Err(CaptureError::Format(format!(
            "packet {n} has no direction (epb_flags bits 0-1 are neither 01 nor 10)"
        )));
    };
    let raw = u64::try_from(epb.timestamp.as_nanos()).unwrap_or(u64::MAX);
    Ok(Chunk {
        at_us: units_to_micros(raw, iface.tsresol),
        direction,
        bytes: epb.data.to_vec(),
        baud: iface.baud,
        dropped_before,
    })
}

/// Refuses `path` when it exists and is not a regular file: a named pipe (opening it waits for
/// its other end), a device, a folder.
pub(crate) fn regular_or_absent(path: &std::path::Path) -> Result<(), CaptureError> {
    match std::fs::metadata(path) {
        Ok(m) if !m.is_file() => Err(CaptureError::Open {
            path: path.display().to_string(),
            reason: format!(
                "not a regular file: {}",
                crate::document::file::kind_of(m.file_type())
            ),
        }),
        _ => Ok(()),
    }
}

/// Reads the capture at `path`; what is not a regular file (a named pipe) is refused before it
/// is opened.
pub fn read_path(path: &std::path::Path) -> Result<CaptureFile, CaptureError> {
    regular_or_absent(path)?;
    let f = std::fs::File::open(path).map_err(|e| CaptureError::Open {
        path: path.display().to_string(),
        reason: e.to_string(),
    })?;
    read(std::io::BufReader::new(f)).map_err(|e| e.in_file(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolutions_convert_to_microseconds() {
        assert_eq!(units_to_micros(1_234_567, 6), 1_234_567);
        assert_eq!(units_to_micros(1_234_567_000, 9), 1_234_567);
        assert_eq!(units_to_micros(3, 0), 3_000_000);
        assert_eq!(units_to_micros(1 << 20, 0x80 | 20), 1_000_000);
    }

    #[test]
    fn comment_round_trips_and_ignores_unknown_keys() {
        let info = CaptureInfo::new("/dev/ttyUSB0", 115_200, "window-cleaner", None);
        let mut back = CaptureInfo::default();
        assert!(back.apply_comment(&format!("{}future=1\n", info.to_comment())));
        // The port travels in if_name, not in the comment.
        assert_eq!(
            back,
            CaptureInfo {
                port: String::new(),
                ..info.clone()
            }
        );
        let with_margin = CaptureInfo {
            margin: Some(Duration::from_micros(1500)),
            ..info
        };
        let mut back = CaptureInfo::default();
        back.apply_comment(&with_margin.to_comment());
        assert_eq!(back.margin, Some(Duration::from_micros(1500)));
        assert!(!CaptureInfo::default().apply_comment("a comment a person wrote"));
    }
}
