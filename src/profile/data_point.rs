//! What a Tuya data point of the profile allows, beyond its wire type: a value's range and step,
//! an enum's labels, a bitmap's defined bits, a string's or raw value's longest length
//! (TUYA_FIELD_NOTES §7-8). A value the MCU reports outside these is impossible for the product
//! and is shown as a misfit, never as a clean value; one given to be sent is refused.

use super::model::DataPointDef;
use super::value::Value;
use crate::protocol::tuya::dp::{DpType, DpValue};
use serde::Serialize;

/// Why a value does not fit its data point's limits. The numbers are formatted as the data
/// point shows them (display units), so that a message reads the same in every language; the
/// window says the words in Chinese (`ui/zh.rs`).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, thiserror::Error)]
#[serde(tag = "limit", rename_all = "snake_case")]
pub enum DpLimit {
    /// A number outside the data point's range.
    #[error("{value}{unit} is out of range: the profile allows {min} to {max}{unit}")]
    OutOfRange {
        /// The value, in display units.
        value: String,
        /// The range's low end, in display units.
        min: String,
        /// The range's high end, in display units.
        max: String,
        /// The unit with its leading space, or empty.
        unit: String,
    },
    /// A number in range but between the data point's steps.
    #[error("{value}{unit} is between steps: the profile allows steps of {step} from {min}")]
    OffStep {
        /// The value, in display units.
        value: String,
        /// The step, in display units.
        step: String,
        /// Where the steps count from (the range's low end), in display units.
        min: String,
        /// The unit with its leading space, or empty.
        unit: String,
    },
    /// An enum index the data point has no label for.
    #[error("enum index {index} has no label: the profile labels {allowed}")]
    NoLabel {
        /// The index reported.
        index: i64,
        /// The labelled indices, `0 to 11` or `0, 2, 5`.
        allowed: String,
    },
    /// A bitmap with bits set that the data point does not define.
    #[error("bits {undefined:#x} are not defined: the profile defines bits {defined}")]
    UndefinedBits {
        /// The undefined bits that are set.
        undefined: u32,
        /// The defined bits, `0 to 6` or `0, 3`.
        defined: String,
    },
    /// A string or raw value longer than the data point's maximum.
    #[error("{len} bytes, over the profile's maximum of {max}")]
    TooLong {
        /// Its length, bytes.
        len: usize,
        /// The maximum, bytes.
        max: u16,
    },
}

/// A data point's value as the profile's fields hold it (raw units): a bool, value, enum or
/// bitmap as a number, a string as text, raw as bytes.
pub fn value_of(v: &DpValue) -> Value {
    match v {
        DpValue::Bool(b) => Value::Int(i64::from(*b)),
        DpValue::Value(x) => Value::Int(i64::from(*x)),
        DpValue::Enum(e) => Value::Int(i64::from(*e)),
        DpValue::Bitmap { bits, .. } => Value::Int(i64::from(*bits)),
        DpValue::String(s) => Value::Text(s.clone()),
        DpValue::Raw(b) => Value::Bytes(b.clone()),
    }
}

/// The power of ten `n` with `scale == 10^-n` (0 to 9): a Tuya schema's `scale`. `None` for a
/// scale that is no such power.
pub fn decimal_scale(scale: f64) -> Option<u8> {
    (0u8..=9).find(|n| (scale * 10f64.powi(i32::from(*n)) - 1.0).abs() < 1e-9)
}

/// `0 to 11` for a run of numbers, else `0, 2, 5`.
fn numbers_text(values: &[i64]) -> String {
    let contiguous = values.windows(2).all(|w| w[1] == w[0] + 1);
    match (values.first(), values.last()) {
        (Some(a), Some(b)) if contiguous && values.len() > 2 => format!("{a} to {b}"),
        _ => values
            .iter()
            .map(i64::to_string)
            .collect::<Vec<_>>()
            .join(", "),
    }
}

impl DataPointDef {
    /// Whether `value` (raw units, as a report or a command carries it) fits what this data
    /// point allows; `None` when it does. Only limits the profile states count: a value data
    /// point without `range` takes any 32-bit number, an enum without labels any index.
    pub fn limit_of(&self, value: &Value) -> Option<DpLimit> {
        match value {
            Value::Int(raw) => self.int_limit(*raw),
            Value::Text(s) => self.len_limit(s.len()),
            Value::Bytes(b) => self.len_limit(b.len()),
        }
    }

