//! The robot vacuum's MCU as the Tuya MCU SDK behaves (seed 003, PROTOCOL_NOTES §3); botbench
//! plays the Wi-Fi module.
//!
//! It answers module frames (version 0x00; any other version is dropped silently) with version
//! 0x03 frames: heartbeat, product info, working mode, Wi-Fi state, data-point commands and
//! queries, and OTA. It also sends requests of its own on demand (local time, Wi-Fi test, ...)
//! from [`Device::tick`] and records the module's answers.

use super::{Device, Outgoing};
use crate::profile::registry::{BUILTIN, parse};
use crate::profile::{Access, DataPointDef, Profile, Protocol, Value};
use crate::protocol::tuya::dp::{DataPoint, DpType, DpValue, encode_one};
use crate::protocol::tuya::{Frame, TuyaDecoder, VERSION_MODULE, cmd};
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
        }
    }
}

/// Where an OTA update stands.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum OtaState {
    /// No update started.
    Idle,
    /// Receiving packets.
    Receiving {
        /// The image size announced.
        size: u32,
        /// Bytes received so far.
        received: u32,
        /// The packet size agreed.
        packet: usize,
    },
    /// The last packet came and the image is whole.
    Complete {
        /// Its size.
        size: u32,
        /// Its CRC-32 (IEEE).
        crc32: u32,
    },
    /// Given up, silently, as the SDK does.
    Aborted {
        /// Why.
        reason: String,
    },
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

/// CRC-32 (IEEE 802.3, as zlib), to check an OTA image.
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = 0xFFFF_FFFFu32;
    for &b in bytes {
        crc ^= b as u32;
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// The value the vacuum starts with for a data point.
fn initial_value(def: &DataPointDef) -> DpValue {
    let int = |v: i64| match def.dp_type {
        DpType::Bool => DpValue::Bool(v != 0),
        DpType::Value => DpValue::Value(v as i32),
        DpType::Enum => DpValue::Enum(v as u8),
        DpType::Bitmap => DpValue::Bitmap {
            bits: v as u32,
            width: def.field.ty.width().unwrap_or(1) as u8,
        },
        DpType::String => DpValue::String(v.to_string()),
        DpType::Raw => DpValue::Raw(Vec::new()),
    };
    match def.id {
        dpid::POWER => int(1),
        dpid::SUCTION => int(1),
        dpid::DIRECTION => int(4),
        dpid::BATTERY => int(80),
        dpid::EDGE_BRUSH_LIFE => int(90),
        dpid::ROLL_BRUSH_LIFE => int(85),
        dpid::FILTER_LIFE => int(70),
        dpid::CLEAN_AREA => int(35),
        dpid::CLEAN_TIME => int(28),
        dpid::CLEAN_RECORD if def.dp_type == DpType::String => {
            DpValue::String("20180411051102008000020".into())
        }
        dpid::MAP_PARAMS if def.dp_type == DpType::Raw => DpValue::Raw(vec![0x00, 0x00, 0xFF]),
        _ => int(def.field.default.unwrap_or(0)),
    }
}

fn as_value(v: &DpValue) -> Value {
    match v {
        DpValue::Bool(b) => Value::Int(*b as i64),
        DpValue::Value(x) => Value::Int(*x as i64),
        DpValue::Enum(e) => Value::Int(*e as i64),
        DpValue::Bitmap { bits, .. } => Value::Int(*bits as i64),
        DpValue::String(s) => Value::Text(s.clone()),
        DpValue::Raw(b) => Value::Bytes(b.clone()),
    }
}

/// One data point read from a 0x06 frame, as the SDK walks them: id, type byte, value bytes.
struct RawDp<'a> {
    id: u8,
    ty: u8,
    value: &'a [u8],
}

