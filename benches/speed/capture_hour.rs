//! An hour of capture at the wire's maximum polling rate, simulated as fast as the writer takes
//! it: memory stays bounded (the queue holds at most `QUEUE_CHUNKS` chunks; resident memory does
//! not grow with the hour), and the writer's throughput is reported as a ratio to the wire rate.
//!
//! `cargo bench -- capture_hour` (one JSON document a line; under `cargo test` it simulates 2 s).
//! The file goes to a sink, not the disk: an hour at 1 Mbaud is gigabytes.

use botbench::capture::{Capture, CaptureInfo, QUEUE_CHUNKS};
use botbench::link::wire_time;
use botbench::protocol::Direction;
use std::io::Write;
use std::time::{Duration, Instant};

/// Resident set size of this process, in KiB (Linux; 0 elsewhere).
fn rss_kib() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmRSS:"))
                .and_then(|l| l.split_whitespace().nth(1).map(str::to_string))
        })
        .and_then(|v| v.parse().ok())
        .unwrap_or(0)
}

/// A device's polling at the wire's maximum: the request, and the reply in the chunks a USB
/// adapter delivers it in.
struct Poll {
    name: &'static str,
    baud: u32,
    request: Vec<u8>,
    reply_chunks: Vec<Vec<u8>>,
}

fn hour(p: &Poll, wire_seconds: f64) {
    let info = CaptureInfo::new("bench", p.baud, p.name, None);
    let capture = Capture::to_writer(std::io::sink(), info, "sink".into()).expect("starts");
    let per_exchange: usize = p.request.len() + p.reply_chunks.iter().map(Vec::len).sum::<usize>();
    let exchange_time = wire_time(per_exchange, p.baud);
    let exchanges = (wire_seconds / exchange_time.as_secs_f64()) as u64;
    let rss_before = rss_kib();
    let mut rss_peak = rss_before;
    let started = Instant::now();
    for i in 0..exchanges {
        // The link never produces faster than the wire: wait for room rather than drop, so the
        // whole hour is written.
        while capture.queued() >= QUEUE_CHUNKS - 1 - p.reply_chunks.len() {
            std::thread::yield_now();
        }
        capture.record(Direction::HostToDevice, &p.request);
        for c in &p.reply_chunks {
            capture.record(Direction::DeviceToHost, c);
        }
        if i % 200_000 == 0 {
            rss_peak = rss_peak.max(rss_kib());
        }
    }
    let summary = capture.stop().expect("written");
    let seconds = started.elapsed().as_secs_f64();
    rss_peak = rss_peak.max(rss_kib());
    let wire = exchange_time.as_secs_f64() * exchanges as f64;
    let doc = serde_json::json!({
        "name": format!(
            "capture: {wire_seconds} s of {} polling at {} baud",
            p.name, p.baud
        ),
        "seconds": seconds,
        "wire_seconds": wire,
        "wire_ratio": wire / seconds,
        "chunks": summary.chunks,
        "dropped": summary.dropped,
        "file_bytes": summary.file_bytes,
        "peak_queue_chunks": capture.peak_queue(),
        "queue_capacity_chunks": QUEUE_CHUNKS,
        "rss_before_kib": rss_before,
        "rss_peak_kib": rss_peak,
        "rss_growth_kib": rss_peak.saturating_sub(rss_before),
    });
    let mut out = std::io::stdout().lock();
    let _ = writeln!(out, "{doc}");
}

/// Measures and prints; `quick` (under `cargo test`) simulates 2 s instead of an hour.
pub fn run(quick: bool) {
    let seconds = if quick { 2.0 } else { 3600.0 };
    let msp = Poll {
        name: "window-cleaner MSP_ATTITUDE",
        baud: 115_200,
        request: vec![0xff, 0xff, 0x03, 0x6c, 0x00, 0x6f],
        reply_chunks: vec![vec![0xff], vec![0xff, 0x6c, 0x06, 1, 2, 3, 4, 5, 6, 0x6a]],
    };
    let servo = Poll {
        name: "servo READ_ANGLE",
        baud: 1_000_000,
        request: vec![0x12, 0x4c, 0x0a, 0x01, 0x01, 0x6a],
        reply_chunks: vec![vec![0x05], vec![0x1c, 0x0a, 0x03, 0x01, 0x84, 0x03, 0xb6]],
    };
    for p in [&msp, &servo] {
        hour(p, seconds);
        std::thread::sleep(Duration::from_millis(10));
    }
}
