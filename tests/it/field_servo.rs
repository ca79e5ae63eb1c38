//! Servo buses as they behave in the field (issue 11, PROTOCOL_NOTES §4), through pseudo-terminals:
//! replies split by a USB adapter's latency tick, adapters that hold answers back, a slow host, a
//! one-wire bus that echoes every request, a servo that ignores a baud change, and the broadcast
//! id. Verdicts only: every servo found, the right value, the right error; never how fast.
//!
//! The command line runs in this process against the simulator served in lockstep with its link
//! ([`Sim`]): the field's timing (a latency timer, a slow host, a late servo) is the simulator's,
//! made explicit by its options, and a loaded machine starves neither side.

use botbench::link::{Link, LinkEvent, LinkOptions};
use botbench::ops::OpError;
use botbench::ops::servo as ops;
use botbench::ops::{Device, Run};
use botbench::profile::{Input, Registry};
use botbench::protocol::Direction;
use botbench::sim::servo_bus::{ServoBus, SimServo};
use botbench::sim::{Faults, PtyServer, SharedDevice};
use std::sync::{Arc, Mutex};

use crate::support::cli::{Ran, Sim, run_watched};

/// The ids a `servo --json scan` found, each with its presence status.
fn scanned(run: &Ran) -> Vec<(u64, String)> {
    let doc = &run.json_docs()[0];
    doc["servos"]
        .as_array()
        .unwrap_or_else(|| panic!("no servos: {}", run.text()))
        .iter()
        .map(|s| {
            (
                s["id"].as_u64().unwrap_or(999),
                s["presence"]["status"].as_str().unwrap_or("?").to_string(),
            )
        })
        .collect()
}

fn present(ids: &[u64]) -> Vec<(u64, String)> {
    ids.iter().map(|&i| (i, "present".to_string())).collect()
}

#[test]
fn a_reply_split_by_a_latency_tick_is_read_whole() {
    // The servo answers 8 ms late, its 9-byte reply as 4 bytes, then 5 bytes 16 ms later.
    let sim = Sim::start(&[
        "servo-bus",
        "--servos",
        "1",
        "--latency-ms",
        "8",
        "--split-after",
        "4",
        "--split-gap-ms",
        "16",
    ]);
    let p = sim.path.as_str();
    for _ in 0..4 {
        let read = sim.run(&[
            "servo",
            "--port",
            p,
            "--margin-ms",
            "20",
            "--json",
            "read",
            "1",
            "voltage",
        ]);
        assert_eq!(read.code, 0, "{}", read.text());
        let mv = read.json_docs()[0]["params"][0]["value"].as_i64();
        assert!(
            mv.is_some_and(|v| (7380..=7420).contains(&v)),
            "{}",
            read.text()
        );
    }
    // Nor is a lone servo taken for a duplicate, at the default margin.
    let scan = sim.run(&["servo", "--port", p, "--json", "scan", "--ids", "0-20"]);
    assert_eq!(scan.code, 0, "{}", scan.text());
    assert_eq!(scanned(&scan), present(&[1]), "{}", scan.text());
}

#[test]
fn a_default_scan_behind_a_16_ms_adapter_finds_every_servo_and_says_how() {
    let sim = Sim::start(&["servo-bus", "--servos", "0,1,5", "--latency-timer-ms", "16"]);
    let p = sim.path.as_str();
    for _ in 0..3 {
        let scan = sim.run(&["servo", "--port", p, "--json", "scan"]);
        assert_eq!(scan.code, 0, "{}", scan.text());
        assert_eq!(scanned(&scan), present(&[0, 1, 5]), "{}", scan.text());
        let doc = &scan.json_docs()[0];
        assert!(doc["asked_again"].is_u64(), "{}", scan.text());
        assert!(
            doc["margin_ms"].as_f64().is_some_and(|m| m >= 1.5),
            "{}",
            scan.text()
        );
        // Every found servo's details were read, however late they came.
        for s in doc["servos"].as_array().unwrap() {
            assert!(s["serial"].is_u64(), "{}", scan.text());
            // The raw reading, and the temperature as the text view shows it.
            assert!(s["temperature"].is_u64(), "{}", scan.text());
            assert!(
                s["temperature_text"]
                    .as_str()
                    .is_some_and(|t| t.contains("°C")),
                "{}",
                scan.text()
            );
        }
    }
    let text = sim.run(&["servo", "--port", p, "scan", "--ids", "0-10"]);
    assert!(
        text.out.contains("id(s) asked again") && text.out.contains("margin"),
        "{}",
        text.text()
    );
    // Single exchanges too, at the default margin.
    for _ in 0..4 {
        let ping = sim.run(&["servo", "--port", p, "ping", "5"]);
        assert_eq!(ping.code, 0, "{}", ping.text());
    }
}

