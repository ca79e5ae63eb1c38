//! Bounded time series for live plots, independent of the UI.
//!
//! A [`Series`] is a ring buffer of `(t, v)` samples with a fixed capacity: its storage is
//! allocated once and never grows, so a recording that runs for hours keeps flat memory; pushing
//! past the capacity drops the oldest sample. Times are seconds (since the recording started) and
//! are kept non-decreasing, which lets a plot find its visible window by binary search and draw
//! it through [`Series::decimate`], a min/max decimation to one or two points per pixel column.
//!
//! A [`SeriesSet`] groups the named series of one plot (say `eulerX`, `eulerY`, `eulerZ`) and
//! exports them as CSV.
//!
//! Choices, documented once here:
//! - **Out-of-order times are clamped.** A sample whose time is earlier than the last one is
//!   accepted and stored at the end with the last time (the reading is fresher than anything
//!   stored, only its clock stepped back); [`Series::push`] reports it as [`Pushed::Clamped`].
//!   A non-finite time (NaN, ±∞) is rejected with [`Rejected::NonFiniteTime`].
//! - **NaN values are stored but never drawn.** A NaN value (a sensor's "no reading") stays in
//!   the buffer, is returned by [`Series::latest`] and [`SeriesSet::value_at`], and becomes an
//!   empty cell in CSV, but [`Series::decimate`] skips it: it takes part in no bucket's min/max,
//!   is left out of the pass-through of small windows and is not used as an edge sample. ±∞
//!   values are ordinary values.

use std::io::{self, Write};

/// Default capacity: 10 minutes at 100 Hz.
pub const DEFAULT_CAPACITY: usize = 60_000;

/// One sample: time in seconds and value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Seconds since the recording started.
    pub t: f64,
    /// The value; NaN means "no reading".
    pub v: f64,
}

/// How [`Series::push`] stored an accepted sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pushed {
    /// Stored with its own time.
    Appended,
    /// Its time was earlier than the last stored one; stored at the end with the last time.
    Clamped,
}

/// Why [`Series::push`] refused a sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum Rejected {
    /// The time was NaN or infinite, so it has no place in a time-sorted buffer.
    #[error("sample time is not finite")]
    NonFiniteTime,
}

/// A bounded ring buffer of time-sorted samples.
///
/// Times and values live in two separate fixed-size arrays (a struct-of-arrays ring), so the
/// decimation scan reads them as plain contiguous `f64` slices.
#[derive(Debug, Clone)]
pub struct Series {
    t: Vec<f64>,
    v: Vec<f64>,
    /// Physical index of the oldest sample.
    head: usize,
    len: usize,
}

impl Default for Series {
    fn default() -> Self {
        Self::new(DEFAULT_CAPACITY)
    }
}

impl Series {
    /// An empty series holding at most `capacity` samples (at least 1), allocated up front.
    pub fn new(capacity: usize) -> Self {
        let cap = capacity.max(1);
        Self {
            t: vec![0.0; cap],
            v: vec![0.0; cap],
            head: 0,
            len: 0,
        }
    }

    /// The most samples the series holds; older ones are dropped past it.
    pub fn capacity(&self) -> usize {
        self.t.len()
    }

    /// The capacity of the underlying allocation, in samples (at least [`Self::capacity`]); it
    /// does not change after construction.
    pub fn allocated(&self) -> usize {
        self.t.capacity().min(self.v.capacity())
    }

    /// The number of samples held.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether no sample is held.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Drops every sample, keeping the allocation.
    pub fn clear(&mut self) {
        self.head = 0;
        self.len = 0;
    }

    /// Appends a sample, dropping the oldest when full. An earlier time than the last is clamped
    /// to the last; a non-finite time is rejected (see the module notes).
    pub fn push(&mut self, t: f64, v: f64) -> Result<Pushed, Rejected> {
        if !t.is_finite() {
            return Err(Rejected::NonFiniteTime);
        }
        let (t, pushed) = match self.latest() {
            Some(last) if t < last.t => (last.t, Pushed::Clamped),
            _ => (t, Pushed::Appended),
        };
        let cap = self.capacity();
        let i = if self.len < cap {
            self.len += 1;
            self.phys(self.len - 1)
        } else {
            let i = self.head;
            self.head = if i + 1 == cap { 0 } else { i + 1 };
            i
        };
        self.t[i] = t;
        self.v[i] = v;
        Ok(pushed)
    }

