//! The station's window (issue 27) in a kittest harness: the demo bundle's three simulated
//! slots run to their verdicts, the Confirm answered by the tile's Yes button; the banners say
//! PASS; STOP ALL stops every slot; the 中文 view shows the same station in Chinese.

use crate::support::cli::WATCHDOG as PATIENCE;
use botbench::i18n::Lang;
use botbench::link::PortOpener;
use botbench::ops::records::record::{Record, RunKind, Verdict};
use botbench::ops::records::{Recorder, RunContext, SqliteStore, Store};
use botbench::ops::station::{self, LoadContext};
use botbench::sim::SimKind;
use botbench::ui::line::LineStation;
use botbench::ui::line::sound::{Tone, VerdictSound};
use eframe::egui;
use egui_kittest::Harness;
use egui_kittest::kittest::{By, Queryable};
use std::path::Path;
use std::time::Instant;

/// The demo station's slots started, in a window of `size` showing `lang`.
fn demo_window(dir: &Path, size: egui::Vec2, lang: Lang) -> Harness<'static, LineStation> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("presets/demo-station.ron");
    window_of(&path, dir, size, lang, true)
}

/// The station of the bundle at `path` started (with `once`, one unit per slot), its records
/// in `dir`/records.sqlite, in a window of `size` showing `lang`.
fn window_of(
    path: &Path,
    dir: &Path,
    size: egui::Vec2,
    lang: Lang,
    once: bool,
) -> Harness<'static, LineStation> {
    let registry = botbench::profile::Registry::builtin().unwrap();
    let sims = SimKind::names_with_profiles();
    let cx = LoadContext {
        registry: &registry,
        simulated: &sims,
    };
    let bundle = station::load(path, &cx).unwrap();
    let store = SqliteStore::open(&dir.join("records.sqlite")).unwrap();
    let recorder = Recorder::with_store(Box::new(store), RunContext::default(), None);
    let context = station::StationContext::new(&bundle, None, recorder);
    let (tx, rx) = crossbeam_channel::unbounded();
    let mut slots = Vec::new();
    for slot in &bundle.slots {
        let ports = PortOpener::system();
        slots.push(
            botbench::sim::fixture::start_slot(slot, context.clone(), &ports, tx.clone(), once)
                .unwrap(),
        );
    }
    let mut st = LineStation::new(&bundle, slots, rx);
    st.sounder = Box::new(botbench::ui::line::sound::Silent);
    st.lang = lang;
    st.access = Some(context);
    crate::support::gui::line_station_harness(st, size)
}

/// Steps `h` until `done` holds, failing after [`PATIENCE`].
fn step_until(
    h: &mut Harness<'static, LineStation>,
    what: &str,
    done: impl Fn(&LineStation) -> bool,
) {
    let deadline = Instant::now() + PATIENCE;
    while !done(h.state()) {
        assert!(Instant::now() < deadline, "{what} never came");
        h.step();
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
}

#[test]
fn the_demo_station_runs_to_three_pass_banners_in_the_window() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = demo_window(dir.path(), egui::vec2(1280.0, 800.0), Lang::En);
    step_until(&mut h, "the spray question", |st| {
        st.tiles[0]
            .asking
            .as_ref()
            .is_some_and(|(k, _, _)| *k == "confirm")
    });
    h.step();
    h.get_by_label("Yes (Y)").click();
    h.step();
    step_until(&mut h, "three verdicts", |st| {
        st.tiles.iter().all(|t| t.verdict.is_some())
    });
    h.step();
    for t in &h.state().tiles {
        assert_eq!(t.verdict.as_ref().map(|v| v.0), Some(true), "{t:?}");
    }
    assert_eq!(h.query_all_by_label("PASS").count(), 3);
    assert!(h.query_by_label("STOP ALL").is_some());
    assert_eq!(h.query_all_by_label("STOP").count(), 3);
}

