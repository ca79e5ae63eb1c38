//! The bus servo simulator: the seed's examples, provisioning (id, baud, range and access
//! checks, batch and extended commands) and a vanished servo.

use super::*;

// ---------------------------------------------------------------- servo: seed examples

#[test]
fn seed_ping_servo_3() {
    let mut bus = ServoBus::new(vec![
        SimServo::fresh(1).with_id(1),
        SimServo::fresh(3).with_id(3),
        SimServo::fresh(5).with_id(5),
    ]);
    let out = bus.receive(&[0x12, 0x4c, 0x01, 0x01, 0x03, 0x63], B, Instant::now());
    assert_eq!(
        out,
        vec![Outgoing::new(
            servo_bus::DEFAULT_LATENCY,
            vec![0x05, 0x1c, 0x01, 0x01, 0x03, 0x26]
        )]
    );
    assert!(servo_bus::DEFAULT_LATENCY >= Duration::from_micros(200));
    assert!(servo_bus::DEFAULT_LATENCY <= ms(1));
}

#[test]
fn seed_read_angle_servo_0_at_90_2() {
    let mut bus = ServoBus::new(vec![SimServo::fresh(1).with_angle(902)]);
    let out = bus.receive(&[0x12, 0x4c, 0x0a, 0x01, 0x00, 0x69], B, Instant::now());
    assert_eq!(out.len(), 1);
    assert_eq!(
        out[0].bytes,
        [0x05, 0x1c, 0x0a, 0x03, 0x00, 0x86, 0x03, 0xb7]
    );
}

#[test]
fn seed_rotate_moves_linearly_and_is_silent_by_default() {
    let t0 = Instant::now();
    let mut bus = ServoBus::new(vec![SimServo::fresh(2).with_id(2)]);
    let rotate = [
        0x12, 0x4c, 0x08, 0x07, 0x02, 0x84, 0x03, 0xf4, 0x01, 0x00, 0x00, 0xeb,
    ];
    assert!(bus.receive(&rotate, B, t0).is_empty(), "response switch 0");
    let half = read_angle(&mut bus, 2, t0 + ms(250));
    assert!((449..=451).contains(&half), "halfway: {half}");
    let quarter = angle_of(&bus, 2, t0 + ms(125));
    assert!((quarter - 225.0).abs() < 1.0, "a quarter: {quarter}");
    assert_eq!(read_angle(&mut bus, 2, t0 + ms(600)), 900);
    assert_eq!(
        bus.servo_by_serial(2)
            .expect("servo")
            .motion_at(t0 + ms(600)),
        Motion::Hold
    );
}

#[test]
fn rotate_replies_when_done_with_the_response_switch_on() {
    let t0 = Instant::now();
    let mut bus = ServoBus::new(vec![
        SimServo::fresh(2)
            .with_id(2)
            .with_param(param::RESPONSE_SWITCH, 1),
    ]);
    let rotate = [
        0x12, 0x4c, 0x08, 0x07, 0x02, 0x84, 0x03, 0xf4, 0x01, 0x00, 0x00, 0xeb,
    ];
    let out = bus.receive(&rotate, B, t0);
    assert_eq!(out.len(), 1);
    assert_eq!(out[0].after, ms(500) + servo_bus::DEFAULT_LATENCY);
    assert_eq!(
        one_reply(&out),
        servo::Frame::reply(scmd::ROTATE, vec![2, 1])
    );
    // Not interruptible: the next move waits for this one (a queue of one); a third is dropped.
    let back = ask(
        &mut bus,
        scmd::ROTATE,
        &[2, 0, 0, 200, 0, 0, 0],
        B,
        t0 + ms(100),
    );
    assert_eq!(back.len(), 1);
    assert_eq!(back[0].after, ms(400 + 200) + servo_bus::DEFAULT_LATENCY);
    assert!(
        ask(
            &mut bus,
            scmd::ROTATE,
            &[2, 0, 0, 1, 0, 0, 0],
            B,
            t0 + ms(150)
        )
        .is_empty()
    );
    assert_eq!(read_angle(&mut bus, 2, t0 + ms(500)), 900);
    let mid = read_angle(&mut bus, 2, t0 + ms(600));
    assert!((449..=451).contains(&mid), "{mid}");
    assert_eq!(read_angle(&mut bus, 2, t0 + ms(800)), 0);
}

