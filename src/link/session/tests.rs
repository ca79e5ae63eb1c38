//! The sessions as state machines, without a port: each request they ask for is answered by hand.

use super::tuya::{HandshakeStep, TuyaEvent, TuyaModuleOptions};
use super::{Precedence, ProtocolSession, Unasked};
use crate::link::request::{ExchangeError, Reply, Request};
use crate::link::{LinkEvent, LinkOptions};
use crate::packet::Packet;
use crate::profile::Registry;
use crate::protocol::{msp, servo, tuya};
use std::time::{Duration, Instant};

use msp::{CMD_BUILD_INFO, CMD_VERSION};
use tuya::cmd::{HEARTBEAT, PRODUCT_INFO, QUERY_STATUS, WIFI_STATE, WORK_MODE};

/// A session and the clock it is driven at, with what it reported.
struct Driver {
    s: ProtocolSession,
    now: Instant,
    events: Vec<LinkEvent>,
}

impl Driver {
    fn new(profile: &str, options: &LinkOptions) -> Self {
        let profile = Registry::builtin().unwrap().get(profile).unwrap();
        let now = Instant::now();
        Self {
            s: ProtocolSession::new(profile, options, now),
            now,
            events: Vec::new(),
        }
    }

    /// Takes the session's next request, checks its command, and answers it with `result`.
    /// Returns the request and whether the session's next request follows at once.
    fn answer(&mut self, command: u8, result: Result<Reply, ExchangeError>) -> (Request, bool) {
        let request = self.s.next_request(self.now).expect("a request due");
        assert_eq!(request.command, command, "{request:?}");
        let more = self.s.on_answer(result, self.now, &mut self.events);
        (request, more)
    }

    /// Runs a whole Tuya handshake from its first step and returns what it reported; the MCU
    /// drives the Wi-Fi LED unless it names the module's `gpio`.
    fn handshake(&mut self, gpio: Option<[u8; 2]>) -> Vec<LinkEvent> {
        self.events.clear();
        assert!(self.answer(HEARTBEAT, mcu(HEARTBEAT, &[0])).1);
        let info = br#"{"p":"abc","v":"1.0.0","m":0}"#;
        self.answer(PRODUCT_INFO, mcu(PRODUCT_INFO, info));
        let mode = gpio.map(|g| g.to_vec()).unwrap_or_default();
        self.answer(WORK_MODE, mcu(WORK_MODE, &mode));
        if gpio.is_none() {
            let (request, _) = self.answer(WIFI_STATE, mcu(WIFI_STATE, &[]));
            assert_eq!(request.payload, vec![4], "the Wi-Fi state of the options");
        }
        // Every data point of the vacuum, in one report (their types do not matter here).
        let all: Vec<u8> = (1..=19).flat_map(|id| [id, 1, 0, 1, 1]).collect();
        let report = mcu(tuya::cmd::DP_REPORT, &all);
        assert!(!self.answer(QUERY_STATUS, report).1);
        std::mem::take(&mut self.events)
    }
}

fn answered(p: Packet) -> Result<Reply, ExchangeError> {
    Ok(Reply {
        packets: vec![p],
        rtt: Duration::ZERO,
        attempts: 1,
    })
}

/// An MSP device's answer.
fn device(command: u8, data: &[u8]) -> Result<Reply, ExchangeError> {
    answered(Packet::msp_reply(msp::Reply::new(command, data.to_vec())))
}

/// A Tuya MCU's answer.
fn mcu(command: u8, data: &[u8]) -> Result<Reply, ExchangeError> {
    answered(Packet::tuya(tuya::Frame::from_mcu(command, data.to_vec())))
}

fn timeout(command: u8) -> Result<Reply, ExchangeError> {
    Err(ExchangeError::Timeout {
        command: command.into(),
        attempts: 2,
        waited_ms: 20,
        host_late: None,
    })
}

fn steps(events: &[LinkEvent]) -> Vec<(HandshakeStep, bool)> {
    events
        .iter()
        .filter_map(|e| match e {
            LinkEvent::Tuya(TuyaEvent::Step { step, result, .. }) => Some((*step, result.ok())),
            _ => None,
        })
        .collect()
}

/// A CMD_VERSION answer: hardware 7, firmware 1.2.3, API 4.5, build 6, every capability flag.
const VERSION: [u8; 8] = [0x07, 1, 2, 3, 4, 5, 6, 0x0f];