#[test]
fn the_station_in_chinese_and_stop_all_stops_every_slot() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = demo_window(dir.path(), egui::vec2(1024.0, 600.0), Lang::Zh);
    h.step();
    assert!(h.query_by_label("全部停止").is_some());
    h.get_by_label("全部停止").click();
    h.step();
    step_until(&mut h, "every slot stopped", |st| {
        st.tiles.iter().all(|t| t.stopped.is_some())
    });
    h.step();
    assert!(h.query_all_by_label_contains("已停止").count() >= 3);
}

#[test]
fn the_operator_view_is_locked_until_the_engineer_s_password_unlocks_it() {
    let dir = tempfile::tempdir().unwrap();
    let presets = Path::new(env!("CARGO_MANIFEST_DIR")).join("presets");
    for f in ["window-cleaner-selftest.ron", "servo-provision-plan.ron"] {
        std::fs::copy(presets.join(f), dir.path().join(f)).unwrap();
    }
    // The example's commented hash is SHA-256 of `password`.
    let text = std::fs::read_to_string(presets.join("demo-station.ron"))
        .unwrap()
        .replace("// engineer_password_sha256:", "engineer_password_sha256:");
    let bundle = dir.path().join("locked.ron");
    std::fs::write(&bundle, text).unwrap();
    let mut h = window_of(
        &bundle,
        dir.path(),
        egui::vec2(1280.0, 800.0),
        Lang::En,
        true,
    );
    h.step();
    // Locked: no slot's configuration is shown.
    assert!(
        h.query_by_label_contains("simulated servo-bus · servo")
            .is_none()
    );
    h.get_by_label("Engineer unlock").click();
    h.step();
    h.step();
    try_password(&mut h, "not it");
    assert!(h.query_by_label("wrong password").is_some());
    assert!(!h.state().engineer.unlocked());
    try_password(&mut h, "password");
    assert!(h.state().engineer.unlocked());
    assert!(h.query_by_label_contains("engineer view (since").is_some());
    assert!(
        h.query_by_label_contains("simulated servo-bus · servo · servo: Provision")
            .is_some()
    );
    // Locked again: the configuration is gone.
    h.get_by_label("Lock").click();
    h.step();
    h.step();
    assert!(
        h.query_by_label_contains("simulated servo-bus · servo")
            .is_none()
    );
    h.state().stop_all();
}

#[test]
fn a_slot_s_number_then_y_or_n_answers_that_slot_s_question() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = demo_window(dir.path(), egui::vec2(1280.0, 800.0), Lang::En);
    step_until(&mut h, "the spray question", |st| {
        st.tiles[0]
            .asking
            .as_ref()
            .is_some_and(|(k, _, _)| *k == "confirm")
    });
    // "2 N": slot 2 asks nothing, so the N goes nowhere (to the oldest question it would
    // fail slot 1); then "1 Y" answers slot 1's.
    h.key_press(egui::Key::Num2);
    h.key_press(egui::Key::N);
    h.step();
    h.key_press(egui::Key::Num1);
    h.key_press(egui::Key::Y);
    h.step();
    step_until(&mut h, "three verdicts", |st| {
        st.tiles.iter().all(|t| t.verdict.is_some())
    });
    for t in &h.state().tiles {
        assert_eq!(t.verdict.as_ref().map(|v| v.0), Some(true), "{t:?}");
    }
}

/// The records of `dir`/records.sqlite matching `filter`, oldest first.
fn records_in(dir: &Path, filter: &botbench::ops::records::Filter) -> Vec<Record> {
    let mut store = SqliteStore::open(&dir.join("records.sqlite")).unwrap();
    let mut back = Vec::new();
    store
        .read(&mut |db| {
            botbench::ops::records::query::each_record(db, filter, &mut |r| {
                back.push(r);
                Ok(())
            })
        })
        .unwrap();
    back
}

/// The demo station with every slot started by its Start button (so that a slot waits idle)
/// and the example's engineer password (`password`), running unit after unit.
fn idle_station(dir: &Path) -> Harness<'static, LineStation> {
    let presets = Path::new(env!("CARGO_MANIFEST_DIR")).join("presets");
    for f in ["window-cleaner-selftest.ron", "servo-provision-plan.ron"] {
        std::fs::copy(presets.join(f), dir.join(f)).unwrap();
    }
    let text = std::fs::read_to_string(presets.join("demo-station.ron"))
        .unwrap()
        .replace("// engineer_password_sha256:", "engineer_password_sha256:")
        .replace("start: Auto", "start: Button");
    let bundle = dir.join("engineer.ron");
    std::fs::write(&bundle, text).unwrap();
    window_of(&bundle, dir, egui::vec2(1280.0, 800.0), Lang::En, false)
}

