//! Decoder throughput over ~1 MiB of realistic back-to-back frames, pushed in 4 KiB chunks as a
//! serial reader would, with and without 10 % junk between frames.
//!
//! Run: `cargo bench --bench decoders -- --warm-up-time 1 --measurement-time 3`

use std::hint::black_box;

use botbench::protocol::msp::{self, ReplyDecoder, ReplyKind, RequestDecoder};
use botbench::protocol::servo::{self, ServoDecoder};
use botbench::protocol::tuya::dp::{self, DataPoint, DpValue};
use botbench::protocol::tuya::{self, TuyaDecoder};
use botbench::protocol::{Decoder, Framing};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};

const TARGET: usize = 1 << 20;
const CHUNK: usize = 4096;

/// A small deterministic generator (xorshift64*), so every run decodes the same bytes.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
    fn bytes(&mut self, n: usize) -> Vec<u8> {
        (0..n).map(|_| self.next() as u8).collect()
    }
}

/// Frames from `make` back to back until ~1 MiB; with `junk_pct`, random bytes between frames
/// make up about that share of the buffer. Returns the buffer and the number of frames.
fn stream(seed: u64, junk_pct: u64, mut make: impl FnMut(&mut Rng) -> Vec<u8>) -> (Vec<u8>, usize) {
    let mut rng = Rng(seed);
    let mut out = Vec::with_capacity(TARGET + 2048);
    let mut frames = 0;
    while out.len() < TARGET {
        let frame = make(&mut rng);
        if junk_pct > 0 {
            // Junk of about junk_pct / (100 - junk_pct) of the frame's length, on average.
            let mean = frame.len() as u64 * junk_pct / (100 - junk_pct);
            let n = rng.below(2 * mean + 1) as usize;
            out.extend(rng.bytes(n));
        }
        out.extend_from_slice(&frame);
        frames += 1;
    }
    (out, frames)
}

fn msp_reply(rng: &mut Rng) -> Vec<u8> {
    let kind = if rng.below(8) == 0 {
        ReplyKind::Async
    } else {
        ReplyKind::Reply
    };
    let n = rng.below(33) as usize;
    msp::Reply {
        kind,
        command: 97 + rng.below(130) as u8,
        data: rng.bytes(n),
    }
    .encode()
    .unwrap()
}

fn msp_request(rng: &mut Rng) -> Vec<u8> {
    let n = rng.below(33) as usize;
    msp::Request::new(0x03, 97 + rng.below(130) as u8, rng.bytes(n))
        .encode()
        .unwrap()
}

fn servo_frame(rng: &mut Rng) -> Vec<u8> {
    let n = 1 + rng.below(32) as usize;
    let command = 1 + rng.below(24) as u8;
    let content = rng.bytes(n);
    let frame = if rng.below(2) == 0 {
        servo::Frame::request(command, content)
    } else {
        servo::Frame::reply(command, content)
    };
    frame.encode().unwrap()
}

fn tuya_frame(rng: &mut Rng) -> Vec<u8> {
    match rng.below(16) {
        // An OTA packet: offset + 1024 bytes.
        0 => {
            let mut data = (rng.below(1 << 20) as u32).to_be_bytes().to_vec();
            data.extend(rng.bytes(1024));
            tuya::Frame::from_module(tuya::cmd::OTA_PACKET, data)
        }
        1 => tuya::Frame::from_mcu(tuya::cmd::HEARTBEAT, vec![1]),
        // DP reports: one to four data points of the vacuum's kinds.
        _ => {
            let points: Vec<DataPoint> = (0..1 + rng.below(4))
                .map(|_| {
                    let id = 1 + rng.below(19) as u8;
                    let value = match rng.below(5) {
                        0 => DpValue::Bool(rng.below(2) == 1),
                        1 => DpValue::Value(rng.below(1000) as i32),
                        2 => DpValue::Enum(rng.below(12) as u8),
                        3 => DpValue::Bitmap {
                            bits: rng.below(128) as u32,
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
    let mut g = c.benchmark_group(group);
    g.throughput(Throughput::Bytes(buf.len() as u64));
    g.bench_function(name, |b| b.iter(|| decode(new(), black_box(&buf))));
    g.finish();
}

fn decoders(c: &mut Criterion) {
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

criterion_group!(benches, decoders);
criterion_main!(benches);
