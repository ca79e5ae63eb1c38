//! The robot vacuum's MCU as the Tuya MCU SDK behaves (seed 003, PROTOCOL_NOTES §3); botbench
//! plays the Wi-Fi module.
//!
//! It answers module frames (version 0x00; any other version is dropped silently, as the SDK
//! does) with its own frames: heartbeat, product info, working mode, Wi-Fi state, data-point
//! commands and queries ([`sdk`]: one report per data point, as the SDK), and OTA ([`ota`]). The
//! vacuum's own rules and battery are in [`vacuum`]. It also sends requests of its own on demand
//! ([`McuRequest`]) from [`Device::tick`] and records the module's answers.
//!
//! It can misbehave as MCUs in the field do (PROTOCOL_NOTES §4), each a [`TuyaConfig`] option:
//! another version byte, a data point reported on its own every few milliseconds, data points
//! reported with another type or length than the profile's, rules that override a command, lost
//! reports of its own changes, and a line that echoes the module's frames.

mod ota;
mod sdk;
mod vacuum;

pub use ota::{OtaState, crc32};
pub use sdk::{WireForm, parse_misreport};

use super::{Device, Outgoing};
use crate::profile::registry::{BUILTIN, parse};
use crate::profile::{Profile, Protocol};
use crate::protocol::tuya::dp::DpValue;
use crate::protocol::tuya::{Frame, TuyaDecoder, VERSION_MCU, VERSION_MODULE, cmd};
use std::collections::{BTreeMap, VecDeque};
use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

/// The default reply latency.
pub const DEFAULT_LATENCY: Duration = Duration::from_millis(2);

/// The vacuum's product id (seed 003).
pub const DEFAULT_PID: &str = "lgldgnmt4ifc.jzex";

/// A product-info answer that is not valid JSON, for bad-input tests.
pub const MALFORMED_PRODUCT_INFO: &[u8] = b"{\"p\":\"lgldgnmt4ifc.jzex\",\"v\":\"1.0.";
/// Data-point ids of the vacuum.
pub mod dpid {
    /// Power, bool.
    pub const POWER: u8 = 1;
    /// Clean switch, bool.
    pub const CLEAN_SWITCH: u8 = 2;
    /// Work mode, enum.
    pub const MODE: u8 = 3;
    /// Direction, enum.
    pub const DIRECTION: u8 = 4;
    /// Status, enum, report only.
    pub const STATUS: u8 = 5;
    /// Battery %, value, report only.
    pub const BATTERY: u8 = 6;
    /// Edge brush life %, value, report only.
    pub const EDGE_BRUSH_LIFE: u8 = 7;
    /// Roll brush life %.
    pub const ROLL_BRUSH_LIFE: u8 = 8;
    /// Filter life %.
    pub const FILTER_LIFE: u8 = 9;
    /// Edge brush reset, bool.
    pub const EDGE_BRUSH_RESET: u8 = 10;
    /// Roll brush reset, bool.
    pub const ROLL_BRUSH_RESET: u8 = 11;
    /// Filter reset, bool.
    pub const FILTER_RESET: u8 = 12;
    /// Find robot, bool.
    pub const FIND_ROBOT: u8 = 13;
    /// Suction, enum.
    pub const SUCTION: u8 = 14;
    /// Clean record, string.
    pub const CLEAN_RECORD: u8 = 15;
    /// Clean area m², value.
    pub const CLEAN_AREA: u8 = 16;
    /// Clean time min, value.
    pub const CLEAN_TIME: u8 = 17;
    /// Fault, bitmap.
    pub const FAULT: u8 = 18;
    /// Map parameters, raw.
    pub const MAP_PARAMS: u8 = 19;
}

/// Status values (DP 5).
pub mod status {
    /// Standby.
    pub const STANDBY: u8 = 0;
    /// Auto cleaning.
    pub const SMART_CLEAN: u8 = 1;
    /// Edge cleaning.
    pub const WALL_CLEAN: u8 = 2;
    /// Spot cleaning.
    pub const SPOT_CLEAN: u8 = 3;
    /// Mopping.
    pub const MOP_CLEAN: u8 = 4;
    /// Returning to the dock.
    pub const GOTO_CHARGE: u8 = 5;
}