#[test]
fn rotate_without_the_switch_is_interrupted_by_the_next() {
    let t0 = Instant::now();
    let mut bus = ServoBus::new(vec![SimServo::fresh(9)]);
    ask(
        &mut bus,
        scmd::ROTATE,
        &[0, 0x84, 0x03, 0xe8, 0x03, 0, 0],
        B,
        t0,
    );
    // At 500 ms it is at 45°; a new command turns it back to 0° over 100 ms from there.
    ask(
        &mut bus,
        scmd::ROTATE,
        &[0, 0, 0, 100, 0, 0, 0],
        B,
        t0 + ms(500),
    );
    let a = read_angle(&mut bus, 0, t0 + ms(550));
    assert!((224..=226).contains(&a), "{a}");
    assert_eq!(read_angle(&mut bus, 0, t0 + ms(700)), 0);
}

#[test]
fn seed_spin_examples_change_the_angle() {
    let t0 = Instant::now();
    let mut bus = ServoBus::new(vec![SimServo::fresh(7)]);
    // Continuous, counter-clockwise, 100 °/s.
    let cont = [
        0x12, 0x4c, 0x07, 0x06, 0x00, 0x01, 0x64, 0x00, 0x00, 0x00, 0xd0,
    ];
    assert!(bus.receive(&cont, B, t0).is_empty());
    assert!((angle_of(&bus, 7, t0 + ms(1000)) + 1000.0).abs() < 0.5);
    // Stop.
    let stop = [
        0x12, 0x4c, 0x07, 0x06, 0x00, 0x00, 0x64, 0x00, 0x00, 0x00, 0xcf,
    ];
    assert!(bus.receive(&stop, B, t0 + ms(1000)).is_empty());
    let s = bus.servo_by_serial(7).expect("servo");
    assert_eq!(s.motion_at(t0 + ms(5000)), Motion::Released);
    assert!((s.angle_at(t0 + ms(5000)) + 1000.0).abs() < 0.5);

    // Five turns clockwise at 100 °/s: 18 s.
    let t1 = t0 + ms(10_000);
    let turns = [
        0x12, 0x4c, 0x07, 0x06, 0x00, 0x82, 0x64, 0x00, 0x05, 0x00, 0x56,
    ];
    assert!(bus.receive(&turns, B, t1).is_empty());
    assert!((angle_of(&bus, 7, t1 + ms(9_000)) - (-1000.0 + 9000.0)).abs() < 0.5);
    assert!((angle_of(&bus, 7, t1 + ms(30_000)) - (-1000.0 + 18000.0)).abs() < 0.5);

    // 1000 ms clockwise at 100 °/s.
    let t2 = t1 + ms(60_000);
    let timed = [
        0x12, 0x4c, 0x07, 0x06, 0x00, 0x83, 0x64, 0x00, 0xe8, 0x03, 0x3d,
    ];
    assert!(bus.receive(&timed, B, t2).is_empty());
    assert!((angle_of(&bus, 7, t2 + ms(5_000)) - 18000.0).abs() < 0.5);
    // Multi-turn read (extended): 1800.0° is five whole turns.
    let f = one_reply(&ask(
        &mut bus,
        ext::READ_ANGLE_MTURN,
        &[0],
        B,
        t2 + ms(5_000),
    ));
    assert_eq!(f.content[1..5], 18000i32.to_le_bytes());
    assert_eq!(f.content[5..7], 5i16.to_le_bytes());
}

