//! The field faults as capture files (tests/captures/*.pcapng) replayed through a pseudo-terminal
//! to the real link.
//!
//! The files are built by [`fault_captures`] below, from the bytes and timings the field
//! reports give (PROTOCOL_NOTES.md section 4). `the_committed_fault_captures_are_current`
//! checks the committed files against it; to rewrite them after a format change:
//! `BOTBENCH_WRITE_CAPTURES=1 cargo test --test it capture_faults`.

use crate::support::{PATIENCE, open_link};
use botbench::capture::{self, CaptureFile, CaptureInfo, Chunk, ReplayDevice};
use botbench::link::{Link, LinkEvent, LinkOptions, Request};
use botbench::profile::Registry;
use botbench::protocol::Direction::{self, DeviceToHost as In, HostToDevice as Out};
use botbench::sim::{Faults, PtyServer, SharedDevice};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// 2026-01-01 00:00:00 UTC in microseconds: the captures' first chunk.
const T0: u64 = 1_767_225_600_000_000;

fn chunk(after_us: u64, direction: Direction, bytes: &[u8], baud: u32) -> Chunk {
    Chunk {
        at_us: T0 + after_us,
        direction,
        bytes: bytes.to_vec(),
        baud,
        dropped_before: 0,
    }
}

fn info(profile: &str, baud: u32) -> CaptureInfo {
    CaptureInfo {
        application: "botbench tests/captures (tests/it/capture_faults.rs)".into(),
        ..CaptureInfo::new("/dev/ttyUSB0", baud, profile, None)
    }
}

/// (file name, capture): each field fault as a technician's capture would hold it.
fn fault_captures() -> Vec<(&'static str, CaptureFile)> {
    let msp = 115_200;
    let servo = 115_200;
    let tuya = 9_600;
    vec![
        (
            // MSP_GET_PWMVALUE (130); the board pushes an async frame (kind 0xFE) with the same
            // command before its reply (kind 0xFF): only the reply answers.
            "msp-async-before-reply.pcapng",
            CaptureFile {
                info: info("window-cleaner", msp),
                chunks: vec![
                    chunk(0, Out, &[0xff, 0xff, 0x03, 0x82, 0x00, 0x81], msp),
                    chunk(1_400, In, &[0xff, 0xfe, 0x82, 0x01, 0xee, 0x6d], msp),
                    chunk(2_100, In, &[0xff, 0xff, 0x82, 0x01, 0x55, 0xd6], msp),
                ],
                truncated: None,
            },
        ),
        (
            // READ_DATA of servo 1, parameter 2: the 9-byte reply held by an FTDI latency
            // timer, 4 bytes then 5 bytes 16 ms later.
            "servo-reply-split-by-latency-tick.pcapng",
            CaptureFile {
                info: info("servo", servo),
                chunks: vec![
                    chunk(0, Out, &[0x12, 0x4c, 0x03, 0x02, 0x01, 0x02, 0x66], servo),
                    chunk(1_900, In, &[0x05, 0x1c, 0x03, 0x04], servo),
                    chunk(17_900, In, &[0x01, 0x02, 0xf4, 0x01, 0x20], servo),
                ],
                truncated: None,
            },
        ),
        (
            // A heartbeat answered by an MCU that sends version 0x00 (the module's) instead
            // of 0x03.
            "tuya-mcu-version-0.pcapng",
            CaptureFile {
                info: info("tuya-vacuum", tuya),
                chunks: vec![
                    chunk(0, Out, &[0x55, 0xaa, 0x00, 0x00, 0x00, 0x00, 0xff], tuya),
                    chunk(
                        21_000,
                        In,
                        &[0x55, 0xaa, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00],
                        tuya,
                    ),
                ],
                truncated: None,
            },
        ),
    ]
}

fn captures_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/captures")
}

fn bytes_of(file: &CaptureFile) -> Vec<u8> {
    let mut out = Vec::new();
    capture::write_chunks(&mut out, &file.info, &file.chunks).expect("writes");
    out
}

