//! The port's own options beyond the baud rate: the modem lines (DTR, RTS) set right after the
//! port opens, the settle time before the first request (a board that reboots when its USB
//! adapter toggles DTR/RTS on open), and the ranges the command line, the window and the
//! station all accept for the answer margin and that settle time.

use super::{LinkError, Opener};
use serde::{Deserialize, Serialize};
use std::ops::RangeInclusive;
use std::time::Duration;

/// The answer margin a user may give (`--margin-ms`, the window's margin, a station), ms.
pub const MARGIN_MS: RangeInclusive<u64> = 1..=5_000;
/// The settle time after open a user may give (`--boot-wait-ms`, the window, a station), ms.
pub const BOOT_WAIT_MS: RangeInclusive<u64> = 0..=30_000;

/// Milliseconds typed by a person (`text`, spaces around allowed) within `range`; the error
/// says what was given and what is allowed, as the command line's do.
pub fn ms_within(text: &str, range: &RangeInclusive<u64>) -> Result<u64, String> {
    crate::document::number_within(text, range, "milliseconds")
}

/// What to do with a modem line (DTR or RTS) right after the port opens.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LineLevel {
    /// Assert it (the line's logic level true).
    On,
    /// Clear it.
    Off,
    /// Leave it as the OS and the adapter set it when the port opened (most adapters assert
    /// both on open).
    #[default]
    Keep,
}

impl LineLevel {
    /// Every level, in the order the window offers them.
    pub const ALL: [LineLevel; 3] = [LineLevel::Keep, LineLevel::On, LineLevel::Off];

    /// The level to set (`None`: keep).
    pub fn level(self) -> Option<bool> {
        match self {
            LineLevel::On => Some(true),
            LineLevel::Off => Some(false),
            LineLevel::Keep => None,
        }
    }

    /// As the command line and a station file write it: `on`, `off`, `keep`.
    pub fn as_str(self) -> &'static str {
        match self {
            LineLevel::On => "on",
            LineLevel::Off => "off",
            LineLevel::Keep => "keep",
        }
    }
}

impl std::fmt::Display for LineLevel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for LineLevel {
    type Err = String;

    /// `on`, `off` or `keep` (any case); the error names the words accepted.
    fn from_str(text: &str) -> Result<Self, String> {
        match text.trim().to_ascii_lowercase().as_str() {
            "on" => Ok(LineLevel::On),
            "off" => Ok(LineLevel::Off),
            "keep" => Ok(LineLevel::Keep),
            _ => Err(format!(
                "'{}' is not a line level; give on, off or keep",
                crate::document::quote(text)
            )),
        }
    }
}

/// What is done to a port right after it opens: its DTR and RTS lines, then a settle time
/// before the first request. `Default`: lines kept, no wait.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PortSetup {
    /// The DTR line.
    pub dtr: LineLevel,
    /// The RTS line.
    pub rts: LineLevel,
    /// How long to send nothing after the port opens (each open, reconnects included): a board
    /// that reboots on open answers nothing for its boot time.
    pub boot_wait: Duration,
}

impl PortSetup {
    /// `opener`, with DTR and RTS set as asked on every transport it opens. Errors: the
    /// opener's, or the port refused a line ([`LinkError::Setting`]).
    pub fn wrap(self, mut opener: Opener) -> Opener {
        if self.dtr == LineLevel::Keep && self.rts == LineLevel::Keep {
            return opener;
        }
        Box::new(move || {
            let mut t = opener()?;
            t.set_lines(self.dtr.level(), self.rts.level())?;
            Ok(t)
        })
    }
}

/// Says which line failed (`DTR on`) with the port's own words.
pub(crate) fn line_error(line: &str, on: bool, why: impl std::fmt::Display) -> LinkError {
    let level = if on { "on" } else { "off" };
    LinkError::Setting(format!("{line} {level}: {why}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_levels_parse_and_name_the_words_accepted() {
        assert_eq!("on".parse::<LineLevel>(), Ok(LineLevel::On));
        assert_eq!(" OFF ".parse::<LineLevel>(), Ok(LineLevel::Off));
        assert_eq!("keep".parse::<LineLevel>(), Ok(LineLevel::Keep));
        let e = "high".parse::<LineLevel>().unwrap_err();
        assert!(e.contains("'high'") && e.contains("on, off or keep"), "{e}");
        assert_eq!(LineLevel::Keep.level(), None);
        assert_eq!(LineLevel::Off.level(), Some(false));
    }
}