/// How the MCU answers OTA start (0x0a).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OtaPacketAnswer {
    /// One byte: 0 = 256, 1 = 512, 2 = 1024 bytes per packet.
    Option(u8),
    /// An empty answer, meaning 256.
    Empty,
}

impl OtaPacketAnswer {
    /// The packet size agreed.
    pub fn size(self) -> usize {
        match self {
            OtaPacketAnswer::Option(1) => 512,
            OtaPacketAnswer::Option(2) => 1024,
            _ => 256,
        }
    }
}

/// A request the MCU sends the module on its own (PROTOCOL_NOTES §3), answered by the module.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum McuRequest {
    /// 0x1c: the local time.
    LocalTime,
    /// 0x0e: the Wi-Fi production test.
    WifiTest,
    /// 0x04: reset the Wi-Fi.
    ResetWifi,
    /// 0x05: reset the Wi-Fi into a pairing mode (0 smartconfig, 1 AP).
    ResetWifiMode(u8),
    /// 0x2b: the network status.
    NetStatus,
    /// 0x2d: the module's MAC address.
    Mac,
}

impl McuRequest {
    /// Every request, the pairing mode reset into AP mode.
    pub const ALL: [McuRequest; 6] = [
        McuRequest::LocalTime,
        McuRequest::WifiTest,
        McuRequest::ResetWifi,
        McuRequest::ResetWifiMode(1),
        McuRequest::NetStatus,
        McuRequest::Mac,
    ];

    /// Its command word.
    pub fn command(self) -> u8 {
        match self {
            McuRequest::LocalTime => cmd::LOCAL_TIME,
            McuRequest::WifiTest => cmd::WIFI_TEST,
            McuRequest::ResetWifi => cmd::RESET_WIFI,
            McuRequest::ResetWifiMode(_) => cmd::RESET_WIFI_MODE,
            McuRequest::NetStatus => cmd::NET_STATUS,
            McuRequest::Mac => cmd::MAC,
        }
    }

    /// Its data.
    pub fn data(self) -> Vec<u8> {
        match self {
            McuRequest::ResetWifiMode(mode) => vec![mode],
            _ => Vec::new(),
        }
    }

    /// The word `botbench sim tuya-vacuum` takes on its stdin for it: `time`, `wifi-test`,
    /// `reset-wifi`, `reset-wifi-mode`, `net-status`, `mac`.
    pub fn word(self) -> &'static str {
        match self {
            McuRequest::LocalTime => "time",
            McuRequest::WifiTest => "wifi-test",
            McuRequest::ResetWifi => "reset-wifi",
            McuRequest::ResetWifiMode(_) => "reset-wifi-mode",
            McuRequest::NetStatus => "net-status",
            McuRequest::Mac => "mac",
        }
    }

    /// The request a word and its argument name (`reset-wifi-mode 0`).
    pub fn parse(word: &str, arg: Option<&str>) -> Result<Self, String> {
        let found = Self::ALL.into_iter().find(|r| r.word() == word);
        match found {
            Some(McuRequest::ResetWifiMode(_)) => match arg.map(str::parse::<u8>) {
                Some(Ok(mode @ (0 | 1))) => Ok(McuRequest::ResetWifiMode(mode)),
                _ => Err("reset-wifi-mode takes 0 (smartconfig) or 1 (AP)".into()),
            },
            Some(r) => Ok(r),
            None => Err(format!("unknown command '{word}'")),
        }
    }
}