#[test]
fn the_engineer_view_is_today_s_window_on_a_lent_slot_and_every_unlock_is_recorded() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = idle_station(dir.path());
    step_until(&mut h, "every slot idle on its port", |st| {
        st.tiles
            .iter()
            .all(|t| t.waiting.is_some() && matches!(t.port, Some((true, _))))
    });
    h.step();
    // Locked: no slot can be opened, no port, baud, profile or margin can be changed.
    let locked = |h: &Harness<'static, LineStation>| {
        h.query_by_label("Open in engineer view").is_none()
            && ["Port", "Baud", "Profile", "Margin", "Connect", "Disconnect"]
                .iter()
                .all(|l| h.query_by_label(l).is_none())
    };
    assert!(locked(&h), "the operator view offers an engineer's control");
    h.get_by_label("Engineer unlock").click();
    h.step();
    h.step();
    try_password(&mut h, "not it");
    try_password(&mut h, "password");
    assert_eq!(h.query_all_by_label("Open in engineer view").count(), 3);
    // Slot 3 (the Tuya vacuum) in today's window: its connection bar, connected to the port
    // the slot gave up.
    open_slot_3_in_engineer_view(&mut h);
    assert!(h.query_by_label("Margin").is_some());
    assert!(h.query_by_label("Disconnect").is_some());
    assert!(h.query_by_label_contains("Engineer view: slot 3").is_some());
    let app = h.state().lent.as_ref().unwrap().app.as_ref().unwrap();
    assert_eq!(app.station().device.profile.id, "tuya-vacuum");
    assert_eq!(
        app.station().link.target().map(|t| t.label()),
        Some("simulated:tuya-vacuum:3".to_string())
    );
    // Locking returns to the operator view and gives the slot back: it runs a unit again.
    h.get_by_label("Lock").click();
    h.step();
    h.step();
    assert!(h.state().lent.is_none());
    assert!(locked(&h), "locked again, an engineer's control is left");
    h.query_all_by_label("Start").nth(2).unwrap().click();
    h.step();
    step_until(&mut h, "slot 3's verdict after the engineer view", |st| {
        st.tiles[2].verdict.is_some()
    });
    assert_eq!(h.state().tiles[2].verdict.as_ref().map(|v| v.0), Some(true));
    let sha = h.state().bundle_sha256.clone();
    access_records_hold(dir.path(), &sha);
    h.state().stop_all();
}

#[test]
fn the_engineer_view_starts_from_the_ordinary_window_s_saved_settings() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = idle_station(dir.path());
    // What the ordinary window saved: a 100 ms answer margin (and 115200 baud) for the Tuya
    // vacuum, telemetry at 10 Hz over 30 s.
    let mut saved = botbench::ui::Settings {
        poll_hz: Some(10.0),
        window_secs: 30.0,
        ..botbench::ui::Settings::default()
    };
    saved.ports.insert(
        "tuya-vacuum".into(),
        botbench::ui::settings::PortSettings {
            baud: Some(115_200),
            margin_ms: Some(100),
            ..Default::default()
        },
    );
    h.state_mut().window_settings = saved;
    step_until(&mut h, "every slot idle on its port", |st| {
        st.tiles
            .iter()
            .all(|t| t.waiting.is_some() && matches!(t.port, Some((true, _))))
    });
    h.get_by_label("Engineer unlock").click();
    h.step();
    h.step();
    try_password(&mut h, "password");
    open_slot_3_in_engineer_view(&mut h);
    let app = h.state().lent.as_ref().unwrap().app.as_ref().unwrap();
    let port = app.settings.port_of("tuya-vacuum");
    assert_eq!(port.margin_ms, Some(100), "{:?}", app.settings);
    assert_eq!(app.settings.poll_hz, Some(10.0));
    assert_eq!(app.settings.window_secs, 30.0);
    // The slot's own rate (the Tuya vacuum's usual 9600), not the ordinary window's last.
    assert_eq!(port.baud.unwrap_or(9600), 9600, "{port:?}");
    // On screen: the connection bar's margin box says the saved margin.
    assert!(
        h.query_all(By::new().predicate(|n| {
            n.value().as_deref() == Some("100 ms") || n.label().as_deref() == Some("100 ms")
        }))
        .next()
        .is_some(),
        "the margin box does not say 100 ms"
    );
    h.state().stop_all();
}

