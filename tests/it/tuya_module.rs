//! botbench as the Wi-Fi module against MCUs as they are in the field (issue 26, items 1-5):
//! impossible values flagged, data points the profile lacks decoded, a slow MCU heard, every
//! request of the MCU answered (an unknown one ignored, an oversize frame refused), each with
//! the simulator's misbehaviour that shows it, through pseudo-terminals in lockstep with the
//! link (and the command line in this process, handed the simulator's port).

use botbench::link::session::tuya::{TuyaEvent, TuyaModuleOptions};
use botbench::link::{Link, LinkError, LinkEvent, LinkOptions, Opener, Transport};
use botbench::ops::Device;
use botbench::ops::tuya as ops;
use botbench::profile::{Input, Profile, Value};
use botbench::protocol::tuya::cmd;
use botbench::protocol::tuya::dp::DpValue;
use botbench::sim::tuya_mcu::{RawValue, TuyaConfig, TuyaMcu};
use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::support::cli::{SimProcess, run, run_in_process};
use crate::support::{Port, Served, next_event, open_link, profile, serve, wait_until};

const BAUD: u32 = 115_200;

/// The MCU on its pty in lockstep, and a link to it that has done its handshake. The pty takes
/// one client at a time: [`Bench::cli`] closes the link first.
struct Bench {
    link: Option<Link>,
    mcu: Served<TuyaMcu>,
    profile: Arc<Profile>,
    options: LinkOptions,
}

impl Bench {
    fn new(cfg: TuyaConfig) -> Self {
        Self::with(cfg, LinkOptions::default())
    }

    fn with(cfg: TuyaConfig, options: LinkOptions) -> Self {
        let mcu = serve(TuyaMcu::new(TuyaConfig {
            baud: Some(BAUD),
            ..cfg
        }));
        Self {
            link: None,
            mcu,
            profile: profile("tuya-vacuum"),
            options,
        }
    }

    /// The link, opened (and its handshake done) the first time.
    fn link(&mut self) -> &Link {
        if self.link.is_none() {
            let link = open_link(&self.mcu, BAUD, self.profile.clone(), self.options.clone());
            next_event(&link, "the handshake", |e| {
                matches!(e, LinkEvent::Tuya(TuyaEvent::HandshakeDone)).then_some(())
            });
            self.link = Some(link);
        }
        self.link.as_ref().expect("opened")
    }

    fn client(&mut self) -> botbench::link::Client {
        self.link().client()
    }

    fn status(&mut self) -> ops::Status {
        let c = self.client();
        ops::query_status(Device::new(&c, &self.profile)).expect("a status")
    }

    /// `botbench tuya --port PTY --baud 115200 ARGS` in this process, handed the simulator's
    /// port (the link closed first), watched ([`run_in_process`]): its exit code.
    fn cli(&mut self, args: &[&str]) -> u8 {
        self.link = None;
        let mut all = vec!["tuya", "--port", self.mcu.path(), "--baud", "115200"];
        all.extend_from_slice(args);
        let ran = run_in_process(&all, &self.mcu.ports());
        u8::try_from(ran.code).unwrap_or_else(|_| panic!("{}", ran.text()))
    }
}

fn shown(status: &ops::Status, profile: &Profile, id: u8) -> String {
    status
        .data_points
        .iter()
        .find(|d| d.id == id)
        .map(|d| d.shown(profile))
        .unwrap_or_else(|| panic!("dp {id} reported: {status:?}"))
}

// ---------------------------------------------------------------- 1. impossible values

