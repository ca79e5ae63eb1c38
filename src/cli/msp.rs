//! `botbench msp`: the window cleaner and the solar cleanbot from the command line.

use super::checks::{self, Rate};
use super::port::{PortArgs, exchange_error, op_error, parse_assignments, print_checks_with};
use super::{CliError, CliResult};
use crate::link::{Link, LinkCommand, LinkEvent, PortOpener, capabilities};
use crate::ops::{Device, Run};
use crate::packet::Packet;

use crate::ops::exchange::{self as ops, Use};
use crate::ops::selftest::{Operator, Plan};
use crate::profile::{Command, Input, Profile, Protocol};
use crate::protocol::Direction;
use clap::Subcommand;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

#[derive(Debug, clap::Args)]
pub(crate) struct MspArgs {
    #[command(flatten)]
    port: PortArgs,
    /// MSP polling at the wire's maximum (`watch --rate max`): requests in flight at once, 1 to
    /// 4. 2 sends the next request while the device still answers; 1 waits for each answer, for
    /// firmware that cannot take a request while it answers.
    #[arg(long, global = true, value_name = "N", default_value_t = 2, value_parser = clap::value_parser!(u8).range(1..=4))]
    poll_pipeline: u8,
    /// Refuse to send when the device did not identify itself (CMD_VERSION unanswered or
    /// garbled): without it, requests go to the profile's device code, with a warning.
    #[arg(long, global = true)]
    strict: bool,
    #[command(subcommand)]
    cmd: MspCmd,
}

#[derive(Debug, Subcommand)]
enum MspCmd {
    /// Hardware, firmware, API, build and capability flags (CMD_VERSION, CMD_BUILD_INFO).
    Version,
    /// CMD_PING, with the round-trip time.
    Ping,
    /// Send a Get or Telemetry command and print its fields.
    Get {
        /// Command name or number.
        command: String,
    },
    /// Send a Set (or Action) command; a Set is read back through its Get, exit 1 on a mismatch.
    ///
    /// Fields of a Set left out keep the device's current values: its Get is read first, and
    /// the output marks them `kept`.
    Set {
        /// Command name or number.
        command: String,
        /// FIELD=VALUE in display units.
        #[arg(value_name = "FIELD=VALUE")]
        fields: Vec<String>,
    },
    /// Poll Get or Telemetry commands and print each answer as a line.
    Watch {
        /// Command names or numbers.
        #[arg(required = true)]
        commands: Vec<String>,
        /// Polls per second for each command, 0.1 to 1000, or max: as fast as the wire allows
        /// (the default).
        #[arg(long, default_value = "max", value_parser = checks::rate)]
        rate: Rate,
        /// Stop after this many answers, 1 to 1000000000 (default: until Ctrl-C).
        #[arg(long, value_parser = checks::count)]
        count: Option<u64>,
    },
    /// Run a production self-test plan (RON); exit 1 on FAIL. The plan is checked first.
    Selftest {
        /// The plan, e.g. presets/window-cleaner-selftest.ron.
        plan: PathBuf,
        /// Append the report to this JSON-lines file (one JSON document per run).
        #[arg(long, value_name = "FILE")]
        log: Option<PathBuf>,
        /// Answer operator prompts without waiting (unattended runs, e.g. a fixture that
        /// presses the switches).
        #[arg(long)]
        yes: bool,
        #[command(flatten)]
        rec: super::records::RecordArgs,
    },
}

fn command<'p>(profile: &'p Profile, name: &str) -> Result<&'p Command, CliError> {
    profile
        .command(name)
        .ok_or_else(|| super::profiles::unknown_command(profile, name))
}