/// Every unlock, refusal, lent slot and lock of the engineer test is in the records of `dir`
/// (waited for: each is saved on a thread of its own), with the bundle's hash `sha`; the
/// reports' filter leaves them out.
fn access_records_hold(dir: &Path, sha: &str) {
    let access = botbench::ops::records::Filter {
        access: true,
        ..Default::default()
    };
    let want = [
        "engineer lock",
        "engineer password refused",
        "engineer unlock",
        "engineer view of slot 3",
        "slot 3 back from the engineer view",
    ];
    let deadline = Instant::now() + PATIENCE;
    let mut seen: Vec<Record>;
    loop {
        seen = records_in(dir, &access)
            .into_iter()
            .filter(|r| r.kind == RunKind::Access)
            .collect();
        if seen.len() >= want.len() {
            break;
        }
        assert!(Instant::now() < deadline, "access records: {seen:?}");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let mut plans: Vec<&str> = seen.iter().map(|r| r.plan.as_str()).collect();
    plans.sort_unstable();
    assert_eq!(plans, want);
    for r in &seen {
        assert_eq!(r.context.bundle_sha256.as_deref(), Some(sha), "{r:?}");
        assert_eq!(r.context.station.as_deref(), Some("demo-station"));
        let refused = r.plan == "engineer password refused";
        assert_eq!(r.verdict == Verdict::Fail, refused, "{r:?}");
        let slot = r.plan.contains("slot 3");
        assert_eq!(r.context.slot.as_deref() == Some("3"), slot, "{r:?}");
    }
    let units = records_in(dir, &Default::default());
    assert!(
        units.iter().all(|r| r.kind == RunKind::Station),
        "{units:?}"
    );
    assert!(!units.is_empty());
}

/// The ordinary window on the built-in window cleaner, its records in `dir`.
fn ordinary_window(dir: &Path) -> crate::support::gui::H {
    let mut saved = botbench::ui::Settings::default();
    saved.files.insert(
        botbench::ui::settings::FileKind::Records,
        dir.join("records.sqlite").display().to_string(),
    );
    crate::support::gui::harness(saved, PortOpener::system())
}

#[test]
fn file_open_station_shows_a_bundle_refuses_a_bad_one_and_closes_only_when_idle() {
    use crate::support::gui::{app, app_mut, step_until};
    use botbench::ui::Action;
    let dir = tempfile::tempdir().unwrap();
    let mut h = ordinary_window(dir.path());
    // The read made on connecting ends first: its notice ("Read: 9 read") would take the place
    // of the refusal's (seen on a loaded machine).
    crate::support::gui::read_on_connecting(&mut h);
    h.step();
    assert!(h.query_all_by_label("File").count() >= 1);
    // A bundle naming a profile that does not exist: refused with its place, nothing changed.
    let presets = Path::new(env!("CARGO_MANIFEST_DIR")).join("presets");
    for f in ["window-cleaner-selftest.ron", "servo-provision-plan.ron"] {
        std::fs::copy(presets.join(f), dir.path().join(f)).unwrap();
    }
    let demo = std::fs::read_to_string(presets.join("demo-station.ron")).unwrap();
    let bad = dir.path().join("bad.ron");
    std::fs::write(
        &bad,
        demo.replace("profile: \"servo\"", "profile: \"servoo\""),
    )
    .unwrap();
    app_mut(&mut h).apply(Action::OpenStation(Some(bad.clone())));
    h.step();
    assert!(app(&h).line.is_none());
    let said = app(&h).station().notice.clone().expect("a notice").text;
    assert!(said.starts_with("station not opened: "), "{said}");
    assert!(said.contains("bad.ron:"), "{said}");
    assert!(said.contains("servoo"), "{said}");
    assert!(app(&h).station().connected());
    assert!(h.query_by_label("Margin").is_some());
    // A good one: the station in place of the panels.
    let good = dir.path().join("good.ron");
    std::fs::write(&good, demo.replace("start: Auto", "start: Button")).unwrap();
    app_mut(&mut h).apply(Action::OpenStation(Some(good)));
    h.step();
    assert!(app(&h).line.is_some(), "{:?}", app(&h).station().notice);
    step_until(&mut h, "every slot idle", |a| {
        a.line.as_ref().is_some_and(|l| {
            l.tiles
                .iter()
                .all(|t| t.waiting.is_some() && matches!(t.port, Some((true, _))))
        })
    });
    h.step();
    assert!(h.query_by_label("Margin").is_none());
    assert!(h.query_by_label("STOP ALL").is_some());
    // A unit running (slot 1 asks whether it sprayed): Close station does nothing.
    h.query_all_by_label("Start").next().unwrap().click();
    h.step();
    step_until(&mut h, "slot 1's question", |a| {
        a.line.as_ref().is_some_and(|l| l.tiles[0].asking.is_some())
    });
    h.step();
    h.get_by_label("Close station").click();
    h.step();
    h.step();
    assert!(app(&h).line.is_some(), "closed while a unit runs");
    step_until(&mut h, "the spray question", |a| {
        a.line
            .as_ref()
            .is_some_and(|l| matches!(l.tiles[0].asking, Some(("confirm", _, _))))
    });
    h.step();
    h.get_by_label("Yes (Y)").click();
    h.step();
    step_until(&mut h, "slot 1 idle again", |a| {
        a.line
            .as_ref()
            .is_some_and(|l| l.tiles[0].verdict.is_some() && !l.running())
    });
    h.step();
    h.get_by_label("Close station").click();
    h.step();
    h.step();
    assert!(app(&h).line.is_none());
    assert!(h.query_by_label("Margin").is_some());
}

#[test]
fn the_port_line_and_the_history_are_as_tall_as_the_unit_line_and_fixtures_speak_chinese() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = demo_window(dir.path(), egui::vec2(1280.0, 800.0), Lang::Zh);
    // The verdict, then the slot stops (`--once`): its port line says so.
    step_until(&mut h, "slot 3's verdict and stop", |st| {
        st.tiles[2].verdict.is_some() && st.tiles[2].stopped.is_some()
    });
    h.step();
    h.step();
    // Read from two metres: the port line (here: why the slot stopped, in 中文) and a history entry are no smaller than the unit's
    // serial line (20 points), not egui's body text.
    let unit = h
        .query_all_by_label_contains("序列号")
        .next()
        .unwrap()
        .rect();
    let port = h
        .query_all_by_label_contains("已测完一个产品(--once)")
        .next()
        .unwrap()
        .rect();
    let history = h
        .query_all_by_label_contains(" 合格")
        .last()
        .unwrap()
        .rect();
    assert!(port.height() >= unit.height() - 0.5, "{port:?} {unit:?}");
    assert!(
        history.height() >= unit.height() - 0.5,
        "{history:?} {unit:?}"
    );
    // The bundle's 中文 fixture names.
    assert!(h.query_by_label_contains("扫地机 MCU 来料检验").is_some());
    assert!(h.query_by_label_contains("Vacuum MCU incoming").is_none());
    h.state().stop_all();
}

