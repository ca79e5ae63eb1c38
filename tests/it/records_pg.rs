//! Production records on a real PostgreSQL server (issue 28), the one `.ci/run` starts and names
//! in `BOTBENCH_TEST_POSTGRES` (with `BOTBENCH_TEST_PG_CTL`, the command that stops and starts
//! it). Without a server these tests say so on the terminal and pass only outside CI: with
//! `CI=true` a missing server fails them.
//!
//! Each test works in a schema of its own; they take turns (one of them stops the server).

use super::records::{check_hand_report, hand_query, hand_set, run};
use botbench::ops::records::report;
use botbench::ops::records::{LineStore, RecordsError, Saved, SqliteStore, Store};
use std::io::Write;
use std::sync::Mutex;

/// One test at a time: the spool test stops the server.
static SERVER: Mutex<()> = Mutex::new(());

/// The server's URL, or `None` (said on the terminal, past the test harness's capture) when
/// there is none; with `CI=true` a missing server fails the test.
fn server(test: &str) -> Option<String> {
    match std::env::var("BOTBENCH_TEST_POSTGRES") {
        Ok(url) if !url.trim().is_empty() => Some(url),
        _ => {
            assert!(
                std::env::var("CI").as_deref() != Ok("true"),
                "CI=true but BOTBENCH_TEST_POSTGRES is not set: .ci/run starts the PostgreSQL server"
            );
            let _ = writeln!(
                std::io::stderr(),
                "SKIPPED {test}: no PostgreSQL server (set BOTBENCH_TEST_POSTGRES=postgres://..., as .ci/run does)"
            );
            None
        }
    }
}

/// A fresh schema `name` on the server, and the URL that works in it.
fn schema(url: &str, name: &str) -> String {
    let mut c = postgres::Client::connect(url, postgres::NoTls).unwrap();
    // Durable at once: the test cluster commits asynchronously and some tests stop it in
    // immediate mode, which would lose a schema created just before.
    c.batch_execute(&format!(
        "SET synchronous_commit TO on; DROP SCHEMA IF EXISTS {name} CASCADE; CREATE SCHEMA {name}"
    ))
    .unwrap();
    let sep = if url.contains('?') { '&' } else { '?' };
    format!("{url}{sep}options=-c%20search_path%3D{name}")
}

fn count(url: &str, sql: &str) -> i64 {
    let mut c = postgres::Client::connect(url, postgres::NoTls).unwrap();
    c.query_one(sql, &[]).unwrap().get::<_, i64>(0)
}

#[test]
fn the_hand_set_on_postgresql_has_the_same_figures_as_worked_out_by_hand() {
    let _turn = SERVER.lock().unwrap_or_else(|e| e.into_inner());
    let Some(url) = server("the_hand_set_on_postgresql") else {
        return;
    };
    let url = schema(&url, "t_hand");
    let dir = crate::support::temp_dir();
    let mut store =
        LineStore::with_spool(&url, "test server", &dir.path().join("spool.sqlite")).unwrap();
    assert!(store.last_error().is_none(), "{:?}", store.last_error());
    for r in hand_set() {
        assert_eq!(store.save(&r).unwrap(), Saved::Stored);
    }
    // Saved again (a forward repeated after a crash): stored once.
    for r in hand_set() {
        assert_eq!(store.save(&r).unwrap(), Saved::Stored);
    }
    assert_eq!(count(&url, "SELECT COUNT(*) FROM runs"), 7);
    let mut out = None;
    store
        .read(&mut |db| {
            out = Some(report::compute(db, &hand_query(), "pg")?);
            Ok(())
        })
        .unwrap();
    check_hand_report(&out.unwrap());
    // A record reads back whole.
    let mut back = Vec::new();
    store
        .read(&mut |db| {
            botbench::ops::records::query::each_record(db, &Default::default(), &mut |r| {
                back.push(r);
                Ok(())
            })
        })
        .unwrap();
    assert_eq!(back, hand_set());
}