#[test]
fn impossible_values_are_misfits_status_says_which_and_fails() {
    let cfg = TuyaConfig {
        report_out_of_range: BTreeMap::from([
            (6, RawValue::Int(150)),
            (3, RawValue::Int(32)),
            (18, RawValue::Int(0x84)),
            (16, RawValue::Int(-50)),
            (15, RawValue::Len(300)),
        ]),
        ..TuyaConfig::default()
    };
    let mut b = Bench::new(cfg);
    let status = b.status();
    let p = &b.profile.clone();
    let mut suspect: Vec<u8> = status.suspect().iter().map(|d| d.id).collect();
    suspect.sort_unstable();
    assert_eq!(suspect, [3, 6, 15, 16, 18], "{status:?}");
    assert!(!status.complete());
    assert_eq!(
        shown(&status, p, 6),
        "raw 00 00 00 96 (150 % is out of range: the profile allows 0 to 100 %)"
    );
    assert_eq!(
        shown(&status, p, 3),
        "raw 20 (enum index 32 has no label: the profile labels 0 to 11)"
    );
    assert_eq!(
        shown(&status, p, 16),
        "raw ff ff ff ce (-5.0 m² is out of range: the profile allows 0.0 to 999.9 m²)"
    );
    assert!(shown(&status, p, 18).contains("bits 0x80 are not defined"));
    assert!(shown(&status, p, 15).contains("300 bytes, over the profile's maximum of 255"));
    // The others are good values.
    assert_eq!(shown(&status, p, 7), "90 %");
    // `tuya status` fails on them.
    assert_eq!(b.cli(&["status"]), 1);
    assert_eq!(b.cli(&["status", "--json"]), 1);
}

#[test]
fn a_write_is_not_verified_by_an_impossible_report() {
    // The firmware reports mode 32 whatever it was told.
    let cfg = TuyaConfig {
        report_out_of_range: BTreeMap::from([(3, RawValue::Int(32))]),
        ..TuyaConfig::default()
    };
    let mut b = Bench::new(cfg);
    let c = b.client();
    let inputs = vec![("mode".to_string(), Input::from("smart"))];
    let checks = ops::set_dps(Device::new(&c, &b.profile), &inputs).expect("sent");
    assert_eq!(checks.len(), 1);
    assert!(!checks[0].verified(), "{checks:?}");
    let last = checks[0].last.as_ref().expect("reported");
    assert_eq!(last.value, Some(Value::Int(32)));
    assert!(last.misfit.is_some());
    assert_eq!(b.cli(&["dp", "mode=smart"]), 1);
    // A value out of range is never sent.
    assert_eq!(
        b.cli(&["dp", "clean_area=1000"]),
        2,
        "read-only and out of range"
    );
}

// ---------------------------------------------------------------- 2. unknown data points

#[test]
fn data_points_the_profile_lacks_are_read_by_their_own_type_and_named() {
    let cfg = TuyaConfig {
        report_unknown_dp: vec![
            (101, DpValue::Value(50)),
            (102, DpValue::String("hi".into())),
        ],
        ..TuyaConfig::default()
    };
    let mut b = Bench::new(cfg);
    let status = b.status();
    let unknown: Vec<u8> = status.unknown().iter().map(|d| d.id).collect();
    assert_eq!(unknown, [101, 102]);
    assert_eq!(status.unknown()[0].name(), "dp 101 (not in the profile)");
    assert_eq!(shown(&status, &b.profile, 101), "value 50");
    assert_eq!(shown(&status, &b.profile, 102), "string \"hi\"");
    // Every data point of the profile is there and fits: the status is complete.
    assert!(status.complete(), "{status:?}");
    assert_eq!(b.cli(&["status"]), 0);
}

#[test]
fn frame_decode_shows_a_data_point_the_profile_lacks_by_its_own_type() {
    // 55 AA 03 07 00 08, DP 101 value 50, checksum.
    let o = run(&[
        "frame", "decode", "tuya", "55", "aa", "03", "07", "00", "08", "65", "02", "00", "04",
        "00", "00", "00", "32", "ae",
    ]);
    assert_eq!(o.code, 0, "{}", o.text());
    assert!(
        o.out.contains("dp 101 (not in the profile): value 50"),
        "{}",
        o.text()
    );
    let o = run(&[
        "frame",
        "decode",
        "tuya",
        "--json",
        "55aa0307000865020004000000 32 ae",
    ]);
    assert_eq!(o.code, 0, "{}", o.text());
    let field = &o.json_docs()[0]["fields"][0];
    assert_eq!(field["in_profile"], false);
    assert_eq!(field["value"], 50);
}

// ---------------------------------------------------------------- 3. a slow MCU

#[test]
fn a_slow_mcus_reports_are_heard_in_one_query() {
    let cfg = TuyaConfig {
        report_gap: Some((Duration::from_millis(100), Duration::from_millis(150))),
        ..TuyaConfig::default()
    };
    let mut b = Bench::new(cfg);
    let status = b.status();
    assert!(status.complete(), "{status:?}");
    assert_eq!(
        status.queries, 1,
        "each report came within the margin of the last"
    );
}

