//! The station's records when their store is away (issue 28): every verdict is still said and
//! its record kept in the spool on this PC, the station says how many wait (a `records` event,
//! as the headless JSON prints it, and a line in the window's header, a note on the tile), and
//! `records_pg.rs` shows the forwarder sending them on once the server is back.

use crate::support::cli::WATCHDOG as PATIENCE;
use botbench::i18n::Lang;
use botbench::link::PortOpener;
use botbench::ops::records::{LineStore, Recorder, RunContext};
use botbench::ops::station::{self, Answer, Bundle, Command, Event, LoadContext, What};
use botbench::sim::SimKind;
use botbench::sim::fixture::{StartedStation, start_station};
use botbench::ui::line::LineStation;
use eframe::egui;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use std::path::Path;
use std::time::Instant;

/// A PostgreSQL URL nobody answers at: port 1 of this machine.
pub const AWAY: &str = "postgres://botbench@127.0.0.1:1/line";

/// The demo bundle (three simulated slots), loaded.
pub fn demo_bundle() -> Bundle {
    let registry = botbench::profile::Registry::builtin().unwrap();
    let sims: Vec<(&str, &str)> = SimKind::ALL
        .iter()
        .map(|k| (k.name(), k.profile_id()))
        .collect();
    let cx = LoadContext {
        registry: &registry,
        simulated: &sims,
    };
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("presets/demo-station.ron");
    station::load(&path, &cx).unwrap()
}

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
    let mut h = Harness::builder()
        .with_size(egui::vec2(1280.0, 800.0))
        .build_ui_state(
            |ui, st: &mut LineStation| {
                botbench::i18n::install_cjk_font(ui.ctx());
                st.logic(ui.ctx());
                st.ui(ui);
            },
            st,
        );
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