#[test]
fn msp_identifies_before_requests_and_learns_the_device_code() {
    let mut d = Driver::new("window-cleaner", &LinkOptions::default());
    assert_eq!(d.s.due(d.now), Some(Precedence::BeforeRequests));
    let (version, more) = d.answer(CMD_VERSION, device(CMD_VERSION, &VERSION));
    assert_eq!(version.device, Some(msp::DEVICE_CORE));
    assert!(
        more && d.events.is_empty(),
        "CMD_BUILD_INFO follows at once"
    );
    let date = b"2025-03-1412:30:00";
    assert!(!d.answer(CMD_BUILD_INFO, device(CMD_BUILD_INFO, date)).1);
    let [LinkEvent::Identified(Ok(info))] = d.events.as_slice() else {
        panic!("{:?}", d.events);
    };
    let read = (info.hw, info.firmware.as_str(), info.api.as_str());
    assert_eq!(read, (7, "1.2.3", "4.5"));
    assert_eq!(info.build_date.as_deref(), Some("2025-03-14 12:30:00"));
    assert_eq!(d.s.due(d.now), None);
    // Core requests go to the hardware code the device named (the profile says Auto)...
    let (bytes, _) =
        d.s.encode(&Request::new(msp::CMD_PING, Vec::new()))
            .unwrap();
    let to_7 = msp::Request::new(0x07, msp::CMD_PING, Vec::new())
        .encode()
        .unwrap();
    assert_eq!(bytes, to_7);
    // ...and nothing else: hardware 7 is not what the window cleaner's profile is for (issue
    // 25, 4d).
    let refused = d.s.encode(&Request::new(0x20, Vec::new()));
    assert!(
        matches!(
            refused,
            Err(ExchangeError::NotThisDevice {
                command: crate::link::CommandName { id: 0x20, .. },
                hw: 7,
                claimed: 3,
                ..
            })
        ),
        "{refused:?}"
    );
}

#[test]
fn an_msp_identify_without_build_info_still_identifies_and_a_failed_one_says_why() {
    let mut d = Driver::new("window-cleaner", &LinkOptions::default());
    d.answer(CMD_VERSION, device(CMD_VERSION, &VERSION));
    d.answer(CMD_BUILD_INFO, timeout(CMD_BUILD_INFO));
    let events = std::mem::take(&mut d.events);
    let identified =
        matches!(&events[..], [LinkEvent::Identified(Ok(i))] if i.build_date.is_none());
    assert!(identified, "{events:?}");

    // Asked again: a too-short answer ends it with the reason, and no CMD_BUILD_INFO.
    d.s.identify_again();
    assert!(!d.answer(CMD_VERSION, device(CMD_VERSION, &[3, 1])).1);
    let unreadable = matches!(
        &d.events[..],
        [LinkEvent::Identified(Err(ExchangeError::Unreadable {
            command: crate::link::CommandName {
                id: CMD_VERSION,
                ..
            },
            ..
        }))]
    );
    assert!(unreadable, "{:?}", d.events);
    assert!(
        format!("{:?}", d.events).contains("\"CMD_VERSION\""),
        "named by the profile: {:?}",
        d.events
    );
    assert_eq!(d.s.next_request(d.now), None);
}

#[test]
fn msp_identifies_again_on_a_new_connection_only_when_the_options_say_so() {
    let mut d = Driver::new("window-cleaner", &LinkOptions::default());
    d.answer(CMD_VERSION, timeout(CMD_VERSION));
    d.s.lost("unplugged");
    d.s.connected(d.now);
    assert_eq!(d.s.due(d.now), Some(Precedence::BeforeRequests));

    let quiet = LinkOptions {
        start_session: false,
        ..LinkOptions::default()
    };
    let mut d = Driver::new("window-cleaner", &quiet);
    assert_eq!(d.s.due(d.now), None);
    d.s.connected(d.now);
    assert_eq!(d.s.due(d.now), None);
}

#[test]
fn the_tuya_handshake_runs_every_step_in_order_then_beats() {
    let options = LinkOptions::default();
    let mut d = Driver::new("tuya-vacuum", &options);
    assert_eq!(d.s.due(d.now), Some(Precedence::AfterRequests));
    let events = d.handshake(None);
    assert_eq!(
        steps(&events),
        HandshakeStep::ALL.map(|s| (s, true)).to_vec()
    );
    let done = matches!(
        events.last(),
        Some(LinkEvent::Tuya(TuyaEvent::HandshakeDone))
    );
    assert!(done, "{events:?}");
    // The heartbeat comes one interval later, and an answer 1 is all well.
    assert_eq!(d.s.due(d.now), None);
    d.now += options.tuya.heartbeat;
    assert!(!d.answer(HEARTBEAT, mcu(HEARTBEAT, &[1])).1);
    assert!(d.events.is_empty(), "{:?}", d.events);
}

