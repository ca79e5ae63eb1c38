//! Hex text for people: parsing what a technician pastes, and printing frames.

use std::fmt::Write;

/// Why hex text could not be read.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum HexError {
    /// A character that is not a hex digit or a separator.
    #[error("'{ch}' at character {pos} is not a hex digit")]
    NotHex {
        /// The character.
        ch: char,
        /// Its 1-based position in the text.
        pos: usize,
    },
    /// A run of digits of odd length.
    #[error("'{token}' has an odd number of hex digits: bytes take two digits each")]
    OddLength {
        /// The run of digits.
        token: String,
    },
}

/// Parses `12 4c 01`, `0x12,0x4C`, `124c01`, `x12 0x4c` and mixtures of these.
///
/// Separators are white space, commas, colons, dashes and semicolons. A token with a `0x` prefix
/// holds one or more bytes; a bare run of digits holds bytes two digits at a time.
pub fn parse(text: &str) -> Result<Vec<u8>, HexError> {
    let mut out = Vec::new();
    let is_sep = |c: char| c.is_whitespace() || matches!(c, ',' | ':' | '-' | ';');
    let mut offset = 0;
    for raw in text.split(is_sep) {
        let start = offset;
        offset += raw.chars().count() + 1;
        if raw.is_empty() {
            continue;
        }
        let (digits, skipped) = match raw.strip_prefix("0x").or_else(|| raw.strip_prefix("0X")) {
            Some(rest) => (rest, 2),
            None => match raw.strip_prefix('x').or_else(|| raw.strip_prefix('X')) {
                Some(rest) => (rest, 1),
                None => (raw, 0),
            },
        };
        if let Some((i, ch)) = digits
            .chars()
            .enumerate()
            .find(|(_, c)| !c.is_ascii_hexdigit())
        {
            return Err(HexError::NotHex {
                ch,
                pos: start + skipped + i + 1,
            });
        }
        if digits.is_empty() {
            return Err(HexError::NotHex {
                ch: raw.chars().last().unwrap_or('x'),
                pos: start + raw.chars().count(),
            });
        }
        if digits.len() % 2 == 1 {
            if skipped > 0 && digits.len() == 1 {
                // `0x5` is a whole byte written with one digit.
                out.push(u8::from_str_radix(digits, 16).unwrap_or_default());
                continue;
            }
            return Err(HexError::OddLength {
                token: raw.to_string(),
            });
        }
        for pair in digits.as_bytes().chunks(2) {
            let s = std::str::from_utf8(pair).unwrap_or("00");
            out.push(u8::from_str_radix(s, 16).unwrap_or_default());
        }
    }
    Ok(out)
}

/// Formats bytes as lower-case hex pairs separated by spaces: `12 4c 01`.
pub fn format(bytes: &[u8]) -> String {
    let mut s = String::with_capacity(bytes.len() * 3);
    for (i, b) in bytes.iter().enumerate() {
        if i > 0 {
            s.push(' ');
        }
        let _ = write!(s, "{b:02x}");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accepts_the_three_documented_forms() {
        let want = vec![0x12, 0x4c, 0x01];
        assert_eq!(parse("12 4c 01").unwrap(), want);
        assert_eq!(parse("0x12,0x4C,0x01").unwrap(), want);
        assert_eq!(parse("124c01").unwrap(), want);
        assert_eq!(parse("x12 0x4c 0x01").unwrap(), want);
        assert_eq!(parse("0x5").unwrap(), vec![5]);
        assert_eq!(parse("").unwrap(), Vec::<u8>::new());
    }

    #[test]
    fn refuses_non_hex_and_odd_length() {
        assert_eq!(
            parse("12 4g").unwrap_err(),
            HexError::NotHex { ch: 'g', pos: 5 }
        );
        assert!(matches!(parse("124"), Err(HexError::OddLength { .. })));
        assert!(matches!(parse("0x"), Err(HexError::NotHex { .. })));
    }

    #[test]
    fn formats_round_trip() {
        let bytes = [0u8, 0x7f, 0xff];
        assert_eq!(format(&bytes), "00 7f ff");
        assert_eq!(parse(&format(&bytes)).unwrap(), bytes);
    }
}
