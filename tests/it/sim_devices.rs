//! The servo bus and Tuya MCU simulators, driven directly through `Device::receive` and `tick`.
//!
//! Seed examples are written out byte for byte; other requests are built with the protocol
//! encoders, and answers are read back with the protocol decoders.

use std::sync::Arc;
use std::time::{Duration, Instant};

use botbench::profile::Access;
use botbench::protocol::servo::{self, ServoDecoder, cmd as scmd};
use botbench::protocol::tuya::dp::{self, DataPoint, DpValue};
use botbench::protocol::tuya::{self, TuyaDecoder, cmd as tcmd};
use botbench::protocol::{Direction, FrameError};
use botbench::sim::servo_bus::{self, Motion, ServoBus, SimServo, ext, param};
use botbench::sim::tuya_mcu::{
    self, OtaPacketAnswer, OtaState, TuyaConfig, TuyaMcu, builtin_vacuum_profile, dpid,
};
use botbench::sim::{Device, Outgoing};

use crate::support::{image, ms};

const B: u32 = 115_200;

// ---------------------------------------------------------------- servo helpers

fn req(command: u8, content: &[u8]) -> Vec<u8> {
    servo::Frame::request(command, content.to_vec())
        .encode()
        .expect("a request encodes")
}

fn servo_items(bytes: &[u8]) -> Vec<Result<servo::Frame, FrameError>> {
    let mut d = ServoDecoder::new();
    d.push(bytes);
    let mut items: Vec<_> = d.by_ref().collect();
    items.extend(d.finish().map(Err));
    items
}

/// The one clean reply in `out`, at the request's baud.
fn one_reply(out: &[Outgoing]) -> servo::Frame {
    assert_eq!(out.len(), 1, "one frame expected: {out:02x?}");
    assert_eq!(out[0].baud, None);
    let items = servo_items(&out[0].bytes);
    match items.as_slice() {
        [Ok(f)] => {
            assert_eq!(f.direction, Direction::DeviceToHost);
            f.clone()
        }
        other => panic!("one clean frame expected, got {other:?}"),
    }
}

fn ask(bus: &mut ServoBus, command: u8, content: &[u8], baud: u32, now: Instant) -> Vec<Outgoing> {
    bus.receive(&req(command, content), baud, now)
}

fn read_angle(bus: &mut ServoBus, id: u8, now: Instant) -> i16 {
    let f = one_reply(&ask(bus, scmd::READ_ANGLE, &[id], B, now));
    assert_eq!(f.content[0], id);
    i16::from_le_bytes([f.content[1], f.content[2]])
}

fn write(bus: &mut ServoBus, id: u8, data_id: u8, data: &[u8], now: Instant) -> Vec<u8> {
    let mut c = vec![id, data_id];
    c.extend_from_slice(data);
    one_reply(&ask(bus, scmd::WRITE_DATA, &c, B, now)).content
}

fn angle_of(bus: &ServoBus, serial: u32, now: Instant) -> f64 {
    bus.servo_by_serial(serial).expect("servo").angle_at(now)
}

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
    assert_eq!(write(&mut bus, 0, param::SERVO_ID, &[7], now), [7, 34, 1]);
    assert!(ask(&mut bus, scmd::PING, &[0], B, now).is_empty());
    assert_eq!(
        one_reply(&ask(&mut bus, scmd::PING, &[7], B, now)).content,
        [7]
    );
    assert_eq!(bus.servo_by_serial(42).expect("servo").id(), 7);
    // 255 cannot be assigned.
    assert_eq!(write(&mut bus, 7, param::SERVO_ID, &[255], now), [7, 34, 0]);
    assert_eq!(bus.servo_by_serial(42).expect("servo").id(), 7);
}

