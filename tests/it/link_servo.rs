//! Servo operations through the link worker against the simulated bus on a pseudo-terminal.

use botbench::ops::Cancel;
use botbench::ops::OpError;
use botbench::ops::servo::{self as ops, Presence, ScanPlan};
use botbench::ops::{Device, Run};
use botbench::profile::Input;
use botbench::sim::servo_bus::SimServo;

use crate::support::servo::Bench;
use crate::support::wait_until;
use std::time::Instant;

impl Bench {
    fn scan(&self, bauds: &[u32]) -> Vec<(u8, u32, Presence)> {
        let plan = ScanPlan {
            ids: 0..=254,
            bauds: bauds.to_vec(),
            home_baud: 115_200,
        };
        ops::scan(
            Device::new(&self.client(), &self.profile),
            &plan,
            &mut Run::quiet(&Cancel::new()),
            &mut |_| {},
        )
        .unwrap()
        .rows
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

/// The rows of a scan of ids 5-12 at 115200 baud.
fn scan_5_to_12(
    client: &botbench::link::Client,
    profile: &botbench::profile::Profile,
) -> Vec<ops::ScanRow> {
    let plan = ScanPlan {
        ids: 5..=12,
        bauds: vec![115_200],
        home_baud: 115_200,
    };
    ops::scan(
        Device::new(client, profile),
        &plan,
        &mut Run::quiet(&Cancel::new()),
        &mut |_| {},
    )
    .unwrap()
    .rows
}

#[test]
fn a_scan_reads_each_servos_details() {
    let bench = Bench::new(vec![SimServo::fresh(4242).with_id(9).with_type(321)]);
    let rows = scan_5_to_12(&bench.client(), &bench.profile);
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
        ops::set_id(Device::new(&c, &bench.profile), 0, 255, &cancel),
        Err(OpError::BroadcastId)
    ));
    ops::set_id(Device::new(&c, &bench.profile), 0, 12, &cancel).unwrap();
    assert_eq!(bench.servo(77).id(), 12);
    // Another servo arrives fresh: id 12 is taken now.
    bench.bus().add(SimServo::fresh(78));
    let err = ops::set_id(Device::new(&c, &bench.profile), 0, 12, &cancel).unwrap_err();
    assert!(err.to_string().contains("already answers"), "{err}");
    // A fresh servo is only given an id when it is alone on the bus... it is alone at id 0,
    // but servo 12 is also on the bus.
    let err = ops::set_id(Device::new(&c, &bench.profile), 0, 13, &cancel).unwrap_err();
    assert!(err.to_string().contains("alone on the bus"), "{err}");
}

#[test]
fn a_baud_change_is_followed_and_verified() {
    let bench = Bench::new(vec![SimServo::fresh(5).with_id(4)]);
    let c = bench.client();
    let baud = ops::set_baud(Device::new(&c, &bench.profile), 4, 4).unwrap();
    assert_eq!(baud, 57_600);
    assert_eq!(bench.servo(5).baud(), 57_600);
    // The link follows: the servo answers at the new rate.
    assert_eq!(ops::ping(&c, 4, 2).unwrap(), Presence::Present);
    let err = ops::set_baud(Device::new(&c, &bench.profile), 4, 9).unwrap_err();
    assert!(
        matches!(
            err,
            OpError::OutOfRange {
                what: "baud option",
                value: 9,
                ..
            }
        ),
        "{err}"
    );
}

#[test]
fn a_servo_lost_after_a_baud_change_is_found_and_its_rate_named() {
    // An old servo does not take option 8 (1 Mbaud): it stays at 115200.
    let bench = Bench::new(vec![SimServo::fresh(9).with_id(2).with_extended(false)]);
    let c = bench.client();
    let err = ops::set_baud(Device::new(&c, &bench.profile), 2, 8).unwrap_err();
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
    let check =
        ops::write_param(Device::new(&c, &bench.profile), 1, p, Input::from("90.5")).unwrap();
    assert!(check.ok(), "{check:?}");
    assert_eq!(bench.servo(3).param(p.id), Some(905));
    let ro = bench.profile.find_param("voltage").unwrap();
    assert!(matches!(
        ops::write_param(Device::new(&c, &bench.profile), 1, ro, Input::from("5000")),
        Err(OpError::ReadOnly { .. })
    ));
    let baud = bench.profile.find_param("baudrate").unwrap();
    assert!(matches!(
        ops::write_param(Device::new(&c, &bench.profile), 1, baud, Input::from("9")),
        Err(OpError::Value(_))
    ));
}