/// An `msp` subcommand with everything it was given checked, before the port is opened.
enum Checked<'p> {
    Version,
    Ping,
    Get(&'p Command),
    Set(&'p Command, Vec<(String, Input)>),
    Watch {
        commands: Vec<&'p Command>,
        interval: Option<Duration>,
        count: Option<u64>,
    },
    Selftest {
        plan: Box<Plan>,
        log: Option<PathBuf>,
        yes: bool,
        recorder: Box<crate::ops::records::Recorder>,
        given: crate::ops::records::runs::Given,
    },
}

/// Checks every name, value and file of `cmd` against `profile`: the command's kind fits the
/// subcommand, its request can be built, every field given is one of its fields, once, with a
/// value it takes.
fn check<'p>(cmd: &MspCmd, profile: &'p Profile) -> Result<Checked<'p>, CliError> {
    Ok(match cmd {
        MspCmd::Version => Checked::Version,
        MspCmd::Ping => Checked::Ping,
        MspCmd::Get { command: name } => {
            let cmd = command(profile, name)?;
            ops::check_kind(profile, cmd, Use::Read).map_err(op_error)?;
            ops::request(profile, cmd, &[], 1).map_err(op_error)?;
            Checked::Get(cmd)
        }
        MspCmd::Set {
            command: name,
            fields,
        } => {
            let cmd = command(profile, name)?;
            let inputs = parse_assignments(fields, "FIELD")?;
            let omitted = ops::check_write(profile, cmd, &inputs).map_err(op_error)?;
            // Given whole (or an action), the request is built now: relations, missing fields.
            if omitted.is_empty() || cmd.kind != crate::profile::CommandKind::Set {
                ops::request(profile, cmd, &inputs, 1).map_err(op_error)?;
            }
            Checked::Set(cmd, inputs)
        }
        MspCmd::Watch {
            commands,
            rate,
            count,
        } => {
            let mut cmds = Vec::new();
            for name in commands {
                let cmd = command(profile, name)?;
                ops::check_kind(profile, cmd, Use::Poll).map_err(op_error)?;
                ops::request(profile, cmd, &[], 1).map_err(op_error)?;
                if cmds.iter().any(|c: &&Command| c.id == cmd.id) {
                    return Err(CliError::input(format!("{} is given twice", cmd.ident)));
                }
                cmds.push(cmd);
            }
            let interval = match rate {
                Rate::Max => None,
                Rate::PerSecond(r) => Some(Duration::from_secs_f64(1.0 / r)),
            };
            Checked::Watch {
                commands: cmds,
                interval,
                count: *count,
            }
        }
        MspCmd::Selftest {
            plan: path,
            log,
            yes,
            rec,
        } => {
            let plan = Plan::load(path, profile).map_err(CliError::input)?;
            if let Some(log) = log {
                crate::document::check_append(log).map_err(CliError::input)?;
            }
            Checked::Selftest {
                plan: Box::new(plan),
                log: log.clone(),
                yes: *yes,
                recorder: Box::new(rec.open(false)?),
                given: rec.given(Some(path)),
            }
        }
    })
}

/// Frames the device sent on its own meanwhile (MSP kind 0xFE), from the link's events.
fn unsolicited(link: &Link) -> Vec<Packet> {
    link.events()
        .try_iter()
        .filter_map(|ev| match ev {
            LinkEvent::Report(p) => Some(p),
            _ => None,
        })
        .collect()
}

/// Unsolicited frames as JSON: each with its command, fields (out-of-range ones marked) and
/// bytes.
fn unsolicited_json(profile: &Profile, frames: &[Packet]) -> serde_json::Value {
    frames
        .iter()
        .map(|p| {
            let fields = p.decode_lenient(profile).map(|d| {
                d.values
                    .iter()
                    .map(|v| {
                        serde_json::json!({
                            "field": v.ident, "value": v.value, "display": v.display(),
                            "out_of_range": v.out_of_range,
                        })
                    })
                    .collect::<Vec<_>>()
            });
            serde_json::json!({
                "kind": "unsolicited",
                "command": p.command_in(profile).map_or(p.command.to_string(), |c| c.ident.clone()),
                "fields": fields,
                "summary": p.summary(profile),
                "bytes": crate::protocol::hex::format(&p.wire),
            })
        })
        .collect()
}

