//! The servo bench's ID & baud rate and motion tabs in the real app, driven through
//! egui_kittest against the simulated servo bus on a pty: an id change, a baud change followed
//! and verified, a lost servo found, the user data reset, a move, wheel mode and damping.

use botbench::i18n::Lang;
use botbench::sim::servo_bus::{Motion, SimServo};
use botbench::ui::servo_bench::ServoBenchPanel;
use eframe::egui;
use egui_kittest::kittest::Queryable;
use std::time::Instant;

use crate::support::gui::{app, app_mut, idle, step_until, type_into};
use crate::support::servo_bench::{bench, harness, scan, set_baud};

#[test]
fn an_id_change_from_the_panel_is_verified_and_bad_ids_are_refused() {
    let b = bench(vec![
        SimServo::fresh(31).with_id(5),
        SimServo::fresh(32).with_id(7),
    ]);
    let mut h = harness(&b, Lang::En);
    scan(&mut h, "0", "10");
    h.get_by_label("Servo 5").click();
    h.step();
    h.get_by_label("ID & baud rate").click();
    h.step();
    for (bad, why) in [("7", "already answers"), ("255", "broadcast")] {
        type_into(&mut h, "New id", bad);
        assert!(
            h.query_by_label_contains(why).is_some(),
            "{bad} is refused because of {why}"
        );
        h.get_by_label("Set ID").click();
        h.run_steps(3);
        assert!(idle(app(&h)));
    }
    type_into(&mut h, "New id", "12");
    h.get_by_label("Set ID").click();
    h.step();
    step_until(&mut h, "the id change", |a| {
        idle(a) && a.panel::<ServoBenchPanel>().setup.message.is_some()
    });
    h.step();
    assert_eq!(b.servo(31).id(), 12);
    assert_eq!(b.servo(32).id(), 7);
    let sel = app(&h).panel::<ServoBenchPanel>().selected.unwrap();
    assert_eq!((sel.id, sel.baud), (12, 115_200));
    assert!(
        h.query_by_label_contains("verified at the new id")
            .is_some()
    );
    assert!(
        app(&h)
            .panel::<ServoBenchPanel>()
            .scan
            .rows
            .iter()
            .any(|r| r.id == 12)
    );
}

#[test]
fn the_live_angle_follows_a_move() {
    let b = bench(vec![SimServo::fresh(61).with_id(4)]);
    let mut h = harness(&b, Lang::En);
    scan(&mut h, "4", "4");
    h.get_by_label("Motion").click();
    h.step();
    h.get_by_label("Live angle").click();
    h.step();
    type_into(&mut h, "Angle (°)", "-45.5");
    type_into(&mut h, "Interval (ms)", "100");
    h.get_by_label("Go to angle").click();
    step_until(&mut h, "the plotted angle", |a| {
        a.panel::<ServoBenchPanel>()
            .motion
            .series
            .last()
            .is_some_and(|p| (p[1] + 45.5).abs() < 1e-6)
    });
    h.step();
    assert!(h.query_by_label("-45.5°").is_some());
}

/// Issue 25, item 3: a MONITOR answer in its "no data" form (angle -235929599, turns 0, which
/// the vendor SDK skips) is said as no data in the Motion tab, in both languages, never as an
/// angle of -23592959.9°.
#[test]
fn the_motion_tabs_monitor_shows_a_no_data_answer_as_no_data() {
    let b = bench(vec![
        SimServo::fresh(62).with_id(4).with_monitor_no_data(true),
    ]);
    let mut h = harness(&b, Lang::En);
    scan(&mut h, "4", "4");
    h.get_by_label("Motion").click();
    h.step();
    h.get_by_label("Also monitor (newer servos)").click();
    h.step();
    h.get_by_label("Live angle").click();
    h.step();
    step_until(&mut h, "a MONITOR answer", |a| {
        a.station()
            .device
            .readings
            .contains_key(&botbench::protocol::servo::cmd::MONITOR)
    });
    h.run_steps(2);
    assert!(
        h.query_by_label("monitor: no data (the servo has no reading to give)")
            .is_some()
    );
    assert!(
        h.query_all_by_label_contains("23592959").next().is_none(),
        "no angle made of the no-data form"
    );
    app_mut(&mut h).settings.lang = Lang::Zh;
    h.run_steps(2);
    assert!(h.query_by_label("监控:无数据(舵机暂无读数)").is_some());
}

