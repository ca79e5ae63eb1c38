//! Presets: a device's tunable parameters saved to a versioned RON file, compared with a device,
//! and written back with read-back verification.
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

use crate::link::{Client, DeviceInfo};
use crate::ops::msp::{self as ops, Check, OpError};
use crate::ops::{Cancel, Progress};
use crate::profile::locate::line_col;
use crate::profile::value::Typed as Text;
use crate::profile::{Command, CommandKind, Field, FieldType, Input, Profile, Value};
use crate::protocol::{Direction, msp};
use serde::Deserialize;
use serde::de::{self, Deserializer, MapAccess, Visitor};
use std::fmt;
use std::path::Path;

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

/// One Set command of a checked preset, ready for [`ops::write_verified`].
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

/// What kind of problem a preset has.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorKind {
    /// The file cannot be read or written.
    Io,
    /// Not valid preset RON.
    Syntax,
    /// No version, or a newer one than this build reads.
    Version,
    /// Made for another profile.
    Profile,
    /// An unknown command or field, a missing field, or a value the field refuses.
    Value,
}

pub use crate::profile::locate::Problem;

/// Why a preset cannot be used. Nothing has been written when this is returned.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PresetError {
    /// The file (or the name given to [`Preset::parse`]).
    pub file: String,
    /// What kind of problem (of the first, when there are several).
    pub kind: ErrorKind,
    /// The problems, at least one.
    pub problems: Vec<Problem>,
}

impl PresetError {
    fn one(file: &str, kind: ErrorKind, (line, col): (usize, usize), message: String) -> Self {
        Self {
            file: file.to_string(),
            kind,
            problems: vec![Problem { line, col, message }],
        }
    }

    /// The first problem's message.
    pub fn message(&self) -> &str {
        self.problems.first().map_or("", |p| p.message.as_str())
    }
}

impl fmt::Display for PresetError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        crate::profile::locate::write_problems(f, &self.file, &self.problems)
    }
}

impl std::error::Error for PresetError {}

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

