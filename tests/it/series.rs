//! Properties of `botbench::series`: flat memory, decimation against a brute-force reference,
//! nearest lookup and CSV round trips.

use botbench::series::{Sample, Series, SeriesSet};
use proptest::collection::vec;
use proptest::prelude::*;

/// Time steps (0 allowed, so equal times happen) and values (some NaN, some ±∞, few distinct so
/// ties happen).
fn samples(max: usize) -> impl Strategy<Value = Vec<(f64, f64)>> {
    vec(
        (
            prop_oneof![Just(0.0), 0.0..0.05f64, 0.0..2.0f64],
            prop_oneof![
                8 => -100.0..100.0f64,
                2 => (-3i32..3).prop_map(f64::from),
                1 => Just(f64::NAN),
                1 => prop_oneof![Just(f64::INFINITY), Just(f64::NEG_INFINITY)],
            ],
        ),
        0..max,
    )
    .prop_map(|steps| {
        let mut t = 0.0;
        steps
            .into_iter()
            .map(|(dt, v)| {
                t += dt;
                (t, v)
            })
            .collect()
    })
}

fn build(cap: usize, data: &[(f64, f64)]) -> Series {
    let mut s = Series::new(cap);
    for &(t, v) in data {
        s.push(t, v).unwrap();
    }
    s
}

