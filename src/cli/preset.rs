//! `botbench preset`: save a device's tunable parameters to a file, compare, and write them back.

use super::port::{PortArgs, op_error, print_checks};
use super::{CliError, CliResult};
use crate::link::{DeviceInfo, Link, PortOpener};
use crate::ops::{self, Cancel};
use crate::ops::{Device, Run};
use crate::preset::{self, Preset};
use crate::profile::{Profile, Protocol};
use clap::Subcommand;
use std::path::PathBuf;
use std::sync::Arc;

/// The profile used when `--profile` is not given.
const DEFAULT_PROFILE: &str = "window-cleaner";

#[derive(Debug, Subcommand)]
pub(crate) enum PresetCmd {
    /// Read every tunable parameter from the device and write them to FILE.
    Save {
        /// The preset file to write (.ron); replaced if it exists.
        file: PathBuf,
        /// A note stored in the file (what it is for, who made it).
        #[arg(long, default_value = "")]
        note: String,
        #[command(flatten)]
        port: PortArgs,
    },
    /// Compare FILE with the device; exit 1 if anything differs.
    Diff {
        /// The preset file.
        file: PathBuf,
        #[command(flatten)]
        port: PortArgs,
    },
    /// Check FILE, then write it to the device and read every value back; exit 1 on a mismatch.
    Apply {
        /// The preset file.
        file: PathBuf,
        #[command(flatten)]
        port: PortArgs,
        #[command(flatten)]
        rec: super::records::RecordArgs,
    },
}

pub(crate) fn run(cmd: PresetCmd, ports: &PortOpener) -> CliResult {
    match cmd {
        PresetCmd::Save { file, note, port } => save(&file, &note, &port.with_ports(ports)),
        PresetCmd::Diff { file, port } => diff(&file, &port.with_ports(ports)),
        PresetCmd::Apply { file, port, rec } => apply(&file, &port.with_ports(ports), &rec),
    }
}

/// Loads and checks the preset before the port is opened: a bad file is exit 2.
fn load(file: &std::path::Path, port: &PortArgs) -> Result<(Preset, Arc<Profile>), CliError> {
    let profile = port.profile(DEFAULT_PROFILE, Protocol::Msp)?;
    let loaded = Preset::load(file, &profile).map_err(CliError::input)?;
    Ok((loaded.preset, profile))
}

/// Opens the port and waits for the session to learn the device (its code) from CMD_VERSION.
fn connect(port: &PortArgs, profile: Arc<Profile>) -> Result<(Link, DeviceInfo), CliError> {
    let link = port.open_with(profile, true)?;
    let info = link
        .client()
        .device_info()
        .map_err(|e| CliError::device(format!("no answer to CMD_VERSION: {e}")))?;
    Ok((link, info))
}

fn save(file: &std::path::Path, note: &str, port: &PortArgs) -> CliResult {
    // The profile and the destination are checked before the device is read: a file that
    // cannot be written is bad input (exit 2), found before the whole device is read for it.
    let profile = port.profile(DEFAULT_PROFILE, Protocol::Msp)?;
    if preset::preset_commands(&profile).is_empty() {
        return Err(CliError::input(format!(
            "profile '{}' has no Set commands with a Get to read them back: nothing to save",
            profile.id
        )));
    }
    crate::document::check_destination(file).map_err(CliError::input)?;
    let (link, info) = connect(port, profile.clone())?;
    let mut captured = ops::preset::capture(
        Device::new(&link.client(), &profile),
        &mut Run::quiet(&Cancel::new()),
    )
    .map_err(op_error)?;
    captured.note = note.to_string();
    captured.device = Some(ops::device::short_description(&info));
    // Still the destination's fault if it fails now (a full disk): exit 2, the device is fine.
    captured
        .save_annotated(file, &profile)
        .map_err(CliError::input)?;
    let fields: usize = captured.values.iter().map(|c| c.fields.len()).sum();
    if port.json {
        outln!(
            "{}",
            serde_json::json!({
                "file": file.display().to_string(), "profile": profile.id,
                "device": captured.device, "commands": captured.values.len(), "fields": fields,
            })
        );
    } else {
        outln!(
            "saved {} commands ({fields} fields) from {} to {}",
            captured.values.len(),
            captured.device.as_deref().unwrap_or("the device"),
            file.display()
        );
    }
    Ok(0)
}

