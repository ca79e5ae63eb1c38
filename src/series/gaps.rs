//! Gaps in a recording: times at which nothing was measured (the link was lost, a poll failed,
//! polling was paused), and the decimation of each unbroken stretch on its own, so that a plot
//! never joins the last sample before a gap to the first after it.

use super::SeriesSet;

/// The most gap times kept; the oldest go first.
pub const BREAKS_CAPACITY: usize = 4096;

impl SeriesSet {
    /// Marks a gap at time `t`: no line joins a sample before it to a sample after it. A time
    /// earlier than the last gap's is taken as the last gap's (times never go back); gaps older
    /// than every sample held, and beyond [`BREAKS_CAPACITY`], are forgotten. A non-finite time
    /// is ignored.
    pub fn mark_break(&mut self, t: f64) {
        if !t.is_finite() {
            return;
        }
        let t = self.breaks.back().map_or(t, |last| t.max(*last));
        if self.breaks.back() == Some(&t) {
            return;
        }
        self.breaks.push_back(t);
        let oldest = self.span().map(|s| s.0);
        while self.breaks.len() > BREAKS_CAPACITY
            || self
                .breaks
                .front()
                .is_some_and(|b| oldest.is_some_and(|o| *b < o))
        {
            self.breaks.pop_front();
        }
    }

    /// The gap times, oldest first.
    pub fn breaks(&self) -> impl Iterator<Item = f64> + '_ {
        self.breaks.iter().copied()
    }

    /// [`super::Series::decimate`] of series `name` over `[t0, t1]` into about `buckets`
    /// columns, one unbroken stretch at a time: `out` gets every stretch's points in time order,
    /// and `starts` the index in `out` where each stretch begins (empty stretches are left
    /// out). A stretch's points never cross a gap, the edge samples just outside the window
    /// included. Empty when the series does not exist or the window is empty.
    pub fn decimate_segments(
        &self,
        name: &str,
        t0: f64,
        t1: f64,
        buckets: usize,
        out: &mut Vec<[f64; 2]>,
        starts: &mut Vec<usize>,
    ) {
        out.clear();
        starts.clear();
        let Some(series) = self.get(name) else {
            return;
        };
        // A NaN bound, or bounds the wrong way round, select nothing.
        if t0.partial_cmp(&t1).is_none_or(|o| o.is_gt()) || buckets == 0 {
            return;
        }
        // The stretches: [t0, b1], [b1, b2], ..., [bk, t1] for the gaps strictly inside.
        let inside: Vec<f64> = self.breaks().filter(|b| *b > t0 && *b < t1).collect();
        let mut edges = Vec::with_capacity(inside.len() + 2);
        edges.push(t0);
        edges.extend(&inside);
        edges.push(t1);
        let span = (t1 - t0).max(f64::MIN_POSITIVE);
        let mut piece = Vec::new();
        for w in edges.windows(2) {
            let (a, c) = (w[0], w[1]);
            // The nearest gaps around the stretch, those outside the window included.
            let left = self.breaks().filter(|b| *b <= a).last();
            let right = self.breaks().find(|b| *b >= c);
            let n = ((buckets as f64 * (c - a) / span).ceil() as usize).max(1);
            series.decimate(a, c, n, &mut piece);
            let start = out.len();
            out.extend(
                piece
                    .iter()
                    .filter(|p| left.is_none_or(|l| p[0] >= l) && right.is_none_or(|r| p[0] <= r)),
            );
            if out.len() > start {
                starts.push(start);
            }
        }
    }
}

/// A poll later than this many times the plot's usual interval is a gap.
pub const SLOW_POLL_FACTOR: f64 = 3.0;
/// ... and later than this, seconds (a fast poll's jitter is not a gap).
pub const SLOW_POLL_MIN: f64 = 0.25;

/// The pace of a polled plot: its usual interval between samples, learned as they come, so
/// that a poll slower than expected (a busy device, a bad adapter, a host that ran late) is
/// drawn as a gap, never as a straight line over a time nothing was measured.
#[derive(Debug, Clone, Copy, Default)]
pub struct Pace {
    /// The last sample's time, seconds.
    last: Option<f64>,
    /// The usual interval, seconds (an exponential average: slow samples move it faster, so
    /// that a new poll rate is learned within a sample or two).
    usual: Option<f64>,
}

