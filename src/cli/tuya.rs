//! `botbench tuya`: botbench as the Wi-Fi module of a Tuya MCU.

use super::port::{PortArgs, op_error, parse_assignments};
use super::{CliError, CliResult, tuya_show};
use crate::link::session::tuya::{HandshakeStep, StepResult, TuyaEvent, version_text};
use crate::link::{LinkEvent, LinkState, PortOpener};
use crate::ops::tuya::{self as ops, Gathered};
use crate::ops::{Device, Progress, Run};
use crate::profile::{Profile, Protocol};
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
    /// Update the MCU's firmware with FILE (at most the profile's `ota_max_bytes`), then wait
    /// for the MCU to restart and name the image's version in its product info (0x01); exit 0
    /// only then.
    Ota {
        /// The firmware image.
        file: PathBuf,
        /// The version the MCU must report after the update, x.y.z (each 0 to 99); default:
        /// the one version string the image holds.
        #[arg(long, value_name = "X.Y.Z", value_parser = super::sim::version)]
        expect_version: Option<String>,
        /// How long the MCU may take, from the last packet, to come back with it, 1 to 600
        /// seconds (Tuya's rule: 60).
        #[arg(long, default_value_t = 60, value_parser = super::checks::handshake_s)]
        restart_wait: u64,
    },
    /// Grade the MCU's firmware against the protocol: a table of checks, PASS or FAIL with the
    /// bytes that show it; exit 0 only when every mandatory check passes. The run is recorded.
    Conform {
        #[command(flatten)]
        args: super::tuya_conform::ConformArgs,
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
    /// The data points the handshake's status query did not hear.
    pub(crate) missing: Vec<u8>,
    /// The reports received during the handshake (its status query's, and any other).
    pub(crate) reports: Vec<crate::packet::Packet>,
    /// The MCU's product info.
    pub(crate) product: Option<crate::link::ProductInfo>,
    /// Frames refused during the handshake (too long, a bad checksum).
    pub(crate) refused: Vec<crate::protocol::FrameError>,
}

impl HandshakeWatch {
    /// Takes an event; a step's result is printed when `show`.
    fn on_event(&mut self, ev: &TuyaEvent, show: bool, json: bool) {
        match ev {
            TuyaEvent::Step { step, result, .. } => {
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
                if let StepResult::Status { missing, .. } = result {
                    // Asked again after the handshake: not where the handshake stopped.
                    self.missing.clone_from(missing);
                    self.last_ok = Some(*step);
                } else if ok {
                    self.last_ok = Some(*step);
                } else {
                    self.last_failed = Some(format!("{step:?}: {result}"));
                }
            }
            TuyaEvent::FrameVersion { version } => self.frame_version = Some(*version),
            TuyaEvent::ProductInfo(info) => self.product = Some(info.clone()),
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
            LinkEvent::Report(p) => watch.reports.push(p),
            LinkEvent::Frame(crate::link::LogEntry {
                frame: Err(e),
                direction: crate::protocol::Direction::DeviceToHost,
                ..
            }) => watch.refused.push(e),
            LinkEvent::State(LinkState::Lost { reason }) => {
                return Err(CliError::device(format!("link lost: {reason}")));
            }
            _ => {}
        }
    }
}

pub(crate) fn run(mut args: TuyaArgs, ports: &PortOpener) -> CliResult {
    args.port = args.port.with_ports(ports);
    let json = args.port.json;
    // Everything given is checked before the port is opened (and the handshake run): an image
    // is read, bounded by the profile's largest; data points are encoded against the profile.
    let profile = args.port.profile("tuya-vacuum", Protocol::Tuya)?;
    let mut image = Vec::new();
    let mut inputs = Vec::new();
    let mut expect = None;
    match &args.cmd {
        TuyaCmd::Ota {
            file,
            expect_version,
            restart_wait,
        } => {
            let (i, e) = read_update(file, expect_version.as_deref(), *restart_wait, &profile)?;
            image = i;
            expect = Some(e);
        }
        TuyaCmd::Dp { values } => {
            inputs = parse_assignments(values, "NAME")?;
            ops::set_dps_request(&profile, &inputs).map_err(op_error)?;
        }
        TuyaCmd::Conform { args: c } => {
            return super::tuya_conform::run(c, &args.port, &profile);
        }
        TuyaCmd::Init | TuyaCmd::Status => {}
    }
    let link = args.port.open_with(profile.clone(), true)?;
    let wait = Duration::from_secs(args.wait);
    let watch = handshake(&link, wait, matches!(args.cmd, TuyaCmd::Init), json)?;
    let client = link.client();
    match args.cmd {
        TuyaCmd::Init => init_done(Device::new(&client, &profile), &watch, json),
        TuyaCmd::Status => {
            let status = ops::query_status(Device::new(&client, &profile)).map_err(op_error)?;
            tuya_show::print_status(&profile, &status, watch.frame_version, json);
            Ok(u8::from(!status.complete()))
        }
        TuyaCmd::Dp { .. } => {
            let checks = ops::set_dps(Device::new(&client, &profile), &inputs).map_err(op_error)?;
            Ok(tuya_show::print_checks(&profile, &checks, json))
        }
        TuyaCmd::Conform { .. } => unreachable!("conform runs without the handshake, above"),
        TuyaCmd::Ota { .. } => {
            errln!(
                "firmware: {}",
                ops::expected_text(image.len() as u64, link_baud(&args.port, &profile))
            );
            let expect = expect.ok_or_else(|| CliError::input("no expected version"))?;
            // Progress is for a person at a terminal; a pipe or --json gets the report alone.
            let show_progress = !json && super::console::stderr_is_terminal();
            let mut last = (0, String::new());
            let report = ops::update(
                &client,
                &image,
                profile.ota_max_bytes(),
                &expect,
                ops::OtaTiming::default(),
                &mut Run::new(&super::port::cancel_on_ctrl_c(), |p: Progress| {
                    let pct = (p.fraction() * 100.0) as u32;
                    if show_progress
                        && (pct >= last.0 + 10 || (pct == 100 && p.message.en != last.1))
                    {
                        last = (pct, p.message.en.clone());
                        errln!("{pct:3}%  {}", p.message.en);
                    }
                }),
            )
            .map_err(op_error)?;
            if json {
                outln!("{}", serde_json::to_string(&report).unwrap_or_default());
            } else {
                print_update(&report);
            }
            Ok(0)
        }
    }
}