#[test]
fn reports_that_come_between_queries_are_kept_and_counted() {
    // The link gives up on a query's answer 30 ms after the last report: the slow MCU's reports
    // come after it, between this query and the next.
    let options = LinkOptions {
        margin: Some(Duration::from_millis(30)),
        ..LinkOptions::default()
    };
    let cfg = TuyaConfig {
        report_gap: Some((Duration::from_millis(100), Duration::from_millis(150))),
        ..TuyaConfig::default()
    };
    let mut b = Bench::with(cfg, options);
    let status = b.status();
    assert!(status.complete(), "{status:?}");
    assert!(status.between > 0, "{status:?}");
    assert!(status.queries <= ops::QUERIES);
    assert_eq!(b.cli(&["--margin-ms", "30", "init"]), 0);
}

/// A port whose host thread is held up for 3 s before it writes a status query (a loaded
/// computer: the thread preempted between two calls of its port), the port itself exact about
/// when the device heard the write (a pty served in lockstep).
struct HeldUpHost(Box<dyn Transport>);

impl Transport for HeldUpHost {
    fn write(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        if bytes.get(3) == Some(&cmd::QUERY_STATUS) {
            std::thread::sleep(Duration::from_secs(3));
        }
        self.0.write(bytes)
    }
    fn read(&mut self, buf: &mut [u8], deadline: Instant) -> Result<usize, LinkError> {
        self.0.read(buf, deadline)
    }
    fn set_baud(&mut self, baud: u32) -> Result<(), LinkError> {
        self.0.set_baud(baud)
    }
    fn baud(&self) -> u32 {
        self.0.baud()
    }
    fn clear_input(&mut self) -> Result<(), LinkError> {
        self.0.clear_input()
    }
    fn describe(&self) -> String {
        self.0.describe()
    }
    fn arrived_at(&self) -> Option<Instant> {
        self.0.arrived_at()
    }
    fn written_at(&self) -> Option<Instant> {
        self.0.written_at()
    }
}

/// A slow MCU's reports are timed from when it heard the query: a host held up before its write
/// (seen with two CPU-bound loops beside the suite: all 19 reports, 100-150 ms apart, taken as
/// the query's answer) still hears those after the answer's end as coming between queries: the
/// link counts from when the port says its write went out, and the simulator, catching up after
/// the hold, hands each report over when it was due, not all with the first.
#[test]
fn a_host_held_up_before_its_query_still_times_a_slow_mcus_reports_from_its_write() {
    let options = LinkOptions {
        margin: Some(Duration::from_millis(30)),
        ..LinkOptions::default()
    };
    let mcu = serve(TuyaMcu::new(TuyaConfig {
        baud: Some(BAUD),
        report_gap: Some((Duration::from_millis(100), Duration::from_millis(150))),
        ..TuyaConfig::default()
    }));
    let mut opener = mcu.opener(BAUD);
    let late: Opener = Box::new(move || Ok(Box::new(HeldUpHost(opener()?)) as Box<dyn Transport>));
    let vacuum = profile("tuya-vacuum");
    let link = Link::open(late, vacuum.clone(), options, None).expect("opens the port");
    next_event(&link, "the handshake", |e| {
        matches!(e, LinkEvent::Tuya(TuyaEvent::HandshakeDone)).then_some(())
    });
    let client = link.client();
    let status = ops::query_status(Device::new(&client, &vacuum)).expect("a status");
    assert!(status.complete(), "{status:?}");
    assert!(status.between > 0, "{status:?}");
}

#[test]
fn init_does_not_say_done_with_data_points_missing() {
    let cfg = TuyaConfig {
        never_report: vec![15, 19],
        ..TuyaConfig::default()
    };
    let mut b = Bench::new(cfg);
    assert_eq!(b.cli(&["init"]), 1);
    let status = b.status();
    assert_eq!(status.missing, [15, 19]);
    assert_eq!(b.cli(&["status"]), 1);
}

// ---------------------------------------------------------------- 4. the MCU's requests