impl Pace {
    /// A sample at `t`, seconds: where a gap goes before it (half-way from the last sample),
    /// when it came more than [`SLOW_POLL_FACTOR`] times the usual interval (and more than
    /// [`SLOW_POLL_MIN`]) after the last one.
    pub fn sample(&mut self, t: f64) -> Option<f64> {
        let last = self.last.replace(t)?;
        let dt = t - last;
        // Not later (or not a number): no interval to learn from.
        if dt.is_nan() || dt <= 0.0 {
            return None;
        }
        let slow = self
            .usual
            .is_some_and(|u| dt > (u * SLOW_POLL_FACTOR).max(SLOW_POLL_MIN));
        let weight = if slow { 0.3 } else { 0.1 };
        self.usual = Some(self.usual.map_or(dt, |u| u + (dt - u) * weight));
        slow.then_some(last + dt / 2.0)
    }

    /// Forgets the pace (polling restarted at another rate, or paused).
    pub fn reset(&mut self) {
        *self = Self::default();
    }
}

#[cfg(test)]
mod pace_tests {
    use super::Pace;

    #[test]
    fn a_poll_slower_than_usual_is_a_gap_and_a_new_rate_is_learned() {
        let mut p = Pace::default();
        let mut t = 0.0;
        for _ in 0..50 {
            assert_eq!(p.sample(t), None, "at 50 Hz, t {t}");
            t += 0.02;
        }
        // One poll took 400 ms: a gap half-way.
        let last = t - 0.02;
        t = last + 0.4;
        assert_eq!(p.sample(t), Some(last + 0.2));
        // 50 Hz again: no gap.
        for _ in 0..5 {
            t += 0.02;
            assert_eq!(p.sample(t), None);
        }
        // Jitter under SLOW_POLL_MIN is never a gap.
        t += 0.2;
        assert_eq!(p.sample(t), None);
        // Down to 1 Hz: one gap at the change, then the new rate is the usual one.
        let mut gaps = 0;
        for _ in 0..10 {
            t += 1.0;
            gaps += usize::from(p.sample(t).is_some());
        }
        assert!(gaps <= 2, "{gaps} gaps at a steady 1 Hz");
        t += 1.0;
        assert_eq!(p.sample(t), None, "1 Hz is the usual rate now");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn segments(set: &SeriesSet, t0: f64, t1: f64) -> Vec<Vec<f64>> {
        let (mut out, mut starts) = (Vec::new(), Vec::new());
        set.decimate_segments("x", t0, t1, 100, &mut out, &mut starts);
        let mut ends = starts.clone();
        ends.remove(0);
        ends.push(out.len());
        starts
            .iter()
            .zip(ends)
            .map(|(s, e)| out[*s..e].iter().map(|p| p[0]).collect())
            .collect()
    }

    #[test]
    fn a_gap_breaks_the_line_and_no_point_crosses_it() {
        let mut set = SeriesSet::new(1000);
        for i in 0..10 {
            set.push("x", f64::from(i), 1.0).unwrap();
        }
        set.mark_break(9.5);
        for i in 20..30 {
            set.push("x", f64::from(i), 2.0).unwrap();
        }
        // Inside the window: two stretches, and neither reaches across.
        assert_eq!(
            segments(&set, 0.0, 29.0),
            [
                (0..10).map(f64::from).collect::<Vec<_>>(),
                (20..30).map(f64::from).collect::<Vec<_>>()
            ]
        );
        // The gap left of the window: the edge sample before it is not joined in.
        assert_eq!(
            segments(&set, 21.0, 25.0),
            [vec![20.0, 21.0, 22.0, 23.0, 24.0, 25.0, 26.0]]
        );
        assert_eq!(segments(&set, 12.0, 19.0), [vec![20.0]]);
        // No gap: one stretch, edge samples included.
        assert_eq!(segments(&set, 2.0, 4.0), [vec![1.0, 2.0, 3.0, 4.0, 5.0]]);
    }

    #[test]
    fn gaps_are_kept_in_order_and_dropped_with_the_samples() {
        let mut set = SeriesSet::new(5);
        set.mark_break(f64::NAN);
        set.mark_break(3.0);
        set.mark_break(2.0);
        assert_eq!(set.breaks().collect::<Vec<_>>(), [3.0]);
        for i in 0..20 {
            set.push("x", f64::from(i), 0.0).unwrap();
        }
        set.mark_break(20.5);
        assert_eq!(
            set.breaks().collect::<Vec<_>>(),
            [20.5],
            "3.0 is older than every sample"
        );
        set.clear();
        assert_eq!(set.breaks().count(), 0);
    }
}
