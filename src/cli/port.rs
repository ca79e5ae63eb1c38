//! What the device subcommands share: the port options, opening a link, printing checks.

use super::{CliError, registry};
use crate::link::{ExchangeError, Link, LinkOptions, serial};
use crate::ops::{Check, OpError};
use crate::profile::{Field, Profile, Protocol};
use clap::Args;
use std::sync::Arc;

/// Port options of every device subcommand.
#[derive(Debug, Args)]
pub(crate) struct PortArgs {
    /// The serial port (e.g. /dev/ttyUSB0, or a /dev/pts path from `botbench sim`).
    #[arg(long, short)]
    pub port: String,
    /// Baud rate (default: the profile's).
    #[arg(long, short)]
    pub baud: Option<u32>,
    /// Device profile name or .ron file.
    #[arg(long)]
    pub profile: Option<String>,
    /// How long the device may take to answer beyond the wire time, in ms (default: the
    /// protocol's: MSP 20, servo 1.5, Tuya 300).
    #[arg(long, value_name = "MS")]
    pub margin_ms: Option<u64>,
    /// MSP polling at the wire's maximum (`watch --rate max`): requests in flight at once. 2
    /// sends the next request while the device still answers; 1 waits for each answer, for
    /// firmware that cannot take a request while it answers.
    #[arg(long, value_name = "N", default_value_t = 2, value_parser = clap::value_parser!(u8).range(1..=4))]
    pub poll_pipeline: u8,
    /// Print JSON.
    #[arg(long, global = true)]
    pub json: bool,
}

impl PortArgs {
    /// Loads the profile, checks its protocol, and opens the port.
    pub fn open(
        &self,
        default_profile: &str,
        protocol: Protocol,
        start_session: bool,
    ) -> Result<(Link, Arc<Profile>), CliError> {
        let profile = self.profile(default_profile, protocol)?;
        let link = self.open_with(profile.clone(), start_session)?;
        Ok((link, profile))
    }

    /// Loads the profile (`--profile`, else `default_profile`) and checks its protocol.
    pub fn profile(
        &self,
        default_profile: &str,
        protocol: Protocol,
    ) -> Result<Arc<Profile>, CliError> {
        let profile = registry()?
            .get(self.profile.as_deref().unwrap_or(default_profile))
            .map_err(CliError::input)?;
        if profile.protocol != protocol {
            return Err(CliError::input(format!(
                "profile '{}' speaks {}, not {}",
                profile.id,
                profile.protocol.name(),
                protocol.name()
            )));
        }
        Ok(profile)
    }

    /// Opens the port with a profile already loaded.
    pub fn open_with(&self, profile: Arc<Profile>, start_session: bool) -> Result<Link, CliError> {
        let baud = self.baud.unwrap_or(profile.baud);
        let options = LinkOptions {
            margin: self.margin_ms.map(std::time::Duration::from_millis),
            reconnect: false,
            start_session,
            poll_pipeline: usize::from(self.poll_pipeline),
            ..LinkOptions::default()
        };
        let link = Link::open(
            serial::opener(&self.port, baud),
            profile.clone(),
            options,
            None,
        )
        .map_err(|e| CliError::input(e.to_string()))?;
        Ok(link)
    }
}

/// Maps an operation's error to an exit code: refused for its input 2, everything else 1.
pub(crate) fn op_error(e: OpError) -> CliError {
    if e.is_input() {
        CliError::input(e)
    } else {
        CliError::device(e)
    }
}

/// Maps a failed exchange to exit code 1.
pub(crate) fn exchange_error(e: ExchangeError) -> CliError {
    CliError::device(e)
}

/// Prints read-back checks; returns exit code 1 if any mismatched.
pub(crate) fn print_checks(
    checks: &[Check],
    field_of: impl Fn(&str) -> Option<Field>,
    json: bool,
) -> u8 {
    print_checks_with(checks, field_of, json, None)
}

/// [`print_checks`], with one more member of the JSON document (`extra`: name, value).
pub(crate) fn print_checks_with(
    checks: &[Check],
    field_of: impl Fn(&str) -> Option<Field>,
    json: bool,
    extra: Option<(&str, serde_json::Value)>,
) -> u8 {
    let bad = checks.iter().filter(|c| !c.ok()).count();
    if json {
        let mut doc = serde_json::json!({
            "verified": bad == 0,
            "fields": checks.iter().map(|c| serde_json::json!({
                "field": c.field, "written": c.written, "read": c.read, "ok": c.ok(),
            })).collect::<Vec<_>>(),
        });
        if let Some((name, value)) = extra {
            doc[name] = value;
        }
        println!("{doc}");
    } else {
        for c in checks {
            let (w, r) = match field_of(&c.field) {
                Some(f) => (f.format(&c.written), f.format(&c.read)),
                None => (format!("{:?}", c.written), format!("{:?}", c.read)),
            };
            if c.ok() {
                println!("{:<24} {w:>12}  verified", c.field);
            } else {
                println!("{:<24} {w:>12}  MISMATCH: device holds {r}", c.field);
            }
        }
        if checks.is_empty() {
            println!("sent and acknowledged (no read-back for this command)");
        }
    }
    u8::from(bad > 0)
}

/// `FIELD=VALUE` arguments as named text inputs.
pub(crate) fn parse_assignments(
    args: &[String],
) -> Result<Vec<(String, crate::profile::Input)>, CliError> {
    args.iter()
        .map(|kv| {
            kv.split_once('=')
                .map(|(k, v)| {
                    (
                        k.trim().to_string(),
                        crate::profile::Input::Text(v.to_string()),
                    )
                })
                .ok_or_else(|| CliError::input(format!("'{kv}' is not FIELD=VALUE")))
        })
        .collect()
}

/// A cancel flag raised by Ctrl-C, so that a long operation stops safely (a motor is stopped, a
/// write is not left half-done and unreported). A second Ctrl-C exits at once.
pub(crate) fn cancel_on_ctrl_c() -> crate::ops::Cancel {
    let cancel = crate::ops::Cancel::new();
    let flag = cancel.clone();
    let result = ctrlc::set_handler(move || {
        if flag.is_cancelled() {
            std::process::exit(130);
        }
        eprintln!("botbench: stopping safely (Ctrl-C again to quit at once)");
        flag.cancel();
    });
    if let Err(e) = result {
        eprintln!("botbench: Ctrl-C will not stop safely: {e}");
    }
    cancel
}
