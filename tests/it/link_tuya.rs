//! botbench as the Tuya Wi-Fi module, through the link worker, against the simulated vacuum MCU
//! on a pseudo-terminal.

use botbench::link::session::tuya::{HandshakeStep, TuyaEvent, TuyaModuleOptions};
use botbench::link::{Link, LinkEvent, LinkOptions};
use botbench::ops::Cancel;
use botbench::ops::OpError;
use botbench::ops::tuya::{self as ops, OtaTiming};
use botbench::ops::{Device, Run};
use botbench::profile::{Input, Profile, Value};
use botbench::sim::tuya_mcu::{OtaPacketAnswer, OtaState, TuyaConfig, TuyaMcu};
use std::sync::Arc;
use std::time::Duration;

use crate::support::{Served, image, next_event, open_link, profile, serve, wait_until};

const BAUD: u32 = 115_200;

/// The MCU on its pty and a link to it (which closes first).
struct Bench {
    link: Link,
    mcu: Served<TuyaMcu>,
    profile: Arc<Profile>,
}

impl Bench {
    fn new(cfg: TuyaConfig, module: TuyaModuleOptions) -> Self {
        Self::at(BAUD, cfg, module)
    }

    fn at(baud: u32, cfg: TuyaConfig, module: TuyaModuleOptions) -> Self {
        let profile = profile("tuya-vacuum");
        let mcu = serve(TuyaMcu::new(TuyaConfig {
            baud: Some(baud),
            ..cfg
        }));
        let options = LinkOptions {
            tuya: module,
            ..LinkOptions::default()
        };
        let link = open_link(&mcu, baud, profile.clone(), options);
        Self { link, mcu, profile }
    }

    fn default() -> Self {
        Self::new(TuyaConfig::default(), TuyaModuleOptions::default())
    }

    /// The Tuya events up to the first that `done` accepts.
    fn events_until(&self, what: &str, mut done: impl FnMut(&TuyaEvent) -> bool) -> Vec<TuyaEvent> {
        let mut out = Vec::new();
        next_event(&self.link, what, |ev| {
            let LinkEvent::Tuya(t) = ev else { return None };
            let stop = done(&t);
            out.push(t);
            stop.then_some(())
        });
        out
    }

    fn handshake(&self) -> Vec<TuyaEvent> {
        self.events_until("the handshake", |e| *e == TuyaEvent::HandshakeDone)
    }
}

fn steps(events: &[TuyaEvent]) -> Vec<(HandshakeStep, bool)> {
    events
        .iter()
        .filter_map(|e| match e {
            TuyaEvent::Step { step, result, .. } => Some((*step, result.ok())),
            _ => None,
        })
        .collect()
}

#[test]
fn the_handshake_completes_step_by_step() {
    let bench = Bench::default();
    let events = bench.handshake();
    assert_eq!(events.last(), Some(&TuyaEvent::HandshakeDone), "{events:?}");
    assert_eq!(
        steps(&events),
        HandshakeStep::ALL.map(|s| (s, true)).to_vec()
    );
    let info = events.iter().find_map(|e| match e {
        TuyaEvent::ProductInfo(p) => Some(p.clone()),
        _ => None,
    });
    assert_eq!(info.unwrap().pid.as_deref(), Some("lgldgnmt4ifc.jzex"));
    // The MCU was told the Wi-Fi state, since it drives the LED.
    assert_eq!(bench.mcu.sim().wifi_state(), Some(4));
}

#[test]
fn an_mcu_restart_is_noticed_by_the_heartbeat_and_the_handshake_runs_again() {
    let module = TuyaModuleOptions {
        heartbeat: Duration::from_millis(200),
        ..TuyaModuleOptions::default()
    };
    let bench = Bench::new(TuyaConfig::default(), module);
    bench.handshake();
    bench.mcu.sim().restart();
    let events = bench.handshake();
    assert!(events.contains(&TuyaEvent::McuRestarted), "{events:?}");
    assert_eq!(events.last(), Some(&TuyaEvent::HandshakeDone));
}