#[test]
fn a_refused_login_and_a_newer_schema_are_said_and_the_record_waits_in_the_spool() {
    let _turn = SERVER.lock().unwrap_or_else(|e| e.into_inner());
    let Some(url) = server("a_refused_login") else {
        return;
    };
    let dir = crate::support::temp_dir();
    // The test server's password user, with a wrong password.
    let port = url.rsplit(':').next().unwrap().split('/').next().unwrap();
    let wrong = format!("postgres://botbench_pw:wrong@127.0.0.1:{port}/botbench");
    let mut store = LineStore::with_spool(
        &wrong,
        "postgres://botbench_pw:***@test",
        &dir.path().join("a.sqlite"),
    )
    .unwrap();
    let e = store.last_error().cloned().unwrap();
    assert!(matches!(e, RecordsError::LoginRefused { .. }), "{e}");
    assert!(e.to_string().contains("refused the login"), "{e}");
    match store.save(&hand_set()[0]).unwrap() {
        Saved::Spooled { waiting: 1, why } => {
            assert!(matches!(why, RecordsError::LoginRefused { .. }))
        }
        other => panic!("{other:?}"),
    }
    let mut spool = SqliteStore::open(&dir.path().join("a.sqlite")).unwrap();
    assert_eq!(spool.oldest().unwrap().unwrap(), hand_set()[0]);

    let newer = schema(&url, "t_newer");
    drop(LineStore::with_spool(&newer, "test", &dir.path().join("b.sqlite")).unwrap());
    let mut c = postgres::Client::connect(&newer, postgres::NoTls).unwrap();
    c.execute(
        "INSERT INTO botbench_schema VALUES (99, 0, 'botbench 9')",
        &[],
    )
    .unwrap();
    let mut store = LineStore::with_spool(&newer, "test", &dir.path().join("b.sqlite")).unwrap();
    let e = store.last_error().cloned().unwrap();
    assert!(
        matches!(e, RecordsError::NewerSchema { found: 99, .. }),
        "{e}"
    );
    assert!(matches!(
        store.save(&hand_set()[1]).unwrap(),
        Saved::Spooled { .. }
    ));
    assert_eq!(count(&newer, "SELECT COUNT(*) FROM runs"), 0);
}

#[test]
fn the_server_killed_and_restarted_during_200_records_has_all_200_once_each() {
    let _turn = SERVER.lock().unwrap_or_else(|e| e.into_inner());
    let Some(url) = server("the_server_killed_and_restarted") else {
        return;
    };
    let Ok(ctl) = std::env::var("BOTBENCH_TEST_PG_CTL") else {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "CI=true but BOTBENCH_TEST_PG_CTL is not set"
        );
        let _ = writeln!(
            std::io::stderr(),
            "SKIPPED the spool test: BOTBENCH_TEST_PG_CTL (stop/start) not set"
        );
        return;
    };
    let pg_ctl = |what: &str| {
        let ran = crate::support::cli::watched(
            std::process::Command::new(&ctl)
                .arg(what)
                .stdin(std::process::Stdio::null()),
            &format!("{ctl} {what}"),
        );
        assert_eq!(ran.code, 0, "{ctl} {what}: {}", ran.text());
    };
    let url = schema(&url, "t_spool");
    let dir = crate::support::temp_dir();
    let spool = dir.path().join("spool.sqlite");
    let mut store = LineStore::with_spool(&url, "test server", &spool).unwrap();
    let mut uuids = Vec::new();
    let mut spooled = 0;
    for i in 0..200 {
        if i == 60 {
            // Killed (immediate shutdown: no checkpoint, connections cut) mid-run.
            pg_ctl("stop");
        }
        if i == 140 {
            pg_ctl("start");
            // Saves leave a failed server alone for a while; a forward tries it at once.
            assert_eq!(store.forward().unwrap(), 0);
        }
        let r = run(
            &format!("spool-{i:03}"),
            super::records::DAY + i * 1000,
            "A",
            "1",
            Some(&format!("S{i}")),
            &[("Battery voltage", "batteryVoltage", "V", 11.5, 12.6, 12.0)],
        );
        uuids.push(r.uuid.clone());
        match store.save(&r).unwrap() {
            Saved::Stored => assert!(
                !(60..140).contains(&i),
                "record {i} stored while the server was down"
            ),
            Saved::Spooled { waiting, why } => {
                assert!(
                    (60..140).contains(&i),
                    "record {i} spooled with the server up: {why}"
                );
                assert!(matches!(why, RecordsError::Unreachable { .. }), "{why}");
                spooled += 1;
                assert_eq!(waiting, spooled, "the spool counts what waits");
            }
        }
    }
    assert_eq!(spooled, 80);
    assert_eq!(store.waiting(), 0);
    assert_eq!(count(&url, "SELECT COUNT(*) FROM runs"), 200);
    // A crash between the server's commit and the spool's removal: the record is in both, and
    // forwarding it again stores nothing.
    let again = run(
        "spool-000",
        super::records::DAY,
        "A",
        "1",
        Some("S0"),
        &[("Battery voltage", "batteryVoltage", "V", 11.5, 12.6, 12.0)],
    );
    SqliteStore::open(&spool).unwrap().insert(&again).unwrap();
    assert_eq!(store.waiting(), 1);
    assert_eq!(store.forward().unwrap(), 0);
    assert_eq!(count(&url, "SELECT COUNT(*) FROM runs"), 200);
    assert_eq!(count(&url, "SELECT COUNT(DISTINCT uuid) FROM runs"), 200);
    assert_eq!(count(&url, "SELECT COUNT(*) FROM steps"), 200);
    // In order: the server's ids follow the runs' order.
    let mut c = postgres::Client::connect(&url, postgres::NoTls).unwrap();
    let order: Vec<String> = c
        .query("SELECT uuid FROM runs ORDER BY id", &[])
        .unwrap()
        .iter()
        .map(|r| r.get(0))
        .collect();
    assert_eq!(order, uuids);
}