/// The decimation spelled out the slow way over a plain slice.
fn reference(held: &[Sample], t0: f64, t1: f64, buckets: usize) -> Vec<[f64; 2]> {
    let mut out = Vec::new();
    if buckets == 0 || held.is_empty() || t0 > t1 {
        return out;
    }
    let start = held.iter().position(|s| s.t >= t0).unwrap_or(held.len());
    let end = held.iter().position(|s| s.t > t1).unwrap_or(held.len());
    let p = |s: &Sample| [s.t, s.v];
    if start > 0 && !held[start - 1].v.is_nan() {
        out.push(p(&held[start - 1]));
    }
    let window = &held[start..end];
    if window.len() < 2 * buckets {
        out.extend(window.iter().filter(|s| !s.v.is_nan()).map(p));
    } else {
        // Bucket b holds e(b) <= t < e(b + 1), e(k) = t0 + k * width; the last takes the rest.
        let width = (t1 - t0) / buckets as f64;
        let bucket_of = |s: &Sample| {
            (1..buckets)
                .filter(|&k| s.t >= t0 + k as f64 * width)
                .count()
        };
        for b in 0..buckets {
            let idx: Vec<usize> = (0..window.len())
                .filter(|&i| !window[i].v.is_nan() && bucket_of(&window[i]) == b)
                .collect();
            if idx.is_empty() {
                continue;
            }
            // First occurrence of the min and of the max.
            let mut lo = idx[0];
            let mut hi = idx[0];
            for &i in &idx {
                if window[i].v < window[lo].v {
                    lo = i;
                }
                if window[i].v > window[hi].v {
                    hi = i;
                }
            }
            let (a, z) = (lo.min(hi), lo.max(hi));
            out.push(p(&window[a]));
            if z != a {
                out.push(p(&window[z]));
            }
        }
    }
    if end < held.len() && !held[end].v.is_nan() {
        out.push(p(&held[end]));
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn memory_is_flat_after_ten_times_capacity(cap in 1usize..2000, seed in any::<u64>()) {
        let mut s = Series::new(cap);
        let alloc = s.allocated();
        let mut rng = fastrand::Rng::with_seed(seed);
        let mut t = 0.0;
        for _ in 0..10 * cap {
            t += rng.f64() * 0.02;
            s.push(t, rng.f64()).unwrap();
        }
        prop_assert_eq!(s.len(), cap);
        prop_assert_eq!(s.capacity(), cap);
        prop_assert_eq!(s.allocated(), alloc);
    }

    #[test]
    fn decimation_matches_brute_force(
        data in samples(600),
        cap in 1usize..700,
        a in 0.0..1.0f64,
        b in 0.0..1.0f64,
        buckets in 0usize..80,
    ) {
        let s = build(cap, &data);
        let held: Vec<Sample> = s.iter().collect();
        // A window somewhere around the data, sometimes past either end.
        let (lo, hi) = s.span().unwrap_or((0.0, 1.0));
        let at = |x: f64| lo - 1.0 + x * (hi - lo + 2.0);
        let (t0, t1) = (at(a.min(b)), at(a.max(b)));
        let mut out = Vec::with_capacity(2 * buckets + 2);
        let room = out.capacity();
        s.decimate(t0, t1, buckets, &mut out);
        prop_assert_eq!(&out, &reference(&held, t0, t1, buckets));
        prop_assert!(out.len() <= 2 * buckets + 2);
        prop_assert_eq!(out.capacity(), room, "allocated");
        prop_assert!(out.windows(2).all(|w| w[0][0] <= w[1][0]), "time order");

        // Independently of the bucket formula: the window's overall min and max are drawn.
        let finite: Vec<f64> =
            held.iter().filter(|p| p.t >= t0 && p.t <= t1 && !p.v.is_nan()).map(|p| p.v).collect();
        if buckets > 0 && !finite.is_empty() {
            let min = finite.iter().copied().fold(f64::INFINITY, f64::min);
            let max = finite.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            prop_assert!(out.iter().any(|p| p[1] == min));
            prop_assert!(out.iter().any(|p| p[1] == max));
        }
    }

    #[test]
    fn small_window_is_exact_with_edges(
        data in samples(300),
        i in any::<prop::sample::Index>(),
        len in 1usize..40,
        extra in 1usize..10,
    ) {
        let data: Vec<(f64, f64)> = data.into_iter().filter(|d| !d.1.is_nan()).collect();
        prop_assume!(!data.is_empty());
        let s = build(data.len(), &data);
        let start = i.index(data.len());
        let end = (start + len).min(data.len()) - 1;
        let (t0, t1) = (data[start].0, data[end].0);
        // Every sample with a time in [t0, t1], whatever the indices.
        let inside: Vec<[f64; 2]> =
            data.iter().filter(|d| d.0 >= t0 && d.0 <= t1).map(|&(t, v)| [t, v]).collect();
        let buckets = inside.len() / 2 + extra;
        let mut out = Vec::new();
        s.decimate(t0, t1, buckets, &mut out);
        let mut want = Vec::new();
        if let Some(&(t, v)) = data.iter().rev().find(|d| d.0 < t0) {
            want.push([t, v]);
        }
        want.extend(inside);
        if let Some(&(t, v)) = data.iter().find(|d| d.0 > t1) {
            want.push([t, v]);
        }
        prop_assert_eq!(out, want);
    }

    #[test]
    fn value_at_is_nearest(data in samples(200), cap in 1usize..250, q in -5.0..300.0f64) {
        let s = build(cap, &data);
        let got = s.value_at(q);
        let held: Vec<Sample> = s.iter().collect();
        match got {
            None => prop_assert!(held.is_empty()),
            Some(g) => {
                let best = held.iter().map(|p| (p.t - q).abs()).fold(f64::INFINITY, f64::min);
                prop_assert_eq!((g.t - q).abs(), best);
                prop_assert!(held.iter().any(|p| p.t == g.t && p.v.to_bits() == g.v.to_bits()));
            }
        }
    }

    #[test]
    fn csv_round_trips(
        series in vec(samples(150), 1..5),
        cap in 1usize..200,
    ) {
        let names = ["eulerX", "eulerY", "eulerZ", "battery"];
        let mut set = SeriesSet::new(cap);
        for (name, data) in names.iter().zip(&series) {
            for &(t, v) in data {
                // NaN is written as an empty cell, the same as "no sample"; left to a unit test.
                set.push(name, t, if v.is_nan() { 0.25 } else { v }).unwrap();
            }
        }
        let mut bytes = Vec::new();
        set.write_csv(&mut bytes).unwrap();
        let text = String::from_utf8(bytes).unwrap();

        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let present: Vec<&str> = set.iter().map(|(n, _)| n).collect();
        prop_assert_eq!(header[0], "t");
        prop_assert_eq!(&header[1..], &present[..]);

        let mut parsed: Vec<Vec<(f64, f64)>> = vec![Vec::new(); present.len()];
        let mut last_t = f64::NEG_INFINITY;
        for line in lines {
            let cells: Vec<&str> = line.split(',').collect();
            prop_assert_eq!(cells.len(), present.len() + 1);
            let (int, frac) = cells[0].split_once('.').unwrap();
            prop_assert_eq!(frac.len(), 3, "ms precision: {}", cells[0]);
            prop_assert!(!int.is_empty());
            let t: f64 = cells[0].parse().unwrap();
            prop_assert!(t >= last_t);
            last_t = t;
            prop_assert!(cells[1..].iter().any(|c| !c.is_empty()), "row without values");
            for (col, cell) in cells[1..].iter().enumerate() {
                if !cell.is_empty() {
                    parsed[col].push((t, cell.parse().unwrap()));
                }
            }
        }
        for ((_, s), got) in set.iter().zip(&parsed) {
            let want: Vec<(f64, f64)> =
                s.iter().map(|p| ((p.t * 1000.0).round() / 1000.0, p.v)).collect();
            prop_assert_eq!(got, &want);
        }
        // One row per distinct millisecond unless a series has two samples in one.
        let mut all: Vec<i64> = set
            .iter()
            .flat_map(|(_, s)| s.iter().map(|p| (p.t * 1000.0).round() as i64))
            .collect();
        all.sort_unstable();
        all.dedup();
        let no_repeats = set.iter().all(|(_, s)| {
            let ms: Vec<i64> = s.iter().map(|p| (p.t * 1000.0).round() as i64).collect();
            ms.windows(2).all(|w| w[0] != w[1])
        });
        if no_repeats {
            prop_assert_eq!(text.lines().count() - 1, all.len());
        }
    }
}
