//! Presets: a device's tunable parameters as a versioned RON document: its schema, its check
//! against a profile, its comparison with a device's values, and its text. Capturing one from a
//! device and applying one (with read-back verification) are operations:
//! ops' `preset.rs`.
//!
//! A preset names each Set command by its canonical ident and gives every field of it as display
//! text ("2.75", not 275; labels such as `on`), so that a technician can read and edit it. The
//! text is read back with [`Field::parse`], which refuses out-of-range values and values between
//! steps; a preset is checked in full against the profile before anything is written.
//!
//! ```ron
//! (
//!     version: 1,
//!     profile: "window-cleaner",
//!     note: "Line 3 tuning",
//!     created: "2025-06-01T10:00:00+08:00",
//!     device: Some("hw 0x03 fw 1.4.2"),
//!     values: {
//!         "MSP_SET_PWMVALUE": {
//!             "pwmValue": "85",
//!         },
//!     },
//! )
//! ```

use crate::document::{self, DocumentError, ErrorKind, Problem, Source, Step};
use crate::profile::{Command, CommandKind, Field, FieldType, Input, Profile, Value};
use crate::protocol::Direction;
use shape::{Doc, Head};
use std::path::Path;

mod shape;

/// The newest preset format this build reads and writes.
pub const VERSION: u32 = 1;

/// A preset document.
#[derive(Debug, Clone, PartialEq)]
pub struct Preset {
    /// The format version ([`VERSION`]).
    pub version: u32,
    /// The profile id it is for, e.g. `window-cleaner`.
    pub profile: String,
    /// Free text: what it is for, who made it.
    pub note: String,
    /// When it was made (RFC 3339).
    pub created: String,
    /// The device it was captured from, e.g. `hw 0x03 fw 1.4.2`.
    pub device: Option<String>,
    /// The values, per Set command, in profile order.
    pub values: Vec<CommandValues>,
}

/// The values of one Set command.
#[derive(Debug, Clone, PartialEq)]
pub struct CommandValues {
    /// The Set command's canonical ident, e.g. `MSP_SET_PWMVALUE`.
    pub command: String,
    /// (field ident, display value), in wire order.
    pub fields: Vec<(String, String)>,
}

impl CommandValues {
    /// A field's display value, by ident (case-insensitive).
    pub fn get(&self, field: &str) -> Option<&str> {
        self.fields
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(field))
            .map(|(_, v)| v.as_str())
    }
}

/// One Set command of a checked preset, ready for a verified write (ops' `write_verified`).
#[derive(Debug, Clone, PartialEq)]
pub struct SetWrite {
    /// The Set command's canonical ident.
    pub command: String,
    /// Every field of the command, parsed and checked (raw values).
    pub inputs: Vec<(String, Input)>,
}

/// A preset read from a file and checked against a profile.
#[derive(Debug, Clone, PartialEq)]
pub struct Loaded {
    /// The document.
    pub preset: Preset,
    /// What applying it writes, per Set command.
    pub writes: Vec<SetWrite>,
}

/// A field of the preset compared with the device.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct DiffRow {
    /// The Set command's ident.
    pub command: String,
    /// The field's ident.
    pub field: String,
    /// The preset's value, as displayed.
    pub preset: String,
    /// The device's value, as displayed; `None` if it was not read.
    pub device: Option<String>,
    /// Whether they differ (or the device's is unknown).
    pub differs: bool,
}

/// The Set commands a preset can hold, with their Gets: a Set whose Get the profile marks
/// `tunable` (the robot's tuning, the same on every unit; a unit's own state such as its
/// auto-test result is never copied between units), takes no arguments, and whose fields are
/// plain values (not servo parameter blocks or Tuya data points). Capture, diff, apply and the
/// command line all take this list.
pub fn preset_commands(profile: &Profile) -> Vec<(&Command, &Command)> {
    profile
        .commands
        .iter()
        .filter(|set| set.kind == CommandKind::Set)
        .filter_map(|set| {
            let get = profile.command_by_id(set.pair?)?;
            let plain = get.kind == CommandKind::Get
                && get.tunable
                && get.request.is_empty()
                && !set.request.is_empty()
                && set.request.iter().all(|f| is_plain(f.ty));
            plain.then_some((set, get))
        })
        .collect()
}

