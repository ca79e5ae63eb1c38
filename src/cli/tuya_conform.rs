//! `botbench tuya conform`: grades the MCU's firmware against the protocol
//! ([`crate::ops::tuya::conform`]), prints the table of checks (or one JSON document) and
//! records the run; exit 0 only when every mandatory check passes.

use super::CliResult;
use super::port::{PortArgs, op_error};
use super::records::RecordArgs;
use crate::ops::tuya::conform::{self, Check, Conformance, Grade};
use crate::ops::{Device, Run};
use crate::profile::Profile;
use std::path::PathBuf;

/// `tuya conform`'s options.
#[derive(Debug, clap::Args)]
pub(crate) struct ConformArgs {
    /// Also grade a firmware update with this image (it must come back naming its version).
    #[arg(long, value_name = "FILE")]
    ota: Option<PathBuf>,
    /// With --ota: the version the MCU must report after it, x.y.z (each 0 to 99); default: the
    /// one version string the image holds.
    #[arg(long, value_name = "X.Y.Z", value_parser = super::sim::version, requires = "ota")]
    expect_version: Option<String>,
    /// With --ota: how long the MCU may take to come back, 1 to 600 seconds (Tuya's rule: 60).
    #[arg(long, default_value_t = 60, value_parser = super::checks::handshake_s)]
    restart_wait: u64,
    #[command(flatten)]
    rec: RecordArgs,
}

/// Runs the grade on the port (without the module's own session: the checks drive the MCU).
pub(crate) fn run(
    args: &ConformArgs,
    port: &PortArgs,
    profile: &std::sync::Arc<Profile>,
) -> CliResult {
    let json = port.json;
    let mut options = conform::Options {
        ota: None,
        ota_max: profile.ota_max_bytes(),
    };
    if let Some(file) = &args.ota {
        let update = super::tuya::read_update(
            file,
            args.expect_version.as_deref(),
            args.restart_wait,
            profile,
        )?;
        options.ota = Some(update);
    }
    let mut recorder = args.rec.open(json)?;
    let given = args.rec.given(None);
    if let Some((serial, _)) = &given.serial {
        super::records::say_history(&mut recorder, &profile.id, serial, json);
    }
    let link = port.open_with(profile.clone(), false)?;
    let client = link.client();
    let cancel = super::port::cancel_on_ctrl_c();
    if !json {
        outln!("{:<18} {:<4}  {:<9} DETAIL / EVIDENCE", "CHECK", "", "KIND");
    }
    let recorded = crate::ops::records::runs::tuya_conform(
        Device::new(&client, profile),
        &options,
        &given,
        &mut Run::quiet(&cancel),
        &mut |c| {
            if !json {
                print_check(c);
            }
        },
        &mut recorder,
    );
    let kept = super::records::say_kept(&recorded.kept, json);
    let grade = recorded.outcome.map_err(op_error)?;
    if json {
        outln!("{}", serde_json::to_string(&grade).unwrap_or_default());
    } else {
        print_verdict(&grade);
    }
    kept?;
    Ok(u8::from(!grade.pass()))
}

/// One row: id, grade, mandatory or advisory, the detail, then the evidence indented below.
fn print_check(c: &Check) {
    let kind = if c.mandatory { "mandatory" } else { "advisory" };
    outln!("{:<18} {:<4}  {kind:<9} {}", c.id, c.grade.word(), c.detail);
    if !c.evidence.is_empty() && c.grade != Grade::Pass {
        outln!("{:<35}{}", "", c.evidence);
    }
}

/// The verdict under the table.
fn print_verdict(grade: &Conformance) {
    let failed = grade.failed();
    let mandatory = failed.iter().filter(|c| c.mandatory).count();
    let who = match (&grade.pid, &grade.version) {
        (Some(p), Some(v)) => format!("{p} {v}"),
        _ => "the firmware".to_string(),
    };
    if mandatory == 0 {
        outln!(
            "CONFORMS: {who} passes every mandatory check ({} advisory not met) in {:.1} s",
            failed.len(),
            grade.seconds
        );
    } else {
        let ids: Vec<&str> = failed
            .iter()
            .filter(|c| c.mandatory)
            .map(|c| c.id)
            .collect();
        outln!(
            "DOES NOT CONFORM: {who} fails {mandatory} mandatory check(s): {} ({:.1} s)",
            ids.join(", "),
            grade.seconds
        );
    }
}