/// Reads a firmware image (bounded by the profile's largest) and the version the MCU must
/// report after it: `--expect-version`, else the one x.y.z string the image holds; refused
/// (exit 2, nothing sent) when neither says one.
pub(crate) fn read_update(
    file: &std::path::Path,
    expect_version: Option<&str>,
    restart_wait: u64,
    profile: &Profile,
) -> Result<(Vec<u8>, ops::Expect), CliError> {
    let image = ops::read_image(file, profile.ota_max_bytes()).map_err(CliError::input)?;
    let version = expect_version
        .map(str::to_string)
        .or_else(|| ops::image_version(&image));
    let version = version.ok_or_else(|| {
        CliError::input(format!(
            "{}: the image names no single version (x.y.z); give the one the MCU must report after the update with --expect-version",
            file.display()
        ))
    })?;
    let expect = ops::Expect {
        version,
        limit: Duration::from_secs(restart_wait),
    };
    Ok((image, expect))
}

/// An update's result: what was sent, then the versions before and after and how long the MCU
/// took to come back.
fn print_update(report: &ops::OtaReport) {
    outln!(
        "sent {} bytes in {} packets of {} in {:.1} s ({} retries)",
        report.size,
        report.packets,
        report.packet_size,
        report.seconds,
        report.retries
    );
    outln!(
        "update done: version {} before, {} now; the MCU came back {:.1} s after the last packet",
        report.before_version.as_deref().unwrap_or("unknown"),
        report.after_version.as_deref().unwrap_or("unknown"),
        report.back_seconds.unwrap_or_default()
    );
}

/// After the handshake: the data points its status query did not hear are asked again (a slow
/// MCU's late reports are listened for first, [`ops::gather`]), and every report is read
/// against the profile. Exit 1 when a data point is still missing or does not fit, or a frame
/// was refused: `init` never says done with 7 of 19 data points.
fn init_done(dev: Device<'_>, watch: &HandshakeWatch, json: bool) -> CliResult {
    let profile = dev.profile;
    let mut gathered = Gathered {
        reports: watch.reports.clone(),
        queries: 1,
        between: 0,
        refused: watch.refused.clone(),
    };
    if !watch.missing.is_empty() {
        let more = ops::gather(dev, &watch.missing, ops::QUERIES).map_err(op_error)?;
        gathered.reports.extend(more.reports);
        gathered.queries += more.queries;
        gathered.between += more.between;
        gathered.refused.extend(more.refused);
    }
    let ids = ops::reported_dps(profile);
    let status = ops::status_of(profile, &ids, &gathered);
    if json {
        let mut doc = tuya_show::status_json(profile, &status, watch.frame_version);
        doc["done"] = json!(true);
        outln!("{doc}");
        return Ok(u8::from(!status.complete()));
    }
    if let Some(v) = watch.frame_version {
        outln!("{}", version_text(v));
    }
    let heard = ids.len() - status.missing.len();
    if status.complete() {
        outln!("handshake done; all {heard} data points reported and fit the profile");
        return Ok(0);
    }
    outln!(
        "handshake done; {heard} of {} data points reported, {} do not fit the profile",
        ids.len(),
        status.suspect().len()
    );
    for d in status.suspect() {
        outln!("{:<24} MISFIT {}", d.name(), d.shown(profile));
    }
    tuya_show::print_status_notes(profile, &status);
    Ok(1)
}

/// The port's rate: `--baud`, else the profile's.
fn link_baud(port: &PortArgs, profile: &Profile) -> u32 {
    port.baud.unwrap_or(profile.baud)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn step(step: HandshakeStep, ok: bool) -> TuyaEvent {
        let result = if ok {
            StepResult::WifiStateNotNeeded
        } else {
            StepResult::Failed(crate::link::ExchangeError::Timeout {
                command: step.command().into(),
                attempts: 1,
                waited_ms: 300,
                host_late: None,
            })
        };
        TuyaEvent::Step {
            step,
            result,
            at: std::time::SystemTime::now(),
            took: None,
        }
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
