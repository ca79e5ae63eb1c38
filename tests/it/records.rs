//! Production records on SQLite (issue 28): a record stored whole and read back the same, stored
//! once whatever happens, refused files named, a full disk kept in the fallback spool, a killed
//! process leaving no half record, and the report's figures against numbers worked out by hand.
//! `records_pg.rs` runs the same against a real PostgreSQL server.

use botbench::ops::records::report::{self, Query, Report};
use botbench::ops::records::sql::Lite;
use botbench::ops::records::{
    Kept, Location, Measurement, ParamWrite, Record, Recorder, RecordsError, RunContext, RunKind,
    SerialSource, SqliteStore, StepRecord, Store, Unit, Verdict, write,
};
use std::path::Path;

/// 2026-12-01 00:00 UTC, ms.
pub const DAY: i64 = 1_796_083_200_000;
const HOUR: i64 = 3_600_000;

/// A record of a hand-made run: `steps` as (name, measurement, unit, low, high, value).
#[allow(clippy::type_complexity)]
pub fn run(
    uuid: &str,
    at: i64,
    station: &str,
    slot: &str,
    serial: Option<&str>,
    steps: &[(&str, &str, &str, f64, f64, f64)],
) -> Record {
    let mut r = Record::start(
        RunKind::Selftest,
        "Line test",
        Some("ab".repeat(32)),
        "window-cleaner",
    );
    r.uuid = uuid.into();
    r.started_ms = at;
    r.utc_offset_min = 0;
    r.context = RunContext {
        station: Some(station.into()),
        slot: Some(slot.into()),
        fixture: None,
        operator: Some("ana".into()),
        bundle_sha256: None,
    };
    r.unit = Unit {
        serial: serial.map(str::to_string),
        serial_source: serial.map(|_| SerialSource::Scanned),
        hardware: Some("0x03".into()),
        firmware: Some("1.4.2".into()),
        build: Some("7".into()),
    };
    for (i, (name, m, unit, low, high, value)) in steps.iter().enumerate() {
        let pass = value >= low && value <= high;
        r.steps.push(StepRecord {
            name: (*name).into(),
            kind: "Range".into(),
            started_ms: at + i as i64 * 1000,
            duration_ms: 900,
            verdict: Verdict::of(pass),
            reason: (!pass).then(|| format!("out of limits: {m}")),
            detail: format!("{m} {value} {unit}"),
            measurements: vec![Measurement {
                name: (*m).into(),
                unit: (*unit).into(),
                low: Some(*low),
                high: Some(*high),
                value: *value,
                pass,
            }],
            writes: Vec::new(),
        });
    }
    r.finish(None);
    r.ended_ms = at + 2000;
    r
}

fn unit_run(
    uuid: &str,
    at: i64,
    station: &str,
    slot: &str,
    serial: Option<&str>,
    battery: f64,
    fan: f64,
) -> Record {
    run(
        uuid,
        at,
        station,
        slot,
        serial,
        &[
            (
                "Battery voltage",
                "batteryVoltage",
                "V",
                11.5,
                12.6,
                battery,
            ),
            ("Fan current", "fanCurrent", "A", 0.8, 1.6, fan),
        ],
    )
}

/// Seven runs of five units, in the order recorded:
///
/// | run | unit | station/slot | shift (UTC) | battery V | fan A | verdict |
/// | 1 | U1 | A/1 | 12-01 07:00 A | 12.0 | 1.0 | PASS |
/// | 2 | U2 | A/2 | 12-01 07:30 A | 11.2 | 1.1 | FAIL battery |
/// | 3 | U2 | A/2 | 12-01 08:00 A | 12.1 | 1.2 | PASS (retest) |
/// | 4 | U3 | B/1 | 12-01 15:00 B | 12.2 | 1.7 | FAIL fan |
/// | 5 | U3 | B/1 | 12-01 15:30 B | 12.3 | 1.8 | FAIL fan (retest) |
/// | 6 | U4 | B/1 | 12-01 23:30 C | 12.4 | 1.3 | PASS |
/// | 7 | (no serial) | A/1 | 12-02 03:00 C of 12-01 | 11.4 | 1.0 | FAIL battery |
pub fn hand_set() -> Vec<Record> {
    vec![
        unit_run("u1-a", DAY + 7 * HOUR, "A", "1", Some("U1"), 12.0, 1.0),
        unit_run(
            "u2-a",
            DAY + 7 * HOUR + HOUR / 2,
            "A",
            "2",
            Some("U2"),
            11.2,
            1.1,
        ),
        unit_run("u2-b", DAY + 8 * HOUR, "A", "2", Some("U2"), 12.1, 1.2),
        unit_run("u3-a", DAY + 15 * HOUR, "B", "1", Some("U3"), 12.2, 1.7),
        unit_run(
            "u3-b",
            DAY + 15 * HOUR + HOUR / 2,
            "B",
            "1",
            Some("U3"),
            12.3,
            1.8,
        ),
        unit_run(
            "u4-a",
            DAY + 23 * HOUR + HOUR / 2,
            "B",
            "1",
            Some("U4"),
            12.4,
            1.3,
        ),
        unit_run("u5-a", DAY + 27 * HOUR, "A", "1", None, 11.4, 1.0),
    ]
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-9
}