#[test]
fn seed_damping_example_and_broadcast() {
    let t0 = Instant::now();
    let mut bus = ServoBus::new(vec![
        SimServo::fresh(1),
        SimServo::fresh(2).with_id(4),
        SimServo::fresh(3).with_id(5).with_baud(9_600),
    ]);
    let damping = [0x12, 0x4c, 0x09, 0x03, 0x00, 0xf4, 0x01, 0x5f];
    assert!(bus.receive(&damping, B, t0).is_empty());
    assert_eq!(
        bus.servo_by_serial(1).expect("servo").motion_at(t0),
        Motion::Damping { power: 500 }
    );
    // Broadcast: every servo at that baud obeys, none answers, even with replies on.
    let s = bus
        .remove(2)
        .expect("servo")
        .with_param(param::RESPONSE_SWITCH, 1);
    bus.add(s);
    let out = ask(&mut bus, scmd::DAMPING, &[255, 100, 0], B, t0);
    assert!(out.is_empty());
    for serial in [1, 2] {
        assert_eq!(
            bus.servo_by_serial(serial).expect("servo").motion_at(t0),
            Motion::Damping { power: 100 }
        );
    }
    assert_eq!(
        bus.servo_by_serial(3).expect("servo").motion_at(t0),
        Motion::Released,
        "the 9600-baud servo did not hear it"
    );
    assert!(ask(&mut bus, scmd::PING, &[255], B, t0).is_empty());
}

// ---------------------------------------------------------------- servo: provisioning

#[test]
fn id_change_is_answered_from_the_new_id() {
    let now = Instant::now();
    let mut bus = ServoBus::new(vec![SimServo::fresh(42)]);
    assert_eq!(write(&mut bus, 0, SERVO_ID, &[7], now), [7, 34, 1]);
    assert!(ask(&mut bus, scmd::PING, &[0], B, now).is_empty());
    assert_eq!(
        one_reply(&ask(&mut bus, scmd::PING, &[7], B, now)).content,
        [7]
    );
    assert_eq!(bus.servo_by_serial(42).expect("servo").id(), 7);
    // 255 cannot be assigned.
    assert_eq!(write(&mut bus, 7, SERVO_ID, &[255], now), [7, 34, 0]);
    assert_eq!(bus.servo_by_serial(42).expect("servo").id(), 7);
}

#[test]
fn baud_change_is_answered_at_the_new_baud() {
    let now = Instant::now();
    let mut bus = ServoBus::new(vec![SimServo::fresh(42)]);
    let out = ask(&mut bus, scmd::WRITE_DATA, &[0, BAUDRATE, 1], B, now);
    assert_eq!(out.len(), 1);
    assert_eq!(out[0].baud, Some(9_600));
    assert_eq!(
        servo_items(&out[0].bytes),
        vec![Ok(servo::Frame::reply(scmd::WRITE_DATA, vec![0, 36, 1]))]
    );
    assert_eq!(bus.servo_by_serial(42).expect("servo").baud(), 9_600);
    assert!(ask(&mut bus, scmd::PING, &[0], B, now).is_empty());
    let out = ask(&mut bus, scmd::PING, &[0], 9_600, now);
    assert_eq!(out.len(), 1);
    assert_eq!(out[0].baud, None);
    // Back to 1 Mbaud: option 8 on a newer servo only.
    assert_eq!(
        ask(&mut bus, scmd::WRITE_DATA, &[0, 36, 8], 9_600, now)[0].baud,
        Some(1_000_000)
    );
    let mut old = ServoBus::new(vec![SimServo::fresh(1).with_extended(false)]);
    assert_eq!(write(&mut old, 0, 36, &[8], now), [0, 36, 0]);
    assert_eq!(old.servos()[0].baud(), B);
}

#[test]
fn a_servo_at_another_baud_is_silent() {
    let now = Instant::now();
    let mut bus = ServoBus::new(vec![SimServo::fresh(1).with_baud(57_600)]);
    assert!(ask(&mut bus, scmd::PING, &[0], B, now).is_empty());
    assert!(ask(&mut bus, scmd::READ_BATCH_DATA, &[0], 250_000, now).is_empty());
    assert_eq!(
        one_reply(&ask(&mut bus, scmd::PING, &[0], 57_600, now)).content,
        [0]
    );
}