#[test]
fn malformed_product_info_is_shown_raw_and_the_handshake_goes_on() {
    let cfg = TuyaConfig {
        product_info_raw: Some(b"{\"p\":\"abc\",\"v\":".to_vec()),
        ..TuyaConfig::default()
    };
    let bench = Bench::new(cfg, TuyaModuleOptions::default());
    let events = bench.handshake();
    assert_eq!(events.last(), Some(&TuyaEvent::HandshakeDone));
    let info = events.iter().find_map(|e| match e {
        TuyaEvent::ProductInfo(p) => Some(p.clone()),
        _ => None,
    });
    let info = info.unwrap();
    assert!(info.error.is_some());
    assert_eq!(info.raw, "{\"p\":\"abc\",\"v\":");
}

#[test]
fn the_mcus_own_requests_are_answered() {
    let fixed = chrono::NaiveDate::from_ymd_opt(2026, 11, 22)
        .unwrap()
        .and_hms_opt(8, 30, 15)
        .unwrap();
    let module = TuyaModuleOptions {
        fixed_time: Some(fixed),
        wifi_test_rssi: 66,
        ..TuyaModuleOptions::default()
    };
    let bench = Bench::new(TuyaConfig::default(), module);
    bench.handshake();
    {
        let mut m = bench.mcu.sim();
        m.request_local_time();
        m.request_wifi_test();
        m.reset_wifi();
        m.reset_wifi_mode(1);
        m.request_net_status();
        m.request_mac();
    }
    let mut answered = 0;
    bench.events_until("six requests answered", |e| {
        if matches!(e, TuyaEvent::McuRequest { .. }) {
            answered += 1;
        }
        answered == 6
    });
    // The last answers may still be on the wire.
    wait_until("the MCU to hold six answers", || {
        bench.mcu.sim().answers().len() >= 6
    });
    let answers = bench.mcu.sim().answers().to_vec();
    let get = |c: u8| {
        answers
            .iter()
            .find(|(cmd, _)| *cmd == c)
            .map(|(_, d)| d.clone())
    };
    // 2026-11-22 is a Sunday: weekday 7.
    assert_eq!(get(0x1c), Some(vec![1, 26, 11, 22, 8, 30, 15, 7]));
    assert_eq!(get(0x0e), Some(vec![1, 66]));
    assert_eq!(get(0x04), Some(vec![]));
    assert_eq!(get(0x05), Some(vec![]));
}

#[test]
fn every_writable_data_point_type_is_set_and_reported_back() {
    let bench = Bench::default();
    bench.handshake();
    let c = bench.link.client();
    let inputs: Vec<(String, Input)> = [
        ("power", "on"),
        ("mode", "spiral"),
        ("suction", "strong"),
        ("find_robot", "on"),
    ]
    .iter()
    .map(|(k, v)| (k.to_string(), Input::from(*v)))
    .collect();
    let checks = ops::set_dps(Device::new(&c, &bench.profile), &inputs).unwrap();
    assert_eq!(checks.len(), 4);
    assert!(checks.iter().all(|c| c.verified()), "{checks:?}");
    assert_eq!(
        bench.mcu.sim().dp(3).map(|v| format!("{v:?}")),
        Some("Enum(5)".into())
    );
    // The status query reports all 19.
    let status = ops::query_status(Device::new(&c, &bench.profile)).unwrap();
    assert_eq!(status.data_points.len(), 19);
    assert!(status.complete(), "{status:?}");
}

#[test]
fn a_wrong_typed_or_report_only_data_point_is_refused_before_sending() {
    let bench = Bench::default();
    bench.handshake();
    let c = bench.link.client();
    for (k, v) in [
        ("battery", "50"),
        ("mode", "7.5"),
        ("power", "maybe"),
        ("nope", "1"),
    ] {
        let err = ops::set_dps(
            Device::new(&c, &bench.profile),
            &[(k.into(), Input::from(v))],
        )
        .unwrap_err();
        assert!(err.is_input(), "{k}={v}: {err}");
    }
    // A raw value of the wrong kind is refused too.
    let err = ops::set_dps(
        Device::new(&c, &bench.profile),
        &[("mode".into(), Input::Raw(Value::Text("x".into())))],
    )
    .unwrap_err();
    assert!(matches!(err, OpError::Value(_)), "{err}");
}