/// The report of [`hand_set`], against the figures worked out by hand.
pub fn check_hand_report(r: &Report) {
    let y = |rows: &[report::Yield], g: &str| {
        rows.iter()
            .find(|y| y.group == g)
            .map(|y| (y.units, y.runs, y.first_pass, y.final_pass))
            .unwrap_or_else(|| panic!("no group {g} in {rows:?}"))
    };
    // Units U1, U2, U3, U4 and the serial-less run: U1 and U4 pass first time (2 of 5), U2
    // passes on its retest (3 of 5 in the end), U3 and the serial-less one never.
    let o = &r.overall;
    assert_eq!(
        (o.units, o.runs, o.first_pass, o.final_pass),
        (5, 7, 2, 3),
        "{o:?}"
    );
    assert!(close(o.fpy(), 0.4) && close(o.final_yield(), 0.6));
    // Per shift: A has U1 and U2 (3 runs); B has U3 (2 runs); C of 12-01 has U4 and the
    // serial-less run at 03:00 the next morning.
    assert_eq!(r.by_shift.len(), 3, "{:?}", r.by_shift);
    assert_eq!(y(&r.by_shift, "2026-12-01 A"), (2, 3, 1, 2));
    assert_eq!(y(&r.by_shift, "2026-12-01 B"), (1, 2, 0, 0));
    assert_eq!(y(&r.by_shift, "2026-12-01 C"), (2, 2, 1, 1));
    // Per station: A has U1, U2 and the serial-less unit (4 runs), B has U3 and U4 (3 runs).
    assert_eq!(y(&r.by_station, "A"), (3, 4, 1, 2));
    assert_eq!(y(&r.by_station, "B"), (2, 3, 1, 1));
    assert_eq!(y(&r.by_slot, "1"), (4, 5, 2, 2));
    assert_eq!(y(&r.by_slot, "2"), (1, 2, 0, 1));
    assert_eq!(r.by_plan.len(), 1);
    assert_eq!(
        y(&r.by_plan, &format!("Line test {}", "ab".repeat(4))),
        (5, 7, 2, 3)
    );
    // Pareto: two battery failures (runs 2 and 7), two fan failures (runs 4 and 5).
    let pareto: Vec<(&str, u64)> = r
        .pareto
        .iter()
        .map(|p| (p.step.as_str(), p.count))
        .collect();
    assert_eq!(pareto, [("Battery voltage", 2), ("Fan current", 2)]);
    assert!(close(r.pareto[0].share, 0.5) && close(r.pareto[1].cumulative, 1.0));
    assert_eq!(r.causes[0].reason, "out of limits: batteryVoltage");
    // batteryVoltage: 12.0 11.2 12.1 12.2 12.3 12.4 11.4: sum 83.6, mean 11.942857142857143;
    // squared deviations sum 1.2771428571, / 6 = 0.2128571429, sigma 0.4613644360558614;
    // Cpk = min(12.6 - mean, mean - 11.5) / 3 sigma = 0.4428571 / 1.3840933 = 0.31996191314836.
    let b = r
        .measurements
        .iter()
        .find(|m| m.name == "batteryVoltage")
        .expect("batteryVoltage");
    assert_eq!((b.n, b.failed, b.unit.as_str()), (7, 2, "V"));
    assert!((b.mean - 11.942857142857143).abs() < 1e-9, "{}", b.mean);
    assert!((b.sigma - 0.4613644360558614).abs() < 1e-9, "{}", b.sigma);
    assert!((b.cpk.unwrap_or_default() - 0.31996191314836014).abs() < 1e-9);
    assert_eq!((b.min, b.max), (11.2, 12.4));
    // Its histogram: 20 bins over 11.2 (its lowest) to 12.6 (its high limit), a bin either
    // side: width 1.4 / 18; 11.2 falls in bin 1, 12.4 in bin 1 + floor(1.2 / (1.4 / 18)) = 16.
    assert_eq!(b.bins.iter().sum::<u64>(), 7);
    assert!(close(b.bin_width, 1.4 / 18.0));
    assert_eq!(b.bins[1], 1, "{:?}", b.bins);
    assert_eq!(b.bins[16], 1, "{:?}", b.bins);
    // fanCurrent: 1.0 1.1 1.2 1.7 1.8 1.3 1.0: mean 1.3, sigma 0.32659863237109044,
    // Cpk = min(0.3, 0.5) / 3 sigma = 0.3061862178478973.
    let f = r
        .measurements
        .iter()
        .find(|m| m.name == "fanCurrent")
        .expect("fanCurrent");
    assert_eq!((f.n, f.failed), (7, 2));
    assert!((f.mean - 1.3).abs() < 1e-9 && (f.sigma - 0.32659863237109044).abs() < 1e-9);
    assert!((f.cpk.unwrap_or_default() - 0.3061862178478973).abs() < 1e-9);
    assert!(r.measurements.iter().all(|m| m.drift.is_none()));
}

