//! `botbench tuya`: botbench as the Wi-Fi module of a Tuya MCU.

use super::port::{PortArgs, op_error, parse_assignments};
use super::{CliError, CliResult};
use crate::link::session::tuya::{HandshakeStep, TuyaEvent, version_text};
use crate::link::{LinkEvent, LinkState, PortOpener};
use crate::ops::tuya::{self as ops, DpCheck, ReportedDp, Status};
use crate::ops::{Device, Progress, Run};
use crate::profile::{Profile, Protocol, Value};
use clap::Subcommand;
use serde_json::json;
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
    /// Query every data point (0x08); exit 1 if one is missing or does not fit the profile.
    Status,
    /// Send data points (0x06) and verify them by the MCU's reports, read back; exit 1 unless
    /// each is verified.
    Dp {
        /// NAME=VALUE for each data point.
        #[arg(value_name = "NAME=VALUE", required = true)]
        values: Vec<String>,
    },
    /// Update the MCU's firmware with FILE (at most the profile's `ota_max_bytes`).
    Ota {
        /// The firmware image.
        file: PathBuf,
    },
}

/// What the handshake's events said, and where it stands.
#[derive(Debug, Default)]
pub(crate) struct HandshakeWatch {
    /// The last step that went well.
    last_ok: Option<HandshakeStep>,
    /// The last step that failed, with why.
    last_failed: Option<String>,
    /// The version byte of the MCU's frames.
    pub(crate) frame_version: Option<u8>,
}

impl HandshakeWatch {
    /// Takes an event; a step's result is printed when `show`.
    fn on_event(&mut self, ev: &TuyaEvent, show: bool, json: bool) {
        match ev {
            TuyaEvent::Step { step, result } => {
                let ok = result.ok();
                if json && show {
                    outln!(
                        "{}",
                        json!({"step": step, "ok": ok, "detail": result.to_string()})
                    );
                } else if show {
                    outln!(
                        "{:<14} {}  {result}",
                        format!("{step:?}"),
                        if ok { "ok  " } else { "FAIL" },
                    );
                }
                if ok {
                    self.last_ok = Some(*step);
                } else {
                    self.last_failed = Some(format!("{step:?}: {result}"));
                }
            }
            TuyaEvent::FrameVersion { version } => self.frame_version = Some(*version),
            _ => {}
        }
    }

    /// Why the handshake did not finish within `wait`: the step that failed last, or the one
    /// under way (the one after the last that went well).
    fn stalled(&self, wait: Duration) -> String {
        if let Some(f) = &self.last_failed {
            return format!("handshake stopped at {f}");
        }
        let next = match self.last_ok {
            None => return "the MCU never answered a heartbeat".to_string(),
            Some(s) => HandshakeStep::ALL
                .iter()
                .position(|x| *x == s)
                .and_then(|i| HandshakeStep::ALL.get(i + 1)),
        };
        match next {
            Some(step) => format!(
                "the handshake stalled at {step:?}: not done within {} s (the steps before it went well)",
                wait.as_secs()
            ),
            None => "the handshake did not finish".to_string(),
        }
    }
}

/// Waits for the handshake, printing its steps when asked; the error names the step it
/// stopped or stalled at.
fn handshake(
    link: &crate::link::Link,
    wait: Duration,
    show: bool,
    json: bool,
) -> Result<HandshakeWatch, CliError> {
    let deadline = Instant::now() + wait;
    let mut watch = HandshakeWatch::default();
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        let Ok(ev) = link.events().recv_timeout(left) else {
            return Err(CliError::device(watch.stalled(wait)));
        };
        match ev {
            LinkEvent::Tuya(TuyaEvent::HandshakeDone) => return Ok(watch),
            LinkEvent::Tuya(ev) => watch.on_event(&ev, show, json),
            LinkEvent::State(LinkState::Lost { reason }) => {
                return Err(CliError::device(format!("link lost: {reason}")));
            }
            _ => {}
        }
    }
}

/// A raw value as the data point's field shows it, with its unit.
fn shown(profile: &Profile, id: u8, v: &Value) -> String {
    profile.data_point(id).map_or(format!("{v:?}"), |d| {
        format!("{}{}", d.field.format(v), d.field.unit_suffix())
    })
}

/// A report as JSON: `dp`, `id`, `value` (raw units, or null), `raw`, `misfit`, `mismatch`.
fn report_json(r: &ReportedDp) -> serde_json::Value {
    let mut doc = serde_json::to_value(r).unwrap_or_default();
    doc["dp"] = json!(r.ident);
    doc["mismatch"] = json!(r.misfit.as_ref().map(ToString::to_string));
    doc
}

fn print_status(profile: &Profile, status: &Status, version: Option<u8>, json: bool) {
    let name = |id: u8| {
        profile
            .data_point(id)
            .map_or(id.to_string(), |d| format!("{} ({id})", d.field.ident))
    };
    if json {
        let doc = json!({
            "frame_version": version,
            "complete": status.complete(),
            "queries": status.queries,
            "data_points": status.data_points.iter().map(report_json).collect::<Vec<_>>(),
            "missing": status.missing.iter().map(|id| json!({
                "id": id, "dp": profile.data_point(*id).map(|d| &d.field.ident),
            })).collect::<Vec<_>>(),
        });
        outln!("{doc}");
        return;
    }
    if let Some(v) = version {
        outln!("{}", version_text(v));
    }
    for d in &status.data_points {
        match &d.misfit {
            None => outln!("{:<20} {}", d.name(), d.shown(profile)),
            Some(_) => outln!("{:<20} MISFIT {}", d.name(), d.shown(profile)),
        }
    }
    if !status.missing.is_empty() {
        let names: Vec<String> = status.missing.iter().map(|id| name(*id)).collect();
        outln!(
            "not reported after {} status queries: {}",
            status.queries,
            names.join(", ")
        );
    }
}

