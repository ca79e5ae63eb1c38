//! A servo's parameters: one at a time (read, and write with read-back), or the 32-byte user
//! block in one exchange.

use super::{baud_param, command, id_param};
use crate::link::{Match, ReplySpec, Request};
use crate::ops::{Check, OpError, Progress};
use crate::ops::{Device, Run};
use crate::profile::model::Access;
use crate::profile::{Input, Param, ParamRole, Profile, Value};
use crate::protocol::Direction;
use crate::protocol::servo::cmd;

/// Reads one parameter of servo `id`.
pub fn read_param(dev: Device<'_>, id: u8, param: &Param) -> Result<i64, OpError> {
    let Device { client, profile } = dev;
    let reply = client.request(read_request(profile, id, param)?)?;
    read_value(profile, id, param, reply.payload().unwrap_or_default())
}

/// The request that reads parameter `param` of servo `id` (READ_DATA, two attempts).
pub(super) fn read_request(profile: &Profile, id: u8, param: &Param) -> Result<Request, OpError> {
    super::addressed(id, "read a parameter")?;
    let read = command(profile, cmd::READ_DATA)?;
    // The answer must name this parameter: a late answer to an earlier read is not this one.
    let answer = Match::servo(cmd::READ_DATA, &[id]).with_prefix(vec![id, param.id]);
    Ok(Request::for_command(profile, read, vec![id, param.id])
        .reply(ReplySpec::Required(answer))
        .attempts(2))
}

