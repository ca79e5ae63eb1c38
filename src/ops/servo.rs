//! Bus-servo operations: ping, scan, parameters, id and baud provisioning, motion.

use super::msp::{Check, OpError};
use super::{Cancel, Progress};
use crate::link::{Client, ExchangeError, Match, ReplySpec, Request};
use crate::profile::model::Access;
use crate::profile::{Input, Param, Profile, Value};
use crate::protocol::Direction;
use crate::protocol::servo::cmd;
use serde::Serialize;
use std::ops::RangeInclusive;

/// Baud rates by option number 1-8 (option 8 on newer servos only).
pub const BAUDS: [u32; 8] = [
    9600, 19200, 38400, 57600, 115_200, 250_000, 500_000, 1_000_000,
];

/// The `data_id` of the servo id parameter.
pub const PARAM_ID: u8 = 34;
/// The `data_id` of the baud-rate option parameter.
pub const PARAM_BAUD: u8 = 36;

/// The baud rate of option 1-8.
pub fn baud_of_option(option: u8) -> Option<u32> {
    BAUDS.get(usize::from(option).checked_sub(1)?).copied()
}

/// The option 1-8 of a baud rate.
pub fn option_of_baud(baud: u32) -> Option<u8> {
    BAUDS.iter().position(|&b| b == baud).map(|i| i as u8 + 1)
}

/// What answers at one id.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(tag = "status", content = "detail", rename_all = "snake_case")]
pub enum Presence {
    /// One servo answered cleanly.
    Present,
    /// Nothing answered.
    Absent,
    /// Answers came back garbled: possibly two servos on one id.
    PossibleDuplicate(String),
}

/// Pings `id` once (a scan) or with retries.
pub fn ping(client: &Client, id: u8, attempts: u8) -> Result<Presence, OpError> {
    Ok(ping_detail(client, id, attempts)?.0)
}

/// Pings `id`; also returns the id of another servo whose late answer turned up meanwhile (on a
/// loaded machine an answer can miss its deadline and arrive during the next ping).
fn ping_detail(client: &Client, id: u8, attempts: u8) -> Result<(Presence, Option<u8>), OpError> {
    let req = Request::new(cmd::PING, vec![id])
        .reply(ReplySpec::Required(Match::servo(cmd::PING, &[id])))
        .attempts(attempts);
    match client.request(req) {
        Ok(_) => Ok((Presence::Present, None)),
        Err(ExchangeError::Timeout { .. }) => Ok((Presence::Absent, None)),
        Err(ExchangeError::Garbled { error, .. }) => {
            Ok((Presence::PossibleDuplicate(error.to_string()), None))
        }
        // A clean answer from another servo is that servo's late answer, not a sign of trouble at
        // this id.
        Err(ExchangeError::Mismatch {
            got: cmd::PING,
            from: Some(other),
            ..
        }) if other != id => Ok((Presence::Absent, Some(other))),
        Err(ExchangeError::Mismatch { got, .. }) => Ok((
            Presence::PossibleDuplicate(format!("answered with command {got}")),
            None,
        )),
        Err(e) => Err(e.into()),
    }
}

/// One servo found by a scan.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ScanRow {
    /// Its id.
    pub id: u8,
    /// The baud rate it answered at.
    pub baud: u32,
    /// Present, or a possible duplicate.
    pub presence: Presence,
    /// Servo type (parameter 6).
    pub servo_type: Option<i64>,
    /// Firmware version (parameter 7).
    pub firmware: Option<i64>,
    /// Serial number (parameter 8).
    pub serial: Option<i64>,
    /// Voltage in mV (parameter 1).
    pub voltage_mv: Option<i64>,
    /// Temperature (parameter 4), raw: °C or a thermistor reading, as the profile says
    /// ([`ScanRow::temperature_text`] shows it).
    pub temperature: Option<i64>,
    /// The raw status byte (parameter 5); its bit order is published inconsistently.
    pub status: Option<i64>,
}

impl ScanRow {
    /// The temperature as the profile shows parameter 4: `32 °C`, or `32.0 °C (raw 1779)` for a
    /// thermistor reading; `-` when not read.
    pub fn temperature_text(&self, profile: &Profile) -> String {
        match (self.temperature, profile.param(4)) {
            (Some(v), Some(p)) => p.field.display(&Value::Int(v)),
            (Some(v), None) => v.to_string(),
            (None, _) => "-".into(),
        }
    }

