//! botbench as the Tuya Wi-Fi module: what it answers the MCU, and the start-up handshake's
//! steps (PROTOCOL_NOTES §3). The worker runs the steps; this file says what they mean.

use crate::protocol::tuya::cmd;
use chrono::{Datelike, Local, NaiveDateTime, Timelike};
use serde::Serialize;
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

/// A step of the module's start-up handshake.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum HandshakeStep {
    /// 0x00 until the MCU answers.
    Heartbeat,
    /// 0x01: PID, MCU version, configuration mode.
    ProductInfo,
    /// 0x02: who drives the Wi-Fi LED.
    WorkMode,
    /// 0x03: the Wi-Fi state, when the MCU drives the LED.
    WifiState,
    /// 0x08: every data point, as a burst of 0x07 reports.
    QueryStatus,
}

impl HandshakeStep {
    /// All steps, in order.
    pub const ALL: [HandshakeStep; 5] = [
        HandshakeStep::Heartbeat,
        HandshakeStep::ProductInfo,
        HandshakeStep::WorkMode,
        HandshakeStep::WifiState,
        HandshakeStep::QueryStatus,
    ];

    /// The command word it sends.
    pub fn command(self) -> u8 {
        match self {
            HandshakeStep::Heartbeat => cmd::HEARTBEAT,
            HandshakeStep::ProductInfo => cmd::PRODUCT_INFO,
            HandshakeStep::WorkMode => cmd::WORK_MODE,
            HandshakeStep::WifiState => cmd::WIFI_STATE,
            HandshakeStep::QueryStatus => cmd::QUERY_STATUS,
        }
    }
}

/// The MCU's product info (0x01), read leniently.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct ProductInfo {
    /// Product id (`p`).
    pub pid: Option<String>,
    /// MCU firmware version (`v`).
    pub version: Option<String>,
    /// Configuration mode (`m`: 0 default, 1 low power, 2 special).
    pub mode: Option<i64>,
    /// The text as received.
    pub raw: String,
    /// Why it could not be read as JSON, if it could not.
    pub error: Option<String>,
}

/// Reads product info: JSON like `{"p":"…","v":"1.0.0","m":0}`, other keys ignored; malformed
/// text is kept raw with the reason.
pub fn parse_product_info(data: &[u8]) -> ProductInfo {
    let raw = String::from_utf8_lossy(data).into_owned();
    match serde_json::from_slice::<serde_json::Value>(data) {
        Ok(serde_json::Value::Object(map)) => ProductInfo {
            pid: map.get("p").and_then(|v| v.as_str()).map(str::to_string),
            version: map.get("v").and_then(|v| v.as_str()).map(str::to_string),
            mode: map.get("m").and_then(|v| v.as_i64()),
            raw,
            error: None,
        },
        Ok(_) => ProductInfo {
            pid: None,
            version: None,
            mode: None,
            raw,
            error: Some("not a JSON object".into()),
        },
        Err(e) => ProductInfo {
            pid: None,
            version: None,
            mode: None,
            raw,
            error: Some(e.to_string()),
        },
    }
}

/// What the Tuya part of the link reports.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "event", rename_all = "snake_case")]
pub enum TuyaEvent {
    /// A handshake step finished, well or not.
    Step {
        /// Which.
        step: HandshakeStep,
        /// Whether it worked.
        ok: bool,
        /// What came back, or why it failed.
        detail: String,
    },
    /// Product info as read.
    ProductInfo(ProductInfo),
    /// The working mode: the MCU drives the LED, or the module's GPIO numbers.
    WorkMode {
        /// GPIO numbers (LED, reset) when the module drives the LED itself.
        gpio: Option<(u8, u8)>,
    },
    /// Every step done; heartbeats follow.
    HandshakeDone,
    /// The heartbeat answer was 0: the MCU restarted, and the handshake runs again.
    McuRestarted,
    /// The MCU stopped answering heartbeats.
    HeartbeatLost,
    /// The MCU asked something and the module answered.
    McuRequest {
        /// The MCU's command word.
        command: u8,
        /// What it asked.
        name: String,
        /// The answer's data.
        answer: Vec<u8>,
    },
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
