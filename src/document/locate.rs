//! Finds where a value sits in RON text, so that an inconsistency found after parsing can be
//! reported with its line and column, as a syntax error is. Comments, strings and raw strings
//! are skipped; a path that leaves the text stops at the deepest step found.

/// One step of a path into a RON document.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Step {
    /// A struct field by name.
    Key(&'static str),
    /// A list element by index.
    Index(usize),
    /// A map entry by its string key, as written (`{ "MSP_SET_PWMVALUE": ... }`). It is placed
    /// at its key, which is where a person looks for it; a further step goes into its value.
    Entry(String),
}

/// The 1-based line and column of the value at `path`, or of the deepest step found.
pub fn locate(src: &str, path: &[Step]) -> (usize, usize) {
    let mut c = Cursor {
        s: src.as_bytes(),
        pos: 0,
        key: None,
    };
    c.skip_ws();
    let mut best = c.pos;
    for step in path {
        let found = match step {
            Step::Key(k) => c.enter_struct() && c.find_key(k),
            Step::Index(i) => c.find_index(*i),
            Step::Entry(k) => c.find_entry(k),
        };
        if !found {
            break;
        }
        best = c.key.take().unwrap_or(c.pos);
    }
    line_col(src, best)
}

/// The 1-based line and column of a byte offset.
pub fn line_col(src: &str, pos: usize) -> (usize, usize) {
    let before = &src[..floor_char_boundary(src, pos)];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

fn floor_char_boundary(s: &str, mut i: usize) -> usize {
    i = i.min(s.len());
    while !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

struct Cursor<'a> {
    s: &'a [u8],
    pos: usize,
    /// Where the map entry just found starts (its key), when the last step was an entry.
    key: Option<usize>,
}

impl Cursor<'_> {
    fn peek(&self) -> Option<u8> {
        self.s.get(self.pos).copied()
    }

    fn skip_ws(&mut self) {
        loop {
            match self.peek() {
                Some(b) if b.is_ascii_whitespace() => self.pos += 1,
                Some(b'/') if self.s.get(self.pos + 1) == Some(&b'/') => {
                    while !matches!(self.peek(), None | Some(b'\n')) {
                        self.pos += 1;
                    }
                }
                Some(b'/') if self.s.get(self.pos + 1) == Some(&b'*') => {
                    self.pos += 2;
                    while self.pos < self.s.len() && !self.s[self.pos..].starts_with(b"*/") {
                        self.pos += 1;
                    }
                    self.pos = (self.pos + 2).min(self.s.len());
                }
                _ => return,
            }
        }
    }

    fn ident(&mut self) -> &[u8] {
        let start = self.pos;
        while matches!(self.peek(), Some(b) if b.is_ascii_alphanumeric() || b == b'_' || b == b'#')
        {
            self.pos += 1;
        }
        &self.s[start..self.pos]
    }

    fn skip_string(&mut self) {
        // at the opening quote
        self.pos += 1;
        while let Some(b) = self.peek() {
            self.pos += 1;
            match b {
                b'\\' => self.pos += 1,
                b'"' => return,
                _ => {}
            }
        }
    }

    fn skip_raw_string(&mut self) {
        // at `r`, then hashes, then quote
        self.pos += 1;
        let mut hashes = 0;
        while self.peek() == Some(b'#') {
            hashes += 1;
            self.pos += 1;
        }
        self.pos += 1;
        let mut close = vec![b'"'];
        close.extend(std::iter::repeat_n(b'#', hashes));
        while self.pos < self.s.len() && !self.s[self.pos..].starts_with(&close) {
            self.pos += 1;
        }
        self.pos = (self.pos + close.len()).min(self.s.len());
    }

    /// Skips one value, whatever it is.
    fn skip_value(&mut self) {
        self.skip_ws();
        match self.peek() {
            None => {}
            Some(b'"') => self.skip_string(),
            Some(b'r') if matches!(self.s.get(self.pos + 1), Some(b'"' | b'#')) => {
                self.skip_raw_string()
            }
            Some(b'\'') => {
                self.pos += 1;
                while let Some(b) = self.peek() {
                    self.pos += 1;
                    match b {
                        b'\\' => self.pos += 1,
                        b'\'' => break,
                        _ => {}
                    }
                }
            }
            Some(b'(' | b'[' | b'{') => self.skip_group(),
            Some(b) if b.is_ascii_alphabetic() || b == b'_' => {
                self.ident();
                self.skip_ws();
                if self.peek() == Some(b'(') {
                    self.skip_group();
                }
            }
            Some(_) => {
                while matches!(self.peek(), Some(b) if !b.is_ascii_whitespace() && !b",)]}".contains(&b))
                {
                    self.pos += 1;
                }
            }
        }
    }

    fn skip_group(&mut self) {
        let close = match self.peek() {
            Some(b'(') => b')',
            Some(b'[') => b']',
            _ => b'}',
        };
        self.pos += 1;
        loop {
            self.skip_ws();
            match self.peek() {
                None => return,
                Some(b) if b == close => {
                    self.pos += 1;
                    return;
                }
                Some(b',' | b':') => self.pos += 1,
                Some(_) => {
                    let before = self.pos;
                    self.skip_value();
                    if self.pos == before {
                        self.pos += 1;
                    }
                }
            }
        }
    }

    /// At a struct value (`Name(`, `(` or `Some(Name(`): moves inside its parentheses.
    fn enter_struct(&mut self) -> bool {
        self.skip_ws();
        let name = self.ident().to_vec();
        self.skip_ws();
        if self.peek() != Some(b'(') {
            return false;
        }
        self.pos += 1;
        if name == b"Some" {
            return self.enter_struct();
        }
        true
    }

    /// Inside a struct: moves to the value of `key`.
    fn find_key(&mut self, key: &str) -> bool {
        loop {
            self.skip_ws();
            match self.peek() {
                None | Some(b')') => return false,
                Some(b',') => {
                    self.pos += 1;
                    continue;
                }
                _ => {}
            }
            let start = self.pos;
            let name = self.ident().to_vec();
            self.skip_ws();
            if self.peek() == Some(b':') && !name.is_empty() {
                self.pos += 1;
                self.skip_ws();
                if name == key.as_bytes() {
                    return true;
                }
            } else {
                self.pos = start;
            }
            let before = self.pos;
            self.skip_value();
            if self.pos == before {
                return false;
            }
        }
    }

    /// At a group opened by `open` (or `Some(` and then it): moves inside it.
    fn enter(&mut self, open: u8) -> bool {
        self.skip_ws();
        if self.s[self.pos..].starts_with(b"Some") {
            self.ident();
            self.skip_ws();
            if self.peek() != Some(b'(') {
                return false;
            }
            self.pos += 1;
            self.skip_ws();
        }
        if self.peek() != Some(open) {
            return false;
        }
        self.pos += 1;
        true
    }

    /// Inside a group closed by `close`: moves to the next item (past commas); false at its end.
    fn next_item(&mut self, close: u8) -> bool {
        loop {
            self.skip_ws();
            match self.peek() {
                None => return false,
                Some(b) if b == close => return false,
                Some(b',') => self.pos += 1,
                _ => return true,
            }
        }
    }

    /// At a list value (or `Some([`): moves to element `index`.
    fn find_index(&mut self, index: usize) -> bool {
        if !self.enter(b'[') {
            return false;
        }
        let mut n = 0;
        while self.next_item(b']') {
            if n == index {
                return true;
            }
            let before = self.pos;
            self.skip_value();
            if self.pos == before {
                return false;
            }
            n += 1;
        }
        false
    }

    /// At a map value (or `Some({`): moves to the value of the entry whose key is the string
    /// `key`.
    fn find_entry(&mut self, key: &str) -> bool {
        if !self.enter(b'{') {
            return false;
        }
        let quoted = ron::to_string(key).unwrap_or_else(|_| format!("\"{key}\""));
        while self.next_item(b'}') {
            let start = self.pos;
            self.skip_value();
            if self.pos == start {
                return false;
            }
            let matched = &self.s[start..self.pos] == quoted.as_bytes();
            self.skip_ws();
            if self.peek() != Some(b':') {
                return false;
            }
            self.pos += 1;
            self.skip_ws();
            if matched {
                self.key = Some(start);
                return true;
            }
            let before = self.pos;
            self.skip_value();
            if self.pos == before {
                return false;
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SRC: &str = r#"// a comment with ( and [
Profile(
    id: "x",
    commands: [
        Command(id: 1, name: (en: "a, b", zh: ")"), reply: []),
        /* block ( */ Command(
            id: 2,
            reply: [Field(ident: "f"), Field(ident: "g", range: Some((0, 300)))],
        ),
    ],
)"#;

    #[test]
    fn finds_nested_keys_and_indices_past_strings_and_comments() {
        use Step::*;
        assert_eq!(locate(SRC, &[Key("id")]), (3, 9));
        assert_eq!(
            locate(SRC, &[Key("commands"), Index(1), Key("id")]),
            (7, 17)
        );
        let range = [
            Key("commands"),
            Index(1),
            Key("reply"),
            Index(1),
            Key("range"),
        ];
        assert_eq!(locate(SRC, &range), (8, 65));
    }

    #[test]
    fn finds_map_entries_by_their_string_key() {
        use Step::*;
        let src = "// \"A\": { in a comment\n(\n    values: {\n        \"A\": { \"x\": \"1\" },\n        \"B\": {\n            \"x\": \"2\", \"y\": \"3\",\n        },\n    },\n)";
        let at = |path: &[Step]| locate(src, path);
        assert_eq!(at(&[Key("values"), Entry("A".into())]), (4, 9));
        assert_eq!(
            at(&[Key("values"), Entry("B".into()), Entry("y".into())]),
            (6, 23)
        );
        // A key not there: the deepest step found.
        assert_eq!(at(&[Key("values"), Entry("C".into())]), (3, 13));
    }

    #[test]
    fn stops_at_the_deepest_step_found() {
        use Step::*;
        assert_eq!(locate(SRC, &[Key("commands"), Index(7)]), (4, 15));
    }
}