/// The tones a station window asked for.
#[derive(Clone, Default)]
struct Heard(std::sync::Arc<std::sync::Mutex<Vec<Tone>>>);

impl VerdictSound for Heard {
    fn play(&mut self, tone: Tone) {
        self.0.lock().unwrap().push(tone);
    }
}

impl Heard {
    fn tones(&self) -> Vec<Tone> {
        self.0.lock().unwrap().clone()
    }
}

/// The demo bundle's window with no slots running: its events come from the test.
fn sounding_window(
    heard: &Heard,
) -> (
    Harness<'static, LineStation>,
    crossbeam_channel::Sender<station::Event>,
) {
    let bundle = crate::support::demo_bundle();
    assert!(bundle.sound, "the demo bundle sounds its verdicts");
    let (tx, rx) = crossbeam_channel::unbounded();
    let mut st = LineStation::new(&bundle, Vec::new(), rx);
    st.sounder = Box::new(heard.clone());
    let h = crate::support::gui::line_station_harness(st, egui::vec2(1280.0, 800.0));
    (h, tx)
}

fn verdict(slot: &str, pass: bool) -> station::Event {
    station::Event {
        slot: slot.into(),
        what: station::What::Verdict {
            pass,
            serial: Some(format!("SN-{slot}")),
            failed_step: (!pass).then(|| "identify".into()),
            failed_step_zh: None,
            reason: (!pass).then(|| "wrong build".into()),
            earlier_runs: None,
            record: "r".into(),
            kept: "record saved".into(),
            stored: true,
        },
    }
}

