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

mod field;
mod ota;
mod sdk;
mod vacuum;

pub use field::{OtaFault, RawValue, parse_gap, parse_id_value, parse_unknown_dp};
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

/// A request the MCU sends the module on its own (PROTOCOL_NOTES §3, TUYA_FIELD_NOTES §1-4),
/// answered by the module.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum McuRequest {
    /// 0x1c: the local time.
    LocalTime,
    /// 0x0c: the GMT (UTC) time.
    UtcTime,
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
    /// 0x24: the Wi-Fi signal strength.
    Rssi,
    /// 0x25: stop the module's heartbeat.
    StopHeartbeat,
    /// 0x34 with this sub-command (0x01 open the time service, 0x04 open reset notifications,
    /// 0x07 module information...).
    Extended(u8),
}

impl McuRequest {
    /// Every request, the pairing mode reset into AP mode and the module information asked of
    /// the extended services.
    pub const ALL: [McuRequest; 10] = [
        McuRequest::LocalTime,
        McuRequest::UtcTime,
        McuRequest::WifiTest,
        McuRequest::ResetWifi,
        McuRequest::ResetWifiMode(1),
        McuRequest::NetStatus,
        McuRequest::Mac,
        McuRequest::Rssi,
        McuRequest::StopHeartbeat,
        McuRequest::Extended(0x07),
    ];

    /// Its command word.
    pub fn command(self) -> u8 {
        match self {
            McuRequest::LocalTime => cmd::LOCAL_TIME,
            McuRequest::UtcTime => cmd::UTC_TIME,
            McuRequest::WifiTest => cmd::WIFI_TEST,
            McuRequest::ResetWifi => cmd::RESET_WIFI,
            McuRequest::ResetWifiMode(_) => cmd::RESET_WIFI_MODE,
            McuRequest::NetStatus => cmd::NET_STATUS,
            McuRequest::Mac => cmd::MAC,
            McuRequest::Rssi => cmd::WIFI_RSSI,
            McuRequest::StopHeartbeat => cmd::HEARTBEAT_STOP,
            McuRequest::Extended(_) => cmd::EXTENDED,
        }
    }

    /// Its data.
    pub fn data(self) -> Vec<u8> {
        match self {
            McuRequest::ResetWifiMode(mode) => vec![mode],
            McuRequest::Extended(sub) => vec![sub],
            _ => Vec::new(),
        }
    }

