//! RON documents a person writes and botbench checks: presets, servo parameter presets, self-test
//! plans and provisioning plans. One place reads them, parses them, says where a problem is
//! (`file:line:col: message`, for a syntax error as for a value the profile refuses) and writes
//! them back atomically.
//!
//! Each document type keeps its own schema and checks; what they share is here: [`Source`] (a
//! document's name and text), [`DocumentError`] (the one error type, with every problem and its
//! place), reading within a size limit ([`file::read_text`], [`Limit`]) and [`write_atomic`].
//! Messages quote at most a line or so of the input ([`quote`]).

pub mod file;
pub mod locate;
pub mod quote;

pub use file::{
    Limit, check_append, check_destination, read_bytes, read_text, write_atomic, write_atomic_with,
};
pub use locate::{Step, line_col, locate};
pub use quote::{clip_message, number_within, quote};

use serde::de::DeserializeOwned;
use std::fmt;
use std::path::Path;

/// What kind of problem a document has.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorKind {
    /// The file cannot be read or written.
    Io,
    /// Not valid RON, or not the document's shape (a missing, unknown or mistyped key).
    Syntax,
    /// No version, or one this build does not read.
    Version,
    /// Made for another profile.
    Profile,
    /// A value the profile refuses: an unknown command, field or parameter, a missing field, a
    /// value out of range or between steps, a name given twice.
    Value,
}

/// One problem in a document, where it is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Problem {
    /// 1-based line, 0 when unknown.
    pub line: usize,
    /// 1-based column, 0 when unknown.
    pub col: usize,
    /// What is wrong.
    pub message: String,
}

impl Problem {
    /// A problem at `(line, col)`. Input the message holds is kept to a line or so
    /// ([`clip_message`]).
    pub fn at((line, col): (usize, usize), message: impl Into<String>) -> Self {
        Self {
            line,
            col,
            message: clip_message(&message.into()),
        }
    }
}

/// Why a document cannot be used, or could not be saved. When a document is refused, nothing
/// has been written to a device.
///
/// Shown as `file:line:col: message` (or `file: message` where the place is unknown); several
/// problems as a count, then one a line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DocumentError {
    /// The file (or the name given to the parser).
    pub file: String,
    /// What kind of problem (of the first, when there are several).
    pub kind: ErrorKind,
    /// The problems, at least one.
    pub problems: Vec<Problem>,
}

impl DocumentError {
    /// One problem of `kind` at `(line, col)` of `file`.
    pub fn one(
        file: &str,
        kind: ErrorKind,
        at: (usize, usize),
        message: impl Into<String>,
    ) -> Self {
        Self {
            file: file.to_string(),
            kind,
            problems: vec![Problem::at(at, message.into())],
        }
    }

    /// `file` cannot be read or written: `what` failed with `error`.
    pub fn io(file: &Path, what: &str, error: &std::io::Error) -> Self {
        Self::one(
            &file.display().to_string(),
            ErrorKind::Io,
            (0, 0),
            format!("cannot {what}: {error}"),
        )
    }

    /// The first problem's message.
    pub fn message(&self) -> &str {
        self.problems.first().map_or("", |p| p.message.as_str())
    }

    /// The first problem's line and column (0, 0 when unknown).
    pub fn at(&self) -> (usize, usize) {
        self.problems.first().map_or((0, 0), |p| (p.line, p.col))
    }
}

impl fmt::Display for DocumentError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let at = |p: &Problem| {
            if p.line == 0 {
                format!("{}: {}", self.file, p.message)
            } else {
                format!("{}:{}:{}: {}", self.file, p.line, p.col, p.message)
            }
        };
        match self.problems.as_slice() {
            [one] => write!(f, "{}", at(one)),
            many => {
                write!(f, "{}: {} problems:", self.file, many.len())?;
                for p in many {
                    write!(f, "\n  {}", at(p))?;
                }
                Ok(())
            }
        }
    }
}

impl std::error::Error for DocumentError {}

/// A document's text and the name its errors give it (its path, or a name for text that came
/// from elsewhere).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Source<'t> {
    /// The name errors give.
    pub name: &'t str,
    /// The RON text.
    pub text: &'t str,
}

impl<'t> Source<'t> {
    /// The text `text`, named `name` in errors.
    pub fn new(name: &'t str, text: &'t str) -> Self {
        Self { name, text }
    }

    /// Parses the text as `T`. `Option` fields may be written without `Some(..)`. A syntax error
    /// (or a key the shape does not have) is reported where it is.
    pub fn parse<T: DeserializeOwned>(&self) -> Result<T, DocumentError> {
        ron::Options::default()
            .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
            .from_str(self.text)
            .map_err(|e| {
                DocumentError::one(
                    self.name,
                    ErrorKind::Syntax,
                    (e.span.start.line, e.span.start.col),
                    without_type_names(&e.code.to_string()),
                )
            })
    }

