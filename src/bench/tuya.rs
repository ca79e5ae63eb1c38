//! The Tuya cases of `botbench bench`: a firmware update (OTA) against the wire limit, a data
//! point's command to its report against the wire time plus the MCU's latency, and the module's
//! start-up handshake against a quiet and a chatty MCU.

use super::{Figure, open, profile};
use crate::link::{LinkEvent, LinkOptions, Match, ReplySpec, Request, wire_time};
use crate::ops::Cancel;
use crate::ops::Run;
use crate::ops::tuya::{self as tuya_ops, OtaTiming};
use crate::profile::{Input, Value};
use crate::protocol::Direction;
use crate::protocol::tuya::cmd as tuya_cmd;
use crate::sim::tuya_mcu::{DEFAULT_LATENCY, OtaPacketAnswer, TuyaConfig, TuyaMcu};
use crate::sim::{Faults, PtyServer, SharedDevice};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// A 64 KiB OTA at `baud` with `packet`-byte packets.
pub fn tuya_ota(baud: u32, packet: u8) -> Result<Figure, String> {
    let p = profile("tuya-vacuum")?;
    let mcu: SharedDevice = Arc::new(Mutex::new(TuyaMcu::new(TuyaConfig {
        baud: Some(baud),
        ota_packet: OtaPacketAnswer::Option(packet),
        ..TuyaConfig::default()
    })));
    let server = PtyServer::start(mcu, Faults::default()).map_err(|e| e.to_string())?;
    let opts = LinkOptions {
        start_session: false,
        ..LinkOptions::default()
    };
    let link = open(&server, p, baud, opts)?;
    let image: Vec<u8> = (0..65_536u32).map(|i| (i * 31 % 251) as u8).collect();
    let started = Instant::now();
    let report = tuya_ops::ota(
        &link.client(),
        &image,
        u32::MAX,
        OtaTiming::default(),
        &mut Run::quiet(&Cancel::new()),
    )
    .map_err(|e| e.to_string())?;
    let secs = started.elapsed().as_secs_f64();
    let size = report.packet_size;
    let packets = image.len().div_ceil(size);
    // Start: 11 bytes out, 8 back. Each packet: 7 + 4 + data out, 7 back. Final: 11 out, 7 back.
    let bytes = 11 + 8 + packets * (7 + 4 + 7) + image.len() + 11 + 7;
    let wire = wire_time(bytes, baud).as_secs_f64();
    Ok(Figure::new(
        &format!("tuya ota 64 KiB, {baud} baud, {size}-byte packets"),
        secs,
        wire,
        format!("{} retries", report.retries),
    )
    .at_least_ratio(0.85))
}