    /// The word `botbench sim tuya-vacuum` takes on its stdin for it: `time`, `utc-time`,
    /// `wifi-test`, `reset-wifi`, `reset-wifi-mode`, `net-status`, `mac`, `rssi`,
    /// `stop-heartbeat`, `extended`.
    pub fn word(self) -> &'static str {
        match self {
            McuRequest::LocalTime => "time",
            McuRequest::UtcTime => "utc-time",
            McuRequest::WifiTest => "wifi-test",
            McuRequest::ResetWifi => "reset-wifi",
            McuRequest::ResetWifiMode(_) => "reset-wifi-mode",
            McuRequest::NetStatus => "net-status",
            McuRequest::Mac => "mac",
            McuRequest::Rssi => "rssi",
            McuRequest::StopHeartbeat => "stop-heartbeat",
            McuRequest::Extended(_) => "extended",
        }
    }

    /// The request a word and its argument name (`reset-wifi-mode 0`, `extended 0x07`).
    pub fn parse(word: &str, arg: Option<&str>) -> Result<Self, String> {
        let found = Self::ALL.into_iter().find(|r| r.word() == word);
        match found {
            Some(McuRequest::ResetWifiMode(_)) => match arg.map(str::parse::<u8>) {
                Some(Ok(mode @ (0 | 1))) => Ok(McuRequest::ResetWifiMode(mode)),
                _ => Err("reset-wifi-mode takes 0 (smartconfig) or 1 (AP)".into()),
            },
            Some(McuRequest::Extended(_)) => arg
                .and_then(crate::profile::codec::parse_id)
                .map(McuRequest::Extended)
                .ok_or_else(|| "extended takes a sub-command byte, e.g. extended 0x07".into()),
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
    /// A slow MCU: the reports answering a status query come this far apart (each drawn between
    /// the two bounds), not at once.
    pub report_gap: Option<(Duration, Duration)>,
    /// The MCU reports its own changes as 0x22 and waits for the module's 0x23 before the next
    /// (a synchronous report; a battery sensor sends nothing else).
    pub sync_reports: bool,
    /// Data points the product's profile does not have, reported with the others on a query.
    pub report_unknown_dp: Vec<(u8, DpValue)>,
    /// Values the profile does not allow, reported for these data points whatever they hold
    /// (battery 150 %, mode 32, a string longer than its maximum).
    pub report_out_of_range: BTreeMap<u8, RawValue>,
    /// How a firmware update fails, if it does.
    pub ota_fault: Option<OtaFault>,
    /// How long the MCU takes to restart after the last OTA packet.
    pub ota_restart: Duration,
    /// The version the MCU runs after an update; `None`: the one the image names (its only
    /// `x.y.z` string), else the old one with its last number raised.
    pub ota_version: Option<String>,
    /// A firmware that takes writes of report-only data points (and reports them changed).
    pub accept_read_only: bool,
    /// A firmware that takes frames whatever their checksum.
    pub ignore_checksum: bool,
    /// A firmware that answers a command it does not know (with an empty frame of the same
    /// command), where the SDK ignores it.
    pub answer_unknown: bool,
    /// A firmware that leaves these data points out of its answer to a status query (it
    /// reports them only when they change).
    pub never_report: Vec<u8>,
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
            report_gap: None,
            sync_reports: false,
            report_unknown_dp: Vec::new(),
            report_out_of_range: BTreeMap::new(),
            ota_fault: None,
            ota_restart: Duration::from_secs(2),
            ota_version: None,
            accept_read_only: false,
            ignore_checksum: false,
            answer_unknown: false,
            never_report: Vec::new(),
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
    /// Synchronous reports waiting, awaiting their 0x23, and the module's results.
    sync: field::Sync,
    /// Restarting after an update: silent until this time (`None` with `offline`: for good).
    back_at: Option<Instant>,
    /// Silent (restarting after an update, or never back).
    offline: bool,
    /// The version running since the last update, when it changed.
    installed: Option<String>,
    /// Frames the module sent that the MCU does not know, as (command, data).
    unknown: Vec<(u8, Vec<u8>)>,
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
            sync: field::Sync::default(),
            back_at: None,
            offline: false,
            installed: None,
            unknown: Vec::new(),
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
        self.own_report(id);
        true
    }

    /// Changes a bool, value, enum or bitmap data point to raw `v` as the robot itself would,
    /// and reports it (as 0x22 with `sync_reports`). False for an id it lacks or a string.
    pub fn set_dp_raw(&mut self, id: u8, v: i64) -> bool {
        let known = matches!(
            self.dps.get(&id),
            Some(DpValue::Bool(_) | DpValue::Value(_) | DpValue::Enum(_) | DpValue::Bitmap { .. })
        );
        if known {
            self.set_int(id, v);
            self.own_report(id);
        }
        known
    }

    /// The version the MCU runs: its configured one, or the one an update installed.
    pub fn version(&self) -> &str {
        self.installed.as_deref().unwrap_or(&self.config.version)
    }

    /// Whether it is silent, restarting after an update (or never back).
    pub fn offline(&self) -> bool {
        self.offline
    }

    /// Frames the module sent that the MCU does not know (command, data), oldest first.
    pub fn unknown_frames(&self) -> &[(u8, Vec<u8>)] {
        &self.unknown
    }

    /// Sends a frame of any command and data from the next tick (`send 0x99 01 02` on the
    /// simulator's stdin): a command the module does not know, a malformed request.
    pub fn send_frame(&mut self, command: u8, data: Vec<u8>) {
        if let Some(bytes) = self.encode(command, data) {
            self.outbox.push_back(bytes);
        }
    }

    /// Sends a data-point report (0x07) of `total` bytes on the wire from the next tick: the
    /// clean record (DP 15) padded to that length, to see how a frame over the protocol's
    /// maximum is taken (`oversize N` on the stdin).
    pub fn send_oversize(&mut self, total: usize) {
        let len = total.saturating_sub(7 + 4).max(1);
        let mut data = vec![dpid::CLEAN_RECORD, 3];
        data.extend_from_slice(&(len.min(usize::from(u16::MAX)) as u16).to_be_bytes());
        data.extend(std::iter::repeat_n(b'x', len));
        self.send_frame(cmd::DP_REPORT, data);
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
                self.config.pid,
                self.version(),
                self.config.mode
            )
            .into_bytes(),
        }
    }

    /// The frames answering one module frame, each after its delay (the MCU's latency; a slow
    /// MCU's query answer spread out).
    fn handle(&mut self, f: Frame, now: Instant) -> Vec<Outgoing> {
        let latency = self.config.latency;
        let at_once = |frames: Vec<Vec<u8>>| {
            frames
                .into_iter()
                .map(|b| Outgoing::new(latency, b))
                .collect()
        };
        let data = f.data;
        let one = match f.command {
            cmd::HEARTBEAT => {
                let first = !self.heartbeat_answered;
                self.heartbeat_answered = true;
                self.encode(cmd::HEARTBEAT, vec![u8::from(!first)])
            }
            cmd::PRODUCT_INFO => self.encode(cmd::PRODUCT_INFO, self.product_info()),
            cmd::WORK_MODE => {
                let data = self.config.work_mode.map(Vec::from).unwrap_or_default();
                self.encode(cmd::WORK_MODE, data)
            }
            cmd::WIFI_STATE => match data.as_slice() {
                [s] => {
                    self.wifi_state = Some(*s);
                    self.encode(cmd::WIFI_STATE, Vec::new())
                }
                _ => None,
            },
            cmd::DP_COMMAND => return at_once(self.dp_command(&data)),
            cmd::QUERY_STATUS => return self.query_answer(),
            cmd::OTA_START => {
                let packet = self.config.ota_packet;
                let data = self.ota.start(&data, packet);
                data.and_then(|d| self.encode(cmd::OTA_START, d))
            }
            cmd::OTA_PACKET => self.ota_packet(&data, now),
            cmd::DP_REPORT_SYNC_RESULT => {
                self.answers.push((f.command, data.clone()));
                self.sync_result(&data);
                None
            }
            c if MODULE_ANSWERS.contains(&c) => {
                self.answers.push((f.command, data));
                None
            }
            c => {
                self.unknown.push((c, data));
                // The SDK ignores a command it does not know; this firmware answers it.
                self.config
                    .answer_unknown
                    .then(|| self.encode(c, Vec::new()))
                    .flatten()
            }
        };
        at_once(one.into_iter().collect())
    }

    /// The answer to a status query (0x08): a report of every data point, then of those the
    /// profile lacks (`report_unknown_dp`); at once, or a slow MCU's `report_gap` apart.
    fn query_answer(&mut self) -> Vec<Outgoing> {
        let ids: Vec<u8> = self
            .dps
            .keys()
            .copied()
            .filter(|id| !self.config.never_report.contains(id))
            .collect();
        let mut frames: Vec<Vec<u8>> = ids.into_iter().filter_map(|id| self.report(id)).collect();
        frames.extend(self.unknown_reports());
        let delays = self.burst_delays(frames.len());
        frames
            .into_iter()
            .zip(delays)
            .map(|(b, after)| Outgoing::new(after, b))
            .collect()
    }

    /// An OTA packet (0x0b): its ack, if any. After the last one the MCU restarts: silent for
    /// `ota_restart`, then running the new version (or, with an [`OtaFault`], the old one, or
    /// never back).
    fn ota_packet(&mut self, data: &[u8], now: Instant) -> Option<Vec<u8>> {
        let refuse = match self.config.ota_fault {
            Some(OtaFault::RefusePacket(at)) => Some(at),
            _ => None,
        };
        let was_complete = matches!(self.ota.state, OtaState::Complete { .. });
        let ack = self.ota.packet(data, self.config.stop_acking_at.or(refuse));
        let answer = ack
            .then(|| self.encode(cmd::OTA_PACKET, Vec::new()))
            .flatten();
        if !was_complete && matches!(self.ota.state, OtaState::Complete { .. }) {
            self.offline = true;
            self.back_at = match self.config.ota_fault {
                Some(OtaFault::NeverBack) => None,
                _ => Some(now + self.config.ota_restart),
            };
        }
        answer
    }

    /// The MCU comes back after an update, if it is time: restarted, running the image's
    /// version (or its old one, with [`OtaFault::OldVersion`]).
    fn come_back(&mut self, now: Instant) {
        if !self.offline || self.back_at.is_none_or(|at| now < at) {
            return;
        }
        self.offline = false;
        self.back_at = None;
        if self.config.ota_fault != Some(OtaFault::OldVersion) {
            let next = self
                .config
                .ota_version
                .clone()
                .or_else(|| crate::ops::tuya::image_version(&self.ota.image));
            self.installed = Some(next.unwrap_or_else(|| bumped(self.version())));
        }
        self.restart();
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

/// Commands the module sends in answer to the MCU's own requests (recorded in
/// [`TuyaMcu::answers`]).
const MODULE_ANSWERS: [u8; 17] = [
    cmd::RESET_WIFI,
    cmd::RESET_WIFI_MODE,
    cmd::WIFI_TEST,
    cmd::LOCAL_TIME,
    cmd::UTC_TIME,
    cmd::NET_STATUS,
    cmd::MAC,
    cmd::WIFI_RSSI,
    cmd::HEARTBEAT_STOP,
    cmd::EXTENDED,
    cmd::FREE_MEMORY,
    cmd::STREAM,
    cmd::MAPS_STREAM,
    cmd::WIFI_CONNECT_TEST,
    cmd::NEW_FUNC,
    cmd::WEATHER_OPEN,
    cmd::WEATHER_DATA,
];

/// `1.0.0` → `1.0.1`: the version after an update whose image names none.
fn bumped(version: &str) -> String {
    let mut parts: Vec<String> = version.split('.').map(str::to_string).collect();
    if let Some(last) = parts.last_mut()
        && let Ok(n) = last.parse::<u32>()
    {
        *last = (n + 1).to_string();
    }
    parts.join(".")
}

impl TuyaMcu {
    /// The module frames in what the decoder holds: good ones, and with `ignore_checksum`
    /// those whose checksum is wrong, read all the same. Frames of another version than the
    /// module's are dropped, as the SDK does.
    fn frames(&mut self) -> Vec<Frame> {
        let lax = self.config.ignore_checksum;
        self.decoder
            .by_ref()
            .filter_map(|r| match r {
                Ok(f) => Some(f),
                Err(crate::protocol::FrameError::Checksum { bytes, .. })
                    if lax && bytes.len() >= 7 =>
                {
                    Some(Frame {
                        version: bytes[2],
                        command: bytes[3],
                        data: bytes[6..bytes.len() - 1].to_vec(),
                    })
                }
                Err(_) => None,
            })
            .filter(|f| f.version == VERSION_MODULE)
            .collect()
    }
}

impl Device for TuyaMcu {
    fn receive(&mut self, bytes: &[u8], baud: u32, now: Instant) -> Vec<Outgoing> {
        let mut out = Vec::new();
        if self.config.echo {
            out.push(Outgoing::new(Duration::ZERO, bytes.to_vec()));
        }
        self.come_back(now);
        if self.config.baud.is_some_and(|b| b != baud) || self.offline {
            // Framing errors at the wrong rate (or a restarting MCU): whatever was
            // half-received is lost too.
            self.decoder.clear();
            return out;
        }
        self.decoder.push(bytes);
        let frames = self.frames();
        let was_cleaning = self.cleaning();
        for f in frames {
            out.extend(self.handle(f, now));
        }
        if self.cleaning() && !was_cleaning {
            self.last_drain = Some(now);
        }
        out
    }

    fn tick(&mut self, now: Instant) -> Vec<Outgoing> {
        self.come_back(now);
        if self.offline {
            return Vec::new();
        }
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
        if let Some(b) = self.next_sync(now) {
            out.push(Outgoing::new(Duration::ZERO, b));
        }
        out
    }
}