/// Prints frames the device sent on its own (text mode), each as what it is.
fn print_unsolicited(profile: &Profile, frames: &[Packet]) {
    for p in frames {
        outln!("~~ {}", p.summary(profile));
    }
}

/// Prints an answer's fields. A payload that does not fit the layout is shown as such: the
/// fields read before the fault, the fault and the raw bytes; a value outside its field's range
/// is marked. The exit code is then 1. Frames the device sent on its own meanwhile are shown
/// apart, as what they are.
fn print_fields(
    profile: &Profile,
    cmd: &Command,
    payload: &[u8],
    frames: &[Packet],
    json: bool,
) -> u8 {
    let d = profile.decode_lenient(cmd, Direction::DeviceToHost, payload);
    let misfit = d.misfit();
    let out_of_range = d.values.iter().any(|v| v.out_of_range);
    if json {
        let mut doc = serde_json::json!({
            "command": cmd.ident,
            "ok": misfit.is_none() && !out_of_range,
            "fields": d.values.iter().map(|v| serde_json::json!({
                "field": v.ident, "value": v.value, "display": v.display(), "unit": v.field.unit,
                "out_of_range": v.out_of_range,
            })).collect::<Vec<_>>(),
        });
        if !frames.is_empty() {
            doc["unsolicited"] = unsolicited_json(profile, frames);
        }
        if let Some(m) = &misfit {
            doc["error"] = serde_json::json!(m.fault.to_string());
            doc["payload"] = serde_json::json!(crate::protocol::hex::format(&m.payload));
            doc["payload_len"] = serde_json::json!(m.payload.len());
            doc["expected_len"] = serde_json::json!({"min": m.expected.0, "max": m.expected.1});
        }
        outln!("{}", super::port::with_warnings(doc));
    } else {
        print_unsolicited(profile, frames);
        for v in &d.values {
            outln!("{:<24} {}", v.ident, v.display());
        }
        if let Some(m) = &misfit {
            outln!(
                "!! {}-byte answer where the layout takes {}: {}\n!! payload = {}",
                m.payload.len(),
                m.expected_text(),
                m.fault,
                crate::protocol::hex::format(&m.payload)
            );
        }
    }
    u8::from(misfit.is_some() || out_of_range)
}

/// The profile of the MSP device on the port, when `--profile` does not name one: the device
/// identifies itself (CMD_VERSION's hardware code: 0x03 the window cleaner, 0x04 the solar
/// cleanbot), and the first profile claiming that code is used, said on stderr. What was given
/// is checked first against `default` and, where it does not fit, against every MSP profile:
/// input no MSP profile takes is refused before the port is opened. A device that does not
/// identify keeps `default`. Returns the profile, and the link it was identified on when that
/// is `default`'s. Errors: bad input (2); a hardware code no profile claims (1, with the
/// profiles and their codes).
fn following_the_device(
    args: &MspArgs,
    default: Arc<Profile>,
) -> Result<(Arc<Profile>, Option<Link>), CliError> {
    let reg = super::registry()?;
    let msp: Vec<&Arc<Profile>> = reg
        .iter()
        .map(|(p, _)| p)
        .filter(|p| p.protocol == Protocol::Msp)
        .collect();
    if let Err(e) = check(&args.cmd, &default)
        && !msp.iter().any(|p| check(&args.cmd, p).is_ok())
    {
        return Err(e);
    }
    let (Some(info), link) = args.port.identify(default.clone())? else {
        return Ok((default, None));
    };
    let claims = |p: &Profile| p.device_code.map(crate::profile::DeviceCode::initial);
    if claims(&default) == Some(info.hw) {
        return Ok((default, Some(link)));
    }
    match msp.iter().find(|p| claims(p) == Some(info.hw)) {
        // What was given is for the default's device: the link refuses to send it to another
        // kind, and says why (issue 25, 4d).
        Some(p) if check(&args.cmd, p).is_err() && check(&args.cmd, &default).is_ok() => {
            Ok((default, Some(link)))
        }
        Some(p) => {
            errln!(
                "botbench: the device identifies as hardware {:#04x}: using profile {} ({}; \
                 --profile chooses another)",
                info.hw,
                p.id,
                p.name.en
            );
            drop(link);
            Ok((Arc::clone(p), None))
        }
        None => {
            let known: Vec<String> = msp
                .iter()
                .filter_map(|p| claims(p).map(|c| format!("{} {c:#04x}", p.id)))
                .collect();
            Err(CliError::device(format!(
                "the device identifies as hardware {:#04x}, which no profile claims (profiles \
                 and their hardware codes: {}); give its profile with --profile FILE.ron \
                 (`botbench profiles show window-cleaner` shows what a profile holds)",
                info.hw,
                known.join(", ")
            )))
        }
    }
}

