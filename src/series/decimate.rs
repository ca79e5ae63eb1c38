//! Min/max decimation of a series' window to a plot's pixel columns.

use super::Series;

impl Series {
    /// Min/max decimation of the window `[t0, t1]` into `buckets` equal time buckets, for a line
    /// plot `buckets` pixels wide. `out` is cleared and filled with `[t, v]` points in time
    /// order:
    ///
    /// - the last sample before `t0`, if any (so the line reaches the left edge);
    /// - if the window holds fewer than `2 × buckets` samples, all of them unchanged; otherwise
    ///   for each non-empty bucket its minimum and maximum sample in the order they occurred
    ///   (one point when they are the same sample; the first occurrence on ties);
    /// - the first sample after `t1`, if any.
    ///
    /// At most `2 × buckets + 2` points. With edges `e(k) = t0 + k × ((t1 - t0) / buckets)`,
    /// bucket `b` holds the samples with `e(b) ≤ t < e(b + 1)`, the last bucket everything from
    /// `e(buckets - 1)` on (the whole window is one bucket when `t0 == t1`). NaN values are
    /// skipped everywhere (module notes). `t0 > t1`, non-finite bounds, `buckets == 0` or an
    /// empty series give an empty `out`.
    ///
    /// O(log n + samples in window + buckets); no allocation when `out` has room for
    /// `2 × buckets + 2`.
    pub fn decimate(&self, t0: f64, t1: f64, buckets: usize, out: &mut Vec<[f64; 2]>) {
        out.clear();
        if buckets == 0 || !t0.is_finite() || !t1.is_finite() || t0 > t1 || self.is_empty() {
            return;
        }
        let start = self.partition_point(|t| t < t0);
        let end = self.partition_point(|t| t <= t1);

        if let Some(s) = start.checked_sub(1).and_then(|i| self.get(i))
            && !s.v.is_nan()
        {
            out.push([s.t, s.v]);
        }

        let ranges = self.ranges(start, end);
        if end - start < 2 * buckets {
            for r in ranges {
                let (ts, vs) = (&self.t[r.clone()], &self.v[r]);
                out.extend(
                    ts.iter()
                        .zip(vs)
                        .filter(|(_, v)| !v.is_nan())
                        .map(|(&t, &v)| [t, v]),
                );
            }
        } else {
            let mut acc = Buckets::new(t0, (t1 - t0) / buckets as f64, buckets - 1);
            for r in ranges {
                acc.feed(&self.t[r.clone()], &self.v[r], out);
            }
            acc.flush(out);
        }

        if let Some(s) = self.get(end)
            && !s.v.is_nan()
        {
            out.push([s.t, s.v]);
        }
    }
}

/// No sample (an index never reached).
const NONE: usize = usize::MAX;

/// The running state of one decimation pass.
struct Buckets {
    t0: f64,
    width: f64,
    last: usize,
    /// The bucket being filled.
    current: usize,
    /// Where the current bucket ends (`+∞` for the last bucket).
    edge: f64,
    /// Samples fed before the current piece, so indices count in order of occurrence.
    base: usize,
    /// (index, t, v) of the current bucket's first minimum and first maximum; the index is
    /// [`NONE`] until one is seen. Starting from v = +∞ / −∞, NaN never compares in.
    min: (usize, f64, f64),
    max: (usize, f64, f64),
}

impl Buckets {
    const EMPTY_MIN: (usize, f64, f64) = (NONE, 0.0, f64::INFINITY);
    const EMPTY_MAX: (usize, f64, f64) = (NONE, 0.0, f64::NEG_INFINITY);

    fn new(t0: f64, width: f64, last: usize) -> Self {
        let mut b = Self {
            t0,
            width,
            last,
            current: 0,
            edge: 0.0,
            base: 0,
            min: Self::EMPTY_MIN,
            max: Self::EMPTY_MAX,
        };
        b.edge = b.edge_after(0);
        b
    }

    fn edge_after(&self, bucket: usize) -> f64 {
        if bucket == self.last {
            f64::INFINITY
        } else {
            self.t0 + (bucket + 1) as f64 * self.width
        }
    }

    /// Feeds the next contiguous piece of the window: bucket by bucket, a galloping search of
    /// the times for where the bucket ends (O(log) in the bucket's size, so cheap for both few
    /// and many samples per bucket), then a tight min/max scan over its values alone, the
    /// sample's place and time looked up only for the winners.
    fn feed(&mut self, ts: &[f64], vs: &[f64], out: &mut Vec<[f64; 2]>) {
        let mut i = 0;
        while i < ts.len() {
            if ts[i] >= self.edge {
                self.flush(out);
                while ts[i] >= self.edge {
                    self.current += 1;
                    self.edge = self.edge_after(self.current);
                }
            }
            let mut j = i + 1;
            let edge = self.edge;
            let mut step = 1;
            while j + step < ts.len() && ts[j + step] < edge {
                j += step;
                step *= 2;
            }
            let hi = (j + step).min(ts.len());
            j += ts[j..hi].partition_point(|&t| t < edge);
            let (mut mn, mut mx) = (self.min.2, self.max.2);
            let (mut a, mut b) = (usize::MAX, usize::MAX);
            for (k, &v) in vs[i..j].iter().enumerate() {
                if v < mn {
                    mn = v;
                    a = k;
                }
                if v > mx {
                    mx = v;
                    b = k;
                }
            }
            if a != usize::MAX {
                self.min = (self.base + i + a, ts[i + a], mn);
            }
            if b != usize::MAX {
                self.max = (self.base + i + b, ts[i + b], mx);
            }
            i = j;
        }
        self.base += ts.len();
    }