#[test]
fn duplicate_ids_collide_into_garbage() {
    let now = Instant::now();
    for seed in 0..20 {
        let mut bus = ServoBus::new(vec![
            SimServo::fresh(100),
            SimServo::fresh(200),
            SimServo::fresh(300).with_id(1),
        ])
        .with_seed(seed);
        for (command, content) in [
            (scmd::PING, vec![0]),
            (scmd::READ_DATA, vec![0, 8]),
            (scmd::READ_BATCH_DATA, vec![0]),
            (scmd::READ_ANGLE, vec![0]),
        ] {
            let out = ask(&mut bus, command, &content, B, now);
            assert_eq!(out.len(), 1, "one line, one stream of bytes");
            let items = servo_items(&out[0].bytes);
            assert!(
                items.iter().all(|i| i.is_err()),
                "seed {seed}, command {command}: a clean frame from a collision: {items:?}"
            );
        }
        // The lone servo on id 1 is fine.
        assert_eq!(
            one_reply(&ask(&mut bus, scmd::PING, &[1], B, now)).content,
            [1]
        );
    }
}

#[test]
fn writes_are_range_checked() {
    let now = Instant::now();
    let mut bus = ServoBus::new(vec![SimServo::fresh(5)]);
    let before = bus.servos()[0].params().clone();
    // stall_protect_mode takes 1 or 2 only.
    assert_eq!(write(&mut bus, 0, 37, &[5], now), [0, 37, 0]);
    // Baud option 9 does not exist.
    assert_eq!(write(&mut bus, 0, 36, &[9], now), [0, 36, 0]);
    // Read-only parameters.
    assert_eq!(write(&mut bus, 0, 1, &[0x10, 0x27], now), [0, 1, 0]);
    assert_eq!(write(&mut bus, 0, 8, &[1, 2, 3, 4], now), [0, 8, 0]);
    // Wrong width, unknown parameter.
    assert_eq!(write(&mut bus, 0, 38, &[1], now), [0, 38, 0]);
    assert_eq!(write(&mut bus, 0, 60, &[1], now), [0, 60, 0]);
    assert_eq!(bus.servos()[0].params(), &before, "nothing stored");
    // A good write is stored and read back.
    assert_eq!(write(&mut bus, 0, 38, &[0x88, 0x13], now), [0, 38, 1]);
    assert_eq!(bus.servos()[0].param(38), Some(5000));
    let f = one_reply(&ask(&mut bus, scmd::READ_DATA, &[0, 38], B, now));
    assert_eq!(f.content, [0, 38, 0x88, 0x13]);
    // Signed parameters.
    assert_eq!(
        write(&mut bus, 0, 52, &(-900i16).to_le_bytes(), now),
        [0, 52, 1]
    );
    assert_eq!(bus.servos()[0].param(52), Some(-900));
}

#[test]
fn read_only_parameters() {
    let now = Instant::now();
    let mut bus = ServoBus::new(vec![
        SimServo::fresh(0xDEAD_BEEF)
            .with_type(0x0305)
            .with_firmware(0x0110)
            .with_status(0x21),
    ]);
    let read = |bus: &mut ServoBus, id: u8| {
        let f = one_reply(&ask(bus, scmd::READ_DATA, &[0, id], B, now));
        assert_eq!(f.content[..2], [0, id]);
        f.content[2..].to_vec()
    };
    assert_eq!(read(&mut bus, 8), 0xDEAD_BEEFu32.to_le_bytes());
    assert_eq!(read(&mut bus, 6), [0x05, 0x03]);
    assert_eq!(read(&mut bus, 7), [0x10, 0x01]);
    assert_eq!(read(&mut bus, 5), [0x21]);
    let mut seen = std::collections::BTreeSet::new();
    for _ in 0..50 {
        let v = read(&mut bus, 1);
        let mv = u16::from_le_bytes([v[0], v[1]]);
        assert!((7_380..=7_420).contains(&mv), "{mv}");
        seen.insert(mv);
    }
    assert!(seen.len() > 3, "the voltage has noise");
    // The user block's defaults: the profile's, and sensible ones elsewhere.
    let s = &bus.servos()[0];
    assert_eq!(s.param(33), Some(0));
    assert_eq!(s.param(36), Some(5));
    assert_eq!(s.param(44), Some(1));
    assert_eq!(s.param(37), Some(1));
    assert_eq!(s.params().len(), 22);
}