pub(crate) fn run(mut args: MspArgs, ports: &PortOpener) -> CliResult {
    args.port = args.port.with_ports(ports);
    args.port.poll_pipeline = args.poll_pipeline;
    let json = args.port.json;
    // Everything given is checked before the port is opened.
    let profile = args.port.profile("window-cleaner", Protocol::Msp)?;
    let (profile, probe) = if args.port.profile.is_none() {
        following_the_device(&args, profile)?
    } else {
        (profile, None)
    };
    let checked = check(&args.cmd, &profile)?;
    let link = match probe {
        Some(link) if args.port.capture.is_none() => link,
        probe => {
            // The port is closed before it is opened again, with the capture.
            drop(probe);
            args.port.open_with(profile.clone(), true)?
        }
    };
    // The session asks CMD_VERSION first, to learn the device code; later requests wait for it.
    let client = link.client();
    let identified = client.device_info();
    // A request without the device's identity goes to the profile's device code: said, or
    // refused with --strict.
    if let (Err(e), Checked::Get(..) | Checked::Set(..) | Checked::Watch { .. }) =
        (&identified, &checked)
    {
        let warning = crate::ops::device::unidentified(&profile, e);
        if args.strict {
            return Err(CliError::device(format!("{warning}: refused (--strict)")));
        }
        super::port::warn(&warning.to_string());
    }
    match checked {
        Checked::Version => match identified {
            Ok(info) => {
                print_version(&profile, &info, json);
                Ok(0)
            }
            Err(e) => Err(exchange_error(e)),
        },
        Checked::Ping => {
            let r = crate::ops::device::ping(Device::new(&client, &profile)).map_err(op_error)?;
            if json {
                outln!(
                    "{}",
                    serde_json::json!({"rtt_ms": r.rtt.as_secs_f64() * 1e3, "attempts": r.attempts})
                );
            } else {
                outln!("answered in {:.2} ms", r.rtt.as_secs_f64() * 1e3);
            }
            Ok(0)
        }
        Checked::Get(cmd) => {
            let reply = ops::send(Device::new(&client, &profile), cmd, &[]).map_err(op_error)?;
            Ok(print_fields(
                &profile,
                cmd,
                reply.payload().unwrap_or_default(),
                &unsolicited(&link),
                json,
            ))
        }
        Checked::Set(cmd, inputs) => {
            let written = ops::write_keeping(Device::new(&client, &profile), cmd, &inputs)
                .map_err(op_error)?;
            let field_of = |ident: &str| cmd.request.iter().find(|f| f.ident == ident).cloned();
            let kept: Vec<&str> = written.kept.iter().map(|(k, _)| k).collect();
            let frames = unsolicited(&link);
            if !json {
                print_unsolicited(&profile, &frames);
            }
            let extra =
                (!frames.is_empty()).then(|| ("unsolicited", unsolicited_json(&profile, &frames)));
            Ok(print_checks_with(
                &written.checks,
                &kept,
                field_of,
                json,
                extra,
            ))
        }
        Checked::Watch {
            commands,
            interval,
            count,
        } => watch(&link, &profile, &commands, interval, count, json),
        Checked::Selftest {
            plan,
            log,
            yes,
            mut recorder,
            given,
        } => selftest_run(
            &client,
            &profile,
            &plan,
            log.as_deref(),
            yes,
            json,
            &mut recorder,
            &given,
        ),
    }
}