    /// Physical index of logical index `i < len`.
    fn phys(&self, i: usize) -> usize {
        let p = self.head + i;
        if p >= self.capacity() {
            p - self.capacity()
        } else {
            p
        }
    }

    /// The physical ranges of logical `[from, to)`, oldest first (the second may be empty).
    fn ranges(&self, from: usize, to: usize) -> [std::ops::Range<usize>; 2] {
        let cap = self.capacity();
        let (a, b) = (self.head + from, self.head + to);
        if b <= cap {
            [a..b, 0..0]
        } else if a >= cap {
            [a - cap..b - cap, 0..0]
        } else {
            [a..cap, 0..b - cap]
        }
    }

    /// The number of oldest samples whose time satisfies `pred` (which must hold for a prefix).
    fn partition_point(&self, pred: impl Fn(f64) -> bool) -> usize {
        let [a, b] = self.ranges(0, self.len);
        let n = a.len();
        let i = self.t[a].partition_point(|&x| pred(x));
        if i < n {
            i
        } else {
            n + self.t[b].partition_point(|&x| pred(x))
        }
    }

    /// The sample at `index` (0 is the oldest held).
    pub fn get(&self, index: usize) -> Option<Sample> {
        (index < self.len).then(|| {
            let i = self.phys(index);
            Sample {
                t: self.t[i],
                v: self.v[i],
            }
        })
    }

    /// The oldest sample held.
    pub fn first(&self) -> Option<Sample> {
        self.get(0)
    }

    /// The newest sample.
    pub fn latest(&self) -> Option<Sample> {
        self.get(self.len.checked_sub(1)?)
    }

    /// The samples, oldest first.
    pub fn iter(&self) -> impl DoubleEndedIterator<Item = Sample> + '_ {
        let [a, b] = self.ranges(0, self.len);
        a.chain(b).map(|i| Sample {
            t: self.t[i],
            v: self.v[i],
        })
    }

    /// First and last time held.
    pub fn span(&self) -> Option<(f64, f64)> {
        Some((self.first()?.t, self.latest()?.t))
    }

    /// The sample nearest in time to `t` (the earlier one on a tie), NaN value or not; `None`
    /// when empty or `t` is NaN. O(log n).
    pub fn value_at(&self, t: f64) -> Option<Sample> {
        if t.is_nan() || self.is_empty() {
            return None;
        }
        let i = self.partition_point(|x| x < t);
        let after = self.get(i);
        let before = i.checked_sub(1).and_then(|j| self.get(j));
        match (before, after) {
            (Some(b), Some(a)) => Some(if a.t - t < t - b.t { a } else { b }),
            (b, a) => b.or(a),
        }
    }

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

/// The named series of one plot, in the order they were first pushed.
#[derive(Debug, Clone)]
pub struct SeriesSet {
    series: Vec<(String, Series)>,
    capacity: usize,
}

impl Default for SeriesSet {
    fn default() -> Self {
        Self::new(DEFAULT_CAPACITY)
    }
}

impl SeriesSet {
    /// An empty set whose series each hold at most `capacity` samples.
    pub fn new(capacity: usize) -> Self {
        Self {
            series: Vec::new(),
            capacity,
        }
    }

    /// Appends a sample to the series `name`, creating it (allocated up front) on first use.
    /// See [`Series::push`].
    pub fn push(&mut self, name: &str, t: f64, v: f64) -> Result<Pushed, Rejected> {
        let i = match self.series.iter().position(|(n, _)| n == name) {
            Some(i) => i,
            None => {
                self.series
                    .push((name.to_owned(), Series::new(self.capacity)));
                self.series.len() - 1
            }
        };
        self.series[i].1.push(t, v)
    }

    /// Drops every sample of every series, keeping the names and the allocations.
    pub fn clear(&mut self) {
        for (_, s) in &mut self.series {
            s.clear();
        }
    }

    /// The series `name`.
    pub fn get(&self, name: &str) -> Option<&Series> {
        self.series.iter().find(|(n, _)| n == name).map(|(_, s)| s)
    }

