//! What botbench, as the Wi-Fi module, answers the MCU's own requests (PROTOCOL_NOTES §3,
//! TUYA_FIELD_NOTES §1-4): every request the protocol knows gets its due answer, with a
//! "failure" or "not supported" value where a bench has nothing real to say, never silence; a
//! command or extended-service sub-command the module does not know is logged with its bytes
//! and ignored, as ESPHome and the SDK's own module do.
//!
//! Choices where the notes mark a fact UNCONFIRMED:
//! - 0x25 (stop heartbeat) is acknowledged with an empty 0x25 (Tasmota's table; harmless to an
//!   SDK MCU, which has no handler for it), and the module stops its heartbeat.
//! - 0x0f (free memory) is answered with 4 bytes big-endian, as every other number of the
//!   protocol is.
//! - 0x2d (MAC) sends the 6 bytes in display order.
//! - 0x34 sub 0x07 (module information) is answered `07 01` (failure) unless a JSON is given.
//! - 0x20 (weather) is a cloud service with undocumented error codes: logged and ignored.

use crate::protocol::tuya::cmd;
use chrono::{Datelike, Local, NaiveDateTime, TimeZone, Timelike, Utc};
use std::time::Duration;

/// What the module answers the MCU's own requests.
#[derive(Debug, Clone, PartialEq)]
pub struct TuyaModuleOptions {
    /// The Wi-Fi state reported after the handshake (0-6; 4 = connected to the cloud).
    pub wifi_state: u8,
    /// The Wi-Fi production test's result.
    pub wifi_test_ok: bool,
    /// The Wi-Fi production test's signal strength (0-100), or the failure reason when not ok
    /// (0 SSID not found, 1 no licence key).
    pub wifi_test_rssi: u8,
    /// The router's signal strength answered to 0x24, dBm (negative; 0 means "not connected",
    /// the failure answer).
    pub rssi_dbm: i8,
    /// The network status answered to 0x2b (0-6, as the Wi-Fi state).
    pub net_status: u8,
    /// The MAC address answered to 0x2d.
    pub mac: [u8; 6],
    /// A fixed local time to answer (0x1c, and 0x0c converted with the host's zone) instead of
    /// the host clock.
    pub fixed_time: Option<NaiveDateTime>,
    /// Whether the module knows the time: when not, 0x0c and 0x1c get the failure answer (the
    /// flag 0 and zeros), as a module not yet synchronised with the cloud sends.
    pub time_known: bool,
    /// The result of each synchronous report (0x22) answered with 0x23: success by default (a
    /// bench has no cloud to fail); failure exercises the MCU's retry path.
    pub sync_report_ok: bool,
    /// The JSON answered to 0x34 sub 0x07 (module information); `None` answers failure.
    pub module_info: Option<String>,
    /// The heartbeat interval after the handshake.
    pub heartbeat: Duration,
}

impl Default for TuyaModuleOptions {
    fn default() -> Self {
        Self {
            wifi_state: 4,
            wifi_test_ok: true,
            wifi_test_rssi: 80,
            rssi_dbm: -54,
            net_status: 4,
            mac: [0x02, 0xb0, 0x7b, 0x00, 0x00, 0x01],
            fixed_time: None,
            time_known: true,
            sync_report_ok: true,
            module_info: None,
            heartbeat: Duration::from_secs(15),
        }
    }
}

/// The free memory answered to 0x0f, bytes: a figure a module of 1 MB flash reports.
const FREE_MEMORY: u32 = 40_960;

/// What the module does with an MCU request beyond answering it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Effect {
    /// 0x25: stop sending heartbeats (the MCU is a low-power one).
    StopHeartbeat,
}

/// The module's answer to an MCU request.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct McuAnswer {
    /// What the MCU asked, as a person reads it.
    pub name: &'static str,
    /// The answer's command word (the request's, but 0x23 for a 0x22) and data; `None`: the
    /// frame needs no answer (an acknowledgement of the module's own push).
    pub reply: Option<(u8, Vec<u8>)>,
    /// What the module does besides.
    pub effect: Option<Effect>,
}

