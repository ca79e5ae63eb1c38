//! `botbench report`: yield, failure causes and measurement capability over a period, computed
//! in the database (the same SQL on SQLite and PostgreSQL) so that a million step records take
//! a few aggregate scans, not a million rows sent to botbench.
//!
//! Definitions (the README says them too):
//! - a **unit** is a device kind's serial number (`profile:serial`); a run without a serial is
//!   a unit of its own;
//! - a unit belongs to the shift, station, slot and plan version of its **first run in the
//!   period**; its **first-pass yield** counts it as passed when that first run passed, its
//!   **final yield** when its last run in the period passed (retests included);
//! - **shifts** are local times of the PC that made the run ([`Shifts`], default A 06:00-14:00,
//!   B 14:00-22:00, C 22:00-06:00, the night counted on the day it began);
//! - the **Pareto** counts every failed step (a self-test goes on after a failed step, so one
//!   unit can fail several), by step and by reason;
//! - each **measurement** (same name, unit and limits) gets its count, mean, sample sigma, Cpk
//!   and a histogram, and a **drift** warning when the means of its last three windows of N
//!   units each (in the order recorded) move the same way toward a limit by at least half a
//!   sigma in all.

pub mod html;
pub mod stats;

pub use stats::{Drift, Shifts};

use super::query::Filter;
use super::sql::{Db, DbError, Dialect, Val};
use serde::Serialize;

/// What the report covers and how.
#[derive(Debug, Clone, PartialEq)]
pub struct Query {
    /// Which runs.
    pub filter: Filter,
    /// The shifts.
    pub shifts: Shifts,
    /// Units per drift window (default 50).
    pub drift_window: usize,
    /// Bins per histogram (default 20).
    pub bins: usize,
}

impl Default for Query {
    fn default() -> Self {
        Query {
            filter: Filter::default(),
            shifts: Shifts::default(),
            drift_window: 50,
            bins: 20,
        }
    }
}

/// First-pass and final yield of one group.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Yield {
    /// The group: a shift (`2026-12-01 A`), a station, a slot, a plan version (`name
    /// 1a2b3c4d`), or `all`.
    pub group: String,
    /// Units whose first run in the period was in this group.
    pub units: u64,
    /// Runs in this group (retests included).
    pub runs: u64,
    /// Of `units`, those whose first run passed.
    pub first_pass: u64,
    /// Of `units`, those whose last run passed.
    pub final_pass: u64,
    /// A shift under way now: its figures are of the units so far.
    pub so_far: bool,
}

impl Yield {
    /// The group as shown: `2026-12-01 C (so far)` for the shift under way.
    pub fn label(&self) -> String {
        if self.so_far {
            format!("{} (so far)", self.group)
        } else {
            self.group.clone()
        }
    }

    /// First-pass yield, 0 to 1 (NaN with no unit).
    pub fn fpy(&self) -> f64 {
        self.first_pass as f64 / self.units as f64
    }

    /// Final yield, 0 to 1 (NaN with no unit).
    pub fn final_yield(&self) -> f64 {
        self.final_pass as f64 / self.units as f64
    }
}

/// A failing step and reason, with how often.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Cause {
    /// The step.
    pub step: String,
    /// The reason (empty when the record gave none).
    pub reason: String,
    /// Failed steps with this step and reason.
    pub count: u64,
}

/// A failing step, with its count, share and the running share (the Pareto's line).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParetoStep {
    /// The step.
    pub step: String,
    /// Failures of it.
    pub count: u64,
    /// Its share of all failed steps, 0 to 1.
    pub share: f64,
    /// The share of it and every step above it, 0 to 1.
    pub cumulative: f64,
}

/// One measurement's figures.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeasurementStats {
    /// Its name (`batteryVoltage`).
    pub name: String,
    /// Its unit.
    pub unit: String,
    /// Its limits.
    pub low: Option<f64>,
    /// See `low`.
    pub high: Option<f64>,
    /// Values.
    pub n: u64,
    /// Values that failed their limits.
    pub failed: u64,
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation.
    pub sigma: f64,
    /// Lowest value.
    pub min: f64,
    /// Highest value.
    pub max: f64,
    /// Cpk; `None` with no limit or no spread.
    pub cpk: Option<f64>,
    /// The histogram's left edge and bin width, in `unit`.
    pub bin_start: f64,
    /// See `bin_start`.
    pub bin_width: f64,
    /// Values per bin.
    pub bins: Vec<u64>,
    /// The means of the last three drift windows, when there are enough values.
    pub recent_means: Option<[f64; 3]>,
    /// A walk toward a limit, if any.
    pub drift: Option<Drift>,
}