fn is_plain(ty: FieldType) -> bool {
    !matches!(
        ty,
        FieldType::ParamId | FieldType::ParamValue | FieldType::ParamBlock | FieldType::DataPoints
    )
}

/// A value as a preset stores it: [`Field::format`], which [`Field::parse`] reads back, except
/// for bit fields, which are stored as raw hex.
pub fn display_value(field: &Field, value: &Value) -> String {
    match value {
        Value::Int(raw) if !field.bits.is_empty() && field.label(*raw).is_none() => {
            format!("{raw:#x}")
        }
        _ => field.format(value),
    }
}

impl Preset {
    /// An empty preset for `profile`, created now.
    pub fn new(profile: &str, note: &str) -> Self {
        Self {
            version: VERSION,
            profile: profile.to_string(),
            note: note.to_string(),
            created: now(),
            device: None,
            values: Vec::new(),
        }
    }

    /// The preset of a profile's field defaults, for the commands whose every field has one.
    pub fn defaults(profile: &Profile, note: &str) -> Self {
        let mut p = Self::new(&profile.id, note);
        for (set, _) in preset_commands(profile) {
            let fields: Option<Vec<(String, String)>> = set
                .request
                .iter()
                .map(|f| {
                    f.default
                        .map(|raw| (f.ident.clone(), display_value(f, &Value::Int(raw))))
                })
                .collect();
            if let Some(fields) = fields {
                p.values.push(CommandValues {
                    command: set.ident.clone(),
                    fields,
                });
            }
        }
        p
    }

    /// Reads a preset file and checks it against `profile`.
    pub fn load(path: &Path, profile: &Profile) -> Result<Loaded, DocumentError> {
        document::load(path, document::Limit::PRESET, |name, text| {
            Self::parse(name, text, profile)
        })
    }

    /// Parses preset text (`name` names it in errors) and checks it against `profile`.
    pub fn parse(name: &str, text: &str, profile: &Profile) -> Result<Loaded, DocumentError> {
        let preset = Self::parse_unchecked(name, text)?;
        let writes = preset.check(profile, &Source::new(name, text))?;
        Ok(Loaded { preset, writes })
    }

    /// Parses preset text, checking its syntax and version only.
    pub fn parse_unchecked(name: &str, text: &str) -> Result<Preset, DocumentError> {
        let src = Source::new(name, text);
        // `device: "..."` and `device: Some("...")` both read.
        let doc: Doc = match src.parse() {
            Ok(doc) => doc,
            Err(e) => {
                // A newer format may not parse; say so rather than show its syntax error.
                if let Ok(Head { version: Some(v) }) = src.parse::<Head>()
                    && v > VERSION
                {
                    return Err(newer(&src, v));
                }
                return Err(e);
            }
        };
        match doc.version {
            None => {
                return Err(DocumentError::one(
                    name,
                    ErrorKind::Version,
                    (1, 1),
                    format!("no `version`: a preset starts with `version: {VERSION},`"),
                ));
            }
            Some(v) if v > VERSION => return Err(newer(&src, v)),
            Some(0) => {
                return Err(src.error(
                    ErrorKind::Version,
                    &[Step::Key("version")],
                    format!(
                        "version 0 is not a preset version; this botbench reads version {VERSION}"
                    ),
                ));
            }
            Some(_) => {}
        }
        Ok(Preset {
            version: doc.version.unwrap_or(VERSION),
            profile: doc.profile,
            note: doc.note,
            created: doc.created,
            device: doc.device,
            values: doc.values.0,
        })
    }

    /// Checks the preset against `profile`: the profile id, every command and field, every value.
    /// Returns what applying it writes.
    pub fn validate(&self, profile: &Profile) -> Result<Vec<SetWrite>, DocumentError> {
        self.check(profile, &Source::new("preset", ""))
    }