#[test]
fn a_new_heartbeat_interval_moves_the_heartbeat_already_scheduled() {
    let options = LinkOptions::default();
    let mut d = Driver::new("tuya-vacuum", &options);
    d.handshake(None);
    let short = Duration::from_millis(300);
    assert!(short < options.tuya.heartbeat, "test setup");
    d.s.set_tuya_options(TuyaModuleOptions {
        heartbeat: short,
        ..options.tuya.clone()
    });
    assert_eq!(d.s.due(d.now + short - Duration::from_millis(1)), None);
    d.now += short;
    d.answer(HEARTBEAT, mcu(HEARTBEAT, &[1]));
    // A longer one waits longer, from the last heartbeat.
    d.s.set_tuya_options(options.tuya.clone());
    assert_eq!(d.s.due(d.now + short), None);
    d.now += options.tuya.heartbeat;
    d.answer(HEARTBEAT, mcu(HEARTBEAT, &[1]));
}

#[test]
fn a_module_that_drives_the_led_skips_the_wifi_state() {
    let mut d = Driver::new("tuya-vacuum", &LinkOptions::default());
    let events = d.handshake(Some([14, 0]));
    assert_eq!(
        steps(&events),
        HandshakeStep::ALL.map(|s| (s, true)).to_vec()
    );
    let told = |e: &LinkEvent| {
        matches!(
            e,
            LinkEvent::Tuya(TuyaEvent::WorkMode {
                gpio: Some((14, 0))
            })
        )
    };
    assert!(events.iter().any(told), "{events:?}");
}

#[test]
fn a_failed_step_ends_the_handshake_and_it_starts_again_a_second_later() {
    let mut d = Driver::new("tuya-vacuum", &LinkOptions::default());
    d.answer(HEARTBEAT, mcu(HEARTBEAT, &[1]));
    assert!(!d.answer(PRODUCT_INFO, timeout(PRODUCT_INFO)).1);
    let expected = vec![
        (HandshakeStep::Heartbeat, true),
        (HandshakeStep::ProductInfo, false),
    ];
    assert_eq!(steps(&d.events), expected);
    assert_eq!(d.s.due(d.now), None);
    d.now += Duration::from_secs(1);
    // It starts again from the first step.
    d.handshake(None);
}

#[test]
fn a_heartbeat_answered_0_means_the_mcu_restarted_and_a_missed_one_is_reported() {
    let options = LinkOptions::default();
    let mut d = Driver::new("tuya-vacuum", &options);
    d.handshake(None);
    d.now += options.tuya.heartbeat;
    d.answer(HEARTBEAT, timeout(HEARTBEAT));
    let lost = matches!(&d.events[..], [LinkEvent::Tuya(TuyaEvent::HeartbeatLost)]);
    assert!(lost, "{:?}", d.events);
    d.events.clear();
    d.now += Duration::from_secs(3);
    d.answer(HEARTBEAT, mcu(HEARTBEAT, &[0]));
    let restarted = matches!(&d.events[..], [LinkEvent::Tuya(TuyaEvent::McuRestarted)]);
    assert!(restarted, "{:?}", d.events);
    // The handshake runs again at once, from its first step.
    d.handshake(None);
}

#[test]
fn a_lost_port_stops_the_heartbeat_until_the_next_connection() {
    let mut d = Driver::new("tuya-vacuum", &LinkOptions::default());
    d.handshake(None);
    d.s.lost("unplugged");
    assert_eq!(d.s.due(d.now + Duration::from_secs(3600)), None);
    d.s.connected(d.now);
    d.handshake(None);
}