    /// The status byte as hex, e.g. `0x00`.
    pub fn status_hex(&self) -> String {
        self.status.map_or("-".into(), |s| format!("{s:#04x}"))
    }
}

/// Reads one parameter of servo `id`.
pub fn read_param(
    client: &Client,
    profile: &Profile,
    id: u8,
    param: &Param,
) -> Result<i64, OpError> {
    let read = profile
        .command_by_id(cmd::READ_DATA)
        .ok_or_else(|| OpError::Input("the profile has no READ_DATA".into()))?;
    // The answer must name this parameter: a late answer to an earlier read is not this one.
    let answer = Match::servo(cmd::READ_DATA, &[id]).with_prefix(vec![id, param.id]);
    let req = Request::for_command(profile, read, vec![id, param.id])
        .reply(ReplySpec::Required(answer))
        .attempts(2);
    let reply = client.request(req)?;
    let payload = reply.payload().unwrap_or_default();
    if payload.get(1) != Some(&param.id) {
        return Err(OpError::Verify(format!(
            "servo {id} answered parameter {:?} for {}",
            payload.get(1),
            param.id
        )));
    }
    let d = profile
        .decode(read, Direction::DeviceToHost, payload)
        .map_err(|e| OpError::answer(&read.ident, e))?;
    match d.values.get(2).map(|v| &v.value) {
        Some(Value::Int(v)) => Ok(*v),
        _ => Err(OpError::Verify(format!(
            "servo {id}: no value for {}",
            param.field.ident
        ))),
    }
}

fn param_by_id(profile: &Profile, id: u8) -> Result<&Param, OpError> {
    profile
        .param(id)
        .ok_or_else(|| OpError::Input(format!("the profile has no parameter {id}")))
}

fn details(client: &Client, profile: &Profile, row: &mut ScanRow) {
    let get = |pid: u8| {
        param_by_id(profile, pid)
            .ok()
            .and_then(|p| read_param(client, profile, row.id, p).ok())
    };
    row.servo_type = get(6);
    row.firmware = get(7);
    row.serial = get(8);
    row.voltage_mv = get(1);
    row.temperature = get(4);
    row.status = get(5);
}

/// What a scan covers.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ScanPlan {
    /// The ids to ping (255, broadcast, is skipped).
    pub ids: RangeInclusive<u8>,
    /// The baud rates to try, in order.
    pub bauds: Vec<u32>,
    /// The rate to leave the port at afterwards.
    pub home_baud: u32,
}

/// Scans the plan's ids at each of its bauds, reading each found servo's details, then returns
/// the port to the plan's home rate. `found` sees each row as it is found.
pub fn scan(
    client: &Client,
    profile: &Profile,
    plan: &ScanPlan,
    cancel: &Cancel,
    progress: &mut dyn FnMut(Progress),
    found: &mut dyn FnMut(&ScanRow),
) -> Result<Vec<ScanRow>, OpError> {
    let (bauds, home_baud) = (&plan.bauds, plan.home_baud);
    let ids: Vec<u8> = plan
        .ids
        .clone()
        .filter(|&i| i != crate::protocol::servo::BROADCAST_ID)
        .collect();
    let total = (ids.len() * bauds.len()) as u64;
    let mut rows = Vec::new();
    let mut done = 0;
    let result = (|| {
        for &baud in bauds.iter() {
            client
                .set_baud(baud)
                .map_err(|e| OpError::Verify(e.to_string()))?;
            for &id in &ids {
                if cancel.is_cancelled() {
                    return Err(OpError::Cancelled);
                }
                let (mut presence, late) = ping_detail(client, id, 1)?;
                // A glitch is not a duplicate: an id is reported as one only when it answers
                // garbled again.
                if matches!(presence, Presence::PossibleDuplicate(_)) {
                    presence = ping(client, id, 2)?;
                }
                let mut here = vec![(id, presence)];
                if let Some(other) =
                    late.filter(|o| !rows.iter().any(|r: &ScanRow| r.id == *o && r.baud == baud))
                {
                    here.push((other, ping(client, other, 3)?));
                }
                for (id, presence) in here {
                    if presence == Presence::Absent {
                        continue;
                    }
                    let mut row = ScanRow {
                        id,
                        baud,
                        presence: presence.clone(),
                        servo_type: None,
                        firmware: None,
                        serial: None,
                        voltage_mv: None,
                        temperature: None,
                        status: None,
                    };
                    if presence == Presence::Present {
                        details(client, profile, &mut row);
                    }
                    found(&row);
                    rows.push(row);
                }
                done += 1;
                if done % 8 == 0 || done == total {
                    progress(Progress {
                        done,
                        total,
                        message: format!("id {id} at {baud} baud"),
                    });
                }
            }
        }
        Ok(())
    })();
    let _ = client.set_baud(home_baud);
    rows.sort_by_key(|r| (bauds.iter().position(|&b| b == r.baud), r.id));
    result.map(|()| rows)
}