/// A report with the hand set's query (drift windows of 2).
pub fn hand_query() -> Query {
    Query {
        drift_window: 2,
        ..Query::default()
    }
}

fn report_of(store: &mut dyn Store, q: &Query) -> Report {
    let mut out = None;
    store
        .read(&mut |db| {
            out = Some(report::compute(db, q, "test")?);
            Ok(())
        })
        .unwrap();
    out.unwrap()
}

fn temp() -> tempfile::TempDir {
    crate::support::temp_dir()
}

#[test]
fn a_record_reads_back_whole_and_a_second_save_of_it_stores_nothing() {
    let dir = temp();
    let mut store = SqliteStore::open(&dir.path().join("r.sqlite")).unwrap();
    let mut r = hand_set().remove(1);
    r.steps[0].writes.push(ParamWrite {
        name: "over_temprature".into(),
        unit: "°C".into(),
        value: "70".into(),
        before: Some("80".into()),
        after: Some("70".into()),
    });
    assert!(store.insert(&r).unwrap());
    assert!(!store.insert(&r).unwrap(), "stored twice");
    assert_eq!(store.count().unwrap(), 1);
    let back = store.oldest().unwrap().unwrap();
    assert_eq!(back, r);
    // WAL mode, as the records need for a reader beside the writer.
    let mode: String = store
        .connection()
        .query_row("PRAGMA journal_mode", [], |row| row.get(0))
        .unwrap();
    assert_eq!(mode, "wal");
}

#[test]
fn the_report_of_the_hand_set_has_the_figures_worked_out_by_hand() {
    let dir = temp();
    let mut store = SqliteStore::open(&dir.path().join("r.sqlite")).unwrap();
    for r in hand_set() {
        store.insert(&r).unwrap();
    }
    check_hand_report(&report_of(&mut store, &hand_query()));
    // The period's filter: from 12-01 15:00, only U3's two runs, U4's and the serial-less one.
    let q = Query {
        filter: botbench::ops::records::Filter {
            since_ms: Some(DAY + 15 * HOUR),
            ..Default::default()
        },
        ..hand_query()
    };
    let r = report_of(&mut store, &q);
    assert_eq!((r.overall.units, r.overall.runs), (3, 4));
    let b = r
        .measurements
        .iter()
        .find(|m| m.name == "batteryVoltage")
        .unwrap();
    assert_eq!(b.n, 4);
    assert!((b.mean - (12.2 + 12.3 + 12.4 + 11.4) / 4.0).abs() < 1e-9);
}

#[test]
fn a_measurement_walking_toward_its_limit_is_a_drift_and_a_steady_one_is_not() {
    let dir = temp();
    let mut store = SqliteStore::open(&dir.path().join("r.sqlite")).unwrap();
    let tx = store.connection().transaction().unwrap();
    botbench::ops::records::demo::generate(1200, DAY, DAY + 86_400_000, 3, &mut |r| {
        write::insert(&mut Lite(&tx), &r).unwrap();
    });
    tx.commit().unwrap();
    let r = report_of(&mut store, &Query::default());
    let drifting: Vec<&str> = r
        .measurements
        .iter()
        .filter(|m| m.drift.is_some())
        .map(|m| m.name.as_str())
        .collect();
    // The generator walks the fan current up over the last 300 units; nothing else moves.
    assert_eq!(drifting, ["fanCurrent"]);
    let d = r
        .measurements
        .iter()
        .find(|m| m.name == "fanCurrent")
        .unwrap();
    let drift = d.drift.as_ref().unwrap();
    assert_eq!((drift.toward, drift.limit), ("high", 1.6));
    assert!(drift.means[0] < drift.means[1] && drift.means[1] < drift.means[2]);
}