#[test]
fn the_mcus_own_requests_are_answered_with_the_module_options() {
    let options = LinkOptions {
        tuya: TuyaModuleOptions {
            net_status: 2,
            ..TuyaModuleOptions::default()
        },
        ..LinkOptions::default()
    };
    let mut s = Driver::new("tuya-vacuum", &options).s;
    let ask = Packet::tuya(tuya::Frame::from_mcu(tuya::cmd::NET_STATUS, Vec::new()));
    let Unasked::McuRequest { reply, .. } = s.unasked(&ask) else {
        panic!("not answered");
    };
    assert_eq!(
        reply,
        Some(tuya::Frame::from_module(tuya::cmd::NET_STATUS, vec![2]))
    );
    // A synchronous report is a report, answered 0x23.
    let sync = Packet::tuya(tuya::Frame::from_mcu(0x22, vec![6, 2, 0, 4, 0, 0, 0, 85]));
    let Unasked::McuRequest { reply, report, .. } = s.unasked(&sync) else {
        panic!("not answered");
    };
    assert!(report);
    assert_eq!(reply, Some(tuya::Frame::from_module(0x23, vec![1])));
    // A command nobody knows is ignored, and said with its bytes.
    let odd = Packet::tuya(tuya::Frame::from_mcu(0x99, vec![1, 2]));
    assert!(matches!(s.unasked(&odd), Unasked::Ignored(_)));
    let report = tuya::Frame::from_mcu(tuya::cmd::DP_REPORT, vec![1, 1, 0, 1, 1]);
    assert!(matches!(s.unasked(&Packet::tuya(report)), Unasked::Report));
    let late = Packet::tuya(tuya::Frame::from_mcu(WORK_MODE, Vec::new()));
    assert!(s.unasked(&late).answers_other());
}

#[test]
fn frames_are_sorted_by_their_own_protocol_only() {
    // An MSP answer numbered like a Tuya MCU request (0x05 is CMD_BUILD_INFO) answers something
    // else all the same; an async message answers nothing.
    let mut s = Driver::new("window-cleaner", &LinkOptions::default()).s;
    let late = Packet::msp_reply(msp::Reply::new(CMD_BUILD_INFO, Vec::new()));
    assert!(s.unasked(&late).answers_other());
    let mut async_msg = msp::Reply::new(0x40, vec![1]);
    async_msg.kind = msp::ReplyKind::Async;
    let unasked = s.unasked(&Packet::msp_reply(async_msg));
    assert!(matches!(unasked, Unasked::Report), "{unasked:?}");

    // A late servo answer is reported and answers something else, whatever its command; our own
    // request read back (a one-wire adapter) is neither.
    let mut s = Driver::new("servo", &LinkOptions::default()).s;
    let late = Packet::servo(servo::Frame::reply(servo::cmd::WRITE_DATA, vec![1, 1]));
    assert!(matches!(s.unasked(&late), Unasked::LateReply));
    let echo = Packet::servo(servo::Frame::request(servo::cmd::WRITE_DATA, vec![1, 1]));
    assert!(matches!(s.unasked(&echo), Unasked::Echo));
    assert!(!s.unasked(&echo).answers_other());
}

#[test]
fn the_tuya_session_reports_heartbeats_wifi_states_and_queries_from_the_frames_themselves() {
    let mut d = Driver::new("tuya-vacuum", &LinkOptions::default());
    let sent =
        |command: u8, data: &[u8]| Packet::tuya(tuya::Frame::from_module(command, data.to_vec()));
    let from_mcu = |command: u8, data: &[u8]| {
        Packet::tuya_received(tuya::Frame::from_mcu(command, data.to_vec()))
    };
    let tuya_event = |ev: Option<LinkEvent>| match ev {
        Some(LinkEvent::Tuya(t)) => Some(t),
        _ => None,
    };
    assert_eq!(
        tuya_event(d.s.wrote(&sent(WIFI_STATE, &[3]))),
        Some(TuyaEvent::WifiStateSent { state: 3 })
    );
    assert_eq!(
        tuya_event(d.s.wrote(&sent(QUERY_STATUS, &[]))),
        Some(TuyaEvent::StatusQueried)
    );
    assert_eq!(tuya_event(d.s.wrote(&sent(HEARTBEAT, &[]))), None);
    let (_, ev) = d.s.received(from_mcu(HEARTBEAT, &[1]));
    assert_eq!(
        tuya_event(ev),
        Some(TuyaEvent::Heartbeat { answer: Some(1) })
    );
    let (_, ev) = d.s.received(from_mcu(WIFI_STATE, &[]));
    assert_eq!(tuya_event(ev), Some(TuyaEvent::WifiStateAcked));
    let (_, ev) =
        d.s.received(from_mcu(tuya::cmd::DP_REPORT, &[1, 1, 0, 1, 1]));
    assert_eq!(tuya_event(ev), None);
    // On a line that echoes, the module's own heartbeat read back is no answer from the MCU.
    let mut d = Driver::new("tuya-vacuum", &LinkOptions::default());
    d.s.wrote(&sent(HEARTBEAT, &[]));
    let echo = Packet::tuya_received(tuya::Frame::from_module(HEARTBEAT, Vec::new()));
    let (p, ev) = d.s.received(echo);
    assert_eq!(p.direction, crate::protocol::Direction::HostToDevice);
    assert_eq!(tuya_event(ev), None);
}
