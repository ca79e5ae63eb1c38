//! What does not fit: a value against its field ([`FieldError`]), a payload against its layout,
//! two values against a relation.

use super::value::Value;
use crate::protocol::hex;

/// Two values that break a relation of the profile, both named.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{low_name} ({low}) {low_value} must be {sign} {high_name} ({high}) {high_value}")]
pub struct Broken {
    /// The smaller side's ident.
    pub low: String,
    /// Its name.
    pub low_name: String,
    /// Its value, as displayed.
    pub low_value: String,
    /// `≤` or `<`.
    pub sign: &'static str,
    /// The larger side's ident.
    pub high: String,
    /// Its name.
    pub high_name: String,
    /// Its value, as displayed.
    pub high_value: String,
}

/// A payload that does not fit the profile's layout. Its text leaves out the command, which
/// whoever shows it names.
#[derive(Debug, Clone, PartialEq)]
pub struct Misfit {
    /// The command's ident.
    pub command: String,
    /// What went wrong: a field the payload ends inside ([`FieldError::ShortPayload`]), bytes
    /// left over ([`FieldError::LongPayload`]), or a value that cannot be read.
    pub fault: FieldError,
    /// The values read before the fault: (ident, raw value, as displayed).
    pub decoded: Vec<(String, Value, String)>,
    /// The payload as received.
    pub payload: Vec<u8>,
    /// The payload lengths the layout takes: (fewest, most; `None`: no limit).
    pub expected: (usize, Option<usize>),
}

impl Misfit {
    /// `5 bytes`, `3 to 5 bytes`, `at least 3 bytes`.
    pub fn expected_text(&self) -> String {
        match self.expected {
            (lo, Some(hi)) if lo == hi => format!("{lo} byte(s)"),
            (lo, Some(hi)) => format!("{lo} to {hi} bytes"),
            (lo, None) => format!("at least {lo} byte(s)"),
        }
    }
}

impl std::fmt::Display for Misfit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}-byte payload where the layout takes {}: {}; raw [{}]",
            self.payload.len(),
            self.expected_text(),
            self.fault,
            hex::format(&self.payload)
        )?;
        if !self.decoded.is_empty() {
            let read: Vec<String> = self
                .decoded
                .iter()
                .map(|(k, _, d)| format!("{k}={d}"))
                .collect();
            write!(f, "; read before the fault: {}", read.join(", "))?;
        }
        Ok(())
    }
}