/// The MCU's settings.
#[derive(Debug, Clone)]
pub struct TuyaConfig {
    /// Product id in the product-info JSON.
    pub pid: String,
    /// MCU version in the product-info JSON.
    pub version: String,
    /// Pairing mode `m` in the product-info JSON.
    pub mode: u8,
    /// Sent instead of the JSON when set (e.g. [`MALFORMED_PRODUCT_INFO`]).
    pub product_info_raw: Option<Vec<u8>>,
    /// Working mode: `None` = the MCU drives the Wi-Fi LED (empty answer), or the LED and reset
    /// GPIO numbers of a self-managing module.
    pub work_mode: Option<[u8; 2]>,
    /// The OTA packet size answered to 0x0a.
    pub ota_packet: OtaPacketAnswer,
    /// Fault: stop acking OTA packets once one with offset ≥ N arrives.
    pub stop_acking_at: Option<u32>,
    /// Delay before each answer.
    pub latency: Duration,
    /// The MCU's UART rate: bytes sent at another rate are garbage to it and ignored. `None`
    /// hears every rate.
    pub baud: Option<u32>,
    /// While cleaning, the battery drops 1 % this often.
    pub battery_drain_every: Duration,
    /// Seed of the random source.
    pub seed: u64,
    /// The version byte of the MCU's frames: 0x03 as the protocol document says, 0x01 as MCU
    /// SDKs before v2.5 send, 0x00 as some firmware does.
    pub frame_version: u8,
    /// A chatty MCU: reports this data point on its own at this interval, whatever else is
    /// going on.
    pub report_every: Option<(u8, Duration)>,
    /// Data points the firmware reports with another type or length than the profile's, by id.
    pub misreport: BTreeMap<u8, WireForm>,
    /// The firmware's rules also change data points the same 0x06 set (power off resets the
    /// mode even when the frame also set one): the MCU then holds another value than its
    /// answer said, and reports the change on its own.
    pub rules_override_command: bool,
    /// The reports of the changes the firmware's rules make are lost on the line (the answers
    /// to the module's commands are not).
    pub lose_rule_reports: bool,
    /// The line echoes every module frame back to the module, as a one-wire adapter does.
    pub echo: bool,
}

impl Default for TuyaConfig {
    fn default() -> Self {
        Self {
            pid: DEFAULT_PID.to_string(),
            version: "1.0.0".to_string(),
            mode: 0,
            product_info_raw: None,
            work_mode: None,
            ota_packet: OtaPacketAnswer::Option(0),
            stop_acking_at: None,
            latency: DEFAULT_LATENCY,
            baud: Some(9600),
            battery_drain_every: Duration::from_secs(30),
            seed: 0,
            frame_version: VERSION_MCU,
            report_every: None,
            misreport: BTreeMap::new(),
            rules_override_command: false,
            lose_rule_reports: false,
            echo: false,
        }
    }
}

/// The built-in vacuum profile (parsed once); an empty profile stands in if it ever fails.
pub fn builtin_vacuum_profile() -> Arc<Profile> {
    static PROFILE: OnceLock<Arc<Profile>> = OnceLock::new();
    PROFILE
        .get_or_init(|| {
            let src = BUILTIN
                .iter()
                .find(|(name, _)| *name == "tuya-vacuum")
                .map_or("", |(_, src)| *src);
            let parsed = parse(
                "builtin:assets/profiles/tuya-vacuum.ron",
                src,
                Some("tuya-vacuum"),
            );
            Arc::new(parsed.unwrap_or_else(|_| Profile::empty("tuya-vacuum", Protocol::Tuya, 9600)))
        })
        .clone()
}

/// The Tuya MCU of the robot vacuum.
#[derive(Debug)]
pub struct TuyaMcu {
    config: TuyaConfig,
    profile: Arc<Profile>,
    decoder: TuyaDecoder,
    rng: fastrand::Rng,
    heartbeat_answered: bool,
    wifi_state: Option<u8>,
    dps: BTreeMap<u8, DpValue>,
    last_drain: Option<Instant>,
    /// When the chatty data point is next reported.
    next_chatty: Option<Instant>,
    /// Frames sent from the next tick, in order.
    outbox: VecDeque<Vec<u8>>,
    answers: Vec<(u8, Vec<u8>)>,
    ota: ota::Ota,
}

impl Default for TuyaMcu {
    fn default() -> Self {
        Self::new(TuyaConfig::default())
    }
}

impl TuyaMcu {
    /// An MCU with these settings and the built-in vacuum profile's data points.
    pub fn new(config: TuyaConfig) -> Self {
        Self::with_profile(builtin_vacuum_profile(), config)
    }