/// Writes one user parameter of servo `id` and reads it back.
pub fn write_param(
    client: &Client,
    profile: &Profile,
    id: u8,
    param: &Param,
    input: Input,
) -> Result<Check, OpError> {
    if param.access == Access::ReadOnly {
        return Err(OpError::Input(format!(
            "{} is read-only",
            param.field.ident
        )));
    }
    let write = profile
        .command_by_id(cmd::WRITE_DATA)
        .ok_or_else(|| OpError::Input("the profile has no WRITE_DATA".into()))?;
    let inputs = vec![
        ("servo_id".to_string(), Input::Raw(Value::Int(id.into()))),
        (
            "data_id".to_string(),
            Input::Raw(Value::Int(param.id.into())),
        ),
        ("data".to_string(), input),
    ];
    let payload = profile.encode(write, Direction::HostToDevice, &inputs)?;
    let written = profile
        .decode(write, Direction::HostToDevice, &payload)
        .ok()
        .and_then(|d| d.values.get(2).map(|v| v.value.clone()))
        .unwrap_or(Value::Bytes(Vec::new()));
    // A relation with other parameters (angle limits low ≤ high) is checked against what the
    // servo holds now, before anything is written.
    if let Value::Int(raw) = written {
        let mut values = vec![(param.id, raw)];
        for other in profile.related_params(param.id) {
            values.push((other.id, read_param(client, profile, id, other)?));
        }
        profile.check_param_relations(&values)?;
    }
    let answer = Match::servo(cmd::WRITE_DATA, &[id]).with_prefix(vec![id, param.id]);
    let req = Request::for_command(profile, write, payload).reply(ReplySpec::Required(answer));
    let reply = client.request(req)?;
    if reply.payload().and_then(|p| p.get(2)) != Some(&1) {
        return Err(OpError::Verify(format!(
            "servo {id} refused {} = {}",
            param.field.ident,
            param.field.format(&written)
        )));
    }
    let read = read_param(client, profile, id, param)?;
    Ok(Check {
        field: param.field.ident.clone(),
        written,
        read: Value::Int(read),
    })
}

/// Gives servo `old` the id `new`, refusing 255 and any id that already answers; a fresh servo
/// (id 0) must be alone on the bus. Verified at the new id afterwards.
pub fn set_id(
    client: &Client,
    profile: &Profile,
    old: u8,
    new: u8,
    cancel: &Cancel,
) -> Result<(), OpError> {
    if new == crate::protocol::servo::BROADCAST_ID {
        return Err(OpError::Input(
            "id 255 is the broadcast address and cannot be assigned".into(),
        ));
    }
    if new == old {
        return Err(OpError::Input(format!("servo {old} already has id {new}")));
    }
    match ping(client, new, 2)? {
        Presence::Absent => {}
        Presence::Present => {
            return Err(OpError::Input(format!(
                "id {new} already answers on the bus"
            )));
        }
        Presence::PossibleDuplicate(e) => {
            return Err(OpError::Input(format!(
                "id {new} already answers on the bus (garbled: {e})"
            )));
        }
    }
    if old == 0 {
        let found = ids_on_bus(client, cancel)?;
        if found != [0] {
            return Err(OpError::Input(format!(
                "a fresh servo (id 0) is given an id only when it is alone on the bus; ids answering: {found:?}"
            )));
        }
    }
    match ping(client, old, 2)? {
        Presence::Present => {}
        Presence::Absent => return Err(OpError::Verify(format!("no servo answers at id {old}"))),
        Presence::PossibleDuplicate(e) => {
            return Err(OpError::Verify(format!(
                "more than one servo may share id {old}: {e}"
            )));
        }
    }
    let write = profile
        .command_by_id(cmd::WRITE_DATA)
        .ok_or_else(|| OpError::Input("the profile has no WRITE_DATA".into()))?;
    let req = Request::new(cmd::WRITE_DATA, vec![old, PARAM_ID, new])
        .reply(ReplySpec::Required(Match::servo(write.id, &[old, new])));
    let reply = client.request(req)?;
    if reply.payload().and_then(|p| p.get(2)) != Some(&1) {
        return Err(OpError::Verify(format!("servo {old} refused the id {new}")));
    }
    let id_param = param_by_id(profile, PARAM_ID)?;
    let now = read_param(client, profile, new, id_param)
        .map_err(|e| OpError::Verify(format!("no answer at the new id {new}: {e}")))?;
    if now != i64::from(new) {
        return Err(OpError::Verify(format!("servo at {new} reports id {now}")));
    }
    // Two attempts: one garbled tail of a late answer is not a servo.
    if ping(client, old, 2)? != Presence::Absent {
        return Err(OpError::Verify(format!(
            "something still answers at the old id {old}"
        )));
    }
    Ok(())
}

