//! The station's window (issue 27) in a kittest harness: the demo bundle's three simulated
//! slots run to their verdicts, the Confirm answered by the tile's Yes button; the banners say
//! PASS; STOP ALL stops every slot; the 中文 view shows the same station in Chinese.

use crate::support::cli::WATCHDOG as PATIENCE;
use botbench::i18n::Lang;
use botbench::link::PortOpener;
use botbench::ops::records::{Recorder, RunContext, SqliteStore};
use botbench::ops::station::{self, LoadContext};
use botbench::sim::SimKind;
use botbench::ui::line::LineStation;
use eframe::egui;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use std::path::Path;
use std::time::Instant;

/// The demo station's slots started, in a window of `size` showing `lang`.
fn demo_window(dir: &Path, size: egui::Vec2, lang: Lang) -> Harness<'static, LineStation> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("presets/demo-station.ron");
    window_of(&path, dir, size, lang)
}

/// The station of the bundle at `path` started, in a window of `size` showing `lang`.
fn window_of(
    path: &Path,
    dir: &Path,
    size: egui::Vec2,
    lang: Lang,
) -> Harness<'static, LineStation> {
    let registry = botbench::profile::Registry::builtin().unwrap();
    let sims: Vec<(&str, &str)> = SimKind::ALL
        .iter()
        .map(|k| (k.name(), k.profile_id()))
        .collect();
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
            botbench::sim::fixture::start_slot(slot, context.clone(), &ports, tx.clone(), true)
                .unwrap(),
        );
    }
    let mut st = LineStation::new(&bundle, slots, rx);
    st.lang = lang;
    Harness::builder().with_size(size).build_ui_state(
        |ui, st: &mut LineStation| {
            botbench::i18n::install_cjk_font(ui.ctx());
            st.logic(ui.ctx());
            st.ui(ui);
        },
        st,
    )
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
    let mut h = window_of(&bundle, dir.path(), egui::vec2(1280.0, 800.0), Lang::En);
    h.step();
    // Locked: no slot's configuration is shown.
    assert!(
        h.query_by_label_contains("simulated servo-bus · servo")
            .is_none()
    );
    h.get_by_label("Engineer unlock").click();
    h.step();
    h.step();
    h.state_mut().engineer.typed = "not it".into();
    h.get_by_label("Unlock").click();
    h.step();
    h.step();
    assert!(h.query_by_label("wrong password").is_some());
    assert!(!h.state().engineer.unlocked());
    h.state_mut().engineer.typed = "password".into();
    h.get_by_label("Unlock").click();
    h.step();
    h.step();
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
