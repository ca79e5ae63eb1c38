//! Field values: typed raw values, their display, and what a person types.

use super::model::{Field, FieldType, Len};
use crate::protocol::hex;
use serde::Serialize;

pub use super::fault::{Broken, FieldError, Misfit};

/// A field's value, raw: integers in wire units (before scaling).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(untagged)]
pub enum Value {
    /// Every integer, bool, enum and bit field.
    Int(i64),
    /// Text fields.
    Text(String),
    /// Byte fields.
    Bytes(Vec<u8>),
}

/// The words a bool field takes besides its labels, for messages.
const BOOL_WORDS: &str = "on, off (or true, false, yes, no, 1, 0)";

impl Field {
    /// A field with only an ident (also its name, in both languages) and a type: no scale,
    /// unit, range, labels or bits.
    pub fn plain(ident: &str, ty: FieldType) -> Field {
        Field {
            ident: ident.to_string(),
            name: crate::i18n::Text::new(ident, ident),
            ty,
            scale: 1.0,
            unit: String::new(),
            range: None,
            labels: Vec::new(),
            bits: Vec::new(),
            default: None,
            optional: false,
            omitted_when: None,
            convert: None,
        }
    }

    /// What may be written, as a message says it: `0 to 100 %`, `strong (0), normal (1)`,
    /// `on, off (…)`, bit names, `text of 16 bytes`, `hex bytes`.
    pub fn allowed_text(&self) -> String {
        match self.ty {
            FieldType::Str(Len::Fixed(n)) => return format!("text of {n} bytes"),
            FieldType::Str(_) => return "text".into(),
            FieldType::Bytes(Len::Fixed(n)) => return format!("{n} hex bytes"),
            FieldType::Bytes(_) => return "hex bytes".into(),
            _ => {}
        }
        if self.ty == FieldType::Bool && self.labels.is_empty() {
            return BOOL_WORDS.into();
        }
        if !self.bits.is_empty() {
            let names: Vec<&str> = self.bits.iter().map(|b| b.ident.as_str()).collect();
            return format!("bit names joined by | ({}), or a number", names.join(", "));
        }
        match self.allowed() {
            Allowed::Range(lo, hi) => format!(
                "{} to {}{}",
                self.format_number(lo),
                self.format_number(hi),
                self.unit_suffix()
            ),
            Allowed::Labels(_) => self.label_list(),
        }
    }