fn print_version(profile: &Profile, info: &crate::link::DeviceInfo, json: bool) {
    if json {
        outln!("{}", serde_json::to_string(info).unwrap_or_default());
        return;
    }
    outln!("hardware   {:#04x}", info.hw);
    outln!("firmware   {}", info.firmware);
    outln!("api        {}", info.api);
    outln!("build      {}", info.build);
    outln!("build date {}", info.build_date.as_deref().unwrap_or("-"));
    if let Some(extra) = &info.extra {
        outln!("!! bytes past the profile's CMD_VERSION layout: {extra}");
    }
    match info.flags {
        Some(f) => {
            let bits: Vec<String> = capabilities(profile, f)
                .iter()
                .map(|c| format!("{} {}", c.name.en, yes(c.set)))
                .collect();
            outln!("flags      {f:#04x}: {}", bits.join(", "));
        }
        None => outln!("flags      none (older firmware)"),
    }
}

/// Polls `cmds` and prints each answer as a line, until `count` answers (or the link is lost).
fn watch(
    link: &crate::link::Link,
    profile: &Profile,
    cmds: &[&Command],
    interval: Option<Duration>,
    count: Option<u64>,
    json: bool,
) -> CliResult {
    let polls = cmds
        .iter()
        .map(|c| crate::ops::telemetry::poll(profile, c, interval))
        .collect();
    link.send(LinkCommand::SetPolls(polls));
    let started = Instant::now();
    let mut seen = 0u64;
    let mut failures = 0u64;
    while count.is_none_or(|n| seen < n) {
        let Ok(ev) = link.events().recv() else { break };
        match ev {
            LinkEvent::Telemetry {
                command: id,
                at,
                result,
            } => {
                seen += 1;
                let t = at.duration_since(started).as_secs_f64();
                let Some(cmd) = profile.command_by_id(id) else {
                    continue;
                };
                match result {
                    Ok(p) => {
                        let line = p.summary(profile);
                        if json {
                            outln!(
                                "{}",
                                serde_json::json!({"t": t, "command": cmd.ident, "summary": line})
                            );
                        } else {
                            outln!("{t:9.3} {line}");
                        }
                    }
                    Err(e) => {
                        failures += 1;
                        outln!("{t:9.3} {} !{e}", cmd.ident);
                    }
                }
            }
            LinkEvent::Report(p) => {
                let t = started.elapsed().as_secs_f64();
                if json {
                    let doc = unsolicited_json(profile, std::slice::from_ref(&p));
                    outln!("{}", serde_json::json!({"t": t, "unsolicited": doc[0]}));
                } else {
                    outln!("{t:9.3} ~~ unsolicited: {}", p.summary(profile));
                }
            }
            LinkEvent::State(crate::link::LinkState::Lost { reason }) => {
                return Err(CliError::device(format!("link lost: {reason}")));
            }
            _ => {}
        }
    }
    // A watch that lost some polls says how many at its end (each was said as it failed); it
    // fails only when nothing answered, as a device that did not answer.
    if failures > 0 {
        errln!("botbench: {failures} of {seen} polls had no answer");
    }
    Ok(u8::from(failures > 0 && failures == seen))
}

/// The operator at a terminal: prompts on stderr, Enter on stdin.
struct Console {
    yes: bool,
}