impl McuAnswer {
    fn reply(name: &'static str, command: u8, data: Vec<u8>) -> Self {
        Self {
            name,
            reply: Some((command, data)),
            effect: None,
        }
    }
}

/// Why an MCU frame got no answer: the module does not know it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Unknown {
    /// What it is, as far as the module knows: `command 0x99`, `extended service 0x36`.
    pub what: String,
}

/// The module's answer to an MCU frame `command` with `data`: `Ok(None)` for a frame that is no
/// MCU request (a report, an answer to the module), `Err` for a command the module does not
/// know (logged with its bytes and ignored).
pub fn answer_mcu_request(
    opts: &TuyaModuleOptions,
    command: u8,
    data: &[u8],
) -> Result<Option<McuAnswer>, Unknown> {
    let same = |name, data| Ok(Some(McuAnswer::reply(name, command, data)));
    match command {
        cmd::HEARTBEAT
        | cmd::PRODUCT_INFO
        | cmd::WORK_MODE
        | cmd::WIFI_STATE
        | cmd::DP_REPORT
        | cmd::QUERY_STATUS
        | cmd::OTA_START
        | cmd::OTA_PACKET
        | cmd::DP_COMMAND => Ok(None),
        cmd::RESET_WIFI => same("reset Wi-Fi", Vec::new()),
        cmd::RESET_WIFI_MODE => same("reset Wi-Fi into a mode", Vec::new()),
        cmd::LOCAL_TIME => same("local time", local_time(opts)),
        cmd::UTC_TIME => same("GMT time", utc_time(opts)),
        cmd::WIFI_TEST => same(
            "Wi-Fi production test",
            vec![u8::from(opts.wifi_test_ok), opts.wifi_test_rssi.min(100)],
        ),
        cmd::FREE_MEMORY => same("free memory", FREE_MEMORY.to_be_bytes().to_vec()),
        cmd::DP_REPORT_SYNC => Ok(Some(McuAnswer::reply(
            "status report (synchronous)",
            cmd::DP_REPORT_SYNC_RESULT,
            vec![u8::from(opts.sync_report_ok)],
        ))),
        cmd::WIFI_RSSI => same("Wi-Fi signal strength", vec![opts.rssi_dbm as u8]),
        cmd::HEARTBEAT_STOP => Ok(Some(McuAnswer {
            effect: Some(Effect::StopHeartbeat),
            ..McuAnswer::reply("stop heartbeat", command, Vec::new())
        })),
        // Stream services: not enabled on a bench (ESPHome's answer too).
        cmd::STREAM => same("stream data", vec![1]),
        cmd::MAPS_STREAM => same("map stream data", vec![1]),
        cmd::NET_STATUS => same("network status", vec![opts.net_status]),
        cmd::WIFI_CONNECT_TEST => same("Wi-Fi test: join a router", vec![1]),
        cmd::MAC => same("MAC address", [&[0][..], &opts.mac].concat()),
        cmd::EXTENDED => extended(opts, data),
        cmd::NEW_FUNC => match data.first() {
            Some(0) => same("new function settings", vec![0, 0]),
            _ => Err(Unknown {
                what: format!(
                    "new function settings sub-command {:#04x}",
                    data.first().copied().unwrap_or(0)
                ),
            }),
        },
        other => Err(Unknown {
            what: format!("command {other:#04x}"),
        }),
    }
}