/// The whole report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Report {
    /// The file or server it was read from.
    pub source: String,
    /// `A 06:00-14:00, ...`.
    pub shifts: String,
    /// Units per drift window.
    pub drift_window: usize,
    /// Every unit of the period.
    pub overall: Yield,
    /// Per shift, oldest first.
    pub by_shift: Vec<Yield>,
    /// Per station (its id, else the PC's host name).
    pub by_station: Vec<Yield>,
    /// Per slot (`-` without one).
    pub by_slot: Vec<Yield>,
    /// Per plan version (`name` and the first 8 digits of its SHA-256).
    pub by_plan: Vec<Yield>,
    /// Failing steps, most first.
    pub pareto: Vec<ParetoStep>,
    /// Failing steps and reasons, most first (at most 20).
    pub causes: Vec<Cause>,
    /// Every measurement, by name.
    pub measurements: Vec<MeasurementStats>,
    /// Records waiting in this PC's spool, not in the report.
    pub waiting: u64,
}

fn int(row: &[Val], i: usize) -> i64 {
    row.get(i).and_then(Val::int).unwrap_or_default()
}

fn real(row: &[Val], i: usize) -> Option<f64> {
    row.get(i).and_then(Val::real)
}

fn text(row: &[Val], i: usize) -> String {
    row.get(i).and_then(Val::text).unwrap_or_default()
}

/// Computes the report over `db`.
pub fn compute(db: &mut dyn Db, q: &Query, source: &str) -> Result<Report, DbError> {
    let (yields, overall) = yields(db, q)?;
    let (pareto, causes) = pareto(db, &q.filter)?;
    let measurements = measurements(db, q)?;
    let pick = |dim: &str| -> Vec<Yield> {
        yields
            .iter()
            .filter(|(d, _)| d == dim)
            .map(|(_, y)| y.clone())
            .collect()
    };
    let mut by_shift = pick("shift");
    // The shift under way now is said so: its yield is of the units so far.
    let now = chrono::Local::now();
    let now_key = q
        .shifts
        .key(now.timestamp() / 60 + i64::from(now.offset().local_minus_utc() / 60));
    for y in &mut by_shift {
        let key: i64 = y.group.parse().unwrap_or_default();
        y.group = q.shifts.label(key);
        y.so_far = key == now_key;
    }
    Ok(Report {
        source: source.to_string(),
        shifts: q.shifts.describe(),
        drift_window: q.drift_window,
        overall,
        by_shift,
        by_station: pick("station"),
        by_slot: pick("slot"),
        by_plan: pick("plan"),
        pareto,
        causes,
        measurements,
        waiting: 0,
    })
}

