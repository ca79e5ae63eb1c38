//! The MCU firmware update (OTA, PROTOCOL_NOTES §3): the image read from its file with a size
//! bound, the expected transfer time at the port's rate, and the upload itself.

use super::super::{OpError, Progress};
use crate::document::{Limit, read_bytes};
use crate::link::{Client, ExchangeError, Match, ReplySpec, Request, wire_time};
use crate::ops::Run;
use crate::protocol::tuya::cmd;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// How long the MCU may take to ack one OTA packet.
pub const OTA_ACK_WAIT: Duration = Duration::from_secs(5);
/// Retries of an OTA packet whose ack did not come.
pub const OTA_RETRIES: u8 = 3;
/// The packet size an MCU asks for unless it says otherwise (0x0a answered 0 or nothing).
pub const DEFAULT_PACKET: usize = 256;

/// Why a firmware file cannot be sent. Nothing was sent.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FirmwareFileError {
    /// No file chosen.
    #[error("choose a firmware file first")]
    NoneChosen,
    /// The file cannot be read.
    #[error("{}: {reason}", path.display())]
    Unreadable {
        /// The file.
        path: PathBuf,
        /// What the system said.
        reason: String,
    },
    /// A folder, a device (such as /dev/zero) or a pipe.
    #[error("{}: not a firmware image file (a folder, a device or a pipe)", path.display())]
    NotAFile {
        /// The path.
        path: PathBuf,
    },
    /// An empty file.
    #[error("{}: the firmware file is empty; nothing to send", path.display())]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// A file larger than the profile's largest image.
    #[error(
        "{}: {} bytes is over the largest image the profile allows ({max} bytes): is it the right file?",
        path.display(),
        size.map_or_else(|| format!("at least {}", u64::from(*max) + 1), |s| s.to_string())
    )]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Its size, when the system knows it (a pipe or a device has none: reading stopped
        /// past the maximum).
        size: Option<u64>,
        /// The profile's largest image ([`crate::profile::Profile::ota_max_bytes`]).
        max: u32,
    },
}

/// The size of the firmware file at `path`, if it can be sent: a regular file (not a folder, a
/// device or a pipe), at most `max` bytes, not empty. Always `Some` size when `Ok`. Reads
/// nothing.
pub fn check_file(path: &Path, max: u32) -> Result<Option<u64>, FirmwareFileError> {
    if path.as_os_str().is_empty() {
        return Err(FirmwareFileError::NoneChosen);
    }
    let meta = std::fs::metadata(path).map_err(|e| FirmwareFileError::Unreadable {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })?;
    if !meta.is_file() {
        return Err(FirmwareFileError::NotAFile {
            path: path.to_path_buf(),
        });
    }
    match meta.len() {
        0 => Err(FirmwareFileError::Empty {
            path: path.to_path_buf(),
        }),
        n if n > u64::from(max) => Err(FirmwareFileError::TooLarge {
            path: path.to_path_buf(),
            size: Some(n),
            max,
        }),
        n => Ok(Some(n)),
    }
}

/// The firmware image at `path`: checked as [`check_file`] checks it (typed errors before a
/// byte is read), then read as every file a person names is ([`crate::document::read_bytes`]),
/// within `max` and never past [`Limit::FIRMWARE`]; a file that grows past the bound while it
/// is read is refused as unreadable.
pub fn read_image(path: &Path, max: u32) -> Result<Vec<u8>, FirmwareFileError> {
    check_file(path, max)?;
    let bound = u64::from(max).min(Limit::FIRMWARE.max);
    let limit = Limit::new(Limit::FIRMWARE.what, bound);
    let image = read_bytes(path, limit).map_err(|e| FirmwareFileError::Unreadable {
        path: path.to_path_buf(),
        reason: e.message().to_string(),
    })?;
    if image.is_empty() {
        // Emptied since it was checked.
        return Err(FirmwareFileError::Empty {
            path: path.to_path_buf(),
        });
    }
    Ok(image)
}

/// The bytes an update of `size` bytes puts on the wire with `packet`-byte packets: the start
/// (11 out, 8 back), each packet (7 + 4 + data out, 7 back), the last, empty packet (11 out, 7
/// back).
pub fn transfer_bytes(size: u64, packet: usize) -> u64 {
    let packets = size.div_ceil(packet.max(1) as u64);
    11 + 8 + packets * (7 + 4 + 7) + size + 11 + 7
}

