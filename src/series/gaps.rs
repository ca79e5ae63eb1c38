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