/// A data-point command (0x06) to its report (0x07): `find_robot` switched `rounds` times at
/// `baud`, each timed from the request to the report of that data point. The limit is
/// the two frames' wire time plus the MCU's latency.
pub fn tuya_dp_report(baud: u32, rounds: usize) -> Result<Figure, String> {
    let p = profile("tuya-vacuum")?;
    let latency = DEFAULT_LATENCY;
    let mcu: SharedDevice = Arc::new(Mutex::new(TuyaMcu::new(TuyaConfig {
        baud: Some(baud),
        latency,
        ..TuyaConfig::default()
    })));
    let server = PtyServer::start(mcu, Faults::default()).map_err(|e| e.to_string())?;
    // No handshake or heartbeat: nothing else on the wire while the exchanges are timed.
    let opts = LinkOptions {
        start_session: false,
        ..LinkOptions::default()
    };
    let link = open(&server, p.clone(), baud, opts)?;
    let client = link.client();
    let command = p
        .command_by_id(tuya_cmd::DP_COMMAND)
        .ok_or("the profile has no data-point command")?;
    let dp = p
        .find_data_point("find_robot")
        .ok_or("the profile has no find_robot data point")?;
    let rounds = rounds.max(1);
    let (mut total, mut worst, mut rtt) = (0.0f64, 0.0f64, 0.0f64);
    let mut frame_bytes = 0;
    for i in 0..rounds {
        let on = i64::from(i % 2 == 0);
        let inputs = [(dp.field.ident.clone(), Input::Raw(Value::Int(on)))];
        let payload = p
            .encode(command, Direction::HostToDevice, &inputs)
            .map_err(|e| e.to_string())?;
        let report = Match::command(tuya_cmd::DP_REPORT).with_prefix(vec![dp.id]);
        let request = Request::new(tuya_cmd::DP_COMMAND, payload.clone())
            .reply(ReplySpec::Required(report))
            .attempts(1);
        let started = Instant::now();
        let reply = client.request(request).map_err(|e| e.to_string())?;
        let secs = started.elapsed().as_secs_f64();
        let answer = reply.payload().unwrap_or_default();
        if answer.last().map(|b| i64::from(*b)) != Some(on) {
            return Err(format!(
                "the MCU reported {answer:02x?} for find_robot = {on}"
            ));
        }
        total += secs;
        worst = worst.max(secs);
        rtt += reply.rtt.as_secs_f64();
        // Each frame: 55 AA, version, command, length (2), data, checksum.
        frame_bytes = (7 + payload.len()) + (7 + answer.len());
    }
    let mean = total / rounds as f64;
    let wire = wire_time(frame_bytes, baud).as_secs_f64();
    let limit = wire + latency.as_secs_f64();
    // The limit this figure is held to is the bytes' wire time and the MCU's own latency
    // together, so that is its "wire" time and its ratio (1.0 at the limit).
    Ok(Figure::new(
        &format!("tuya dp command to its report, {baud} baud"),
        mean,
        limit,
        format!(
            "mean of {rounds}; worst {:.2} ms, link rtt {:.2} ms; limit {:.2} ms (wire {:.2} ms \
             + MCU latency {:.1} ms)",
            worst * 1e3,
            rtt / rounds as f64 * 1e3,
            limit * 1e3,
            wire * 1e3,
            latency.as_secs_f64() * 1e3,
        ),
    )
    .at_most_seconds(limit))
}

/// The module's start-up handshake (heartbeat to status query, PROTOCOL_NOTES §4) at `baud`,
/// from the port's opening to its last step, against a quiet MCU or one that reports a data
/// point on its own every `chatty` (a field MCU's habit, issue 12). The wire time is that of
/// every frame on the line until then, the chatty MCU's own reports included. Errors when the
/// handshake does not finish within 30 s.
pub fn tuya_handshake(baud: u32, chatty: Option<Duration>) -> Result<Figure, String> {
    use crate::link::session::tuya::TuyaEvent;
    let p = profile("tuya-vacuum")?;
    let mcu: SharedDevice = Arc::new(Mutex::new(TuyaMcu::new(TuyaConfig {
        baud: Some(baud),
        // The battery, as `botbench sim tuya-vacuum --report-every` reports by default.
        report_every: chatty.map(|every| (6, every)),
        ..TuyaConfig::default()
    })));
    let server = PtyServer::start(mcu, Faults::default()).map_err(|e| e.to_string())?;
    let started = Instant::now();
    let link = open(&server, p, baud, LinkOptions::default())?;
    let deadline = started + Duration::from_secs(30);
    let mut bytes = 0;
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        match link.events().recv_timeout(left) {
            Ok(LinkEvent::Tuya(TuyaEvent::HandshakeDone)) => break,
            Ok(LinkEvent::Frame(entry)) => {
                bytes += entry.frame.as_ref().map_or(0, |f| f.wire.len());
            }
            Ok(_) => {}
            Err(_) => return Err("the handshake did not finish within 30 s".to_string()),
        }
    }
    let secs = started.elapsed().as_secs_f64();
    let wire = wire_time(bytes, baud).as_secs_f64();
    let who = match chatty {
        Some(every) => format!("an MCU reporting every {} ms", every.as_millis()),
        None => "a quiet MCU".to_string(),
    };
    Ok(Figure::new(
        &format!("tuya handshake, {baud} baud, {who}"),
        secs,
        wire,
        format!(
            "{bytes} bytes on the line, from the port's opening to the status query's last report"
        ),
    ))
}