#[test]
fn a_slow_host_still_finds_every_servo_and_every_answer() {
    // Each answer is seen up to 25 ms late, at random.
    let sim = Sim::start(&[
        "servo-bus",
        "--servos",
        "0,1,5",
        "--host-delay-ms",
        "25",
        "--seed",
        "7",
    ]);
    let p = sim.path.as_str();
    for _ in 0..3 {
        let scan = sim.run(&["servo", "--port", p, "--json", "scan"]);
        assert_eq!(scan.code, 0, "{}", scan.text());
        assert_eq!(scanned(&scan), present(&[0, 1, 5]), "{}", scan.text());
    }
    for _ in 0..6 {
        let ping = sim.run(&["servo", "--port", p, "ping", "5"]);
        assert_eq!(ping.code, 0, "{}", ping.text());
        let read = sim.run(&["servo", "--port", p, "--json", "read", "1", "assigned_id"]);
        assert_eq!(read.code, 0, "{}", read.text());
        assert_eq!(
            read.json_docs()[0]["params"][0]["value"],
            1,
            "{}",
            read.text()
        );
    }
}

#[test]
fn a_one_wire_bus_echo_is_not_taken_for_an_answer() {
    let sim = Sim::start(&["servo-bus", "--servos", "2,3", "--echo"]);
    let scan = sim.cli("servo", &["--json", "scan", "--ids", "0-10"]);
    assert_eq!(scanned(&scan), present(&[2, 3]), "{}", scan.text());
    let write = sim.cli("servo", &["write", "3", "over_temprature", "70"]);
    assert_eq!(write.code, 0, "{}", write.text());
    assert!(write.out.contains("verified"), "{}", write.text());
}

#[test]
fn a_servo_that_ignores_a_baud_change_is_reported_where_it_still_is() {
    let sim = Sim::start(&["servo-bus", "--servos", "4", "--ignore-baud-change"]);
    let set = sim.cli("servo", &["set-baud", "4", "57600"]);
    assert_eq!(set.code, 1, "{}", set.text());
    assert!(
        set.err.contains("57600") && set.err.contains("115200"),
        "the error says where the servo is: {}",
        set.text()
    );
    let ping = sim.cli("servo", &["ping", "4"]);
    assert_eq!(ping.code, 0, "still at 115200: {}", ping.text());
}

#[test]
fn the_broadcast_id_is_refused_where_an_answer_is_expected_before_the_port_is_opened() {
    let port = "/nonexistent/botbench-port";
    for args in [
        &["write", "255", "over_temprature", "70"][..],
        &["read", "255", "voltage"],
        &["read", "255"],
        &["ping", "255"],
        &["set-baud", "255", "57600"],
        &["set-id", "255", "3"],
        &["angle", "255", "90"],
        &["monitor", "1,255"],
        &["write", "3", "over_temprature", "70", "--broadcast"],
    ] {
        let mut all = vec!["servo", "--port", port];
        all.extend_from_slice(args);
        let run = run_watched(&all);
        assert_eq!(run.code, 2, "{args:?}: {}", run.text());
        assert!(
            run.err.contains("255") && !run.err.contains("nonexistent"),
            "{args:?}: {}",
            run.text()
        );
    }
}

#[test]
fn an_explicit_broadcast_changes_every_servo_and_reads_nothing_back() {
    let sim = Sim::start(&["servo-bus", "--servos", "1,2"]);
    let run = sim.cli(
        "servo",
        &["write", "255", "over_temprature", "70", "--broadcast"],
    );
    assert_eq!(run.code, 0, "{}", run.text());
    assert!(run.out.contains("nothing read back"), "{}", run.text());
    for id in ["1", "2"] {
        let read = sim.cli("servo", &["--json", "read", id, "over_temprature"]);
        assert_eq!(
            read.json_docs()[0]["params"][0]["value"],
            70,
            "{}",
            read.text()
        );
    }
}

