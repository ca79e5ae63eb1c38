//! Protocol-neutral pieces every operation is built of: send a profile command, read its answer
//! as named values, and write with read-back verification. Used for MSP devices, and by the
//! other protocols' single commands.

use super::OpError;
use crate::link::{Reply, Request};
use crate::ops::Device;
use crate::profile::{Command, CommandKind, Decoded, Field, FieldError, Input, Profile, Value};
use crate::protocol::Direction;

/// What an operation does with a profile command, and so which kinds of command it takes
/// ([`check_kind`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Use {
    /// Reads its answer once (`msp get`, a batch read): a Get or Telemetry command.
    Read,
    /// Polls it (`msp watch`, the plots): a Get or Telemetry command.
    Poll,
    /// Writes with it (`msp set`, presets, actions): a Set or Action command.
    Write,
}

impl Use {
    fn takes(self, kind: CommandKind) -> bool {
        match self {
            Use::Read | Use::Poll => matches!(kind, CommandKind::Get | CommandKind::Telemetry),
            Use::Write => matches!(kind, CommandKind::Set | CommandKind::Action),
        }
    }

    fn words(self) -> (&'static str, &'static str) {
        match self {
            Use::Read => ("reading", "a Get or Telemetry command"),
            Use::Poll => ("polling", "a Get or Telemetry command"),
            Use::Write => ("writing", "a Set or Action command"),
        }
    }
}

/// Refuses, before anything is sent, a command of a kind `usage` does not take: a Set or an
/// Action to read or poll (it would be sent with an empty payload), a Get or Telemetry command
/// to write, a Raw command (no published layout) to any. The error names the command's Get or
/// Set partner where it has one.
pub fn check_kind(profile: &Profile, cmd: &Command, usage: Use) -> Result<(), OpError> {
    if usage.takes(cmd.kind) {
        return Ok(());
    }
    let kind = match cmd.kind {
        CommandKind::Get => "a Get command",
        CommandKind::Set => "a Set command",
        CommandKind::Telemetry => "a Telemetry command",
        CommandKind::Action => "an Action",
        CommandKind::Raw => "a Raw command (its payload layout is not published)",
    };
    let pair = cmd.pair.and_then(|id| profile.command_by_id(id));
    let hint = match (cmd.kind, pair) {
        (CommandKind::Set, Some(get)) => format!("; its Get is {}", get.ident),
        (CommandKind::Get, Some(set)) => format!("; its Set is {}", set.ident),
        _ => String::new(),
    };
    let (operation, expected) = usage.words();
    Err(OpError::WrongCommand {
        command: cmd.ident.clone(),
        kind,
        operation,
        expected,
        hint,
    })
}

/// Checks a write's named inputs against `cmd` before anything is sent, without needing every
/// field: the command is one to write ([`check_kind`]), each name is one of its fields and is
/// given once, each value is one the field takes. Returns the fields left out. A Set with
/// fields given none is refused ([`OpError::NothingGiven`]).
pub fn check_write<'c>(
    profile: &Profile,
    cmd: &'c Command,
    inputs: &[(String, Input)],
) -> Result<Vec<&'c Field>, OpError> {
    check_kind(profile, cmd, Use::Write)?;
    let fields = profile.fields(cmd, Direction::HostToDevice);
    if inputs.is_empty() && cmd.kind == CommandKind::Set && !fields.is_empty() {
        return Err(OpError::NothingGiven {
            what: "field",
            hint: "give FIELD=VALUE for each field to change",
        });
    }
    let mut given: Vec<&Field> = Vec::new();
    for (name, input) in inputs {
        let Some(field) = fields.iter().find(|f| f.ident.eq_ignore_ascii_case(name)) else {
            let known: Vec<&str> = fields.iter().map(|f| f.ident.as_str()).collect();
            return Err(FieldError::UnknownField {
                command: cmd.ident.clone(),
                field: crate::document::quote(name),
                known: known.join(", "),
            }
            .into());
        };
        if given.iter().any(|g| std::ptr::eq(*g, field)) {
            return Err(FieldError::Duplicate {
                command: cmd.ident.clone(),
                field: field.ident.clone(),
            }
            .into());
        }
        match input {
            Input::Text(t) => field.parse(t).map(drop)?,
            Input::Raw(v) => field.check(v)?,
        }
        given.push(field);
    }
    Ok(fields
        .iter()
        .filter(|f| !given.iter().any(|g| std::ptr::eq(*g, *f)))
        .collect())
}