#[test]
fn drift_follows_the_order_units_were_tested_not_the_order_their_records_arrived() {
    // The same 1200 units as above, but the last 300 (the fan current walking up) were stored
    // first and the 900 before them arrived afterwards, forwarded from a station's spool: in
    // arrival order the newest 150 values are steady units, in test order the walk.
    let dir = temp();
    let mut store = SqliteStore::open(&dir.path().join("r.sqlite")).unwrap();
    let mut all = Vec::new();
    botbench::ops::records::demo::generate(1200, DAY, DAY + 86_400_000, 3, &mut |r| all.push(r));
    let cut = DAY + 86_400_000 * 900 / 1200;
    let (late, early): (Vec<Record>, Vec<Record>) =
        all.into_iter().partition(|r| r.started_ms >= cut);
    assert!(late.len() >= 300 && early.len() >= 900);
    let tx = store.connection().transaction().unwrap();
    for r in late.iter().chain(&early) {
        write::insert(&mut Lite(&tx), r).unwrap();
    }
    tx.commit().unwrap();
    let r = report_of(&mut store, &Query::default());
    let fan = r
        .measurements
        .iter()
        .find(|m| m.name == "fanCurrent")
        .unwrap();
    let drift = fan
        .drift
        .as_ref()
        .unwrap_or_else(|| panic!("no drift: {:?}", fan.recent_means));
    assert_eq!((drift.toward, drift.limit), ("high", 1.6));
    let drifting = r.measurements.iter().filter(|m| m.drift.is_some()).count();
    assert_eq!(drifting, 1);
    // A period filter reads the runs the same way.
    let q = Query {
        filter: botbench::ops::records::Filter {
            since_ms: Some(DAY),
            ..Default::default()
        },
        ..Query::default()
    };
    let r = report_of(&mut store, &q);
    let fan = r
        .measurements
        .iter()
        .find(|m| m.name == "fanCurrent")
        .unwrap();
    assert!(fan.drift.is_some(), "{:?}", fan.recent_means);
}

#[test]
fn a_file_that_is_not_botbenchs_or_is_newer_is_refused_naming_it() {
    let dir = temp();
    let text = dir.path().join("notes.txt");
    std::fs::write(&text, "a shopping list, not a database\n".repeat(200)).unwrap();
    let e = SqliteStore::open(&text).err().unwrap();
    assert!(matches!(e, RecordsError::NotDatabase { .. }), "{e}");
    assert!(e.to_string().contains("notes.txt") && e.to_string().contains("not a SQLite database"));

    let other = dir.path().join("other.sqlite");
    let conn = rusqlite::Connection::open(&other).unwrap();
    conn.execute_batch("CREATE TABLE invoices (id INTEGER PRIMARY KEY, total REAL)")
        .unwrap();
    drop(conn);
    let e = SqliteStore::open(&other).err().unwrap();
    assert!(matches!(e, RecordsError::NotBotbench { .. }), "{e}");
    assert!(
        e.to_string().contains("other.sqlite") && e.to_string().contains("invoices"),
        "{e}"
    );
    // Nothing was added to it.
    let conn = rusqlite::Connection::open(&other).unwrap();
    let tables: i64 = conn
        .query_row(
            "SELECT COUNT(*) FROM sqlite_master WHERE type = 'table'",
            [],
            |r| r.get(0),
        )
        .unwrap();
    assert_eq!(tables, 1);

    let newer = dir.path().join("newer.sqlite");
    drop(SqliteStore::open(&newer).unwrap());
    let conn = rusqlite::Connection::open(&newer).unwrap();
    conn.execute(
        "INSERT INTO botbench_schema VALUES (99, 0, 'botbench 9.0')",
        [],
    )
    .unwrap();
    drop(conn);
    let e = SqliteStore::open(&newer).err().unwrap();
    assert!(
        matches!(e, RecordsError::NewerSchema { found: 99, .. }),
        "{e}"
    );
    assert!(e.to_string().contains("newer botbench"), "{e}");
}