/// Why a value cannot be read, written or shown.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FieldError {
    /// A number outside the field's range.
    #[error("{field}: {value} is out of range; allowed {min} to {max}{unit}")]
    OutOfRange {
        /// The field's ident.
        field: String,
        /// The value, as displayed.
        value: String,
        /// The smallest allowed, as displayed.
        min: String,
        /// The largest allowed, as displayed.
        max: String,
        /// The unit, with a leading space, or empty.
        unit: String,
    },
    /// A value the field's labels do not name.
    #[error("{field}: '{value}' is not one of {allowed}")]
    NotALabel {
        /// The field's ident.
        field: String,
        /// What was given.
        value: String,
        /// The allowed labels and numbers.
        allowed: String,
    },
    /// Text that is not a number.
    #[error("{field}: '{input}' is not a number; allowed {allowed}")]
    NotANumber {
        /// The field's ident.
        field: String,
        /// What was typed (a line or so of it).
        input: String,
        /// What the field takes ([`Field::allowed_text`]).
        allowed: String,
    },
    /// Nothing typed where a value is needed (`pwmValue=`).
    #[error("{field}: no value given; allowed {allowed}")]
    NoValue {
        /// The field's ident.
        field: String,
        /// What the field takes ([`Field::allowed_text`]).
        allowed: String,
    },
    /// A number finer than the field's step (`2.755` where the step is 0.01).
    #[error("{field}: {input} is not a multiple of the field's step {step}")]
    NotOnStep {
        /// The field's ident.
        field: String,
        /// What was typed.
        input: String,
        /// The step (the scale).
        step: String,
    },
    /// A value of the wrong kind (text for a number...).
    #[error("{field}: expected {expected}")]
    WrongType {
        /// The field's ident.
        field: String,
        /// What the field takes.
        expected: String,
    },
    /// Text or bytes of the wrong length.
    #[error("{field}: expected exactly {expected} bytes, got {actual}")]
    WrongLength {
        /// The field's ident.
        field: String,
        /// The field's length.
        expected: usize,
        /// The value's length.
        actual: usize,
    },
    /// A payload that ends inside a field.
    #[error("{field}: payload ends early: {need} more byte(s) needed, {have} left")]
    ShortPayload {
        /// The field's ident.
        field: String,
        /// Bytes the field needs.
        need: usize,
        /// Bytes left.
        have: usize,
    },
    /// Text bytes that are not UTF-8.
    #[error("{field}: text is not valid UTF-8")]
    NotUtf8 {
        /// The field's ident.
        field: String,
    },
    /// A name that is not a field of the command.
    #[error("{command} has no field '{field}'; {}", fields_text(known))]
    UnknownField {
        /// The command's ident.
        command: String,
        /// The unknown name (a line or so of it).
        field: String,
        /// The fields it has, comma-separated; empty when it takes none.
        known: String,
    },
    /// A name that is no data point of the profile.
    #[error("no data point '{name}'; data points: {known}")]
    UnknownDataPoint {
        /// The name given (a line or so of it).
        name: String,
        /// The profile's data points, comma-separated.
        known: String,
    },
    /// One field (or data point) given twice: which value was meant is not known.
    #[error("{command}: '{field}' is given twice; give it once")]
    Duplicate {
        /// The command's ident.
        command: String,
        /// The field's ident.
        field: String,
    },
    /// A field left out.
    #[error("{command}: field '{field}' is missing")]
    MissingField {
        /// The command's ident.
        command: String,
        /// The field's ident.
        field: String,
    },
    /// A data point value outside what the data point allows (range, step, labels, bits,
    /// length: [`super::DpLimit`]).
    #[error("{field}: {limit}")]
    DataPointLimit {
        /// The data point's ident.
        field: String,
        /// Which limit, with the value and what is allowed.
        limit: Box<super::DpLimit>,
    },
    /// A parameter or data point that cannot be written.
    #[error("{field} is read-only")]
    ReadOnly {
        /// Its ident.
        field: String,
    },
    /// A parameter or data point the profile does not have.
    #[error("{what} {id} is not in the profile")]
    Unknown {
        /// "parameter" or "data point".
        what: &'static str,
        /// Its id or name.
        id: String,
    },
    /// A data point whose type differs from the profile's.
    #[error("data point {field}: type {actual} on the wire, the profile says {expected}")]
    DpType {
        /// The DP's ident.
        field: String,
        /// The profile's type.
        expected: &'static str,
        /// The wire type.
        actual: &'static str,
    },
    /// A malformed data-point list.
    #[error("{0}")]
    Dp(#[from] crate::protocol::tuya::dp::DpError),
    /// Bytes left over after the layout's last field (firmware that sends more than the
    /// profile knows).
    #[error("{} byte(s) past the layout's last field: {}", extra.len(), hex::format(extra))]
    LongPayload {
        /// The bytes left over.
        extra: Vec<u8>,
    },
    /// A payload that does not fit its layout: the fault, what was read before it, the raw
    /// bytes. Never shown as clean values.
    #[error("{0}")]
    Misfit(Box<Misfit>),
    /// Records of a synchronous command (servo 25) that do not fit their sub-command.
    #[error("{field}: {message}")]
    Records {
        /// The field's ident.
        field: String,
        /// What does not fit.
        message: String,
    },
    /// Two values that break a relation of the profile (a minimum above its maximum).
    #[error("{0}")]
    Relation(Box<Broken>),
}

/// The end of an unknown-field message: the fields a command has, or that it takes none.
fn fields_text(known: &str) -> String {
    if known.is_empty() {
        "it takes no fields".to_string()
    } else {
        format!("its fields: {known}")
    }
}