#[test]
fn every_request_of_a_field_mcu_gets_its_due_answer() {
    use botbench::sim::tuya_mcu::McuRequest;
    let fixed = chrono::NaiveDate::from_ymd_opt(2024, 2, 29)
        .and_then(|d| d.and_hms_opt(14, 45, 30))
        .unwrap();
    let module = TuyaModuleOptions {
        fixed_time: Some(fixed),
        rssi_dbm: -70,
        net_status: 3,
        mac: [0x12, 0x34, 0x56, 0x78, 0x9A, 0xBC],
        ..TuyaModuleOptions::default()
    };
    let options = LinkOptions {
        tuya: module,
        ..LinkOptions::default()
    };
    let mut b = Bench::with(
        TuyaConfig {
            sync_reports: true,
            ..TuyaConfig::default()
        },
        options,
    );
    let asked = [
        McuRequest::LocalTime,
        McuRequest::UtcTime,
        McuRequest::Rssi,
        McuRequest::NetStatus,
        McuRequest::Mac,
        McuRequest::Extended(0x01),
        McuRequest::Extended(0x04),
        McuRequest::Extended(0x07),
    ];
    b.link();
    {
        let mut m = b.mcu.sim();
        m.take_answers();
        for r in asked {
            m.request(r);
        }
        // The robot's own change, reported as 0x22.
        assert!(m.set_dp_raw(6, 77));
    }
    wait_until("every request answered", || {
        b.mcu.sim().answers().len() > asked.len()
    });
    let answers = b.mcu.sim().answers().to_vec();
    let get = |c: u8, first: Option<u8>| {
        answers
            .iter()
            .find(|(cmd, d)| *cmd == c && first.is_none_or(|f| d.first() == Some(&f)))
            .map(|(_, d)| d.clone())
            .unwrap_or_else(|| panic!("no answer {c:#04x}: {answers:02x?}"))
    };
    assert_eq!(get(cmd::LOCAL_TIME, None), [1, 24, 2, 29, 14, 45, 30, 4]);
    assert_eq!(get(cmd::UTC_TIME, None).len(), 7);
    assert_eq!(get(cmd::UTC_TIME, None)[0], 1);
    assert_eq!(get(cmd::WIFI_RSSI, None), [(-70i8) as u8]);
    assert_eq!(get(cmd::NET_STATUS, None), [3]);
    assert_eq!(get(cmd::MAC, None), [0, 0x12, 0x34, 0x56, 0x78, 0x9A, 0xBC]);
    assert_eq!(get(cmd::EXTENDED, Some(1)), [1, 0]);
    assert_eq!(get(cmd::EXTENDED, Some(4)), [4, 0]);
    assert_eq!(get(cmd::EXTENDED, Some(7)), [7, 1]);
    assert_eq!(get(cmd::DP_REPORT_SYNC_RESULT, None), [1]);
    assert_eq!(b.mcu.sim().sync_results(), [1]);
    // The synchronous report is a report: the status holds its value.
    assert_eq!(b.status().data_points[5].value, Some(Value::Int(77)));
}

#[test]
fn an_unknown_command_is_said_with_its_bytes_and_not_answered() {
    let mut b = Bench::new(TuyaConfig::default());
    b.link();
    b.mcu.sim().take_answers();
    b.mcu.sim().send_frame(0x99, vec![1, 2, 3]);
    b.mcu
        .sim()
        .request(botbench::sim::tuya_mcu::McuRequest::Extended(0x36));
    let mut seen = Vec::new();
    next_event(b.link(), "the two unknown frames said", |e| {
        if let LinkEvent::Tuya(TuyaEvent::McuUnknown {
            command,
            what,
            data,
            ..
        }) = e
        {
            seen.push((command, what, data));
        }
        (seen.len() == 2).then_some(())
    });
    assert_eq!(seen[0], (0x99, "command 0x99".into(), vec![1, 2, 3]));
    assert_eq!(seen[1].1, "extended service sub-command 0x36", "{seen:?}");
    // A status query after them: anything the module had written has reached the MCU.
    b.status();
    assert!(
        b.mcu.sim().answers().is_empty(),
        "{:?}",
        b.mcu.sim().answers()
    );
}