fn walk_dps(data: &[u8]) -> Vec<RawDp<'_>> {
    let mut out = Vec::new();
    let mut at = 0;
    while let Some(&[id, ty, hi, lo]) = data.get(at..at + 4) {
        let len = u16::from_be_bytes([hi, lo]) as usize;
        let Some(value) = data.get(at + 4..at + 4 + len) else {
            break;
        };
        out.push(RawDp { id, ty, value });
        at += 4 + len;
    }
    out
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
    outbox: VecDeque<Vec<u8>>,
    answers: Vec<(u8, Vec<u8>)>,
    ota: OtaState,
    ota_image: Vec<u8>,
    ota_stalled: bool,
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
            .map(|d| (d.id, initial_value(d)))
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
            outbox: VecDeque::new(),
            answers: Vec::new(),
            ota: OtaState::Idle,
            ota_image: Vec::new(),
            ota_stalled: false,
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
        if matches!(self.ota, OtaState::Receiving { .. }) {
            self.ota = OtaState::Idle;
            self.ota_image.clear();
        }
        self.ota_stalled = false;
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
        &self.ota
    }

    /// The image received so far (all of it once complete).
    pub fn ota_image(&self) -> &[u8] {
        &self.ota_image
    }

    /// Queues a local-time request (0x1c), sent by the next tick.
    pub fn request_local_time(&mut self) {
        self.queue(cmd::LOCAL_TIME, Vec::new());
    }

    /// Queues a Wi-Fi production test request (0x0e).
    pub fn request_wifi_test(&mut self) {
        self.queue(cmd::WIFI_TEST, Vec::new());
    }

    /// Queues a Wi-Fi reset request (0x04).
    pub fn reset_wifi(&mut self) {
        self.queue(cmd::RESET_WIFI, Vec::new());
    }

    /// Queues a Wi-Fi reset into a pairing mode (0x05; 0 smartconfig, 1 AP).
    pub fn reset_wifi_mode(&mut self, mode: u8) {
        self.queue(cmd::RESET_WIFI_MODE, vec![mode]);
    }

    /// Queues a network-status request (0x2b).
    pub fn request_net_status(&mut self) {
        self.queue(cmd::NET_STATUS, Vec::new());
    }

    /// Queues a MAC-address request (0x2d).
    pub fn request_mac(&mut self) {
        self.queue(cmd::MAC, Vec::new());
    }

    fn queue(&mut self, command: u8, data: Vec<u8>) {
        if let Ok(bytes) = Frame::from_mcu(command, data).encode() {
            self.outbox.push_back(bytes);
        }
    }

    fn frame(&self, command: u8, data: Vec<u8>) -> Option<Outgoing> {
        let bytes = Frame::from_mcu(command, data).encode().ok()?;
        Some(Outgoing::new(self.config.latency, bytes))
    }

    /// A 0x07 frame reporting one data point.
    fn report(&self, id: u8) -> Option<Vec<u8>> {
        let value = self.dps.get(&id)?.clone();
        let mut data = Vec::new();
        encode_one(&DataPoint { id, value }, &mut data).ok()?;
        Frame::from_mcu(cmd::DP_REPORT, data).encode().ok()
    }

    fn reply_report(&self, id: u8) -> Option<Outgoing> {
        Some(Outgoing::new(self.config.latency, self.report(id)?))
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

    fn int(&self, id: u8) -> i64 {
        match self.dps.get(&id).map(as_value) {
            Some(Value::Int(i)) => i,
            _ => 0,
        }
    }

    /// Sets an integer-like data point, keeping its type; returns whether it changed.
    fn set_int(&mut self, id: u8, v: i64) -> bool {
        let Some(old) = self.dps.get(&id) else {
            return false;
        };
        let new = match old {
            DpValue::Bool(_) => DpValue::Bool(v != 0),
            DpValue::Value(_) => DpValue::Value(v as i32),
            DpValue::Enum(_) => DpValue::Enum(v as u8),
            DpValue::Bitmap { width, .. } => DpValue::Bitmap {
                bits: v as u32,
                width: *width,
            },
            _ => return false,
        };
        let changed = *old != new;
        self.dps.insert(id, new);
        changed
    }

    fn cleaning(&self) -> bool {
        (1..=4).contains(&self.int(dpid::STATUS))
    }

    /// Applies a commanded data point and its natural side effects. Returns the ids to report,
    /// the commanded one first.
    fn apply(&mut self, id: u8, value: DpValue, now: Instant) -> Vec<u8> {
        let was_cleaning = self.cleaning();
        let on = matches!(value, DpValue::Bool(true));
        let n = match &value {
            DpValue::Enum(e) => *e as i64,
            _ => 0,
        };
        self.dps.insert(id, value);
        let mut changed = vec![id];
        let mut set = |s: &mut Self, id: u8, v: i64| {
            if s.set_int(id, v) {
                changed.push(id);
            }
        };
        match id {
            dpid::POWER if !on => {
                set(self, dpid::CLEAN_SWITCH, 0);
                set(self, dpid::STATUS, status::STANDBY as i64);
                set(self, dpid::MODE, 0);
            }
            dpid::CLEAN_SWITCH if on => {
                set(self, dpid::POWER, 1);
                if self.int(dpid::MODE) == 0 {
                    set(self, dpid::MODE, 2);
                }
                set(self, dpid::STATUS, status::SMART_CLEAN as i64);
            }
            dpid::CLEAN_SWITCH => set(self, dpid::STATUS, status::STANDBY as i64),
            dpid::MODE => {
                let st = match n {
                    0 => status::STANDBY,
                    3 => status::WALL_CLEAN,
                    4 => status::MOP_CLEAN,
                    5..=7 => status::SPOT_CLEAN,
                    11 => status::GOTO_CHARGE,
                    _ => status::SMART_CLEAN,
                };
                set(self, dpid::STATUS, st as i64);
                set(self, dpid::CLEAN_SWITCH, i64::from((1..=4).contains(&st)));
                if n != 0 {
                    set(self, dpid::POWER, 1);
                }
            }
            dpid::EDGE_BRUSH_RESET if on => set(self, dpid::EDGE_BRUSH_LIFE, 100),
            dpid::ROLL_BRUSH_RESET if on => set(self, dpid::ROLL_BRUSH_LIFE, 100),
            dpid::FILTER_RESET if on => set(self, dpid::FILTER_LIFE, 100),
            _ => {}
        }
        if self.cleaning() && !was_cleaning {
            self.last_drain = Some(now);
        }
        changed
    }

    /// Handles a 0x06 frame: each valid, writable DP of the right type is applied and reported.
    fn dp_command(&mut self, data: &[u8], now: Instant) -> Vec<Outgoing> {
        let mut out = Vec::new();
        for raw in walk_dps(data) {
            let Some(def) = self.profile.data_point(raw.id).cloned() else {
                continue;
            };
            if def.access != Access::ReadWrite || raw.ty != def.dp_type.byte() {
                continue;
            }
            let value = match (def.dp_type, raw.value) {
                (DpType::Bool, [b]) => DpValue::Bool(*b != 0),
                (DpType::Enum, [e]) => DpValue::Enum(*e),
                (DpType::Value, &[a, b, c, d]) => DpValue::Value(i32::from_be_bytes([a, b, c, d])),
                (DpType::Bitmap, v) if matches!(v.len(), 1 | 2 | 4) => {
                    let mut b = [0u8; 4];
                    b[4 - v.len()..].copy_from_slice(v);
                    DpValue::Bitmap {
                        bits: u32::from_be_bytes(b),
                        width: def.field.ty.width().unwrap_or(v.len()).min(4) as u8,
                    }
                }
                (DpType::String, v) => match std::str::from_utf8(v) {
                    Ok(s) => DpValue::String(s.to_string()),
                    Err(_) => continue,
                },
                (DpType::Raw, v) => DpValue::Raw(v.to_vec()),
                _ => continue,
            };
            if def.field.check(&as_value(&value)).is_err() {
                continue;
            }
            for id in self.apply(raw.id, value, now) {
                out.extend(self.reply_report(id));
            }
        }
        out
    }

    fn ota_start(&mut self, data: &[u8]) -> Option<Outgoing> {
        let &[a, b, c, d] = data else {
            return None;
        };
        let size = u32::from_be_bytes([a, b, c, d]);
        self.ota = OtaState::Receiving {
            size,
            received: 0,
            packet: self.config.ota_packet.size(),
        };
        self.ota_image.clear();
        self.ota_stalled = false;
        let answer = match self.config.ota_packet {
            OtaPacketAnswer::Option(o) => vec![o],
            OtaPacketAnswer::Empty => Vec::new(),
        };
        self.frame(cmd::OTA_START, answer)
    }

    fn ota_abort(&mut self, reason: String) {
        self.ota = OtaState::Aborted { reason };
    }

    fn ota_packet(&mut self, data: &[u8]) -> Option<Outgoing> {
        let (head, chunk) = data.split_first_chunk::<4>()?;
        let offset = u32::from_be_bytes(*head);
        let OtaState::Receiving {
            size,
            received,
            packet,
        } = self.ota
        else {
            return None;
        };
        if self.config.stop_acking_at.is_some_and(|n| offset >= n) {
            self.ota_stalled = true;
        }
        if self.ota_stalled {
            return None;
        }
        if chunk.len() > packet {
            self.ota_abort(format!(
                "packet of {} bytes at offset {offset}, over the agreed {packet}",
                chunk.len()
            ));
            return None;
        }
        let len = chunk.len() as u32;
        if chunk.is_empty() && offset >= size {
            if received == size {
                self.ota = OtaState::Complete {
                    size,
                    crc32: crc32(&self.ota_image),
                };
            } else {
                self.ota_abort(format!("image ended at {received} of {size} bytes"));
                return None;
            }
        } else if offset == received && received.saturating_add(len) <= size {
            self.ota_image.extend_from_slice(chunk);
            self.ota = OtaState::Receiving {
                size,
                received: received + len,
                packet,
            };
        } else if offset.checked_add(len) == Some(received)
            && self.ota_image.get(offset as usize..) == Some(chunk)
        {
            // The module resent the last packet (our ack was lost): ack it again.
        } else {
            self.ota_abort(format!(
                "packet at offset {offset} of {len} bytes, expected offset {received} (size {size})"
            ));
            return None;
        }
        self.frame(cmd::OTA_PACKET, Vec::new())
    }

    fn handle(&mut self, f: Frame, now: Instant) -> Vec<Outgoing> {
        let data = f.data;
        match f.command {
            cmd::HEARTBEAT => {
                let first = !self.heartbeat_answered;
                self.heartbeat_answered = true;
                self.frame(cmd::HEARTBEAT, vec![u8::from(!first)])
                    .into_iter()
                    .collect()
            }
            cmd::PRODUCT_INFO => self
                .frame(cmd::PRODUCT_INFO, self.product_info())
                .into_iter()
                .collect(),
            cmd::WORK_MODE => {
                let data = self.config.work_mode.map(Vec::from).unwrap_or_default();
                self.frame(cmd::WORK_MODE, data).into_iter().collect()
            }
            cmd::WIFI_STATE => match data.as_slice() {
                [s] => {
                    self.wifi_state = Some(*s);
                    self.frame(cmd::WIFI_STATE, Vec::new())
                        .into_iter()
                        .collect()
                }
                _ => Vec::new(),
            },
            cmd::DP_COMMAND => self.dp_command(&data, now),
            cmd::QUERY_STATUS => {
                let ids: Vec<u8> = self.dps.keys().copied().collect();
                ids.into_iter()
                    .filter_map(|id| self.reply_report(id))
                    .collect()
            }
            cmd::OTA_START => self.ota_start(&data).into_iter().collect(),
            cmd::OTA_PACKET => self.ota_packet(&data).into_iter().collect(),
            cmd::RESET_WIFI
            | cmd::RESET_WIFI_MODE
            | cmd::WIFI_TEST
            | cmd::LOCAL_TIME
            | cmd::NET_STATUS
            | cmd::MAC => {
                self.answers.push((f.command, data));
                Vec::new()
            }
            _ => Vec::new(),
        }
    }

    fn drain_battery(&mut self, now: Instant) -> Option<Vec<u8>> {
        if !self.cleaning() {
            self.last_drain = None;
            return None;
        }
        let every = self
            .config
            .battery_drain_every
            .max(Duration::from_millis(1));
        let last = *self.last_drain.get_or_insert(now);
        if now.saturating_duration_since(last) < every {
            return None;
        }
        self.last_drain = Some(last + every);
        let battery = self.int(dpid::BATTERY);
        // A little jitter in when the gauge ticks over, as a real one does.
        if self.rng.u8(0..10) == 0 || battery <= 0 {
            return None;
        }
        self.set_int(dpid::BATTERY, battery - 1);
        self.report(dpid::BATTERY)
    }
}

impl Device for TuyaMcu {
    fn receive(&mut self, bytes: &[u8], baud: u32, now: Instant) -> Vec<Outgoing> {
        if self.config.baud.is_some_and(|b| b != baud) {
            // Framing errors at the wrong rate: whatever was half-received is lost too.
            self.decoder.clear();
            return Vec::new();
        }
        self.decoder.push(bytes);
        let frames: Vec<Frame> = self
            .decoder
            .by_ref()
            .filter_map(Result::ok)
            .filter(|f| f.version == VERSION_MODULE)
            .collect();
        let mut out = Vec::new();
        for f in frames {
            out.extend(self.handle(f, now));
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
        out
    }
}