#[test]
fn baud_change_is_answered_at_the_new_baud() {
    let now = Instant::now();
    let mut bus = ServoBus::new(vec![SimServo::fresh(42)]);
    let out = ask(&mut bus, scmd::WRITE_DATA, &[0, param::BAUDRATE, 1], B, now);
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

// ---------------------------------------------------------------- Tuya helpers

fn module(command: u8, data: &[u8]) -> Vec<u8> {
    tuya::Frame::from_module(command, data.to_vec())
        .encode()
        .expect("encodes")
}

fn tuya_frames(out: &[Outgoing]) -> Vec<tuya::Frame> {
    out.iter()
        .map(|o| {
            let mut d = TuyaDecoder::new();
            d.push(&o.bytes);
            let items: Vec<_> = d.by_ref().collect();
            match items.as_slice() {
                [Ok(f)] => {
                    assert_eq!(f.version, tuya::VERSION_MCU);
                    f.clone()
                }
                other => panic!("one clean frame per Outgoing: {other:?}"),
            }
        })
        .collect()
}

fn dp_frame(points: &[DataPoint]) -> Vec<u8> {
    module(tcmd::DP_COMMAND, &dp::encode(points).expect("encodes"))
}

fn reports(out: &[Outgoing]) -> Vec<DataPoint> {
    tuya_frames(out)
        .into_iter()
        .flat_map(|f| {
            assert_eq!(f.command, tcmd::DP_REPORT);
            let dps = dp::decode(&f.data).expect("a DP list");
            assert_eq!(dps.len(), 1, "one DP per report");
            dps
        })
        .collect()
}

fn point(id: u8, value: DpValue) -> DataPoint {
    DataPoint { id, value }
}

// ---------------------------------------------------------------- Tuya

#[test]
fn seed_heartbeat_and_restart() {
    let now = Instant::now();
    let mut mcu = TuyaMcu::default();
    let hb = [0x55, 0xaa, 0x00, 0x00, 0x00, 0x00, 0xff];
    let first = mcu.receive(&hb, 9600, now);
    assert_eq!(
        first,
        vec![Outgoing::new(
            tuya_mcu::DEFAULT_LATENCY,
            vec![0x55, 0xaa, 0x03, 0x00, 0x00, 0x01, 0x00, 0x03]
        )]
    );
    for _ in 0..3 {
        let later = mcu.receive(&hb, 9600, now);
        assert_eq!(
            later[0].bytes,
            [0x55, 0xaa, 0x03, 0x00, 0x00, 0x01, 0x01, 0x04]
        );
    }
    mcu.restart();
    assert_eq!(mcu.receive(&hb, 9600, now)[0].bytes[6], 0x00);
    assert_eq!(mcu.receive(&hb, 9600, now)[0].bytes[6], 0x01);
}

#[test]
fn seed_product_info() {
    let now = Instant::now();
    let mut mcu = TuyaMcu::new(TuyaConfig {
        pid: "RN2FVAgXG6WfAktU".into(),
        ..TuyaConfig::default()
    });
    let out = mcu.receive(&[0x55, 0xaa, 0x00, 0x01, 0x00, 0x00, 0x00], 9600, now);
    let expected: [u8; 49] = [
        0x55, 0xaa, 0x03, 0x01, 0x00, 0x2a, 0x7b, 0x22, 0x70, 0x22, 0x3a, 0x22, 0x52, 0x4e, 0x32,
        0x46, 0x56, 0x41, 0x67, 0x58, 0x47, 0x36, 0x57, 0x66, 0x41, 0x6b, 0x74, 0x55, 0x22, 0x2c,
        0x22, 0x76, 0x22, 0x3a, 0x22, 0x31, 0x2e, 0x30, 0x2e, 0x30, 0x22, 0x2c, 0x22, 0x6d, 0x22,
        0x3a, 0x30, 0x7d, 0x0c,
    ];
    assert_eq!(out.len(), 1);
    assert_eq!(out[0].bytes, expected);

    // The default product, and a malformed answer on request.
    let mut mcu = TuyaMcu::default();
    let f = &tuya_frames(&mcu.receive(&module(tcmd::PRODUCT_INFO, &[]), 9600, now))[0];
    let json: serde_json::Value = serde_json::from_slice(&f.data).expect("JSON");
    assert_eq!(json["p"], "lgldgnmt4ifc.jzex");
    assert_eq!(json["v"], "1.0.0");
    assert_eq!(json["m"], 0);
    mcu.config_mut().product_info_raw = Some(tuya_mcu::MALFORMED_PRODUCT_INFO.to_vec());
    let f = &tuya_frames(&mcu.receive(&module(tcmd::PRODUCT_INFO, &[]), 9600, now))[0];
    assert!(serde_json::from_slice::<serde_json::Value>(&f.data).is_err());
}

#[test]
fn working_mode_and_wifi_state() {
    let now = Instant::now();
    let mut mcu = TuyaMcu::default();
    let f = tuya_frames(&mcu.receive(&module(tcmd::WORK_MODE, &[]), 9600, now));
    assert_eq!(
        (f[0].command, f[0].data.as_slice()),
        (tcmd::WORK_MODE, &[][..])
    );
    mcu.config_mut().work_mode = Some([14, 0]);
    let f = tuya_frames(&mcu.receive(&module(tcmd::WORK_MODE, &[]), 9600, now));
    assert_eq!(f[0].data, [14, 0]);

    let f = tuya_frames(&mcu.receive(&module(tcmd::WIFI_STATE, &[4]), 9600, now));
    assert_eq!((f[0].command, f[0].data.len()), (tcmd::WIFI_STATE, 0));
    assert_eq!(mcu.wifi_state(), Some(4));
}

#[test]
fn frames_of_another_version_are_dropped() {
    let now = Instant::now();
    let mut mcu = TuyaMcu::default();
    let from_mcu = |c: u8, d: &[u8]| tuya::Frame::from_mcu(c, d.to_vec()).encode().expect("ok");
    assert!(
        mcu.receive(&from_mcu(tcmd::HEARTBEAT, &[]), 9600, now)
            .is_empty()
    );
    assert!(
        mcu.receive(&from_mcu(tcmd::QUERY_STATUS, &[]), 9600, now)
            .is_empty()
    );
    assert!(
        mcu.receive(&from_mcu(tcmd::DP_COMMAND, &[1, 1, 0, 1, 0]), 9600, now)
            .is_empty()
    );
    assert_eq!(mcu.dp(dpid::POWER), Some(&DpValue::Bool(true)));
    // The dropped heartbeat did not count: the first real one still answers 00.
    assert_eq!(mcu.receive(&module(0, &[]), 9600, now)[0].bytes[6], 0);
}

#[test]
fn the_mcu_hears_only_its_own_baud() {
    let now = Instant::now();
    let mut mcu = TuyaMcu::default();
    assert!(mcu.receive(&module(0, &[]), 115_200, now).is_empty());
    assert_eq!(mcu.receive(&module(0, &[]), 9600, now).len(), 1);
    let mut any = TuyaMcu::new(TuyaConfig {
        baud: None,
        ..TuyaConfig::default()
    });
    assert_eq!(any.receive(&module(0, &[]), 115_200, now).len(), 1);
}

#[test]
fn query_gives_19_reports() {
    let now = Instant::now();
    let mut mcu = TuyaMcu::default();
    let got = reports(&mcu.receive(&module(tcmd::QUERY_STATUS, &[]), 9600, now));
    assert_eq!(got.len(), 19);
    let ids: Vec<u8> = got.iter().map(|p| p.id).collect();
    assert_eq!(ids, (1..=19).collect::<Vec<u8>>());
    let profile = builtin_vacuum_profile();
    for p in &got {
        let def = profile.data_point(p.id).expect("a profile DP");
        assert_eq!(p.value.dp_type(), def.dp_type, "dp {}", p.id);
    }
    assert_eq!(got[5].value, DpValue::Value(80));
    assert_eq!(got[6].value, DpValue::Value(90));
    assert_eq!(got[7].value, DpValue::Value(85));
    assert_eq!(got[8].value, DpValue::Value(70));
    assert_eq!(got[4].value, DpValue::Enum(0));
    assert_eq!(got[17].value, DpValue::Bitmap { bits: 0, width: 1 });
    assert_eq!(got[18].value, DpValue::Raw(vec![0, 0, 0xff]));
}

#[test]
fn dp_commands_are_applied_and_reported() {
    let now = Instant::now();
    let mut mcu = TuyaMcu::default();
    // Bool: power off; standby follows.
    mcu.receive(&dp_frame(&[point(2, DpValue::Bool(true))]), 9600, now);
    assert_eq!(mcu.dp(dpid::STATUS), Some(&DpValue::Enum(1)));
    let got = reports(&mcu.receive(&dp_frame(&[point(1, DpValue::Bool(false))]), 9600, now));
    assert_eq!(got[0], point(1, DpValue::Bool(false)));
    assert!(got.contains(&point(5, DpValue::Enum(0))));
    assert!(got.contains(&point(2, DpValue::Bool(false))));
    // Enum: wall-follow mode → edge cleaning.
    let got = reports(&mcu.receive(&dp_frame(&[point(3, DpValue::Enum(3))]), 9600, now));
    assert_eq!(got[0], point(3, DpValue::Enum(3)));
    assert!(got.contains(&point(5, DpValue::Enum(2))));
    // A consumable reset: life back to 100.
    let got = reports(&mcu.receive(&dp_frame(&[point(12, DpValue::Bool(true))]), 9600, now));
    assert_eq!(
        got,
        [
            point(12, DpValue::Bool(true)),
            point(9, DpValue::Value(100))
        ]
    );
    // Several DPs in one frame: each its own report.
    let got = reports(&mcu.receive(
        &dp_frame(&[point(14, DpValue::Enum(0)), point(13, DpValue::Bool(true))]),
        9600,
        now,
    ));
    assert_eq!(
        got,
        [point(14, DpValue::Enum(0)), point(13, DpValue::Bool(true))]
    );
}

#[test]
fn every_dp_type_is_reported_back_when_writable() {
    // The vacuum's value, string, bitmap and raw DPs are report-only; make them writable.
    let mut profile = (*builtin_vacuum_profile()).clone();
    for d in &mut profile.data_points {
        d.access = Access::ReadWrite;
    }
    let now = Instant::now();
    let mut mcu = TuyaMcu::with_profile(Arc::new(profile), TuyaConfig::default());
    for p in [
        point(1, DpValue::Bool(false)),
        point(3, DpValue::Enum(11)),
        point(16, DpValue::Value(9999)),
        point(15, DpValue::String("20240501120003012000007".into())),
        point(
            18,
            DpValue::Bitmap {
                bits: 0x45,
                width: 1,
            },
        ),
        point(19, DpValue::Raw(vec![1, 0x80, 0x40])),
    ] {
        let got = reports(&mcu.receive(&dp_frame(std::slice::from_ref(&p)), 9600, now));
        assert_eq!(got.first(), Some(&p));
        assert_eq!(mcu.dp(p.id), Some(&p.value));
    }
    // Still range-checked.
    assert!(
        mcu.receive(&dp_frame(&[point(16, DpValue::Value(10_000))]), 9600, now)
            .is_empty()
    );
}

#[test]
fn bad_dps_get_no_answer() {
    let now = Instant::now();
    let mut mcu = TuyaMcu::default();
    let before = mcu.dps().clone();
    for points in [
        vec![point(1, DpValue::Enum(0))],     // power as an enum
        vec![point(3, DpValue::Bool(true))],  // mode as a bool
        vec![point(3, DpValue::Value(2))],    // mode as a value
        vec![point(3, DpValue::Enum(12))],    // no such mode
        vec![point(6, DpValue::Value(50))],   // battery: report only
        vec![point(5, DpValue::Enum(1))],     // status: report only
        vec![point(99, DpValue::Bool(true))], // unknown dpid
        vec![point(14, DpValue::String("x".into()))],
    ] {
        let out = mcu.receive(&dp_frame(&points), 9600, now);
        assert!(out.is_empty(), "{points:?} answered: {out:02x?}");
    }
    // A bool of the wrong length, a truncated list.
    assert!(
        mcu.receive(&module(tcmd::DP_COMMAND, &[1, 1, 0, 2, 0, 0]), 9600, now)
            .is_empty()
    );
    assert!(
        mcu.receive(&module(tcmd::DP_COMMAND, &[1, 1, 0, 1]), 9600, now)
            .is_empty()
    );
    assert_eq!(mcu.dps(), &before);
    // A good DP next to a bad one: only the good one is answered.
    let got = reports(&mcu.receive(
        &dp_frame(&[point(1, DpValue::Enum(0)), point(13, DpValue::Bool(true))]),
        9600,
        now,
    ));
    assert_eq!(got, [point(13, DpValue::Bool(true))]);
}

#[test]
fn battery_drains_while_cleaning_and_is_reported() {
    let t0 = Instant::now();
    let mut mcu = TuyaMcu::new(TuyaConfig {
        battery_drain_every: Duration::from_secs(1),
        seed: 7,
        ..TuyaConfig::default()
    });
    assert!(
        mcu.tick(t0 + ms(5_000)).is_empty(),
        "not cleaning: no drain"
    );
    mcu.receive(&dp_frame(&[point(2, DpValue::Bool(true))]), 9600, t0);
    let mut seen = Vec::new();
    for s in 1..=60 {
        for p in reports(&mcu.tick(t0 + ms(s * 1000))) {
            assert_eq!(p.id, dpid::BATTERY);
            seen.push(p.value);
        }
    }
    assert!(seen.len() >= 40, "{} reports", seen.len());
    assert_eq!(seen.last(), mcu.dp(dpid::BATTERY));
    assert!(matches!(mcu.dp(dpid::BATTERY), Some(DpValue::Value(v)) if *v < 40));
    // Stop cleaning: no more.
    mcu.receive(
        &dp_frame(&[point(2, DpValue::Bool(false))]),
        9600,
        t0 + ms(60_000),
    );
    assert!(mcu.tick(t0 + ms(120_000)).is_empty());
    // A change the robot makes itself is reported from the next tick.
    assert!(mcu.set_dp(
        dpid::FAULT,
        DpValue::Bitmap {
            bits: 0x04,
            width: 1
        }
    ));
    assert_eq!(
        reports(&mcu.tick(t0 + ms(120_001))),
        [point(
            18,
            DpValue::Bitmap {
                bits: 0x04,
                width: 1
            }
        )]
    );
}

#[test]
fn mcu_requests_are_sent_and_answers_recorded() {
    let now = Instant::now();
    let mut mcu = TuyaMcu::default();
    assert!(mcu.tick(now).is_empty());
    mcu.request_local_time();
    mcu.request_wifi_test();
    mcu.reset_wifi();
    mcu.reset_wifi_mode(1);
    mcu.request_net_status();
    mcu.request_mac();
    let sent = tuya_frames(&mcu.tick(now));
    let cmds: Vec<(u8, Vec<u8>)> = sent.into_iter().map(|f| (f.command, f.data)).collect();
    assert_eq!(
        cmds,
        [
            (0x1c, vec![]),
            (0x0e, vec![]),
            (0x04, vec![]),
            (0x05, vec![1]),
            (0x2b, vec![]),
            (0x2d, vec![]),
        ]
    );
    assert!(mcu.tick(now).is_empty(), "each sent once");
    let time = [1, 24, 5, 1, 12, 30, 0, 3];
    assert!(mcu.receive(&module(0x1c, &time), 9600, now).is_empty());
    assert!(mcu.receive(&module(0x0e, &[1, 80]), 9600, now).is_empty());
    assert!(mcu.receive(&module(0x04, &[]), 9600, now).is_empty());
    assert_eq!(
        mcu.answers(),
        [(0x1c, time.to_vec()), (0x0e, vec![1, 80]), (0x04, vec![])]
    );
    assert_eq!(mcu.take_answers().len(), 3);
    assert!(mcu.answers().is_empty());
}

// ---------------------------------------------------------------- OTA

fn ota_packet(offset: u32, data: &[u8]) -> Vec<u8> {
    let mut d = offset.to_be_bytes().to_vec();
    d.extend_from_slice(data);
    module(tcmd::OTA_PACKET, &d)
}

fn is_ack(out: &[Outgoing]) -> bool {
    matches!(tuya_frames(out).as_slice(), [f] if f.command == tcmd::OTA_PACKET && f.data.is_empty())
}

#[test]
fn ota_of_64_kib_at_every_packet_size() {
    let img = image(64 * 1024 + 7);
    for (answer, data, size) in [
        (OtaPacketAnswer::Option(0), vec![0], 256),
        (OtaPacketAnswer::Option(1), vec![1], 512),
        (OtaPacketAnswer::Option(2), vec![2], 1024),
        (OtaPacketAnswer::Empty, vec![], 256),
    ] {
        let now = Instant::now();
        let mut mcu = TuyaMcu::new(TuyaConfig {
            ota_packet: answer,
            ..TuyaConfig::default()
        });
        let start = module(tcmd::OTA_START, &(img.len() as u32).to_be_bytes());
        let f = tuya_frames(&mcu.receive(&start, 9600, now));
        assert_eq!((f[0].command, &f[0].data), (tcmd::OTA_START, &data));
        for (i, chunk) in img.chunks(size).enumerate() {
            let out = mcu.receive(&ota_packet((i * size) as u32, chunk), 9600, now);
            assert!(is_ack(&out), "packet {i} at size {size}");
        }
        assert!(matches!(mcu.ota_state(), OtaState::Receiving { .. }));
        assert!(is_ack(&mcu.receive(
            &ota_packet(img.len() as u32, &[]),
            9600,
            now
        )));
        assert_eq!(
            mcu.ota_state(),
            &OtaState::Complete {
                size: img.len() as u32,
                crc32: tuya_mcu::crc32(&img)
            }
        );
        assert_eq!(mcu.ota_image(), img.as_slice());
    }
    assert_eq!(tuya_mcu::crc32(b"123456789"), 0xCBF4_3926);
}

#[test]
fn ota_faults() {
    let now = Instant::now();
    let img = image(4096);
    let start = module(tcmd::OTA_START, &4096u32.to_be_bytes());

    // stop_acking_at: acks stop at the first packet at or past the offset, for good.
    let mut mcu = TuyaMcu::new(TuyaConfig {
        stop_acking_at: Some(1024),
        ..TuyaConfig::default()
    });
    mcu.receive(&start, 9600, now);
    let acks: Vec<bool> = img
        .chunks(256)
        .enumerate()
        .map(|(i, c)| is_ack(&mcu.receive(&ota_packet(i as u32 * 256, c), 9600, now)))
        .collect();
    assert_eq!(acks.iter().filter(|a| **a).count(), 4);
    assert!(acks[..4].iter().all(|a| *a));
    assert!(
        mcu.receive(&ota_packet(0, &img[..256]), 9600, now)
            .is_empty()
    );

    // A packet larger than agreed: silent abort; later packets are ignored.
    let mut mcu = TuyaMcu::default();
    mcu.receive(&start, 9600, now);
    assert!(is_ack(&mcu.receive(&ota_packet(0, &img[..256]), 9600, now)));
    assert!(
        mcu.receive(&ota_packet(256, &img[256..768]), 9600, now)
            .is_empty()
    );
    assert!(matches!(mcu.ota_state(), OtaState::Aborted { .. }));
    assert!(
        mcu.receive(&ota_packet(256, &img[256..512]), 9600, now)
            .is_empty()
    );

    // A gap in the offsets aborts; a resent last packet is acked again without being stored twice.
    let mut mcu = TuyaMcu::default();
    mcu.receive(&start, 9600, now);
    assert!(is_ack(&mcu.receive(&ota_packet(0, &img[..256]), 9600, now)));
    assert!(is_ack(&mcu.receive(&ota_packet(0, &img[..256]), 9600, now)));
    assert_eq!(mcu.ota_image().len(), 256);
    assert!(
        mcu.receive(&ota_packet(512, &img[512..768]), 9600, now)
            .is_empty()
    );
    assert!(matches!(mcu.ota_state(), OtaState::Aborted { .. }));

    // Ending early is no success.
    let mut mcu = TuyaMcu::default();
    mcu.receive(&start, 9600, now);
    mcu.receive(&ota_packet(0, &img[..256]), 9600, now);
    assert!(mcu.receive(&ota_packet(4096, &[]), 9600, now).is_empty());
    assert!(matches!(mcu.ota_state(), OtaState::Aborted { .. }));

    // Packets with no update started are ignored.
    let mut mcu = TuyaMcu::default();
    assert!(
        mcu.receive(&ota_packet(0, &img[..256]), 9600, now)
            .is_empty()
    );
    assert_eq!(mcu.ota_state(), &OtaState::Idle);
}

// ---------------------------------------------------------------- robustness

#[test]
fn random_bytes_never_panic() {
    let mut rng = fastrand::Rng::with_seed(0xB0B);
    let t0 = Instant::now();
    let mut bus = ServoBus::new(vec![
        SimServo::fresh(1),
        SimServo::fresh(2),
        SimServo::fresh(3).with_id(3).with_param(33, 1),
        SimServo::fresh(4).with_id(3).with_extended(false),
    ]);
    let mut mcu = TuyaMcu::default();
    let bauds = [9_600, 115_200, 1_000_000];
    for i in 0..20_000u64 {
        let now = t0 + Duration::from_micros(i * 137);
        let len = rng.usize(0..40);
        let mut bytes: Vec<u8> = (0..len).map(|_| rng.u8(..)).collect();
        // Often a valid header and a plausible command, so the handlers see odd contents.
        match rng.u8(0..4) {
            0 => {
                let command = rng.u8(0..30);
                let mut content: Vec<u8> = (0..rng.usize(0..14)).map(|_| rng.u8(..)).collect();
                if !content.is_empty() && rng.bool() {
                    content[0] = rng.u8(0..5);
                }
                bytes = req(command, &content);
            }
            1 => {
                let command = rng.u8(0..0x30);
                bytes = module(command, &bytes);
            }
            _ => {}
        }
        let baud = bauds[rng.usize(0..bauds.len())];
        let _ = bus.receive(&bytes, baud, now);
        let _ = bus.tick(now);
        let _ = mcu.receive(&bytes, 9600, now);
        let _ = mcu.tick(now);
    }
    // The devices still work afterwards (a reboot empties the MCU's half-received frame).
    mcu.restart();
    let mut bus = ServoBus::new(vec![SimServo::fresh(9)]);
    assert_eq!(
        one_reply(&ask(&mut bus, scmd::PING, &[0], B, t0)).content,
        [0]
    );
    let out = mcu.receive(&[0x55, 0xaa, 0x00, 0x00, 0x00, 0x00, 0xff], 9600, t0);
    assert_eq!(tuya_frames(&out)[0].command, tcmd::HEARTBEAT);
}
