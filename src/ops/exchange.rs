//! Protocol-neutral pieces every operation is built of: send a profile command, read its answer
//! as named values, and write with read-back verification. Used for MSP devices, and by the
//! other protocols' single commands.

use super::OpError;
use crate::link::{Client, Reply, Request};
use crate::profile::{Command, CommandKind, Decoded, Input, Profile, Value};
use crate::protocol::Direction;

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
pub fn send(
    client: &Client,
    profile: &Profile,
    cmd: &Command,
    inputs: &[(String, Input)],
) -> Result<Reply, OpError> {
    let payload = profile.encode(cmd, Direction::HostToDevice, inputs)?;
    Ok(client.request(Request::for_command(profile, cmd, payload))?)
}

/// Reads a command's answer as named raw values.
pub fn read(
    client: &Client,
    profile: &Profile,
    cmd: &Command,
    inputs: &[(String, Input)],
) -> Result<FieldValues, OpError> {
    let reply = send(client, profile, cmd, inputs)?;
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
/// checked against the profile before anything is sent. Returns the checks (all `ok()` when the
/// device holds what was written); a command without a Get partner is sent and acknowledged only.
pub fn write_verified(
    client: &Client,
    profile: &Profile,
    set: &Command,
    inputs: &[(String, Input)],
) -> Result<Vec<Check>, OpError> {
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
    let read = read(client, profile, get, &[])?;
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
