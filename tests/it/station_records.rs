//! The station's records when their store is away (issue 28): every verdict is still said and
//! its record kept in the spool on this PC, the station says how many wait (a `records` event,
//! as the headless JSON prints it, and a line in the window's header, a note on the tile), and
//! `records_pg.rs` shows the forwarder sending them on once the server is back.

use crate::support::cli::WATCHDOG as PATIENCE;
use crate::support::demo_bundle;
use botbench::i18n::Lang;
use botbench::link::PortOpener;
use botbench::ops::records::{LineStore, Recorder, RunContext};
use botbench::ops::station::{Answer, Bundle, Command, Event, What};
use botbench::sim::fixture::{StartedStation, start_station};
use botbench::ui::line::LineStation;
use eframe::egui;
use egui_kittest::kittest::Queryable;
use std::path::Path;
use std::time::Instant;

/// A PostgreSQL URL nobody answers at: port 1 of this machine.
pub const AWAY: &str = "postgres://botbench@127.0.0.1:1/line";

/// The demo station, one unit per slot, recording to the line server at `url` behind the
/// spool `spool`.
pub fn demo_station(url: &str, spool: &Path) -> (Bundle, StartedStation) {
    let bundle = demo_bundle();
    let store = LineStore::with_spool(url, "the line server", spool).unwrap();
    let recorder = Recorder::with_store(Box::new(store), RunContext::default(), None);
    let started = start_station(&bundle, recorder, None, &PortOpener::system(), true).unwrap();
    (bundle, started)
}

/// Every event of `started` until each slot stopped, a Confirm answered yes.
pub fn run_to_the_end(started: &StartedStation) -> Vec<Event> {
    let deadline = Instant::now() + PATIENCE;
    let mut events = Vec::new();
    let mut stopped = 0;
    while stopped < started.slots.len() {
        assert!(
            Instant::now() < deadline,
            "the station never ended: {events:#?}"
        );
        let Ok(ev) = started
            .events
            .recv_timeout(std::time::Duration::from_millis(100))
        else {
            continue;
        };
        match &ev.what {
            What::Ask {
                kind: "confirm", ..
            } => {
                let slot = started.slots.iter().find(|s| s.name == ev.slot).unwrap();
                slot.commands.send(Command::Answer(Answer::Yes)).unwrap();
            }
            What::Stopped { .. } => stopped += 1,
            _ => {}
        }
        events.push(ev);
    }
    events
}

#[test]
fn with_the_line_server_away_the_station_says_how_many_records_wait_in_the_spool() {
    let dir = crate::support::temp_dir();
    let spool = dir.path().join("spool.sqlite");
    let (_, started) = demo_station(AWAY, &spool);
    let events = run_to_the_end(&started);
    // Every verdict said, PASS, its record not stored but kept in the spool.
    let verdicts: Vec<&Event> = events
        .iter()
        .filter(|e| matches!(e.what, What::Verdict { .. }))
        .collect();
    assert_eq!(verdicts.len(), 3, "{events:#?}");
    for v in &verdicts {
        let What::Verdict {
            pass, stored, kept, ..
        } = &v.what
        else {
            unreachable!()
        };
        assert!(*pass && !*stored, "{v:?}");
        assert!(kept.contains("spool.sqlite"), "{kept}");
    }
    // The count after each record, as `--headless --json` prints it: 1, 2, 3 waiting.
    let said: Vec<serde_json::Value> = events
        .iter()
        .filter(|e| !e.slot.is_empty() && matches!(e.what, What::Records { .. }))
        .map(|e| serde_json::to_value(e).unwrap())
        .collect();
    let counts: Vec<u64> = said
        .iter()
        .map(|d| d["waiting"].as_u64().unwrap())
        .collect();
    assert_eq!(counts, [1, 2, 3], "{said:#?}");
    let last = said.last().unwrap();
    assert_eq!(last["event"], "records");
    assert_eq!(last["store"], "the line server");
    assert!(
        last["why"].as_str().unwrap().contains("cannot be reached"),
        "{last}"
    );
    // All three in the spool, each once.
    let db = rusqlite::Connection::open(&spool).unwrap();
    let n: i64 = db
        .query_row("SELECT COUNT(DISTINCT uuid) FROM runs", [], |r| r.get(0))
        .unwrap();
    assert_eq!(n, 3);
    started.forwarder.stop();
}

