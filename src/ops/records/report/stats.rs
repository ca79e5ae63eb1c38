//! The arithmetic of the report, apart from any database: shifts, mean and sigma from sums,
//! Cpk, and the drift rule.

use serde::Serialize;

/// The shifts of a day: their local start times (minutes after midnight, ascending) and names.
/// Default: three 8-hour shifts, A from 06:00, B from 14:00, C from 22:00 (until 06:00 the next
/// day, and counted on the day it started).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Shifts {
    /// Start of each shift, minutes after local midnight, ascending.
    pub starts: Vec<u32>,
}

impl Default for Shifts {
    fn default() -> Self {
        Shifts {
            starts: vec![6 * 60, 14 * 60, 22 * 60],
        }
    }
}

impl Shifts {
    /// Reads `06:00,14:00,22:00`: one to six start times, each `HH:MM`, distinct. Shifts are
    /// named A, B, C... from the first.
    pub fn parse(text: &str) -> Result<Shifts, String> {
        let mut starts = Vec::new();
        for part in text.split(',') {
            let p = part.trim();
            let (h, m) = p
                .split_once(':')
                .and_then(|(h, m)| Some((h.parse::<u32>().ok()?, m.parse::<u32>().ok()?)))
                .filter(|(h, m)| *h < 24 && *m < 60)
                .ok_or_else(|| {
                    format!("shift start '{p}' is not a time of day HH:MM (00:00 to 23:59)")
                })?;
            starts.push(h * 60 + m);
        }
        starts.sort_unstable();
        starts.dedup();
        if starts.is_empty() || starts.len() > 6 {
            return Err("give one to six shift starts, e.g. 06:00,14:00,22:00".into());
        }
        Ok(Shifts { starts })
    }

    /// The shift's name: `A`, `B`, ...
    pub fn name(&self, index: usize) -> String {
        char::from(b'A' + (index % 26) as u8).to_string()
    }

