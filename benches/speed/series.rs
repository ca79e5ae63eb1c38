//! Plot-path costs of `botbench::series` at the GUI's sizing: 4 series × 10 min at 100 Hz
//! (60_000 points each, ring wrapped) decimated into 1200 pixel columns, pushing samples, and
//! the CSV export of the whole set. Each `decimate` iteration is one frame's worth (all 4
//! series); the frame budget is 4 ms p95.
//!
//! Run: `cargo bench -- series --warm-up-time 1 --measurement-time 3`

use std::hint::black_box;

use botbench::series::{DEFAULT_CAPACITY, SeriesSet};
use criterion::{Criterion, Throughput};

use fastrand::Rng;

const NAMES: [&str; 4] = ["eulerX", "eulerY", "eulerZ", "battery"];
const HZ: f64 = 100.0;
const BUCKETS: usize = 1200;

fn value(rng: &mut Rng, k: usize, t: f64) -> f64 {
    let noise = rng.f64() - 0.5;
    match k {
        3 => 12.6 - t * 1e-4 + noise * 0.05,
        _ => 30.0 * (t * 0.3 + k as f64).sin() + noise * 2.0,
    }
}

/// A set of 4 full series; 1.5× capacity was pushed so the rings have wrapped.
fn full_set() -> (SeriesSet, Rng, u64) {
    let mut set = SeriesSet::new(DEFAULT_CAPACITY);
    let mut rng = Rng::with_seed(0x9E37_79B9_7F4A_7C15);
    let n = DEFAULT_CAPACITY as u64 * 3 / 2;
    for i in 0..n {
        let t = i as f64 / HZ;
        for (k, name) in NAMES.iter().enumerate() {
            set.push(name, t, value(&mut rng, k, t)).unwrap();
        }
    }
    (set, rng, n)
}

fn decimate(c: &mut Criterion) {
    let (set, _, _) = full_set();
    let (_, end) = set.span().unwrap();
    let mut outs: Vec<Vec<[f64; 2]>> = (0..4)
        .map(|_| Vec::with_capacity(2 * BUCKETS + 2))
        .collect();
    let mut g = c.benchmark_group("series/decimate_4_series_frame");
    // Samples scanned per frame, for the throughput figure.
    for (label, secs) in [
        ("full_10min", 600.0),
        ("last_60s", 60.0),
        ("last_10s", 10.0),
    ] {
        let t0 = end - secs;
        let scanned: usize = set
            .iter()
            .map(|(_, s)| s.iter().filter(|p| p.t >= t0).count())
            .sum();
        g.throughput(Throughput::Elements(scanned as u64));
        g.bench_function(label, |b| {
            b.iter(|| {
                for ((_, s), out) in set.iter().zip(&mut outs) {
                    s.decimate(black_box(t0), black_box(end), BUCKETS, out);
                }
                black_box(outs.iter().map(Vec::len).sum::<usize>())
            })
        });
    }
    g.finish();
}

fn push(c: &mut Criterion) {
    let (mut set, mut rng, mut i) = full_set();
    let mut g = c.benchmark_group("series/push_full_ring");
    // One 100 Hz tick: a sample for each of the 4 series, looked up by name. Values are plain
    // random numbers so the figure is the push, not the generator's `sin`.
    g.throughput(Throughput::Elements(4));
    g.bench_function("tick_4_series_by_name", |b| {
        b.iter(|| {
            let t = i as f64 / HZ;
            i += 1;
            for name in NAMES {
                black_box(set.push(black_box(name), t, rng.f64())).unwrap();
            }
        })
    });
    let mut series = set.get(NAMES[0]).unwrap().clone();
    g.throughput(Throughput::Elements(1));
    g.bench_function("one_series", |b| {
        b.iter(|| {
            let t = i as f64 / HZ;
            i += 1;
            black_box(series.push(t, rng.f64())).unwrap();
        })
    });
    g.finish();
}

/// The telemetry CSV export of the full set (4 series × 60_000 samples, one row per 10 ms),
/// written with the `csv` crate into memory: rows a second.
fn csv_export(c: &mut Criterion) {
    let (set, _, _) = full_set();
    let mut out = Vec::with_capacity(8 << 20);
    set.write_csv(&mut out).unwrap();
    let rows = out.iter().filter(|&&b| b == b'\n').count() as u64;
    let mut g = c.benchmark_group("series/csv_export");
    g.throughput(Throughput::Elements(rows));
    g.bench_function("full_set_rows", |b| {
        b.iter(|| {
            out.clear();
            set.write_csv(&mut out).unwrap();
            black_box(out.len())
        })
    });
    g.finish();
}

/// Decimating a frame's worth, pushing samples and exporting CSV: groups
/// `series/decimate_4_series_frame`, `series/push_full_ring` and `series/csv_export`.
pub fn benches(c: &mut Criterion) {
    decimate(c);
    push(c);
    csv_export(c);
}