    fn len_limit(&self, len: usize) -> Option<DpLimit> {
        let max = self.max_len?;
        (len > usize::from(max)).then_some(DpLimit::TooLong { len, max })
    }

    fn int_limit(&self, raw: i64) -> Option<DpLimit> {
        let f = &self.field;
        if let Some((lo, hi)) = f.range
            && !(lo..=hi).contains(&raw)
        {
            return Some(DpLimit::OutOfRange {
                value: f.format_number(raw),
                min: f.format_number(lo),
                max: f.format_number(hi),
                unit: f.unit_suffix(),
            });
        }
        match self.dp_type {
            DpType::Value => {
                let step = self.step.filter(|s| *s > 1)?;
                let from = f.range.map_or(0, |(lo, _)| lo);
                ((raw - from).rem_euclid(step) != 0).then(|| DpLimit::OffStep {
                    value: f.format_number(raw),
                    step: f.format_number(step),
                    min: f.format_number(from),
                    unit: f.unit_suffix(),
                })
            }
            DpType::Enum if !f.labels.is_empty() && f.label(raw).is_none() => {
                let values: Vec<i64> = f.labels.iter().map(|l| l.value).collect();
                Some(DpLimit::NoLabel {
                    index: raw,
                    allowed: numbers_text(&values),
                })
            }
            DpType::Bitmap if !f.bits.is_empty() => {
                let defined = f
                    .bits
                    .iter()
                    .filter(|b| b.bit < 32)
                    .fold(0u32, |m, b| m | 1 << b.bit);
                let undefined = (raw as u32) & !defined;
                (undefined != 0).then(|| {
                    let bits: Vec<i64> = f.bits.iter().map(|b| i64::from(b.bit)).collect();
                    DpLimit::UndefinedBits {
                        undefined,
                        defined: numbers_text(&bits),
                    }
                })
            }
            _ => None,
        }
    }

    /// What the data point allows, as a person reads it beside a misfit: `0 to 100 %`,
    /// `0 to 9999 in steps of 5`, `labels 0 to 11`, `bits 0 to 6`, `at most 255 bytes`, or
    /// its type alone (`bool`, `any value`).
    pub fn allowed_text(&self) -> String {
        let f = &self.field;
        match self.dp_type {
            DpType::Value => {
                let range = match f.range {
                    Some((lo, hi)) => format!(
                        "{} to {}{}",
                        f.format_number(lo),
                        f.format_number(hi),
                        f.unit_suffix()
                    ),
                    None => "any 32-bit value".to_string(),
                };
                match self.step.filter(|s| *s > 1) {
                    Some(s) => format!("{range} in steps of {}", f.format_number(s)),
                    None => range,
                }
            }
            DpType::Enum => {
                let values: Vec<i64> = f.labels.iter().map(|l| l.value).collect();
                format!("labels {}", numbers_text(&values))
            }
            DpType::Bitmap => {
                let bits: Vec<i64> = f.bits.iter().map(|b| i64::from(b.bit)).collect();
                format!("bits {}", numbers_text(&bits))
            }
            DpType::String | DpType::Raw => match self.max_len {
                Some(m) => format!("at most {m} bytes"),
                None => "any length".to_string(),
            },
            DpType::Bool => "false or true".to_string(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scale_is_a_power_of_ten_or_none() {
        assert_eq!(decimal_scale(1.0), Some(0));
        assert_eq!(decimal_scale(0.1), Some(1));
        assert_eq!(decimal_scale(0.001), Some(3));
        assert_eq!(decimal_scale(0.5), None);
        assert_eq!(decimal_scale(10.0), None);
    }

    #[test]
    fn numbers_are_said_as_a_run_or_a_list() {
        assert_eq!(numbers_text(&[0, 1, 2, 3]), "0 to 3");
        assert_eq!(numbers_text(&[0, 1]), "0, 1");
        assert_eq!(numbers_text(&[0, 2, 5]), "0, 2, 5");
    }
}
