//! Why a unit's step failed, typed: what the operations found (a device refused, no answer, a
//! value out of its limits, the operator's no, a link lost), carried from the step to whoever
//! shows the station. Its English is its `Display`, the very words the records, the JSON lines
//! and the command line have always kept (`out of limits: Suction`, `link lost during Write
//! result`); the window says it in 中文 from the same values (`ui::zh`). Nothing here is
//! Chinese but the bundle's own step names.

use crate::ops::OpError;
use crate::ops::records::Measurement;
use serde::{Serialize, Serializer};
use std::fmt;

/// Why a step failed. `Display`: the English the records keep; [`Reason::Other`] is words
/// from below with no type of their own (a plan's problem, a device's text), shown as they came.
#[derive(Debug, Clone, PartialEq)]
pub enum Reason {
    /// Identify: the device's hardware code is not one the plan allows (`hardware 0x04 not
    /// allowed`); nothing was written.
    HardwareNotAllowed {
        /// The code it reported (CMD_VERSION).
        hw: u8,
    },
    /// Identify: the device's firmware version is not one the plan allows.
    FirmwareNotAllowed {
        /// The version it reported (`1.4.1`).
        firmware: String,
    },
    /// The device did not answer (every attempt timed out): `no answer`.
    NoAnswer,
    /// The device did not answer while this computer was held up [`crate::link::HELD_UP`] or
    /// more past the answer's deadline (a loaded computer, not necessarily the unit): `no
    /// answer, computer held up`. The figure is in the step's detail; the words stay the same
    /// for every unit, so that a line's failure reasons group.
    NoAnswerHeldUp,
    /// The device did not answer a command: `no answer to CMD_VERSION` (a self-test step).
    NoAnswerTo {
        /// The command as the profile names it.
        command: String,
    },
    /// The port went away during the step: `link lost`.
    LinkLost,
    /// The port went away, with what the system said: `link lost: /dev/ttyUSB0 vanished`.
    LinkLostBecause {
        /// The system's words.
        why: String,
    },
    /// The unit's run ended because its port went away during `step`: `link lost during
    /// <step>`.
    LinkLostDuring {
        /// The plan's step name.
        step: String,
        /// Its 中文 name, as the bundle gives it.
        step_zh: String,
    },
    /// STOP for the slot (or STOP ALL): `cancelled`.
    Cancelled,
    /// A self-test's operator said no (`the operator aborted`).
    OperatorAborted,
    /// The operator did not answer within the step's timeout: `no answer in time`.
    NotAnsweredInTime,
    /// Confirm: the operator said no.
    OperatorSaidNo,
    /// Confirm: the answer was neither yes nor no.
    NotYesNo,
    /// Scan: a yes/no came where a code was wanted.
    NoSerialScanned,
    /// Scan: the code does not match the plan's pattern (or is empty).
    SerialMismatch,
    /// Measure: a yes/no came where a value was wanted.
    NotAValue,
    /// Measure: the text typed is not a number.
    NotANumber,
    /// Values outside their limits (a Measure step's, a self-test step's): `out of limits:
    /// Suction`, each with its value, unit and limits.
    OutOfLimits {
        /// The values that failed (at least one).
        values: Vec<Measurement>,
    },
    /// A self-test's read that did not give the expected value: `unexpected value: mode`.
    UnexpectedValue {
        /// The fields read.
        fields: Vec<String>,
    },
    /// A self-test's operator step whose input never changed: `not toggled: cornerLeft`.
    NotToggled {
        /// The field watched.
        field: String,
    },
    /// Provisioning found no servo to provision: `no servo`.
    NoServo,
    /// The operation did not run at all: `not run`.
    NotRun,
    /// Tuya handshake: the product info (0x01) came but could not be read.
    ProductInfoUnreadable,
    /// Tuya status: data points missing or holding impossible values.
    DataPointsMissing,
    /// WriteResult on a device whose profile has no MSP_SET_AUTO_TEST_RESULT.
    NoResultCommand,
    /// A write that does not read back as written: `read back differs: speed, mode`.
    ReadBackDiffers {
        /// The fields (empty: not said).
        fields: Vec<String>,
    },
    /// A mandatory Tuya conformance check failed: its name (`heartbeat (0x00) answered 00/01
    /// within 3 s`).
    Conformance {
        /// The check's id (`heartbeat`, `answer_time`).
        id: String,
        /// Its name in English.
        name: String,
    },
    /// A servo's provisioning stopped at `step` (`detect`, `verify`): `why`, as provisioning
    /// says it.
    Provision {
        /// The provisioning step (`crate::ops::servo::provision::step`).
        step: String,
        /// Provisioning's words.
        why: String,
    },
    /// An operation's error (a refused value, a device's error answer, a firmware update
    /// that failed).
    Error(OpError),
    /// Anything else, as it came.
    Other(String),
}

