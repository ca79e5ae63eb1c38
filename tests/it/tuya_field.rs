//! botbench as the Tuya Wi-Fi module against MCUs that behave as MCUs in the field do
//! (PROTOCOL_NOTES §4): through pseudo-terminals, on the command line as a user runs it, and
//! through the link.

use botbench::link::{
    Link, LinkError, LinkEvent, LinkOptions, Match, ReplySpec, Request, Transport, TuyaEvent,
};
use botbench::ops::Device;
use botbench::protocol::tuya::{Frame, TuyaDecoder, cmd};
use botbench::sim::Faults;
use botbench::sim::tuya_mcu::{TuyaConfig, TuyaMcu};
use std::time::{Duration, Instant};

use crate::support::cli::{Ran, Sim, run_in_process};
use crate::support::{Served, lossy, next_event, open_link, profile, serve_with, temp_dir};

/// `botbench sim tuya-vacuum ARGS`, served in lockstep with the command line run in this
/// process ([`Sim`]).
fn sim(args: &[&str]) -> Sim {
    let all: Vec<&str> = ["tuya-vacuum"].iter().chain(args).copied().collect();
    Sim::start(&all)
}

/// An MCU at 115200 baud on a pseudo-terminal, in lockstep with the command line run in this
/// process.
fn serve(cfg: TuyaConfig, faults: Faults) -> Served<TuyaMcu> {
    serve_with(
        TuyaMcu::new(TuyaConfig {
            baud: Some(115_200),
            ..cfg
        }),
        faults,
    )
}

/// `botbench tuya --port PATH --baud 115200 ARGS`, `PATH` opened with `ports`.
fn tuya(path: &str, ports: &botbench::link::PortOpener, args: &[&str]) -> Ran {
    let mut all = vec!["tuya", "--port", path, "--baud", "115200"];
    all.extend_from_slice(args);
    run_in_process(&all, ports)
}

// ---------------------------------------------------------------- 1. version byte 0x00

#[test]
fn an_mcu_whose_frames_carry_version_0x00_is_answered_and_its_version_shown() {
    let sim = sim(&["--frame-version", "0", "--baud", "115200"]);
    let o = tuya(&sim.path, sim.ports(), &["init"]);
    assert_eq!(o.code, 0, "{o:?}");
    let out = o.out.clone();
    assert!(out.contains("Heartbeat      ok"), "{out}");
    assert!(
        out.contains("MCU frames carry version 0x00 (the protocol document says 0x03)"),
        "{out}"
    );
    let o = tuya(&sim.path, sim.ports(), &["status", "--json"]);
    assert_eq!(o.code, 0, "{o:?}");
    let doc = o.json();
    assert_eq!(doc["frame_version"], 0);
    assert_eq!(doc["data_points"].as_array().map(Vec::len), Some(19));
}

#[test]
fn on_a_line_that_echoes_the_modules_frames_a_version_0x00_mcu_is_told_apart_by_what_was_sent() {
    let cfg = TuyaConfig {
        frame_version: 0,
        echo: true,
        ..TuyaConfig::default()
    };
    let served = serve(cfg, Faults::default());
    let o = tuya(served.path(), &served.ports(), &["dp", "find_robot=on"]);
    assert_eq!(o.code, 0, "{o:?}");
    assert!(o.out.contains("verified"), "{o:?}");
    // The MCU's requests: a reset-Wi-Fi ack is the very bytes of the request (version 0x00);
    // its echo must not be taken for another request, or the module acks its own ack forever.
    let profile = profile("tuya-vacuum");
    let link = open_link(&served, 115_200, profile.clone(), LinkOptions::default());
    next_event(&link, "the handshake", |e| {
        matches!(e, LinkEvent::Tuya(TuyaEvent::HandshakeDone)).then_some(())
    });
    served.sim().take_answers();
    served.sim().reset_wifi();
    served.sim().request_local_time();
    let mut asked = 0;
    next_event(&link, "the MCU's two requests", |e| {
        asked += usize::from(matches!(e, LinkEvent::Tuya(TuyaEvent::McuRequest { .. })));
        (asked == 2).then_some(())
    });
    // A status query after them: anything the module wrote in between has reached the MCU.
    botbench::ops::tuya::query_status(Device::new(&link.client(), &profile)).unwrap();
    let answers = served.sim().take_answers();
    let commands: Vec<u8> = answers.iter().map(|(c, _)| *c).collect();
    assert_eq!(
        commands,
        [cmd::RESET_WIFI, cmd::LOCAL_TIME],
        "{answers:02x?}"
    );
}

