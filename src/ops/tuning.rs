//! A device's parameters as the tuning panel works them: a batch of commands read one after
//! another, and a batch of Set commands written with their full payloads, each read back
//! through its Get.

use super::{Check, FieldValues, OpError, Progress, exchange};
use crate::ops::{Device, Run};
use crate::profile::Input;

/// One Set command to write: its id and every field of its payload.
pub type SetWrite = (u8, Vec<(String, Input)>);

/// How a batch went: commands done, and how many of them failed (a read that failed, or a
/// write that failed or was not verified).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Tally {
    /// Commands in the batch.
    pub total: usize,
    /// Commands done (read, or written and read back).
    pub done: usize,
    /// Commands that failed or were not verified.
    pub failed: usize,
}

/// Reads the commands `ids` (Get or Telemetry, empty request) one after another; `each` sees
/// every result as it comes, and progress follows each command. Ids the profile does not have
/// are skipped. A failed read does not stop the batch; a cancel does, between commands
/// (`Err(Cancelled)`).
pub fn read_commands(
    dev: Device<'_>,
    ids: &[u8],
    run: &mut Run<'_>,
    each: &mut dyn FnMut(u8, Result<FieldValues, OpError>),
) -> Result<Tally, OpError> {
    let profile = dev.profile;
    let mut tally = Tally {
        total: ids.len(),
        ..Tally::default()
    };
    for (i, id) in ids.iter().enumerate() {
        run.go_on()?;
        let Some(cmd) = profile.command_by_id(*id) else {
            continue;
        };
        let r = exchange::read(dev, cmd, &[]);
        tally.done += 1;
        tally.failed += usize::from(r.is_err());
        each(*id, r);
        run.report(Progress {
            done: i as u64 + 1,
            total: ids.len() as u64,
            message: cmd.name.clone(),
        });
    }
    Ok(tally)
}

/// Writes each Set command with its full payload, then reads it back through its Get
/// ([`exchange::write_verified`]); `each` sees every command's checks (or why it failed) as they
/// come. A failed or mismatched write does not stop the batch; a cancel does, between commands
/// ([`OpError::CancelledAfter`]: what was written and what was not, after `each` has seen what
/// was written).
pub fn write_commands(
    dev: Device<'_>,
    writes: &[SetWrite],
    run: &mut Run<'_>,
    each: &mut dyn FnMut(u8, Result<Vec<Check>, OpError>),
) -> Result<Tally, OpError> {
    let profile = dev.profile;
    let mut tally = Tally {
        total: writes.len(),
        ..Tally::default()
    };
    let name = |(id, _): &SetWrite| {
        profile
            .command_by_id(*id)
            .map_or_else(|| format!("command {id}"), |c| c.ident.clone())
    };
    for (i, (set, inputs)) in writes.iter().enumerate() {
        if run.is_cancelled() {
            return Err(OpError::cancelled_after(writes, i, "commands", name));
        }
        let Some(cmd) = profile.command_by_id(*set) else {
            continue;
        };
        let r = exchange::write_verified(dev, cmd, inputs);
        tally.done += 1;
        if !matches!(&r, Ok(checks) if checks.iter().all(Check::ok)) {
            tally.failed += 1;
        }
        each(*set, r);
        run.report(Progress {
            done: i as u64 + 1,
            total: writes.len() as u64,
            message: cmd.name.clone(),
        });
    }
    Ok(tally)
}

/// Sends command `id` (an action) with `inputs`, checked against the profile first, and waits
/// for its acknowledgement. Returns the command's ident.
pub fn send_command(
    dev: Device<'_>,
    id: u8,
    inputs: &[(String, Input)],
) -> Result<String, OpError> {
    let profile = dev.profile;
    let cmd = profile
        .command_by_id(id)
        .ok_or_else(|| OpError::unknown_command(profile, id))?;
    exchange::send(dev, cmd, inputs)?;
    Ok(cmd.ident.clone())
}