    /// The raw values that may be written: the explicit range, else the labels, else the type's.
    pub fn allowed(&self) -> Allowed<'_> {
        if let Some((lo, hi)) = self.range {
            Allowed::Range(lo, hi)
        } else if !self.labels.is_empty() {
            Allowed::Labels(self)
        } else {
            let (lo, hi) = self.ty.int_bounds().unwrap_or((0, 0));
            Allowed::Range(lo, hi)
        }
    }

    /// A measurement: a whole-number wire type that stands for a quantity or a count (with or
    /// without a unit), so that a line through its values means something. Not an enum (named
    /// values), a flag (bool) or a bit field, nor a command id or length.
    pub fn is_measurement(&self) -> bool {
        let number = !matches!(
            self.ty,
            FieldType::Bool | FieldType::CommandId | FieldType::RecordLen | FieldType::RecordCount
        ) && self.ty.int_bounds().is_some();
        number && !self.is_state()
    }

    /// A state: an enum (named values), a flag (bool) or a bit field, read by its names, never
    /// as a quantity.
    pub fn is_state(&self) -> bool {
        self.ty.int_bounds().is_some()
            && (self.ty == FieldType::Bool || !self.labels.is_empty() || !self.bits.is_empty())
    }

    /// Digits after the decimal point that the scale calls for.
    pub fn decimals(&self) -> usize {
        decimals_for(self.scale)
    }

    /// A raw integer as displayed, scaled, without labels or unit: `275` → `2.75`.
    pub fn format_number(&self, raw: i64) -> String {
        if self.scale == 1.0 {
            raw.to_string()
        } else {
            format!("{:.*}", self.decimals(), raw as f64 * self.scale)
        }
    }

    /// The label of a raw value, if it has one.
    pub fn label(&self, raw: i64) -> Option<&super::model::Label> {
        self.labels.iter().find(|l| l.value == raw)
    }

    /// The displayed number of a raw integer, after scale or conversion; `None` where a
    /// conversion is undefined for it.
    pub fn display_number(&self, raw: i64) -> Option<f64> {
        match self.convert {
            Some(c) => c.apply(raw),
            None => Some(raw as f64 * self.scale),
        }
    }

    /// A converted value as shown, without unit: `25.0 (raw 2048)`, `n/a (raw 0)`.
    fn format_converted(&self, c: super::model::Conversion, raw: i64) -> String {
        match c.apply(raw) {
            Some(v) => format!("{v:.*} (raw {raw})", c.decimals()),
            None => format!("n/a (raw {raw})"),
        }
    }

    /// A value as shown to a person: scaled number, label, set bits, text or hex; a converted
    /// value with its raw value beside it, `25.0 (raw 2048)`. [`Field::parse`] reads it back.
    pub fn format(&self, value: &Value) -> String {
        match value {
            Value::Int(raw) => {
                if let Some(label) = self.label(*raw) {
                    return label.ident.clone();
                }
                if let Some(c) = self.convert {
                    return self.format_converted(c, *raw);
                }
                if !self.bits.is_empty() {
                    let set: Vec<&str> = self
                        .bits
                        .iter()
                        .filter(|b| b.bit < 64 && raw >> b.bit & 1 == 1)
                        .map(|b| b.ident.as_str())
                        .collect();
                    return format!("{raw:#04x} [{}]", set.join(", "));
                }
                if self.ty == FieldType::Bool {
                    return (*raw != 0).to_string();
                }
                self.format_number(*raw)
            }
            Value::Text(s) => s.clone(),
            Value::Bytes(b) => hex::format(b),
        }
    }

    /// The field's range, when `value` (a number read from a device) lies outside it: such a
    /// value is never shown as a clean one. Only an explicit `range` counts (a decoded number
    /// always fits its type).
    pub fn out_of_range(&self, value: &Value) -> Option<(i64, i64)> {
        match (self.range, value) {
            (Some((lo, hi)), Value::Int(raw)) if !(lo..=hi).contains(raw) => Some((lo, hi)),
            _ => None,
        }
    }

    /// The mark an out-of-range value is shown with: `!! out of range 0 to 100 %`; `None` for a
    /// value in range.
    pub fn range_mark(&self, value: &Value) -> Option<String> {
        let (lo, hi) = self.out_of_range(value)?;
        Some(format!(
            "!! out of range {} to {}{}",
            self.format_number(lo),
            self.format_number(hi),
            self.unit_suffix()
        ))
    }

    /// A value as shown with its unit: `2.75`, `90.0 °`, `25.0 °C (raw 2048)`, `on`; a value
    /// outside the field's range carries its mark: `238 % !! out of range 0 to 100 %`.
    pub fn display(&self, value: &Value) -> String {
        let shown = self.display_plain(value);
        match self.range_mark(value) {
            Some(mark) => format!("{shown} {mark}"),
            None => shown,
        }
    }

    /// A value as shown with its unit, without the out-of-range mark.
    pub(super) fn display_plain(&self, value: &Value) -> String {
        match value {
            Value::Int(raw) if self.label(*raw).is_none() => match self.convert {
                Some(c) => match c.apply(*raw) {
                    Some(v) => format!("{v:.*}{} (raw {raw})", c.decimals(), self.unit_suffix()),
                    None => format!("n/a (raw {raw})"),
                },
                None => format!("{}{}", self.format(value), self.unit_suffix()),
            },
            _ => self.format(value),
        }
    }

    /// The unit with a leading space, or empty.
    pub fn unit_suffix(&self) -> String {
        if self.unit.is_empty() {
            String::new()
        } else {
            format!(" {}", self.unit)
        }
    }

    /// Checks that a raw value may be written to this field.
    pub fn check(&self, value: &Value) -> Result<(), FieldError> {
        match (self.ty, value) {
            (FieldType::Str(len), Value::Text(s)) => check_len(self, len, s.len()),
            (FieldType::Bytes(len), Value::Bytes(b)) => check_len(self, len, b.len()),
            (ty, Value::Int(raw)) if ty.int_bounds().is_some() => match self.allowed() {
                Allowed::Range(lo, hi) if (lo..=hi).contains(raw) => Ok(()),
                Allowed::Range(..) => Err(self.out_of_range_error(self.format_number(*raw))),
                Allowed::Labels(_) if self.label(*raw).is_some() => Ok(()),
                Allowed::Labels(_) => Err(self.out_of_range_error(raw.to_string())),
            },
            _ => Err(FieldError::WrongType {
                field: self.ident.clone(),
                expected: self.expected(),
            }),
        }
    }

    /// `shown` (a value as displayed, or as typed) is not what the field allows: out of its
    /// range, or not one of its labels.
    fn out_of_range_error(&self, shown: String) -> FieldError {
        match self.allowed() {
            Allowed::Range(lo, hi) => FieldError::OutOfRange {
                field: self.ident.clone(),
                value: crate::document::quote(&shown),
                min: self.format_number(lo),
                max: self.format_number(hi),
                unit: self.unit_suffix(),
            },
            Allowed::Labels(_) => FieldError::NotALabel {
                field: self.ident.clone(),
                value: crate::document::quote(&shown),
                allowed: self.label_list(),
            },
        }
    }

    fn label_list(&self) -> String {
        self.labels
            .iter()
            .map(|l| format!("{} ({})", l.ident, l.value))
            .collect::<Vec<_>>()
            .join(", ")
    }

    fn expected(&self) -> String {
        match self.ty {
            FieldType::Str(_) => "text".into(),
            FieldType::Bytes(_) => "hex bytes".into(),
            _ => "a number".into(),
        }
    }

    /// Reads what a person typed, in display units, and checks it: `2.75` → raw 275.
    ///
    /// Integer fields take a number (scaled), a label's ident, `true`/`false`/`on`/`off` for
    /// bools, bit idents joined by `|` for bit fields, or `0x..` raw hex where the scale is 1.
    pub fn parse(&self, input: &str) -> Result<Value, FieldError> {
        let text = input.trim();
        let takes_text = matches!(self.ty, FieldType::Str(_));
        if text.is_empty() && !takes_text {
            return Err(FieldError::NoValue {
                field: self.ident.clone(),
                allowed: self.allowed_text(),
            });
        }
        let value = match self.ty {
            FieldType::Str(_) => Value::Text(input.to_string()),
            FieldType::Bytes(_) => {
                Value::Bytes(hex::parse(text).map_err(|e| FieldError::WrongType {
                    field: self.ident.clone(),
                    expected: format!("hex bytes ({e})"),
                })?)
            }
            _ => Value::Int(self.parse_int(text)?),
        };
        self.check(&value)?;
        Ok(value)
    }

    fn parse_int(&self, text: &str) -> Result<i64, FieldError> {
        if let Some(c) = self.convert {
            return self.parse_converted(c, text);
        }
        if let Some(label) = self
            .labels
            .iter()
            .find(|l| l.ident.eq_ignore_ascii_case(text))
        {
            return Ok(label.value);
        }
        if self.ty == FieldType::Bool {
            match text.to_ascii_lowercase().as_str() {
                "true" | "on" | "yes" => return Ok(1),
                "false" | "off" | "no" => return Ok(0),
                _ if self.labels.is_empty() && text.parse::<f64>().is_err() => {
                    return Err(FieldError::NotALabel {
                        field: self.ident.clone(),
                        value: crate::document::quote(text),
                        allowed: BOOL_WORDS.into(),
                    });
                }
                _ => {}
            }
        }
        if !self.bits.is_empty()
            && text.chars().any(|c| c.is_alphabetic())
            && !text.starts_with("0x")
        {
            let mut raw = 0i64;
            for part in text
                .split(['|', '+', ','])
                .map(str::trim)
                .filter(|p| !p.is_empty())
            {
                let bit = self
                    .bits
                    .iter()
                    .find(|b| b.ident.eq_ignore_ascii_case(part))
                    .ok_or_else(|| FieldError::NotALabel {
                        field: self.ident.clone(),
                        value: crate::document::quote(part),
                        allowed: self
                            .bits
                            .iter()
                            .map(|b| b.ident.as_str())
                            .collect::<Vec<_>>()
                            .join(", "),
                    })?;
                raw |= 1i64 << bit.bit;
            }
            return Ok(raw);
        }
        let hex = text.strip_prefix("0x").or_else(|| text.strip_prefix("0X"));
        if let (Some(digits), true) = (hex, self.scale == 1.0) {
            return i64::from_str_radix(digits, 16).map_err(|_| self.not_a_number(text));
        }
        if !self.labels.is_empty() && text.parse::<f64>().is_err() {
            return Err(FieldError::NotALabel {
                field: self.ident.clone(),
                value: crate::document::quote(text),
                allowed: self.label_list(),
            });
        }
        parse_scaled(text, self.scale).map_err(|e| match e {
            ScaledError::NotANumber => self.not_a_number(text),
            ScaledError::NotOnStep => FieldError::NotOnStep {
                field: self.ident.clone(),
                input: crate::document::quote(text),
                step: format!("{:.*}", self.decimals(), self.scale),
            },
            // Beyond any integer: out of the field's own range (not its type's).
            ScaledError::Huge => self.out_of_range_error(text.to_string()),
        })
    }

    /// A converted field takes `raw N` (or what [`Field::format`] shows, `25.0 (raw 2048)`) for
    /// a raw value, else a number in converted units, to the nearest raw value.
    fn parse_converted(&self, c: super::model::Conversion, text: &str) -> Result<i64, FieldError> {
        let raw_part = text
            .split_once("raw")
            .map(|(_, r)| r.trim_matches(|ch: char| ch == ')' || ch == ':' || ch.is_whitespace()));
        if let Some(r) = raw_part {
            return r.parse::<i64>().map_err(|_| self.not_a_number(text));
        }
        let v: f64 = text
            .trim_end_matches(self.unit.as_str())
            .trim()
            .parse()
            .map_err(|_| self.not_a_number(text))?;
        c.invert(v).ok_or_else(|| FieldError::WrongType {
            field: self.ident.clone(),
            expected: format!("a value the sensor can read ('{text}' is beyond it), or `raw N`"),
        })
    }

    fn not_a_number(&self, text: &str) -> FieldError {
        FieldError::NotANumber {
            field: self.ident.clone(),
            input: crate::document::quote(text),
            allowed: self.allowed_text(),
        }
    }
}