/// The values of one answer (or one command), named by field ident, in wire order. Fields are
/// looked up by ident, ignoring ASCII case, as profiles and documents name them.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FieldValues(Vec<(String, Value)>);

impl FieldValues {
    /// No values.
    pub fn new() -> Self {
        Self::default()
    }

    /// The value of `field`, if the answer holds it.
    pub fn get(&self, field: &str) -> Option<&Value> {
        self.0
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(field))
            .map(|(_, v)| v)
    }

    /// The raw integer of `field`, if the answer holds it as a number.
    pub fn int(&self, field: &str) -> Option<i64> {
        match self.get(field) {
            Some(Value::Int(v)) => Some(*v),
            _ => None,
        }
    }

    /// Whether the answer holds `field`.
    pub fn contains(&self, field: &str) -> bool {
        self.get(field).is_some()
    }

    /// Adds a value at the end.
    pub fn push(&mut self, field: impl Into<String>, value: Value) {
        self.0.push((field.into(), value));
    }

    /// (field ident, value), in wire order.
    pub fn iter(&self) -> impl DoubleEndedIterator<Item = (&str, &Value)> + '_ {
        self.0.iter().map(|(k, v)| (k.as_str(), v))
    }

    /// How many values.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

impl From<Decoded<'_>> for FieldValues {
    fn from(d: Decoded<'_>) -> Self {
        Self(d.values.into_iter().map(|v| (v.ident, v.value)).collect())
    }
}

