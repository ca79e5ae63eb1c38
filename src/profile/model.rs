//! The shape of a device profile, as written in `assets/profiles/*.ron`.
//!
//! Every integer field's `range` and `default` are in raw (wire) units; `scale` turns a raw value
//! into the displayed one (`display = raw × scale`), so `scale: 0.01` shows 275 as 2.75.

use crate::i18n::Text;
use crate::protocol::tuya::dp::DpType;
use serde::{Deserialize, Serialize};

/// The wire protocol a profile speaks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Protocol {
    /// The framed MSP protocol (window cleaner, solar cleanbot).
    Msp,
    /// The UART bus-servo protocol.
    Servo,
    /// The Tuya MCU protocol (botbench is the Wi-Fi module).
    Tuya,
}

impl Protocol {
    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Protocol::Msp => "msp",
            Protocol::Servo => "servo",
            Protocol::Tuya => "tuya",
        }
    }

    /// The byte order of multi-byte fields.
    pub fn byte_order(self) -> ByteOrder {
        match self {
            Protocol::Msp | Protocol::Servo => ByteOrder::Little,
            Protocol::Tuya => ByteOrder::Big,
        }
    }
}

/// Byte order of multi-byte fields.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum ByteOrder {
    /// Least significant byte first (MSP, servo).
    Little,
    /// Most significant byte first (Tuya).
    Big,
}

/// How an MSP device code is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum DeviceCode {
    /// Learned from the `hw` byte of CMD_VERSION; the number is used until then.
    Auto(u8),
    /// Always this code.
    Pinned(u8),
}

impl DeviceCode {
    /// The code to use before (or instead of) learning it.
    pub fn initial(self) -> u8 {
        match self {
            DeviceCode::Auto(c) | DeviceCode::Pinned(c) => c,
        }
    }
}

/// A device profile.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Profile {
    /// The profile's name, e.g. `window-cleaner`; it is also the file name.
    pub id: String,
    /// What the device is.
    pub name: Text,
    /// Its protocol.
    pub protocol: Protocol,
    /// The usual baud rate.
    pub baud: u32,
    /// MSP only: the device code of requests.
    #[serde(default)]
    pub device_code: Option<DeviceCode>,
    /// Groups that panels show commands under, in order.
    #[serde(default)]
    pub groups: Vec<Group>,
    /// The command set.
    pub commands: Vec<Command>,
    /// Servo only: the parameters that READ_DATA / WRITE_DATA address by `data_id`.
    #[serde(default)]
    pub params: Vec<Param>,
    /// Tuya only: the product's data points.
    #[serde(default)]
    pub data_points: Vec<DataPointDef>,
    /// Tuya only: the largest MCU firmware image an update may send, in bytes
    /// ([`Profile::ota_max_bytes`] gives [`DEFAULT_OTA_MAX_BYTES`] when the profile is silent).
    #[serde(default)]
    pub ota_max_bytes: Option<u32>,
    /// Live plots: which telemetry fields to draw together.
    #[serde(default)]
    pub plots: Vec<Plot>,
    /// The panels the window shows for this device, in order (the packet monitor is always
    /// there). One meaning: a listed panel is shown, unless it names a CMD_VERSION capability
    /// `flag` (MSP) that the device reports clear. Each is checked at load for what it shows
    /// (Tuning needs a Set, Solar a command with role Drive...).
    #[serde(default)]
    pub panels: Vec<PanelRule>,
    /// Relations between fields that every write must keep (minimum ≤ default ≤ maximum...).
    #[serde(default)]
    pub relations: Vec<Relation>,
    /// What STOP sends, in order: the commands that bring the robot to rest (motors, fan,
    /// spray off) with every field's value. The window's STOP, the self-test's safe state and
    /// the "running" indicator all read it here ([`crate::profile::stop`]).
    #[serde(default)]
    pub stop: Vec<StopCommand>,
}

/// One command of the profile's STOP: the command and the value of each of its request fields,
/// as display text (`{"motor": "stop"}`, `{"pwm": "0"}`). Checked at load: the command exists
/// and is sent by the host, every field has a value the field takes, no other names.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StopCommand {
    /// The command's canonical ident (or number).
    pub command: String,
    /// Field ident → value, as a person writes it.
    #[serde(default)]
    pub values: std::collections::BTreeMap<String, String>,
}

/// The largest MCU firmware image a Tuya update sends unless the profile says otherwise: 512 KiB,
/// the flash of the larger MCUs Tuya's MCU SDK is built for (and over 9 minutes at 9600 baud).
/// A file past it is the wrong file (the 20 MB image of another product would take 6 hours).
pub const DEFAULT_OTA_MAX_BYTES: u32 = 512 * 1024;

impl Profile {
    /// Tuya: the largest firmware image an update may send, in bytes.
    pub fn ota_max_bytes(&self) -> u32 {
        self.ota_max_bytes.unwrap_or(DEFAULT_OTA_MAX_BYTES)
    }