    /// `A 06:00-14:00, B 14:00-22:00, C 22:00-06:00`.
    pub fn describe(&self) -> String {
        let hm = |m: u32| format!("{:02}:{:02}", m / 60, m % 60);
        (0..self.starts.len())
            .map(|i| {
                let end = self.starts[(i + 1) % self.starts.len()];
                format!("{} {}-{}", self.name(i), hm(self.starts[i]), hm(end))
            })
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The shift a run belongs to, as `day * 10 + index` where `day` counts days since
    /// 1970-01-01 from the first shift's start: SQL computes the same key (see
    /// [`Shifts::sql_key`]). `local_min` is the run's local time in minutes since 1970.
    pub fn key(&self, local_min: i64) -> i64 {
        let first = i64::from(self.starts[0]);
        let rel = local_min - first;
        let day = rel.div_euclid(1440);
        let m = rel.rem_euclid(1440);
        let index = self
            .starts
            .iter()
            .rposition(|&s| i64::from(s) - first <= m)
            .unwrap_or(0) as i64;
        day * 10 + index
    }

    /// The SQL expression of [`Shifts::key`] over `runs` aliased `r` (times after 1970).
    pub fn sql_key(&self) -> String {
        let first = i64::from(self.starts[0]);
        let rel = format!("(r.started_ms / 60000 + r.utc_offset_min - {first})");
        let mut case = String::from("CASE");
        for (i, s) in self.starts.iter().enumerate().skip(1).rev() {
            case.push_str(&format!(
                " WHEN {rel} % 1440 >= {} THEN {i}",
                i64::from(*s) - first
            ));
        }
        case.push_str(" ELSE 0 END");
        format!("(({rel} / 1440) * 10 + {case})")
    }

    /// `2026-12-01 A` for a key.
    pub fn label(&self, key: i64) -> String {
        let day = key.div_euclid(10);
        let index = key.rem_euclid(10) as usize;
        let date = chrono::NaiveDate::from_ymd_opt(1970, 1, 1)
            .and_then(|d| d.checked_add_signed(chrono::TimeDelta::days(day)))
            .map(|d| d.format("%Y-%m-%d").to_string())
            .unwrap_or_else(|| day.to_string());
        format!("{date} {}", self.name(index))
    }
}

/// Mean and sample standard deviation from a count, a sum and a sum of squares.
pub fn mean_sigma(n: u64, sum: f64, sum_sq: f64) -> (f64, f64) {
    if n == 0 {
        return (f64::NAN, f64::NAN);
    }
    let nf = n as f64;
    let mean = sum / nf;
    if n < 2 {
        return (mean, 0.0);
    }
    let var = ((sum_sq - nf * mean * mean) / (nf - 1.0)).max(0.0);
    (mean, var.sqrt())
}

/// Cpk: the distance from the mean to the nearer limit in units of 3 sigma (one-sided with one
/// limit); `None` with no limit or no spread.
pub fn cpk(mean: f64, sigma: f64, low: Option<f64>, high: Option<f64>) -> Option<f64> {
    if sigma.is_nan() || sigma <= 0.0 || !mean.is_finite() {
        return None;
    }
    let upper = high.map(|h| (h - mean) / (3.0 * sigma));
    let lower = low.map(|l| (mean - l) / (3.0 * sigma));
    match (lower, upper) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

/// A measurement walking toward a limit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Drift {
    /// The means of the last three windows of `window` units each, oldest first.
    pub means: [f64; 3],
    /// Units per window.
    pub window: usize,
    /// `high` or `low`: the limit walked toward.
    pub toward: &'static str,
    /// That limit.
    pub limit: f64,
    /// How far the mean moved over the windows, in sigmas of the whole period.
    pub moved_sigma: f64,
    /// How far the newest window's mean still is from the limit, in sigmas.
    pub left_sigma: f64,
}

/// The smallest move, in sigmas, that the drift rule reports.
pub const DRIFT_MIN_SIGMA: f64 = 0.5;

/// The drift rule: over `newest_last` (values in the order the units were tested, the last `3 * window`
/// at least), the means of the last three windows of `window` units each move the same way,
/// toward a limit on that side, by at least [`DRIFT_MIN_SIGMA`] sigmas in all. `None` when they
/// do not, or when there are fewer than `3 * window` values or no limit on that side.
pub fn drift(
    newest_last: &[f64],
    window: usize,
    sigma: f64,
    low: Option<f64>,
    high: Option<f64>,
) -> Option<Drift> {
    if window == 0 || newest_last.len() < 3 * window || sigma.is_nan() || sigma <= 0.0 {
        return None;
    }
    let tail = &newest_last[newest_last.len() - 3 * window..];
    let mean = |s: &[f64]| s.iter().sum::<f64>() / s.len() as f64;
    let m = [
        mean(&tail[..window]),
        mean(&tail[window..2 * window]),
        mean(&tail[2 * window..]),
    ];
    let moved = m[2] - m[0];
    let (toward, limit) = if m[0] < m[1] && m[1] < m[2] {
        ("high", high?)
    } else if m[0] > m[1] && m[1] > m[2] {
        ("low", low?)
    } else {
        return None;
    };
    let moved_sigma = moved.abs() / sigma;
    if moved_sigma < DRIFT_MIN_SIGMA {
        return None;
    }
    Some(Drift {
        means: m,
        window,
        toward,
        limit,
        moved_sigma,
        left_sigma: (limit - m[2]).abs() / sigma,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shift_keys_split_the_day_at_the_starts_and_night_counts_on_its_first_day() {
        let s = Shifts::default();
        // 2026-12-01 is day 20788 since 1970-01-01.
        let day = 20788i64;
        let at = |d: i64, h: i64, m: i64| d * 1440 + h * 60 + m;
        assert_eq!(s.key(at(day, 6, 0)), day * 10);
        assert_eq!(s.key(at(day, 13, 59)), day * 10);
        assert_eq!(s.key(at(day, 14, 0)), day * 10 + 1);
        assert_eq!(s.key(at(day, 22, 30)), day * 10 + 2);
        // 03:00 the next day is still the night shift that began the day before.
        assert_eq!(s.key(at(day + 1, 3, 0)), day * 10 + 2);
        assert_eq!(s.label(day * 10 + 2), "2026-12-01 C");
        assert_eq!(s.describe(), "A 06:00-14:00, B 14:00-22:00, C 22:00-06:00");
    }

    #[test]
    fn cpk_of_a_centred_process_with_limits_at_four_sigma_is_four_thirds() {
        let c = cpk(10.0, 0.5, Some(8.0), Some(12.0)).unwrap_or_default();
        assert!((c - 4.0 / 3.0).abs() < 1e-12);
        let one_sided = cpk(10.0, 0.5, None, Some(11.5)).unwrap_or_default();
        assert!((one_sided - 1.0).abs() < 1e-12);
        assert_eq!(cpk(10.0, 0.0, Some(8.0), None), None);
    }

    #[test]
    fn mean_and_sigma_from_sums() {
        // 2, 4, 4, 4, 5, 5, 7, 9: mean 5, sample sigma sqrt(32/7).
        let v = [2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0];
        let (m, s) = mean_sigma(8, v.iter().sum(), v.iter().map(|x| x * x).sum());
        assert!((m - 5.0).abs() < 1e-12);
        assert!((s - (32.0f64 / 7.0).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn drift_needs_three_windows_moving_one_way_by_half_a_sigma() {
        let w = 4;
        let walk: Vec<f64> = [vec![10.0; 4], vec![10.3; 4], vec![10.6; 4]].concat();
        let d = drift(&walk, w, 1.0, Some(8.0), Some(12.0));
        let d = d.unwrap_or_else(|| panic!("no drift in {walk:?}"));
        assert_eq!(d.toward, "high");
        assert!((d.moved_sigma - 0.6).abs() < 1e-9);
        assert!((d.left_sigma - 1.4).abs() < 1e-9);
        // Too small a move, not monotonic, too few values, or no limit on that side.
        let small: Vec<f64> = [vec![10.0; 4], vec![10.1; 4], vec![10.2; 4]].concat();
        assert_eq!(drift(&small, w, 1.0, Some(8.0), Some(12.0)), None);
        let zigzag: Vec<f64> = [vec![10.0; 4], vec![10.9; 4], vec![10.6; 4]].concat();
        assert_eq!(drift(&zigzag, w, 1.0, Some(8.0), Some(12.0)), None);
        assert_eq!(drift(&walk[1..], w, 1.0, Some(8.0), Some(12.0)), None);
        assert_eq!(drift(&walk, w, 1.0, Some(8.0), None), None);
    }
}
