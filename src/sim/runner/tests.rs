//! The simulated wire's timing, faults and garbling.

use super::*;

/// Echoes every chunk after 1 ms, optionally at another baud.
struct Echo(Option<u32>);

impl Device for Echo {
    fn receive(&mut self, bytes: &[u8], _baud: u32, _now: Instant) -> Vec<Outgoing> {
        vec![Outgoing {
            after: Duration::from_millis(1),
            bytes: bytes.to_vec(),
            baud: self.0,
        }]
    }
}

fn echo(baud: Option<u32>, faults: Faults) -> SimTransport {
    SimTransport::new(Arc::new(Mutex::new(Echo(baud))), 9600, faults, "echo")
}

fn read_all(t: &mut SimTransport, within: Duration) -> Vec<u8> {
    let deadline = Instant::now() + within;
    let mut out = Vec::new();
    let mut buf = [0u8; 64];
    while let Ok(n) = t.read(&mut buf, deadline) {
        if n == 0 {
            break;
        }
        out.extend_from_slice(&buf[..n]);
    }
    out
}

#[test]
fn echo_arrives_byte_by_byte_after_the_request_and_the_latency() {
    let mut t = echo(None, Faults::default());
    let start = Instant::now();
    t.write(&[1, 2, 3, 4, 5, 6, 7, 8, 9, 10]).unwrap();
    let mut buf = [0u8; 64];
    let mut got = Vec::new();
    let mut first = None;
    while got.len() < 10 {
        let n = t.read(&mut buf, start + Duration::from_secs(5)).unwrap();
        assert!(n > 0, "timed out with {got:?}");
        first.get_or_insert(start.elapsed());
        got.extend_from_slice(&buf[..n]);
    }
    let took = start.elapsed();
    assert_eq!(got, [1, 2, 3, 4, 5, 6, 7, 8, 9, 10]);
    // The request takes 10.4 ms at 9600 baud, the device 1 ms, each echoed byte 1.04 ms.
    let first = first.unwrap();
    assert!(
        first >= Duration::from_micros(12_400),
        "first byte after {first:?}"
    );
    assert!(
        took >= Duration::from_micros(21_800),
        "last byte after {took:?}"
    );
}

#[test]
fn nothing_arrives_before_the_deadline_when_dropped() {
    let faults = Faults {
        drop: 1.0,
        ..Faults::default()
    };
    let mut t = echo(None, faults);
    t.write(&[1, 2, 3]).unwrap();
    assert!(read_all(&mut t, Duration::from_millis(50)).is_empty());
}

#[test]
fn another_baud_arrives_as_garbage_of_the_scaled_length() {
    let mut t = echo(Some(9600 * 4), Faults::default());
    t.write(&[0x55; 40]).unwrap();
    let got = read_all(&mut t, Duration::from_millis(200));
    assert_eq!(got.len(), 10);
    assert_ne!(got, vec![0x55; 10]);
}

#[test]
fn corrupt_flips_one_bit_of_the_last_byte() {
    let faults = Faults {
        corrupt: 1.0,
        seed: 7,
        ..Faults::default()
    };
    let mut t = echo(None, faults);
    t.write(&[0, 0, 0, 0]).unwrap();
    let got = read_all(&mut t, Duration::from_millis(100));
    assert_eq!(&got[..3], &[0, 0, 0]);
    assert_eq!(got[3].count_ones(), 1);
}

#[test]
fn clear_input_drops_what_arrived_and_vanish_disconnects() {
    let mut t = echo(None, Faults::default());
    t.write(&[9]).unwrap();
    std::thread::sleep(Duration::from_millis(20));
    t.clear_input().unwrap();
    assert!(read_all(&mut t, Duration::from_millis(10)).is_empty());
    let h = t.vanish_handle();
    h.vanish();
    assert!(matches!(t.write(&[1]), Err(LinkError::Disconnected(_))));
    let mut buf = [0u8; 4];
    assert!(matches!(
        t.read(&mut buf, Instant::now()),
        Err(LinkError::Disconnected(_))
    ));
}

#[test]
fn checks_fault_probabilities() {
    let bad = Faults {
        drop: 1.5,
        ..Faults::default()
    };
    assert!(bad.check().is_err());
    assert!(Faults::default().check().is_ok());
}

