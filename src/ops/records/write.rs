//! A record into the tables and back, on either database: the caller wraps [`insert`] in one
//! transaction, so a record is stored whole or not at all.

use super::record::{
    Measurement, ParamWrite, Record, RunContext, RunKind, SerialSource, StepRecord, Unit, Verdict,
};
use super::sql::{Db, DbError, Val};

/// The columns of `runs` that a record fills, in [`run_values`] order.
const RUN_COLUMNS: &str = "uuid, kind, started_ms, ended_ms, utc_offset_min, verdict, \
    failed_step, reason, station, slot, fixture, operator, bundle_sha256, host, plan, \
    plan_sha256, profile, software, software_commit, serial, serial_source, hardware, \
    firmware, build, steps";

fn run_values(r: &Record) -> Vec<Val> {
    let c = &r.context;
    vec![
        Val::text_of(&r.uuid),
        Val::text_of(r.kind.name()),
        Val::Int(Some(r.started_ms)),
        Val::Int(Some(r.ended_ms)),
        Val::Int(Some(i64::from(r.utc_offset_min))),
        Val::text_of(r.verdict.name()),
        Val::opt_text(&r.failed_step),
        Val::opt_text(&r.reason),
        Val::opt_text(&c.station),
        Val::opt_text(&c.slot),
        Val::opt_text(&c.fixture),
        Val::opt_text(&c.operator),
        Val::opt_text(&c.bundle_sha256),
        Val::text_of(&r.host),
        Val::text_of(&r.plan),
        Val::opt_text(&r.plan_sha256),
        Val::text_of(&r.profile),
        Val::text_of(&r.software),
        Val::text_of(&r.commit),
        Val::opt_text(&r.unit.serial),
        Val::Text(r.unit.serial_source.map(|s| s.name().to_string())),
        Val::opt_text(&r.unit.hardware),
        Val::opt_text(&r.unit.firmware),
        Val::opt_text(&r.unit.build),
        Val::Int(Some(r.steps.len() as i64)),
    ]
}

/// Inserts `record` (call inside a transaction). Returns `false` when a record with its UUID
/// is already stored: nothing is written then, so forwarding one twice stores it once.
pub fn insert(db: &mut dyn Db, record: &Record) -> Result<bool, DbError> {
    let values = run_values(record);
    let marks: Vec<String> = (1..=values.len()).map(|i| format!("?{i}")).collect();
    let sql = format!(
        "INSERT INTO runs ({RUN_COLUMNS}) VALUES ({}) ON CONFLICT (uuid) DO NOTHING RETURNING id",
        marks.join(", ")
    );
    let Some(run) = db
        .rows(&sql, &values)?
        .first()
        .and_then(|r| r.first())
        .and_then(Val::int)
    else {
        return Ok(false);
    };
    for (i, s) in record.steps.iter().enumerate() {
        let step = i as i64;
        db.exec(
            "INSERT INTO steps (run, idx, name, kind, started_ms, duration_ms, verdict, reason, detail) \
             VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9)",
            &[
                Val::Int(Some(run)),
                Val::Int(Some(step)),
                Val::text_of(&s.name),
                Val::text_of(&s.kind),
                Val::Int(Some(s.started_ms)),
                Val::Int(Some(s.duration_ms)),
                Val::text_of(s.verdict.name()),
                Val::opt_text(&s.reason),
                Val::text_of(&s.detail),
            ],
        )?;
        for (j, m) in s.measurements.iter().enumerate() {
            db.exec(
                "INSERT INTO measurements (run, step, idx, name, unit, low, high, value, pass) \
                 VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9)",
                &[
                    Val::Int(Some(run)),
                    Val::Int(Some(step)),
                    Val::Int(Some(j as i64)),
                    Val::text_of(&m.name),
                    Val::text_of(&m.unit),
                    Val::Real(m.low),
                    Val::Real(m.high),
                    Val::Real(Some(m.value)),
                    Val::Int(Some(i64::from(m.pass))),
                ],
            )?;
        }
        for (j, w) in s.writes.iter().enumerate() {
            db.exec(
                "INSERT INTO writes (run, step, idx, name, unit, value, before, after) \
                 VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8)",
                &[
                    Val::Int(Some(run)),
                    Val::Int(Some(step)),
                    Val::Int(Some(j as i64)),
                    Val::text_of(&w.name),
                    Val::text_of(&w.unit),
                    Val::text_of(&w.value),
                    Val::opt_text(&w.before),
                    Val::opt_text(&w.after),
                ],
            )?;
        }
    }
    Ok(true)
}

fn text(row: &[Val], i: usize) -> Option<String> {
    row.get(i).and_then(Val::text)
}

fn int(row: &[Val], i: usize) -> i64 {
    row.get(i).and_then(Val::int).unwrap_or_default()
}