/// The raw values a field accepts.
#[derive(Debug, Clone, Copy)]
pub enum Allowed<'a> {
    /// An inclusive range.
    Range(i64, i64),
    /// Only the field's labelled values.
    Labels(&'a Field),
}

fn check_len(field: &Field, len: Len, actual: usize) -> Result<(), FieldError> {
    match len {
        Len::Fixed(n) if n != actual => Err(FieldError::WrongLength {
            field: field.ident.clone(),
            expected: n,
            actual,
        }),
        _ => Ok(()),
    }
}

/// Digits after the decimal point for a scale: 1 → 0, 0.1 → 1, 0.01 → 2, 0.25 → 2. A scale
/// with no short decimal form (the IMU's 1/4096 g) gets the digits of its step, enough for two
/// neighbouring raw values to read differently: 1/4096 → 4 (`0.0095 g`, not the twelve digits
/// of its exact value cut at nine, `0.009521484 g`).
pub fn decimals_for(scale: f64) -> usize {
    if !(scale.is_finite() && scale > 0.0) {
        return 0;
    }
    (0..=EXACT_DECIMALS)
        .find(|&d| {
            let x = scale * 10f64.powi(d as i32);
            (x - x.round()).abs() < 1e-9 * x.max(1.0)
        })
        .unwrap_or_else(|| (-scale.log10()).ceil().clamp(0.0, 9.0) as usize)
}

