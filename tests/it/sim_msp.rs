//! The MSP simulators as a host meets them: through a real pseudo-terminal, through the
//! in-process transport, and through `botbench sim`.

use botbench::link::{LinkError, Transport, wire_time};
use botbench::protocol::msp::{Reply, ReplyDecoder, Request};
use botbench::protocol::{Direction, FrameError};
use botbench::sim::solar_cleanbot::SolarCleanbot;
use botbench::sim::window_cleaner::{Fault, WindowCleaner};
use botbench::sim::{Faults, PtyServer, SimKind, SimOptions, SimTransport, build};
use serialport::SerialPort;
use std::io::ErrorKind;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crate::support::cli::{self, SimProcess};
use crate::support::{PATIENCE, profile, wait_until};

const WINDOW: u8 = 0x03;
const SOLAR: u8 = 0x04;

type Answer = Option<Result<Reply, FrameError>>;

fn next_item(dec: &mut ReplyDecoder) -> Answer {
    dec.next()
}

/// Sends a request through a transport and returns the first frame or frame error back.
fn exchange(t: &mut dyn Transport, req: &Request, within: Duration) -> Answer {
    t.write(&req.encode().expect("encodes")).expect("writes");
    let deadline = Instant::now() + within;
    let mut dec = ReplyDecoder::new();
    let mut buf = [0u8; 256];
    loop {
        let n = t.read(&mut buf, deadline).expect("reads");
        if n == 0 {
            return None;
        }
        dec.push(&buf[..n]);
        if let Some(item) = next_item(&mut dec) {
            return Some(item);
        }
    }
}

/// The same through a serial port.
fn exchange_port(port: &mut dyn SerialPort, req: &Request, within: Duration) -> Answer {
    port.write_all(&req.encode().expect("encodes"))
        .expect("writes");
    let deadline = Instant::now() + within;
    let mut dec = ReplyDecoder::new();
    let mut buf = [0u8; 256];
    while Instant::now() < deadline {
        match port.read(&mut buf) {
            Ok(n) => {
                dec.push(&buf[..n]);
                if let Some(item) = next_item(&mut dec) {
                    return Some(item);
                }
            }
            Err(e) if e.kind() == ErrorKind::TimedOut => {}
            Err(e) => panic!("read failed: {e}"),
        }
    }
    None
}

fn reply(answer: Answer) -> Reply {
    match answer {
        Some(Ok(r)) => r,
        other => panic!("expected a reply, got {other:?}"),
    }
}

fn window(faults: Faults) -> (Arc<Mutex<WindowCleaner>>, SimTransport) {
    window_at(115_200, faults)
}

fn window_at(baud: u32, faults: Faults) -> (Arc<Mutex<WindowCleaner>>, SimTransport) {
    let opts = SimOptions {
        baud: Some(baud),
        ..SimOptions::default()
    };
    let dev = Arc::new(Mutex::new(WindowCleaner::new(&opts).expect("builds")));
    let t = SimTransport::new(dev.clone(), baud, faults, "simulated window cleaner");
    (dev, t)
}

fn open(path: &str, baud: u32) -> Box<dyn SerialPort> {
    serialport::new(path, baud)
        .timeout(Duration::from_millis(20))
        .open()
        .expect("opens the pty")
}

fn field(id: &str, cmd: &str, r: &Reply, ident: &str) -> i64 {
    let p = profile(id);
    let c = p.command(cmd).expect("command");
    p.decode(c, Direction::DeviceToHost, &r.data)
        .expect("decodes")
        .int(ident)
        .unwrap_or_else(|| panic!("{cmd} has no {ident}"))
}

#[test]
fn version_and_set_then_get_through_a_real_pty() {
    let dev = build(SimKind::WindowCleaner, &SimOptions::default()).expect("builds");
    let server = PtyServer::start(dev, Faults::default()).expect("starts");
    assert!(server.path().starts_with("/dev/"), "{}", server.path());
    let mut port = open(server.path(), 115_200);

    let v = reply(exchange_port(
        &mut *port,
        &Request::new(0, 2, vec![]),
        PATIENCE,
    ));
    assert_eq!(v.command, 2);
    assert_eq!(field("window-cleaner", "CMD_VERSION", &v, "hw"), 3);
    assert_eq!(v.data.len(), 8);

    let get = Request::new(WINDOW, 130, vec![]);
    let before = reply(exchange_port(&mut *port, &get, PATIENCE));
    assert_eq!(before.data, vec![85], "factory default");
    let ack = reply(exchange_port(
        &mut *port,
        &Request::new(WINDOW, 220, vec![42]),
        PATIENCE,
    ));
    assert_eq!((ack.command, ack.data.len()), (220, 0));
    let after = reply(exchange_port(&mut *port, &get, PATIENCE));
    assert_eq!(after.data, vec![42]);

    // A multi-field SET: fan constant pressure, targets ×100.
    let set = Request::new(
        WINDOW,
        222,
        vec![50, 65, 95, 0x2C, 0x01, 0x5E, 0x01, 0xFA, 0x00],
    );
    reply(exchange_port(&mut *port, &set, PATIENCE));
    let got = reply(exchange_port(
        &mut *port,
        &Request::new(WINDOW, 132, vec![]),
        PATIENCE,
    ));
    assert_eq!(field("window-cleaner", "132", &got, "defaultTarget"), 300);
    assert_eq!(
        field("window-cleaner", "132", &got, "fanPwmvalueAtIdle"),
        50
    );
}