impl<'a> IntoIterator for &'a FieldValues {
    type Item = (&'a str, &'a Value);
    type IntoIter = std::iter::Map<
        std::slice::Iter<'a, (String, Value)>,
        fn(&'a (String, Value)) -> (&'a str, &'a Value),
    >;

    fn into_iter(self) -> Self::IntoIter {
        self.0.iter().map(|(k, v)| (k.as_str(), v))
    }
}

impl FromIterator<(String, Value)> for FieldValues {
    fn from_iter<I: IntoIterator<Item = (String, Value)>>(iter: I) -> Self {
        Self(iter.into_iter().collect())
    }
}

impl Extend<(String, Value)> for FieldValues {
    fn extend<I: IntoIterator<Item = (String, Value)>>(&mut self, iter: I) {
        self.0.extend(iter);
    }
}

/// A value written and the value read back.
#[derive(Debug, Clone, PartialEq)]
pub struct Check {
    /// The field.
    pub field: String,
    /// What was written (raw).
    pub written: Value,
    /// What the device holds now (raw); empty bytes when the answer did not hold the field.
    pub read: Value,
}

impl Check {
    /// Whether the device holds what was written.
    pub fn ok(&self) -> bool {
        self.written == self.read
    }
}

/// The request that sends `cmd` with named inputs, each checked against the profile (range,
/// labels, step, type) before anything is built. For requests that go to the worker without
/// waiting on this thread (a control while a job runs); `attempts` is how often it is sent.
pub fn request(
    profile: &Profile,
    cmd: &Command,
    inputs: &[(String, Input)],
    attempts: u8,
) -> Result<Request, OpError> {
    let payload = profile.encode(cmd, Direction::HostToDevice, inputs)?;
    Ok(Request::for_command(profile, cmd, payload).attempts(attempts))
}

/// Sends a profile command built from named inputs and returns the answer.
pub fn send(dev: Device<'_>, cmd: &Command, inputs: &[(String, Input)]) -> Result<Reply, OpError> {
    let Device { client, profile } = dev;
    let payload = profile.encode(cmd, Direction::HostToDevice, inputs)?;
    Ok(client.request(Request::for_command(profile, cmd, payload))?)
}

/// Reads a command's answer as named raw values.
pub fn read(
    dev: Device<'_>,
    cmd: &Command,
    inputs: &[(String, Input)],
) -> Result<FieldValues, OpError> {
    let profile = dev.profile;
    check_kind(profile, cmd, Use::Read)?;
    let reply = send(dev, cmd, inputs)?;
    decode_answer(profile, cmd, reply.payload().unwrap_or_default())
}

/// A device's answer to `cmd` as named raw values, or why it does not fit the profile.
pub fn decode_answer(
    profile: &Profile,
    cmd: &Command,
    payload: &[u8],
) -> Result<FieldValues, OpError> {
    profile
        .decode(cmd, Direction::DeviceToHost, payload)
        .map(FieldValues::from)
        .map_err(|e| OpError::answer(&cmd.ident, e))
}

/// Writes with a Set command, then reads its Get back and compares every field. Values are
/// checked against the profile before anything is sent, and so is the command's kind (a Set or
/// an Action). Returns the checks (all `ok()` when the device holds what was written); a command
/// without a Get partner is sent and acknowledged only.
pub fn write_verified(
    dev: Device<'_>,
    set: &Command,
    inputs: &[(String, Input)],
) -> Result<Vec<Check>, OpError> {
    let Device { client, profile } = dev;
    check_kind(profile, set, Use::Write)?;
    let payload = profile.encode(set, Direction::HostToDevice, inputs)?;
    let written = profile
        .decode(set, Direction::HostToDevice, &payload)
        .map_err(|e| OpError::answer(&set.ident, e))?;
    client.request(Request::for_command(profile, set, payload.clone()))?;
    let get = match (set.kind, set.pair) {
        (CommandKind::Set, Some(pair)) => profile.command_by_id(pair),
        _ => None,
    };
    let Some(get) = get else {
        return Ok(Vec::new());
    };
    let read = read(dev, get, &[])?;
    Ok(checks(&FieldValues::from(written), &read))
}

/// Each field written compared with what was read back.
pub fn checks(written: &FieldValues, read: &FieldValues) -> Vec<Check> {
    written
        .iter()
        .map(|(field, w)| Check {
            field: field.to_string(),
            written: w.clone(),
            read: read.get(field).cloned().unwrap_or(Value::Bytes(Vec::new())),
        })
        .collect()
}

/// A write of some fields of a Set: the checks of every field, and the fields left out whose
/// values the device already held and kept (raw).
#[derive(Debug, Clone, PartialEq)]
pub struct Kept {
    /// Every field written, read back.
    pub checks: Vec<Check>,
    /// The fields not given, written with the value the device held.
    pub kept: FieldValues,
}

/// Writes the fields given with a Set command and keeps the device's current values for the
/// rest: when fields are left out, the Set's Get is read first and its values fill them; then
/// [`write_verified`]. An Action is written as given (its omitted fields take their defaults).
/// Everything given is checked before anything is sent ([`check_write`]); a kept value the
/// profile refuses, or one the answer lacks, is [`OpError::CannotKeep`] and nothing is written.
pub fn write_keeping(
    dev: Device<'_>,
    set: &Command,
    inputs: &[(String, Input)],
) -> Result<Kept, OpError> {
    let profile = dev.profile;
    let omitted = check_write(profile, set, inputs)?;
    let get = match (set.kind, set.pair) {
        (CommandKind::Set, Some(pair)) if !omitted.is_empty() => profile.command_by_id(pair),
        _ => None,
    };
    let Some(get) = get else {
        let checks = write_verified(dev, set, inputs)?;
        return Ok(Kept {
            checks,
            kept: FieldValues::new(),
        });
    };
    let now = read(dev, get, &[])?;
    let mut all = inputs.to_vec();
    let mut kept = FieldValues::new();
    for field in omitted {
        let cannot = |why: String| OpError::CannotKeep {
            command: set.ident.clone(),
            field: field.ident.clone(),
            why,
        };
        let value = now
            .get(&field.ident)
            .ok_or_else(|| cannot(format!("{} does not answer with it", get.ident)))?;
        field.check(value).map_err(|e| {
            cannot(format!(
                "it holds {}, which the profile refuses ({e})",
                field.format(value)
            ))
        })?;
        all.push((field.ident.clone(), Input::Raw(value.clone())));
        kept.push(field.ident.clone(), value.clone());
    }
    let checks = write_verified(dev, set, &all)?;
    Ok(Kept { checks, kept })
}