/// The most digits a scale is shown with exactly (0.000001); a finer or binary scale is shown to
/// its step.
const EXACT_DECIMALS: usize = 6;

#[cfg(test)]
mod decimals_tests {
    use super::decimals_for;

    #[test]
    fn a_scale_shows_its_exact_digits_or_those_of_its_step() {
        for (scale, digits) in [
            (1.0, 0),
            (10.0, 0),
            (4096.0, 0),
            (0.1, 1),
            (0.25, 2),
            (0.001, 3),
            (0.0625, 4),
            (1.0 / 4096.0, 4),
            (1.0 / 3.0, 1),
            (0.0, 0),
            (f64::NAN, 0),
        ] {
            assert_eq!(decimals_for(scale), digits, "scale {scale}");
        }
        // Neighbouring raw values of the IMU's scale read differently.
        let s = 1.0 / 4096.0;
        let shown = |raw: i64| format!("{:.*}", decimals_for(s), raw as f64 * s);
        assert_ne!(shown(39), shown(40));
    }
}

enum ScaledError {
    NotANumber,
    NotOnStep,
    Huge,
}

/// `display / scale`, exactly: refuses values between steps rather than rounding them.
fn parse_scaled(text: &str, scale: f64) -> Result<i64, ScaledError> {
    if text.is_empty() {
        return Err(ScaledError::NotANumber);
    }
    if scale == 1.0
        && let Ok(v) = text.parse::<i64>()
    {
        return Ok(v);
    }
    let x: f64 = text.parse().map_err(|_| ScaledError::NotANumber)?;
    if x.is_nan() {
        return Err(ScaledError::NotANumber);
    }
    if x.is_infinite() {
        return Err(ScaledError::Huge);
    }
    let raw = x / scale;
    let rounded = raw.round();
    if (raw - rounded).abs() > 1e-6 * rounded.abs().max(1.0) {
        return Err(ScaledError::NotOnStep);
    }
    if rounded.abs() > 9.0e15 {
        return Err(ScaledError::Huge);
    }
    Ok(rounded as i64)
}

