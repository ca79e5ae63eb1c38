//! A line plan as it runs: each step's operation with its files already read, parsed and
//! checked against the slot's profile ([`super::load`] makes them).

use super::doc::StartMode;
use crate::i18n::Text;
use std::sync::Arc;
use std::time::Duration;

/// A line plan resolved for one profile.
#[derive(Debug, Clone)]
pub struct LinePlan {
    /// Its name in the bundle (`window-cleaner`): the records' plan name.
    pub name: String,
    /// How a unit is started.
    pub start: StartMode,
    /// Whether a failed step may be retried once by the operator.
    pub retry_once: bool,
    /// The steps, in order.
    pub steps: Vec<LineStep>,
}

impl LinePlan {
    /// The steps' names, joined: `Identify, SelfTest window-cleaner-selftest.ron, WriteResult`.
    pub fn step_names(&self) -> String {
        self.steps
            .iter()
            .map(|s| s.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// One step: its name as shown and recorded, and its operation.
#[derive(Debug, Clone)]
pub struct LineStep {
    /// `Identify`, `SelfTest window-cleaner-selftest.ron`, `Confirm Did it spray?`.
    pub name: String,
    /// What it does.
    pub op: Op,
}

impl LineStep {
    /// The step doing `op`, named after it.
    pub fn new(op: Op) -> Self {
        Self {
            name: op.name(),
            op,
        }
    }
}

/// A step's operation, with what it needs.
#[derive(Debug, Clone)]
pub enum Op {
    /// MSP identify; refused unless the hardware code and firmware are among those allowed
    /// (empty lists allow any).
    Identify {
        /// Allowed hardware codes.
        hardware: Vec<u8>,
        /// Allowed firmware versions.
        firmware: Vec<String>,
    },
    /// The unit's serial, scanned and matched whole against `pattern`.
    Scan {
        /// `^(?:pattern)$`; `None`: any non-empty code.
        pattern: Option<regex::Regex>,
        /// How long the scan is waited for.
        timeout: Duration,
    },
    /// A preset applied with read-back.
    Preset {
        /// The file as named.
        file: String,
        /// The preset, checked against the profile.
        preset: crate::preset::Preset,
    },
    /// A self-test plan run unchanged.
    SelfTest {
        /// The file as named.
        file: String,
        /// The plan, checked against the profile.
        plan: crate::ops::selftest::Plan,
    },
    /// Fresh servos provisioned, one after another.
    Provision {
        /// The file as named.
        file: String,
        /// The plan, checked against the profile.
        plan: crate::ops::servo::provision::Plan,
        /// How many servos.
        count: u32,
    },
    /// The Tuya handshake: product info answered.
    TuyaHandshake,
    /// The Tuya status query: every reported data point, none impossible.
    TuyaStatus,
    /// The Tuya conformance run.
    TuyaConform,
    /// A Tuya MCU firmware update, proven by the version after.
    FirmwareUpdate {
        /// The file as named.
        file: String,
        /// The image's bytes.
        image: Arc<Vec<u8>>,
        /// The version it brings.
        version: String,
    },
    /// The unit's verdict written with MSP_SET_AUTO_TEST_RESULT (147) and read back (148).
    WriteResult,
    /// A yes/no question to the operator.
    Confirm {
        /// The question, in both languages.
        question: Text,
        /// No answer by then is FAIL.
        timeout: Duration,
    },
    /// A value from an instrument, within `[min, max]`.
    Measure {
        /// What is measured.
        name: String,
        /// Its unit.
        unit: String,
        /// Lowest allowed.
        min: f64,
        /// Highest allowed.
        max: f64,
        /// No value by then is FAIL.
        timeout: Duration,
    },
}

impl Op {
    /// The step's kind (`Identify`, `SelfTest`, ...), as the record's step kind.
    pub fn kind(&self) -> &'static str {
        match self {
            Op::Identify { .. } => "Identify",
            Op::Scan { .. } => "Scan",
            Op::Preset { .. } => "Preset",
            Op::SelfTest { .. } => "SelfTest",
            Op::Provision { .. } => "Provision",
            Op::TuyaHandshake => "TuyaHandshake",
            Op::TuyaStatus => "TuyaStatus",
            Op::TuyaConform => "TuyaConform",
            Op::FirmwareUpdate { .. } => "FirmwareUpdate",
            Op::WriteResult => "WriteResult",
            Op::Confirm { .. } => "Confirm",
            Op::Measure { .. } => "Measure",
        }
    }

    /// The step's name: its kind, and the file or question it works with.
    pub fn name(&self) -> String {
        match self {
            Op::Preset { file, .. }
            | Op::SelfTest { file, .. }
            | Op::Provision { file, .. }
            | Op::FirmwareUpdate { file, .. } => format!("{} {file}", self.kind()),
            Op::Confirm { question, .. } => format!("Confirm: {}", question.en),
            Op::Measure { name, .. } => format!("Measure {name}"),
            _ => self.kind().to_string(),
        }
    }

    /// Whether the step waits on the operator (a Confirm, a Measure, a scanned serial).
    pub fn needs_operator(&self) -> bool {
        matches!(
            self,
            Op::Confirm { .. } | Op::Measure { .. } | Op::Scan { .. }
        )
    }
}
