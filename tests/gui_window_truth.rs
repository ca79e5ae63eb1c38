//! Issue 14, "show only what is true": the real app through egui_kittest against the simulated
//! window cleaner on a pty. Cursor readout, broken lines, the packet monitor's view, port open
//! vs device answering, a unit's values and verdicts forgotten, the safe state and what is
//! running, tunable presets, per-profile port settings, pause.

use botbench::i18n::Lang;
use botbench::sim::SimOptions;
use botbench::sim::window_cleaner::WindowCleaner;
use botbench::ui::{App, PanelId};
use eframe::egui;
use egui_kittest::kittest::Queryable;

mod gui_harness;
use gui_harness::{H, Served, app, app_mut, serve, settings, step_until};

fn bench() -> Served<WindowCleaner> {
    serve(WindowCleaner::new(&SimOptions::default()).unwrap())
}

/// The app on the window cleaner at `path`, with 100 ms for the device to start answering:
/// generous for a loaded test machine.
fn harness(path: &str, panel: PanelId) -> H {
    let mut saved = settings(path, "window-cleaner", panel, Lang::En);
    saved.port_mut().margin_ms = Some(100);
    gui_harness::harness(saved)
}

fn show(h: &mut H, panel: PanelId) {
    app_mut(h).settings.panel = panel;
    h.run_steps(3);
}

#[test]
fn the_packet_monitor_opened_late_shows_the_newest_and_holds_where_the_technician_scrolled() {
    let b = bench();
    let mut h = harness(b.path(), PanelId::Tuning);
    // A small log, so that it is full (and drops its oldest) within the test.
    app_mut(&mut h).state.packets.capacity = 400;
    step_until(&mut h, "traffic", |a| a.state.packets.entries.len() >= 400);
    show(&mut h, PanelId::Monitor);
    let newest = |a: &App| a.state.packets.first_seq() + a.state.packets.entries.len() as u64;
    {
        let a = app(&h);
        assert!(a.monitor.follow, "it follows by default");
        let top = a.monitor.top.expect("rows shown");
        assert!(
            top + 60 >= newest(a),
            "the newest is in view: top {top}, newest {}",
            newest(a)
        );
    }
    // The technician scrolls up: the view leaves the newest and stays on the same frames while
    // new ones come and old ones are dropped.
    let area = h
        .get_all_by_label_contains("MSP_")
        .last()
        .unwrap()
        .rect()
        .center();
    h.hover_at(area);
    for _ in 0..6 {
        h.event(egui::Event::MouseWheel {
            unit: egui::MouseWheelUnit::Line,
            delta: egui::vec2(0.0, 5.0),
            phase: egui::TouchPhase::Move,
            source: egui::MouseWheelSource::Unknown,
            modifiers: egui::Modifiers::NONE,
        });
        h.step();
    }
    h.run_steps(20);
    let held = app(&h).monitor.top.unwrap();
    assert!(!app(&h).monitor.follow);
    let until = newest(app(&h)) + 200;
    step_until(&mut h, "more traffic", |a| newest(a) >= until);
    h.run_steps(2);
    let a = app(&h);
    assert_eq!(
        a.monitor.top,
        Some(held),
        "the view stays on the frames it was on"
    );
    let (below, secs) = a.monitor.behind.expect("says how far behind");
    assert!(below >= 200 && secs > 0.0, "{below} {secs}");
    assert!(
        h.query_by_label_contains("newer frame(s) below the view")
            .is_some()
    );
    // "Newest" follows again.
    h.get_by_label("Newest").click();
    h.run_steps(3);
    let a = app(&h);
    assert!(a.monitor.follow);
    assert!(a.monitor.top.unwrap() + 60 >= newest(a));
}
