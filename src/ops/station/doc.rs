//! The station bundle as written: the RON shapes a line engineer edits (`botbench station new`
//! writes a commented example). [`super::load`] reads one, checks it whole and resolves it into
//! a [`super::Bundle`]; nothing here touches a file or a port.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The bundle format this botbench reads (`version: 1`).
pub const VERSION: u32 = 1;

/// A station bundle file: the station's id, its line plans by name and its slots.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BundleDoc {
    /// The format's version: [`VERSION`].
    pub version: Option<u32>,
    /// The station's id as records name it (`line3-st2`): 1 to 64 characters.
    pub id: String,
    /// The operator view's language: `En` or `Zh` (default `En`).
    #[serde(default)]
    pub language: Option<crate::i18n::Lang>,
    /// Where the records go: a SQLite file or `postgres://...` (default: this PC's records
    /// file, as `--records` takes it).
    #[serde(default)]
    pub records: Option<String>,
    /// SHA-256 (64 lower-case hex digits) of the engineer's password that unlocks the
    /// operator view (`botbench station password` prints it); none: the settings' one.
    #[serde(default)]
    pub engineer_password_sha256: Option<String>,
    /// A short sound on each verdict in the window (default `true`); the operator may turn
    /// it off or on, and the window keeps that choice.
    #[serde(default)]
    pub sound: Option<bool>,
    /// Pinned SHA-256 of named files (the path as written in the bundle → 64 hex digits): a
    /// file that no longer matches refuses the bundle.
    #[serde(default)]
    pub pins: BTreeMap<String, String>,
    /// The line plans, by name.
    pub plans: BTreeMap<String, PlanDoc>,
    /// The slots, in the order the window shows them.
    pub slots: Vec<SlotDoc>,
}

/// One slot: a fixture, its port, the device profile and the plan it runs.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SlotDoc {
    /// The slot's name (`1`, `A`): what the operator types before Y/N, what records call it.
    pub name: String,
    /// The fixture's name on its label (`WC fixture 2`).
    pub fixture: String,
    /// The fixture's name in 中文 (`擦窗机治具 2`), shown when the station is shown in 中文;
    /// optional (a bundle without it shows `fixture` in both languages).
    #[serde(default)]
    pub fixture_zh: Option<String>,
    /// How its port is found.
    pub port: PortLocator,
    /// The device profile: an id (`window-cleaner`) or a `.ron` file.
    pub profile: String,
    /// The line plan's name in `plans`.
    pub plan: String,
    /// The DTR line right after the port opens: `"on"`, `"off"` or `"keep"` (the default).
    #[serde(default)]
    pub dtr: Option<String>,
    /// The RTS line right after the port opens: `"on"`, `"off"` or `"keep"` (the default).
    #[serde(default)]
    pub rts: Option<String>,
    /// How long to send nothing after the port opens, ms, 0 to 30000 (default 0): a board that
    /// reboots when its port opens.
    #[serde(default)]
    pub boot_wait_ms: Option<u64>,
}

/// How a slot's port is found, by what stays true when its adapter is replugged.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum PortLocator {
    /// The USB physical path (`/dev/serial/by-path/pci-0000:00:14.0-usb-0:2:1.0-port0`): the
    /// socket the adapter is plugged into.
    UsbPath(String),
    /// The USB adapter's serial number (`A10K3X7Q`), wherever it is plugged.
    AdapterSerial(String),
    /// A plain device path (`/dev/ttyUSB0`, `COM3`): may change when adapters are replugged.
    Path(String),
    /// A built-in simulated device: `window-cleaner`, `solar-cleanbot`, `servo-bus` or
    /// `tuya-vacuum`. Each slot has its own.
    Simulated(String),
}

impl PortLocator {
    /// As the window and the events say it: `usb-path …`, `adapter sn …`, `/dev/ttyUSB0`,
    /// `simulated window-cleaner`.
    pub fn said(&self) -> String {
        match self {
            PortLocator::UsbPath(p) => format!("usb-path {p}"),
            PortLocator::AdapterSerial(s) => format!("adapter sn {s}"),
            PortLocator::Path(p) => p.clone(),
            PortLocator::Simulated(k) => format!("simulated {k}"),
        }
    }
}

/// How a slot starts a unit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum StartMode {
    /// The operator presses Start (or types `start SLOT` headless).
    #[default]
    Button,
    /// The unit's serial number scanned into the slot starts it (the plan's first Scan step
    /// takes it).
    Scan,
    /// A new unit answering on the port starts it (its identity is read about every 0.5 s
    /// while the fixture is idle).
    Auto,
}

/// A line plan: the steps one unit goes through, in order.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanDoc {
    /// How a unit is started.
    #[serde(default)]
    pub start: StartMode,
    /// Whether the operator may retry a failed step once (the record keeps both tries).
    #[serde(default)]
    pub retry_once: bool,
    /// The steps.
    pub steps: Vec<StepDoc>,
}