/// The ids that answer at the current baud rate.
fn ids_on_bus(client: &Client, cancel: &Cancel) -> Result<Vec<u8>, OpError> {
    let mut out = Vec::new();
    for id in 0..crate::protocol::servo::BROADCAST_ID {
        if cancel.is_cancelled() {
            return Err(OpError::Cancelled);
        }
        let (presence, late) = ping_detail(client, id, 1)?;
        if presence != Presence::Absent {
            out.push(id);
        }
        // A late answer still proves that servo is there.
        if let Some(other) = late.filter(|o| !out.contains(o)) {
            out.push(other);
        }
    }
    out.sort_unstable();
    Ok(out)
}

/// Where a servo was found after a baud change that could not be verified.
fn recover(client: &Client, id: u8) -> Result<Option<u32>, OpError> {
    for &b in &BAUDS {
        client
            .set_baud(b)
            .map_err(|e| OpError::Verify(e.to_string()))?;
        if ping(client, id, 2)? == Presence::Present {
            return Ok(Some(b));
        }
    }
    Ok(None)
}

/// Sets servo `id`'s baud option (1-8), switches the port to the new rate and verifies there.
/// If the servo is not found at the new rate, every rate is scanned for it: the error says where
/// it is, and the port is left at that rate.
pub fn set_baud(client: &Client, profile: &Profile, id: u8, option: u8) -> Result<u32, OpError> {
    let Some(baud) = baud_of_option(option) else {
        return Err(OpError::Input(format!(
            "baud option {option} is out of range; allowed 1 to 8 ({})",
            BAUDS.map(|b| b.to_string()).join(", ")
        )));
    };
    let baud_param = param_by_id(profile, PARAM_BAUD)?;
    baud_param.field.check(&Value::Int(option.into()))?;
    match ping(client, id, 2)? {
        Presence::Present => {}
        other => {
            return Err(OpError::Verify(format!(
                "servo {id} is not answering cleanly: {other:?}"
            )));
        }
    }
    // The servo switches at once and may answer at the new rate: its answer is not awaited here.
    let req = Request::new(cmd::WRITE_DATA, vec![id, PARAM_BAUD, option])
        .reply(ReplySpec::Optional(Match::servo(cmd::WRITE_DATA, &[id])))
        .attempts(1);
    match client.request(req) {
        Ok(_) | Err(ExchangeError::Garbled { .. } | ExchangeError::Timeout { .. }) => {}
        Err(e) => return Err(e.into()),
    }
    client
        .set_baud(baud)
        .map_err(|e| OpError::Verify(e.to_string()))?;
    let verified = ping(client, id, 3)? == Presence::Present
        && read_param(client, profile, id, baud_param).ok() == Some(i64::from(option));
    if verified {
        return Ok(baud);
    }
    match recover(client, id)? {
        Some(b) => Err(OpError::Verify(format!(
            "servo {id} did not answer at {baud} baud; it was found at {b} baud (the port is now at {b})"
        ))),
        None => Err(OpError::Verify(format!(
            "servo {id} did not answer at {baud} baud, nor at any other rate"
        ))),
    }
}

