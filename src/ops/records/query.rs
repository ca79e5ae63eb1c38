//! Reading records back: which runs ([`Filter`]), a unit's history, the list, and the exports
//! (CSV one row per measurement or step, JSON lines one record per line).

use super::record::Record;
use super::sql::{Db, DbError, Val};
use super::write;
use serde::Serialize;

/// Which runs: each `None` field matches all.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Filter {
    /// Runs started at or after, ms since 1970 UTC.
    pub since_ms: Option<i64>,
    /// Runs started before, ms since 1970 UTC.
    pub until_ms: Option<i64>,
    /// Runs at this station.
    pub station: Option<String>,
    /// Runs of this plan: its name, or the start of its SHA-256 (at least 6 hex digits).
    pub plan: Option<String>,
    /// Runs of the unit with this serial number.
    pub serial: Option<String>,
    /// Whether the station's access events ([`super::record::RunKind::Access`]: engineer
    /// unlocks, refused passwords, locks) are included; `false` (the reports, the exports):
    /// only units' runs.
    pub access: bool,
}

impl Filter {
    /// The condition on `runs` (aliased `r`, or not when `alias` is empty) and its parameters.
    pub fn sql(&self, alias: &str) -> (String, Vec<Val>) {
        let a = if alias.is_empty() {
            String::new()
        } else {
            format!("{alias}.")
        };
        let mut conds = vec!["1 = 1".to_string()];
        let mut params = Vec::new();
        let mut add = |cond: String, v: Val, params: &mut Vec<Val>| {
            params.push(v);
            conds.push(cond.replace("?N", &format!("?{}", params.len())));
        };
        if let Some(t) = self.since_ms {
            add(
                format!("{a}started_ms >= ?N"),
                Val::Int(Some(t)),
                &mut params,
            );
        }
        if let Some(t) = self.until_ms {
            add(
                format!("{a}started_ms < ?N"),
                Val::Int(Some(t)),
                &mut params,
            );
        }
        if let Some(s) = &self.station {
            add(format!("{a}station = ?N"), Val::text_of(s), &mut params);
        }
        if let Some(p) = &self.plan {
            let hex = p.len() >= 6 && p.chars().all(|c| c.is_ascii_hexdigit());
            if hex {
                add(
                    format!("{a}plan_sha256 LIKE ?N"),
                    Val::Text(Some(format!("{}%", p.to_ascii_lowercase()))),
                    &mut params,
                );
            } else {
                add(format!("{a}plan = ?N"), Val::text_of(p), &mut params);
            }
        }
        if let Some(s) = &self.serial {
            add(format!("{a}serial = ?N"), Val::text_of(s), &mut params);
        }
        if !self.access {
            let access = super::record::RunKind::Access.name();
            add(format!("{a}kind <> ?N"), Val::text_of(access), &mut params);
        }
        (conds.join(" AND "), params)
    }
}

/// What the records say of one unit before a run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct History {
    /// Runs recorded for it.
    pub runs: u64,
    /// The last one's verdict, `PASS` or `FAIL`.
    pub last_verdict: String,
    /// The last one's failed step, on FAIL.
    pub last_step: Option<String>,
    /// When the last one started, ms since 1970 UTC.
    pub last_ms: i64,
    /// Where (its station, else the PC's host name).
    pub last_place: String,
}

impl History {
    /// `already tested 2 times, last: FAIL at Battery voltage on 2026-12-01 14:03 at line3-st2`.
    pub fn line(&self) -> String {
        let when = local_time(self.last_ms);
        let times = if self.runs == 1 { "time" } else { "times" };
        let verdict = match &self.last_step {
            Some(step) => format!("{} at {step}", self.last_verdict),
            None => self.last_verdict.clone(),
        };
        format!(
            "already tested {} {times}, last: {verdict} on {when} at {}",
            self.runs, self.last_place
        )
    }
}