#[test]
fn a_64_kib_image_arrives_intact_at_each_packet_size() {
    for answer in [
        OtaPacketAnswer::Option(0),
        OtaPacketAnswer::Option(1),
        OtaPacketAnswer::Option(2),
        OtaPacketAnswer::Empty,
    ] {
        // At 921600 baud to keep the test short; the benchmark measures 9600 and 115200.
        let bench = Bench::at(
            921_600,
            TuyaConfig {
                ota_packet: answer,
                ..TuyaConfig::default()
            },
            TuyaModuleOptions::default(),
        );
        let hs = bench.handshake();
        assert_eq!(
            hs.last(),
            Some(&TuyaEvent::HandshakeDone),
            "{answer:?}: {hs:?}"
        );
        let img = image(65_536);
        let report = ops::ota(
            &bench.link.client(),
            &img,
            bench.profile.ota_max_bytes(),
            OtaTiming::default(),
            &mut Run::quiet(&Cancel::new()),
        )
        .unwrap();
        let want = match answer {
            OtaPacketAnswer::Option(1) => 512,
            OtaPacketAnswer::Option(2) => 1024,
            _ => 256,
        };
        assert_eq!(report.packet_size, want);
        let mcu = bench.mcu.sim();
        assert!(
            matches!(mcu.ota_state(), OtaState::Complete { size: 65_536, .. }),
            "{:?}",
            mcu.ota_state()
        );
        assert_eq!(mcu.ota_image(), img.as_slice());
    }
}

#[test]
fn an_mcu_that_stops_acking_ends_the_upload_with_the_offset_named() {
    let bench = Bench::new(
        TuyaConfig {
            ota_packet: OtaPacketAnswer::Option(2),
            stop_acking_at: Some(8192),
            ..TuyaConfig::default()
        },
        TuyaModuleOptions::default(),
    );
    bench.handshake();
    let timing = OtaTiming {
        ack_wait: Duration::from_millis(150),
        retries: 3,
    };
    let err = ops::ota(
        &bench.link.client(),
        &image(65_536),
        bench.profile.ota_max_bytes(),
        timing,
        &mut Run::quiet(&Cancel::new()),
    )
    .unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("offset 8192") && msg.contains("4 attempts"),
        "{msg}"
    );
}

#[test]
fn an_empty_image_is_refused() {
    let bench = Bench::default();
    let err = ops::ota(
        &bench.link.client(),
        &[],
        bench.profile.ota_max_bytes(),
        OtaTiming::default(),
        &mut Run::quiet(&Cancel::new()),
    )
    .unwrap_err();
    assert!(matches!(err, OpError::EmptyImage), "{err}");
}

/// A request whose answer is optional and that nothing answers has no round trip: how long
/// the link waited for none is no answer time (before: the wait, and a whole-process stall
/// during it, counted as the MCU's slowest answer in `tuya conform`).
#[test]
fn an_optional_answer_that_never_came_has_no_round_trip() {
    use botbench::link::{Match, ReplySpec, Request};
    use botbench::protocol::tuya::cmd;
    let bench = Bench::default();
    bench.handshake();
    // DP 6 (battery) is report-only: the MCU drops a command for it, and no report answers.
    let request = Request::new(cmd::DP_COMMAND, vec![6, 2, 0, 4, 0, 0, 0, 50])
        .reply(ReplySpec::Optional(Match::command(cmd::DP_REPORT)))
        .margin(Duration::from_millis(200))
        .attempts(1);
    let reply = bench.link.client().request(request).expect("no error");
    assert!(reply.packets.is_empty(), "{reply:?}");
    assert_eq!(reply.rtt, Duration::ZERO);
}
