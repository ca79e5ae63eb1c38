//! The vendor SDK's commands 14, 15, 18, 19 and 25 in the servo-bus simulator (issue 13): driven
//! directly through `Device::receive` with simulated time, and through a pty with the link and
//! the synchronous-MONITOR operation. Also: parameter 4 and MONITOR agree on the temperature,
//! whichever form (°C or a thermistor reading) the profile says the firmware sends.

use botbench::ops::Device as Dut;
use botbench::ops::servo as ops;
use botbench::ops::servo::monitor::{Reading, monitor_all, read_monitor};
use botbench::profile::registry::parse;
use botbench::profile::{Input, Value};
use botbench::protocol::Direction;
use botbench::protocol::servo::{self, ServoDecoder, cmd};
use botbench::sim::servo_bus::{ServoBus, SimServo, builtin_servo_profile};
use botbench::sim::{Device, Outgoing};
use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::support::ms;

use crate::support::cli::Sim;
use crate::support::servo::Bench;
use crate::support::wait_until;

const B: u32 = 115_200;

fn send(bus: &mut ServoBus, command: &str, fields: &[(&str, i64)], now: Instant) -> Vec<Outgoing> {
    let p = builtin_servo_profile();
    let c = p.command(command).unwrap();
    let inputs: Vec<(String, Input)> = fields
        .iter()
        .map(|(k, v)| (k.to_string(), Input::from(*v)))
        .collect();
    let payload = p.encode(c, Direction::HostToDevice, &inputs).unwrap();
    let bytes = servo::Frame::request(c.id, payload).encode().unwrap();
    bus.receive(&bytes, B, now)
}

fn frames(out: &[Outgoing]) -> Vec<(Duration, servo::Frame)> {
    let mut v = Vec::new();
    for o in out {
        let mut d = ServoDecoder::new();
        d.push(&o.bytes);
        for f in d.by_ref() {
            v.push((o.after, f.expect("a clean frame")));
        }
    }
    v
}

/// The multi-turn angle of servo `id` (command 16), 0.1°.
fn mturn(bus: &mut ServoBus, id: u8, now: Instant) -> i32 {
    let out = send(bus, "READ_ANGLE_MTURN", &[("servo_id", id.into())], now);
    let f = &frames(&out)[0].1;
    i32::from_le_bytes(f.content[1..5].try_into().unwrap())
}

fn bus3() -> ServoBus {
    ServoBus::with_ids(&[1, 2, 3], B)
}

#[test]
fn commands_14_and_15_move_over_several_turns() {
    let t0 = Instant::now();
    let mut bus = bus3();
    let by_interval = [
        ("servo_id", 1),
        ("angle", -10805),
        ("interval", 500),
        ("t_acc", 100),
        ("t_dec", 100),
    ];
    assert!(send(&mut bus, "ROTATE_MTURN_BY_INTERVAL", &by_interval, t0).is_empty());
    let half = mturn(&mut bus, 1, t0 + ms(250));
    assert!((-6000..-4000).contains(&half), "half way: {half}");
    assert_eq!(mturn(&mut bus, 1, t0 + ms(501)), -10805);
    // 15: 4000.0° at 750 °/s from -1080.5°: (4000 + 1080.5) / 750 = 6.77 s.
    let t1 = t0 + ms(1000);
    let by_speed = [("servo_id", 1), ("angle", 40000), ("speed", 7500)];
    assert!(send(&mut bus, "ROTATE_MTURN_BY_VELOCITY", &by_speed, t1).is_empty());
    assert!(mturn(&mut bus, 1, t1 + ms(3000)) < 40000);
    assert_eq!(mturn(&mut bus, 1, t1 + ms(6800)), 40000);
}