/// A `runs` row (columns: `id`, then [`RUN_COLUMNS`]) as a record without its steps.
fn run_of(row: &[Val]) -> (i64, Record) {
    let t = |i| text(row, i);
    let record = Record {
        uuid: t(1).unwrap_or_default(),
        kind: t(2)
            .as_deref()
            .and_then(RunKind::from_name)
            .unwrap_or(RunKind::Station),
        started_ms: int(row, 3),
        ended_ms: int(row, 4),
        utc_offset_min: int(row, 5) as i32,
        verdict: Verdict::from_name(&t(6).unwrap_or_default()),
        failed_step: t(7),
        reason: t(8),
        context: RunContext {
            station: t(9),
            slot: t(10),
            fixture: t(11),
            operator: t(12),
            bundle_sha256: t(13),
        },
        host: t(14).unwrap_or_default(),
        plan: t(15).unwrap_or_default(),
        plan_sha256: t(16),
        profile: t(17).unwrap_or_default(),
        software: t(18).unwrap_or_default(),
        commit: t(19).unwrap_or_default(),
        unit: Unit {
            serial: t(20),
            serial_source: t(21).as_deref().and_then(SerialSource::from_name),
            hardware: t(22),
            firmware: t(23),
            build: t(24),
        },
        steps: Vec::new(),
    };
    (int(row, 0), record)
}

/// The records whose run matches `where_sql` (a condition on `runs`, with `params`), oldest
/// first, each whole, handed to `each` one by one (an export of a year's records is never all
/// in memory); `limit` keeps the newest that many instead, still oldest first.
pub fn load_each(
    db: &mut dyn Db,
    where_sql: &str,
    params: &[Val],
    limit: Option<u64>,
    each: &mut dyn FnMut(Record) -> Result<(), DbError>,
) -> Result<(), DbError> {
    let order = match limit {
        Some(n) => format!(
            "id IN (SELECT id FROM runs WHERE {where_sql} ORDER BY started_ms DESC, id DESC LIMIT {n})"
        ),
        None => where_sql.to_string(),
    };
    let sql = format!("SELECT id, {RUN_COLUMNS} FROM runs WHERE {order} ORDER BY started_ms, id");
    let mut runs: Vec<(i64, Record)> = Vec::new();
    // Runs in pages of 500: each page's steps are read in three queries.
    let mut flush = |db: &mut dyn Db, runs: &mut Vec<(i64, Record)>| -> Result<(), DbError> {
        if runs.is_empty() {
            return Ok(());
        }
        fill_steps(db, runs)?;
        for (_, r) in runs.drain(..) {
            each(r)?;
        }
        Ok(())
    };
    let rows = db.rows(&sql, params)?;
    for row in rows {
        runs.push(run_of(&row));
        if runs.len() == 500 {
            flush(db, &mut runs)?;
        }
    }
    flush(db, &mut runs)
}

/// Reads the steps, measurements and writes of `runs` (one page).
fn fill_steps(db: &mut dyn Db, runs: &mut [(i64, Record)]) -> Result<(), DbError> {
    let (lo, hi) = runs.iter().fold((i64::MAX, i64::MIN), |(lo, hi), (id, _)| {
        (lo.min(*id), hi.max(*id))
    });
    let range = [Val::Int(Some(lo)), Val::Int(Some(hi))];
    let index: std::collections::HashMap<i64, usize> = runs
        .iter()
        .enumerate()
        .map(|(i, (id, _))| (*id, i))
        .collect();
    let rows = db.rows(
        "SELECT run, idx, name, kind, started_ms, duration_ms, verdict, reason, detail \
         FROM steps WHERE run BETWEEN ?1 AND ?2 ORDER BY run, idx",
        &range,
    )?;
    for row in rows {
        let Some(&at) = index.get(&int(&row, 0)) else {
            continue;
        };
        runs[at].1.steps.push(StepRecord {
            name: text(&row, 2).unwrap_or_default(),
            kind: text(&row, 3).unwrap_or_default(),
            started_ms: int(&row, 4),
            duration_ms: int(&row, 5),
            verdict: Verdict::from_name(&text(&row, 6).unwrap_or_default()),
            reason: text(&row, 7),
            detail: text(&row, 8).unwrap_or_default(),
            measurements: Vec::new(),
            writes: Vec::new(),
        });
    }
    let rows = db.rows(
        "SELECT run, step, name, unit, low, high, value, pass FROM measurements \
         WHERE run BETWEEN ?1 AND ?2 ORDER BY run, step, idx",
        &range,
    )?;
    for row in rows {
        let Some(&at) = index.get(&int(&row, 0)) else {
            continue;
        };
        if let Some(step) = runs[at].1.steps.get_mut(int(&row, 1) as usize) {
            step.measurements.push(Measurement {
                name: text(&row, 2).unwrap_or_default(),
                unit: text(&row, 3).unwrap_or_default(),
                low: row.get(4).and_then(Val::real),
                high: row.get(5).and_then(Val::real),
                value: row.get(6).and_then(Val::real).unwrap_or(f64::NAN),
                pass: int(&row, 7) != 0,
            });
        }
    }
    let rows = db.rows(
        "SELECT run, step, name, unit, value, before, after FROM writes \
         WHERE run BETWEEN ?1 AND ?2 ORDER BY run, step, idx",
        &range,
    )?;
    for row in rows {
        let Some(&at) = index.get(&int(&row, 0)) else {
            continue;
        };
        if let Some(step) = runs[at].1.steps.get_mut(int(&row, 1) as usize) {
            step.writes.push(ParamWrite {
                name: text(&row, 2).unwrap_or_default(),
                unit: text(&row, 3).unwrap_or_default(),
                value: text(&row, 4).unwrap_or_default(),
                before: text(&row, 5),
                after: text(&row, 6),
            });
        }
    }
    Ok(())
}