/// The user parameters (32-53) of the 32-byte block, in block order.
fn block_params(profile: &Profile) -> Vec<&Param> {
    profile.block_params().collect()
}

/// Reads the 32-byte user block (parameters 32-53) in one exchange: raw values by `data_id`, in
/// block order.
pub fn read_block(client: &Client, profile: &Profile, id: u8) -> Result<Vec<(u8, i64)>, OpError> {
    let read = profile
        .command_by_id(cmd::READ_BATCH_DATA)
        .ok_or_else(|| OpError::Input("the profile has no READ_BATCH_DATA".into()))?;
    let req = Request::for_command(profile, read, vec![id])
        .reply(ReplySpec::Required(Match::servo(
            cmd::READ_BATCH_DATA,
            &[id],
        )))
        .attempts(2);
    let reply = client.request(req)?;
    let d = profile
        .decode(
            read,
            Direction::DeviceToHost,
            reply.payload().unwrap_or_default(),
        )
        .map_err(|e| OpError::answer(&read.ident, e))?;
    let params = block_params(profile);
    let values = d.values.get(1..).unwrap_or_default();
    if values.len() != params.len() {
        return Err(OpError::Verify(format!(
            "servo {id}: the user block holds {} values, the profile {}",
            values.len(),
            params.len()
        )));
    }
    params
        .iter()
        .zip(values)
        .map(|(p, v)| match v.value {
            Value::Int(raw) => Ok((p.id, raw)),
            _ => Err(OpError::Verify(format!(
                "servo {id}: no value for {}",
                p.field.ident
            ))),
        })
        .collect()
}

/// Writes the whole 32-byte user block of servo `id` in one exchange, then reads it back.
/// `values` must give every user parameter (raw, by `data_id`); each is checked against the
/// profile first. The block also holds the id (34) and the baud option (36): they must be what
/// the servo holds now (they are changed with [`set_id`] and [`set_baud`], which follow the servo).
pub fn write_block(
    client: &Client,
    profile: &Profile,
    id: u8,
    values: &[(u8, i64)],
) -> Result<Vec<Check>, OpError> {
    let write = profile
        .command_by_id(cmd::WRITE_BATCH_DATA)
        .ok_or_else(|| OpError::Input("the profile has no WRITE_BATCH_DATA".into()))?;
    let params = block_params(profile);
    let mut inputs = vec![("servo_id".to_string(), Input::Raw(Value::Int(id.into())))];
    for p in &params {
        let Some(&(_, raw)) = values.iter().find(|(pid, _)| *pid == p.id) else {
            return Err(OpError::Input(format!(
                "the block needs a value for {} ({})",
                p.field.ident, p.id
            )));
        };
        p.field.check(&Value::Int(raw))?;
        inputs.push((p.field.ident.clone(), Input::Raw(Value::Int(raw))));
    }
    let before = read_block(client, profile, id)?;
    for pid in [PARAM_ID, PARAM_BAUD] {
        let now = before.iter().find(|(p, _)| *p == pid).map(|(_, v)| *v);
        let new = values.iter().find(|(p, _)| *p == pid).map(|(_, v)| *v);
        if now != new {
            let name = param_by_id(profile, pid)?.field.ident.clone();
            return Err(OpError::Input(format!(
                "the block would change {name} from {now:?} to {new:?}: change the id or baud rate with their own commands, which follow the servo"
            )));
        }
    }
    let payload = profile.encode(write, Direction::HostToDevice, &inputs)?;
    let req = Request::for_command(profile, write, payload).reply(ReplySpec::Required(
        Match::servo(cmd::WRITE_BATCH_DATA, &[id]),
    ));
    let reply = client.request(req)?;
    if reply.payload().and_then(|p| p.get(1)) != Some(&1) {
        return Err(OpError::Verify(format!(
            "servo {id} refused the user block"
        )));
    }
    let after = read_block(client, profile, id)?;
    Ok(params
        .iter()
        .map(|p| {
            let written = values.iter().find(|(pid, _)| *pid == p.id).map(|(_, v)| *v);
            let read = after.iter().find(|(pid, _)| *pid == p.id).map(|(_, v)| *v);
            Check {
                field: p.field.ident.clone(),
                written: written.map_or(Value::Bytes(Vec::new()), Value::Int),
                read: read.map_or(Value::Bytes(Vec::new()), Value::Int),
            }
        })
        .collect())
}