#[test]
fn a_baud_change_is_followed_and_verified_and_a_lost_servo_is_found() {
    let b = bench(vec![
        SimServo::fresh(81).with_id(4),
        // An old servo does not take option 8 (1 Mbaud): it stays at 115200.
        SimServo::fresh(82).with_id(6).with_extended(false),
    ]);
    let mut h = harness(&b, Lang::En);
    scan(&mut h, "0", "8");
    set_baud(&mut h, "Servo 4", "4 (57600)");
    step_until(&mut h, "the baud change", |a| {
        idle(a) && a.panel::<ServoBenchPanel>().setup.message.is_some()
    });
    h.step();
    assert_eq!(b.servo(81).baud(), 57_600);
    let sel = app(&h).panel::<ServoBenchPanel>().selected.unwrap();
    assert_eq!((sel.id, sel.baud), (4, 57_600));
    assert!(h.query_by_label_contains("57600 baud: verified").is_some());

    h.get_by_label("Bus scan").click();
    h.step();
    set_baud(&mut h, "Servo 6", "8 (1000000, newer servos)");
    step_until(&mut h, "the failed baud change", |a| {
        idle(a)
            && a.panel::<ServoBenchPanel>()
                .setup
                .message
                .as_ref()
                .is_some_and(|(ok, m)| !ok && m.contains("found at 115200"))
    });
    let sel = app(&h).panel::<ServoBenchPanel>().selected.unwrap();
    assert_eq!(
        (sel.id, sel.baud),
        (6, 115_200),
        "the servo is where it was found"
    );
    assert_eq!(b.servo(82).baud(), 115_200);
}

#[test]
fn reset_user_data_asks_first_then_follows_the_servo_to_id_0() {
    let b = bench(vec![
        SimServo::fresh(95)
            .with_id(9)
            .with_baud(57_600)
            .with_param(41, 61),
    ]);
    let mut h = harness(&b, Lang::En);
    h.get_by_label("57600").click();
    scan(&mut h, "9", "9");
    h.get_by_label("Parameters").click();
    // The tab reads the selected servo as soon as it shows it.
    step_until(&mut h, "the parameters read", |a| {
        idle(a) && a.panel::<ServoBenchPanel>().params.values.get(&41) == Some(&Ok(61))
    });
    h.get_by_label("Reset user data…").click();
    h.run_steps(2);
    h.get_by_label("Keep").click();
    h.run_steps(3);
    assert!(idle(app(&h)));
    assert_eq!(b.servo(95).id(), 9);
    h.get_by_label("Reset user data…").click();
    h.run_steps(2);
    h.get_by_label("Reset").click();
    h.step();
    step_until(&mut h, "the reset", |a| {
        idle(a) && a.panel::<ServoBenchPanel>().params.message.is_some()
    });
    let s = b.servo(95);
    assert_eq!((s.id(), s.baud()), (0, 115_200));
    let sel = app(&h).panel::<ServoBenchPanel>().selected.unwrap();
    assert_eq!((sel.id, sel.baud), (0, 115_200));
    assert!(
        app(&h).panel::<ServoBenchPanel>().params.values.get(&34) == Some(&Ok(0)),
        "read again"
    );
}

#[test]
fn wheel_mode_and_damping_reach_the_servo() {
    let b = bench(vec![SimServo::fresh(97).with_id(8)]);
    let mut h = harness(&b, Lang::En);
    scan(&mut h, "8", "8");
    h.get_by_label("Motion").click();
    h.step();
    h.get_by_label("Method").click();
    h.run_steps(2);
    h.get_by_label("Continuous").click();
    h.step();
    type_into(&mut h, "Speed (°/s)", "120");
    h.get_by_label("Run wheel").click();
    h.step();
    step_until(
        &mut h,
        "the spin",
        |_| matches!(b.servo(97).motion_at(Instant::now()), Motion::Spin { rate, .. } if rate > 0.0),
    );
    // Out of range speeds are refused before sending.
    type_into(&mut h, "Speed (°/s)", "70000");
    assert!(
        h.query_all_by_label_contains("out of range")
            .next()
            .is_some()
    );
    type_into(&mut h, "Holding power (mW, 0 = limit)", "1500");
    h.get_by_label("Damping mode").click();
    h.step();
    step_until(&mut h, "damping", |_| {
        b.servo(97).motion_at(Instant::now()) == Motion::Damping { power: 1500 }
    });
}