    /// The line and column of the value at `path` (of the deepest step found); (0, 0) when there
    /// is no text (a document made in memory).
    pub fn locate(&self, path: &[Step]) -> (usize, usize) {
        if self.text.is_empty() {
            (0, 0)
        } else {
            locate(self.text, path)
        }
    }

    /// A problem with the value at `path`.
    pub fn problem(&self, path: &[Step], message: impl Into<String>) -> Problem {
        Problem::at(self.locate(path), message)
    }

    /// One problem of `kind` with the value at `path`, as an error.
    pub fn error(
        &self,
        kind: ErrorKind,
        path: &[Step],
        message: impl Into<String>,
    ) -> DocumentError {
        DocumentError::one(self.name, kind, self.locate(path), message)
    }

    /// `problems` of `kind`, as an error; `Ok` when there are none.
    pub fn check(&self, kind: ErrorKind, problems: Vec<Problem>) -> Result<(), DocumentError> {
        if problems.is_empty() {
            Ok(())
        } else {
            Err(DocumentError {
                file: self.name.to_string(),
                kind,
                problems,
            })
        }
    }
}

/// Reads the document at `path` (a `limit.what`, at most `limit.max` bytes, a regular file:
/// [`read_text`]) and parses it with `parse`, which is given the name errors use (the path) and
/// the text. An empty file is refused as such. A relative path that is not in the working folder
/// but is among the shipped examples (`presets/window-cleaner-selftest.ron` on an installed
/// machine) is read from there ([`crate::system::shipped_or_given`]), and errors name the file
/// read.
pub fn load<T>(
    path: &Path,
    limit: Limit,
    parse: impl FnOnce(&str, &str) -> Result<T, DocumentError>,
) -> Result<T, DocumentError> {
    let path = &crate::system::shipped_or_given(path);
    let text = read_text(path, limit)?;
    let name = path.display().to_string();
    if text.trim().is_empty() {
        return Err(DocumentError::one(
            &name,
            ErrorKind::Syntax,
            (0, 0),
            format!("the file is empty: it holds no {}", limit.what),
        ));
    }
    parse(&name, &text)
}

/// A RON error's words without the names of botbench's own types (`in \`Doc\``), which mean
/// nothing to the person who wrote the file: "Unexpected field named `version` in `Doc`,
/// expected one of ..." becomes "Unexpected field named `version`, expected one of ...".
fn without_type_names(message: &str) -> String {
    let mut out = String::with_capacity(message.len());
    let mut rest = message;
    while let Some(at) = rest.find(" in `Doc") {
        out.push_str(&rest[..at]);
        let after = &rest[at + " in `".len()..];
        match after.find('`') {
            Some(end) => rest = &after[end + 1..],
            None => {
                rest = "";
            }
        }
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ron_error_names_no_type_of_botbench() {
        assert_eq!(
            without_type_names(
                "Unexpected field named `version` in `Doc`, expected one of `ids` or `record` instead"
            ),
            "Unexpected field named `version`, expected one of `ids` or `record` instead"
        );
        assert_eq!(
            without_type_names("Unexpected field `x` in `DocStep` in `Doc`"),
            "Unexpected field `x`"
        );
        assert_eq!(
            without_type_names("Expected closing `)`"),
            "Expected closing `)`"
        );
    }

    #[test]
    fn an_atomic_write_replaces_the_file_and_leaves_nothing_behind() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("doc.ron");
        write_atomic(&path, b"one").unwrap();
        write_atomic(&path, b"two").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "two");
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, ["doc.ron"]);
        // A folder that does not exist: an Io error naming the file, nothing written.
        let e = write_atomic(&dir.path().join("no/such/x.ron"), b"x").unwrap_err();
        assert_eq!(e.kind, ErrorKind::Io);
        assert!(e.to_string().contains("x.ron"), "{e}");
    }

    #[test]
    fn errors_show_their_place() {
        let src = Source::new("t.ron", "(\n  a: 1,\n  b: [2, 3],\n)");
        let e = src.error(ErrorKind::Value, &[Step::Key("b"), Step::Index(1)], "bad");
        assert_eq!(e.to_string(), "t.ron:3:10: bad");
        assert_eq!(e.at(), (3, 10));
        let e = DocumentError {
            file: "t.ron".into(),
            kind: ErrorKind::Value,
            problems: vec![Problem::at((0, 0), "one"), Problem::at((2, 3), "two")],
        };
        assert_eq!(
            e.to_string(),
            "t.ron: 2 problems:\n  t.ron: one\n  t.ron:2:3: two"
        );
        #[derive(serde::Deserialize, Debug)]
        #[serde(deny_unknown_fields)]
        #[allow(dead_code)]
        struct Doc {
            a: u8,
        }
        let e = src.parse::<Doc>().unwrap_err();
        assert_eq!(e.kind, ErrorKind::Syntax);
        assert_eq!(e.at().0, 3, "{e}");
    }
}