/// The Set commands a preset can hold: a Set whose Get takes no arguments and whose fields are
/// plain values (not servo parameter blocks or Tuya data points), with its Get.
pub fn preset_commands(profile: &Profile) -> Vec<(&Command, &Command)> {
    profile
        .commands
        .iter()
        .filter(|set| set.kind == CommandKind::Set)
        .filter_map(|set| {
            let get = profile.command_by_id(set.pair?)?;
            let plain = get.kind == CommandKind::Get
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

/// "hw 0x03 fw 1.4.2"
pub fn describe_device(info: &DeviceInfo) -> String {
    format!("hw {:#04x} fw {}", info.hw, info.firmware)
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
    pub fn load(path: &Path, profile: &Profile) -> Result<Loaded, PresetError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| {
            PresetError::one(&file, ErrorKind::Io, (0, 0), format!("cannot read: {e}"))
        })?;
        Self::parse(&file, &text, profile)
    }

    /// Parses preset text (`name` names it in errors) and checks it against `profile`.
    pub fn parse(name: &str, text: &str, profile: &Profile) -> Result<Loaded, PresetError> {
        let preset = Self::parse_unchecked(name, text)?;
        let writes = preset.check(profile, name, Some(text))?;
        Ok(Loaded { preset, writes })
    }

    /// Parses preset text, checking its syntax and version only.
    pub fn parse_unchecked(name: &str, text: &str) -> Result<Preset, PresetError> {
        // `device: "..."` and `device: Some("...")` both read.
        let options = ron::Options::default()
            .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
        let doc: Doc = match options.from_str(text) {
            Ok(doc) => doc,
            Err(e) => {
                // A newer format may not parse; say so rather than show its syntax error.
                if let Ok(Head {
                    version: Some(v), ..
                }) = options.from_str::<Head>(text)
                    && v > VERSION
                {
                    return Err(newer(name, text, v));
                }
                return Err(PresetError::one(
                    name,
                    ErrorKind::Syntax,
                    (e.span.start.line, e.span.start.col),
                    e.code.to_string(),
                ));
            }
        };
        match doc.version {
            None => {
                return Err(PresetError::one(
                    name,
                    ErrorKind::Version,
                    (1, 1),
                    format!("no `version`: a preset starts with `version: {VERSION},`"),
                ));
            }
            Some(v) if v > VERSION => return Err(newer(name, text, v)),
            Some(0) => {
                return Err(PresetError::one(
                    name,
                    ErrorKind::Version,
                    find_key(text, "version"),
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
    pub fn validate(&self, profile: &Profile) -> Result<Vec<SetWrite>, PresetError> {
        self.check(profile, "preset", None)
    }

    fn check(
        &self,
        profile: &Profile,
        name: &str,
        text: Option<&str>,
    ) -> Result<Vec<SetWrite>, PresetError> {
        let text = text.unwrap_or("");
        if self.profile != profile.id {
            return Err(PresetError::one(
                name,
                ErrorKind::Profile,
                find_key(text, "profile"),
                format!(
                    "this preset is for {}; the connected device uses {}",
                    if self.profile.is_empty() {
                        "no profile (`profile` is empty)"
                    } else {
                        &self.profile
                    },
                    profile.id
                ),
            ));
        }
        let allowed = preset_commands(profile);
        let mut problems = Vec::new();
        let mut writes = Vec::new();
        let mut seen: Vec<&str> = Vec::new();
        for cv in &self.values {
            let at_cmd = find_entry(text, &cv.command, None);
            let mut problem = |at: (usize, usize), message: String| {
                problems.push(Problem {
                    line: at.0,
                    col: at.1,
                    message,
                })
            };
            let Some(cmd) = profile
                .commands
                .iter()
                .find(|c| c.ident.eq_ignore_ascii_case(&cv.command))
            else {
                problem(
                    at_cmd,
                    format!(
                        "{} has no command '{}'; a preset can hold {}",
                        profile.id,
                        cv.command,
                        list(allowed.iter().map(|(s, _)| s.ident.as_str()))
                    ),
                );
                continue;
            };
            let Some(&(set, _)) = allowed.iter().find(|(s, _)| s.id == cmd.id) else {
                let partner = cmd
                    .pair
                    .and_then(|p| profile.command_by_id(p))
                    .filter(|p| p.kind == CommandKind::Set && cmd.kind == CommandKind::Get);
                let hint = match partner {
                    Some(set) => format!("; name its Set, {}", set.ident),
                    None => String::new(),
                };
                problem(
                    at_cmd,
                    format!(
                        "{} is not a Set command with a Get to read it back, so a preset cannot hold it{hint}",
                        cmd.ident
                    ),
                );
                continue;
            };
            if seen.contains(&set.ident.as_str()) {
                problem(at_cmd, format!("{} is given twice", set.ident));
                continue;
            }
            seen.push(&set.ident);
            let mut inputs = Vec::new();
            let mut ok = true;
            for (key, text_value) in &cv.fields {
                let at = find_entry(text, &cv.command, Some(key));
                let Some(field) = set
                    .request
                    .iter()
                    .find(|f| f.ident.eq_ignore_ascii_case(key))
                else {
                    ok = false;
                    problem(
                        at,
                        format!(
                            "{} has no field '{key}'; its fields: {}",
                            set.ident,
                            list(set.request.iter().map(|f| f.ident.as_str()))
                        ),
                    );
                    continue;
                };
                if inputs
                    .iter()
                    .any(|(k, _): &(String, Input)| k == &field.ident)
                {
                    ok = false;
                    problem(
                        at,
                        format!("{}: field '{}' is given twice", set.ident, field.ident),
                    );
                    continue;
                }
                // FieldError's messages name the field, the value and what is allowed.
                match field.parse(text_value) {
                    Ok(v) => inputs.push((field.ident.clone(), Input::Raw(v))),
                    Err(e) => {
                        ok = false;
                        problem(at, format!("{}: {e}", set.ident));
                    }
                }
            }
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
                ok = false;
                problem(
                    at_cmd,
                    format!(
                        "{}: missing {}; a preset gives every field of a command, since its Set sends them all",
                        set.ident,
                        list(missing.iter().copied())
                    ),
                );
            }
            if ok {
                // In wire order, whatever the file's order.
                inputs.sort_by_key(|(k, _)| set.request.iter().position(|f| &f.ident == k));
                // The profile's relations (a minimum above its maximum), named at load.
                if let Err(e) = profile.encode(set, Direction::HostToDevice, &inputs) {
                    problem(at_cmd, format!("{}: {e}", set.ident));
                    continue;
                }
                writes.push(SetWrite {
                    command: set.ident.clone(),
                    inputs,
                });
            }
        }
        if self.values.is_empty() {
            problems.push(Problem {
                line: find_key(text, "values").0,
                col: find_key(text, "values").1,
                message: format!(
                    "the preset holds no values; it can hold {}",
                    list(allowed.iter().map(|(s, _)| s.ident.as_str()))
                ),
            });
        }
        if problems.is_empty() {
            Ok(writes)
        } else {
            Err(PresetError {
                file: name.to_string(),
                kind: ErrorKind::Value,
                problems,
            })
        }
    }

    /// Reads every Get command that has a Set partner and returns the values as a preset, keyed
    /// by the Set's ident. The device's identity is asked with CMD_VERSION where the profile has
    /// it (MSP).
    pub fn capture(
        client: &Client,
        profile: &Profile,
        cancel: &Cancel,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<Preset, OpError> {
        let mut preset = Preset::new(&profile.id, "");
        preset.device = device_description(client, profile);
        let values = read_device(client, profile, cancel, progress)?;
        preset.values = values;
        Ok(preset)
    }

    /// Compares the preset with values read from the device (e.g. [`Preset::capture`]'s or
    /// [`read_device`]'s). Values are compared as raw values, so "2.8" equals "2.80".
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

    /// Checks the preset, then writes each Set command's full payload with
    /// [`ops::write_verified`], reporting progress per command. Returns every read-back check;
    /// a mismatch is a check that is not `ok()`, not an error. When cancelled it stops between
    /// commands and returns the checks of what was written.
    pub fn apply(
        &self,
        client: &Client,
        profile: &Profile,
        cancel: &Cancel,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<Vec<Check>, OpError> {
        let mut all = Vec::new();
        self.apply_each(client, profile, cancel, progress, &mut |_, checks| {
            all.extend_from_slice(checks)
        })?;
        Ok(all)
    }

    /// [`Preset::apply`], telling `written` each command's checks as it is written. Progress is
    /// reported before the first command and after each; a cancel raised then stops before the
    /// next command.
    pub fn apply_each(
        &self,
        client: &Client,
        profile: &Profile,
        cancel: &Cancel,
        progress: &mut dyn FnMut(Progress),
        written: &mut dyn FnMut(&str, &[Check]),
    ) -> Result<(), OpError> {
        let writes = self
            .validate(profile)
            .map_err(|e| OpError::Input(e.to_string()))?;
        let total = writes.len() as u64;
        progress(Progress {
            done: 0,
            total,
            message: "checked; writing".into(),
        });
        for (i, w) in writes.iter().enumerate() {
            if cancel.is_cancelled() {
                break;
            }
            let set = profile.command(&w.command).ok_or_else(|| {
                OpError::Input(format!("{} has no command '{}'", profile.id, w.command))
            })?;
            let checks = ops::write_verified(client, profile, set, &w.inputs)?;
            written(&set.ident, &checks);
            progress(Progress {
                done: i as u64 + 1,
                total,
                message: format!("wrote {}", set.ident),
            });
        }
        Ok(())
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
    pub fn save(&self, path: &Path) -> Result<(), PresetError> {
        write_atomic(path, &self.to_ron(None))
    }

    /// Writes the preset with field comments from `profile`, atomically.
    pub fn save_annotated(&self, path: &Path, profile: &Profile) -> Result<(), PresetError> {
        write_atomic(path, &self.to_ron(Some(profile)))
    }
}

/// Reads every presettable Get of the profile, as display values keyed by the Set's ident.
pub fn read_device(
    client: &Client,
    profile: &Profile,
    cancel: &Cancel,
    progress: &mut dyn FnMut(Progress),
) -> Result<Vec<CommandValues>, OpError> {
    let pairs = preset_commands(profile);
    let total = pairs.len() as u64;
    let mut values = Vec::new();
    for (i, (set, get)) in pairs.iter().enumerate() {
        if cancel.is_cancelled() {
            return Err(OpError::Cancelled);
        }
        let read = ops::read(client, profile, get, &[])?;
        let fields = set
            .request
            .iter()
            .filter_map(|f| {
                read.iter()
                    .find(|(k, _)| k.eq_ignore_ascii_case(&f.ident))
                    .map(|(_, v)| (f.ident.clone(), display_value(f, v)))
            })
            .collect();
        values.push(CommandValues {
            command: set.ident.clone(),
            fields,
        });
        progress(Progress {
            done: i as u64 + 1,
            total,
            message: format!("read {}", get.ident),
        });
    }
    Ok(values)
}

fn device_description(client: &Client, profile: &Profile) -> Option<String> {
    if profile.protocol != crate::profile::Protocol::Msp {
        return None;
    }
    let cmd = profile.command_by_id(msp::CMD_VERSION)?;
    let reply = ops::send(client, profile, cmd, &[]).ok()?;
    let info = DeviceInfo::from_version(profile, reply.payload().unwrap_or_default()).ok()?;
    Some(describe_device(&info))
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

fn newer(name: &str, text: &str, v: u32) -> PresetError {
    PresetError::one(
        name,
        ErrorKind::Version,
        find_key(text, "version"),
        format!(
            "preset version {v} is newer than this botbench reads (version {VERSION}); update botbench"
        ),
    )
}

/// Writes `text` to a temporary file beside `path`, then renames it over `path`.
fn write_atomic(path: &Path, text: &str) -> Result<(), PresetError> {
    use std::io::Write;
    let file = path.display().to_string();
    let io = |what: &str, e: std::io::Error| {
        PresetError::one(&file, ErrorKind::Io, (0, 0), format!("cannot {what}: {e}"))
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    let stem = path
        .file_name()
        .map_or_else(|| "preset".into(), |n| n.to_string_lossy().into_owned());
    let tmp = dir.join(format!(".{stem}.{}.tmp", std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp).map_err(|e| io("create a temporary file", e))?;
        f.write_all(text.as_bytes())
            .and_then(|()| f.sync_all())
            .map_err(|e| io("write", e))?;
        drop(f);
        std::fs::rename(&tmp, path).map_err(|e| io("replace the file", e))
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// The line and column of a top-level `key:` outside comments, or (1, 1).
fn find_key(text: &str, key: &str) -> (usize, usize) {
    find_outside_comments(text, key, 0, |rest| rest.trim_start().starts_with(':'))
        .map_or((1, 1), |pos| line_col(text, pos))
}

/// Where a command's key (and, given `field`, that field's key after it) sits in the text.
fn find_entry(text: &str, command: &str, field: Option<&str>) -> (usize, usize) {
    let quoted = |s: &str| ron::to_string(s).unwrap_or_else(|_| format!("\"{s}\""));
    let Some(cmd_at) = find_outside_comments(text, &quoted(command), 0, |_| true) else {
        return (0, 0);
    };
    let pos = match field {
        Some(f) => find_outside_comments(text, &quoted(f), cmd_at, |_| true).unwrap_or(cmd_at),
        None => cmd_at,
    };
    line_col(text, pos)
}

fn find_outside_comments(
    text: &str,
    needle: &str,
    from: usize,
    followed: impl Fn(&str) -> bool,
) -> Option<usize> {
    let mut start = from;
    while let Some(i) = text.get(start..)?.find(needle) {
        let pos = start + i;
        let line_start = text[..pos].rfind('\n').map_or(0, |n| n + 1);
        let in_comment = text[line_start..pos].contains("//");
        if !in_comment && followed(&text[pos + needle.len()..]) {
            return Some(pos);
        }
        start = pos + needle.len();
    }
    None
}

// ---- The file's shape ----

/// The document as written; `version` is optional here so that its absence gets a clear message.
#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "preset")]
struct Doc {
    #[serde(default)]
    version: Option<u32>,
    profile: String,
    #[serde(default)]
    note: String,
    #[serde(default)]
    created: String,
    #[serde(default)]
    device: Option<String>,
    values: Values,
}

/// Just the version, to explain a newer file that does not parse as this version.
#[derive(Deserialize)]
struct Head {
    #[serde(default)]
    version: Option<u32>,
}

/// `{ "COMMAND": { "field": "value", ... }, ... }`, in the file's order.
struct Values(Vec<CommandValues>);

impl<'de> Deserialize<'de> for Values {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Values;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str(
                    r#"a map of Set commands, e.g. { "MSP_SET_PWMVALUE": { "pwmValue": "85" } }"#,
                )
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Values, A::Error> {
                let mut out: Vec<CommandValues> = Vec::new();
                while let Some(command) = map.next_key::<String>()? {
                    if out.iter().any(|c| c.command.eq_ignore_ascii_case(&command)) {
                        return Err(de::Error::custom(format!(
                            "command \"{command}\" is given twice"
                        )));
                    }
                    let Fields(fields) = map.next_value()?;
                    out.push(CommandValues { command, fields });
                }
                Ok(Values(out))
            }
        }
        d.deserialize_map(V)
    }
}

struct Fields(Vec<(String, String)>);

impl<'de> Deserialize<'de> for Fields {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Fields;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str(r#"a map of fields to values, e.g. { "pwmValue": "85" }"#)
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Fields, A::Error> {
                let mut out: Vec<(String, String)> = Vec::new();
                while let Some(field) = map.next_key::<String>()? {
                    if out.iter().any(|(k, _)| k.eq_ignore_ascii_case(&field)) {
                        return Err(de::Error::custom(format!(
                            "field \"{field}\" is given twice"
                        )));
                    }
                    let Text(value) = map.next_value()?;
                    out.push((field, value));
                }
                Ok(Fields(out))
            }
        }
        d.deserialize_map(V)
    }
}