/// 0x34 by sub-command (TUYA_FIELD_NOTES §4.7): services opened answer `[sub, 0]` (0 is success
/// here), module information `[07, 1]` (failure) or `[07, 0, JSON]`, the record-type status
/// `[0B, 0]`; the MCU's acknowledgements of the module's pushes (0x02, 0x05) need no answer.
fn extended(opts: &TuyaModuleOptions, data: &[u8]) -> Result<Option<McuAnswer>, Unknown> {
    let ok = |name, sub: u8| Ok(Some(McuAnswer::reply(name, cmd::EXTENDED, vec![sub, 0])));
    let ack = |name| {
        Ok(Some(McuAnswer {
            name,
            reply: None,
            effect: None,
        }))
    };
    match data.first().copied() {
        Some(0x01) => ok("open the time service", 0x01),
        Some(0x02) => ack("time push acknowledged"),
        Some(0x03) => ok("weather now", 0x03),
        Some(0x04) => ok("open reset notifications", 0x04),
        Some(0x05) => ack("reset notification acknowledged"),
        Some(0x07) => {
            let answer = match &opts.module_info {
                Some(json) => [&[0x07, 0][..], json.as_bytes()].concat(),
                None => vec![0x07, 1],
            };
            Ok(Some(McuAnswer::reply(
                "module information",
                cmd::EXTENDED,
                answer,
            )))
        }
        Some(0x0B) => ok("status report with its time", 0x0B),
        Some(sub) => Err(Unknown {
            what: format!("extended service sub-command {sub:#04x}"),
        }),
        None => Err(Unknown {
            what: "extended service without a sub-command".into(),
        }),
    }
}

/// The local time the module answers: the fixed one, or the host clock's.
fn local_now(opts: &TuyaModuleOptions) -> NaiveDateTime {
    opts.fixed_time
        .unwrap_or_else(|| Local::now().naive_local())
}

/// `[ok, year-2000, month, day, hour, minute, second]` then the weekday when `weekday`; the
/// failure answer (all zeros) when the module does not know the time.
fn time_bytes(t: NaiveDateTime, known: bool, weekday: bool) -> Vec<u8> {
    let n = if weekday { 8 } else { 7 };
    if !known {
        return vec![0; n];
    }
    let year = (t.year() - 2000).clamp(0, 255) as u8;
    let mut out = vec![
        1,
        year,
        t.month() as u8,
        t.day() as u8,
        t.hour() as u8,
        t.minute() as u8,
        t.second() as u8,
    ];
    if weekday {
        out.push(t.weekday().number_from_monday() as u8);
    }
    out
}

/// 0x1c: `[1, year-2000, month, day, hour, minute, second, weekday 1=Mon..7=Sun]`, or 8 zeros
/// when the time is not known.
pub fn local_time(opts: &TuyaModuleOptions) -> Vec<u8> {
    time_bytes(local_now(opts), opts.time_known, true)
}

/// 0x0c: `[1, year-2000, month, day, hour, minute, second]` in GMT (UTC; no weekday), or 7
/// zeros when the time is not known. A fixed local time is converted with the host's zone.
pub fn utc_time(opts: &TuyaModuleOptions) -> Vec<u8> {
    let utc = match opts.fixed_time {
        Some(t) => Local
            .from_local_datetime(&t)
            .earliest()
            .map_or(t, |l| l.with_timezone(&Utc).naive_utc()),
        None => Utc::now().naive_utc(),
    };
    time_bytes(utc, opts.time_known, false)
}

#[cfg(test)]
mod tests {
    use super::*;
    use chrono::NaiveDate;

    fn at(opts: TuyaModuleOptions) -> TuyaModuleOptions {
        TuyaModuleOptions {
            fixed_time: NaiveDate::from_ymd_opt(2024, 2, 29)
                .and_then(|d| d.and_hms_opt(14, 45, 30)),
            ..opts
        }
    }

    fn frame(command: u8, data: &[u8]) -> Vec<u8> {
        crate::protocol::tuya::Frame::from_module(command, data.to_vec())
            .encode()
            .unwrap()
    }

    fn answer(opts: &TuyaModuleOptions, command: u8, data: &[u8]) -> Vec<u8> {
        let a = answer_mcu_request(opts, command, data).unwrap().unwrap();
        let (c, d) = a.reply.unwrap();
        frame(c, &d)
    }