fn diff(file: &std::path::Path, port: &PortArgs) -> CliResult {
    let (preset, profile) = load(file, port)?;
    let (link, _) = connect(port, profile.clone())?;
    let device = ops::preset::read_device(
        Device::new(&link.client(), &profile),
        &mut Run::quiet(&Cancel::new()),
    )
    .map_err(op_error)?;
    let rows = preset.diff(&profile, &device);
    let differing = rows.iter().filter(|r| r.differs).count();
    if port.json {
        outln!(
            "{}",
            serde_json::json!({ "same": differing == 0, "differing": differing, "rows": rows })
        );
    } else {
        outln!(
            "{:<36} {:<22} {:>10} {:>10}",
            "command",
            "field",
            "preset",
            "device"
        );
        for r in &rows {
            outln!(
                "{:<36} {:<22} {:>10} {:>10}{}",
                r.command,
                r.field,
                r.preset,
                r.device.as_deref().unwrap_or("-"),
                if r.differs { "  DIFFERS" } else { "" }
            );
        }
        if differing == 0 {
            outln!("the device holds the preset ({} fields)", rows.len());
        } else {
            outln!("{differing} of {} fields differ", rows.len());
        }
    }
    Ok(u8::from(differing > 0))
}

fn apply(file: &std::path::Path, port: &PortArgs, rec: &super::records::RecordArgs) -> CliResult {
    let (preset, profile) = load(file, port)?;
    let mut recorder = rec.open(port.json)?;
    let given = rec.given(Some(file));
    let (link, _) = connect(port, profile.clone())?;
    if let Some((serial, _)) = &given.serial {
        super::records::say_history(&mut recorder, &profile.id, serial, port.json);
    }
    let mut results = Vec::new();
    let json = port.json;
    let recorded = crate::ops::records::runs::preset_apply(
        Device::new(&link.client(), &profile),
        &preset,
        &given,
        &mut Run::quiet(&super::port::cancel_on_ctrl_c()),
        &mut |command, checks| {
            if !json {
                outln!("{command}");
                let set = profile.command(command);
                let field_of = |ident: &str| {
                    set.and_then(|s| s.request.iter().find(|f| f.ident == ident))
                        .cloned()
                };
                print_checks(checks, field_of, false);
            }
            results.push((command.to_string(), checks.to_vec()));
        },
        &mut recorder,
    );
    let outcome = recorded.outcome.map(|_| ());
    let bad = results
        .iter()
        .flat_map(|(_, c)| c)
        .filter(|c| !c.ok())
        .count();
    if json {
        let mut doc = serde_json::json!({
            "verified": bad == 0 && outcome.is_ok(),
            "commands": results.iter().map(|(command, checks)| serde_json::json!({
                "command": command,
                "fields": checks.iter().map(|c| serde_json::json!({
                    "field": c.field, "written": c.written, "read": c.read, "ok": c.ok(),
                })).collect::<Vec<_>>(),
            })).collect::<Vec<_>>(),
        });
        // An apply that stopped (cancelled, the link lost) or whose record could not be kept
        // is still one document: what was written and checked, and why it failed, as every
        // --json failure says it.
        let kept = super::records::say_kept(&recorded.kept, json);
        let failed = match outcome {
            Err(e) => Some(op_error(e)),
            Ok(()) => kept.err(),
        };
        if let (Some(e), Some(fields)) = (&failed, doc.as_object_mut()) {
            fields.insert("error".into(), e.message.clone().into());
            fields.insert("exit".into(), e.code.into());
        }
        outln!("{doc}");
        return Ok(match failed {
            Some(e) => {
                errln!("botbench: {}", e.message);
                e.code
            }
            None => u8::from(bad > 0),
        });
    }
    let kept = super::records::say_kept(&recorded.kept, json);
    outcome.map_err(op_error)?;
    if !json {
        if bad == 0 {
            outln!("applied {}: every field verified", file.display());
        } else {
            outln!("{bad} field(s) MISMATCH: the device does not hold the preset");
        }
    }
    kept?;
    Ok(u8::from(bad > 0))
}
