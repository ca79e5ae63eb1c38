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
    /// The steps' names, joined: `Identify, Self-test (window-cleaner-selftest), Write result`.
    pub fn step_names(&self) -> String {
        self.steps
            .iter()
            .map(|s| s.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// One step: its name as shown and recorded (in English; 中文 for the window and the events),
/// and its operation.
#[derive(Debug, Clone)]
pub struct LineStep {
    /// `Identify`, `Self-test (window-cleaner-selftest)`, `Confirm: Did it spray?`: the
    /// records keep this name.
    pub name: String,
    /// The same in 中文: `识别`, `自检(window-cleaner-selftest)`, `确认:喷水了吗?`.
    pub name_zh: String,
    /// What it does.
    pub op: Op,
}

impl LineStep {
    /// The step doing `op`, named after it ([`Op::title`]).
    pub fn new(op: Op) -> Self {
        let title = op.title();
        Self {
            name: title.en,
            name_zh: title.zh,
            op,
        }
    }
}

/// The file a step works with as people name it: its name without folders and its extension
/// (`presets/window-cleaner-selftest.ron` → `window-cleaner-selftest`, `vacuum-1.2.3.bin` →
/// `vacuum-1.2.3`; a last part of digits is a version, not an extension).
fn stem(file: &str) -> &str {
    let name = file.rsplit(['/', '\\']).next().unwrap_or(file);
    match name.rsplit_once('.') {
        Some((base, ext))
            if !base.is_empty()
                && !ext.is_empty()
                && ext.chars().all(|c| c.is_ascii_alphabetic()) =>
        {
            base
        }
        _ => name,
    }
}

/// The English and 中文 names of the steps that have a fixed name, or a name around a file:
/// `(English, 中文, takes a file)`. [`Op::title`] and [`title_zh`] read it.
const TITLES: [(&str, &str, bool); 10] = [
    ("Identify", "识别设备", false),
    ("Scan serial", "扫描序列号", false),
    ("Preset", "预设", true),
    ("Self-test", "自检", true),
    ("Provision", "舵机配置", true),
    ("Tuya handshake", "涂鸦握手", false),
    ("Tuya status", "涂鸦状态查询", false),
    ("Tuya conformance", "涂鸦协议一致性", false),
    ("Firmware update", "固件升级", true),
    ("Write result", "写入测试结果", false),
];

/// The 中文 name of a line step from its English name as the records keep it (for the
/// report's Pareto): `Self-test (wc)` → `自检(wc)`, `Measure Suction` → `测量 Suction`;
/// `None` for a name no line step has (a Confirm's question is known in English only).
pub fn title_zh(en: &str) -> Option<String> {
    for (e, z, file) in TITLES {
        if !file && en == e {
            return Some(z.to_string());
        }
        if file
            && let Some(inner) = en
                .strip_prefix(e)
                .and_then(|r| r.strip_prefix(" ("))
                .and_then(|r| r.strip_suffix(')'))
        {
            return Some(format!("{z}({inner})"));
        }
    }
    en.strip_prefix("Measure ").map(|m| format!("测量 {m}"))
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

    /// The step's name for people, in English and 中文: what it does, and the file (without
    /// folders and `.ron`) or question it works with: `Self-test (window-cleaner-selftest)`,
    /// `自检(window-cleaner-selftest)`; `Confirm: Did it spray?`; `Measure Suction`.
    pub fn title(&self) -> Text {
        let fixed = |i: usize| Text::new(TITLES[i].0, TITLES[i].1);
        let with_file = |i: usize, file: &str| {
            Text::new(
                format!("{} ({})", TITLES[i].0, stem(file)),
                format!("{}({})", TITLES[i].1, stem(file)),
            )
        };
        match self {
            Op::Identify { .. } => fixed(0),
            Op::Scan { .. } => fixed(1),
            Op::Preset { file, .. } => with_file(2, file),
            Op::SelfTest { file, .. } => with_file(3, file),
            Op::Provision { file, .. } => with_file(4, file),
            Op::TuyaHandshake => fixed(5),
            Op::TuyaStatus => fixed(6),
            Op::TuyaConform => fixed(7),
            Op::FirmwareUpdate { file, .. } => with_file(8, file),
            Op::WriteResult => fixed(9),
            Op::Confirm { question, .. } => Text::new(
                format!("Confirm: {}", question.en),
                format!("确认:{}", question.zh),
            ),
            Op::Measure { name, .. } => {
                Text::new(format!("Measure {name}"), format!("测量 {name}"))
            }
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