    #[test]
    fn every_request_of_the_field_notes_gets_its_frame() {
        let o = at(TuyaModuleOptions::default());
        // TUYA_FIELD_NOTES §3: Thu 2024-02-29 14:45:30 local.
        assert_eq!(
            answer(&o, cmd::LOCAL_TIME, &[]),
            [
                0x55, 0xAA, 0, 0x1C, 0, 8, 1, 0x18, 2, 0x1D, 0x0E, 0x2D, 0x1E, 4, 0xB8
            ]
        );
        // §2: a synchronous report is answered 0x23 01; failure 0x23 00.
        assert_eq!(
            answer(&o, cmd::DP_REPORT_SYNC, &[6, 2, 0, 4, 0, 0, 0, 0x55]),
            [0x55, 0xAA, 0, 0x23, 0, 1, 1, 0x24]
        );
        let fail = TuyaModuleOptions {
            sync_report_ok: false,
            ..o.clone()
        };
        assert_eq!(
            answer(&fail, cmd::DP_REPORT_SYNC, &[]),
            [0x55, 0xAA, 0, 0x23, 0, 1, 0, 0x23]
        );
        // §4.2: -54 dBm.
        assert_eq!(
            answer(&o, cmd::WIFI_RSSI, &[]),
            [0x55, 0xAA, 0, 0x24, 0, 1, 0xCA, 0xEE]
        );
        // §4.3, §4.4.
        assert_eq!(
            answer(&o, cmd::NET_STATUS, &[]),
            [0x55, 0xAA, 0, 0x2B, 0, 1, 4, 0x2F]
        );
        let mac = TuyaModuleOptions {
            mac: [0x12, 0x34, 0x56, 0x78, 0x9A, 0xBC],
            ..o.clone()
        };
        assert_eq!(
            answer(&mac, cmd::MAC, &[]),
            [
                0x55, 0xAA, 0, 0x2D, 0, 7, 0, 0x12, 0x34, 0x56, 0x78, 0x9A, 0xBC, 0x9D
            ]
        );
        // §4.1, §4.7, §4.9.
        assert_eq!(
            answer(&o, cmd::HEARTBEAT_STOP, &[]),
            [0x55, 0xAA, 0, 0x25, 0, 0, 0x24]
        );
        assert_eq!(
            answer(&o, cmd::EXTENDED, &[4]),
            [0x55, 0xAA, 0, 0x34, 0, 2, 4, 0, 0x39]
        );
        assert_eq!(
            answer(&o, cmd::NEW_FUNC, &[0, b'{']),
            [0x55, 0xAA, 0, 0x37, 0, 2, 0, 0, 0x38]
        );
        assert_eq!(
            answer(&o, cmd::EXTENDED, &[7]),
            frame(cmd::EXTENDED, &[7, 1])
        );
        // §3: the failure answer when the time is not known.
        let unknown = TuyaModuleOptions {
            time_known: false,
            ..o.clone()
        };
        assert_eq!(
            answer(&unknown, cmd::LOCAL_TIME, &[]),
            [0x55, 0xAA, 0, 0x1C, 0, 8, 0, 0, 0, 0, 0, 0, 0, 0, 0x23]
        );
        assert_eq!(answer(&unknown, cmd::UTC_TIME, &[]).len(), 7 + 7);
    }

    #[test]
    fn unknown_commands_and_sub_commands_get_no_answer_and_acks_need_none() {
        let o = TuyaModuleOptions::default();
        assert_eq!(
            answer_mcu_request(&o, 0x99, &[1, 2]),
            Err(Unknown {
                what: "command 0x99".into()
            })
        );
        assert!(answer_mcu_request(&o, cmd::EXTENDED, &[0x36]).is_err());
        let ack = answer_mcu_request(&o, cmd::EXTENDED, &[0x02])
            .unwrap()
            .unwrap();
        assert_eq!(ack.reply, None);
        assert_eq!(answer_mcu_request(&o, cmd::DP_REPORT, &[]), Ok(None));
        let stop = answer_mcu_request(&o, cmd::HEARTBEAT_STOP, &[])
            .unwrap()
            .unwrap();
        assert_eq!(stop.effect, Some(Effect::StopHeartbeat));
    }
}