/// The value of `param` in servo `id`'s READ_DATA answer `payload`.
pub(super) fn read_value(
    profile: &Profile,
    id: u8,
    param: &Param,
    payload: &[u8],
) -> Result<i64, OpError> {
    let read = command(profile, cmd::READ_DATA)?;
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

/// Writes one user parameter of servo `id` and reads it back.
pub fn write_param(dev: Device<'_>, id: u8, param: &Param, input: Input) -> Result<Check, OpError> {
    let Device { client, profile } = dev;
    super::addressed(id, "write a parameter and read it back")?;
    let input = baud_as_option(param, input);
    let (write, payload, written) = write_payload(profile, id, param, input)?;
    if let Some(role @ (ParamRole::ServoId | ParamRole::BaudOption { .. })) = &param.role {
        return write_followed(dev, id, param, role, written);
    }
    // A relation with other parameters (angle limits low ≤ high) is checked against what the
    // servo holds now, before anything is written.
    if let Value::Int(raw) = written {
        let mut values = vec![(param.id, raw)];
        for other in profile.related_params(param.id) {
            values.push((other.id, read_param(dev, id, other)?));
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
    let read = read_param(dev, id, param)?;
    Ok(Check {
        field: param.field.ident.clone(),
        written,
        read: Value::Int(read),
    })
}

/// A baud option given as the rate it stands for (`57600`, as `servo set-baud` takes it) is
/// that option; any other input is as given.
pub fn baud_as_option(param: &Param, input: Input) -> Input {
    let (Some(ParamRole::BaudOption { rates }), Input::Text(text)) = (&param.role, &input) else {
        return input;
    };
    let Ok(baud) = text.trim().parse::<u32>() else {
        return input;
    };
    match rates.iter().find(|(_, b)| **b == baud) {
        Some((option, _)) => Input::Raw(Value::Int(i64::from(*option))),
        None => input,
    }
}

/// Writes servo `id`'s id or baud option (`param`, whose role is `role`) as the one checked way
/// to change them does: [`super::set_id`] (the new id free, a fresh servo alone on the bus, the
/// servo verified at its new id) or [`super::set_baud`] (the port follows the servo to its new
/// rate and verifies it there). `written` is the raw value, already checked against the profile.
fn write_followed(
    dev: Device<'_>,
    id: u8,
    param: &Param,
    role: &ParamRole,
    written: Value,
) -> Result<Check, OpError> {
    let raw = match &written {
        Value::Int(raw) => u8::try_from(*raw).map_err(|_| OpError::OutOfRange {
            what: "servo id or baud option",
            value: *raw,
            min: 0,
            max: 254,
            note: String::new(),
        })?,
        other => {
            return Err(OpError::Verify(format!(
                "{} takes a whole number, not {other:?}",
                param.field.ident
            )));
        }
    };
    match role {
        ParamRole::ServoId => super::set_id(dev, id, raw, &crate::ops::Cancel::new())?,
        _ => {
            super::set_baud(dev, id, raw)?;
        }
    }
    // Both read the value back where the servo now is (its new id, its new rate).
    Ok(Check {
        field: param.field.ident.clone(),
        written: written.clone(),
        read: written,
    })
}

/// Writes one user parameter to every servo at the port's rate (id 255, the broadcast address),
/// asked for on purpose: nobody answers a broadcast, so nothing is read back. The value is
/// checked against the profile first. Returns the raw value written.
pub fn write_param_broadcast(
    dev: Device<'_>,
    param: &Param,
    input: Input,
) -> Result<Value, OpError> {
    let Device { client, profile } = dev;
    if matches!(
        param.role,
        Some(ParamRole::ServoId | ParamRole::BaudOption { .. })
    ) {
        return Err(OpError::NotBroadcast {
            param: param.field.ident.clone(),
        });
    }
    let id = crate::protocol::servo::BROADCAST_ID;
    let (write, payload, written) = write_payload(profile, id, param, input)?;
    client.request(Request::for_command(profile, write, payload).reply(ReplySpec::None))?;
    Ok(written)
}

/// The WRITE_DATA command, its payload for `param` of servo `id` and the raw value in it,
/// checked against the profile.
fn write_payload<'p>(
    profile: &'p Profile,
    id: u8,
    param: &Param,
    input: Input,
) -> Result<(&'p crate::profile::Command, Vec<u8>, Value), OpError> {
    if param.access == Access::ReadOnly {
        return Err(OpError::ReadOnly {
            param: param.field.ident.clone(),
        });
    }
    let write = command(profile, cmd::WRITE_DATA)?;
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
    Ok((write, payload, written))
}

/// The user parameters (32-53) of the 32-byte block, in block order.
fn block_params(profile: &Profile) -> Vec<&Param> {
    profile.block_params().collect()
}

/// Reads the 32-byte user block (parameters 32-53) in one exchange: raw values by `data_id`, in
/// block order.
pub fn read_block(dev: Device<'_>, id: u8) -> Result<Vec<(u8, i64)>, OpError> {
    let Device { client, profile } = dev;
    super::addressed(id, "read the user block")?;
    let read = command(profile, cmd::READ_BATCH_DATA)?;
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
/// profile first. The block also holds the id and the baud option (the parameters with those
/// roles): they must be what the servo holds now (they are changed with [`set_id`] and [`set_baud`], which follow the servo).
pub fn write_block(dev: Device<'_>, id: u8, values: &[(u8, i64)]) -> Result<Vec<Check>, OpError> {
    let Device { client, profile } = dev;
    super::addressed(id, "write the user block and read it back")?;
    let write = command(profile, cmd::WRITE_BATCH_DATA)?;
    let params = block_params(profile);
    let mut inputs = vec![("servo_id".to_string(), Input::Raw(Value::Int(id.into())))];
    for p in &params {
        let Some(&(_, raw)) = values.iter().find(|(pid, _)| *pid == p.id) else {
            return Err(OpError::MissingValue {
                param: p.field.ident.clone(),
                data_id: p.id,
            });
        };
        p.field.check(&Value::Int(raw))?;
        inputs.push((p.field.ident.clone(), Input::Raw(Value::Int(raw))));
    }
    let before = read_block(dev, id)?;
    for followed in [id_param(profile)?, baud_param(profile)?.0] {
        let pid = followed.id;
        let now = before.iter().find(|(p, _)| *p == pid).map(|(_, v)| *v);
        let new = values.iter().find(|(p, _)| *p == pid).map(|(_, v)| *v);
        if now != new {
            return Err(OpError::FollowedChange {
                param: followed.field.ident.clone(),
                now,
                new,
            });
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
    let after = read_block(dev, id)?;
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

/// Every parameter of servo `id`: the read-only ones one by one, the user block in one
/// exchange. Raw values by `data_id`, each with why it could not be read.
pub fn read_all(dev: Device<'_>, id: u8) -> Vec<(u8, Result<i64, OpError>)> {
    let profile = dev.profile;
    let mut out = Vec::new();
    for p in profile
        .params
        .iter()
        .filter(|p| p.access == Access::ReadOnly)
    {
        out.push((p.id, read_param(dev, id, p)));
    }
    match read_block(dev, id) {
        Ok(block) => out.extend(block.into_iter().map(|(pid, v)| (pid, Ok(v)))),
        Err(e) => out.extend(profile.block_params().map(|p| (p.id, Err(e.clone())))),
    }
    out
}

/// Writes each of `values` (raw, by `data_id`) to servo `id` with [`write_param`], each read
/// back. A failed or mismatched write does not stop the others; a cancel stops between
/// parameters. Returns each parameter's check, or why it failed, in order.
pub fn write_params(
    dev: Device<'_>,
    id: u8,
    values: &[(u8, i64)],
    run: &mut Run<'_>,
) -> Vec<(u8, Result<Check, OpError>)> {
    let profile = dev.profile;
    let mut checks = Vec::new();
    for (i, (pid, raw)) in values.iter().enumerate() {
        if run.is_cancelled() {
            break;
        }
        let Some(p) = profile.param(*pid) else {
            continue;
        };
        run.report(Progress {
            done: i as u64,
            total: values.len() as u64,
            message: p.field.name.clone(),
        });
        checks.push((*pid, write_param(dev, id, p, Input::Raw(Value::Int(*raw)))));
    }
    checks
}