    /// The names and series, in the order they were first pushed.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = (&str, &Series)> + '_ {
        self.series.iter().map(|(n, s)| (n.as_str(), s))
    }

    /// The number of series.
    pub fn len(&self) -> usize {
        self.series.len()
    }

    /// Whether the set has no series.
    pub fn is_empty(&self) -> bool {
        self.series.is_empty()
    }

    /// The newest sample of `name`.
    pub fn latest(&self, name: &str) -> Option<Sample> {
        self.get(name)?.latest()
    }

    /// The sample of `name` nearest in time to `t`, for a cursor readout; see
    /// [`Series::value_at`].
    pub fn value_at(&self, name: &str, t: f64) -> Option<Sample> {
        self.get(name)?.value_at(t)
    }

    /// The earliest and latest time over all series; `None` when all are empty.
    pub fn span(&self) -> Option<(f64, f64)> {
        self.series
            .iter()
            .filter_map(|(_, s)| s.span())
            .reduce(|(a0, a1), (b0, b1)| (a0.min(b0), a1.max(b1)))
    }

    /// Writes the set as CSV: a header `t,<name1>,<name2>,...` (names quoted when they hold a
    /// comma, quote or line break), then one row per distinct time in increasing order, the time
    /// in seconds with three decimals (the samples' own times, seconds since the recording
    /// started). Times are compared at that millisecond precision: the samples of all series
    /// that fall on the same millisecond share a row, with empty cells for series that have no
    /// sample there. A series with several samples in one millisecond puts each on its own row
    /// (same time), so nothing is lost. Values are written in Rust's shortest round-trip form;
    /// NaN values as empty cells.
    ///
    /// Writes one row at a time; wrap a file in a [`std::io::BufWriter`].
    pub fn write_csv(&self, w: &mut impl Write) -> io::Result<()> {
        let mut line = String::from("t");
        for (name, _) in &self.series {
            line.push(',');
            push_csv_field(&mut line, name);
        }
        line.push('\n');
        w.write_all(line.as_bytes())?;

        let mut iters: Vec<_> = self
            .series
            .iter()
            .map(|(_, s)| s.iter().peekable())
            .collect();
        loop {
            let Some(key) = iters
                .iter_mut()
                .filter_map(|it| it.peek().map(|s| ms(s.t)))
                .min()
            else {
                return Ok(());
            };
            line.clear();
            push_ms(&mut line, key);
            for it in &mut iters {
                line.push(',');
                if let Some(s) = it.next_if(|s| ms(s.t) == key)
                    && !s.v.is_nan()
                {
                    use std::fmt::Write as _;
                    let _ = write!(line, "{}", s.v);
                }
            }
            line.push('\n');
            w.write_all(line.as_bytes())?;
        }
    }
}

/// A time in whole milliseconds (saturating far outside any recording).
fn ms(t: f64) -> i64 {
    (t * 1000.0).round() as i64
}

/// Writes a millisecond count as seconds with three decimals, exactly.
fn push_ms(line: &mut String, ms: i64) {
    use std::fmt::Write as _;
    let sign = if ms < 0 { "-" } else { "" };
    let abs = ms.unsigned_abs();
    let _ = write!(line, "{sign}{}.{:03}", abs / 1000, abs % 1000);
}