/// Where a servo is after [`reset_user_data`]: its factory id and baud rate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Location {
    /// Its id.
    pub id: u8,
    /// Its baud rate.
    pub baud: u32,
}

/// The id and baud rate the user parameters reset to (the profile's defaults of 34 and 36).
pub fn factory_location(profile: &Profile) -> Location {
    let id = profile
        .param(PARAM_ID)
        .and_then(|p| p.field.default)
        .and_then(|v| u8::try_from(v).ok())
        .unwrap_or(0);
    let baud = profile
        .param(PARAM_BAUD)
        .and_then(|p| p.field.default)
        .and_then(|v| u8::try_from(v).ok())
        .and_then(baud_of_option)
        .unwrap_or(profile.baud);
    Location { id, baud }
}

/// Restores servo `id`'s user parameters (32-53) to the factory defaults. That includes its id
/// and baud rate: refused when another servo already answers at the factory id and rate (the two
/// would then share an id). The servo is then looked for at its factory id and rate, and the port
/// is left there; if it is not found, the error says so. `baud` is the rate the servo talks at
/// now.
pub fn reset_user_data(
    client: &Client,
    profile: &Profile,
    id: u8,
    baud: u32,
) -> Result<Location, OpError> {
    let reset = profile
        .command_by_id(cmd::RESET_USER_DATA)
        .ok_or_else(|| OpError::Input("the profile has no RESET_USER_DATA".into()))?;
    let home = factory_location(profile);
    let switch = |b: u32| {
        client
            .set_baud(b)
            .map_err(|e| OpError::Verify(e.to_string()))
    };
    if home != (Location { id, baud }) {
        switch(home.baud)?;
        let there = ping(client, home.id, 2)?;
        switch(baud)?;
        if there != Presence::Absent {
            return Err(OpError::Input(format!(
                "another servo answers at the factory id {} at {} baud: after a reset the two would share an id; give that one another id first",
                home.id, home.baud
            )));
        }
    }
    match ping(client, id, 2)? {
        Presence::Present => {}
        other => {
            return Err(OpError::Verify(format!(
                "servo {id} is not answering cleanly: {other:?}"
            )));
        }
    }
    // The servo may answer from its new id and at its new rate: the answer is not awaited here.
    let req = Request::for_command(profile, reset, vec![id])
        .reply(ReplySpec::Optional(Match::servo(
            cmd::RESET_USER_DATA,
            &[id, home.id],
        )))
        .attempts(1);
    match client.request(req) {
        Ok(r) if r.payload().and_then(|p| p.get(1)) == Some(&0) => {
            return Err(OpError::Verify(format!("servo {id} refused the reset")));
        }
        Ok(_) | Err(ExchangeError::Garbled { .. } | ExchangeError::Timeout { .. }) => {}
        Err(e) => return Err(e.into()),
    }
    switch(home.baud)?;
    if ping(client, home.id, 3)? == Presence::Present {
        return Ok(home);
    }
    match recover(client, home.id)? {
        Some(b) => Err(OpError::Verify(format!(
            "after the reset servo {} answers at {b} baud, not at {} (the port is now at {b})",
            home.id, home.baud
        ))),
        None => {
            let _ = switch(baud);
            Err(OpError::Verify(format!(
                "after the reset no servo answers at the factory id {} at any rate",
                home.id
            )))
        }
    }
}

/// The ROTATE request: servo `id` to `deci_degrees` (0.1°) over `interval_ms`, with `power` mW
/// (0: the servo's limit). Checked against the profile.
pub fn rotate_request(
    profile: &Profile,
    id: u8,
    deci_degrees: i64,
    interval_ms: i64,
    power: i64,
) -> Result<Request, OpError> {
    motion_request(
        profile,
        cmd::ROTATE,
        id,
        &[
            ("angle", deci_degrees),
            ("interval", interval_ms),
            ("power", power),
        ],
    )
}

/// Wheel-mode methods (SPIN, bits 1-0).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wheel {
    /// Stop turning.
    Stop,
    /// Turn until told otherwise.
    Continuous,
    /// Turn this many turns.
    Turns(u16),
    /// Turn for this many milliseconds.
    Timed(u16),
}

