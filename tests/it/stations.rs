//! Two stations in one window (issue 24 §1): a window cleaner and a bus of fresh servos, each on
//! its own pseudo-terminal served in lockstep, one job each at the same time (the self-test on
//! one, provisioning on the other). Their readings, packet logs, panels and verdicts never mix;
//! unplugging one port leaves the other answering, and the unplugged one comes back on its own.

use crate::support::gui::{H, app, app_mut, harness, settings, step_until, type_into};
use crate::support::{selftest_plan, serve, temp_dir, window_cleaner};
use botbench::i18n::Lang;
use botbench::link::{LinkState, Opener, PortOpener};
use botbench::packet::Header;
use botbench::sim::servo_bus::{ServoBus, SimServo};
use botbench::ui::selftest::SelfTestPanel;
use botbench::ui::servo_bench::ServoBenchPanel;
use botbench::ui::station::Station;
use botbench::ui::{App, PanelId, Target};
use egui_kittest::kittest::Queryable;
use std::sync::{Arc, Mutex};

/// What the second station's fixture path opens: the bus plugged in now (a new pty stands in
/// for an adapter plugged back in), or nothing.
type Plugged = Arc<Mutex<Option<(String, PortOpener)>>>;

/// The name the servo station's port has, as a fixture's stable path does.
const FIXTURE_B: &str = "fixture-b";

/// A port opener where [`FIXTURE_B`] opens whatever `plugged` holds when the link opens it.
fn fixture(plugged: &Plugged) -> PortOpener {
    let plugged = plugged.clone();
    PortOpener::system().with_port(FIXTURE_B, move |baud| -> Opener {
        let plugged = plugged.clone();
        Box::new(move || {
            let now = plugged.lock().unwrap().clone();
            match now {
                Some((path, ports)) => ports.open(&path, baud)(),
                None => Err(botbench::link::LinkError::Open {
                    path: FIXTURE_B.into(),
                    reason: "nothing plugged in".into(),
                }),
            }
        })
    })
}

/// Whether `station`'s packet log holds frames, each of the servo protocol (`servo`) or of MSP
/// (bytes that are no frame, as an answer at another baud rate, are no protocol's); fails
/// naming a frame of the other protocol.
fn only(station: &Station, servo: bool) -> bool {
    let frames: Vec<_> = station
        .packets
        .entries
        .iter()
        .filter_map(|l| l.frame().and_then(|e| e.frame.as_ref().ok()))
        .collect();
    let wrong: Vec<_> = frames
        .iter()
        .filter(|p| matches!(p.header, Header::Servo) != servo)
        .collect();
    assert!(wrong.is_empty(), "{wrong:?}");
    !frames.is_empty()
}

fn station(a: &App, i: usize) -> &Station {
    &a.state.stations()[i]
}

/// Shows station `i` and lets the window draw it.
fn show(h: &mut H, i: usize) {
    app_mut(h).state.show(i);
    h.run_steps(2);
}

/// Station 0 (shown) starts its self-test and waits at the operator prompt.
fn start_selftest(h: &mut H, plan: &std::path::Path) {
    app_mut(h).panel_mut::<SelfTestPanel>().path = plan.display().to_string();
    app_mut(h).panel_mut::<SelfTestPanel>().log_path = String::new();
    h.step();
    h.get_by_label("Open plan").click();
    h.run_steps(2);
    step_until(h, "nothing running on the window cleaner", |a| {
        station(a, 0).job_progress().is_none()
    });
    h.get_by_label("Run self-test").click();
    step_until(h, "the operator prompt", |a| {
        a.panel::<SelfTestPanel>().prompt.is_some()
    });
}

/// Station 1 (shown) starts provisioning the fresh servo with the shipped plan.
fn start_provisioning(h: &mut H) {
    h.get_by_label("Production").click();
    h.step();
    let plan = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/presets/servo-provision-plan.ron"
    );
    type_into(h, "Plan", plan);
    type_into(h, "CSV log", "");
    h.get_by_label("Load plan").click();
    h.step();
    h.get_by_label("Provision next").click();
    h.step();
    step_until(h, "provisioning under way", |a| {
        station(a, 1).job_progress().is_some() || !station(a, 1).verdicts.is_empty()
    });
}