#[test]
fn begin_async_holds_motion_until_end_async_runs_or_drops_it() {
    let t0 = Instant::now();
    let mut bus = bus3();
    assert!(send(&mut bus, "BEGIN_ASYNC", &[], t0).is_empty());
    let go = [("servo_id", 2), ("angle", 300), ("interval", 0)];
    assert!(send(&mut bus, "ROTATE", &go, t0).is_empty());
    assert_eq!(mturn(&mut bus, 2, t0 + ms(100)), 0, "held, not run");
    assert!(send(&mut bus, "END_ASYNC", &[("cancel", 0)], t0 + ms(200)).is_empty());
    assert_eq!(mturn(&mut bus, 2, t0 + ms(300)), 300, "run at END_ASYNC");

    assert!(send(&mut bus, "BEGIN_ASYNC", &[], t0 + ms(400)).is_empty());
    let back = [("servo_id", 2), ("angle", -300), ("interval", 0)];
    assert!(send(&mut bus, "ROTATE", &back, t0 + ms(400)).is_empty());
    assert!(send(&mut bus, "END_ASYNC", &[("cancel", 1)], t0 + ms(500)).is_empty());
    assert_eq!(mturn(&mut bus, 2, t0 + ms(600)), 300, "dropped by cancel");
    // After END_ASYNC, commands run at once again.
    assert!(send(&mut bus, "ROTATE", &back, t0 + ms(700)).is_empty());
    assert_eq!(mturn(&mut bus, 2, t0 + ms(800)), -300);
}

#[test]
fn a_synchronous_angle_moves_every_servo_it_names() {
    let t0 = Instant::now();
    let mut bus = bus3();
    let fields = [
        ("sub_command", i64::from(cmd::ROTATE_MTURN_BY_INTERVAL)),
        ("servo_id[0]", 1),
        ("angle[0]", 4000),
        ("interval[0]", 200),
        ("servo_id[1]", 3),
        ("angle[1]", -8000),
        ("interval[1]", 400),
    ];
    assert!(send(&mut bus, "SYNC_COMMAND", &fields, t0).is_empty());
    assert_eq!(mturn(&mut bus, 1, t0 + ms(500)), 4000);
    assert_eq!(mturn(&mut bus, 2, t0 + ms(500)), 0, "not named");
    assert_eq!(mturn(&mut bus, 3, t0 + ms(500)), -8000);
}

#[test]
fn a_synchronous_monitor_is_answered_by_each_servo_in_the_order_asked() {
    let t0 = Instant::now();
    let mut bus = ServoBus::new(vec![
        SimServo::fresh(1).with_id(1).with_angle(100),
        SimServo::fresh(2).with_id(2).with_angle(200),
        SimServo::fresh(3).with_id(3).with_angle(300),
        // An old servo does not know command 25.
        SimServo::fresh(4).with_id(4).with_extended(false),
    ]);
    let fields = [
        ("sub_command", i64::from(cmd::MONITOR)),
        ("servo_id[0]", 3),
        ("servo_id[1]", 9),
        ("servo_id[2]", 1),
        ("servo_id[3]", 4),
        ("servo_id[4]", 2),
    ];
    let got = frames(&send(&mut bus, "SYNC_COMMAND", &fields, t0));
    let order: Vec<u8> = got.iter().map(|(_, f)| f.content[0]).collect();
    assert_eq!(order, [3, 1, 2], "absent 9 and old 4 stay silent");
    let p = builtin_servo_profile();
    for (i, (after, f)) in got.iter().enumerate() {
        assert_eq!(f.command, cmd::MONITOR, "each servo's own MONITOR reply");
        let m = read_monitor(&p, &f.content).unwrap();
        assert_eq!(m.angle_deg, f64::from(f.content[0]) * 10.0);
        if i > 0 {
            // Each answer starts after the one before has ended (21 bytes at 115200 baud).
            assert!(*after >= got[i - 1].0 + ms(1), "{after:?}");
        }
    }
}