#[test]
fn batch_read_write_round_trip_and_reset() {
    let now = Instant::now();
    let mut bus = ServoBus::new(vec![SimServo::fresh(77)]);
    let block = one_reply(&ask(&mut bus, scmd::READ_BATCH_DATA, &[0], B, now)).content;
    assert_eq!(block.len(), 33);
    let profile = bus.profile().clone();
    let read_cmd = profile.command("READ_BATCH_DATA").expect("command");
    let decoded = profile
        .decode(read_cmd, Direction::DeviceToHost, &block)
        .expect("the block decodes by the profile");
    assert_eq!(decoded.int("baudrate"), Some(5));
    assert_eq!(decoded.int("accel_switch"), Some(1));

    // Change the stall power limit (block bytes 6-7 after the servo id) and the centre offset.
    let mut new = block.clone();
    new[7..9].copy_from_slice(&3210u16.to_le_bytes());
    new[31..33].copy_from_slice(&(-55i16).to_le_bytes());
    assert_eq!(
        one_reply(&ask(&mut bus, scmd::WRITE_BATCH_DATA, &new, B, now)).content,
        [0, 1]
    );
    let back = one_reply(&ask(&mut bus, scmd::READ_BATCH_DATA, &[0], B, now)).content;
    assert_eq!(back, new);
    assert_eq!(bus.servos()[0].param(38), Some(3210));
    assert_eq!(bus.servos()[0].param(53), Some(-55));

    // A block with id 255 or a bad option is refused whole.
    let mut bad = back.clone();
    bad[3] = 255;
    bad[8] = 0x7f;
    assert_eq!(
        one_reply(&ask(&mut bus, scmd::WRITE_BATCH_DATA, &bad, B, now)).content,
        [0, 0]
    );
    let mut short = back.clone();
    short.pop();
    assert_eq!(
        one_reply(&ask(&mut bus, scmd::WRITE_BATCH_DATA, &short, B, now)).content,
        [0, 0]
    );
    assert_eq!(
        one_reply(&ask(&mut bus, scmd::READ_BATCH_DATA, &[0], B, now)).content,
        back
    );

    // Reset restores the defaults, id included: answered from id 0.
    assert_eq!(write(&mut bus, 0, 34, &[12], now), [12, 34, 1]);
    assert_eq!(
        one_reply(&ask(&mut bus, scmd::RESET_USER_DATA, &[12], B, now)).content,
        [0, 1]
    );
    assert_eq!(
        one_reply(&ask(&mut bus, scmd::READ_BATCH_DATA, &[0], B, now)).content,
        block
    );
}