    /// A profile with no commands, parameters or data points: what a simulator falls back to
    /// should its built-in profile ever fail to parse.
    pub fn empty(id: &str, protocol: Protocol, baud: u32) -> Self {
        Self {
            id: id.to_string(),
            name: Text {
                en: id.to_string(),
                zh: id.to_string(),
            },
            protocol,
            baud,
            device_code: None,
            groups: Vec::new(),
            commands: Vec::new(),
            params: Vec::new(),
            data_points: Vec::new(),
            ota_max_bytes: None,
            plots: Vec::new(),
            panels: Vec::new(),
            relations: Vec::new(),
            stop: Vec::new(),
        }
    }
}

/// How two values compare in a [`Relation`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum RelOp {
    /// `low ≤ high`.
    #[default]
    Le,
    /// `low < high`.
    Lt,
}

impl RelOp {
    /// The sign, `≤` or `<`.
    pub fn sign(self) -> &'static str {
        match self {
            RelOp::Le => "≤",
            RelOp::Lt => "<",
        }
    }
}

/// Two fields whose values must keep an order, compared in display units (after scale and
/// conversion). Each side is `COMMAND.field` (a field of one command's payload: a Get's
/// reply, which its Set sends too) or, in a servo profile, a parameter's ident. Both sides name
/// fields of one command, or two parameters. Checked at load (unknown fields, fields of two
/// commands, the fields' defaults) and before every write.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Relation {
    /// The side that must be smaller, e.g. `MSP_GET_USE_FAN_OUTPUT_PID.minTarget`.
    pub low: String,
    /// `Le` (the default) or `Lt`.
    #[serde(default)]
    pub op: RelOp,
    /// The side that must be larger.
    pub high: String,
}

/// The panels a profile can name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum PanelKind {
    /// Ping, version, power state.
    Device,
    /// Parameters (Get/Set pairs).
    Tuning,
    /// Live plots.
    Telemetry,
    /// Parameter presets.
    Presets,
    /// Action commands.
    Actions,
    /// The solar cleanbot's readouts, drive controls and STOP.
    Solar,
    /// The production self-test (test plans).
    SelfTest,
    /// Bus servos: scan, parameters, provisioning, motion.
    ServoBench,
    /// Tuya: the Wi-Fi module's side, data points, MCU requests, OTA.
    TuyaConsole,
}

/// A panel of a profile and the capability it needs.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PanelRule {
    /// The panel.
    pub panel: PanelKind,
    /// The CMD_VERSION capability bit (0-7) the panel needs; `None`: always shown.
    #[serde(default)]
    pub flag: Option<u8>,
}

/// A group of commands on a panel (e.g. "Fan").
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Group {
    /// Referenced by [`Command::group`].
    pub id: String,
    /// Shown as the group's heading.
    pub name: Text,
}

/// What a command does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum CommandKind {
    /// Reads a tunable parameter; `pair` names its Set.
    Get,
    /// Writes a tunable parameter; `pair` names its Get, whose reply layout it sends.
    Set,
    /// Reads live or read-only data.
    Telemetry,
    /// Makes the device do something.
    Action,
    /// A command whose payload layout is not published: bytes only.
    Raw,
}

/// Who sends a command's first frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Initiator {
    /// botbench asks, the device answers.
    #[default]
    Host,
    /// The device asks (Tuya MCU requests), botbench answers.
    Device,
}

/// One command of a profile.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Command {
    /// The command number on the wire.
    pub id: u8,
    /// The canonical identifier from the protocol document, e.g. `MSP_GET_PWMVALUE`.
    pub ident: String,
    /// A readable name.
    pub name: Text,
    /// What it does.
    pub kind: CommandKind,
    /// Get↔Set partner's id.
    #[serde(default)]
    pub pair: Option<u8>,
    /// The panel group.
    #[serde(default)]
    pub group: Option<String>,
    /// Who sends first.
    #[serde(default)]
    pub initiator: Initiator,
    /// MSP: a device code this command always uses (CMD_VERSION goes to 0x00).
    #[serde(default)]
    pub device: Option<u8>,
    /// Tuya: the command word of the answer when it differs (0x06 and 0x08 are answered by 0x07).
    #[serde(default)]
    pub reply_command: Option<u8>,
    /// Servo: the device answers only when its response switch is on.
    #[serde(default)]
    pub reply_optional: bool,
    /// The robot moves: ask the operator first.
    #[serde(default)]
    pub confirm: bool,
    /// On a Get: its values are the robot's tuning, meant to be the same on every unit, so
    /// presets capture, compare and apply it (with its Set). A unit's own state (its auto-test
    /// result, a calibration) is left unmarked and never copied from one unit to the next.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub tunable: bool,
    /// What code finds this command by (MSP core, the solar drive or heartbeat).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub role: Option<super::roles::CommandRole>,
    /// The initiator's payload. A Set with none sends its Get's reply layout; a Set with its own
    /// (firmware that takes fewer fields than its Get answers with) sends that, and every field
    /// of it must be a field of the Get's reply, so that the write can be read back.
    #[serde(default)]
    pub request: Vec<Field>,
    /// The answer's payload.
    #[serde(default)]
    pub reply: Vec<Field>,
}