// ---------------------------------------------------------------- 2. a chatty MCU

#[test]
fn an_mcu_that_reports_every_30_ms_is_initialised_queried_and_commanded() {
    // At the profile's 9600 baud, as the issue found it.
    let sim = sim(&["--report-every", "30"]);
    let o = sim.run(&["tuya", "--port", &sim.path, "init"]);
    assert_eq!(o.code, 0, "{o:?}");
    assert_eq!(o.out.matches("  ok  ").count(), 5, "{o:?}");
    let o = sim.run(&["tuya", "--port", &sim.path, "status", "--json"]);
    assert_eq!(o.code, 0, "{o:?}");
    assert_eq!(o.json()["data_points"].as_array().map(Vec::len), Some(19));
    let o = sim.run(&[
        "tuya",
        "--port",
        &sim.path,
        "dp",
        "power=off",
        "find_robot=on",
    ]);
    assert_eq!(o.code, 0, "{o:?}");
    assert_eq!(o.out.matches("verified").count(), 2, "{o:?}");
}

// ---------------------------------------------------------------- 3. another type or length

#[test]
fn data_points_of_another_type_or_length_are_shown_raw_and_status_fails() {
    let sim = sim(&[
        "--misreport",
        "3:value:4",
        "--misreport",
        "1:bool:4",
        "--baud",
        "115200",
    ]);
    let o = tuya(&sim.path, sim.ports(), &["status"]);
    assert_eq!(o.code, 1, "{o:?}");
    let out = o.out.clone();
    assert!(
        out.contains("power (1)                MISFIT raw 00 00 00 01 (bool of 4 byte(s) on the wire; a bool is 1 byte(s); allowed: bool false or true)"),
        "{out}"
    );
    assert!(
        out.contains("mode (3)                 MISFIT raw 00 00 00 00 (type value on the wire, the profile says enum; allowed: enum labels 0 to 11)"),
        "{out}"
    );
    assert!(out.contains("battery"), "the others are listed: {out}");
    let o = tuya(&sim.path, sim.ports(), &["status", "--json"]);
    assert_eq!(o.code, 1, "{o:?}");
    let doc = o.json();
    assert_eq!(doc["complete"], false);
    let points = doc["data_points"].as_array().expect("data points");
    assert_eq!(points.len(), 19);
    let power = points.iter().find(|p| p["id"] == 1).expect("power");
    assert_eq!(power["raw"], "00 00 00 01");
    assert_eq!(power["value"], serde_json::Value::Null);
    assert_eq!(power["misfit"], "length");
    let mode = points.iter().find(|p| p["id"] == 3).expect("mode");
    assert_eq!(mode["misfit"], "type");
    assert!(
        mode["mismatch"]
            .as_str()
            .unwrap_or("")
            .contains("the profile says enum")
    );
}

// ---------------------------------------------------------------- 4. drops and corruption

#[test]
fn under_drops_and_corruption_status_asks_again_or_names_what_is_missing() {
    for seed in 1..=8u64 {
        let served = serve(TuyaConfig::default(), lossy(seed));
        // The handshake's limit is the wall clock's, which two CPU-bound loops beside the suite
        // can stretch past the default 10 s (the link's own timing is the simulator's, in
        // lockstep); this test is about the status query under loss, not that limit.
        let o = tuya(
            served.path(),
            &served.ports(),
            &["--wait", "120", "status", "--json"],
        );
        let doc = o.json();
        let points = doc["data_points"]
            .as_array()
            .unwrap_or_else(|| panic!("seed {seed}: no data points: {o:?}"))
            .len();
        let missing = doc["missing"]
            .as_array()
            .unwrap_or_else(|| panic!("seed {seed}: no missing: {o:?}"))
            .clone();
        match o.code {
            0 => assert_eq!((points, missing.len()), (19, 0), "seed {seed}: {doc}"),
            1 => {
                assert!(!missing.is_empty(), "seed {seed}: {doc}");
                assert!(missing.iter().all(|m| m["dp"].is_string()), "{doc}");
            }
            _ => panic!("seed {seed}: {o:?}"),
        }
    }
}

