//! The sessions as state machines, without a port: each request they ask for is answered by hand.

use super::tuya::{HandshakeStep, TuyaEvent, TuyaModuleOptions};
use super::{Precedence, ProtocolSession, Unasked};
use crate::link::request::{ExchangeError, Reply, Request};
use crate::link::{LinkEvent, LinkOptions};
use crate::packet::Packet;
use crate::profile::{Profile, Registry};
use crate::protocol::{msp, servo, tuya};
use std::sync::Arc;
use std::time::{Duration, Instant};

fn profile(name: &str) -> Arc<Profile> {
    Registry::builtin().unwrap().get(name).unwrap()
}

fn session(name: &str, options: &LinkOptions) -> ProtocolSession {
    ProtocolSession::new(profile(name), options, Instant::now())
}

fn answered(p: Packet) -> Result<Reply, ExchangeError> {
    Ok(Reply {
        packets: vec![p],
        rtt: Duration::ZERO,
        attempts: 1,
    })
}

fn msp_answer(command: u8, data: &[u8]) -> Result<Reply, ExchangeError> {
    answered(Packet::msp_reply(msp::Reply::new(command, data.to_vec())))
}

fn mcu_answer(command: u8, data: &[u8]) -> Result<Reply, ExchangeError> {
    answered(Packet::tuya(tuya::Frame::from_mcu(command, data.to_vec())))
}

fn timeout(command: u8) -> Result<Reply, ExchangeError> {
    Err(ExchangeError::Timeout {
        command,
        attempts: 2,
        waited_ms: 20,
    })
}

/// Takes the session's next request at `now`, checks its command, and answers it.
fn step(
    s: &mut ProtocolSession,
    now: Instant,
    command: u8,
    result: Result<Reply, ExchangeError>,
    events: &mut Vec<LinkEvent>,
) -> (Request, bool) {
    let request = s.next_request(now, 115_200).expect("a request is due");
    assert_eq!(request.command, command, "{request:?}");
    let more = s.on_answer(result, now, events);
    (request, more)
}

const VERSION: [u8; 8] = [0x07, 1, 2, 3, 4, 5, 6, 0x0f];

#[test]
fn msp_identifies_before_requests_and_learns_the_device_code() {
    let mut s = session("window-cleaner", &LinkOptions::default());
    let now = Instant::now();
    assert_eq!(s.due(now), Some(Precedence::BeforeRequests));
    let mut events = Vec::new();
    let (version, more) = step(
        &mut s,
        now,
        msp::CMD_VERSION,
        msp_answer(msp::CMD_VERSION, &VERSION),
        &mut events,
    );
    assert_eq!(version.device, Some(msp::DEVICE_CORE));
    assert!(more, "CMD_BUILD_INFO follows at once");
    assert!(events.is_empty());
    let date = b"2025-03-1412:30:00";
    let (_, more) = step(
        &mut s,
        now,
        msp::CMD_BUILD_INFO,
        msp_answer(msp::CMD_BUILD_INFO, date),
        &mut events,
    );
    assert!(!more);
    let [LinkEvent::Identified(Ok(info))] = events.as_slice() else {
        panic!("{events:?}");
    };
    assert_eq!(
        (info.hw, info.firmware.as_str(), info.api.as_str()),
        (7, "1.2.3", "4.5")
    );
    assert_eq!(info.build_date.as_deref(), Some("2025-03-14 12:30:00"));
    assert_eq!(s.due(now), None);
    // Later requests go to the hardware code the device named (the profile says Auto).
    let (bytes, _) = s.encode(&Request::new(0x20, Vec::new())).unwrap();
    assert_eq!(
        bytes,
        msp::Request::new(0x07, 0x20, Vec::new()).encode().unwrap()
    );
}

#[test]
fn an_msp_identify_without_build_info_still_identifies_and_a_failed_one_says_why() {
    let mut s = session("window-cleaner", &LinkOptions::default());
    let now = Instant::now();
    let mut events = Vec::new();
    step(
        &mut s,
        now,
        msp::CMD_VERSION,
        msp_answer(msp::CMD_VERSION, &VERSION),
        &mut events,
    );
    step(
        &mut s,
        now,
        msp::CMD_BUILD_INFO,
        timeout(msp::CMD_BUILD_INFO),
        &mut events,
    );
    assert!(
        matches!(&events[..], [LinkEvent::Identified(Ok(i))] if i.build_date.is_none()),
        "{events:?}"
    );

    // Asked again: a too-short answer ends it with the reason, and no CMD_BUILD_INFO.
    s.identify_again();
    events.clear();
    let (_, more) = step(
        &mut s,
        now,
        msp::CMD_VERSION,
        msp_answer(msp::CMD_VERSION, &[3, 1]),
        &mut events,
    );
    assert!(!more);
    assert!(
        matches!(
            &events[..],
            [LinkEvent::Identified(Err(ExchangeError::Unreadable {
                command: msp::CMD_VERSION,
                ..
            }))]
        ),
        "{events:?}"
    );
    assert_eq!(s.next_request(now, 115_200), None);
}