impl fmt::Display for Reason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::HardwareNotAllowed { hw } => write!(f, "hardware {hw:#04x} not allowed"),
            Self::FirmwareNotAllowed { firmware } => write!(f, "firmware {firmware} not allowed"),
            Self::NoAnswer => f.write_str("no answer"),
            Self::NoAnswerHeldUp => f.write_str("no answer, computer held up"),
            Self::NoAnswerTo { command } => write!(f, "no answer to {command}"),
            Self::LinkLost => f.write_str("link lost"),
            Self::LinkLostBecause { why } => write!(f, "link lost: {why}"),
            Self::LinkLostDuring { step, .. } => write!(f, "link lost during {step}"),
            Self::Cancelled => f.write_str("cancelled"),
            Self::OperatorAborted => f.write_str("the operator aborted"),
            Self::NotAnsweredInTime => f.write_str("no answer in time"),
            Self::OperatorSaidNo => f.write_str("operator said no"),
            Self::NotYesNo => f.write_str("not a yes/no answer"),
            Self::NoSerialScanned => f.write_str("no serial scanned"),
            Self::SerialMismatch => f.write_str("serial does not match the pattern"),
            Self::NotAValue => f.write_str("not a value"),
            Self::NotANumber => f.write_str("not a number"),
            Self::OutOfLimits { values } => {
                let names: Vec<&str> = values.iter().map(|m| m.name.as_str()).collect();
                write!(f, "out of limits: {}", names.join(", "))
            }
            Self::UnexpectedValue { fields } => {
                write!(f, "unexpected value: {}", fields.join(", "))
            }
            Self::NotToggled { field } => write!(f, "not toggled: {field}"),
            Self::NoServo => f.write_str("no servo"),
            Self::NotRun => f.write_str("not run"),
            Self::ProductInfoUnreadable => f.write_str("product info unreadable"),
            Self::DataPointsMissing => f.write_str("data points missing or impossible"),
            Self::NoResultCommand => f.write_str("no MSP_SET_AUTO_TEST_RESULT"),
            Self::ReadBackDiffers { fields } if fields.is_empty() => {
                f.write_str("read back differs")
            }
            Self::ReadBackDiffers { fields } => {
                write!(f, "read back differs: {}", fields.join(", "))
            }
            Self::Conformance { name, .. } => f.write_str(name),
            Self::Provision { why, .. } => f.write_str(why),
            Self::Error(e) => write!(f, "{e}"),
            Self::Other(s) => f.write_str(s),
        }
    }
}

/// As JSON: its English, as the JSON lines always said it.
impl Serialize for Reason {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

/// Words with no type of their own: [`Reason::Other`].
impl From<&str> for Reason {
    fn from(words: &str) -> Self {
        Self::Other(words.to_string())
    }
}

impl Reason {
    /// Whether the port went away (the run ends at once, said `link lost during <step>`).
    pub fn link_lost(&self) -> bool {
        matches!(
            self,
            Self::LinkLost | Self::LinkLostBecause { .. } | Self::LinkLostDuring { .. }
        )
    }