#[test]
fn a_request_that_meets_a_reply_on_a_half_duplex_line_garbles_both() {
    // The wire itself, at instants the test names (never the clock: a loaded machine that held
    // this thread up between reading the reply's first byte and writing the next request let
    // the reply end first, and the test failed). 300 baud: a 10-byte request or reply takes
    // 333 ms on the wire.
    let faults = Faults {
        line: Line {
            half_duplex: true,
            ..Line::default()
        },
        ..Faults::default()
    };
    let mut wire = Wire::new(Arc::new(Mutex::new(Echo(None))), 300, faults);
    let t0 = Instant::now();
    let at = |ms: u64| t0 + Duration::from_millis(ms);
    let first: Vec<u8> = (1..=10).collect();
    let second: Vec<u8> = (11..=20).collect();
    wire.host_wrote(&first, t0);
    // The request has crossed by 333 ms, the device echoes it 1 ms later: by 400 ms the first
    // byte of the reply (33 ms a byte) has crossed, the rest is on the wire until ~668 ms.
    wire.pump(at(400));
    let mut reply = vec![0u8; 64];
    let n = wire.take_due(at(400), &mut reply);
    assert!(
        (1..10).contains(&n),
        "the reply has begun, not ended: {n} bytes"
    );
    // The host's next request meets it.
    wire.host_wrote(&second, at(400));
    wire.pump(at(2_000));
    let rest = wire.take_due(at(2_000), &mut reply[n..]);
    let reply = &reply[..n + rest];
    assert_eq!(reply[0], first[0], "what crossed before the request began");
    assert_ne!(reply[9], first[9], "what crossed with it: {reply:?}");
    // The device heard the request garbled where it met the reply, and echoes what it heard.
    let mut heard = reply[10..].to_vec();
    if heard.len() < second.len() {
        wire.pump(at(4_000));
        let mut more = [0u8; 64];
        let k = wire.take_due(at(4_000), &mut more);
        heard.extend_from_slice(&more[..k]);
    }
    assert_eq!(heard.len(), second.len(), "{heard:?}");
    assert_ne!(heard[0], second[0], "{heard:?}");
}

/// Sends what it heard at its next tick, as a Tuya MCU sends a report it queued.
struct AtNextTick(Vec<u8>);

impl Device for AtNextTick {
    fn receive(&mut self, bytes: &[u8], _baud: u32, _now: Instant) -> Vec<Outgoing> {
        self.0.extend_from_slice(bytes);
        Vec::new()
    }

    fn tick(&mut self, _now: Instant) -> Vec<Outgoing> {
        if self.0.is_empty() {
            return Vec::new();
        }
        vec![Outgoing::new(Duration::ZERO, std::mem::take(&mut self.0))]
    }
}

/// A simulator's thread that runs 6 s late (a stopped or starved process) still has the device
/// act at its own ticks: what it queued for its next tick goes out a tick after it heard the
/// request, not when the thread got to run (before: 6 s late, and a Tuya conformance run
/// failed its 5 s answer limit).
#[test]
fn a_device_acts_at_its_own_ticks_however_late_its_thread_runs() {
    let start = Instant::now();
    let mut wire = Wire::new(
        Arc::new(Mutex::new(AtNextTick(Vec::new()))),
        115_200,
        Faults::default(),
    );
    wire.pump(start);
    wire.host_wrote(&[1, 2, 3], start);
    let late = start + Duration::from_secs(6);
    wire.pump(late);
    let mut buf = [0u8; 16];
    assert_eq!(wire.take_due(late, &mut buf), 3);
    let seen = wire.last_seen().expect("seen").duration_since(start);
    // The request's 0.26 ms on the wire, the next tick (3 ms) and the answer's 0.26 ms.
    assert!(
        seen <= wire_time(6, 115_200) + 2 * TICK,
        "seen after {seen:?}"
    );
}

/// Counts the bytes it hears.
#[derive(Default)]
struct Hears(usize);

impl Device for Hears {
    fn receive(&mut self, bytes: &[u8], _baud: u32, _now: Instant) -> Vec<Outgoing> {
        self.0 += bytes.len();
        Vec::new()
    }
}