    fn flush(&mut self, out: &mut Vec<[f64; 2]>) {
        let (mut min, mut max) = (self.min, self.max);
        (self.min, self.max) = (Self::EMPTY_MIN, Self::EMPTY_MAX);
        // Only ±∞ values: +∞ never beats the starting min, −∞ never the starting max.
        match (min.0, max.0) {
            (NONE, NONE) => return,
            (NONE, _) => min = max,
            (_, NONE) => max = min,
            _ => {}
        }
        let (first, second) = if min.0 <= max.0 {
            (min, max)
        } else {
            (max, min)
        };
        out.push([first.1, first.2]);
        if second.0 != first.0 {
            out.push([second.1, second.2]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn filled(n: usize) -> Series {
        let mut s = Series::new(n);
        for i in 0..n {
            s.push(i as f64, (i as f64).sin()).unwrap();
        }
        s
    }

    #[test]
    fn degenerate_inputs_give_empty_output_without_panic() {
        let mut out = vec![[9.0, 9.0]];
        Series::new(10).decimate(0.0, 1.0, 100, &mut out);
        assert!(out.is_empty());
        let s = filled(100);
        for (t0, t1, b) in [
            (0.0, 10.0, 0),
            (10.0, 0.0, 100),
            (f64::NAN, 10.0, 100),
            (0.0, f64::INFINITY, 100),
        ] {
            out.push([1.0, 1.0]);
            s.decimate(t0, t1, b, &mut out);
            assert!(out.is_empty(), "{t0} {t1} {b}");
        }
        assert_eq!(Series::new(4).value_at(1.0), None);
        assert_eq!(s.value_at(f64::NAN), None);
        assert_eq!(crate::series::SeriesSet::default().span(), None);
    }

    #[test]
    fn small_window_returns_exact_samples_plus_edges() {
        let s = filled(100);
        let mut out = Vec::new();
        // Window [10, 20] holds 11 samples < 2 × 6.
        s.decimate(10.0, 20.0, 6, &mut out);
        let want: Vec<[f64; 2]> = (9..=21).map(|i| [i as f64, (i as f64).sin()]).collect();
        assert_eq!(out, want);
        // Window before all data: only the right edge; after: only the left edge.
        s.decimate(-5.0, -1.0, 10, &mut out);
        assert_eq!(out, vec![[0.0, 0.0]]);
        s.decimate(200.0, 300.0, 10, &mut out);
        assert_eq!(out, vec![[99.0, 99f64.sin()]]);
        // A window between two samples: both edges only.
        s.decimate(10.2, 10.8, 10, &mut out);
        assert_eq!(out, vec![[10.0, 10f64.sin()], [11.0, 11f64.sin()]]);
    }

    #[test]
    fn buckets_emit_min_and_max_in_order_of_occurrence() {
        let mut s = Series::new(100);
        // Bucket 0 [0, 4): max first then min; bucket 1 [4, 8): min first then max.
        for (t, v) in [(0.0, 1.0), (1.0, 5.0), (2.0, -3.0), (3.0, 0.0)] {
            s.push(t, v).unwrap();
        }
        for (t, v) in [(4.0, 0.0), (5.0, -2.0), (6.0, 7.0), (7.0, 1.0)] {
            s.push(t, v).unwrap();
        }
        s.push(8.0, 2.0).unwrap();
        let mut out = Vec::new();
        s.decimate(0.0, 7.999, 2, &mut out);
        assert_eq!(
            out,
            vec![[1.0, 5.0], [2.0, -3.0], [5.0, -2.0], [6.0, 7.0], [8.0, 2.0]]
        );
    }

    #[test]
    fn decimation_skips_nan() {
        let mut s = Series::new(100);
        for i in 0..40 {
            let v = if i % 3 == 0 { f64::NAN } else { i as f64 };
            s.push(i as f64, v).unwrap();
        }
        let mut out = Vec::new();
        for (t0, t1, b) in [(0.0, 39.0, 2), (0.5, 38.5, 100), (3.0, 33.0, 5)] {
            s.decimate(t0, t1, b, &mut out);
            assert!(!out.is_empty());
            assert!(out.iter().all(|p| !p[1].is_nan()), "{out:?}");
        }
        // All-NaN window with NaN edges: nothing.
        let mut s = Series::new(10);
        for i in 0..10 {
            s.push(i as f64, f64::NAN).unwrap();
        }
        s.decimate(2.0, 8.0, 1, &mut out);
        assert!(out.is_empty());
    }

    #[test]
    fn decimation_across_the_ring_seam() {
        // After wrapping, the window straddles the two slices of the ring.
        let mut s = Series::new(100);
        for i in 0..150 {
            s.push(i as f64, (i % 7) as f64).unwrap();
        }
        let mut out = Vec::with_capacity(2 * 10 + 2);
        let cap = out.capacity();
        s.decimate(60.0, 140.0, 10, &mut out);
        assert!(out.len() <= 22);
        assert_eq!(out.capacity(), cap);
        assert_eq!(out.first(), Some(&[59.0, (59 % 7) as f64]));
        assert_eq!(out.last(), Some(&[141.0, (141 % 7) as f64]));
        assert!(out.windows(2).all(|w| w[0][0] < w[1][0]));
    }

    #[test]
    fn zero_width_window_is_one_bucket() {
        let mut s = Series::new(100);
        for i in 0..10 {
            s.push(1.0, i as f64).unwrap();
        }
        s.push(2.0, 0.0).unwrap();
        let mut out = Vec::new();
        s.decimate(1.0, 1.0, 2, &mut out);
        assert_eq!(out, vec![[1.0, 0.0], [1.0, 9.0], [2.0, 0.0]]);
    }
}
