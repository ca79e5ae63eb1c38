//! Presets on a device: capture one (every presettable Get read, with the device's identity),
//! read the device's values to compare with one, and apply one with read-back verification. The
//! document itself (schema, check, diff, text) is [`crate::preset`].

use super::{Check, FieldValues, OpError, Progress, device, exchange};
use crate::ops::{Device, Run};
use crate::preset::{CommandValues, Preset, display_value, preset_commands};
use crate::profile::{Command, Protocol};

/// The values of `set` in `answer` (its Get's answer), as a preset stores them.
pub fn command_values(set: &Command, answer: &FieldValues) -> CommandValues {
    CommandValues {
        command: set.ident.clone(),
        fields: set
            .request
            .iter()
            .filter_map(|f| Some((f.ident.clone(), display_value(f, answer.get(&f.ident)?))))
            .collect(),
    }
}

/// Reads every presettable Get of the profile, as display values keyed by the Set's ident.
/// Progress follows each command; a cancel stops between commands (`Err(Cancelled)`).
pub fn read_device(dev: Device<'_>, run: &mut Run<'_>) -> Result<Vec<CommandValues>, OpError> {
    let profile = dev.profile;
    let pairs = preset_commands(profile);
    let total = pairs.len() as u64;
    let mut values = Vec::new();
    for (i, (set, get)) in pairs.iter().enumerate() {
        run.go_on()?;
        let answer = exchange::read(dev, get, &[])?;
        values.push(command_values(set, &answer));
        run.report(Progress {
            done: i as u64 + 1,
            total,
            message: crate::i18n::Text::new(
                format!("read {}", get.name.en),
                format!("已读取 {}", get.name.zh),
            ),
        });
    }
    Ok(values)
}

/// Reads every Get command that has a Set partner and returns the values as a preset, keyed by
/// the Set's ident. An MSP device's identity is asked with CMD_VERSION (`hw 0x03 fw 1.4.2`);
/// the preset has none when the device does not say.
pub fn capture(dev: Device<'_>, run: &mut Run<'_>) -> Result<Preset, OpError> {
    let Device { client, profile } = dev;
    let mut preset = Preset::new(&profile.id, "");
    if profile.protocol == Protocol::Msp {
        preset.device = device::identify(client)
            .ok()
            .map(|info| device::short_description(&info));
    }
    preset.values = read_device(dev, run)?;
    Ok(preset)
}

/// Checks `preset` against the profile, then writes each Set command's full payload with
/// [`exchange::write_verified`], reporting progress per command. Returns every read-back check;
/// a mismatch is a check that is not `ok()`, not an error. When cancelled it stops between
/// commands with [`OpError::CancelledAfter`]. A preset that does not fit the profile
/// is refused (`OpError::Document`) before anything is written.
pub fn apply(dev: Device<'_>, preset: &Preset, run: &mut Run<'_>) -> Result<Vec<Check>, OpError> {
    let mut all = Vec::new();
    apply_each(dev, preset, run, &mut |_, checks| {
        all.extend_from_slice(checks)
    })?;
    Ok(all)
}

/// [`apply`], telling `written` each command's checks as it is written. Progress is reported
/// before the first command and after each; a cancel raised then stops before the next command
/// and ends the apply with [`OpError::CancelledAfter`] (what was written and what was not).
pub fn apply_each(
    dev: Device<'_>,
    preset: &Preset,
    run: &mut Run<'_>,
    written: &mut dyn FnMut(&str, &[Check]),
) -> Result<(), OpError> {
    let profile = dev.profile;
    let writes = preset.validate(profile)?;
    let total = writes.len() as u64;
    run.report(Progress {
        done: 0,
        total,
        message: crate::i18n::Text::new("checked; writing", "已检查,正在写入"),
    });
    for (i, w) in writes.iter().enumerate() {
        if run.is_cancelled() {
            let name = |w: &crate::preset::SetWrite| w.command.clone();
            return Err(OpError::cancelled_after(&writes, i, "commands", name));
        }
        let set = profile
            .command(&w.command)
            .ok_or_else(|| OpError::unknown_command(profile, &w.command))?;
        let checks = exchange::write_verified(dev, set, &w.inputs)?;
        written(&set.ident, &checks);
        run.report(Progress {
            done: i as u64 + 1,
            total,
            message: crate::i18n::Text::new(
                format!("wrote {}", set.name.en),
                format!("已写入 {}", set.name.zh),
            ),
        });
    }
    Ok(())
}