#[test]
fn a_station_s_records_spooled_while_the_server_was_away_are_forwarded_once_it_is_back() {
    use botbench::ops::station::What;
    let _turn = SERVER.lock().unwrap_or_else(|e| e.into_inner());
    let Some(url) = server("a_station_s_records_spooled") else {
        return;
    };
    let Ok(ctl) = std::env::var("BOTBENCH_TEST_PG_CTL") else {
        assert!(std::env::var("CI").as_deref() != Ok("true"));
        let _ = writeln!(
            std::io::stderr(),
            "SKIPPED the station spool test: BOTBENCH_TEST_PG_CTL (stop/start) not set"
        );
        return;
    };
    let pg_ctl = |what: &str| {
        let ok = std::process::Command::new(&ctl)
            .arg(what)
            .stdout(std::process::Stdio::null())
            .status()
            .unwrap()
            .success();
        assert!(ok, "{ctl} {what}");
    };
    let url = schema(&url, "t_station_spool");
    let dir = crate::support::temp_dir();
    pg_ctl("stop");
    let (_, started) = super::station_records::demo_station(&url, &dir.path().join("spool.sqlite"));
    let events = super::station_records::run_to_the_end(&started);
    let waiting = |e: &botbench::ops::station::Event| match e.what {
        What::Records { waiting, .. } => Some(waiting),
        _ => None,
    };
    assert_eq!(
        events.iter().filter_map(waiting).max(),
        Some(3),
        "{events:#?}"
    );
    pg_ctl("start");
    // The forwarder (slot "") sends them on by itself: no unit runs after the server is back.
    let deadline = std::time::Instant::now() + crate::support::cli::WATCHDOG;
    let mut seen = Vec::new();
    loop {
        assert!(
            std::time::Instant::now() < deadline,
            "never forwarded; seen since the server started: {seen:#?}"
        );
        let Ok(ev) = started
            .events
            .recv_timeout(std::time::Duration::from_millis(200))
        else {
            continue;
        };
        let done = ev.slot.is_empty() && waiting(&ev) == Some(0);
        seen.push(ev);
        if done {
            break;
        }
    }
    started.forwarder.stop();
    assert_eq!(count(&url, "SELECT COUNT(DISTINCT uuid) FROM runs"), 3);
    assert_eq!(count(&url, "SELECT COUNT(*) FROM runs"), 3);
}