#[test]
fn after_stop_heartbeat_the_module_sends_none() {
    let module = TuyaModuleOptions {
        heartbeat: Duration::from_millis(50),
        ..TuyaModuleOptions::default()
    };
    let mut b = Bench::with(
        TuyaConfig::default(),
        LinkOptions {
            tuya: module,
            ..LinkOptions::default()
        },
    );
    b.link();
    b.mcu
        .sim()
        .request(botbench::sim::tuya_mcu::McuRequest::StopHeartbeat);
    next_event(b.link(), "the heartbeat stopped", |e| {
        matches!(e, LinkEvent::Tuya(TuyaEvent::HeartbeatStopped)).then_some(())
    });
    // Ten heartbeat intervals at least, then a query: not one heartbeat went out meanwhile.
    std::thread::sleep(Duration::from_millis(500));
    b.status();
    let mut heartbeats = 0;
    while let Ok(e) = b.link().events().try_recv() {
        if let LinkEvent::Frame(f) = e
            && f.direction == botbench::protocol::Direction::HostToDevice
            && f.frame.as_ref().is_ok_and(|p| p.command == cmd::HEARTBEAT)
        {
            heartbeats += 1;
        }
    }
    assert_eq!(heartbeats, 0);
    assert!(
        b.mcu
            .sim()
            .answers()
            .iter()
            .any(|(c, d)| *c == cmd::HEARTBEAT_STOP && d.is_empty())
    );
}

#[test]
fn a_frame_over_the_maximum_is_refused_as_such() {
    let mut b = Bench::new(TuyaConfig::default());
    let watch = b.client().watch();
    b.mcu.sim().send_oversize(1100);
    let deadline = std::time::Instant::now() + Duration::from_secs(10);
    let refused = loop {
        let left = deadline.saturating_duration_since(std::time::Instant::now());
        match watch.next(left) {
            Some(botbench::link::Watched::Refused(e)) => break e.to_string(),
            Some(_) => {}
            None => panic!("the oversize frame was not refused within 10 s"),
        }
    };
    assert!(
        refused.contains("frame length 1093 is over the cap of 1028"),
        "{refused}"
    );
    // Its data point came again with the query: nothing is missing for it.
    let status = b.status();
    assert!(status.complete(), "{status:?}");
}

// ---------------------------------------------------------------- 5. the simulator's options

#[test]
fn the_simulators_field_options_are_taken_and_bad_ones_refused() {
    let mut sim = SimProcess::start(&[
        "tuya-vacuum",
        "--baud",
        "115200",
        "--report-gap-ms",
        "100-150",
        "--report-unknown-dp",
        "101:value:50",
        "--report-out-of-range",
        "6=150",
        "--sync-reports",
        "--never-report",
        "19",
    ]);
    let profile = profile("tuya-vacuum");
    // The simulator is the process under test (real-time where it may be), this link is not in
    // lockstep with it: its margin is explicit and generous, a loaded test process's threads
    // may wake late.
    let options = LinkOptions {
        margin: Some(Duration::from_secs(1)),
        ..LinkOptions::default()
    };
    let link = Link::open(
        botbench::link::serial::opener(&sim.path, BAUD),
        profile.clone(),
        options,
        None,
    )
    .expect("opens the simulator's pty");
    next_event(&link, "the handshake", |e| {
        matches!(e, LinkEvent::Tuya(TuyaEvent::HandshakeDone)).then_some(())
    });
    let c = link.client();
    let status = ops::query_status(Device::new(&c, &profile)).expect("a status");
    assert_eq!(status.missing, [19]);
    assert_eq!(status.unknown().len(), 1);
    assert_eq!(status.suspect().len(), 1);
    // Its stdin: the MCU's own requests, each answered and said.
    for line in [
        "utc-time",
        "rssi",
        "extended 0x04",
        "send 0x99 01 02",
        "dp 6 70",
    ] {
        sim.type_line(line);
    }
    let mut said = (0, 0);
    next_event(&link, "the requests from stdin", |e| {
        match e {
            LinkEvent::Tuya(TuyaEvent::McuRequest { .. }) => said.0 += 1,
            LinkEvent::Tuya(TuyaEvent::McuUnknown { command: 0x99, .. }) => said.1 += 1,
            _ => {}
        }
        // 0x0c, 0x24, 0x34 and the 0x22 of DP 6.
        (said == (4, 1)).then_some(())
    });
    for bad in [
        ["--report-gap-ms", "150-100"],
        ["--report-unknown-dp", "6:value:1"],
        ["--report-out-of-range", "6"],
        ["--ota-fault", "sometimes"],
    ] {
        let o = run(&["sim", "tuya-vacuum", bad[0], bad[1]]);
        assert_eq!(o.code, 2, "{bad:?}: {}", o.text());
    }
}
