//! `botbench tuya`: botbench as the Wi-Fi module of a Tuya MCU.

use super::port::{PortArgs, op_error, parse_assignments, print_checks};
use super::{CliError, CliResult};
use crate::link::session::tuya::TuyaEvent;
use crate::link::{LinkEvent, LinkState};
use crate::ops::tuya as ops;
use crate::profile::{Profile, Protocol};
use clap::Subcommand;
use std::path::PathBuf;
use std::time::{Duration, Instant};

#[derive(Debug, clap::Args)]
pub(crate) struct TuyaArgs {
    #[command(flatten)]
    port: PortArgs,
    /// How long to wait for the start-up handshake, 1 to 600 seconds.
    #[arg(long, default_value_t = 10, value_parser = super::checks::handshake_s)]
    wait: u64,
    #[command(subcommand)]
    cmd: TuyaCmd,
}

#[derive(Debug, Subcommand)]
enum TuyaCmd {
    /// Run the module's start-up handshake and show each step.
    Init,
    /// Query every data point (0x08).
    Status,
    /// Send data points (0x06) and check what the MCU reports back; exit 1 on a mismatch.
    Dp {
        /// NAME=VALUE for each data point.
        #[arg(value_name = "NAME=VALUE", required = true)]
        values: Vec<String>,
    },
    /// Update the MCU's firmware with FILE.
    Ota {
        /// The firmware image.
        file: PathBuf,
    },
}

/// Waits for the handshake, printing its steps when asked; the error names the step it stopped at.
fn handshake(
    link: &crate::link::Link,
    wait: Duration,
    show: bool,
    json: bool,
) -> Result<(), CliError> {
    let deadline = Instant::now() + wait;
    let mut last_failed: Option<String> = None;
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        let ev = match link.events().recv_timeout(left) {
            Ok(ev) => ev,
            Err(_) => {
                return Err(CliError::device(match last_failed {
                    Some(s) => format!("handshake stopped at {s}"),
                    None => "the MCU never answered a heartbeat".to_string(),
                }));
            }
        };
        match ev {
            LinkEvent::Tuya(TuyaEvent::Step { step, ok, detail }) => {
                if json && show {
                    println!(
                        "{}",
                        serde_json::json!({"step": step, "ok": ok, "detail": detail})
                    );
                } else if show {
                    println!(
                        "{:<14} {}  {detail}",
                        format!("{step:?}"),
                        if ok { "ok  " } else { "FAIL" }
                    );
                }
                if !ok {
                    last_failed = Some(format!("{step:?}: {detail}"));
                }
            }
            LinkEvent::Tuya(TuyaEvent::HandshakeDone) => return Ok(()),
            LinkEvent::State(LinkState::Lost { reason }) => {
                return Err(CliError::device(format!("link lost: {reason}")));
            }
            _ => {}
        }
    }
}

fn print_reports(profile: &Profile, reports: &[crate::packet::Packet], json: bool) {
    let values = ops::report_values(profile, reports);
    if json {
        let doc: Vec<_> = values
            .iter()
            .map(|(k, v)| serde_json::json!({"dp": k, "value": v}))
            .collect();
        println!("{}", serde_json::json!({"data_points": doc}));
        return;
    }
    for (k, v) in &values {
        let shown = profile.find_data_point(k).map_or(format!("{v:?}"), |d| {
            format!("{}{}", d.field.format(v), d.field.unit_suffix())
        });
        println!("{k:<20} {shown}");
    }
}

pub(crate) fn run(args: TuyaArgs) -> CliResult {
    let json = args.port.json;
    // Everything given is checked before the port is opened (and the handshake run).
    let profile = args.port.profile("tuya-vacuum", Protocol::Tuya)?;
    let mut image = Vec::new();
    let mut inputs = Vec::new();
    match &args.cmd {
        TuyaCmd::Ota { file } => {
            image = crate::document::read_bytes(file, crate::document::Limit::FIRMWARE)
                .map_err(CliError::input)?;
            if image.is_empty() {
                return Err(CliError::input(format!(
                    "{}: the firmware file is empty",
                    file.display()
                )));
            }
        }
        TuyaCmd::Dp { values } => {
            inputs = parse_assignments(values, "NAME")?;
            ops::set_dps_request(&profile, &inputs).map_err(op_error)?;
        }
        TuyaCmd::Init | TuyaCmd::Status => {}
    }
    let link = args.port.open_with(profile.clone(), true)?;
    let wait = Duration::from_secs(args.wait);
    handshake(&link, wait, matches!(args.cmd, TuyaCmd::Init), json)?;
    let client = link.client();
    match args.cmd {
        TuyaCmd::Init => {
            if !json {
                println!("handshake done");
            }
            Ok(0)
        }
        TuyaCmd::Status => {
            let reports = ops::query(&client).map_err(op_error)?;
            print_reports(&profile, &reports, json);
            Ok(0)
        }
        TuyaCmd::Dp { .. } => {
            let checks = ops::set_dps(&client, &profile, &inputs).map_err(op_error)?;
            let field_of = |ident: &str| profile.find_data_point(ident).map(|d| d.field.clone());
            Ok(print_checks(&checks, field_of, json))
        }
        TuyaCmd::Ota { .. } => {
            let mut last_pct = 0;
            let report = ops::ota(
                &client,
                &image,
                ops::OtaTiming::default(),
                &super::port::cancel_on_ctrl_c(),
                &mut |p| {
                    let pct = (p.fraction() * 100.0) as u32;
                    if !json && pct >= last_pct + 10 {
                        last_pct = pct;
                        eprintln!("{pct:3}%  {}", p.message);
                    }
                },
            )
            .map_err(op_error)?;
            if json {
                println!("{}", serde_json::to_string(&report).unwrap_or_default());
            } else {
                println!(
                    "sent {} bytes in {} packets of {} in {:.1} s ({} retries)",
                    report.size, report.packets, report.packet_size, report.seconds, report.retries
                );
            }
            Ok(0)
        }
    }
}