#[test]
fn the_station_window_shows_the_records_waiting_in_its_header_and_on_the_tiles() {
    let dir = crate::support::temp_dir();
    let spool = dir.path().join("spool.sqlite");
    let (bundle, started) = demo_station(AWAY, &spool);
    let st = LineStation::started(&bundle, started);
    let mut h = crate::support::gui::line_station_harness(st, egui::vec2(1280.0, 800.0));
    let deadline = Instant::now() + PATIENCE;
    while !h.state().tiles.iter().all(|t| t.verdict.is_some()) {
        assert!(Instant::now() < deadline, "three verdicts never came");
        if let Some(i) = h
            .state()
            .tiles
            .iter()
            .position(|t| matches!(t.asking, Some(("confirm", _, _))))
        {
            let slot = h.state().tiles[i].slot.clone();
            h.state().send(&slot, Command::Answer(Answer::Yes));
        }
        h.step();
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    let deadline = Instant::now() + PATIENCE;
    while h.state().records.as_ref().map(|r| r.waiting) != Some(3) {
        assert!(Instant::now() < deadline, "{:?}", h.state().records);
        h.step();
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    h.step();
    assert!(
        h.query_by_label_contains(
            "Records: 3 waiting on this PC to be forwarded to the line server"
        )
        .is_some()
    );
    assert_eq!(h.query_all_by_label("PASS").count(), 3);
    assert_eq!(
        h.query_all_by_label_contains("Record not in its store: record kept in the spool")
            .count(),
        3
    );
    h.state_mut().lang = Lang::Zh;
    h.step();
    h.step();
    assert!(h.query_by_label_contains("记录:3 条在本机暂存").is_some());
    h.state().stop_all();
}

/// A tmpfs of `kib` KiB mounted at a fresh folder (root only), unmounted when dropped.
struct TinyDisk {
    dir: tempfile::TempDir,
}

impl TinyDisk {
    /// `None` (said on the terminal) where this process may not mount.
    fn mount(kib: u64, test: &str) -> Option<TinyDisk> {
        let dir = crate::support::temp_dir();
        let ok = std::process::Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={kib}k"), "tmpfs"])
            .arg(dir.path())
            .stderr(std::process::Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
        if !ok {
            use std::io::Write;
            let _ = writeln!(
                std::io::stderr(),
                "SKIPPED {test}: cannot mount a tiny tmpfs here (needs root)"
            );
            return None;
        }
        Some(TinyDisk { dir })
    }

    fn path(&self) -> &Path {
        self.dir.path()
    }

    /// Fills it to the last byte.
    fn fill(&self) {
        use std::io::Write;
        let mut f = std::fs::File::create(self.path().join("filler")).unwrap();
        let block = vec![0u8; 4096];
        loop {
            match f.write(&block) {
                Ok(0) => break,
                Ok(_) => {}
                Err(e) if e.raw_os_error() == Some(28) => break,
                Err(e) => panic!("filling: {e}"),
            }
        }
        let _ = f.sync_all();
    }

    /// Room again.
    fn free(&self) {
        std::fs::remove_file(self.path().join("filler")).unwrap();
    }
}

impl Drop for TinyDisk {
    fn drop(&mut self) {
        let _ = std::process::Command::new("umount")
            .arg("-l")
            .arg(self.dir.path())
            .status();
    }
}

#[test]
fn a_records_file_on_a_full_disk_says_so_naming_it_and_every_verdict_and_record_is_kept() {
    let Some(disk) = TinyDisk::mount(512, "a_records_file_on_a_full_disk") else {
        return;
    };
    let records = disk.path().join("records.sqlite");
    let mut store = botbench::ops::records::SqliteStore::open(&records).unwrap();
    // Nothing of the write-ahead log is left to reuse: every record needs new room on the disk.
    store
        .connection()
        .execute_batch("PRAGMA wal_checkpoint(TRUNCATE)")
        .unwrap();
    disk.fill();
    let elsewhere = crate::support::temp_dir();
    let fallback = elsewhere.path().join("unsaved.sqlite");
    let recorder = Recorder::with_store(
        Box::new(store),
        RunContext::default(),
        Some(fallback.clone()),
    );
    let bundle = demo_bundle();
    let started = start_station(&bundle, recorder, None, &PortOpener::system(), true).unwrap();
    let events = run_to_the_end(&started);
    // Every verdict said (PASS), its record not in the full file but in the fallback spool,
    // the file named and the disk said full.
    let mut verdicts = 0;
    for e in &events {
        if let What::Verdict {
            pass, stored, kept, ..
        } = &e.what
        {
            verdicts += 1;
            assert!(*pass && !*stored, "{e:?}");
            assert!(
                kept.contains(&format!("{}: the disk is full", records.display()))
                    && kept.contains("unsaved.sqlite"),
                "{kept}"
            );
        }
    }
    assert_eq!(verdicts, 3, "{events:#?}");
    let fallback_runs = || {
        rusqlite::Connection::open(&fallback)
            .unwrap()
            .query_row("SELECT COUNT(*) FROM runs", [], |r| r.get::<_, i64>(0))
            .unwrap()
    };
    assert_eq!(fallback_runs(), 3);
    // Room again: the station's forwarder moves them into the records file, each once.
    disk.free();
    let deadline = Instant::now() + PATIENCE;
    loop {
        assert!(Instant::now() < deadline, "never forwarded");
        match started
            .events
            .recv_timeout(std::time::Duration::from_millis(200))
        {
            Ok(Event {
                what: What::Records { waiting: 0, .. },
                slot,
            }) if slot.is_empty() => break,
            _ => {}
        }
    }
    started.forwarder.stop();
    let db = rusqlite::Connection::open(&records).unwrap();
    let (runs, distinct, half): (i64, i64, i64) = db
        .query_row(
            "SELECT COUNT(*), COUNT(DISTINCT uuid), \
             SUM(steps <> (SELECT COUNT(*) FROM steps s WHERE s.run = r.id)) FROM runs r",
            [],
            |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)),
        )
        .unwrap();
    assert_eq!((runs, distinct, half), (3, 3, 0));
    assert_eq!(fallback_runs(), 0);
}

#[test]
fn with_the_fallback_spool_on_the_same_full_disk_the_record_is_kept_in_memory_and_said_whole() {
    let Some(disk) = TinyDisk::mount(512, "with_the_fallback_spool_on_the_same_full_disk") else {
        return;
    };
    let records = disk.path().join("records.sqlite");
    let mut store = botbench::ops::records::SqliteStore::open(&records).unwrap();
    store
        .connection()
        .execute_batch("PRAGMA wal_checkpoint(TRUNCATE)")
        .unwrap();
    disk.fill();
    let fallback = disk.path().join("unsaved.sqlite");
    let mut recorder = Recorder::with_store(Box::new(store), RunContext::default(), Some(fallback));
    let mut record = crate::records::hand_set().remove(0);
    let kept = recorder.save(&mut record);
    let line = kept.line();
    match &kept {
        botbench::ops::records::Kept::InMemory { json, .. } => {
            // The record itself is in the message, whole: nothing of it is lost.
            let back: botbench::ops::records::Record = serde_json::from_str(json).unwrap();
            assert_eq!(back, record);
        }
        other => panic!("{other:?}"),
    }
    assert!(line.starts_with("RECORD NOT WRITTEN"), "{line}");
    assert!(
        line.contains(&records.display().to_string()) && line.contains("disk is full"),
        "{line}"
    );
    assert!(
        line.contains("unsaved.sqlite"),
        "the fallback not named: {line}"
    );
    assert_eq!(recorder.waiting(), 1);
    // Room again: the next save sends the one kept in memory first, then its own.
    disk.free();
    let mut next = crate::records::hand_set().remove(1);
    assert!(recorder.save(&mut next).stored());
    assert_eq!(recorder.waiting(), 0);
    assert_eq!(crate::records::whole_records(&records), 2);
}
