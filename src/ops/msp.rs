//! Profile commands over a link: reads, and writes that are read back before they count.
//! Used for MSP devices, and by the other protocols' single commands.

use crate::link::{Client, ExchangeError, Reply, Request};
use crate::profile::{Command, CommandKind, FieldError, Input, Profile, Value};
use crate::protocol::Direction;

/// Why an operation failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OpError {
    /// Bad input, refused before anything was sent.
    #[error("{0}")]
    Input(String),
    /// The exchange failed.
    #[error("{0}")]
    Exchange(#[from] ExchangeError),
    /// The device's answer does not fit the profile.
    #[error("{command}: the answer does not fit the profile: {error}")]
    Answer {
        /// The command.
        command: String,
        /// What does not fit.
        error: Box<FieldError>,
    },
    /// The device does not hold what was written, or is not where it should be.
    #[error("{0}")]
    Verify(String),
    /// Cancelled by the operator.
    #[error("cancelled")]
    Cancelled,
}

impl OpError {
    /// The device's answer to `command` does not fit the profile.
    pub fn answer(command: &str, error: FieldError) -> Self {
        OpError::Answer {
            command: command.to_string(),
            error: Box::new(error),
        }
    }
}

impl From<FieldError> for OpError {
    fn from(e: FieldError) -> Self {
        OpError::Input(e.to_string())
    }
}

/// A value written and the value read back.
#[derive(Debug, Clone, PartialEq)]
pub struct Check {
    /// The field.
    pub field: String,
    /// What was written (raw).
    pub written: Value,
    /// What the device holds now (raw).
    pub read: Value,
}

impl Check {
    /// Whether the device holds what was written.
    pub fn ok(&self) -> bool {
        self.written == self.read
    }
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
) -> Result<Vec<(String, Value)>, OpError> {
    let reply = send(client, profile, cmd, inputs)?;
    decode_answer(profile, cmd, reply.payload().unwrap_or_default())
}

fn decode_answer(
    profile: &Profile,
    cmd: &Command,
    payload: &[u8],
) -> Result<Vec<(String, Value)>, OpError> {
    let d = profile
        .decode(cmd, Direction::DeviceToHost, payload)
        .map_err(|e| OpError::answer(&cmd.ident, e))?;
    Ok(d.values.into_iter().map(|v| (v.ident, v.value)).collect())
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
    Ok(written
        .values
        .iter()
        .map(|w| Check {
            field: w.ident.clone(),
            written: w.value.clone(),
            read: read
                .iter()
                .find(|(k, _)| k.eq_ignore_ascii_case(&w.ident))
                .map_or(Value::Bytes(Vec::new()), |(_, v)| v.clone()),
        })
        .collect())
}
