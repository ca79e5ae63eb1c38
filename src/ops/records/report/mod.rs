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
//!   units each (in the order the units were tested: their runs' start, not the order the
//!   records arrived in from a spool) move the same way toward a limit by at least half a
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
    /// How long each part took to compute, seconds (for the benchmark).
    #[serde(skip)]
    pub phases: Vec<(&'static str, f64)>,
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
    compute_with(db, None, q, source)
}

/// The report of `store` (its yields on a second connection beside the rest, where the store
/// can open one), with the records waiting in its spool. Errors name the file or server.
pub fn of_store(store: &mut dyn super::Store, q: &Query) -> Result<Report, super::RecordsError> {
    let source = store.place();
    let mut second = store.reader();
    let mut out = None;
    store.read(&mut |db| {
        out = Some(compute_with(db, second.take(), q, &source)?);
        Ok(())
    })?;
    let mut r = out.ok_or_else(|| super::RecordsError::Database {
        place: source.clone(),
        why: "the report was not computed".into(),
    })?;
    r.waiting = store.waiting();
    Ok(r)
}

/// [`compute`], the yields computed on `second`'s connection (a thread of its own,
/// `report-yields`) while `db` computes the rest: on two cores the report takes as long as the
/// longer part, not both.
pub fn compute_with(
    db: &mut dyn Db,
    second: Option<super::sql::Opener>,
    q: &Query,
    source: &str,
) -> Result<Report, DbError> {
    let mut phases = Vec::new();
    let mut clock = std::time::Instant::now();
    let mut lap = |name: &'static str, phases: &mut Vec<(&'static str, f64)>| {
        phases.push((name, clock.elapsed().as_secs_f64()));
        clock = std::time::Instant::now();
    };
    let (yields, overall, pareto, causes, measurements) = std::thread::scope(|scope| {
        let beside = second.and_then(|open| {
            let q = q.clone();
            std::thread::Builder::new()
                .name("report-yields".into())
                .spawn_scoped(scope, move || {
                    let started = std::time::Instant::now();
                    let mut db = open()?;
                    yields(db.as_mut(), &q).map(|y| (y, started.elapsed().as_secs_f64()))
                })
                .ok()
        });
        let (pareto, causes) = pareto(db, &q.filter)?;
        lap("pareto", &mut phases);
        let measurements = measurements(db, q, &mut phases)?;
        lap("measurements", &mut phases);
        let ((yields, overall), took) = match beside {
            Some(h) => h
                .join()
                .map_err(|_| DbError::Shape("the report's yield thread failed".into()))??,
            None => {
                let t = std::time::Instant::now();
                (yields(db, q)?, t.elapsed().as_secs_f64())
            }
        };
        phases.push(("yields", took));
        Ok::<_, DbError>((yields, overall, pareto, causes, measurements))
    })?;
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
        phases,
    })
}

/// A combination of the groups a run belongs to: shift key, station, host, slot, plan, plan
/// hash (as stored; labelled when the dimensions are made).
type Groups = (
    i64,
    Option<String>,
    String,
    Option<String>,
    String,
    Option<String>,
);

/// Units (first runs), runs, first passes and final passes of one combination of groups.
#[derive(Default, Clone, Copy)]
struct Counts {
    units: u64,
    runs: u64,
    first_pass: u64,
    final_pass: u64,
}

fn groups_of(row: &[Val], at: usize) -> Groups {
    (
        int(row, at),
        row.get(at + 1).and_then(Val::text),
        text(row, at + 2),
        row.get(at + 3).and_then(Val::text),
        text(row, at + 4),
        row.get(at + 5).and_then(Val::text),
    )
}

/// The unit being read: its key, its first run's groups and verdict, its last verdict.
type Reading = ((String, String), Groups, bool, bool);

fn count_unit(u: Option<Reading>, combos: &mut std::collections::HashMap<Groups, Counts>) {
    if let Some((_, groups, first, last)) = u {
        let c = combos.entry(groups).or_default();
        c.units += 1;
        c.first_pass += u64::from(first);
        c.final_pass += u64::from(last);
    }
}