impl Operator for Console {
    fn prompt(&mut self, text: &str) -> bool {
        if self.yes {
            errln!("OPERATOR: {text} (--yes: not waiting)");
            return true;
        }
        err!("OPERATOR: {text}. Press Enter to start, or q and Enter to abort: ");
        let mut line = String::new();
        match super::console::read_line(&mut line) {
            Ok(0) | Err(_) => {
                errln!(
                    "\nbotbench: stdin is closed: no operator to press Enter, so the self-test \
                     stops here; --yes runs it unattended"
                );
                false
            }
            Ok(_) => !line.trim().eq_ignore_ascii_case("q"),
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn selftest_run(
    client: &crate::link::Client,
    profile: &Profile,
    plan: &Plan,
    log: Option<&std::path::Path>,
    yes: bool,
    json: bool,
    recorder: &mut crate::ops::records::Recorder,
    given: &crate::ops::records::runs::Given,
) -> CliResult {
    let cancel = super::port::cancel_on_ctrl_c();
    if let Some((serial, _)) = &given.serial {
        super::records::say_history(recorder, &profile.id, serial, json);
    }
    let mut operator = Console { yes };
    if !json {
        outln!(
            "self-test: {} ({} steps)",
            if plan.name.is_empty() {
                "plan"
            } else {
                &plan.name
            },
            plan.steps.len()
        );
    }
    let recorded = crate::ops::records::runs::selftest(
        Device::new(client, profile),
        plan,
        given,
        &mut operator,
        &mut Run::new(&cancel, |p: crate::ops::Progress| {
            // The safe state is said as it is reached, before the first step's line.
            if !json && p.message.en.starts_with(crate::ops::selftest::SAFE_STATE) {
                outln!("{}", p.message.en);
            }
        }),
        &mut |r| {
            if !json {
                outln!(
                    "{}  {:<26} {}",
                    if r.pass { "PASS" } else { "FAIL" },
                    r.name,
                    r.detail
                );
            }
        },
        recorder,
        log,
    );
    let report = &recorded.outcome;
    let logged = recorded.export.map(|r| {
        r.map_err(|e| {
            format!(
                "cannot append to {}: {e}",
                log.map(|p| p.display().to_string()).unwrap_or_default()
            )
        })
    });
    let kept = super::records::say_kept(&recorded.kept, json);
    if json {
        outln!("{}", serde_json::to_string(&report).unwrap_or_default());
    } else {
        let device = report.device.as_deref().unwrap_or("unknown device");
        let failed: Vec<&str> = report.failed().map(|r| r.name.as_str()).collect();
        let lost = report
            .interrupted()
            .filter(|(_, why)| *why == crate::ops::selftest::Interruption::LinkLost);
        if report.pass {
            outln!("PASS: all {} steps passed ({device})", report.results.len());
        } else if let (Some((step, _)), true) = (lost, failed.is_empty()) {
            // The unit failed nothing: the run says nothing of it.
            outln!(
                "NO VERDICT: link lost during {}: {} ({device}); test the unit again",
                step.name,
                step.detail
            );
        } else if let Some(why) = &report.aborted {
            outln!("FAIL: stopped at {why} ({device})");
        } else {
            outln!(
                "FAIL: {} of {} steps failed: {} ({device})",
                failed.len(),
                report.results.len(),
                failed.join(", ")
            );
        }
    }
    if let Some(Err(e)) = logged {
        // The exit code names who failed: a failed device first, else the log.
        return Err(if report.pass {
            CliError::input(e)
        } else {
            CliError::device(e)
        });
    }
    kept?;
    if cancel.is_cancelled() && !report.pass {
        return Err(cancelled_selftest(plan, report));
    }
    Ok(u8::from(!report.pass))
}

/// A self-test the operator cancelled (Ctrl-C): `cancelled after N of M steps`, the steps that
/// ran whole and those that did not (the one the cancel cut counts as not run), exit 130.
fn cancelled_selftest(plan: &Plan, report: &crate::ops::selftest::Report) -> CliError {
    let done = if report.aborted.is_some() {
        report.results.len().saturating_sub(1)
    } else {
        report.results.len()
    };
    op_error(crate::ops::OpError::cancelled_after(
        &plan.steps,
        done,
        "steps",
        |s| s.name.clone(),
    ))
}

fn yes(b: bool) -> &'static str {
    if b { "yes" } else { "no" }
}