    /// `no answer` or `link lost` for an operation's error that is one, else the error.
    pub fn of_error(e: &OpError) -> Self {
        use crate::link::ExchangeError;
        match e {
            OpError::Exchange(ExchangeError::Timeout {
                host_late: Some(_), ..
            }) => Self::NoAnswerHeldUp,
            OpError::Exchange(ExchangeError::Timeout { .. }) => Self::NoAnswer,
            other if other.lost_port().is_some() => Self::LinkLost,
            other => Self::Error(other.clone()),
        }
    }

    /// A failed self-test step's reason, the same words for the same cause on every unit (its
    /// values are in its measurements and detail): the values out of their limits, the reads
    /// not as expected, the switch never toggled, else the head of its detail (`link lost`,
    /// `no answer to CMD_X`).
    pub fn of_selftest_step(s: &crate::ops::selftest::StepResult) -> Self {
        let failed: Vec<Measurement> = s.measurements.iter().filter(|m| !m.pass).cloned().collect();
        if !failed.is_empty() {
            return Self::OutOfLimits { values: failed };
        }
        match s.kind.as_str() {
            "Reads" if s.detail.contains("WRONG") || s.detail.contains("missing") => {
                let fields = s
                    .detail
                    .split(", ")
                    .filter(|p| p.contains("WRONG") || p.contains("missing"))
                    .filter_map(|p| p.split(' ').next())
                    .map(str::to_string)
                    .collect();
                Self::UnexpectedValue { fields }
            }
            "Operator" if s.detail.contains("never") => Self::NotToggled {
                field: s
                    .detail
                    .split_whitespace()
                    .next()
                    .unwrap_or_default()
                    .to_string(),
            },
            _ => {
                let head = |d: &str| d.split([';', '(']).next().unwrap_or(d).trim().to_string();
                let d = s.detail.split(": ").next().unwrap_or(&s.detail);
                let head = if s.detail.starts_with("link lost") || s.detail.starts_with("cancel") {
                    head(d)
                } else {
                    head(&s.detail)
                };
                Self::of_words(&head)
            }
        }
    }

    /// A self-test's aborted run (no step failed): what stopped it.
    pub fn of_aborted(words: &str) -> Self {
        match words.strip_prefix("link lost: ") {
            Some(why) => Self::LinkLostBecause {
                why: why.to_string(),
            },
            None => Self::of_words(words),
        }
    }

    /// The words an operation said, typed where they are one of its known causes.
    fn of_words(words: &str) -> Self {
        match words {
            "link lost" => Self::LinkLost,
            "cancelled" => Self::Cancelled,
            "no answer" => Self::NoAnswer,
            "no answer, computer held up" => Self::NoAnswerHeldUp,
            "the operator aborted" => Self::OperatorAborted,
            other => match other.strip_prefix("no answer to ") {
                Some(command) if !command.contains(' ') => Self::NoAnswerTo {
                    command: command.to_string(),
                },
                _ => Self::Other(other.to_string()),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::ExchangeError;
    use std::time::Duration;

    fn timeout(host_late: Option<Duration>) -> OpError {
        OpError::Exchange(ExchangeError::Timeout {
            command: 3.into(),
            attempts: 3,
            waited_ms: 100,
            host_late,
        })
    }

    /// Issue 25, item 4e: a unit's silence while this computer was held up is said as such, in
    /// words that read back as the same reason (the records keep the English), and one on time
    /// stays `no answer`.
    #[test]
    fn no_answer_on_a_held_up_computer_is_a_reason_of_its_own_that_reads_back() {
        let held = Reason::of_error(&timeout(Some(Duration::from_millis(31))));
        assert_eq!(held, Reason::NoAnswerHeldUp);
        assert_eq!(Reason::of_words(&held.to_string()), held);
        let on_time = Reason::of_error(&timeout(None));
        assert_eq!(on_time, Reason::NoAnswer);
        assert_eq!(Reason::of_words(&on_time.to_string()), on_time);
    }
}