/// How long an update of `size` bytes takes at `baud` with `packet`-byte packets: the bytes'
/// own time on the wire, which the update comes close to (see the README's figures).
pub fn transfer_time(size: u64, packet: usize, baud: u32) -> Duration {
    let bytes = usize::try_from(transfer_bytes(size, packet)).unwrap_or(usize::MAX);
    wire_time(bytes, baud)
}

/// A duration as `1 h 02 min`, `4 min 05 s` or `12 s`.
pub fn duration_text(d: Duration) -> String {
    let s = d.as_secs_f64().round() as u64;
    match s {
        s if s >= 3600 => format!("{} h {:02} min", s / 3600, s % 3600 / 60),
        s if s >= 60 => format!("{} min {:02} s", s / 60, s % 60),
        s => format!("{s} s"),
    }
}

/// What an update of `size` bytes will take at `baud`, for a person about to start it:
/// `65536 bytes: about 1 min 14 s at 9600 baud (256-byte packets; less if the MCU asks for
/// larger ones)`.
pub fn expected_text(size: u64, baud: u32) -> String {
    format!(
        "{size} bytes: about {} at {baud} baud ({DEFAULT_PACKET}-byte packets; less if the MCU asks for larger ones)",
        duration_text(transfer_time(size, DEFAULT_PACKET, baud))
    )
}

/// The MCU version a firmware image names, if it names exactly one: the only distinct
/// dot-decimal `x.y.z` string in it (each part 1 or 2 digits, between bytes that are no digit
/// or dot). An MCU SDK image holds its `MCU_VER` string (`"1.0.0"`), which the product info's
/// `"v"` reports; the image carries no header that says it (TUYA_FIELD_NOTES §5 gives none), so
/// this is botbench's reading, and `--expect-version` overrides it. `None` when the image holds
/// none, or several different ones.
pub fn image_version(image: &[u8]) -> Option<String> {
    let is_version = |t: &[u8]| {
        let parts: Vec<&[u8]> = t.split(|b| *b == b'.').collect();
        parts.len() == 3
            && parts
                .iter()
                .all(|p| (1..=2).contains(&p.len()) && p.iter().all(u8::is_ascii_digit))
    };
    let mut found: Option<&[u8]> = None;
    for token in image.split(|b| !(b.is_ascii_digit() || *b == b'.')) {
        if !is_version(token) {
            continue;
        }
        match found {
            Some(f) if f != token => return None,
            _ => found = Some(token),
        }
    }
    found.map(|t| String::from_utf8_lossy(t).into_owned())
}

/// Whether `text` is a dot-decimal MCU version (`1.0.0`; each part 0-99, as Tuya's pages allow).
pub fn is_version(text: &str) -> bool {
    let parts: Vec<&str> = text.split('.').collect();
    parts.len() == 3
        && parts
            .iter()
            .all(|p| (1..=2).contains(&p.len()) && p.bytes().all(|b| b.is_ascii_digit()))
}

/// The result of a firmware upload.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct OtaReport {
    /// Image size in bytes.
    pub size: usize,
    /// The packet size the MCU asked for.
    pub packet_size: usize,
    /// Data packets sent.
    pub packets: usize,
    /// Packets sent again after a missing ack.
    pub retries: u32,
    /// Seconds the upload took (0x0a to the end frame).
    pub seconds: f64,
    /// The version the MCU's product info named before the update (`None`: not asked, or
    /// it named none).
    pub before_version: Option<String>,
    /// The version it names after it restarted ([`update`]; `None` from [`ota`] alone).
    pub after_version: Option<String>,
    /// Seconds from the end frame to the product info that named the new version.
    pub back_seconds: Option<f64>,
}

/// The packet size of the MCU's answer to 0x0a: 0 → 256, 1 → 512, 2 → 1024, nothing → 256.
pub fn packet_size(answer: &[u8]) -> Result<usize, OpError> {
    match answer.first() {
        None | Some(0) => Ok(256),
        Some(1) => Ok(512),
        Some(2) => Ok(1024),
        Some(x) => Err(OpError::Verify(format!(
            "the MCU asked for unknown packet size option {x}"
        ))),
    }
}

/// How an upload waits for acks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OtaTiming {
    /// How long the MCU may take to ack a packet.
    pub ack_wait: Duration,
    /// How many times a packet is sent again when its ack does not come.
    pub retries: u8,
}

impl Default for OtaTiming {
    /// 5 s and 3 retries, as the Tuya MCU SDK expects.
    fn default() -> Self {
        Self {
            ack_wait: OTA_ACK_WAIT,
            retries: OTA_RETRIES,
        }
    }
}