/// The yields by every dimension. The runs with a serial come in each unit's order (the
/// `runs_unit` index: no sort) with their groups; a unit's first run gives its groups and
/// first pass, its last run its final verdict, and each run counts in its own groups. Runs
/// without a serial are units of their own, counted by one GROUP BY. Then each dimension's
/// figures are the sums over the combinations (a few hundred).
#[allow(clippy::type_complexity)]
fn yields(db: &mut dyn Db, q: &Query) -> Result<(Vec<(String, Yield)>, Yield), DbError> {
    let (cond, params) = q.filter.sql("r");
    let cols = format!(
        "{}, r.station, r.host, r.slot, r.plan, r.plan_sha256",
        q.shifts.sql_key()
    );
    let mut combos: std::collections::HashMap<Groups, Counts> = Default::default();
    let mut unit: Option<Reading> = None;
    db.each_row(
        &format!(
            "SELECT r.profile, r.serial, r.verdict, {cols} FROM runs r \
             WHERE {cond} AND r.serial IS NOT NULL ORDER BY r.profile, r.serial, r.started_ms, r.id"
        ),
        &params,
        &mut |row| {
            let key = (text(&row, 0), text(&row, 1));
            let pass = text(&row, 2) == "PASS";
            let groups = groups_of(&row, 3);
            combos.entry(groups.clone()).or_default().runs += 1;
            match &mut unit {
                Some((k, _, _, last)) if *k == key => *last = pass,
                _ => {
                    let done = unit.replace((key, groups, pass, pass));
                    count_unit(done, &mut combos);
                }
            }
            Ok(())
        },
    )?;
    count_unit(unit.take(), &mut combos);
    for row in db.rows(
        &format!(
            "SELECT {cols}, COUNT(*), CAST(SUM(CASE WHEN r.verdict = 'PASS' THEN 1 ELSE 0 END) AS BIGINT) \
             FROM runs r WHERE {cond} AND r.serial IS NULL \
             GROUP BY 1, r.station, r.host, r.slot, r.plan, r.plan_sha256"
        ),
        &params,
    )? {
        let c = combos.entry(groups_of(&row, 0)).or_default();
        let (n, pass) = (int(&row, 6).max(0) as u64, int(&row, 7).max(0) as u64);
        c.units += n;
        c.runs += n;
        c.first_pass += pass;
        c.final_pass += pass;
    }
    let mut dims: std::collections::BTreeMap<(String, String), Yield> = Default::default();
    let mut overall = Yield {
        group: "all".into(),
        units: 0,
        runs: 0,
        first_pass: 0,
        final_pass: 0,
        so_far: false,
    };
    let add = |y: &mut Yield, c: &Counts| {
        y.units += c.units;
        y.runs += c.runs;
        y.first_pass += c.first_pass;
        y.final_pass += c.final_pass;
    };
    for ((shift, station, host, slot, plan, sha), c) in &combos {
        add(&mut overall, c);
        let plan = format!(
            "{plan} {}",
            sha.as_deref().map_or("-", |h| h.get(..8).unwrap_or(h))
        );
        for (dim, group) in [
            ("shift", shift.to_string()),
            ("station", station.clone().unwrap_or_else(|| host.clone())),
            ("slot", slot.clone().unwrap_or_else(|| "-".into())),
            ("plan", plan),
        ] {
            let y = dims
                .entry((dim.to_string(), group.clone()))
                .or_insert_with(|| Yield {
                    group,
                    units: 0,
                    runs: 0,
                    first_pass: 0,
                    final_pass: 0,
                    so_far: false,
                });
            add(y, c);
        }
    }
    // A group where only retests ran has no unit of its own: its runs are in the first run's
    // group.
    let mut out: Vec<(String, Yield)> = dims
        .into_iter()
        .map(|((dim, _), y)| (dim, y))
        .filter(|(_, y)| y.units > 0)
        .collect();
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
fn measurements(
    db: &mut dyn Db,
    q: &Query,
    phases: &mut Vec<(&'static str, f64)>,
) -> Result<Vec<MeasurementStats>, DbError> {
    let started = std::time::Instant::now();
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
    phases.push(("measurement sums", started.elapsed().as_secs_f64()));
    let mut in_histograms = 0.0;
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
        let t = std::time::Instant::now();
        histogram(db, q, &from, &key, &p, &mut m)?;
        in_histograms += t.elapsed().as_secs_f64();
        let window = q.drift_window;
        let mut values = last_values(db, &from, &p, k, 3 * window, filtered)?;
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
    phases.push(("histograms", in_histograms));
    Ok(out)
}

/// The last `n` values of the measurement keyed by `p[k..k + 4]` (name, unit, low, high), in
/// the order the units were tested (their runs' start, then the order recorded), newest first.
/// Not the order the records arrived in: a station's records forwarded from its spool an hour
/// late are older units than those stored meanwhile. Read backwards along the runs' start
/// index from the newest, over a span of runs that quadruples until it holds `n` values or
/// every run, so that the measurement's index (ordered by value) is not walked whole.
fn last_values(
    db: &mut dyn Db,
    from: &str,
    p: &[Val],
    k: usize,
    n: usize,
    filtered: bool,
) -> Result<Vec<f64>, DbError> {
    let d = db.dialect();
    // On SQLite `+` keeps the key off the measurement's index: the runs' order is wanted.
    let plus = if d == Dialect::Sqlite { "+" } else { "" };
    let key = format!(
        "{plus}m.name = ?{} AND {plus}m.unit = ?{} AND {} AND {}",
        k + 1,
        k + 2,
        same(d, &format!("{plus}m.low"), k + 3),
        same(d, &format!("{plus}m.high"), k + 4)
    );
    // The filtered `from` joins the runs already; the unfiltered one is joined to them here.
    let from = if filtered {
        from.to_string()
    } else {
        "measurements m JOIN runs r ON r.id = m.run WHERE 1 = 1".to_string()
    };
    let mut span = (2 * n as i64).max(64);
    loop {
        // The start of the `span`-th newest run: every run from it on is read.
        let since = if filtered {
            None
        } else {
            db.rows(
                &format!(
                    "SELECT started_ms FROM runs ORDER BY started_ms DESC LIMIT 1 OFFSET {}",
                    span - 1
                ),
                &[],
            )?
            .first()
            .and_then(|r| r.first())
            .and_then(Val::int)
        };
        let mut q = p.to_vec();
        let bound = match since {
            Some(t) => {
                q.push(Val::Int(Some(t)));
                format!(" AND r.started_ms >= ?{}", q.len())
            }
            None => String::new(),
        };
        let rows = db.rows(
            &format!(
                "SELECT m.value FROM {from} AND {key}{bound} \
                 ORDER BY r.started_ms DESC, m.run DESC, m.step DESC, m.idx DESC LIMIT {n}"
            ),
            &q,
        )?;
        if rows.len() >= n || since.is_none() {
            return Ok(rows.iter().filter_map(|r| real(r, 0)).collect());
        }
        span *= 4;
    }
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
    if db.dialect() == Dialect::Postgres {
        // PostgreSQL: one pass, the bins hashed (its counts of index ranges cost a heap visit
        // each until the table is vacuumed). A value on an edge counts in the bin above it,
        // whatever the rounding of the division (a millionth of a bin).
        let bin = Dialect::Postgres.floor(&format!(
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
        return Ok(());
    }
    // SQLite: a count per bin, each a range of the value-ordered index (no pass over every
    // value, no sort): the first bin takes everything below its upper edge, the last
    // everything from its lower edge. A value on an edge counts in the bin above it, whatever
    // the rounding of the edge (a millionth of a bin).
    let edge = |i: usize| start + width * i as f64 - width * 1e-6;
    let k = params.len();
    let sql = format!(
        "SELECT COUNT(*) FROM {from} AND {key} AND m.value >= ?{} AND m.value < ?{}",
        k + 1,
        k + 2
    );
    for i in 0..bins {
        let lo = if i == 0 { f64::MIN } else { edge(i) };
        let hi = if i + 1 == bins {
            f64::INFINITY
        } else {
            edge(i + 1)
        };
        let mut p = params.to_vec();
        p.extend([Val::Real(Some(lo)), Val::Real(Some(hi))]);
        m.bins[i] = db
            .rows(&sql, &p)?
            .first()
            .map_or(0, |row| int(row, 0).max(0) as u64);
    }
    Ok(())
}