fn push_csv_field(line: &mut String, field: &str) {
    if field.contains([',', '"', '\n', '\r']) {
        line.push('"');
        line.push_str(&field.replace('"', "\"\""));
        line.push('"');
    } else {
        line.push_str(field);
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
    fn capacity_holds_and_memory_stays_flat() {
        let mut s = Series::new(1000);
        let alloc = s.allocated();
        assert!(alloc >= 1000);
        for i in 0..10_000 {
            s.push(i as f64 * 0.01, i as f64).unwrap();
            assert!(s.len() <= 1000);
        }
        assert_eq!(s.len(), 1000);
        assert_eq!(s.capacity(), 1000);
        assert_eq!(s.allocated(), alloc);
        assert_eq!(s.first().unwrap().v, 9000.0);
        assert_eq!(s.latest().unwrap().v, 9999.0);
    }

    #[test]
    fn zero_capacity_holds_one() {
        let mut s = Series::new(0);
        s.push(1.0, 1.0).unwrap();
        s.push(2.0, 2.0).unwrap();
        assert_eq!(s.len(), 1);
        assert_eq!(s.latest(), Some(Sample { t: 2.0, v: 2.0 }));
    }

    #[test]
    fn earlier_time_is_clamped_and_non_finite_rejected() {
        let mut s = Series::new(10);
        assert_eq!(s.push(5.0, 1.0), Ok(Pushed::Appended));
        assert_eq!(s.push(5.0, 2.0), Ok(Pushed::Appended));
        assert_eq!(s.push(4.0, 3.0), Ok(Pushed::Clamped));
        assert_eq!(s.latest(), Some(Sample { t: 5.0, v: 3.0 }));
        assert_eq!(s.push(f64::NAN, 0.0), Err(Rejected::NonFiniteTime));
        assert_eq!(s.push(f64::INFINITY, 0.0), Err(Rejected::NonFiniteTime));
        assert_eq!(s.len(), 3);
        assert_eq!(s.push(6.0, f64::NAN), Ok(Pushed::Appended));
        assert!(s.latest().unwrap().v.is_nan());
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
        assert_eq!(SeriesSet::default().span(), None);
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

    #[test]
    fn value_at_picks_nearest() {
        let mut s = Series::new(10);
        for t in [1.0, 2.0, 4.0] {
            s.push(t, t * 10.0).unwrap();
        }
        let v = |t| s.value_at(t).unwrap().v;
        assert_eq!(v(-3.0), 10.0);
        assert_eq!(v(1.4), 10.0);
        assert_eq!(v(1.5), 10.0); // tie: the earlier
        assert_eq!(v(1.6), 20.0);
        assert_eq!(v(3.1), 40.0);
        assert_eq!(v(2.9), 20.0);
        assert_eq!(v(100.0), 40.0);
    }

    #[test]
    fn set_groups_named_series() {
        let mut set = SeriesSet::new(100);
        set.push("eulerX", 0.5, 1.0).unwrap();
        set.push("eulerY", 0.2, 2.0).unwrap();
        set.push("eulerX", 1.5, 3.0).unwrap();
        assert_eq!(set.len(), 2);
        assert_eq!(
            set.iter().map(|(n, _)| n).collect::<Vec<_>>(),
            ["eulerX", "eulerY"]
        );
        assert_eq!(set.latest("eulerX"), Some(Sample { t: 1.5, v: 3.0 }));
        assert_eq!(set.latest("nope"), None);
        assert_eq!(set.value_at("eulerX", 1.2).unwrap().v, 3.0);
        assert_eq!(set.span(), Some((0.2, 1.5)));
        set.clear();
        assert_eq!(set.len(), 2);
        assert_eq!(set.span(), None);
        assert_eq!(
            set.get("eulerX").unwrap().allocated(),
            Series::new(100).allocated()
        );
    }

    #[test]
    fn csv_rows_merge_same_millisecond() {
        let mut set = SeriesSet::new(100);
        set.push("a", 0.0, 1.0).unwrap();
        set.push("b,\"c\"", 0.0004, 2.0).unwrap();
        set.push("a", 0.01, f64::NAN).unwrap();
        set.push("b,\"c\"", 0.02, -0.5).unwrap();
        set.push("b,\"c\"", 0.0201, 3.0).unwrap();
        let mut out = Vec::new();
        set.write_csv(&mut out).unwrap();
        assert_eq!(
            String::from_utf8(out).unwrap(),
            "t,a,\"b,\"\"c\"\"\"\n0.000,1,2\n0.010,,\n0.020,,-0.5\n0.020,,3\n"
        );
        let mut out = Vec::new();
        SeriesSet::default().write_csv(&mut out).unwrap();
        assert_eq!(out, b"t\n");
    }

    #[test]
    fn ms_formatting() {
        let mut s = String::new();
        for m in [0, 1, 999, 1000, 123_456, -1, -1500] {
            push_ms(&mut s, m);
            s.push(' ');
        }
        assert_eq!(s, "0.000 0.001 0.999 1.000 123.456 -0.001 -1.500 ");
    }
}