#[test]
fn operations_refuse_the_broadcast_id_and_send_nothing() {
    let profile = Registry::builtin().unwrap().get("servo").unwrap();
    let bus: SharedDevice = Arc::new(Mutex::new(ServoBus::new(vec![
        SimServo::fresh(1).with_id(1),
    ])));
    let server = PtyServer::start_lockstep(bus, Faults::default()).unwrap();
    let link = Link::open(
        server.opener(115_200),
        profile.clone(),
        LinkOptions::default(),
        None,
    )
    .unwrap();
    let client = link.client();
    let param = profile.find_param("over_temprature").unwrap();
    let refused = [
        ops::ping(&client, 255, 1).err(),
        ops::read_param(Device::new(&client, &profile), 255, param).err(),
        ops::write_param(
            Device::new(&client, &profile),
            255,
            param,
            Input::Text("70".into()),
        )
        .err(),
        ops::read_block(Device::new(&client, &profile), 255).err(),
        ops::set_baud(Device::new(&client, &profile), 255, 4).err(),
        ops::set_id(
            Device::new(&client, &profile),
            255,
            3,
            &botbench::ops::Cancel::new(),
        )
        .err(),
    ];
    for e in refused {
        assert!(matches!(e, Some(OpError::BroadcastAnswer { .. })), "{e:?}");
        assert!(e.unwrap().is_input());
    }
    // Nothing went out: the next frame written is this ping's.
    assert_eq!(ops::ping(&client, 1, 2).unwrap(), ops::Presence::Present);
    let first = link.events().try_iter().find_map(|ev| match ev {
        LinkEvent::Frame(e) if e.direction == Direction::HostToDevice => e.frame.ok(),
        _ => None,
    });
    assert_eq!(first.map(|p| p.payload), Some(vec![1]));
}

/// A bus whose answers all reach the host `late_ms` late, and a link told to wait 2 ms for them
/// (a `--margin-ms` set too short): each answer comes after its window.
fn late_bus(
    late_ms: u64,
    servos: Vec<SimServo>,
) -> (PtyServer, Link, Arc<botbench::profile::Profile>) {
    late_bus_with(
        Faults {
            extra_latency: std::time::Duration::from_millis(late_ms),
            ..Faults::default()
        },
        servos,
    )
}

fn late_bus_with(
    faults: Faults,
    servos: Vec<SimServo>,
) -> (PtyServer, Link, Arc<botbench::profile::Profile>) {
    let profile = Registry::builtin().unwrap().get("servo").unwrap();
    let bus: SharedDevice = Arc::new(Mutex::new(ServoBus::new(servos)));
    let server = PtyServer::start_lockstep(bus, faults).unwrap();
    let options = LinkOptions {
        margin: Some(std::time::Duration::from_millis(2)),
        ..LinkOptions::default()
    };
    let link = Link::open(server.opener(115_200), profile.clone(), options, None).unwrap();
    (server, link, profile)
}

fn pings(ids: &[u8], listen: bool) -> botbench::link::Sweep {
    let mut sweep = ops::ping_sweep(ids);
    sweep.listen = listen;
    sweep
}

/// A default scan of ids 0-254 at the profile's rate.
fn scan_all(link: &Link, profile: &botbench::profile::Profile) -> ops::ScanReport {
    let plan = ops::ScanPlan {
        ids: 0..=254,
        bauds: vec![profile.baud],
        home_baud: profile.baud,
    };
    ops::scan(
        Device::new(&link.client(), profile),
        &plan,
        &mut Run::quiet(&botbench::ops::Cancel::new()),
        &mut |_| {},
    )
    .unwrap()
}

#[test]
fn a_sweep_that_listens_hands_back_the_answers_still_on_their_way() {
    let (_server, link, _) = late_bus(30, vec![SimServo::fresh(1).with_id(7)]);
    let client = link.client();
    // The sweep ends 2 ms after its window: servo 7's answer is still on its way.
    let first = client.sweep(pings(&[7], false)).unwrap();
    assert!(first.answers[0].is_none(), "{first:?}");
    // A sweep that listens takes it, as an answer to none of its own requests.
    let next = client.sweep(pings(&[9], true)).unwrap();
    assert!(next.answers[0].is_none(), "{next:?}");
    let late: Vec<Vec<u8>> = next.strays.iter().map(|p| p.payload.clone()).collect();
    assert_eq!(late, vec![vec![7]], "{next:?}");
}