/// `2026-12-01 14:03` in this PC's time zone.
pub fn local_time(ms: i64) -> String {
    use chrono::TimeZone;
    chrono::Local
        .timestamp_millis_opt(ms)
        .single()
        .map(|t| t.format("%Y-%m-%d %H:%M").to_string())
        .unwrap_or_else(|| ms.to_string())
}

/// The unit `serial` of `profile`'s runs: how many, and the last; `None` when never tested.
pub fn history(db: &mut dyn Db, profile: &str, serial: &str) -> Result<Option<History>, DbError> {
    let params = [Val::text_of(profile), Val::text_of(serial)];
    let count = db
        .rows(
            "SELECT COUNT(*) FROM runs WHERE profile = ?1 AND serial = ?2",
            &params,
        )?
        .first()
        .and_then(|r| r.first())
        .and_then(Val::int)
        .unwrap_or(0);
    if count == 0 {
        return Ok(None);
    }
    let last = db.rows(
        "SELECT verdict, failed_step, started_ms, COALESCE(station, host) FROM runs \
         WHERE profile = ?1 AND serial = ?2 ORDER BY started_ms DESC, id DESC LIMIT 1",
        &params,
    )?;
    let Some(row) = last.first() else {
        return Ok(None);
    };
    Ok(Some(History {
        runs: count as u64,
        last_verdict: row.first().and_then(Val::text).unwrap_or_default(),
        last_step: row.get(1).and_then(Val::text),
        last_ms: row.get(2).and_then(Val::int).unwrap_or_default(),
        last_place: row.get(3).and_then(Val::text).unwrap_or_default(),
    }))
}

/// One line of `records list`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunLine {
    /// The record's UUID.
    pub uuid: String,
    /// When it started, ms since 1970 UTC.
    pub started_ms: i64,
    /// `selftest`, `provision`, ...
    pub kind: String,
    /// The unit's serial.
    pub serial: Option<String>,
    /// `PASS` or `FAIL`.
    pub verdict: String,
    /// The failed step, on FAIL.
    pub failed_step: Option<String>,
    /// Station (else host), slot and operator.
    pub station: String,
    /// The slot.
    pub slot: Option<String>,
    /// The operator.
    pub operator: Option<String>,
    /// The plan's name.
    pub plan: String,
}

/// The newest `limit` runs matching `filter`, newest first.
pub fn list(db: &mut dyn Db, filter: &Filter, limit: u64) -> Result<Vec<RunLine>, DbError> {
    let (cond, params) = filter.sql("");
    let rows = db.rows(
        &format!(
            "SELECT uuid, started_ms, kind, serial, verdict, failed_step, COALESCE(station, host), \
             slot, operator, plan FROM runs WHERE {cond} ORDER BY started_ms DESC, id DESC LIMIT {limit}"
        ),
        &params,
    )?;
    Ok(rows
        .iter()
        .map(|r| {
            let t = |i: usize| r.get(i).and_then(Val::text);
            RunLine {
                uuid: t(0).unwrap_or_default(),
                started_ms: r.get(1).and_then(Val::int).unwrap_or_default(),
                kind: t(2).unwrap_or_default(),
                serial: t(3),
                verdict: t(4).unwrap_or_default(),
                failed_step: t(5),
                station: t(6).unwrap_or_default(),
                slot: t(7),
                operator: t(8),
                plan: t(9).unwrap_or_default(),
            }
        })
        .collect())
}

/// Every record matching `filter`, oldest first, whole, handed to `each` one at a time.
pub fn each_record(
    db: &mut dyn Db,
    filter: &Filter,
    each: &mut dyn FnMut(Record) -> Result<(), DbError>,
) -> Result<(), DbError> {
    let (cond, params) = filter.sql("");
    write::load_each(db, &cond, &params, None, each)
}

/// The CSV export's columns: one row per measurement (a step without one is a row of its own,
/// its measurement cells empty).
pub const CSV_COLUMNS: [&str; 22] = [
    "uuid",
    "kind",
    "started",
    "station",
    "slot",
    "operator",
    "plan",
    "plan_sha256",
    "profile",
    "serial",
    "serial_source",
    "run_verdict",
    "step",
    "step_kind",
    "step_started",
    "duration_ms",
    "step_verdict",
    "reason",
    "measurement",
    "unit",
    "low_high",
    "value",
];