#[test]
fn the_user_block_is_read_and_written_as_a_batch_and_read_back() {
    let bench = Bench::new(vec![SimServo::fresh(21).with_id(4).with_param(41, 65)]);
    let (client, profile) = (bench.client(), bench.profile.clone());
    let mut block = ops::read_block(Device::new(&client, &profile), 4).unwrap();
    assert_eq!(block.len(), 22);
    assert!(block.contains(&(41, 65)));
    assert!(block.contains(&(34, 4)));
    for (id, v) in block.iter_mut() {
        if *id == 41 {
            *v = 72;
        }
    }
    let checks = ops::write_block(Device::new(&client, &profile), 4, &block).unwrap();
    assert!(checks.iter().all(|c| c.ok()), "{checks:?}");
    assert_eq!(bench.servo(21).param(41), Some(72));
    // The id is not changed through the block: the servo would be lost.
    let mut moved = block.clone();
    for (id, v) in moved.iter_mut() {
        if *id == 34 {
            *v = 9;
        }
    }
    let e = ops::write_block(Device::new(&client, &profile), 4, &moved).unwrap_err();
    assert!(matches!(e, OpError::FollowedChange { .. }), "{e}");
    assert_eq!(bench.servo(21).id(), 4);
    // Out of range values are refused before anything is sent.
    let mut bad = block.clone();
    bad.retain(|(id, _)| *id != 44);
    bad.push((44, 7));
    assert!(matches!(
        ops::write_block(Device::new(&client, &profile), 4, &bad),
        Err(OpError::Value(_))
    ));
}

#[test]
fn reset_user_data_follows_the_servo_to_its_factory_id_and_rate() {
    let bench = Bench::new(vec![
        SimServo::fresh(31)
            .with_id(6)
            .with_baud(57_600)
            .with_param(41, 60),
    ]);
    let (client, profile) = (bench.client(), bench.profile.clone());
    client.set_baud(57_600).unwrap();
    let at = ops::reset_user_data(Device::new(&client, &profile), 6, 57_600).unwrap();
    assert_eq!(
        at,
        ops::Location {
            id: 0,
            baud: 115_200
        }
    );
    let s = bench.servo(31);
    assert_eq!((s.id(), s.baud()), (0, 115_200));
    assert_ne!(s.param(41), Some(60));
}

#[test]
fn reset_user_data_is_refused_when_another_servo_holds_the_factory_id() {
    let bench = Bench::new(vec![SimServo::fresh(41).with_id(6), SimServo::fresh(42)]);
    let (client, profile) = (bench.client(), bench.profile.clone());
    let e = ops::reset_user_data(Device::new(&client, &profile), 6, 115_200).unwrap_err();
    assert!(matches!(e, OpError::FactoryIdTaken { .. }), "{e}");
    assert_eq!(bench.servo(41).id(), 6);
}

#[test]
fn motion_requests_move_the_servo_and_stop_all_stops_every_servo() {
    use botbench::sim::servo_bus::Motion;
    let bench = Bench::new(vec![
        SimServo::fresh(51).with_id(1),
        SimServo::fresh(52).with_id(2).with_extended(false),
    ]);
    let (client, profile) = (bench.client(), bench.profile.clone());
    let r = ops::rotate_request(&profile, 1, 450, 10, 0).unwrap();
    let _ = client.request(r);
    wait_until("the move to end", || {
        bench.servo(51).motion_at(Instant::now()) == Motion::Hold
    });
    let angle = ops::read_angle(Device::new(&client, &profile), 1).unwrap();
    assert_eq!(angle, 450);
    assert!(ops::rotate_request(&profile, 1, 40_000, 10, 0).is_err());
    for id in [1, 2] {
        let r = ops::spin_request(&profile, id, ops::Wheel::Continuous, true, 60).unwrap();
        let _ = client.request(r);
    }
    wait_until("both servos to spin", || {
        [51, 52].iter().all(|s| {
            matches!(
                bench.servo(*s).motion_at(Instant::now()),
                Motion::Spin { .. }
            )
        })
    });
    for r in ops::stop_all_requests(&profile) {
        client.request(r).unwrap();
    }
    // A broadcast is not answered: the ping makes sure it has crossed the wire.
    assert_eq!(ops::ping(&client, 1, 2).unwrap(), Presence::Present);
    let now = Instant::now();
    assert_eq!(bench.servo(51).motion_at(now), Motion::Hold);
    assert_eq!(bench.servo(52).motion_at(now), Motion::Damping { power: 0 });
}