/// One step of a line plan, over an operation botbench already has. Files are named relative
/// to the bundle's folder.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum StepDoc {
    /// MSP identify (CMD_VERSION): the hardware codes and firmware versions allowed (empty:
    /// any). Another device is refused before any write.
    Identify {
        /// Allowed hardware codes (`[3]`).
        #[serde(default)]
        hardware: Vec<u8>,
        /// Allowed firmware versions (`["1.4.2"]`).
        #[serde(default)]
        firmware: Vec<String>,
    },
    /// The unit's serial number from a barcode scanner (a keyboard that types the code and
    /// Enter), checked against `pattern` (a regular expression, whole match). A servo's serial
    /// is read from the servo by its Provision step.
    Scan {
        /// The regular expression a scanned serial must match whole (`WC[0-9]{6}`).
        #[serde(default)]
        pattern: Option<String>,
        /// How long to wait for the scan, s (default 120).
        #[serde(default)]
        timeout_s: Option<u32>,
    },
    /// Applies a preset file with read-back (MSP).
    Preset(String),
    /// Runs a self-test plan file unchanged (the window cleaner's line test).
    SelfTest(String),
    /// Provisions fresh servos by a provisioning plan file: `count` of them (default 1).
    Provision {
        /// The provisioning plan file.
        plan: String,
        /// How many fresh servos the tray holds.
        #[serde(default)]
        count: Option<u32>,
    },
    /// The Tuya handshake (heartbeat, product info, working mode) as botbench the module.
    TuyaHandshake,
    /// The Tuya status query: every reported data point answers and none is impossible.
    TuyaStatus,
    /// The Tuya conformance run: every mandatory check passes.
    TuyaConform,
    /// A Tuya MCU firmware update from an image file, proven by the version the MCU names
    /// after its restart.
    FirmwareUpdate {
        /// The image file.
        image: String,
        /// The version it brings (`1.0.1`); default: the version the image holds.
        #[serde(default)]
        version: Option<String>,
    },
    /// Writes the unit's verdict so far into the device (MSP_SET_AUTO_TEST_RESULT 147: 1 pass,
    /// 0 fail) and reads it back with MSP_AUTO_TEST_RESULT 148.
    WriteResult,
    /// A yes/no question to the operator (Y/N keys, a pedal, a scanned PASS/FAIL code).
    Confirm {
        /// The question (`Did it spray?`).
        question: String,
        /// The question in 中文.
        #[serde(default)]
        question_zh: Option<String>,
        /// How long to wait for the answer, s (default 60): no answer is FAIL.
        #[serde(default)]
        timeout_s: Option<u32>,
    },
    /// A value typed or scanned from an instrument, checked against limits.
    Measure {
        /// What is measured (`Suction`).
        name: String,
        /// Its unit (`kPa`).
        #[serde(default)]
        unit: String,
        /// The lowest value allowed.
        min: f64,
        /// The highest value allowed.
        max: f64,
        /// How long to wait for the value, s (default 120).
        #[serde(default)]
        timeout_s: Option<u32>,
    },
}

impl StepDoc {
    /// The step's kind as events and records name it: `Identify`, `SelfTest`, ...
    pub fn kind(&self) -> &'static str {
        match self {
            StepDoc::Identify { .. } => "Identify",
            StepDoc::Scan { .. } => "Scan",
            StepDoc::Preset(_) => "Preset",
            StepDoc::SelfTest(_) => "SelfTest",
            StepDoc::Provision { .. } => "Provision",
            StepDoc::TuyaHandshake => "TuyaHandshake",
            StepDoc::TuyaStatus => "TuyaStatus",
            StepDoc::TuyaConform => "TuyaConform",
            StepDoc::FirmwareUpdate { .. } => "FirmwareUpdate",
            StepDoc::WriteResult => "WriteResult",
            StepDoc::Confirm { .. } => "Confirm",
            StepDoc::Measure { .. } => "Measure",
        }
    }

    /// The protocol the step needs (`None`: any device).
    pub fn protocol(&self) -> Option<crate::profile::Protocol> {
        use crate::profile::Protocol;
        match self {
            StepDoc::Identify { .. }
            | StepDoc::Preset(_)
            | StepDoc::SelfTest(_)
            | StepDoc::WriteResult => Some(Protocol::Msp),
            StepDoc::Provision { .. } => Some(Protocol::Servo),
            StepDoc::TuyaHandshake
            | StepDoc::TuyaStatus
            | StepDoc::TuyaConform
            | StepDoc::FirmwareUpdate { .. } => Some(Protocol::Tuya),
            StepDoc::Scan { .. } | StepDoc::Confirm { .. } | StepDoc::Measure { .. } => None,
        }
    }
}
