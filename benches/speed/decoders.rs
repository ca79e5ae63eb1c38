//! Decoder throughput over ~1 MiB of realistic back-to-back frames, pushed in 4 KiB chunks as a
//! serial reader would, with and without 10 % junk between frames.
//!
//! Run: `cargo bench -- decoders --warm-up-time 1 --measurement-time 3`

use std::hint::black_box;

use botbench::protocol::msp::{self, ReplyDecoder, ReplyKind, RequestDecoder};
use botbench::protocol::servo::{self, ServoDecoder};
use botbench::protocol::tuya::dp::{self, DataPoint, DpValue};
use botbench::protocol::tuya::{self, TuyaDecoder};
use botbench::protocol::{Decoder, Framing};
use criterion::{Criterion, Throughput};

use fastrand::Rng;

const TARGET: usize = 1 << 20;
const CHUNK: usize = 4096;

/// `n` random bytes.
fn bytes(rng: &mut Rng, n: usize) -> Vec<u8> {
    std::iter::repeat_with(|| rng.u8(..)).take(n).collect()
}

/// Frames from `make` back to back until ~1 MiB; with `junk_pct`, random bytes between frames
/// make up about that share of the buffer. Returns the buffer and the number of frames.
fn stream(seed: u64, junk_pct: u64, mut make: impl FnMut(&mut Rng) -> Vec<u8>) -> (Vec<u8>, usize) {
    let mut rng = Rng::with_seed(seed);
    let mut out = Vec::with_capacity(TARGET + 2048);
    let mut frames = 0;
    while out.len() < TARGET {
        let frame = make(&mut rng);
        if junk_pct > 0 {
            // Junk of about junk_pct / (100 - junk_pct) of the frame's length, on average.
            let mean = frame.len() as u64 * junk_pct / (100 - junk_pct);
            let n = rng.u64(..2 * mean + 1) as usize;
            out.extend(bytes(&mut rng, n));
        }
        out.extend_from_slice(&frame);
        frames += 1;
    }
    (out, frames)
}

fn msp_reply(rng: &mut Rng) -> Vec<u8> {
    let kind = if rng.u64(..8) == 0 {
        ReplyKind::Async
    } else {
        ReplyKind::Reply
    };
    let n = rng.u64(..33) as usize;
    msp::Reply {
        kind,
        command: 97 + rng.u64(..130) as u8,
        data: bytes(rng, n),
    }
    .encode()
    .unwrap()
}

fn msp_request(rng: &mut Rng) -> Vec<u8> {
    let n = rng.u64(..33) as usize;
    msp::Request::new(0x03, 97 + rng.u64(..130) as u8, bytes(rng, n))
        .encode()
        .unwrap()
}

fn servo_frame(rng: &mut Rng) -> Vec<u8> {
    let n = 1 + rng.u64(..32) as usize;
    let command = 1 + rng.u64(..24) as u8;
    let content = bytes(rng, n);
    let frame = if rng.u64(..2) == 0 {
        servo::Frame::request(command, content)
    } else {
        servo::Frame::reply(command, content)
    };
    frame.encode().unwrap()
}

fn tuya_frame(rng: &mut Rng) -> Vec<u8> {
    match rng.u64(..16) {
        // An OTA packet: offset + 1024 bytes.
        0 => {
            let mut data = (rng.u64(..1 << 20) as u32).to_be_bytes().to_vec();
            data.extend(bytes(rng, 1024));
            tuya::Frame::from_module(tuya::cmd::OTA_PACKET, data)
        }
        1 => tuya::Frame::from_mcu(tuya::cmd::HEARTBEAT, vec![1]),
        // DP reports: one to four data points of the vacuum's kinds.
        _ => {
            let points: Vec<DataPoint> = (0..1 + rng.u64(..4))
                .map(|_| {
                    let id = 1 + rng.u64(..19) as u8;
                    let value = match rng.u64(..5) {
                        0 => DpValue::Bool(rng.u64(..2) == 1),
                        1 => DpValue::Value(rng.u64(..1000) as i32),
                        2 => DpValue::Enum(rng.u64(..12) as u8),
                        3 => DpValue::Bitmap {
                            bits: rng.u64(..128) as u32,
                            width: 1,
                        },
                        _ => DpValue::String("20180411051102008000020".into()),
                    };
                    DataPoint { id, value }
                })
                .collect();
            tuya::Frame::from_mcu(tuya::cmd::DP_REPORT, dp::encode(&points).unwrap())
        }
    }
    .encode()
    .unwrap()
}

/// Decodes `buf` in 4 KiB chunks; returns (frames, errors).
fn decode<P: Framing>(mut dec: Decoder<P>, buf: &[u8]) -> (usize, usize) {
    let (mut frames, mut errors) = (0, 0);
    for chunk in buf.chunks(CHUNK) {
        dec.push(chunk);
        for item in dec.by_ref() {
            match black_box(item) {
                Ok(_) => frames += 1,
                Err(_) => errors += 1,
            }
        }
    }
    if dec.finish().is_some() {
        errors += 1;
    }
    (frames, errors)
}

fn bench_one<P: Framing>(
    c: &mut Criterion,
    group: &str,
    name: &str,
    new: fn() -> Decoder<P>,
    (buf, frames): (Vec<u8>, usize),
    clean: bool,
) {
    // The buffer must really be what it claims: every frame decodes when there is no junk.
    let (got, errors) = decode(new(), &buf);
    if clean {
        assert_eq!((got, errors), (frames, 0), "{name}: clean buffer");
    } else {
        assert!(got > frames * 9 / 10, "{name}: {got} of {frames} frames");
    }
    let mut g = c.benchmark_group(format!("decoders/{group}"));
    g.throughput(Throughput::Bytes(buf.len() as u64));
    g.bench_function(name, |b| b.iter(|| decode(new(), black_box(&buf))));
    g.finish();
}

/// Every decoder on a clean stream and on one with 10 % junk: groups `decoders/clean` and
/// `decoders/junk_10pct`.
pub fn benches(c: &mut Criterion) {
    for (group, junk) in [("clean", 0), ("junk_10pct", 10)] {
        let clean = junk == 0;
        bench_one(
            c,
            group,
            "msp_reply",
            ReplyDecoder::new,
            stream(1, junk, msp_reply),
            clean,
        );
        bench_one(
            c,
            group,
            "msp_request",
            RequestDecoder::new,
            stream(2, junk, msp_request),
            clean,
        );
        bench_one(
            c,
            group,
            "servo",
            ServoDecoder::new,
            stream(3, junk, servo_frame),
            clean,
        );
        bench_one(
            c,
            group,
            "tuya",
            TuyaDecoder::new,
            stream(4, junk, tuya_frame),
            clean,
        );
    }
}