// ---------------------------------------------------------------- 5. verified

#[test]
fn a_value_the_mcu_changed_back_is_not_verified_though_the_report_of_the_change_was_lost() {
    // The firmware resets the mode when the power goes off, even when the same frame set one,
    // and the report of that change is lost.
    let cfg = TuyaConfig {
        rules_override_command: true,
        lose_rule_reports: true,
        ..TuyaConfig::default()
    };
    let served = serve(cfg, Faults::default());
    let o = tuya(
        served.path(),
        &served.ports(),
        &["dp", "mode=8", "power=off"],
    );
    assert_eq!(o.code, 1, "{o:?}");
    let out = o.out.clone();
    let mode = out
        .lines()
        .find(|l| l.starts_with("mode"))
        .unwrap_or_default();
    assert!(mode.contains("MISMATCH: the MCU reports standby"), "{out}");
    let power = out
        .lines()
        .find(|l| l.starts_with("power"))
        .unwrap_or_default();
    assert!(power.ends_with("verified"), "{out}");
    assert_eq!(
        format!("{:?}", served.sim().dp(3)),
        "Some(Enum(0))",
        "the MCU holds mode 0"
    );
    // A firmware that keeps what it was told: both verified, by the read-back.
    let served = serve(TuyaConfig::default(), Faults::default());
    let o = tuya(
        served.path(),
        &served.ports(),
        &["dp", "mode=8", "power=off", "--json"],
    );
    assert_eq!(o.code, 0, "{o:?}");
    let doc = o.json();
    assert_eq!(doc["verified"], true);
    assert_eq!(doc["data_points"][0]["last"]["value"], 8);
    assert_eq!(format!("{:?}", served.sim().dp(3)), "Some(Enum(8))");
}

// ---------------------------------------------------------------- 6. firmware images

/// A 20 MB firmware file in `dir`, by its size (sparse: nothing to read), as the issue gave it.
pub(crate) fn twenty_mb_image(dir: &std::path::Path) -> std::path::PathBuf {
    let big = dir.join("20mb.bin");
    std::fs::File::create(&big)
        .and_then(|f| f.set_len(20_000_000))
        .unwrap();
    big
}

#[test]
fn an_image_over_the_profiles_maximum_is_refused_before_anything_is_sent() {
    let tmp = temp_dir();
    let dir = tmp.path();
    let big = twenty_mb_image(dir);
    let served = serve(TuyaConfig::default(), Faults::default());
    let big_path = big.display().to_string();
    for (file, said) in [
        (
            big_path.as_str(),
            "20000000 bytes is over the largest image the profile allows (524288 bytes)",
        ),
        (
            "/dev/zero",
            "/dev/zero: not a firmware image file (a folder, a device or a pipe)",
        ),
    ] {
        let o = tuya(served.path(), &served.ports(), &["ota", file]);
        assert_eq!(o.code, 2, "{file}: {o:?}");
        assert!(
            format!("{}{}", o.out, o.err).contains(said),
            "{file}: {o:?}"
        );
    }
    assert_eq!(
        format!("{:?}", served.sim().ota_state()),
        "Idle",
        "nothing reached the MCU"
    );
    // An image that fits: the expected time at the port's rate, before it starts.
    let fw = dir.join("fw.bin");
    std::fs::write(&fw, vec![0x5a; 3000]).unwrap();
    let o = tuya(
        served.path(),
        &served.ports(),
        &[
            "ota",
            "--expect-version",
            "1.0.1",
            &fw.display().to_string(),
        ],
    );
    assert_eq!(o.code, 0, "{o:?}");
    let err = &o.err;
    assert!(
        err.contains("firmware: 3000 bytes: about 0 s at 115200 baud"),
        "{err}"
    );
}