/// The servo profile with parameter 4 and MONITOR's temperature in °C (the seed's reading).
fn celsius_profile() -> Arc<botbench::profile::Profile> {
    let src = crate::support::builtin_src("servo");
    let edited = src.replace(", convert: Some(Ntc(beta: 3435.0, full_scale: 4096))", "");
    assert_eq!(src.matches("convert: Some(Ntc").count(), 2, "test setup");
    Arc::new(parse("servo-celsius.ron", &edited, None).unwrap())
}

#[test]
fn parameter_4_and_monitor_agree_on_the_temperature_in_either_form() {
    for (profile, raw) in [(builtin_servo_profile(), 1779), (celsius_profile(), 32)] {
        let t0 = Instant::now();
        let servo = SimServo::fresh(1).with_id(1).with_temperature(32);
        let mut bus = ServoBus::with_profile(profile.clone(), vec![servo]);
        let read = profile.command("READ_DATA").unwrap();
        let bytes = servo::Frame::request(read.id, vec![1, 4]).encode().unwrap();
        let param4 = frames(&bus.receive(&bytes, B, t0))[0].1.clone();
        let d = profile
            .decode(read, Direction::DeviceToHost, &param4.content)
            .unwrap();
        assert_eq!(d.int("temprature"), Some(raw), "parameter 4's raw value");
        let t4 = d.values[2].field.display_number(raw).unwrap();
        let out = send(&mut bus, "MONITOR", &[("servo_id", 1)], t0);
        let m = read_monitor(&profile, &frames(&out)[0].1.content).unwrap();
        assert_eq!(m.temperature_raw, raw);
        let t22 = m.temperature_c.unwrap();
        assert!(
            (t4 - 32.0).abs() < 0.1 && (t22 - 32.0).abs() < 0.1,
            "{t4} {t22}"
        );
        assert_eq!(
            d.values[2].display(),
            if raw == 32 {
                "32 °C".to_string()
            } else {
                format!("32.0 °C (raw {raw})")
            }
        );
    }
}

#[test]
fn through_a_pty_one_exchange_reads_every_servo_and_the_temperatures_agree() {
    let bench = Bench::new(vec![
        SimServo::fresh(11).with_id(1).with_temperature(40),
        SimServo::fresh(12).with_id(2).with_temperature(55),
        SimServo::fresh(13).with_id(5).with_temperature(61),
    ]);
    let client = bench.client();
    let p = &bench.profile;
    let rows = monitor_all(Dut::new(&client, p), &[1, 2, 3, 5]).unwrap();
    let ids: Vec<(u8, bool)> = rows
        .iter()
        .map(|r| (r.id, matches!(r.reading, Reading::Values(_))))
        .collect();
    assert_eq!(ids, [(1, true), (2, true), (3, false), (5, true)]);
    for (row, celsius) in rows
        .iter()
        .filter(|r| r.reading != Reading::NoAnswer)
        .zip([40.0, 55.0, 61.0])
    {
        let Reading::Values(m) = &row.reading else {
            panic!("{row:?}")
        };
        let t22 = m.temperature_c.unwrap();
        let raw4 = ops::read_param(Dut::new(&client, p), row.id, p.param(4).unwrap()).unwrap();
        let t4 = p.param(4).unwrap().field.display_number(raw4).unwrap();
        assert!((t22 - celsius).abs() < 0.1, "MONITOR {t22} °C");
        assert!(
            (t4 - t22).abs() < 0.1,
            "parameter 4 {t4} °C, MONITOR {t22} °C"
        );
        assert_eq!(m.temperature_raw, raw4, "the same reading in both");
    }
    // A synchronous angle through the link: no answer awaited, every servo moves.
    let sync = p.command("SYNC_COMMAND").unwrap();
    let inputs: Vec<(String, Input)> = [
        ("sub_command", Value::Int(i64::from(cmd::ROTATE))),
        ("servo_id[0]", Value::Int(1)),
        ("angle[0]", Value::Int(450)),
        ("interval[0]", Value::Int(0)),
        ("servo_id[1]", Value::Int(2)),
        ("angle[1]", Value::Int(-450)),
        ("interval[1]", Value::Int(0)),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), Input::Raw(v)))
    .collect();
    let reply = botbench::ops::exchange::send(Dut::new(&client, p), sync, &inputs).unwrap();
    assert!(reply.packets.is_empty());
    for (id, want) in [(1u8, 450), (2, -450)] {
        wait_until(&format!("servo {id} at {want}"), || {
            ops::read_angle(Dut::new(&client, p), id).unwrap() == want
        });
    }
    // The servo it did not name stays where it was.
    let bus = bench.bus();
    assert_eq!(
        bus.servo_by_serial(13).unwrap().angle_at(Instant::now()),
        0.0
    );
}