/// After one job each: each station's verdict, readings, packets and panels are its own.
fn nothing_mixed(a: &App) {
    let s = &a.state;
    let (cleaner, servos) = (&s.stations()[0], &s.stations()[1]);
    // Each verdict on its own station's unit, and only there.
    let report = cleaner.verdicts.selftest.as_ref().unwrap();
    assert!(report.pass, "{report:#?}");
    assert!(cleaner.verdicts.provisioned.is_none());
    let record = servos.verdicts.provisioned.as_ref().unwrap();
    assert!(record.result.is_pass(), "{record:#?}");
    assert_eq!(record.serial, Some(4001));
    assert!(servos.verdicts.selftest.is_none());
    // Readings and plots: the window cleaner's on its station, none on the servo station.
    assert!((130..=136).all(|id| cleaner.device.readings.contains_key(&id)));
    assert!(cleaner.device.plots.values().any(|p| p.span().is_some()));
    assert!(servos.device.readings.is_empty() && servos.device.plots.is_empty());
    // Packet logs: MSP frames on one, servo frames on the other.
    assert!(!cleaner.packets.entries.is_empty() && !servos.packets.entries.is_empty());
    assert!(only(cleaner, false), "no frame in the window cleaner's log");
    assert!(only(servos, true), "no frame in the servo station's log");
    // Panels: each job's output went to the panel of its own station.
    let panel = |i: usize| s.stations()[i].panels.get::<ServoBenchPanel>().unwrap();
    assert_eq!(panel(1).production.history.len(), 1);
    assert!(panel(0).production.history.is_empty());
    let selftest = |i: usize| s.stations()[i].panels.get::<SelfTestPanel>().unwrap();
    assert!(!selftest(0).results.is_empty());
    assert!(selftest(1).results.is_empty() && selftest(1).prompt.is_none());
    assert_eq!(
        a.settings.profile, "window-cleaner",
        "the shown station's is saved"
    );
}

#[test]
fn two_stations_in_one_window_never_mix_and_lose_their_ports_independently() {
    let wc = serve(window_cleaner());
    let plugged: Plugged = Arc::default();
    let bus = serve(ServoBus::new(vec![SimServo::fresh(4001)]));
    *plugged.lock().unwrap() = Some((bus.path().to_string(), bus.ports()));
    let mut h = harness(
        settings(wc.path(), "window-cleaner", PanelId::SELF_TEST, Lang::En),
        wc.ports(),
    );
    let b = app_mut(&mut h)
        .add_station(
            Target::Port(FIXTURE_B.into()),
            115_200,
            "servo",
            fixture(&plugged),
        )
        .expect("the second station connects");
    assert_eq!(b, 1);
    step_until(&mut h, "both links", |a| {
        station(a, 0).connected() && station(a, 1).connected()
    });

    // One job each, at the same time: the self-test waits at its operator prompt while the
    // other station provisions its servo.
    let dir = temp_dir();
    let plan = dir.path().join("plan.ron");
    std::fs::write(&plan, selftest_plan(60_000)).unwrap();
    start_selftest(&mut h, &plan);
    show(&mut h, 1);
    assert!(
        h.query_by_label("Run self-test").is_none(),
        "the servo station has no self-test"
    );
    start_provisioning(&mut h);
    // Back on the window cleaner: the technician covers the corners and answers.
    show(&mut h, 0);
    h.get_by_label("Self-test").click();
    h.run_steps(2);
    wc.sim().set_corners(0b1111);
    h.get_by_label("Done").click();
    step_until(&mut h, "both verdicts", |a| {
        station(a, 0).verdicts.selftest.is_some() && station(a, 1).verdicts.provisioned.is_some()
    });
    step_until(&mut h, "both jobs ended", |a| {
        a.state
            .stations()
            .iter()
            .all(|s| s.job_progress().is_none())
    });

    nothing_mixed(app(&h));

    // The servo station's adapter is unplugged: its link is lost, the window cleaner answers.
    let mut bus = bus;
    *plugged.lock().unwrap() = None;
    bus.server.vanish();
    step_until(&mut h, "the servo station's link lost", |a| {
        !station(a, 1).connected()
            && matches!(
                station(a, 1).link.state,
                Some(LinkState::Lost { .. } | LinkState::Reconnecting { .. })
            )
    });
    // A lost link says nothing of which unit is on the fixture: the verdict stays with its
    // unit, until the next run or another unit identifies itself (issue 25, item 6).
    assert!(
        !station(app(&h), 1).verdicts.is_empty(),
        "its verdict stays with its unit"
    );
    let newest = |a: &App| station(a, 0).packets.entries.back().map(|l| l.row.at());
    let before = newest(app(&h));
    step_until(
        &mut h,
        "the window cleaner still polled and answering",
        |a| station(a, 0).connected() && newest(a) > before,
    );
    assert!(
        station(app(&h), 0).verdicts.selftest.is_some(),
        "the window cleaner's unit keeps its verdict"
    );

    // A bus is plugged back in at the fixture: the servo station reconnects by itself.
    let bus2 = serve(ServoBus::new(vec![SimServo::fresh(4002)]));
    *plugged.lock().unwrap() = Some((bus2.path().to_string(), bus2.ports()));
    step_until(&mut h, "the servo station back", |a| {
        station(a, 1).connected()
    });
    assert!(station(app(&h), 0).connected());
    assert!(only(station(app(&h), 1), true) && only(station(app(&h), 0), false));
}
