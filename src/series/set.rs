//! The named series of one plot, and their CSV export.

use super::{DEFAULT_CAPACITY, Pushed, Rejected, Sample, Series};
use std::io::{self, Write};

/// The named series of one plot, in the order they were first pushed.
#[derive(Debug, Clone)]
pub struct SeriesSet {
    series: Vec<(String, Series)>,
    capacity: usize,
    /// Times of gaps in the recording, oldest first (see [`SeriesSet::mark_break`]).
    pub(super) breaks: std::collections::VecDeque<f64>,
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
            breaks: std::collections::VecDeque::new(),
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

    /// Drops every sample of every series (and every break), keeping the names and the
    /// allocations.
    pub fn clear(&mut self) {
        for (_, s) in &mut self.series {
            s.clear();
        }
        self.breaks.clear();
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
    /// Written with the `csv` crate, which quotes what needs quoting and buffers the rows.
    pub fn write_csv(&self, w: &mut impl Write) -> io::Result<()> {
        self.write_csv_as(w, &CsvFormat::default())
    }

    /// [`Self::write_csv`] as `format` says: with a first column `time` of wall-clock times
    /// (local, RFC 3339 with milliseconds) when it gives the recording's start, and each series'
    /// values at its decimals where it gives them (a field's precision: `14.7`, never the
    /// binary float's `14.700000000000001`).
    pub fn write_csv_as(&self, w: &mut impl Write, format: &CsvFormat) -> io::Result<()> {
        use std::fmt::Write as _;
        let mut out = csv::Writer::from_writer(w);
        let head = format.start.map(|_| "time").into_iter().chain(["t"]);
        out.write_record(head.chain(self.series.iter().map(|(n, _)| n.as_str())))?;
        let mut iters: Vec<_> = self
            .series
            .iter()
            .map(|(_, s)| s.iter().peekable())
            .collect();
        let mut cell = String::new();
        while let Some(key) = iters
            .iter_mut()
            .filter_map(|it| it.peek().map(|s| ms(s.t)))
            .min()
        {
            if let Some(start) = format.start {
                out.write_field(wall_clock(start, key))?;
            }
            cell.clear();
            push_ms(&mut cell, key);
            out.write_field(&cell)?;
            for (i, it) in iters.iter_mut().enumerate() {
                cell.clear();
                if let Some(s) = it.next_if(|s| ms(s.t) == key)
                    && !s.v.is_nan()
                {
                    let _ = match format.decimals.get(i).copied().flatten() {
                        Some(d) => write!(cell, "{:.*}", d, s.v),
                        None => write!(cell, "{}", s.v),
                    };
                }
                out.write_field(&cell)?;
            }
            out.write_record(None::<&[u8]>)?;
        }
        out.flush()
    }
}

/// How [`SeriesSet::write_csv_as`] writes a recording.
#[derive(Debug, Clone, Default)]
pub struct CsvFormat {
    /// The wall-clock time of t = 0: a `time` column of absolute times when given.
    pub start: Option<std::time::SystemTime>,
    /// Each series' decimals, in the set's order (`None`: the shortest round-trip form).
    pub decimals: Vec<Option<usize>>,
}

/// `start` plus `ms` milliseconds as local RFC 3339 time with milliseconds.
fn wall_clock(start: std::time::SystemTime, ms: i64) -> String {
    let offset = std::time::Duration::from_millis(ms.unsigned_abs());
    let at = if ms < 0 {
        start.checked_sub(offset)
    } else {
        start.checked_add(offset)
    };
    at.map(|t| {
        chrono::DateTime::<chrono::Local>::from(t)
            .format("%Y-%m-%dT%H:%M:%S%.3f%:z")
            .to_string()
    })
    .unwrap_or_default()
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 25, item 10: values at the field's precision and absolute time.
    #[test]
    fn csv_values_at_the_fields_precision_with_wall_clock_time() {
        let mut set = SeriesSet::new(10);
        set.push("voltage", 0.25, 147.0 * 0.1).unwrap();
        set.push("count", 0.25, 3.0).unwrap();
        let start = std::time::UNIX_EPOCH + std::time::Duration::from_secs(1_700_000_000);
        let format = CsvFormat {
            start: Some(start),
            decimals: vec![Some(1), None],
        };
        let mut out = Vec::new();
        set.write_csv_as(&mut out, &format).unwrap();
        let text = String::from_utf8(out).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some("time,t,voltage,count"));
        let row: Vec<&str> = lines.next().unwrap().split(',').collect();
        let at =
            chrono::DateTime::<chrono::Local>::from(start + std::time::Duration::from_millis(250));
        assert_eq!(row[0], at.format("%Y-%m-%dT%H:%M:%S%.3f%:z").to_string());
        assert_eq!(&row[1..], ["0.250", "14.7", "3"]);
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