#[test]
fn each_verdict_asks_once_for_its_sound_and_the_operator_may_mute_it() {
    let heard = Heard::default();
    let (mut h, tx) = sounding_window(&heard);
    tx.send(verdict("1", true)).unwrap();
    tx.send(verdict("2", false)).unwrap();
    for _ in 0..5 {
        h.step();
    }
    // Once per verdict, not once per frame while its banner stands.
    assert_eq!(heard.tones(), vec![Tone::Pass, Tone::Fail]);
    // The operator mutes it on the bar: the next verdicts are silent, and the choice is kept.
    h.get_by_label("Sound on verdict").click();
    h.step();
    assert!(!h.state().sound);
    assert_eq!(h.state().sound_chosen, Some(false));
    tx.send(verdict("1", false)).unwrap();
    tx.send(verdict("3", true)).unwrap();
    for _ in 0..5 {
        h.step();
    }
    assert_eq!(heard.tones().len(), 2, "muted: {:?}", heard.tones());
    assert_eq!(h.state().tiles[2].verdict.as_ref().map(|v| v.0), Some(true));
    // Turned on again, the next one is heard.
    h.get_by_label("Sound on verdict").click();
    h.step();
    tx.send(verdict("3", false)).unwrap();
    h.step();
    h.step();
    assert_eq!(heard.tones().last(), Some(&Tone::Fail));
    assert_eq!(heard.tones().len(), 3);
}

#[test]
fn a_bundle_may_start_silent_and_a_saved_choice_outranks_it() {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("presets/demo-station.ron"),
    )
    .unwrap()
    .replace("    sound: true,", "    sound: false,");
    // The files it names are found in the shipped presets folder.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("demo-station.ron");
    std::fs::write(&path, text).unwrap();
    let registry = botbench::profile::Registry::builtin().unwrap();
    let sims = SimKind::names_with_profiles();
    let cx = LoadContext {
        registry: &registry,
        simulated: &sims,
    };
    let bundle = station::load(&path, &cx).unwrap();
    assert!(!bundle.sound);
    let (_tx, rx) = crossbeam_channel::unbounded();
    let st = LineStation::new(&bundle, Vec::new(), rx);
    assert!(!st.sound);
    let st = st.with_sound_chosen(Some(true));
    assert!(st.sound);
    assert_eq!(st.sound_chosen, Some(true));
}

/// Clicks slot 3's "Open in engineer view" (the Tuya vacuum) and waits until today's window on
/// it is connected to the port the slot gave up.
fn open_slot_3_in_engineer_view(h: &mut Harness<'static, LineStation>) {
    h.query_all_by_label("Open in engineer view")
        .nth(2)
        .unwrap()
        .click();
    h.step();
    step_until(h, "the engineer view connected", |st| {
        st.lent
            .as_ref()
            .and_then(|l| l.app.as_ref())
            .is_some_and(|app| app.station().connected())
    });
    h.step();
    h.step();
}

/// Types `password` into the open unlock dialog and clicks Unlock.
fn try_password(h: &mut Harness<'static, LineStation>, password: &str) {
    h.state_mut().engineer.typed = password.into();
    h.get_by_label("Unlock").click();
    h.step();
    h.step();
}