/// A write made before the port was opened again reaches the device, even when the simulator
/// takes the write and the open together (a loaded machine) and pumps after both; what comes
/// during a boot after the open is lost.
#[test]
fn a_write_before_an_open_is_heard_and_one_during_the_boot_is_not() {
    for boot in [Duration::ZERO, Duration::from_millis(500)] {
        let hears = Arc::new(Mutex::new(Hears::default()));
        let faults = Faults {
            boot,
            ..Faults::default()
        };
        let t0 = Instant::now() + Duration::from_secs(1);
        let mut wire = Wire::new(hears.clone(), 115_200, faults);
        wire.host_wrote(&[1, 2, 3], t0);
        wire.opened(t0 + Duration::from_millis(50));
        wire.pump(t0 + Duration::from_millis(60));
        assert_eq!(
            hears.lock().unwrap().0,
            3,
            "boot {boot:?}: the write before the open"
        );
        wire.host_wrote(&[4, 5], t0 + Duration::from_millis(70));
        wire.pump(t0 + Duration::from_secs(1));
        let expected = if boot.is_zero() { 5 } else { 3 };
        assert_eq!(
            hears.lock().unwrap().0,
            expected,
            "boot {boot:?}: the write after the open"
        );
    }
}

/// A slow MCU: the request `[0]` starts a burst of three reports 1 s apart, `[9]` has two frames
/// sent at once; any other request is answered with itself at once.
struct SlowReports;

impl Device for SlowReports {
    fn receive(&mut self, bytes: &[u8], _baud: u32, _now: Instant) -> Vec<Outgoing> {
        if bytes == [0] {
            (0..3u8)
                .map(|i| Outgoing::new(Duration::from_secs(u64::from(i)), vec![0xB0 + i; 4]))
                .collect()
        } else if bytes == [9] {
            vec![
                Outgoing::new(Duration::ZERO, vec![0xC0; 3]),
                Outgoing::new(Duration::ZERO, vec![0xC1; 3]),
            ]
        } else {
            vec![Outgoing::new(Duration::ZERO, bytes.to_vec())]
        }
    }
}

/// Reads what the host has seen by `at`, pumping the wire there first.
fn seen_by(wire: &mut Wire, at: Instant) -> Vec<u8> {
    wire.pump(at);
    let mut buf = [0u8; 64];
    let n = wire.take_due(at, &mut buf);
    buf[..n].to_vec()
}

/// An answer due while a slow MCU's later reports are still to come goes out in the line's idle
/// gap before the next report, as a UART sends, not behind every report scheduled (a heartbeat's
/// answer was seen 6.6 s late behind reports 100-150 ms apart, and a conformance run failed its
/// answer time); frames are still seen whole and in wire order, behind an adapter's latency
/// timer too.
#[test]
fn an_answer_goes_out_in_the_gap_before_reports_scheduled_for_later() {
    let lines = [
        Line::default(),
        Line {
            latency_timer: Some(Duration::from_millis(16)),
            host_delay: Some(Duration::from_millis(5)),
            ..Line::default()
        },
    ];
    for line in lines {
        let faults = Faults {
            line: line.clone(),
            ..Faults::default()
        };
        let t0 = Instant::now();
        let mut wire = Wire::new(Arc::new(Mutex::new(SlowReports)), 115_200, faults);
        wire.host_wrote(&[0], t0);
        assert_eq!(
            seen_by(&mut wire, t0 + Duration::from_millis(100)),
            [0xB0; 4]
        );
        wire.host_wrote(&[7, 7], t0 + Duration::from_millis(300));
        let answer = seen_by(&mut wire, t0 + Duration::from_millis(400));
        assert_eq!(
            answer,
            [7, 7],
            "{line:?}: the answer before the report due at 1 s"
        );
        let rest = seen_by(&mut wire, t0 + Duration::from_secs(3));
        assert_eq!(rest, [[0xB1; 4], [0xB2; 4]].concat(), "{line:?}");
    }
}

/// Two frames sent at once do not share the wire: the second starts when the first has ended.
#[test]
fn frames_sent_together_go_out_one_after_the_other() {
    let t0 = Instant::now();
    let mut wire = Wire::new(Arc::new(Mutex::new(SlowReports)), 9600, Faults::default());
    wire.host_wrote(&[9], t0);
    // The request takes 1.04 ms at 9600 baud, each frame 3.1 ms: half a byte after the first
    // frame's end, none of the second has arrived.
    let byte = wire_time(1, 9600);
    let first_done = t0 + byte * 4 + byte / 2;
    assert_eq!(seen_by(&mut wire, first_done), [0xC0; 3]);
    let second_done = first_done + byte * 3;
    assert_eq!(seen_by(&mut wire, second_done), [0xC1; 3]);
}