    /// [`Preset::validate`], placing each problem in `src`, the text the preset was read from.
    fn check(&self, profile: &Profile, src: &Source) -> Result<Vec<SetWrite>, DocumentError> {
        if self.profile != profile.id {
            let preset = if self.profile.is_empty() {
                "no profile (`profile` is empty)"
            } else {
                &self.profile
            };
            return Err(src.error(
                ErrorKind::Profile,
                &[Step::Key("profile")],
                format!(
                    "this preset is for {preset}; the connected device uses {}",
                    profile.id
                ),
            ));
        }
        let allowed = preset_commands(profile);
        let mut problems = Vec::new();
        let mut writes = Vec::new();
        let mut seen: Vec<&str> = Vec::new();
        for cv in &self.values {
            let at_cmd = src.locate(&[Step::Key("values"), Step::Entry(cv.command.clone())]);
            let set = match presettable(profile, &allowed, &cv.command) {
                Ok(set) => set,
                Err(message) => {
                    problems.push(Problem::at(at_cmd, message));
                    continue;
                }
            };
            if seen.contains(&set.ident.as_str()) {
                problems.push(Problem::at(at_cmd, format!("{} is given twice", set.ident)));
                continue;
            }
            seen.push(&set.ident);
            match set_write(profile, set, cv, src) {
                Ok(write) => writes.push(write),
                Err(found) => problems.extend(found),
            }
        }
        if self.values.is_empty() {
            problems.push(src.problem(
                &[Step::Key("values")],
                format!(
                    "the preset holds no values; it can hold {}",
                    list(allowed.iter().map(|(s, _)| s.ident.as_str()))
                ),
            ));
        }
        src.check(ErrorKind::Value, problems)?;
        Ok(writes)
    }

    /// Compares the preset with values read from the device (e.g. by ops' `preset::capture` or
    /// `preset::read_device`). Values are compared as raw values, so "2.8" equals "2.80".
    pub fn diff(&self, profile: &Profile, device: &[CommandValues]) -> Vec<DiffRow> {
        let mut rows = Vec::new();
        for cv in &self.values {
            let set = profile
                .commands
                .iter()
                .find(|c| c.ident.eq_ignore_ascii_case(&cv.command));
            let from_device = device
                .iter()
                .find(|d| d.command.eq_ignore_ascii_case(&cv.command));
            for (key, mine) in &cv.fields {
                let field =
                    set.and_then(|s| s.request.iter().find(|f| f.ident.eq_ignore_ascii_case(key)));
                let theirs = from_device.and_then(|d| d.get(key)).map(str::to_string);
                let differs = match (&theirs, field) {
                    (None, _) => true,
                    (Some(t), Some(f)) => match (f.parse(mine), f.parse(t)) {
                        (Ok(a), Ok(b)) => a != b,
                        _ => mine.trim() != t.trim(),
                    },
                    (Some(t), None) => mine.trim() != t.trim(),
                };
                rows.push(DiffRow {
                    command: set.map_or_else(|| cv.command.clone(), |s| s.ident.clone()),
                    field: field.map_or_else(|| key.clone(), |f| f.ident.clone()),
                    preset: mine.clone(),
                    device: theirs,
                    differs,
                });
            }
        }
        rows
    }