/// The type of a payload field.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum FieldType {
    /// Unsigned 8-bit.
    U8,
    /// Signed 8-bit.
    I8,
    /// Unsigned 16-bit.
    U16,
    /// Signed 16-bit.
    I16,
    /// Unsigned 32-bit.
    U32,
    /// Signed 32-bit.
    I32,
    /// One byte, 0 or 1.
    Bool,
    /// Bytes: a fixed count, or the rest of the payload.
    Bytes(Len),
    /// Text (UTF-8): a fixed count of bytes, or the rest of the payload.
    Str(Len),
    /// Servo: a parameter id; the next field's layout is that parameter's.
    ParamId,
    /// Servo: the value of the parameter named by the preceding `ParamId` field.
    ParamValue,
    /// Servo: the 32-byte user block, i.e. the read-write parameters packed in id order.
    ParamBlock,
    /// Tuya: a list of data points, each named by the profile's `data_points`.
    DataPoints,
    /// Servo, command 25: the number of a command of the profile (one byte), whose request
    /// layout the records of the following `Records` field have.
    CommandId,
    /// Servo, command 25: the length of each record (one byte); computed when encoding.
    RecordLen,
    /// Servo, command 25: the number of records (one byte); computed when encoding.
    RecordCount,
    /// Servo, command 25: the rest of the payload, `RecordCount` records of `RecordLen` bytes,
    /// each laid out as the request of the `CommandId` command. Record `i`'s values are named
    /// `ident[i]` (`servo_id[0]`, `angle[0]`, `servo_id[1]`...).
    Records,
}

/// The length of a bytes or text field.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Len {
    /// Exactly this many bytes.
    Fixed(usize),
    /// Everything left in the payload.
    Rest,
}

impl FieldType {
    /// The raw range an integer type can hold, or `None` for the other types.
    pub fn int_bounds(self) -> Option<(i64, i64)> {
        Some(match self {
            FieldType::U8 => (0, u8::MAX as i64),
            FieldType::I8 => (i8::MIN as i64, i8::MAX as i64),
            FieldType::U16 => (0, u16::MAX as i64),
            FieldType::I16 => (i16::MIN as i64, i16::MAX as i64),
            FieldType::U32 => (0, u32::MAX as i64),
            FieldType::I32 => (i32::MIN as i64, i32::MAX as i64),
            FieldType::Bool => (0, 1),
            FieldType::CommandId | FieldType::RecordLen | FieldType::RecordCount => {
                (0, u8::MAX as i64)
            }
            _ => return None,
        })
    }

    /// The width on the wire of a fixed-size type.
    pub fn width(self) -> Option<usize> {
        Some(match self {
            FieldType::U8
            | FieldType::I8
            | FieldType::Bool
            | FieldType::ParamId
            | FieldType::CommandId
            | FieldType::RecordLen
            | FieldType::RecordCount => 1,
            FieldType::U16 | FieldType::I16 => 2,
            FieldType::U32 | FieldType::I32 => 4,
            FieldType::Bytes(Len::Fixed(n)) | FieldType::Str(Len::Fixed(n)) => n,
            FieldType::ParamBlock => 32,
            _ => return None,
        })
    }
}

fn one() -> f64 {
    1.0
}

fn is_one(x: &f64) -> bool {
    *x == 1.0
}

/// A payload field.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Field {
    /// The canonical identifier from the protocol document, e.g. `pwmValue`.
    pub ident: String,
    /// A readable name.
    pub name: Text,
    /// The wire type.
    #[serde(rename = "type")]
    pub ty: FieldType,
    /// display = raw × scale.
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub scale: f64,
    /// The displayed unit.
    #[serde(default)]
    pub unit: String,
    /// The allowed raw range, inclusive; the type's range when absent.
    #[serde(default)]
    pub range: Option<(i64, i64)>,
    /// Named values (an enum). With labels and no `range`, only labelled values can be written.
    #[serde(default)]
    pub labels: Vec<Label>,
    /// Named bits (a bit field).
    #[serde(default)]
    pub bits: Vec<Bit>,
    /// The raw value the firmware starts with, where known.
    #[serde(default)]
    pub default: Option<i64>,
    /// The field may be missing at the end of a payload (older firmware).
    #[serde(default)]
    pub optional: bool,
    /// The firmware leaves the field out of the payload when it holds this raw value (the
    /// earlier configurator drops SET 224's second byte when it is 0). A payload one field
    /// shorter than the layout then reads as this value. At most one such field per layout, in
    /// a layout of fixed-size fields.
    #[serde(default)]
    pub omitted_when: Option<i64>,
    /// What the raw value stands for, when it is not `raw × scale` (a thermistor reading to be
    /// converted to °C). The converted value is shown with `unit`, the raw value beside it.
    #[serde(default)]
    pub convert: Option<Conversion>,
}