/// Uploads `image` to the MCU: 0x0a with the size, then 0x0b packets of the size the MCU asked
/// for (never larger), each acked within `timing.ack_wait` and sent up to `timing.retries` more
/// times, then the final empty packet at offset == size. An image over `max` bytes (the
/// profile's [`crate::profile::Profile::ota_max_bytes`]) is refused before anything is sent.
pub fn ota(
    client: &Client,
    image: &[u8],
    max: u32,
    timing: OtaTiming,
    run: &mut Run<'_>,
) -> Result<OtaReport, OpError> {
    let attempts = timing.retries.saturating_add(1);
    if image.is_empty() {
        return Err(OpError::EmptyImage);
    }
    let size = u32::try_from(image.len())
        .ok()
        .filter(|s| *s <= max)
        .ok_or(OpError::ImageTooLarge {
            size: image.len(),
            max,
        })?;
    let started = Instant::now();
    let start = Request::new(cmd::OTA_START, size.to_be_bytes().to_vec())
        .margin(timing.ack_wait)
        .attempts(attempts);
    let answer = client
        .request(start)
        .map_err(|e| OpError::Verify(format!("the MCU did not accept the update: {e}")))?;
    let chunk = packet_size(answer.payload().unwrap_or_default())?;
    let mut retries = 0u32;
    let mut packets = 0usize;
    let total = image.len() as u64;
    let count = image.len().div_ceil(chunk.max(1));
    for (i, data) in image.chunks(chunk).enumerate() {
        let offset = (i * chunk) as u32;
        if run.is_cancelled() {
            return Err(cancelled_at(i, count, offset, size));
        }
        let mut payload = offset.to_be_bytes().to_vec();
        payload.extend_from_slice(data);
        let req = Request::new(cmd::OTA_PACKET, payload)
            .margin(timing.ack_wait)
            .attempts(attempts);
        let reply = client.request(req).map_err(|e| match e {
            // The port went, not the MCU: said as a lost link (`OpError::lost_port`).
            ExchangeError::Disconnected(r) => OpError::Exchange(ExchangeError::Disconnected(
                format!("{r} (the update at offset {offset} of {size} bytes)"),
            )),
            e => OpError::Verify(format!(
                "the MCU stopped acking at offset {offset} (of {size} bytes) after {attempts} attempts: {e}"
            )),
        })?;
        retries += u32::from(reply.attempts - 1);
        packets += 1;
        let done = (offset as u64) + data.len() as u64;
        let secs = started.elapsed().as_secs_f64().max(1e-6);
        let rate = done as f64 / secs;
        let left = (total - done) as f64 / rate.max(1.0);
        run.report(Progress {
            done,
            total,
            message: crate::i18n::Text::new(
                format!("offset {done} of {size}, {rate:.0} B/s, {left:.0} s left"),
                format!("偏移 {done}/{size},{rate:.0} B/s,剩余 {left:.0} s"),
            ),
        });
    }
    let last = Request::new(cmd::OTA_PACKET, size.to_be_bytes().to_vec())
        .reply(ReplySpec::Optional(Match::command(cmd::OTA_PACKET)))
        .margin(Duration::from_secs(1))
        .attempts(1);
    client.request(last)?;
    Ok(OtaReport {
        size: image.len(),
        packet_size: chunk,
        packets,
        retries,
        seconds: started.elapsed().as_secs_f64(),
        before_version: None,
        after_version: None,
        back_seconds: None,
    })
}

/// What an update must prove: the version the MCU reports once it runs the image (from the
/// image, [`image_version`], or given), and how long after the end frame it may take.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Expect {
    /// The dot-decimal version, `1.0.1`.
    pub version: String,
    /// At most this from the end frame ([`super::COME_BACK_LIMIT`], 60 s, by default).
    pub limit: Duration,
}