#[test]
fn msp_identifies_again_on_a_new_connection_only_when_the_options_say_so() {
    let mut s = session("window-cleaner", &LinkOptions::default());
    let now = Instant::now();
    let mut events = Vec::new();
    step(
        &mut s,
        now,
        msp::CMD_VERSION,
        timeout(msp::CMD_VERSION),
        &mut events,
    );
    s.lost("unplugged");
    s.connected(now);
    assert_eq!(s.due(now), Some(Precedence::BeforeRequests));

    let quiet = LinkOptions {
        start_session: false,
        ..LinkOptions::default()
    };
    let mut s = session("window-cleaner", &quiet);
    assert_eq!(s.due(now), None);
    s.connected(now);
    assert_eq!(s.due(now), None);
}

/// Runs a whole Tuya handshake from its first step; the MCU drives the Wi-Fi LED unless `gpio`.
fn handshake(s: &mut ProtocolSession, now: Instant, gpio: Option<[u8; 2]>) -> Vec<LinkEvent> {
    let mut events = Vec::new();
    let (_, more) = step(
        s,
        now,
        tuya::cmd::HEARTBEAT,
        mcu_answer(tuya::cmd::HEARTBEAT, &[0]),
        &mut events,
    );
    assert!(more);
    let info = br#"{"p":"abc","v":"1.0.0","m":0}"#;
    step(
        s,
        now,
        tuya::cmd::PRODUCT_INFO,
        mcu_answer(tuya::cmd::PRODUCT_INFO, info),
        &mut events,
    );
    let mode = gpio.map(|g| g.to_vec()).unwrap_or_default();
    step(
        s,
        now,
        tuya::cmd::WORK_MODE,
        mcu_answer(tuya::cmd::WORK_MODE, &mode),
        &mut events,
    );
    if gpio.is_none() {
        let (req, _) = step(
            s,
            now,
            tuya::cmd::WIFI_STATE,
            mcu_answer(tuya::cmd::WIFI_STATE, &[]),
            &mut events,
        );
        assert_eq!(req.payload, vec![4], "the Wi-Fi state of the options");
    }
    let report = mcu_answer(tuya::cmd::DP_REPORT, &[1, 1, 0, 1, 1]);
    let (_, more) = step(s, now, tuya::cmd::QUERY_STATUS, report, &mut events);
    assert!(!more);
    events
}

fn steps(events: &[LinkEvent]) -> Vec<(HandshakeStep, bool)> {
    events
        .iter()
        .filter_map(|e| match e {
            LinkEvent::Tuya(TuyaEvent::Step { step, ok, .. }) => Some((*step, *ok)),
            _ => None,
        })
        .collect()
}

#[test]
fn the_tuya_handshake_runs_every_step_in_order_then_beats() {
    let options = LinkOptions::default();
    let mut s = session("tuya-vacuum", &options);
    let now = Instant::now();
    assert_eq!(s.due(now), Some(Precedence::AfterRequests));
    let events = handshake(&mut s, now, None);
    assert_eq!(
        steps(&events),
        HandshakeStep::ALL.map(|s| (s, true)).to_vec()
    );
    assert!(matches!(
        events.last(),
        Some(LinkEvent::Tuya(TuyaEvent::HandshakeDone))
    ));
    // The heartbeat comes one interval later.
    assert_eq!(s.due(now), None);
    let later = now + options.tuya.heartbeat;
    let mut events = Vec::new();
    let (_, more) = step(
        &mut s,
        later,
        tuya::cmd::HEARTBEAT,
        mcu_answer(tuya::cmd::HEARTBEAT, &[1]),
        &mut events,
    );
    assert!(!more && events.is_empty(), "{events:?}");
}

#[test]
fn a_module_that_drives_the_led_skips_the_wifi_state() {
    let mut s = session("tuya-vacuum", &LinkOptions::default());
    let events = handshake(&mut s, Instant::now(), Some([14, 0]));
    assert_eq!(
        steps(&events),
        HandshakeStep::ALL.map(|s| (s, true)).to_vec()
    );
    assert!(events.iter().any(|e| matches!(
        e,
        LinkEvent::Tuya(TuyaEvent::WorkMode {
            gpio: Some((14, 0))
        })
    )));
}