    /// The preset as RON text with a header comment; with `profile`, each field carries a
    /// comment with its name, unit and allowed values.
    pub fn to_ron(&self, profile: Option<&Profile>) -> String {
        let q = |s: &str| ron::to_string(s).unwrap_or_else(|_| format!("{s:?}"));
        let mut out = String::new();
        out.push_str(&format!(
            "// botbench preset for {}.\n\
             // Values are as displayed (\"2.75\", not 275; labels such as \"on\"). Edit them by hand\n\
             // if you like: every field of a command must stay, since its Set sends them all, and\n\
             // each value is checked against the profile before anything is written.\n\
             // Compare: botbench preset diff FILE --port PORT\n\
             // Write:   botbench preset apply FILE --port PORT\n",
            self.profile
        ));
        out.push_str("(\n");
        out.push_str(&format!("    version: {},\n", self.version));
        out.push_str(&format!("    profile: {},\n", q(&self.profile)));
        out.push_str(&format!("    note: {},\n", q(&self.note)));
        out.push_str(&format!("    created: {},\n", q(&self.created)));
        match &self.device {
            Some(d) => out.push_str(&format!("    device: Some({}),\n", q(d))),
            None => out.push_str("    device: None,\n"),
        }
        out.push_str("    values: {\n");
        for cv in &self.values {
            let set = profile.and_then(|p| p.command(&cv.command));
            if let Some(set) = set {
                out.push_str(&format!("        // {}\n", set.name.en));
            }
            out.push_str(&format!("        {}: {{\n", q(&cv.command)));
            for (k, v) in &cv.fields {
                let field =
                    set.and_then(|s| s.request.iter().find(|f| f.ident.eq_ignore_ascii_case(k)));
                let note = field.map(describe_field).unwrap_or_default();
                let line = format!("            {}: {},", q(k), q(v));
                if note.is_empty() {
                    out.push_str(&format!("{line}\n"));
                } else {
                    out.push_str(&format!("{line:<48} // {note}\n"));
                }
            }
            out.push_str("        },\n");
        }
        out.push_str("    },\n)\n");
        out
    }

    /// Writes the preset (plain, without field comments), atomically.
    pub fn save(&self, path: &Path) -> Result<(), DocumentError> {
        document::write_atomic(path, self.to_ron(None).as_bytes())
    }

    /// Writes the preset with field comments from `profile`, atomically.
    pub fn save_annotated(&self, path: &Path, profile: &Profile) -> Result<(), DocumentError> {
        document::write_atomic(path, self.to_ron(Some(profile)).as_bytes())
    }
}

fn describe_field(f: &Field) -> String {
    let labels = list(f.labels.iter().map(|l| l.ident.as_str()));
    let range = f
        .range
        .or_else(|| f.ty.int_bounds().filter(|_| f.labels.is_empty()));
    let mut allowed = match range {
        Some((lo, hi)) => format!(
            "{} to {}{}",
            f.format_number(lo),
            f.format_number(hi),
            f.unit_suffix()
        ),
        None => String::new(),
    };
    if !f.labels.is_empty() {
        allowed = if allowed.is_empty() {
            labels
        } else {
            format!("{labels}, or {allowed}")
        };
    }
    if f.scale != 1.0 {
        allowed.push_str(&format!(", step {}", f.format_number(1)));
    }
    if allowed.is_empty() {
        f.name.en.clone()
    } else {
        format!("{}: {allowed}", f.name.en)
    }
}

fn list<'a>(items: impl Iterator<Item = &'a str>) -> String {
    let v: Vec<&str> = items.collect();
    if v.is_empty() {
        "nothing".into()
    } else {
        v.join(", ")
    }
}

fn now() -> String {
    chrono::Local::now().to_rfc3339_opts(chrono::SecondsFormat::Secs, false)
}

fn newer(src: &Source, v: u32) -> DocumentError {
    src.error(
        ErrorKind::Version,
        &[Step::Key("version")],
        format!(
            "preset version {v} is newer than this botbench reads (version {VERSION}); update botbench"
        ),
    )
}

