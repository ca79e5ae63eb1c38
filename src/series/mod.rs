//! Bounded time series for live plots, independent of the UI.
//!
//! A [`Series`] is a ring buffer of `(t, v)` samples with a fixed capacity: its storage is
//! allocated once and never grows, so a recording that runs for hours keeps flat memory; pushing
//! past the capacity drops the oldest sample. Times are seconds (since the recording started) and
//! are kept non-decreasing, which lets a plot find its visible window by binary search and draw
//! it through [`Series::decimate`], a min/max decimation to one or two points per pixel column.
//!
//! A [`SeriesSet`] groups the named series of one plot (say `eulerX`, `eulerY`, `eulerZ`) and
//! exports them as CSV. It also keeps the times of gaps in the recording (a link outage, a
//! failed poll, polling paused): a plot draws each unbroken stretch as its own line
//! ([`SeriesSet::decimate_segments`]), so no straight line stands in for what was not
//! measured.
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

mod decimate;
mod gaps;
mod set;

pub use gaps::{Pace, SLOW_POLL_FACTOR, SLOW_POLL_MIN};
pub use set::{CsvFormat, SeriesSet};

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

    /// Samples a second over the newest `over` seconds held (counted between the first and the
    /// last sample in that stretch): what a poll achieves, beside what it asked for. `None`
    /// with fewer than two samples in it.
    pub fn rate(&self, over: f64) -> Option<f64> {
        let last = self.latest()?.t;
        let from = self.partition_point(|x| x < last - over);
        let first = self.get(from)?.t;
        let n = self.len - from;
        (n >= 2 && last > first).then(|| (n - 1) as f64 / (last - first))
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
}

#[cfg(test)]
mod rate_tests {
    use super::Series;

    #[test]
    fn the_rate_counts_the_newest_stretch_only() {
        let mut s = Series::new(1000);
        assert_eq!(s.rate(2.0), None);
        // 10 Hz for 10 s, then 2 Hz for the last 3 s.
        for i in 0..100 {
            s.push(f64::from(i) * 0.1, 0.0).unwrap();
        }
        assert_eq!(s.rate(0.0), None, "one sample is no rate");
        let r = s.rate(2.0).unwrap();
        assert!((r - 10.0).abs() < 1e-6, "{r}");
        for i in 1..=6 {
            s.push(9.9 + f64::from(i) * 0.5, 0.0).unwrap();
        }
        let r = s.rate(2.0).unwrap();
        assert!((r - 2.0).abs() < 1e-6, "{r}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