#[test]
fn a_failed_step_ends_the_handshake_and_it_starts_again_a_second_later() {
    let mut s = session("tuya-vacuum", &LinkOptions::default());
    let now = Instant::now();
    let mut events = Vec::new();
    step(
        &mut s,
        now,
        tuya::cmd::HEARTBEAT,
        mcu_answer(tuya::cmd::HEARTBEAT, &[1]),
        &mut events,
    );
    let (_, more) = step(
        &mut s,
        now,
        tuya::cmd::PRODUCT_INFO,
        timeout(tuya::cmd::PRODUCT_INFO),
        &mut events,
    );
    assert!(!more);
    assert_eq!(
        steps(&events),
        vec![
            (HandshakeStep::Heartbeat, true),
            (HandshakeStep::ProductInfo, false)
        ]
    );
    assert_eq!(s.due(now), None);
    assert!(s.due(now + Duration::from_secs(1)).is_some());
    // It starts from the first step.
    handshake(&mut s, now + Duration::from_secs(1), None);
}

#[test]
fn a_heartbeat_answered_0_means_the_mcu_restarted_and_a_missed_one_is_reported() {
    let options = LinkOptions::default();
    let beat = options.tuya.heartbeat;
    let mut s = session("tuya-vacuum", &options);
    let now = Instant::now();
    handshake(&mut s, now, None);
    let mut events = Vec::new();
    step(
        &mut s,
        now + beat,
        tuya::cmd::HEARTBEAT,
        timeout(tuya::cmd::HEARTBEAT),
        &mut events,
    );
    assert!(
        matches!(&events[..], [LinkEvent::Tuya(TuyaEvent::HeartbeatLost)]),
        "{events:?}"
    );
    events.clear();
    let again = now + beat + Duration::from_secs(3);
    step(
        &mut s,
        again,
        tuya::cmd::HEARTBEAT,
        mcu_answer(tuya::cmd::HEARTBEAT, &[0]),
        &mut events,
    );
    assert!(
        matches!(&events[..], [LinkEvent::Tuya(TuyaEvent::McuRestarted)]),
        "{events:?}"
    );
    // The handshake runs again at once, from its first step.
    handshake(&mut s, again, None);
}

#[test]
fn a_lost_port_stops_the_heartbeat_until_the_next_connection() {
    let mut s = session("tuya-vacuum", &LinkOptions::default());
    let now = Instant::now();
    handshake(&mut s, now, None);
    s.lost("unplugged");
    assert_eq!(s.due(now + Duration::from_secs(3600)), None);
    s.connected(now);
    handshake(&mut s, now, None);
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
    let s = session("tuya-vacuum", &options);
    let ask = Packet::tuya(tuya::Frame::from_mcu(tuya::cmd::NET_STATUS, Vec::new()));
    let Unasked::McuRequest { reply, .. } = s.unasked(&ask) else {
        panic!("not answered");
    };
    assert_eq!(
        reply,
        tuya::Frame::from_module(tuya::cmd::NET_STATUS, vec![2])
    );
    let report = Packet::tuya(tuya::Frame::from_mcu(
        tuya::cmd::DP_REPORT,
        vec![1, 1, 0, 1, 1],
    ));
    assert!(matches!(s.unasked(&report), Unasked::Report));
    let late = Packet::tuya(tuya::Frame::from_mcu(tuya::cmd::WORK_MODE, Vec::new()));
    assert!(s.unasked(&late).answers_other());
}

#[test]
fn frames_are_sorted_by_their_own_protocol_only() {
    // An MSP answer numbered like a Tuya MCU request (0x05 is CMD_BUILD_INFO) answers something
    // else all the same; an async message answers nothing.
    let s = session("window-cleaner", &LinkOptions::default());
    let late = Packet::msp_reply(msp::Reply::new(msp::CMD_BUILD_INFO, Vec::new()));
    assert!(s.unasked(&late).answers_other());
    let mut async_msg = msp::Reply::new(0x40, vec![1]);
    async_msg.kind = msp::ReplyKind::Async;
    assert!(matches!(
        s.unasked(&Packet::msp_reply(async_msg)),
        Unasked::Report
    ));

    // A late servo answer is reported and answers something else, whatever its command; our own
    // request read back (a one-wire adapter) is neither.
    let s = session("servo", &LinkOptions::default());
    let late = Packet::servo(servo::Frame::reply(servo::cmd::WRITE_DATA, vec![1, 1]));
    assert!(matches!(s.unasked(&late), Unasked::LateReply));
    let echo = Packet::servo(servo::Frame::request(servo::cmd::WRITE_DATA, vec![1, 1]));
    assert!(matches!(s.unasked(&echo), Unasked::Echo));
    assert!(!s.unasked(&echo).answers_other());
}