#[test]
fn a_damaged_frame_before_any_clean_answer_may_be_an_earlier_sweeps_answer() {
    // Every answer damaged, and 30 ms late.
    let faults = Faults {
        extra_latency: std::time::Duration::from_millis(30),
        corrupt: 1.0,
        ..Faults::default()
    };
    let (_server, link, _) = late_bus_with(faults, vec![SimServo::fresh(1).with_id(7)]);
    let client = link.client();
    let first = client.sweep(pings(&[7], false)).unwrap();
    assert!(
        first.answers[0].is_none() && first.garbled.is_empty(),
        "{first:?}"
    );
    // Servo 7's damaged answer comes during the next sweep, or before it: nothing of that sweep
    // answered before it, so it may answer an earlier request (a scan asks 7 again).
    let next = client.sweep(pings(&[9], true)).unwrap();
    assert_eq!(next.garbled.len(), 1, "{next:?}");
    assert!(next.garbled[0].maybe_earlier, "{next:?}");
}

#[test]
fn an_answer_that_comes_after_its_exchange_gave_up_is_handed_to_the_next_sweep() {
    // 200 ms: beyond the grace a first exchange is given (150 ms).
    let (_server, link, _) = late_bus(200, vec![SimServo::fresh(1).with_id(7)]);
    let client = link.client();
    assert_eq!(ops::ping(&client, 7, 1).unwrap(), ops::Presence::Absent);
    // Read while the next sweep listens, or before it began: a stray of that sweep either way,
    // so that a scan that asked servo 7 again still finds it.
    let tail = client.sweep(ops::ping_sweep(&[])).unwrap();
    let late: Vec<Vec<u8>> = tail.strays.iter().map(|p| p.payload.clone()).collect();
    assert_eq!(late, vec![vec![7]], "{tail:?}");
}

#[test]
fn a_servo_whose_ping_answer_comes_after_the_last_sweep_is_found_with_its_details() {
    // 254 is pinged last: its answer comes while the details of 3 are read.
    let (_server, link, profile) = late_bus(
        30,
        vec![
            SimServo::fresh(1003).with_id(3),
            SimServo::fresh(1254).with_id(254),
        ],
    );
    let report = scan_all(&link, &profile);
    let found: Vec<(u8, Option<i64>)> = report.rows.iter().map(|r| (r.id, r.serial)).collect();
    assert_eq!(
        found,
        vec![(3, Some(1003)), (254, Some(1254))],
        "{report:?}"
    );
    assert!(report.asked_again >= 1, "{report:?}");
    assert!(report.late_answers >= 2, "{report:?}");
}

#[test]
fn a_scan_paced_by_the_bus_behind_a_16_ms_adapter_collides_with_no_answer_and_learns_the_latency() {
    // A half-duplex bus whose servos take the longest the vendor allows (1 ms) to answer, behind
    // an adapter that hands the host what it received only every 16 ms; the simulator knows when
    // each request went out (lockstep), so a request sent while an answer is still on the wire
    // garbles both.
    let profile = Registry::builtin().unwrap().get("servo").unwrap();
    let servos = [0u8, 1, 5]
        .map(|id| SimServo::fresh(1000 + u32::from(id)).with_id(id))
        .to_vec();
    let bus = ServoBus::new(servos).with_latency(std::time::Duration::from_millis(1));
    let faults = Faults {
        line: botbench::sim::Line {
            latency_timer: Some(std::time::Duration::from_millis(16)),
            half_duplex: true,
            ..botbench::sim::Line::default()
        },
        ..Faults::default()
    };
    let server = PtyServer::start_lockstep(Arc::new(Mutex::new(bus)), faults).unwrap();
    // A default scan: the automatic margin, nothing known of the adapter.
    let link = Link::open(
        server.opener(profile.baud),
        profile.clone(),
        LinkOptions::default(),
        None,
    )
    .unwrap();
    let report = scan_all(&link, &profile);
    let found: Vec<(u8, Option<i64>)> = report.rows.iter().map(|r| (r.id, r.serial)).collect();
    assert_eq!(
        found,
        vec![(0, Some(1000)), (1, Some(1001)), (5, Some(1005))],
        "{report:?}"
    );
    // Each ping left the bus to its answer: none collided, so no id had to be asked again.
    assert_eq!(report.asked_again, 0, "{report:?}");
    // The first answers reached the host after their 1.5 ms window, and counted all the same;
    // the margin the scan ended with is what it measured, not the servo's 1.5 ms. The adapter
    // hands bytes over on its own 16 ms clock: a request written just after a tick waits nearly
    // a whole tick for its answer, one written later in the tick less. A punctual host writes
    // just after the tick it read on (16 ms measured); a loaded one later (12-13 ms measured
    // with two CPU loops beside the suite), and the answers are measured to when they arrived,
    // not to when the host got to read them: so more than four of the servo's margins, not 16.
    assert!(report.late_answers >= 1, "{report:?}");
    assert!(report.margin_ms > 4.0 * 1.5, "{report:?}");
}