#[test]
fn pty_follows_the_client_baud_and_a_wrong_baud_gets_nothing() {
    let opts = SimOptions {
        baud: Some(9600),
        ..SimOptions::default()
    };
    let dev = build(SimKind::WindowCleaner, &opts).expect("builds");
    let server = PtyServer::start(dev, Faults::default()).expect("starts");
    let mut port = open(server.path(), 115_200);
    let ping = Request::new(WINDOW, 1, vec![]);
    assert!(exchange_port(&mut *port, &ping, Duration::from_millis(300)).is_none());

    port.set_baud_rate(9600).expect("sets baud");
    let start = Instant::now();
    let r = reply(exchange_port(&mut *port, &ping, PATIENCE));
    let took = start.elapsed();
    assert_eq!((r.command, r.data.len()), (1, 0));
    // 6 bytes out and 5 back at 9600 baud.
    let wire = wire_time(6 + 5, 9600);
    assert!(took >= wire.mul_f64(0.8), "{took:?} < 80% of {wire:?}");
}

#[test]
fn telemetry_moves_with_time() {
    let (dev, mut t) = window(Faults::default());
    let att = Request::new(WINDOW, 108, vec![]);
    let a = reply(exchange(&mut t, &att, PATIENCE));
    wait_until("the attitude to move", || {
        reply(exchange(&mut t, &att, PATIENCE)).data != a.data
    });

    // The fan ADC rises with the fan speed set by MSP_SET_FAN.
    let analog = Request::new(WINDOW, 110, vec![]);
    let idle = field(
        "window-cleaner",
        "110",
        &reply(exchange(&mut t, &analog, PATIENCE)),
        "adcFan",
    );
    reply(exchange(
        &mut t,
        &Request::new(WINDOW, 211, vec![90]),
        PATIENCE,
    ));
    assert_eq!(dev.lock().expect("lock").fan_pwm(), 90);
    wait_until("the fan ADC to rise by 500", || {
        let running = field(
            "window-cleaner",
            "110",
            &reply(exchange(&mut t, &analog, PATIENCE)),
            "adcFan",
        );
        running > idle + 500
    });

    // Corners set from the test, as an operator covering switches.
    dev.lock().expect("lock").set_corners(0b0101);
    let c = reply(exchange(
        &mut t,
        &Request::new(WINDOW, 112, vec![]),
        PATIENCE,
    ));
    assert_eq!(c.data, vec![0b0101]);
    dev.lock().expect("lock").inject(Fault::BatteryLow);
    let v = reply(exchange(
        &mut t,
        &Request::new(WINDOW, 111, vec![]),
        PATIENCE,
    ));
    assert_eq!(field("window-cleaner", "111", &v, "batteryVoltage"), 108);
}