#[test]
fn servo_monitor_on_the_command_line_reads_every_servo_in_one_exchange() {
    let sim = Sim::start(&["servo-bus", "--servos", "1,2,3"]);
    let monitor = |ids: &str, json: bool| {
        let mut args = vec!["servo", "--port", &sim.path, "monitor", ids];
        if json {
            args.push("--json");
        }
        sim.run(&args)
    };
    let text = monitor("1-3", false);
    let json = monitor("2,7", true);
    drop(sim);
    let out = &text.out;
    assert_eq!(text.code, 0, "{out}");
    assert_eq!(out.matches("32.0 (1779)").count(), 3, "{out}");
    assert_eq!(json.code, 1, "servo 7 does not answer");
    let doc: serde_json::Value = serde_json::from_str(&json.out).unwrap();
    assert_eq!(doc["servos"][0]["id"], 2);
    assert_eq!(doc["servos"][0]["answer"], "values");
    assert_eq!(doc["servos"][0]["temperature_raw"], 1779);
    assert_eq!(doc["servos"][1]["answer"], "no_answer");
}

#[test]
fn a_monitor_answer_without_data_is_shown_as_no_data_not_as_an_angle() {
    // The "no data" form: angle -235929599 (0.1°), turns 0; the vendor SDK skips it.
    let sim = Sim::start(&["servo-bus", "--servos", "1,2", "--monitor-no-data"]);
    let text = sim.run(&["servo", "--port", &sim.path, "monitor", "1,2"]);
    let json = sim.run(&["servo", "--port", &sim.path, "monitor", "1", "--json"]);
    drop(sim);
    let out = &text.out;
    assert!(!out.contains("-23592959"), "{out}");
    assert_eq!(out.matches("no data").count(), 2, "{out}");
    assert_eq!(text.code, 1, "no values is not a full reading: {out}");
    let doc: serde_json::Value = serde_json::from_str(&json.out).unwrap();
    assert_eq!(doc["servos"][0]["answer"], "no_data", "{}", json.out);
    assert!(doc["servos"][0].get("angle_deg").is_none(), "{}", json.out);
}

#[test]
fn a_json_command_that_fails_prints_a_json_document_too() {
    let sim = Sim::start(&["servo-bus", "--servos", "1"]);
    // The device fails: nobody answers at id 9. Bad input: id 300 is not an id.
    let device = sim.run(&["servo", "--port", &sim.path, "read", "9", "--json"]);
    let input = sim.run(&["servo", "--port", &sim.path, "read", "300", "--json"]);
    drop(sim);
    for (ran, code) in [(&device, 1), (&input, 2)] {
        assert_eq!(ran.code, code, "{}", ran.text());
        let doc: serde_json::Value = serde_json::from_str(ran.out.trim())
            .unwrap_or_else(|e| panic!("stdout is one JSON document ({e}): {}", ran.text()));
        assert_eq!(doc["exit"], code, "{}", ran.out);
        let error = doc["error"].as_str().unwrap_or_default();
        assert!(!error.is_empty(), "{}", ran.out);
        assert!(
            ran.err.contains(error.lines().next().unwrap_or("-")),
            "{}",
            ran.text()
        );
    }
}