fn print_checks(profile: &Profile, checks: &[DpCheck], json: bool) -> u8 {
    let bad = checks.iter().filter(|c| !c.verified()).count();
    if json {
        let doc = json!({
            "verified": bad == 0,
            "data_points": checks.iter().map(|c| json!({
                "dp": c.ident, "id": c.id, "sent": c.sent, "ok": c.verified(),
                "reports": c.reports, "last": c.last.as_ref().map(report_json),
            })).collect::<Vec<_>>(),
        });
        outln!("{doc}");
    } else {
        for c in checks {
            let sent = shown(profile, c.id, &c.sent);
            let verdict = match &c.last {
                _ if c.verified() => "verified".to_string(),
                Some(r) => format!("MISMATCH: the MCU reports {}", r.shown(profile)),
                None => "NOT VERIFIED: the MCU reported nothing of it after the command".into(),
            };
            outln!("{:<20} {sent:>12}  {verdict}", c.ident);
        }
    }
    u8::from(bad > 0)
}

pub(crate) fn run(mut args: TuyaArgs, ports: &PortOpener) -> CliResult {
    args.port = args.port.with_ports(ports);
    let json = args.port.json;
    // Everything given is checked before the port is opened (and the handshake run): an image
    // is read, bounded by the profile's largest; data points are encoded against the profile.
    let profile = args.port.profile("tuya-vacuum", Protocol::Tuya)?;
    let mut image = Vec::new();
    let mut inputs = Vec::new();
    match &args.cmd {
        TuyaCmd::Ota { file } => {
            image = ops::read_image(file, profile.ota_max_bytes()).map_err(CliError::input)?;
        }
        TuyaCmd::Dp { values } => {
            inputs = parse_assignments(values, "NAME")?;
            ops::set_dps_request(&profile, &inputs).map_err(op_error)?;
        }
        TuyaCmd::Init | TuyaCmd::Status => {}
    }
    let link = args.port.open_with(profile.clone(), true)?;
    let wait = Duration::from_secs(args.wait);
    let watch = handshake(&link, wait, matches!(args.cmd, TuyaCmd::Init), json)?;
    let client = link.client();
    match args.cmd {
        TuyaCmd::Init => {
            if json {
                outln!(
                    "{}",
                    json!({"done": true, "frame_version": watch.frame_version})
                );
            } else {
                if let Some(v) = watch.frame_version {
                    outln!("{}", version_text(v));
                }
                outln!("handshake done");
            }
            Ok(0)
        }
        TuyaCmd::Status => {
            let status = ops::query_status(Device::new(&client, &profile)).map_err(op_error)?;
            print_status(&profile, &status, watch.frame_version, json);
            Ok(u8::from(!status.complete()))
        }
        TuyaCmd::Dp { .. } => {
            let checks = ops::set_dps(Device::new(&client, &profile), &inputs).map_err(op_error)?;
            Ok(print_checks(&profile, &checks, json))
        }
        TuyaCmd::Ota { .. } => {
            errln!(
                "firmware: {}",
                ops::expected_text(image.len() as u64, link_baud(&args.port, &profile))
            );
            let mut last_pct = 0;
            let report = ops::ota(
                &client,
                &image,
                profile.ota_max_bytes(),
                ops::OtaTiming::default(),
                &mut Run::new(&super::port::cancel_on_ctrl_c(), |p: Progress| {
                    let pct = (p.fraction() * 100.0) as u32;
                    if !json && pct >= last_pct + 10 {
                        last_pct = pct;
                        errln!("{pct:3}%  {}", p.message.en);
                    }
                }),
            )
            .map_err(op_error)?;
            if json {
                outln!("{}", serde_json::to_string(&report).unwrap_or_default());
            } else {
                outln!(
                    "sent {} bytes in {} packets of {} in {:.1} s ({} retries)",
                    report.size,
                    report.packets,
                    report.packet_size,
                    report.seconds,
                    report.retries
                );
            }
            Ok(0)
        }
    }
}

/// The port's rate: `--baud`, else the profile's.
fn link_baud(port: &PortArgs, profile: &Profile) -> u32 {
    port.baud.unwrap_or(profile.baud)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::StepResult;

    fn step(step: HandshakeStep, ok: bool) -> TuyaEvent {
        let result = if ok {
            StepResult::WifiStateNotNeeded
        } else {
            StepResult::Failed(crate::link::ExchangeError::Timeout {
                command: step.command(),
                attempts: 1,
                waited_ms: 300,
            })
        };
        TuyaEvent::Step { step, result }
    }

    #[test]
    fn a_handshake_that_does_not_finish_names_the_step_it_stalled_at() {
        let wait = Duration::from_secs(10);
        let mut w = HandshakeWatch::default();
        assert_eq!(w.stalled(wait), "the MCU never answered a heartbeat");
        for s in &HandshakeStep::ALL[..4] {
            w.on_event(&step(*s, true), false, false);
        }
        assert_eq!(
            w.stalled(wait),
            "the handshake stalled at QueryStatus: not done within 10 s (the steps before it went well)"
        );
        w.on_event(&step(HandshakeStep::QueryStatus, false), false, false);
        assert_eq!(
            w.stalled(wait),
            "handshake stopped at QueryStatus: no answer to command 8 after 1 attempt(s) of 300 ms"
        );
    }
}