// ---------------------------------------------------------------- 8. the round trip

/// A scripted MCU: answers a status query (0x08) with three reports, the first at once and
/// the other two only after the host has read the first and a while has passed.
struct SlowBurst {
    pending: Vec<Vec<u8>>,
    held: Vec<Vec<u8>>,
    decoder: TuyaDecoder,
}

/// How long the last reports of the scripted burst are held back after the first is read.
const HELD: Duration = Duration::from_millis(120);

impl Transport for SlowBurst {
    fn write(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        self.decoder.push(bytes);
        while let Some(Ok(f)) = self.decoder.next() {
            if f.command == cmd::QUERY_STATUS {
                let report = |id: u8| Frame::from_mcu(cmd::DP_REPORT, vec![id, 1, 0, 1, 1]);
                self.pending.push(report(1).encode().unwrap());
                self.held = vec![report(2).encode().unwrap(), report(13).encode().unwrap()];
            }
        }
        Ok(())
    }

    fn read(&mut self, buf: &mut [u8], deadline: Instant) -> Result<usize, LinkError> {
        let next = if !self.pending.is_empty() {
            self.pending.remove(0)
        } else if !self.held.is_empty() {
            std::thread::sleep(HELD);
            std::mem::take(&mut self.held).concat()
        } else {
            std::thread::sleep(deadline.saturating_duration_since(Instant::now()));
            return Ok(0);
        };
        buf[..next.len()].copy_from_slice(&next);
        Ok(next.len())
    }

    fn set_baud(&mut self, _baud: u32) -> Result<(), LinkError> {
        Ok(())
    }

    fn baud(&self) -> u32 {
        115_200
    }

    fn clear_input(&mut self) -> Result<(), LinkError> {
        Ok(())
    }

    fn describe(&self) -> String {
        "scripted MCU".into()
    }
}

#[test]
fn the_links_round_trip_is_the_first_answers_not_the_end_of_a_burst() {
    let profile = profile("tuya-vacuum");
    let options = LinkOptions {
        start_session: false,
        ..LinkOptions::default()
    };
    let opener = Box::new(|| {
        Ok(Box::new(SlowBurst {
            pending: Vec::new(),
            held: Vec::new(),
            decoder: TuyaDecoder::new(),
        }) as Box<dyn Transport>)
    });
    let link = Link::open(opener, profile, options, None).unwrap();
    let request = Request::new(cmd::QUERY_STATUS, Vec::new()).reply(ReplySpec::Burst {
        each: Match::command(cmd::DP_REPORT),
        quiet: Duration::from_millis(300),
    });
    let reply = link.client().request(request).unwrap();
    assert_eq!(reply.packets.len(), 3);
    assert!(
        reply.rtt >= HELD,
        "the reply lasts to its last frame: {reply:?}"
    );
    let rtt = next_event(&link, "the link's round trip", |e| match e {
        LinkEvent::Stats(s) => s.rtt,
        _ => None,
    });
    // The link's round trip ends at the first report, read before the others were let go.
    assert!(
        rtt + HELD <= reply.rtt,
        "round trip {rtt:?}, reply {:?}",
        reply.rtt
    );
}

#[test]
fn the_bench_times_the_handshake_against_a_chatty_mcu_beside_a_quiet_one() {
    let every = Duration::from_millis(30);
    let quiet = botbench::bench::tuya_handshake(9600, None).expect("quiet MCU");
    let chatty = botbench::bench::tuya_handshake(9600, Some(every)).expect("chatty MCU");
    assert!(chatty.name.contains("every 30 ms"), "{}", chatty.name);
    // The handshake's own frames are on the line in both; the chatty MCU adds its reports.
    assert!(quiet.wire_seconds > 0.0, "{quiet:?}");
    assert!(
        chatty.wire_seconds > quiet.wire_seconds,
        "{quiet:?} {chatty:?}"
    );
}
