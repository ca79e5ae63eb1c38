//! `bench --only records-report`: `botbench report` over a million step records (issue 28:
//! at most 2 s on SQLite, 5 s on PostgreSQL). The records are generated
//! ([`crate::ops::records::demo`]: 100,000 units of ten measured steps, the failed ones
//! retested) into a temporary SQLite file, and, when `BOTBENCH_BENCH_POSTGRES` names a server,
//! into a schema of its own there (dropped afterwards); the report is computed three times on
//! each and its median time given.

use super::Figure;
use crate::ops::records::demo;
use crate::ops::records::report::{self, Query};
use crate::ops::records::sql::{Lite, Pg};
use crate::ops::records::{Record, SqliteStore, schema, write};
use std::io::Write;
use std::time::Instant;

/// Units generated: ten step records each, and about 4 % retested.
const UNITS: usize = 100_000;
/// Reports computed on each database; the median is the figure.
const RUNS: usize = 3;
/// The environment variable naming the PostgreSQL server for the benchmark.
pub const POSTGRES_ENV: &str = "BOTBENCH_BENCH_POSTGRES";

/// The generated records, a batch at a time, to `each`; the number of step records.
fn generate(each: &mut dyn FnMut(&[Record]) -> Result<(), String>) -> Result<u64, String> {
    let end = crate::ops::records::record::now_ms();
    let start = end - 30 * 86_400_000;
    let mut batch = Vec::with_capacity(2000);
    let mut steps = 0u64;
    let mut failed = None;
    demo::generate(UNITS, start, end, 28, &mut |r| {
        steps += r.steps.len() as u64;
        batch.push(r);
        if batch.len() == 2000 && failed.is_none() {
            failed = each(&batch).err();
            batch.clear();
        }
    });
    if let Some(e) = failed {
        return Err(e);
    }
    if !batch.is_empty() {
        each(&batch)?;
    }
    Ok(steps)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The SQLite figure, and PostgreSQL's when [`POSTGRES_ENV`] is set.
pub(super) fn records_report() -> Result<Vec<Figure>, String> {
    let mut out = vec![sqlite()?];
    match std::env::var(POSTGRES_ENV) {
        Ok(url) if !url.trim().is_empty() => out.push(postgres(&url)?),
        _ => out.push(Figure::new(
            "records report, PostgreSQL, 1M step records",
            0.0,
            0.0,
            format!("not measured: set {POSTGRES_ENV}=postgres://USER@HOST/DB (a schema of its own is made and dropped)"),
        )),
    }
    Ok(out)
}

/// Where the SQLite case keeps its generated file between runs when set (generated there once);
/// otherwise a temporary file.
pub const SQLITE_FILE_ENV: &str = "BOTBENCH_BENCH_RECORDS_FILE";

fn sqlite() -> Result<Figure, String> {
    let dir = tempfile::tempdir().map_err(|e| e.to_string())?;
    let path = match std::env::var(SQLITE_FILE_ENV) {
        Ok(p) if !p.trim().is_empty() => std::path::PathBuf::from(p),
        _ => dir.path().join("bench.sqlite"),
    };
    let mut store = SqliteStore::open(&path).map_err(|e| e.to_string())?;
    let loaded = Instant::now();
    let kept = store.count().map_err(|e| e.to_string())? > 0;
    let steps = if kept {
        let n: i64 = store
            .connection()
            .query_row("SELECT COUNT(*) FROM steps", [], |r| r.get(0))
            .map_err(|e| e.to_string())?;
        n as u64
    } else {
        generate(&mut |batch| {
            let conn = store.connection();
            let tx = conn.transaction().map_err(|e| e.to_string())?;
            for r in batch {
                write::insert(&mut Lite(&tx), r).map_err(|e| e.to_string())?;
            }
            tx.commit().map_err(|e| e.to_string())
        })?
    };
    store
        .connection()
        .execute_batch("ANALYZE")
        .map_err(|e| e.to_string())?;
    let load = loaded.elapsed().as_secs_f64();
    let mut times = Vec::new();
    let mut summary = String::new();
    for _ in 0..RUNS {
        let t = Instant::now();
        let r = report::of_store(&mut store, &Query::default()).map_err(|e| e.to_string())?;
        times.push(t.elapsed().as_secs_f64());
        summary = said(&r);
    }
    let size = std::fs::metadata(store.path())
        .map(|m| m.len())
        .unwrap_or(0);
    Ok(Figure::new(
        "records report, SQLite, 1M step records",
        median(times.clone()),
        0.0,
        format!(
            "{steps} step records ({} MB file, loaded in {}); {RUNS} reports: {}; {summary}",
            size >> 20,
            super::ms(load),
            times
                .iter()
                .map(|t| super::ms(*t))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    )
    .at_most_seconds(2.0))
}

fn said(r: &report::Report) -> String {
    let phases: Vec<String> = r
        .phases
        .iter()
        .map(|(name, s)| format!("{name} {s:.3}"))
        .collect();
    format!(
        "{} units, first-pass {:.1} %, final {:.1} %, {} measurements, {} drifting; last report's parts (s): {}",
        r.overall.units,
        100.0 * r.overall.fpy(),
        100.0 * r.overall.final_yield(),
        r.measurements.len(),
        r.measurements.iter().filter(|m| m.drift.is_some()).count(),
        phases.join(", ")
    )
}

/// COPY's text format: tab-separated, `\N` for null, backslash escapes.
fn cell(out: &mut Vec<u8>, v: Option<&str>) {
    match v {
        None => out.extend_from_slice(b"\\N"),
        Some(s) => {
            for c in s.chars() {
                match c {
                    '\\' => out.extend_from_slice(b"\\\\"),
                    '\t' => out.extend_from_slice(b"\\t"),
                    '\n' => out.extend_from_slice(b"\\n"),
                    '\r' => out.extend_from_slice(b"\\r"),
                    c => {
                        let mut buf = [0u8; 4];
                        out.extend_from_slice(c.encode_utf8(&mut buf).as_bytes());
                    }
                }
            }
        }
    }
}

fn row(out: &mut Vec<u8>, cells: &[Option<String>]) {
    for (i, c) in cells.iter().enumerate() {
        if i > 0 {
            out.push(b'\t');
        }
        cell(out, c.as_deref());
    }
    out.push(b'\n');
}

/// Loads a batch with COPY (three streams: runs, steps, measurements), run ids from `next_id`.
fn copy_batch(
    client: &mut postgres::Client,
    batch: &[Record],
    next_id: &mut i64,
) -> Result<(), String> {
    let (mut runs, mut steps, mut ms) = (Vec::new(), Vec::new(), Vec::new());
    let s = |v: &str| Some(v.to_string());
    let n = |v: i64| Some(v.to_string());
    for r in batch {
        *next_id += 1;
        let id = *next_id;
        let c = &r.context;
        row(
            &mut runs,
            &[
                n(id),
                s(&r.uuid),
                s(r.kind.name()),
                n(r.started_ms),
                n(r.ended_ms),
                n(i64::from(r.utc_offset_min)),
                s(r.verdict.name()),
                r.failed_step.clone(),
                r.reason.clone(),
                c.station.clone(),
                c.slot.clone(),
                c.fixture.clone(),
                c.operator.clone(),
                c.bundle_sha256.clone(),
                s(&r.host),
                s(&r.plan),
                r.plan_sha256.clone(),
                s(&r.profile),
                s(&r.software),
                s(&r.commit),
                r.unit.serial.clone(),
                r.unit.serial_source.map(|x| x.name().to_string()),
                r.unit.hardware.clone(),
                r.unit.firmware.clone(),
                r.unit.build.clone(),
                n(r.steps.len() as i64),
            ],
        );
        for (i, st) in r.steps.iter().enumerate() {
            row(
                &mut steps,
                &[
                    n(id),
                    n(i as i64),
                    s(&st.name),
                    s(&st.kind),
                    n(st.started_ms),
                    n(st.duration_ms),
                    s(st.verdict.name()),
                    st.reason.clone(),
                    s(&st.detail),
                ],
            );
            for (j, m) in st.measurements.iter().enumerate() {
                row(
                    &mut ms,
                    &[
                        n(id),
                        n(i as i64),
                        n(j as i64),
                        s(&m.name),
                        s(&m.unit),
                        m.low.map(|x| x.to_string()),
                        m.high.map(|x| x.to_string()),
                        Some(m.value.to_string()),
                        n(i64::from(m.pass)),
                    ],
                );
            }
        }
    }
    let e = |e: postgres::Error| e.to_string();
    for (sql, data) in [
        (
            "COPY runs (id, uuid, kind, started_ms, ended_ms, utc_offset_min, verdict, failed_step, \
             reason, station, slot, fixture, operator, bundle_sha256, host, plan, plan_sha256, \
             profile, software, software_commit, serial, serial_source, hardware, firmware, build, \
             steps) FROM STDIN",
            runs,
        ),
        (
            "COPY steps (run, idx, name, kind, started_ms, duration_ms, verdict, reason, detail) FROM STDIN",
            steps,
        ),
        (
            "COPY measurements (run, step, idx, name, unit, low, high, value, pass) FROM STDIN",
            ms,
        ),
    ] {
        let mut w = client.copy_in(sql).map_err(e)?;
        w.write_all(&data).map_err(|e| e.to_string())?;
        w.finish().map_err(e)?;
    }
    Ok(())
}

fn postgres(url: &str) -> Result<Figure, String> {
    let e = |e: postgres::Error| format!("{POSTGRES_ENV}: {e}");
    let mut client = postgres::Client::connect(url, postgres::NoTls).map_err(e)?;
    let schema_name = format!("botbench_bench_{}", std::process::id());
    client
        .batch_execute(&format!(
            "DROP SCHEMA IF EXISTS {schema_name} CASCADE; CREATE SCHEMA {schema_name}; SET search_path TO {schema_name}"
        ))
        .map_err(e)?;
    let result = (|| {
        {
            let mut tx = client.transaction().map_err(e)?;
            schema::migrate(&mut Pg(&mut tx))
                .map_err(|_| "cannot create the schema".to_string())?;
            tx.commit().map_err(e)?;
        }
        let loaded = Instant::now();
        let mut next_id = 0i64;
        let steps = generate(&mut |batch| copy_batch(&mut client, batch, &mut next_id))?;
        client
            .batch_execute("SELECT setval(pg_get_serial_sequence('runs', 'id'), (SELECT MAX(id) FROM runs)); ANALYZE")
            .map_err(e)?;
        let load = loaded.elapsed().as_secs_f64();
        let mut times = Vec::new();
        let mut summary = String::new();
        for _ in 0..RUNS {
            let t = Instant::now();
            // The yields on a second connection, in the same schema, as `of_store` does.
            let (url, schema_name) = (url.to_string(), schema_name.clone());
            let second: crate::ops::records::sql::Opener = Box::new(move || {
                let mut c = postgres::Client::connect(&url, postgres::NoTls)?;
                c.batch_execute(&format!("SET search_path TO {schema_name}"))?;
                Ok(Box::new(crate::ops::records::sql::OwnedPg(c))
                    as Box<dyn crate::ops::records::sql::Db + Send>)
            });
            let r = report::compute_with(
                &mut Pg(&mut client),
                Some(second),
                &Query::default(),
                "bench",
            )
            .map_err(|e| e.to_string())?;
            times.push(t.elapsed().as_secs_f64());
            summary = said(&r);
        }
        Ok(Figure::new(
            "records report, PostgreSQL, 1M step records",
            median(times.clone()),
            0.0,
            format!(
                "{steps} step records (loaded by COPY in {}); {RUNS} reports: {}; {summary}",
                super::ms(load),
                times
                    .iter()
                    .map(|t| super::ms(*t))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        )
        .at_most_seconds(5.0))
    })();
    let _ = client.batch_execute(&format!("DROP SCHEMA IF EXISTS {schema_name} CASCADE"));
    result
}