/// A proven firmware update: the version before (product info, 0x01), the upload ([`ota`]),
/// then the wait until the MCU restarted and names `expect.version`
/// ([`super::confirm::await_new_version`]). Only then is it done; each way it fails is said as
/// what it is (a refused packet, never back, back with the old version, never restarted).
pub fn update(
    client: &Client,
    image: &[u8],
    max: u32,
    expect: &Expect,
    timing: OtaTiming,
    run: &mut Run<'_>,
) -> Result<OtaReport, OpError> {
    let before = super::confirm::product_info(client).and_then(|i| i.version);
    let watch = client.watch();
    let mut report = ota(client, image, max, timing, run)?;
    let ended = Instant::now();
    let size = image.len() as u64;
    let limit = expect.limit.as_secs();
    run.report(Progress {
        done: size,
        total: size,
        message: crate::i18n::Text::new(
            format!(
                "all {size} bytes sent; waiting for the MCU to restart with version {} (at most {limit} s)",
                expect.version
            ),
            format!(
                "{size} 字节已全部发送;等待 MCU 以版本 {} 重启(最多 {limit} 秒)",
                expect.version
            ),
        ),
    });
    let back = super::confirm::await_new_version(
        client,
        &watch,
        &expect.version,
        ended,
        expect.limit,
        run,
    )?;
    report.before_version = before;
    report.after_version = Some(back.version);
    report.back_seconds = Some(back.seconds);
    Ok(report)
}

/// An update cancelled before packet `done` of `total` (at byte `offset` of `size`): what the
/// MCU was sent and what not; it keeps running its old firmware, the update not finished.
fn cancelled_at(done: usize, total: usize, offset: u32, size: u32) -> OpError {
    let sent = if offset == 0 {
        Vec::new()
    } else {
        vec![format!("bytes 0 to {offset}")]
    };
    OpError::CancelledAfter {
        done,
        total,
        what: "packets",
        done_items: sent,
        not_done: vec![format!(
            "bytes {offset} to {size} (the MCU keeps its old firmware: the update was not finished)"
        )],
    }
}
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_image_names_its_version_when_it_holds_exactly_one() {
        let mut image = vec![0u8; 64];
        image.extend_from_slice(b"{\"p\":\"\0lgldgnmt4ifc.jzex\0");
        image.extend_from_slice(b"1.2.3\0");
        assert_eq!(image_version(&image).as_deref(), Some("1.2.3"));
        image.extend_from_slice(b"\x001.2.3\x00");
        assert_eq!(
            image_version(&image).as_deref(),
            Some("1.2.3"),
            "the same twice"
        );
        image.extend_from_slice(b"\x002.0.10\x00");
        assert_eq!(image_version(&image), None, "two different");
        assert_eq!(image_version(b"v1.2.3.4 and 123.1.1"), None);
        assert!(is_version("1.0.0") && is_version("10.2.33"));
        assert!(!is_version("1.0") && !is_version("1.0.0.0") && !is_version("a.b.c"));
    }

    #[test]
    fn the_expected_time_is_the_wire_time_of_every_frame() {
        // 64 KiB in 256 packets of 256 bytes: 65536 + 256 × 18, and 37 for the start and the end.
        assert_eq!(transfer_bytes(65_536, 256), 65_536 + 256 * 18 + 37);
        let t = transfer_time(65_536, 256, 9600);
        assert_eq!(duration_text(t), "1 min 13 s");
        // 20 MB at 9600 baud: about 6 hours.
        assert_eq!(
            duration_text(transfer_time(20_000_000, 256, 9600)),
            "6 h 11 min"
        );
        assert!(expected_text(65_536, 9600).starts_with("65536 bytes: about 1 min 13 s at 9600"));
    }

    #[test]
    fn a_file_is_refused_by_its_size_and_a_device_is_not_an_image() {
        let dir = std::env::temp_dir().join(format!("botbench-ota-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let big = dir.join("big.bin");
        // Sparse: 20 MB by its size, nothing written.
        std::fs::File::create(&big)
            .and_then(|f| f.set_len(20_000_000))
            .unwrap();
        let err = read_image(&big, 1024).unwrap_err();
        assert!(
            matches!(
                err,
                FirmwareFileError::TooLarge {
                    size: Some(20_000_000),
                    max: 1024,
                    ..
                }
            ),
            "{err}"
        );
        assert!(err.to_string().contains("20000000 bytes is over"), "{err}");
        let err = read_image(Path::new("/dev/zero"), 1024).unwrap_err();
        assert_eq!(
            err.to_string(),
            "/dev/zero: not a firmware image file (a folder, a device or a pipe)"
        );
        let small = dir.join("small.bin");
        std::fs::write(&small, [1, 2, 3]).unwrap();
        assert_eq!(read_image(&small, 3).unwrap(), [1, 2, 3]);
        std::fs::write(&small, []).unwrap();
        assert!(matches!(
            read_image(&small, 3),
            Err(FirmwareFileError::Empty { .. })
        ));
        assert!(matches!(
            read_image(&dir, 3),
            Err(FirmwareFileError::NotAFile { .. })
        ));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
