//! What botbench, as the Wi-Fi module, answers the MCU's own requests (PROTOCOL_NOTES §3): reset
//! Wi-Fi, local time, the Wi-Fi production test, network status, MAC address.

use crate::protocol::tuya::cmd;
use chrono::{Datelike, Local, NaiveDateTime, Timelike};
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
    /// The network status answered to 0x2b (0-6, as the Wi-Fi state).
    pub net_status: u8,
    /// The MAC address answered to 0x2d.
    pub mac: [u8; 6],
    /// A fixed local time to answer instead of the host clock.
    pub fixed_time: Option<NaiveDateTime>,
    /// The heartbeat interval after the handshake.
    pub heartbeat: Duration,
}

impl Default for TuyaModuleOptions {
    fn default() -> Self {
        Self {
            wifi_state: 4,
            wifi_test_ok: true,
            wifi_test_rssi: 80,
            net_status: 4,
            mac: [0x02, 0xb0, 0x7b, 0x00, 0x00, 0x01],
            fixed_time: None,
            heartbeat: Duration::from_secs(15),
        }
    }
}

/// The module's answer (data of the same command word) to an MCU request, with its name; `None`
/// for frames that are not MCU requests.
pub fn answer_mcu_request(
    opts: &TuyaModuleOptions,
    command: u8,
) -> Option<(&'static str, Vec<u8>)> {
    Some(match command {
        cmd::RESET_WIFI => ("reset Wi-Fi", Vec::new()),
        cmd::RESET_WIFI_MODE => ("reset Wi-Fi into a mode", Vec::new()),
        cmd::LOCAL_TIME => ("local time", local_time(opts)),
        cmd::WIFI_TEST => (
            "Wi-Fi production test",
            vec![u8::from(opts.wifi_test_ok), opts.wifi_test_rssi.min(100)],
        ),
        cmd::NET_STATUS => ("network status", vec![opts.net_status]),
        cmd::MAC => ("MAC address", {
            let mut v = vec![0];
            v.extend_from_slice(&opts.mac);
            v
        }),
        _ => return None,
    })
}

/// `[1, year-2000, month, day, hour, minute, second, weekday 1=Mon..7=Sun]`.
pub fn local_time(opts: &TuyaModuleOptions) -> Vec<u8> {
    let t = opts
        .fixed_time
        .unwrap_or_else(|| Local::now().naive_local());
    let year = (t.year() - 2000).clamp(0, 255) as u8;
    vec![
        1,
        year,
        t.month() as u8,
        t.day() as u8,
        t.hour() as u8,
        t.minute() as u8,
        t.second() as u8,
        t.weekday().number_from_monday() as u8,
    ]
}