#[test]
fn the_committed_fault_captures_are_current() {
    let write = std::env::var_os("BOTBENCH_WRITE_CAPTURES").is_some();
    for (name, file) in fault_captures() {
        let path = captures_dir().join(name);
        let want = bytes_of(&file);
        if write {
            std::fs::write(&path, &want).expect("writes the capture");
        }
        let have = std::fs::read(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(have, want, "{name} differs from its generator");
        // And it reads back as written.
        assert_eq!(capture::read_path(&path).expect("reads"), file, "{name}");
    }
}

/// The replayed capture `name` on a pty, and a link to it with `margin`.
fn replay(name: &str, margin_ms: u64) -> (PtyServer, Link, Arc<Mutex<ReplayDevice>>) {
    let file = capture::read_path(&captures_dir().join(name)).expect("reads");
    let device = Arc::new(Mutex::new(ReplayDevice::new(&file).expect("replayable")));
    let shared: SharedDevice = device.clone();
    let server = PtyServer::start_lockstep(shared, Faults::default()).expect("pty");
    let profile = Registry::builtin()
        .and_then(|r| r.get(&file.info.profile))
        .expect("profile");
    let options = LinkOptions {
        start_session: false,
        reconnect: false,
        // Generous: the answer must not depend on the machine's load.
        margin: Some(Duration::from_millis(margin_ms)),
        ..LinkOptions::default()
    };
    let link = open_link(&server, file.info.baud, profile, options);
    (server, link, device)
}

#[test]
fn msp_an_async_frame_before_the_reply_reaches_the_host_first_as_recorded() {
    let (_server, link, device) = replay("msp-async-before-reply.pcapng", 200);
    // Which frame answers is the link's business (issue 11); the replay serves both, in order.
    let _ = link
        .client()
        .request(Request::new(130, Vec::new()).attempts(1));
    assert_eq!(device.lock().unwrap().stats().answered, 1);
    let mut inbound = Vec::new();
    while inbound.len() < 2 {
        match link.events().recv_timeout(PATIENCE) {
            Ok(LinkEvent::Frame(e)) if e.direction == In => {
                inbound.push(e.frame.expect("a valid frame").wire);
            }
            Ok(_) => {}
            Err(e) => panic!("only {inbound:02x?} arrived: {e}"),
        }
    }
    assert_eq!(
        inbound,
        [
            vec![0xff, 0xfe, 0x82, 0x01, 0xee, 0x6d],
            vec![0xff, 0xff, 0x82, 0x01, 0x55, 0xd6]
        ]
    );
}

#[test]
fn msp_only_the_reply_answers_a_request_after_an_async_frame() {
    let (_server, link, _device) = replay("msp-async-before-reply.pcapng", 200);
    let reply = link
        .client()
        .request(Request::new(130, Vec::new()).attempts(1))
        .expect("answered");
    assert_eq!(
        reply.payload(),
        Some(&[0x55][..]),
        "the reply, not the async frame"
    );
}

#[test]
fn servo_a_reply_split_by_a_latency_tick_is_served_late_and_whole() {
    let (_server, link, device) = replay("servo-reply-split-by-latency-tick.pcapng", 100);
    let reply = link
        .client()
        .request(Request::new(3, vec![0x01, 0x02]).attempts(1))
        .expect("answered");
    assert_eq!(reply.payload(), Some(&[0x01, 0x02, 0xf4, 0x01][..]));
    // Its last byte arrived after the tick, as in the capture.
    assert!(reply.rtt >= Duration::from_millis(16), "{:?}", reply.rtt);
    assert_eq!(device.lock().unwrap().stats().answered, 1);
}

#[test]
fn tuya_a_heartbeat_answer_with_version_0_reaches_the_host_as_recorded() {
    let (_server, link, device) = replay("tuya-mcu-version-0.pcapng", 300);
    // What the link makes of it is the link's business (issue 11); the replay serves it.
    let _ = link
        .client()
        .request(Request::new(0x00, Vec::new()).attempts(1));
    assert_eq!(device.lock().unwrap().stats().answered, 1);
    let seen_in = link.events().try_iter().any(|e| match e {
        LinkEvent::Frame(entry) => match entry.frame {
            Ok(p) => p.wire == [0x55, 0xaa, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00],
            Err(e) => e.bytes().starts_with(&[0x55, 0xaa, 0x00, 0x00]),
        },
        _ => false,
    });
    assert!(seen_in, "the MCU's version-0 answer arrived at the host");
}