/// A record as CSV rows in [`CSV_COLUMNS`] order (times in RFC 3339, UTC).
pub fn csv_rows(r: &Record) -> Vec<Vec<String>> {
    let iso = |ms: i64| {
        chrono::DateTime::from_timestamp_millis(ms)
            .map(|t| t.to_rfc3339_opts(chrono::SecondsFormat::Millis, true))
            .unwrap_or_default()
    };
    let o = |v: &Option<String>| v.clone().unwrap_or_default();
    let run = vec![
        r.uuid.clone(),
        r.kind.name().to_string(),
        iso(r.started_ms),
        o(&r.context.station),
        o(&r.context.slot),
        o(&r.context.operator),
        r.plan.clone(),
        o(&r.plan_sha256),
        r.profile.clone(),
        o(&r.unit.serial),
        r.unit
            .serial_source
            .map(|s| s.name().to_string())
            .unwrap_or_default(),
        r.verdict.name().to_string(),
    ];
    let mut out = Vec::new();
    for s in &r.steps {
        let mut step = run.clone();
        step.extend([
            s.name.clone(),
            s.kind.clone(),
            iso(s.started_ms),
            s.duration_ms.to_string(),
            s.verdict.name().to_string(),
            o(&s.reason),
        ]);
        if s.measurements.is_empty() {
            let mut row = step.clone();
            row.extend([String::new(), String::new(), String::new(), String::new()]);
            out.push(row);
        }
        for m in &s.measurements {
            let lim = |v: Option<f64>| v.map(|x| x.to_string()).unwrap_or_default();
            let mut row = step.clone();
            row.extend([
                m.name.clone(),
                m.unit.clone(),
                format!("{}..{}", lim(m.low), lim(m.high)),
                m.value.to_string(),
            ]);
            out.push(row);
        }
    }
    if r.steps.is_empty() {
        let mut row = run;
        row.resize(CSV_COLUMNS.len(), String::new());
        out.push(row);
    }
    out
}

/// Reads `--since` / `--until`: `2026-12-01`, `2026-12-01 06:00`, RFC 3339, or a span back
/// from now (`8h`, `7d`, `30m`); local time unless the text says a zone. Ms since 1970 UTC.
pub fn parse_time(text: &str) -> Result<i64, String> {
    use chrono::{NaiveDate, NaiveDateTime, TimeZone};
    let t = text.trim();
    let now = chrono::Utc::now().timestamp_millis();
    if let Some((n, unit)) = t
        .strip_suffix(['m', 'h', 'd'])
        .and_then(|n| n.parse::<i64>().ok())
        .map(|n| (n, t.chars().last()))
    {
        let ms = match unit {
            Some('m') => 60_000,
            Some('h') => 3_600_000,
            _ => 86_400_000,
        };
        return Ok(now - n.max(0) * ms);
    }
    if let Ok(dt) = chrono::DateTime::parse_from_rfc3339(t) {
        return Ok(dt.timestamp_millis());
    }
    let local = |naive: NaiveDateTime| {
        chrono::Local
            .from_local_datetime(&naive)
            .earliest()
            .map(|d| d.timestamp_millis())
    };
    for f in ["%Y-%m-%d %H:%M", "%Y-%m-%dT%H:%M", "%Y-%m-%d %H:%M:%S"] {
        if let Ok(n) = NaiveDateTime::parse_from_str(t, f)
            && let Some(ms) = local(n)
        {
            return Ok(ms);
        }
    }
    if let Ok(d) = NaiveDate::parse_from_str(t, "%Y-%m-%d")
        && let Some(ms) = d.and_hms_opt(0, 0, 0).and_then(local)
    {
        return Ok(ms);
    }
    Err(format!(
        "'{}' is not a time: give 2026-12-01, '2026-12-01 06:00', RFC 3339, or a span back from now such as 8h or 7d",
        crate::document::quote(t)
    ))
}
