//! Servo operations through the link worker against the simulated bus on a pseudo-terminal.

use botbench::ops::Cancel;
use botbench::ops::msp::OpError;
use botbench::ops::servo::{self as ops, Presence, ScanPlan};
use botbench::profile::Input;
use botbench::sim::servo_bus::SimServo;

mod common;
use common::Bench;

impl Bench {
    fn scan(&self, bauds: &[u32]) -> Vec<(u8, u32, Presence)> {
        let plan = ScanPlan {
            ids: 0..=254,
            bauds: bauds.to_vec(),
            home_baud: 115_200,
        };
        ops::scan(
            &self.client(),
            &self.profile,
            &plan,
            &Cancel::new(),
            &mut |_| {},
            &mut |_| {},
        )
        .unwrap()
        .into_iter()
        .map(|r| (r.id, r.baud, r.presence))
        .collect()
    }
}

#[test]
fn a_scan_finds_exactly_the_servos_configured_at_their_bauds() {
    let bench = Bench::new(vec![
        SimServo::fresh(11).with_id(3),
        SimServo::fresh(12).with_id(17),
        SimServo::fresh(13).with_id(200).with_baud(57_600),
    ]);
    let mut found = bench.scan(&[115_200, 57_600]);
    found.sort_by_key(|(id, baud, _)| (*id, *baud));
    assert_eq!(
        found,
        vec![
            (3, 115_200, Presence::Present),
            (17, 115_200, Presence::Present),
            (200, 57_600, Presence::Present),
        ]
    );
}

#[test]
fn a_scan_reads_each_servos_details() {
    let bench = Bench::new(vec![SimServo::fresh(4242).with_id(9).with_type(321)]);
    let plan = ScanPlan {
        ids: 5..=12,
        bauds: vec![115_200],
        home_baud: 115_200,
    };
    let rows = ops::scan(
        &bench.client(),
        &bench.profile,
        &plan,
        &Cancel::new(),
        &mut |_| {},
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(rows.len(), 1);
    assert_eq!(rows[0].serial, Some(4242));
    assert_eq!(rows[0].servo_type, Some(321));
    assert!(rows[0].voltage_mv.is_some_and(|v| v > 5000));
}

#[test]
fn two_servos_on_one_id_are_reported_as_a_possible_duplicate() {
    let bench = Bench::new(vec![
        SimServo::fresh(1).with_id(6),
        SimServo::fresh(2).with_id(6),
    ]);
    let found = bench.scan(&[115_200]);
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!(found[0].0, 6);
    assert!(
        matches!(found[0].2, Presence::PossibleDuplicate(_)),
        "{found:?}"
    );
}

#[test]
fn an_id_change_is_followed_and_verified_and_bad_ids_are_refused() {
    let bench = Bench::new(vec![SimServo::fresh(77)]);
    let c = bench.client();
    let cancel = Cancel::new();
    assert!(matches!(
        ops::set_id(&c, &bench.profile, 0, 255, &cancel),
        Err(OpError::Input(_))
    ));
    ops::set_id(&c, &bench.profile, 0, 12, &cancel).unwrap();
    assert_eq!(
        bench.bus.lock().unwrap().servo_by_serial(77).unwrap().id(),
        12
    );
    // Another servo arrives fresh: id 12 is taken now.
    bench.bus.lock().unwrap().add(SimServo::fresh(78));
    let err = ops::set_id(&c, &bench.profile, 0, 12, &cancel).unwrap_err();
    assert!(err.to_string().contains("already answers"), "{err}");
    // A fresh servo is only given an id when it is alone on the bus... it is alone at id 0,
    // but servo 12 is also on the bus.
    let err = ops::set_id(&c, &bench.profile, 0, 13, &cancel).unwrap_err();
    assert!(err.to_string().contains("alone on the bus"), "{err}");
}

#[test]
fn a_baud_change_is_followed_and_verified() {
    let bench = Bench::new(vec![SimServo::fresh(5).with_id(4)]);
    let c = bench.client();
    let baud = ops::set_baud(&c, &bench.profile, 4, 4).unwrap();
    assert_eq!(baud, 57_600);
    assert_eq!(
        bench.bus.lock().unwrap().servo_by_serial(5).unwrap().baud(),
        57_600
    );
    // The link follows: the servo answers at the new rate.
    assert_eq!(ops::ping(&c, 4, 2).unwrap(), Presence::Present);
    let err = ops::set_baud(&c, &bench.profile, 4, 9).unwrap_err();
    assert!(
        matches!(err, OpError::Input(ref m) if m.contains("out of range")),
        "{err}"
    );
}

#[test]
fn a_servo_lost_after_a_baud_change_is_found_and_its_rate_named() {
    // An old servo does not take option 8 (1 Mbaud): it stays at 115200.
    let bench = Bench::new(vec![SimServo::fresh(9).with_id(2).with_extended(false)]);
    let c = bench.client();
    let err = ops::set_baud(&c, &bench.profile, 2, 8).unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains("found at 115200"), "{msg}");
    assert_eq!(
        ops::ping(&c, 2, 2).unwrap(),
        Presence::Present,
        "the port was left where it is"
    );
}

#[test]
fn a_parameter_write_is_range_checked_and_read_back() {
    let bench = Bench::new(vec![SimServo::fresh(3).with_id(1)]);
    let c = bench.client();
    let p = bench.profile.find_param("angle_limit_high").unwrap();
    let check = ops::write_param(&c, &bench.profile, 1, p, Input::from("90.5")).unwrap();
    assert!(check.ok(), "{check:?}");
    assert_eq!(
        bench
            .bus
            .lock()
            .unwrap()
            .servo_by_serial(3)
            .unwrap()
            .param(p.id),
        Some(905)
    );
    let ro = bench.profile.find_param("voltage").unwrap();
    assert!(matches!(
        ops::write_param(&c, &bench.profile, 1, ro, Input::from("5000")),
        Err(OpError::Input(_))
    ));
    let baud = bench.profile.find_param("baudrate").unwrap();
    assert!(matches!(
        ops::write_param(&c, &bench.profile, 1, baud, Input::from("9")),
        Err(OpError::Input(_))
    ));
}