#[test]
fn a_malformed_records_url_is_refused_naming_what_is_wrong() {
    for (given, says) in [
        (
            "postgres://ana:secret@host:notaport/db",
            "not a PostgreSQL URL",
        ),
        ("mysql://line/db", "neither"),
        ("  ", "empty"),
    ] {
        let e = Location::parse(given)
            .err()
            .unwrap_or_else(|| panic!("{given} taken"));
        let text = e.to_string();
        assert!(text.contains(says), "{given}: {text}");
        assert!(!text.contains("secret"), "the password shown: {text}");
    }
    assert_eq!(
        Location::parse("postgres://ana:secret@line-db/records")
            .unwrap()
            .to_string(),
        "postgres://ana:***@line-db/records"
    );
    assert!(matches!(
        Location::parse("line3.sqlite"),
        Ok(Location::Sqlite(_))
    ));
}

#[test]
fn a_full_disk_keeps_the_record_in_the_fallback_spool_and_forwards_it_once_there_is_room() {
    let dir = temp();
    let path = dir.path().join("full.sqlite");
    let mut store = SqliteStore::open(&path).unwrap();
    // The file may not grow: what a full disk does to SQLite.
    let pages: i64 = store
        .connection()
        .query_row("PRAGMA page_count", [], |r| r.get(0))
        .unwrap();
    store.limit_pages(pages as u64).unwrap();
    let fallback = dir.path().join("unsaved.sqlite");
    let mut recorder = Recorder::with_store(
        Box::new(store),
        RunContext::default(),
        Some(fallback.clone()),
    );
    let mut r = hand_set().remove(0);
    let big = "x".repeat(64 << 10);
    r.steps[0].detail = big;
    let kept = recorder.save(&mut r);
    match &kept {
        Kept::Spooled {
            why,
            spool,
            waiting,
        } => {
            assert!(matches!(why, RecordsError::DiskFull { .. }), "{why}");
            assert!(
                why.to_string().contains("full.sqlite") && why.to_string().contains("disk is full")
            );
            assert!(spool.contains("unsaved.sqlite"), "{spool}");
            assert_eq!(*waiting, 1);
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(recorder.waiting(), 1);
    // Room again (a new connection has no page limit): the record goes over, once.
    let mut recorder = Recorder::with_store(
        Box::new(SqliteStore::open(&path).unwrap()),
        RunContext::default(),
        Some(fallback),
    );
    assert_eq!(recorder.forward_waiting().unwrap(), 0);
    assert_eq!(recorder.waiting(), 0);
    assert_eq!(recorder.forward_waiting().unwrap(), 0);
    let mut main = SqliteStore::open(&path).unwrap();
    assert_eq!(main.count().unwrap(), 1);
    assert_eq!(main.oldest().unwrap().unwrap().uuid, r.uuid);
}

/// The consistency of a records file: every run has exactly the steps it says, and every step
/// its measurement; returns the runs.
pub fn whole_records(path: &Path) -> i64 {
    let conn = rusqlite::Connection::open(path).unwrap();
    let half: i64 = conn
        .query_row(
            "SELECT COUNT(*) FROM runs r WHERE r.steps <> (SELECT COUNT(*) FROM steps s WHERE s.run = r.id) \
             OR r.steps <> (SELECT COUNT(*) FROM measurements m WHERE m.run = r.id)",
            [],
            |row| row.get(0),
        )
        .unwrap();
    assert_eq!(half, 0, "runs whose steps are not all there");
    conn.query_row("SELECT COUNT(*) FROM runs", [], |row| row.get(0))
        .unwrap()
}

#[test]
fn a_process_killed_while_it_writes_records_leaves_no_half_record() {
    let dir = temp();
    let path = dir.path().join("killed.sqlite");
    let mut child = crate::support::cli::botbench([
        "records",
        "--records",
        path.to_str().unwrap(),
        "demo",
        "--units",
        "1000000",
    ])
    .stdout(std::process::Stdio::null())
    .stderr(std::process::Stdio::null())
    .spawn()
    .unwrap();
    // Killed once some records are in (each is its own transaction), within 60 s.
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
    loop {
        let n = rusqlite::Connection::open(&path)
            .ok()
            .and_then(|c| {
                c.query_row("SELECT COUNT(*) FROM runs", [], |r| r.get::<_, i64>(0))
                    .ok()
            })
            .unwrap_or(0);
        if n >= 20 {
            break;
        }
        assert!(std::time::Instant::now() < deadline, "no records written");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let runs = whole_records(&path);
    assert!(runs >= 20, "{runs}");
    // And the file opens and takes records as before.
    let mut store = SqliteStore::open(&path).unwrap();
    assert!(store.insert(&hand_set().remove(0)).unwrap());
}