/// A conversion from a field's raw value to the value shown.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Conversion {
    /// A `full_scale`-count ADC reading of an NTC thermistor (its B constant `beta`, in K,
    /// nominal at 25 °C) in a divider with a resistor of its nominal resistance, to °C:
    /// `T = 1 / (ln(raw / (full_scale − raw)) / beta + 1 / 298.15) − 273.15`, as the servo
    /// vendor's SDK (1.3.x, Python and C) converts parameter 4 and the MONITOR temperature with
    /// `beta: 3435.0, full_scale: 4096`. Undefined for raw 0 and raw ≥ `full_scale`.
    Ntc {
        /// The B constant, K.
        beta: f64,
        /// The ADC's full scale, counts (4096 for 12 bits).
        full_scale: u32,
    },
}

/// A named value of an enum field.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Label {
    /// The raw value.
    pub value: i64,
    /// The canonical identifier, e.g. `standby`.
    pub ident: String,
    /// A readable name.
    pub name: Text,
}

/// A named bit of a bit field.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Bit {
    /// The bit number, 0 = least significant.
    pub bit: u8,
    /// The canonical identifier.
    pub ident: String,
    /// A readable name.
    pub name: Text,
}

/// Whether a parameter or data point can be written, and whether it is read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Access {
    /// Read or reported only (a Tuya schema's mode `ro`).
    ReadOnly,
    /// Read and written (mode `rw`).
    ReadWrite,
    /// Tuya only: sent by the module, never reported by the MCU (mode `wr`, e.g. a "beep once"
    /// trigger). Servo parameters are never write-only (checked at load).
    WriteOnly,
}

impl Access {
    /// Whether the module (or the host) may write it.
    pub fn writable(self) -> bool {
        matches!(self, Access::ReadWrite | Access::WriteOnly)
    }

    /// Whether the device reports (or is read for) it.
    pub fn reported(self) -> bool {
        matches!(self, Access::ReadOnly | Access::ReadWrite)
    }

    /// The Tuya schema's `mode`: `ro`, `rw` or `wr`.
    pub fn tuya_mode(self) -> &'static str {
        match self {
            Access::ReadOnly => "ro",
            Access::ReadWrite => "rw",
            Access::WriteOnly => "wr",
        }
    }
}

/// A servo parameter (`data_id`).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Param {
    /// The `data_id`.
    pub id: u8,
    /// Read-only (1-8) or user (32-53).
    pub access: Access,
    /// Reserved by the maker: shown, and written back as read in the user block, never edited.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub reserved: bool,
    /// What code finds this parameter by (the servo id, the baud option and its rates, the
    /// serial number).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub role: Option<super::roles::ParamRole>,
    /// Its layout, name, unit, range and labels.
    pub field: Field,
}

/// A Tuya data point of the product.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DataPointDef {
    /// The dpid.
    pub id: u8,
    /// Report-only or commandable.
    pub access: Access,
    /// The type on the wire.
    pub dp_type: DpType,
    /// Its name, range, unit, labels or bit names. The field type must suit `dp_type`:
    /// Raw↔Bytes(Rest), Bool↔Bool, Value↔I32, String↔Str(Rest), Enum↔U8, Bitmap↔U8/U16/U32.
    /// A value's `scale` is a power of ten (a Tuya schema's `scale` n is `scale: 1e-n` here).
    pub field: Field,
    /// String and raw only: the most bytes the value may have (a schema's `maxlen`). `None`:
    /// no limit beyond the frame's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_len: Option<u16>,
    /// Value only: the step between allowed raw values, counted from the range's low end (a
    /// schema's `step`, in transmitted units). `None` or 1: every raw value in range.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub step: Option<i64>,
}

/// A live plot: fields of one telemetry command drawn together.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Plot {
    /// e.g. `attitude`, `battery`.
    pub id: String,
    /// The plot's title.
    pub name: Text,
    /// The telemetry command's ident.
    pub command: String,
    /// The field idents drawn as lines: measurements only (a number with a unit or a count,
    /// see [`Field::is_measurement`]), never an enum, flag or bit field (its codes are no
    /// quantity).
    pub fields: Vec<String>,
    /// The enum, flag and bit fields of the same command shown beside the plot by their names
    /// (the last value read), e.g. the battery's state beside its voltage.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub states: Vec<String>,
}