    /// An MCU whose data points are `profile`'s.
    pub fn with_profile(profile: Arc<Profile>, config: TuyaConfig) -> Self {
        let dps = profile
            .data_points
            .iter()
            .map(|d| (d.id, vacuum::initial_value(d)))
            .collect();
        Self {
            rng: fastrand::Rng::with_seed(config.seed),
            config,
            profile,
            decoder: TuyaDecoder::new(),
            heartbeat_answered: false,
            wifi_state: None,
            dps,
            last_drain: None,
            next_chatty: None,
            outbox: VecDeque::new(),
            answers: Vec::new(),
            ota: ota::Ota::default(),
        }
    }

    /// The settings (change them at any time).
    pub fn config_mut(&mut self) -> &mut TuyaConfig {
        &mut self.config
    }

    /// The settings.
    pub fn config(&self) -> &TuyaConfig {
        &self.config
    }

    /// A reboot: the next heartbeat answer is `00` again; an OTA in progress is lost, and so is
    /// half a frame in the receive buffer. Data points keep their values.
    pub fn restart(&mut self) {
        self.heartbeat_answered = false;
        self.decoder.clear();
        self.outbox.clear();
        self.ota.restart();
    }

    /// A data point's value.
    pub fn dp(&self, id: u8) -> Option<&DpValue> {
        self.dps.get(&id)
    }

    /// Every data point.
    pub fn dps(&self) -> &BTreeMap<u8, DpValue> {
        &self.dps
    }

    /// Changes a data point as the robot itself would (a key press, a fault) and reports it
    /// from the next [`Device::tick`]. Returns false for an unknown id.
    pub fn set_dp(&mut self, id: u8, value: DpValue) -> bool {
        if !self.dps.contains_key(&id) {
            return false;
        }
        self.dps.insert(id, value);
        if let Some(f) = self.report(id) {
            self.outbox.push_back(f);
        }
        true
    }

    /// The Wi-Fi state the module last reported (0x03).
    pub fn wifi_state(&self) -> Option<u8> {
        self.wifi_state
    }

    /// The module's answers to the MCU's own requests (0x04, 0x05, 0x0e, 0x1c, 0x2b, 0x2d), as
    /// (command, data), oldest first.
    pub fn answers(&self) -> &[(u8, Vec<u8>)] {
        &self.answers
    }

    /// Takes the recorded answers.
    pub fn take_answers(&mut self) -> Vec<(u8, Vec<u8>)> {
        std::mem::take(&mut self.answers)
    }

    /// The OTA state.
    pub fn ota_state(&self) -> &OtaState {
        &self.ota.state
    }

    /// The image received so far (all of it once complete).
    pub fn ota_image(&self) -> &[u8] {
        &self.ota.image
    }

    /// Queues one of the MCU's own requests, sent by the next tick.
    pub fn request(&mut self, request: McuRequest) {
        if let Some(bytes) = self.encode(request.command(), request.data()) {
            self.outbox.push_back(bytes);
        }
    }

    /// Queues a local-time request (0x1c), sent by the next tick.
    pub fn request_local_time(&mut self) {
        self.request(McuRequest::LocalTime);
    }

    /// Queues a Wi-Fi production test request (0x0e).
    pub fn request_wifi_test(&mut self) {
        self.request(McuRequest::WifiTest);
    }

    /// Queues a Wi-Fi reset request (0x04).
    pub fn reset_wifi(&mut self) {
        self.request(McuRequest::ResetWifi);
    }

    /// Queues a Wi-Fi reset into a pairing mode (0x05; 0 smartconfig, 1 AP).
    pub fn reset_wifi_mode(&mut self, mode: u8) {
        self.request(McuRequest::ResetWifiMode(mode));
    }

    /// Queues a network-status request (0x2b).
    pub fn request_net_status(&mut self) {
        self.request(McuRequest::NetStatus);
    }

    /// Queues a MAC-address request (0x2d).
    pub fn request_mac(&mut self) {
        self.request(McuRequest::Mac);
    }