#[test]
fn solar_speed_and_rotate_change_the_robot() {
    let dev = Arc::new(Mutex::new(
        SolarCleanbot::new(&SimOptions::default()).expect("builds"),
    ));
    let mut t = SimTransport::new(
        dev.clone(),
        115_200,
        Faults::default(),
        "simulated solar cleanbot",
    );
    let speed = Request::new(SOLAR, 104, vec![]);
    let attitude = Request::new(SOLAR, 108, vec![]);
    let still = reply(exchange(&mut t, &speed, PATIENCE));
    assert_eq!(field("solar-cleanbot", "104", &still, "averageSpeed"), 0);
    let yaw0 = field(
        "solar-cleanbot",
        "108",
        &reply(exchange(&mut t, &attitude, PATIENCE)),
        "yaw",
    );

    let ack = reply(exchange(
        &mut t,
        &Request::new(SOLAR, 100, 250i16.to_le_bytes().to_vec()),
        PATIENCE,
    ));
    assert_eq!((ack.command, ack.data.len()), (100, 0));
    reply(exchange(
        &mut t,
        &Request::new(SOLAR, 99, 60i16.to_le_bytes().to_vec()),
        PATIENCE,
    ));
    assert_eq!(dev.lock().expect("lock").commanded_speed(), 250);
    wait_until("the robot to run and move away", || {
        let moving = reply(exchange(&mut t, &speed, PATIENCE));
        field("solar-cleanbot", "104", &moving, "averageSpeed") > 150
            && field("solar-cleanbot", "104", &moving, "moveDistance") > 50
    });
    wait_until("the robot to turn", || {
        let attitude = reply(exchange(&mut t, &attitude, PATIENCE));
        field("solar-cleanbot", "108", &attitude, "yaw") > yaw0 + 10
    });

    // Settings are stored; the battery answers in 0.01 V with a state.
    reply(exchange(
        &mut t,
        &Request::new(SOLAR, 98, 5i16.to_le_bytes().to_vec()),
        PATIENCE,
    ));
    assert_eq!(dev.lock().expect("lock").heartbeat(), 5);
    let b = reply(exchange(
        &mut t,
        &Request::new(SOLAR, 130, vec![]),
        PATIENCE,
    ));
    assert!(field("solar-cleanbot", "130", &b, "voltage") > 2400);
    assert_eq!(field("solar-cleanbot", "130", &b, "state"), 0);
}

#[test]
fn round_trip_takes_at_least_the_wire_time_and_the_latency() {
    let (_, mut t) = window_at(9600, Faults::default());
    let get = Request::new(WINDOW, 132, vec![]);
    let start = Instant::now();
    let r = reply(exchange(&mut t, &get, PATIENCE));
    let took = start.elapsed();
    let wire = wire_time(get.wire_len() + r.data.len() + 5, 9600);
    assert!(took >= wire.mul_f64(0.8), "{took:?} < 80% of {wire:?}");

    let slow = Faults {
        extra_latency: Duration::from_millis(30),
        ..Faults::default()
    };
    let (_, mut t) = window_at(9600, slow);
    let start = Instant::now();
    reply(exchange(&mut t, &get, PATIENCE));
    let took = start.elapsed();
    let floor = (wire + Duration::from_millis(30)).mul_f64(0.8);
    assert!(took >= floor, "{took:?} < {floor:?}");
}

#[test]
fn drop_all_answers_nothing_and_corrupt_all_fails_every_checksum() {
    let (_, mut t) = window(Faults {
        drop: 1.0,
        ..Faults::default()
    });
    for _ in 0..3 {
        let r = exchange(
            &mut t,
            &Request::new(WINDOW, 1, vec![]),
            Duration::from_millis(100),
        );
        assert!(r.is_none(), "{r:?}");
    }

    let (_, mut t) = window(Faults {
        corrupt: 1.0,
        seed: 11,
        ..Faults::default()
    });
    for cmd in [1, 2, 108, 110, 130, 133] {
        let dev = if cmd == 2 { 0 } else { WINDOW };
        match exchange(&mut t, &Request::new(dev, cmd, vec![]), PATIENCE) {
            Some(Err(FrameError::Checksum { .. })) => {}
            other => panic!("command {cmd}: expected a checksum error, got {other:?}"),
        }
    }

    let (_, mut t) = window(Faults {
        silent: true,
        ..Faults::default()
    });
    assert!(
        exchange(
            &mut t,
            &Request::new(WINDOW, 1, vec![]),
            Duration::from_millis(100)
        )
        .is_none()
    );
}

#[test]
fn corrupt_faults_through_the_pty_too() {
    let dev = build(SimKind::SolarCleanbot, &SimOptions::default()).expect("builds");
    let faults = Faults {
        corrupt: 1.0,
        ..Faults::default()
    };
    let server = PtyServer::start(dev, faults).expect("starts");
    let mut port = open(server.path(), 115_200);
    match exchange_port(&mut *port, &Request::new(SOLAR, 97, vec![]), PATIENCE) {
        Some(Err(FrameError::Checksum { .. })) => {}
        other => panic!("expected a checksum error, got {other:?}"),
    }
}

