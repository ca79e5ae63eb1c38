//! What does not fit: a payload against its layout, two values against a relation.

use super::value::{FieldError, Value};
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