/// The yields by every dimension, in one statement over the filtered runs.
#[allow(clippy::type_complexity)]
fn yields(db: &mut dyn Db, q: &Query) -> Result<(Vec<(String, Yield)>, Yield), DbError> {
    let (cond, params) = q.filter.sql("r");
    let shift = q.shifts.sql_key();
    let plan = "r.plan || ' ' || COALESCE(substr(r.plan_sha256, 1, 8), '-')";
    let dims = [
        ("shift", format!("CAST({shift} AS TEXT)")),
        ("station", "COALESCE(r.station, r.host)".to_string()),
        ("slot", "COALESCE(r.slot, '-')".to_string()),
        ("plan", plan.to_string()),
        ("all", "'all'".to_string()),
    ];
    let cols: Vec<String> = dims.iter().map(|(d, e)| format!("{e} AS g_{d}")).collect();
    let mut parts = Vec::new();
    for (d, _) in &dims {
        parts.push(format!(
            "SELECT '{d}', g_{d}, SUM(CASE WHEN n = 1 THEN 1 ELSE 0 END), COUNT(*), \
             SUM(CASE WHEN n = 1 AND verdict = 'PASS' THEN 1 ELSE 0 END), \
             SUM(CASE WHEN n = 1 AND last_verdict = 'PASS' THEN 1 ELSE 0 END) \
             FROM o GROUP BY g_{d}"
        ));
    }
    let sql = format!(
        "WITH o AS MATERIALIZED (SELECT r.verdict, {cols}, \
           ROW_NUMBER() OVER (PARTITION BY u ORDER BY r.started_ms, r.id) AS n, \
           FIRST_VALUE(r.verdict) OVER (PARTITION BY u ORDER BY r.started_ms DESC, r.id DESC) AS last_verdict \
         FROM (SELECT r.*, CASE WHEN r.serial IS NULL THEN r.uuid ELSE r.profile || ':' || r.serial END AS u \
               FROM runs r WHERE {cond}) r) \
         {}",
        parts.join(" UNION ALL "),
        cols = cols.join(", "),
    );
    let rows = db.rows(&sql, &params)?;
    let mut out = Vec::new();
    let mut overall = Yield {
        group: "all".into(),
        units: 0,
        runs: 0,
        first_pass: 0,
        final_pass: 0,
        so_far: false,
    };
    for row in rows {
        let y = Yield {
            group: text(&row, 1),
            units: int(&row, 2).max(0) as u64,
            runs: int(&row, 3).max(0) as u64,
            first_pass: int(&row, 4).max(0) as u64,
            final_pass: int(&row, 5).max(0) as u64,
            so_far: false,
        };
        let dim = text(&row, 0);
        if dim == "all" {
            overall = y;
        } else if y.units > 0 {
            // A group where only retests ran has no unit of its own: its runs are in the
            // first run's group.
            out.push((dim, y));
        }
    }
    out.sort_by(|a, b| (&a.0, &a.1.group).cmp(&(&b.0, &b.1.group)));
    // Shifts sort by their key, as numbers.
    out.sort_by_key(|(d, y)| {
        if d == "shift" {
            y.group.parse::<i64>().unwrap_or_default()
        } else {
            0
        }
    });
    Ok((out, overall))
}

/// The failed steps by step and reason.
fn pareto(db: &mut dyn Db, filter: &Filter) -> Result<(Vec<ParetoStep>, Vec<Cause>), DbError> {
    let (cond, params) = filter.sql("r");
    let sql = if cond == "1 = 1" {
        "SELECT s.name, COALESCE(s.reason, ''), COUNT(*) FROM steps s WHERE s.verdict = 'FAIL' \
         GROUP BY s.name, s.reason"
            .to_string()
    } else {
        format!(
            "SELECT s.name, COALESCE(s.reason, ''), COUNT(*) FROM steps s JOIN runs r ON r.id = s.run \
             WHERE s.verdict = 'FAIL' AND {cond} GROUP BY s.name, s.reason"
        )
    };
    let mut causes: Vec<Cause> = db
        .rows(&sql, &params)?
        .iter()
        .map(|r| Cause {
            step: text(r, 0),
            reason: text(r, 1),
            count: int(r, 2).max(0) as u64,
        })
        .collect();
    let mut steps: std::collections::BTreeMap<String, u64> = Default::default();
    for c in &causes {
        *steps.entry(c.step.clone()).or_default() += c.count;
    }
    let total: u64 = steps.values().sum();
    let mut pareto: Vec<ParetoStep> = steps
        .into_iter()
        .map(|(step, count)| ParetoStep {
            step,
            count,
            share: count as f64 / total as f64,
            cumulative: 0.0,
        })
        .collect();
    pareto.sort_by(|a, b| b.count.cmp(&a.count).then(a.step.cmp(&b.step)));
    let mut run = 0u64;
    for p in &mut pareto {
        run += p.count;
        p.cumulative = run as f64 / total as f64;
    }
    causes.sort_by(|a, b| {
        b.count
            .cmp(&a.count)
            .then(a.step.cmp(&b.step))
            .then(a.reason.cmp(&b.reason))
    });
    causes.truncate(20);
    Ok((pareto, causes))
}

/// `m.low IS ?N` as each database says a comparison that holds between two nulls.
fn same(d: Dialect, col: &str, n: usize) -> String {
    match d {
        Dialect::Sqlite => format!("{col} IS ?{n}"),
        Dialect::Postgres => format!("{col} IS NOT DISTINCT FROM ?{n}"),
    }
}