#[test]
fn vanishing_ports_disconnect_the_host() {
    let (_, mut t) = window(Faults::default());
    reply(exchange(&mut t, &Request::new(WINDOW, 1, vec![]), PATIENCE));
    let handle = t.vanish_handle();
    handle.vanish();
    assert!(matches!(t.write(&[0xFF]), Err(LinkError::Disconnected(_))));
    let mut buf = [0u8; 8];
    let far = Instant::now() + PATIENCE;
    assert!(matches!(
        t.read(&mut buf, far),
        Err(LinkError::Disconnected(_))
    ));
    assert!(matches!(t.clear_input(), Err(LinkError::Disconnected(_))));

    let dev = build(SimKind::WindowCleaner, &SimOptions::default()).expect("builds");
    let mut server = PtyServer::start(dev, Faults::default()).expect("starts");
    let mut port = open(server.path(), 115_200);
    reply(exchange_port(
        &mut *port,
        &Request::new(WINDOW, 1, vec![]),
        PATIENCE,
    ));
    server.vanish();
    assert!(!server.is_running());
    let err = port.read(&mut buf).expect_err("the port is gone");
    assert_eq!(err.kind(), ErrorKind::BrokenPipe, "{err}");
}

#[test]
fn cli_sim_prints_the_pty_path_first_and_answers_there() {
    let sim = SimProcess::start(&["window-cleaner", "--seed", "3"]);
    assert!(sim.path.starts_with("/dev/pts/"), "{}", sim.path);
    let mut port = open(&sim.path, 115_200);
    let v = reply(exchange_port(
        &mut *port,
        &Request::new(0, 2, vec![]),
        PATIENCE,
    ));
    assert_eq!(v.data.first(), Some(&3));
}

#[test]
fn cli_sim_rejects_bad_options_with_exit_code_2() {
    for args in [
        &["sim", "toaster"][..],
        &["sim", "window-cleaner", "--drop", "1.5"][..],
        &["sim", "window-cleaner", "--corrupt", "-0.1"][..],
        &["sim", "tuya-vacuum", "--report-every", "0"][..],
    ] {
        let o = cli::run(args);
        assert_eq!(o.code, 2, "{args:?}");
        assert!(!o.err.is_empty(), "{args:?}: no message");
        assert!(o.out.is_empty(), "{args:?}");
    }
}

#[test]
fn a_transport_by_kind_describes_itself_and_answers() {
    let mut t = SimTransport::of_kind(
        SimKind::SolarCleanbot,
        &SimOptions::default(),
        Faults::default(),
    )
    .expect("builds");
    assert_eq!(t.describe(), "simulated solar cleanbot");
    assert_eq!(t.baud(), 115_200);
    let v = reply(exchange(&mut t, &Request::new(0, 2, vec![]), PATIENCE));
    assert_eq!(v.data.first(), Some(&SOLAR));
    let bad = Faults {
        drop: 2.0,
        ..Faults::default()
    };
    assert!(SimTransport::of_kind(SimKind::WindowCleaner, &SimOptions::default(), bad).is_err());
}

#[test]
fn an_answer_still_crossing_when_the_host_changes_rate_arrives_as_garbage() {
    // 300 baud: the version answer takes about half a second to cross.
    let version = Request::new(0, 2, vec![]).encode().expect("encodes");
    let read_all = |t: &mut SimTransport, first: &mut Vec<u8>| {
        let mut buf = [0u8; 64];
        let deadline = Instant::now() + PATIENCE;
        while first.is_empty() {
            let n = t.read(&mut buf, deadline).expect("reads");
            assert!(n > 0, "no answer at all");
            first.extend_from_slice(&buf[..n]);
        }
    };
    let rest = |t: &mut SimTransport| {
        let mut got = Vec::new();
        let mut buf = [0u8; 64];
        // Until the line has been quiet for a few bytes' time.
        while let n @ 1.. = t
            .read(&mut buf, Instant::now() + Duration::from_millis(200))
            .expect("reads")
        {
            got.extend_from_slice(&buf[..n]);
        }
        got
    };
    let (_, mut clean) = window_at(300, Faults::default());
    clean.write(&version).expect("writes");
    let mut whole = Vec::new();
    read_all(&mut clean, &mut whole);
    whole.extend(rest(&mut clean));
    let mut dec = ReplyDecoder::new();
    dec.push(&whole);
    assert!(
        matches!(dec.next(), Some(Ok(r)) if r.command == 2),
        "{whole:02x?}"
    );

    let (_, mut cut) = window_at(300, Faults::default());
    cut.write(&version).expect("writes");
    let mut first = Vec::new();
    read_all(&mut cut, &mut first);
    cut.set_baud(115_200).expect("switches");
    let after = rest(&mut cut);
    assert_eq!(
        first,
        whole[..first.len()],
        "what crossed before the switch"
    );
    assert_ne!(
        after,
        whole[first.len()..],
        "read at the new rate, the rest is garbage"
    );
    let mut dec = ReplyDecoder::new();
    dec.push(&first);
    dec.push(&after);
    assert!(
        !matches!(dec.next(), Some(Ok(_))),
        "{first:02x?} {after:02x?}"
    );
}
