//! Input quoted in a message, kept to a line or so: a 100 MB junk file or a 10,000-digit number
//! gives a short message that still shows what was given.

/// The most characters of one quoted input.
pub const QUOTE_MAX: usize = 60;

/// The most bytes of a whole message (a safety net under [`quote`]).
pub const MESSAGE_MAX: usize = 2000;

/// `text` as quoted in a message: its first line, at most [`QUOTE_MAX`] characters, control
/// characters escaped, and `…` where something was left out.
pub fn quote(text: &str) -> String {
    let mut out = String::new();
    for (shown, c) in text.chars().enumerate() {
        if c == '\n' || shown == QUOTE_MAX {
            out.push('…');
            break;
        }
        push_escaped(&mut out, c);
    }
    out
}

fn push_escaped(out: &mut String, c: char) {
    if c.is_control() {
        out.extend(c.escape_default());
    } else {
        out.push(c);
    }
}

/// A message that may hold input it did not quote itself (a parser's error): control characters
/// escaped, each quoted stretch (between `` ` `` or `"`) and each run without spaces of more
/// than [`QUOTE_MAX`] characters shortened with `…`, and the whole kept to about [`MESSAGE_MAX`] bytes.
pub fn clip_message(message: &str) -> String {
    let chars: Vec<char> = message.chars().collect();
    let mut out = String::new();
    let mut i = 0;
    while i < chars.len() {
        if out.len() >= MESSAGE_MAX {
            out.push('…');
            break;
        }
        let c = chars[i];
        // A quoted stretch: up to the same quote, or the end.
        if matches!(c, '`' | '"')
            && let Some(len) = chars[i + 1..].iter().position(|&d| d == c)
            && len > QUOTE_MAX
        {
            out.push(c);
            out.push_str(&quote(
                &chars[i + 1..i + 1 + len].iter().collect::<String>(),
            ));
            out.push(c);
            i += len + 2;
            continue;
        }
        // A run without spaces.
        let run = chars[i..].iter().take_while(|d| !d.is_whitespace()).count();
        if run > QUOTE_MAX {
            out.push_str(&quote(&chars[i..i + run].iter().collect::<String>()));
            i += run;
            continue;
        }
        push_escaped(&mut out, c);
        i += 1;
    }
    out
}

/// A number typed by a person (`text`, spaces around allowed) as a `T` within `range`; the
/// error quotes what was given and says what is allowed (`what`: "milliseconds", "a baud
/// rate"), as the command line's, the window's and a station file's checks all say it.
pub fn number_within<T>(
    text: &str,
    range: &std::ops::RangeInclusive<T>,
    what: &str,
) -> Result<T, String>
where
    T: std::str::FromStr + PartialOrd + std::fmt::Display,
{
    let quoted = quote(text);
    let allowed = format!("{what} from {} to {}", range.start(), range.end());
    let value: T = text
        .trim()
        .parse()
        .map_err(|_| format!("'{quoted}' is not a number; give {allowed}"))?;
    if range.contains(&value) {
        Ok(value)
    } else {
        Err(format!("{quoted} is out of range; give {allowed}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_quote_is_one_short_line() {
        assert_eq!(quote("70"), "70");
        assert_eq!(quote("七十"), "七十");
        assert_eq!(quote("a\tb"), "a\\tb");
        assert_eq!(quote("one\ntwo"), "one…");
        let long = "9".repeat(10_000);
        let q = quote(&long);
        assert_eq!(q.chars().count(), QUOTE_MAX + 1);
        assert!(q.ends_with('…'));
    }

    #[test]
    fn a_parser_message_keeps_its_words_and_loses_the_junk() {
        let junk = "Z".repeat(1_000_000);
        let m = clip_message(&format!("Expected struct `preset` but found `{junk}`"));
        assert!(
            m.starts_with("Expected struct `preset` but found `ZZZ"),
            "{m}"
        );
        assert!(m.len() < 200, "{}", m.len());
        let spaced = "word ".repeat(100_000);
        let m = clip_message(&format!(
            "invalid type: string \"{spaced}\", expected a number"
        ));
        assert!(m.ends_with(", expected a number"), "{m}");
        assert!(m.len() < 200, "{}", m.len());
        let m = clip_message(&format!("found {junk} here"));
        assert!(m.ends_with("… here"), "{m}");
        assert!(clip_message(&"a ".repeat(10_000)).len() <= MESSAGE_MAX + 4);
        // Short messages are left as they are.
        let list = "unknown field `x`, expected one of `version`, `profile`, `values`";
        assert_eq!(clip_message(list), list);
        assert_eq!(clip_message("line\nbreak"), "line\\nbreak");
    }
}