#[test]
fn a_baud_change_right_after_a_broadcast_lets_the_broadcast_cross_the_wire_whole() {
    use botbench::sim::servo_bus::Motion;
    let bench = Bench::new(vec![SimServo::fresh(61).with_id(1)]);
    let (client, profile) = (bench.client(), bench.profile.clone());
    let r = ops::spin_request(&profile, 1, ops::Wheel::Continuous, true, 60).unwrap();
    let _ = client.request(r);
    wait_until("the servo to spin", || {
        matches!(
            bench.servo(61).motion_at(Instant::now()),
            Motion::Spin { .. }
        )
    });
    // Nobody answers a broadcast: each returns as soon as it is written, and the baud change
    // comes at once after them. The simulator hears the host's writes and baud changes at the
    // instants the host made them (lockstep), so a change that cut a broadcast off garbles it
    // here however the threads are scheduled.
    for r in ops::stop_all_requests(&profile) {
        client.request(r).unwrap();
    }
    client.set_baud(9600).unwrap();
    client.set_baud(115_200).unwrap();
    assert_eq!(ops::ping(&client, 1, 2).unwrap(), Presence::Present);
    assert_eq!(bench.servo(61).motion_at(Instant::now()), Motion::Hold);
}

#[test]
fn a_simulator_held_up_past_the_answer_deadline_still_answers_in_time() {
    // As a loaded machine holds up the simulator's thread: here the device is busy (locked by
    // the test) well past the ping's deadline, the wire time plus the servo's 1.5 ms. The
    // simulator serves in lockstep: the answer is due when the device would have sent it, and
    // the host's read waits for the simulator to catch up before it calls the deadline passed.
    let bench = Bench::new(vec![SimServo::fresh(71).with_id(3)]);
    let held = bench.bus();
    let client = bench.client();
    let ping = std::thread::spawn(move || ops::ping(&client, 3, 1));
    std::thread::sleep(std::time::Duration::from_millis(50));
    drop(held);
    assert_eq!(
        crate::support::joined(ping, "the ping").unwrap(),
        Presence::Present
    );
}

#[test]
fn an_edited_baud_table_is_the_rate_the_servo_and_the_link_move_to() {
    use botbench::link::LinkOptions;
    use botbench::sim::servo_bus::ServoBus;
    use std::sync::Arc;
    let src = crate::support::builtin_src("servo");
    assert!(src.contains(" 4: 57600,"), "test setup");
    let src = src.replacen(" 4: 57600,", " 4: 230400,", 1);
    let profile = Arc::new(
        botbench::profile::registry::parse("servo.ron", &src, None).expect("the edit loads"),
    );
    let served = crate::support::serve(ServoBus::with_profile(
        profile.clone(),
        vec![SimServo::fresh_with(&profile, 5).with_id(4)],
    ));
    let link = crate::support::open_link(
        &served,
        profile.baud,
        profile.clone(),
        LinkOptions::default(),
    );
    let c = link.client();
    assert_eq!(
        ops::set_baud(Device::new(&c, &profile), 4, 4).unwrap(),
        230_400
    );
    assert_eq!(served.servo(5).baud(), 230_400);
    assert_eq!(ops::ping(&c, 4, 2).unwrap(), Presence::Present);
}

#[test]
fn a_scan_reads_the_parameters_the_profile_gives_the_roles_of() {
    use botbench::link::LinkOptions;
    use botbench::sim::servo_bus::ServoBus;
    use std::sync::Arc;
    // A firmware variant whose document swaps the type and firmware parameters, and that has
    // no status byte to show.
    let src = crate::support::builtin_src("servo");
    let edits = [
        ("role: Some(ServoType),", "role: Some(Swapped),"),
        ("role: Some(FirmwareVersion),", "role: Some(ServoType),"),
        ("role: Some(Swapped),", "role: Some(FirmwareVersion),"),
        ("role: Some(Status),", ""),
    ];
    let mut src = src.to_string();
    for (from, to) in edits {
        assert!(src.contains(from), "test setup: {from}");
        src = src.replacen(from, to, 1);
    }
    let profile = Arc::new(
        botbench::profile::registry::parse("servo.ron", &src, None).expect("the edit loads"),
    );
    let served = crate::support::serve(ServoBus::with_profile(
        profile.clone(),
        vec![
            SimServo::fresh_with(&profile, 4242)
                .with_id(9)
                .with_type(321)
                .with_firmware(77)
                .with_status(0x21),
        ],
    ));
    let link = crate::support::open_link(
        &served,
        profile.baud,
        profile.clone(),
        LinkOptions::default(),
    );
    let rows = scan_5_to_12(&link.client(), &profile);
    assert_eq!(rows.len(), 1, "{rows:?}");
    // Parameter 7 (the servo's 77) is this profile's type, parameter 6 (321) its firmware.
    assert_eq!(rows[0].servo_type, Some(77), "{rows:?}");
    assert_eq!(rows[0].firmware, Some(321), "{rows:?}");
    assert_eq!(rows[0].serial, Some(4242), "{rows:?}");
    assert_eq!(rows[0].status, None, "no role, not read: {rows:?}");
    assert_eq!(rows[0].status_hex(), "-");
}
