//! English texts of the layers below said in Chinese by a table of their fixed phrases: for
//! texts that are stored or passed on as English strings (a record's reason, a self-test's
//! detail) and shown in the window in 中文. Values inside them (paths, numbers, names) are left
//! as they are.

/// Whether `c` continues a word.
fn wordy(c: Option<char>) -> bool {
    c.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// `text` with each phrase of `table` (English, Chinese) replaced, in order (a longer phrase
/// before one it holds), where it stands at a word's edge: a phrase that starts or ends with a
/// letter or digit is left alone inside a longer word ("volt" in "voltage").
pub fn replace(text: &str, table: &[(&str, &str)]) -> String {
    let mut text = text.to_string();
    for (en, zh) in table {
        let (starts, ends) = (
            en.starts_with(|c: char| c.is_ascii_alphanumeric()),
            en.ends_with(|c: char| c.is_ascii_alphanumeric()),
        );
        let mut out = String::with_capacity(text.len());
        let mut rest = text.as_str();
        while let Some(at) = rest.find(en) {
            let before = rest[..at].chars().next_back().or(out.chars().next_back());
            let after = rest[at + en.len()..].chars().next();
            let inside_a_word = (starts && wordy(before)) || (ends && wordy(after));
            out.push_str(&rest[..at]);
            out.push_str(if inside_a_word { en } else { zh });
            rest = &rest[at + en.len()..];
        }
        out.push_str(rest);
        text = out;
    }
    text
}

#[cfg(test)]
mod tests {
    use super::replace;

    #[test]
    fn phrases_are_replaced_in_order_and_never_inside_a_word() {
        let table = [("none", "无"), ("write", "写入"), (" of ", "/")];
        assert_eq!(replace("nonexistent none", &table), "nonexistent 无");
        assert_eq!(replace("rewrite: write", &table), "rewrite: 写入");
        assert_eq!(replace("2 of 5", &table), "2/5");
    }
}