    fn product_info(&self) -> Vec<u8> {
        match &self.config.product_info_raw {
            Some(raw) => raw.clone(),
            None => format!(
                "{{\"p\":\"{}\",\"v\":\"{}\",\"m\":{}}}",
                self.config.pid, self.config.version, self.config.mode
            )
            .into_bytes(),
        }
    }

    /// The frames answering one module frame.
    fn handle(&mut self, f: Frame) -> Vec<Vec<u8>> {
        let data = f.data;
        let answer = |s: &Self, command: u8, data: Vec<u8>| s.encode(command, data);
        let one = match f.command {
            cmd::HEARTBEAT => {
                let first = !self.heartbeat_answered;
                self.heartbeat_answered = true;
                answer(self, cmd::HEARTBEAT, vec![u8::from(!first)])
            }
            cmd::PRODUCT_INFO => answer(self, cmd::PRODUCT_INFO, self.product_info()),
            cmd::WORK_MODE => {
                let data = self.config.work_mode.map(Vec::from).unwrap_or_default();
                answer(self, cmd::WORK_MODE, data)
            }
            cmd::WIFI_STATE => match data.as_slice() {
                [s] => {
                    self.wifi_state = Some(*s);
                    answer(self, cmd::WIFI_STATE, Vec::new())
                }
                _ => None,
            },
            cmd::DP_COMMAND => return self.dp_command(&data),
            cmd::QUERY_STATUS => {
                let ids: Vec<u8> = self.dps.keys().copied().collect();
                return ids.into_iter().filter_map(|id| self.report(id)).collect();
            }
            cmd::OTA_START => {
                let packet = self.config.ota_packet;
                let data = self.ota.start(&data, packet);
                data.and_then(|d| answer(self, cmd::OTA_START, d))
            }
            cmd::OTA_PACKET => {
                let ack = self.ota.packet(&data, self.config.stop_acking_at);
                ack.then(|| answer(self, cmd::OTA_PACKET, Vec::new()))
                    .flatten()
            }
            cmd::RESET_WIFI
            | cmd::RESET_WIFI_MODE
            | cmd::WIFI_TEST
            | cmd::LOCAL_TIME
            | cmd::NET_STATUS
            | cmd::MAC => {
                self.answers.push((f.command, data));
                None
            }
            _ => None,
        };
        one.into_iter().collect()
    }

    /// The chatty data point's report, when it is due.
    fn chatter(&mut self, now: Instant) -> Option<Vec<u8>> {
        let (id, every) = self.config.report_every?;
        let due = *self.next_chatty.get_or_insert(now);
        if now < due {
            return None;
        }
        self.next_chatty = Some((due + every.max(Duration::from_millis(1))).max(now));
        self.report(id)
    }
}

impl Device for TuyaMcu {
    fn receive(&mut self, bytes: &[u8], baud: u32, now: Instant) -> Vec<Outgoing> {
        let mut out = Vec::new();
        if self.config.echo {
            out.push(Outgoing::new(Duration::ZERO, bytes.to_vec()));
        }
        if self.config.baud.is_some_and(|b| b != baud) {
            // Framing errors at the wrong rate: whatever was half-received is lost too.
            self.decoder.clear();
            return out;
        }
        self.decoder.push(bytes);
        let frames: Vec<Frame> = self
            .decoder
            .by_ref()
            .filter_map(Result::ok)
            .filter(|f| f.version == VERSION_MODULE)
            .collect();
        let was_cleaning = self.cleaning();
        for f in frames {
            let latency = self.config.latency;
            out.extend(
                self.handle(f)
                    .into_iter()
                    .map(|b| Outgoing::new(latency, b)),
            );
        }
        if self.cleaning() && !was_cleaning {
            self.last_drain = Some(now);
        }
        out
    }

    fn tick(&mut self, now: Instant) -> Vec<Outgoing> {
        let mut out: Vec<Outgoing> = self
            .outbox
            .drain(..)
            .map(|b| Outgoing::new(Duration::ZERO, b))
            .collect();
        if let Some(b) = self.drain_battery(now) {
            out.push(Outgoing::new(Duration::ZERO, b));
        }
        if let Some(b) = self.chatter(now) {
            out.push(Outgoing::new(Duration::ZERO, b));
        }
        out
    }
}