/// The Set command named `name` (any case) when a preset can hold it: one of `allowed` (a Set
/// with a Get to read it back); else what is wrong, said as a person would fix it.
fn presettable<'p>(
    profile: &'p Profile,
    allowed: &[(&'p Command, &'p Command)],
    name: &str,
) -> Result<&'p Command, String> {
    let Some(cmd) = profile
        .commands
        .iter()
        .find(|c| c.ident.eq_ignore_ascii_case(name))
    else {
        return Err(format!(
            "{} has no command '{name}'; a preset can hold {}",
            profile.id,
            list(allowed.iter().map(|(s, _)| s.ident.as_str()))
        ));
    };
    if let Some(&(set, _)) = allowed.iter().find(|(s, _)| s.id == cmd.id) {
        return Ok(set);
    }
    let get = match cmd.kind {
        CommandKind::Set => cmd.pair.and_then(|p| profile.command_by_id(p)),
        _ => Some(cmd),
    };
    if get.is_some_and(|g| g.kind == CommandKind::Get && !g.tunable) {
        return Err(format!(
            "{} is not tunable: it holds the unit's own state, which a preset \
             never copies from one unit to the next; delete this entry",
            cmd.ident
        ));
    }
    let partner = cmd
        .pair
        .and_then(|p| profile.command_by_id(p))
        .filter(|p| p.kind == CommandKind::Set && cmd.kind == CommandKind::Get);
    let hint = match partner {
        Some(set) => format!("; name its Set, {}", set.ident),
        None => String::new(),
    };
    Err(format!(
        "{} is not a Set command with a Get to read it back, so a preset cannot hold it{hint}",
        cmd.ident
    ))
}

/// What applying `cv` writes with `set`: every field given once, each value parsed by its field,
/// none missing, in wire order, and the whole within the profile's relations; else every
/// problem found, placed in `src`.
fn set_write(
    profile: &Profile,
    set: &Command,
    cv: &CommandValues,
    src: &Source,
) -> Result<SetWrite, Vec<Problem>> {
    let at_cmd = src.locate(&[Step::Key("values"), Step::Entry(cv.command.clone())]);
    let (mut inputs, mut problems) = field_inputs(set, cv, src);
    let missing: Vec<&str> = set
        .request
        .iter()
        .filter(|f| {
            !f.optional
                && !cv
                    .fields
                    .iter()
                    .any(|(k, _)| k.eq_ignore_ascii_case(&f.ident))
        })
        .map(|f| f.ident.as_str())
        .collect();
    if !missing.is_empty() {
        problems.push(Problem::at(
            at_cmd,
            format!(
                "{}: missing {}; a preset gives every field of a command, since its Set sends them all",
                set.ident,
                list(missing.iter().copied())
            ),
        ));
    }
    if !problems.is_empty() {
        return Err(problems);
    }
    // In wire order, whatever the file's order.
    inputs.sort_by_key(|(k, _)| set.request.iter().position(|f| &f.ident == k));
    // The profile's relations (a minimum above its maximum), named at load.
    if let Err(e) = profile.encode(set, Direction::HostToDevice, &inputs) {
        return Err(vec![Problem::at(at_cmd, format!("{}: {e}", set.ident))]);
    }
    Ok(SetWrite {
        command: set.ident.clone(),
        inputs,
    })
}

/// The fields of `cv` parsed by `set`'s request fields, and a problem for each one unknown,
/// given twice or out of its range.
fn field_inputs(
    set: &Command,
    cv: &CommandValues,
    src: &Source,
) -> (Vec<(String, Input)>, Vec<Problem>) {
    let mut inputs: Vec<(String, Input)> = Vec::new();
    let mut problems = Vec::new();
    for (key, text_value) in &cv.fields {
        let at = src.locate(&[
            Step::Key("values"),
            Step::Entry(cv.command.clone()),
            Step::Entry(key.clone()),
        ]);
        let Some(field) = set
            .request
            .iter()
            .find(|f| f.ident.eq_ignore_ascii_case(key))
        else {
            let fields = list(set.request.iter().map(|f| f.ident.as_str()));
            let message = format!("{} has no field '{key}'; its fields: {fields}", set.ident);
            problems.push(Problem::at(at, message));
            continue;
        };
        if inputs.iter().any(|(k, _)| k == &field.ident) {
            let message = format!("{}: field '{}' is given twice", set.ident, field.ident);
            problems.push(Problem::at(at, message));
            continue;
        }
        // FieldError's messages name the field, the value and what is allowed.
        match field.parse(text_value) {
            Ok(v) => inputs.push((field.ident.clone(), Input::Raw(v))),
            Err(e) => problems.push(Problem::at(at, format!("{}: {e}", set.ident))),
        }
    }
    (inputs, problems)
}