/// The SPIN request: servo `id` in wheel mode at `speed` °/s, clockwise or not.
pub fn spin_request(
    profile: &Profile,
    id: u8,
    wheel: Wheel,
    clockwise: bool,
    speed: u16,
) -> Result<Request, OpError> {
    let (mode, value) = match wheel {
        Wheel::Stop => (0, 0),
        Wheel::Continuous => (1, 0),
        Wheel::Turns(n) => (2, n),
        Wheel::Timed(ms) => (3, ms),
    };
    let method = mode | if clockwise { 0x80 } else { 0 };
    motion_request(
        profile,
        cmd::SPIN,
        id,
        &[
            ("method", method),
            ("speed", speed.into()),
            ("value", value.into()),
        ],
    )
}

/// The DAMPING request: servo `id` (255: all) in damping mode with `power` mW (0: the limit).
pub fn damping_request(profile: &Profile, id: u8, power: i64) -> Result<Request, OpError> {
    motion_request(profile, cmd::DAMPING, id, &[("power", power)])
}

fn motion_request(
    profile: &Profile,
    command: u8,
    id: u8,
    values: &[(&str, i64)],
) -> Result<Request, OpError> {
    let c = profile
        .command_by_id(command)
        .ok_or_else(|| OpError::Input(format!("the profile has no command {command}")))?;
    let mut inputs = vec![("servo_id".to_string(), Input::Raw(Value::Int(id.into())))];
    inputs.extend(
        values
            .iter()
            .map(|(k, v)| (k.to_string(), Input::Raw(Value::Int(*v)))),
    );
    let payload = profile.encode(c, Direction::HostToDevice, &inputs)?;
    Ok(Request::for_command(profile, c, payload).attempts(1))
}

/// "Stop all": broadcasts that stop every servo at the port's baud rate. Damping (every servo
/// knows it) stops a move or a spin; then STOP with hold (newer servos) locks them where they are.
/// Nobody answers a broadcast.
pub fn stop_all_requests(profile: &Profile) -> Vec<Request> {
    let broadcast = crate::protocol::servo::BROADCAST_ID;
    let mut out = Vec::new();
    if let Ok(r) = damping_request(profile, broadcast, 0) {
        out.push(r);
    }
    // 0x11: stop and hold.
    if let Ok(r) = motion_request(
        profile,
        cmd::STOP,
        broadcast,
        &[("mode", 0x11), ("power", 0)],
    ) {
        out.push(r);
    }
    // Nobody answers a broadcast. (The worker lets a frame cross the wire whole before a baud
    // change queued after it.)
    out.into_iter().map(|r| r.reply(ReplySpec::None)).collect()
}

/// The READ_ANGLE request to poll for servo `id`'s angle (answer: id, angle i16 in 0.1°).
pub fn read_angle_request(id: u8) -> Request {
    Request::new(cmd::READ_ANGLE, vec![id])
        .reply(ReplySpec::Required(Match::servo(cmd::READ_ANGLE, &[id])))
        .attempts(1)
}

/// The MONITOR request (newer servos) to poll for all of servo `id`'s live values.
pub fn monitor_request(id: u8) -> Request {
    Request::new(cmd::MONITOR, vec![id])
        .reply(ReplySpec::Required(Match::servo(cmd::MONITOR, &[id])))
        .attempts(1)
}

/// Reads servo `id`'s angle, 0.1°.
pub fn read_angle(client: &Client, profile: &Profile, id: u8) -> Result<i64, OpError> {
    let c = profile
        .command_by_id(cmd::READ_ANGLE)
        .ok_or_else(|| OpError::Input("the profile has no READ_ANGLE".into()))?;
    let reply = client.request(read_angle_request(id).attempts(2))?;
    let d = profile
        .decode(
            c,
            Direction::DeviceToHost,
            reply.payload().unwrap_or_default(),
        )
        .map_err(|e| OpError::answer(&c.ident, e))?;
    match d.values.get(1).map(|v| &v.value) {
        Some(Value::Int(v)) => Ok(*v),
        _ => Err(OpError::Verify(format!("servo {id}: no angle"))),
    }
}

/// Looks for servo `id` at every baud rate; the port is left where it answered. Returns that rate.
pub fn locate(client: &Client, id: u8) -> Result<Option<u32>, OpError> {
    recover(client, id)
}