#[test]
fn a_multi_turn_move_shorter_than_its_acceleration_and_deceleration_is_refused_as_typed() {
    let b = bench(vec![SimServo::fresh(71).with_id(4)]);
    let mut h = harness(&b, Lang::En);
    scan(&mut h, "4", "4");
    h.get_by_label("Motion").click();
    h.step();
    h.get_by_label("Multi-turn").click();
    h.step();
    let before = b.servo(71).motion_at(Instant::now());
    type_into(&mut h, "Angle (°)", "720");
    type_into(&mut h, "Interval (ms)", "50");
    type_into(&mut h, "Acceleration (ms)", "30");
    type_into(&mut h, "Deceleration (ms)", "40");
    // The profile's rule, as the command line applies it: 50 ms given, 70 ms the least.
    assert!(h.query_by_label_contains("= 70 ms must be ≤").is_some());
    let go = h.get_by_label("Go to angle");
    assert!(egui_kittest::kittest::NodeT::accesskit_node(&go).is_disabled());
    assert_eq!(
        b.servo(71).motion_at(Instant::now()),
        before,
        "nothing sent"
    );

    type_into(&mut h, "Interval (ms)", "70");
    h.get_by_label("Go to angle").click();
    step_until(&mut h, "the multi-turn move", |_| {
        matches!(b.servo(71).motion_at(Instant::now()), Motion::Move { to, .. } if to == 7200.0)
            || b.servo(71).angle_at(Instant::now()) == 7200.0
    });
}

/// The connection bar's baud rate, as shown.
fn bar_baud(h: &crate::support::gui::H) -> String {
    h.get_by(|n| {
        n.role() == egui::accesskit::Role::ComboBox && n.label().as_deref() == Some("Baud")
    })
    .value()
    .unwrap_or_default()
}

/// Issue 25, item 10: the top bar's baud is the port's actual rate. A baud change from the ID &
/// baud tab takes the port to the servo's new rate: the bar shows it (it showed the rate it had
/// connected with). A rate the technician picked in the bar to reconnect with is theirs: the
/// port moving again leaves it.
#[test]
fn the_top_bars_baud_follows_the_port_to_a_servos_new_rate() {
    let b = bench(vec![SimServo::fresh(83).with_id(4)]);
    let mut h = harness(&b, Lang::En);
    h.run_steps(2);
    assert_eq!(bar_baud(&h), "115200");
    scan(&mut h, "4", "4");
    set_baud(&mut h, "Servo 4", "4 (57600)");
    step_until(&mut h, "the baud change", |a| {
        idle(a) && a.panel::<ServoBenchPanel>().setup.message.is_some()
    });
    h.run_steps(2);
    assert_eq!(app(&h).station().link.baud(), Some(57_600));
    assert_eq!(bar_baud(&h), "57600", "the bar shows the port's rate");
    let reconnect = h.get_by_label("Reconnect");
    assert!(
        egui_kittest::kittest::NodeT::accesskit_node(&reconnect).is_disabled(),
        "the port is where the bar says: nothing to reconnect"
    );

    // The technician picks 230400 to reconnect with; the port then moves back to 115200.
    h.get_by(|n| {
        n.role() == egui::accesskit::Role::ComboBox && n.label().as_deref() == Some("Baud")
    })
    .click();
    h.run_steps(2);
    h.get_by_label("230400").click();
    h.run_steps(2);
    h.get_by_label("Bus scan").click();
    h.step();
    set_baud(&mut h, "Servo 4", "5 (115200)");
    step_until(&mut h, "the port back at 115200", |a| {
        idle(a) && a.station().link.baud() == Some(115_200)
    });
    h.run_steps(2);
    assert_eq!(bar_baud(&h), "230400", "the rate picked is kept");
}