/// Every measurement's figures: one aggregate scan for the sums, then per measurement its
/// histogram (one scan of its index range) and its last values for the drift rule.
fn measurements(db: &mut dyn Db, q: &Query) -> Result<Vec<MeasurementStats>, DbError> {
    let (cond, params) = q.filter.sql("r");
    let filtered = cond != "1 = 1";
    let from = if filtered {
        format!("measurements m JOIN runs r ON r.id = m.run WHERE {cond}")
    } else {
        "measurements m WHERE 1 = 1".to_string()
    };
    let rows = db.rows(
        &format!(
            "SELECT m.name, m.unit, m.low, m.high, COUNT(*), SUM(m.value), SUM(m.value * m.value), \
             MIN(m.value), MAX(m.value), CAST(SUM(1 - m.pass) AS BIGINT) FROM {from} \
             GROUP BY m.name, m.unit, m.low, m.high ORDER BY m.name, m.unit, m.low, m.high"
        ),
        &params,
    )?;
    let d = db.dialect();
    let mut out = Vec::new();
    for row in rows {
        let n = int(&row, 4).max(0) as u64;
        let (mean, sigma) = stats::mean_sigma(
            n,
            real(&row, 5).unwrap_or(0.0),
            real(&row, 6).unwrap_or(0.0),
        );
        let (low, high) = (real(&row, 2), real(&row, 3));
        let (min, max) = (real(&row, 7).unwrap_or(mean), real(&row, 8).unwrap_or(mean));
        let mut m = MeasurementStats {
            name: text(&row, 0),
            unit: text(&row, 1),
            low,
            high,
            n,
            failed: int(&row, 9).max(0) as u64,
            mean,
            sigma,
            min,
            max,
            cpk: stats::cpk(mean, sigma, low, high),
            bin_start: 0.0,
            bin_width: 1.0,
            bins: Vec::new(),
            recent_means: None,
            drift: None,
        };
        // This measurement's rows: its name, unit and limits, then the period's filter.
        let k = params.len();
        let mut p = params.clone();
        p.extend([
            Val::text_of(&m.name),
            Val::text_of(&m.unit),
            Val::Real(low),
            Val::Real(high),
        ]);
        let key = format!(
            "m.name = ?{} AND m.unit = ?{} AND {} AND {}",
            k + 1,
            k + 2,
            same(d, "m.low", k + 3),
            same(d, "m.high", k + 4)
        );
        histogram(db, q, &from, &key, &p, &mut m)?;
        let window = q.drift_window;
        let last = db.rows(
            &format!(
                "SELECT m.value FROM {from} AND {key} ORDER BY m.run DESC, m.step DESC, m.idx DESC LIMIT {}",
                3 * window
            ),
            &p,
        )?;
        let mut values: Vec<f64> = last.iter().filter_map(|r| real(r, 0)).collect();
        values.reverse();
        if values.len() >= 3 * window && window > 0 {
            let mean_of = |s: &[f64]| s.iter().sum::<f64>() / s.len() as f64;
            m.recent_means = Some([
                mean_of(&values[..window]),
                mean_of(&values[window..2 * window]),
                mean_of(&values[2 * window..]),
            ]);
        }
        m.drift = stats::drift(&values, window, sigma, low, high);
        out.push(m);
    }
    Ok(out)
}

/// The histogram's bins: `q.bins` equal bins over the values and the limits together, so
/// that both limits are always on the plot.
fn histogram(
    db: &mut dyn Db,
    q: &Query,
    from: &str,
    key: &str,
    params: &[Val],
    m: &mut MeasurementStats,
) -> Result<(), DbError> {
    let lo = [Some(m.min), m.low]
        .into_iter()
        .flatten()
        .fold(f64::INFINITY, f64::min);
    let hi = [Some(m.max), m.high]
        .into_iter()
        .flatten()
        .fold(f64::NEG_INFINITY, f64::max);
    let bins = q.bins.max(1);
    let span = if hi > lo { hi - lo } else { 1.0 };
    // A margin of a bin either side: the limits are not drawn on the frame.
    let width = span / (bins as f64 - 2.0).max(1.0);
    let start = lo - width;
    m.bin_start = start;
    m.bin_width = width;
    m.bins = vec![0; bins];
    let d = db.dialect();
    // A value on a bin's edge counts in the bin above it, whatever the rounding of the
    // division (a millionth of a bin).
    let bin = d.floor(&format!(
        "(CASE WHEN m.value < {start:e} THEN 0 ELSE (m.value - {start:e}) / {width:e} + 1e-6 END)"
    ));
    let rows = db.rows(
        &format!("SELECT {bin} AS b, COUNT(*) FROM {from} AND {key} GROUP BY b"),
        params,
    )?;
    for row in rows {
        let b = (int(&row, 0).max(0) as usize).min(bins - 1);
        m.bins[b] += int(&row, 1).max(0) as u64;
    }
    Ok(())
}