#[test]
fn extended_commands_and_old_servos() {
    let t0 = Instant::now();
    let mut bus = ServoBus::new(vec![
        SimServo::fresh(1).with_angle(-300),
        SimServo::fresh(2).with_id(2).with_extended(false),
    ]);
    let f = one_reply(&ask(&mut bus, ext::MONITOR, &[0], B, t0));
    let c = &f.content;
    assert_eq!(c.len(), 16);
    let voltage = u16::from_le_bytes([c[1], c[2]]);
    let current = u16::from_le_bytes([c[3], c[4]]);
    let power = u16::from_le_bytes([c[5], c[6]]);
    assert!((7_380..=7_420).contains(&voltage));
    assert_eq!(power as u32, voltage as u32 * current as u32 / 1000);
    assert_eq!(c[9], 0, "status");
    assert_eq!(c[10..14], (-300i32).to_le_bytes());
    assert_eq!(c[14..16], 0i16.to_le_bytes());
    // Old servo: silent on 11-24, fine on 1-10.
    for command in [11, 12, 13, 16, 17, 22, 23, 24] {
        assert!(ask(&mut bus, command, &[2, 0, 0, 0], B, t0).is_empty());
    }
    assert_eq!(read_angle(&mut bus, 2, t0), 0);

    // Multi-turn move to 720.0° over 1 s, then set origin and reset turns.
    let mut m = vec![0];
    m.extend(7200i32.to_le_bytes());
    m.extend(1000u32.to_le_bytes());
    m.extend(0u16.to_le_bytes());
    assert!(ask(&mut bus, ext::ROTATE_MTURN, &m, B, t0).is_empty());
    let f = one_reply(&ask(
        &mut bus,
        ext::READ_ANGLE_MTURN,
        &[0],
        B,
        t0 + ms(2000),
    ));
    assert_eq!(f.content[1..7], [0x20, 0x1c, 0, 0, 2, 0]);
    assert!(ask(&mut bus, ext::SET_ORIGIN, &[0, 0], B, t0 + ms(2000)).is_empty());
    assert_eq!(read_angle(&mut bus, 0, t0 + ms(2000)), 0);

    // By speed: 90° at 45 °/s takes 2 s (reply when done, with the switch on).
    assert_eq!(write(&mut bus, 0, 33, &[1], t0), [0, 33, 1]);
    let mut v = vec![0];
    v.extend(900i16.to_le_bytes());
    v.extend(450u16.to_le_bytes());
    v.extend([0, 0, 0, 0, 0, 0]);
    let t1 = t0 + ms(3000);
    let out = ask(&mut bus, ext::ROTATE_BY_VELOCITY, &v, B, t1);
    assert_eq!(out.len(), 1);
    assert_eq!(out[0].after, ms(2000) + servo_bus::DEFAULT_LATENCY);
    assert_eq!(read_angle(&mut bus, 0, t1 + ms(1000)), 450);
    // STOP (hold) is queued behind the move, then takes hold.
    assert!(ask(&mut bus, ext::STOP, &[0, 0x11, 0, 0], B, t1 + ms(1000)).is_empty());
    assert_eq!(bus.servos()[0].motion_at(t1 + ms(2500)), Motion::Hold);
    assert_eq!(read_angle(&mut bus, 0, t1 + ms(2500)), 900);
}

#[test]
fn a_servo_that_vanishes_stops_answering() {
    let now = Instant::now();
    let mut bus = ServoBus::with_ids(&[0, 1, 5], B);
    assert_eq!(bus.servos().len(), 3);
    assert_eq!(
        one_reply(&ask(&mut bus, scmd::PING, &[5], B, now)).content,
        [5]
    );
    let serial = bus.servos()[2].serial();
    let gone = bus.remove(serial).expect("it was there");
    assert!(ask(&mut bus, scmd::PING, &[5], B, now).is_empty());
    bus.add(gone);
    assert_eq!(
        one_reply(&ask(&mut bus, scmd::PING, &[5], B, now)).content,
        [5]
    );
    let bus = bus.with_latency(ms(1));
    assert_eq!(bus.latency(), ms(1));
}

#[test]
fn requests_split_across_receives_and_replies_ignored() {
    let now = Instant::now();
    let mut bus = ServoBus::new(vec![SimServo::fresh(1)]);
    let ping = req(scmd::PING, &[0]);
    assert!(bus.receive(&ping[..3], B, now).is_empty());
    assert_eq!(bus.receive(&ping[3..], B, now).len(), 1);
    // The adapter's echo of a reply is not a request.
    let reply = servo::Frame::reply(scmd::PING, vec![0])
        .encode()
        .expect("encodes");
    assert!(bus.receive(&reply, B, now).is_empty());
    // A corrupted request is ignored.
    let mut bad = ping.clone();
    bad[4] ^= 1;
    assert!(bus.receive(&bad, B, now).is_empty());
}