/// A value as a person writes it in a RON file (a preset, a plan): text, or a bare number or
/// bool typed without quotes. It is read later by [`Field::parse`], in display units.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Typed(pub String);

impl<'de> serde::Deserialize<'de> for Typed {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::{Error, Visitor};
        struct V;
        impl Visitor<'_> for V {
            type Value = Typed;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(r#"a value as displayed, e.g. "2.75", "on" or 70"#)
            }
            fn visit_str<E: Error>(self, v: &str) -> Result<Typed, E> {
                Ok(Typed(v.to_string()))
            }
            fn visit_string<E: Error>(self, v: String) -> Result<Typed, E> {
                Ok(Typed(v))
            }
            fn visit_i64<E: Error>(self, v: i64) -> Result<Typed, E> {
                Ok(Typed(v.to_string()))
            }
            fn visit_u64<E: Error>(self, v: u64) -> Result<Typed, E> {
                Ok(Typed(v.to_string()))
            }
            fn visit_f64<E: Error>(self, v: f64) -> Result<Typed, E> {
                Ok(Typed(v.to_string()))
            }
            fn visit_bool<E: Error>(self, v: bool) -> Result<Typed, E> {
                Ok(Typed(v.to_string()))
            }
        }
        d.deserialize_any(V)
    }
}
