//! `botbench servo`: scan, parameters, id and baud provisioning, motion.

use super::checks;
use super::port::{PortArgs, op_error, print_checks};
use super::{CliError, CliResult};
use crate::link::PortOpener;
use crate::ops::Device;
use crate::ops::servo::{self as ops, Presence};
use crate::profile::{Input, Param, Profile, Protocol, Value};
use clap::Subcommand;
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub(crate) struct ServoArgs {
    #[command(flatten)]
    port: PortArgs,
    #[command(subcommand)]
    cmd: ServoCmd,
}

#[derive(Debug, Subcommand)]
enum ServoCmd {
    /// Find the servos on the bus.
    Scan {
        /// Ids to try: `0-254`, `3`, `0-10`.
        #[arg(long, default_value = "0-254")]
        ids: String,
        /// Baud rates: `all`, or a list such as `115200,9600` (default: the port's).
        #[arg(long)]
        bauds: Option<String>,
        /// Exit 0 when no servo answers (a script that expects an empty bus); otherwise a scan
        /// that finds nothing exits 1.
        #[arg(long)]
        allow_empty: bool,
    },
    /// The live values of several servos in one exchange (voltage, current, power,
    /// temperature with its raw reading, status, angle): the synchronous MONITOR, command 25.
    /// Newer servos only; exit 1 when one did not answer.
    Monitor {
        /// Servo ids: `1,2,3`, `0-5`, `1,4-6`.
        ids: String,
    },
    /// Is servo ID there?
    Ping {
        /// Servo id, 0 to 254.
        #[arg(value_parser = checks::servo_id)]
        id: u8,
    },
    /// Read one parameter, or all of them.
    Read {
        /// Servo id, 0 to 254.
        #[arg(value_parser = checks::servo_id)]
        id: u8,
        /// Parameter name or data_id (default: all).
        param: Option<String>,
    },
    /// Write one user parameter and read it back.
    Write {
        /// Servo id, 0 to 255 (255, every servo, only with --broadcast).
        #[arg(value_parser = checks::servo_id_or_broadcast)]
        id: u8,
        /// Parameter name or data_id.
        param: String,
        /// Value in display units, or a label (the parameter's range, as `read` shows it).
        #[arg(allow_hyphen_values = true)]
        value: String,
        /// With id 255: tell every servo at this rate, expecting no answer and reading nothing
        /// back.
        #[arg(long)]
        broadcast: bool,
    },
    /// Give servo OLD the id NEW (refuses 255 and ids in use; a fresh servo must be alone).
    SetId {
        /// Its id now, 0 to 254.
        #[arg(value_parser = checks::servo_id)]
        old: u8,
        /// The id to give it, 0 to 254.
        #[arg(value_parser = checks::servo_id)]
        new: u8,
    },
    /// Set servo ID's baud rate (a rate such as 57600, or its option in the profile's baud
    /// table), follow it and verify.
    SetBaud {
        /// Servo id, 0 to 254.
        #[arg(value_parser = checks::servo_id)]
        id: u8,
        /// The new rate (the servo profile's: 9600, 19200, 38400, 57600, 115200, 250000,
        /// 500000 or 1000000), or its option 1 to 8. (Its own name: `--baud` is the port's.)
        #[arg(id = "new_baud", value_name = "BAUD")]
        baud: String,
    },
    /// Turn servo ID to DEG degrees over --ms milliseconds.
    Angle {
        /// Servo id, 0 to 255 (255, every servo, only with --broadcast).
        #[arg(value_parser = checks::servo_id_or_broadcast)]
        id: u8,
        /// Target angle in degrees, in 0.1° steps, within the profile's range (the built-in
        /// servo's: -180.0 to 180.0).
        #[arg(allow_hyphen_values = true)]
        deg: String,
        /// Time to get there, 0 to 65535 ms.
        #[arg(long, default_value_t = 500)]
        ms: u16,
        /// Power, 0 to 65535 mW (0: the servo's limit).
        #[arg(long, default_value_t = 0)]
        power: u16,
        /// With id 255: turn every servo at this rate.
        #[arg(long)]
        broadcast: bool,
        /// A multi-turn move (ROTATE_MTURN_BY_INTERVAL, ±368640°): --ms must be at least
        /// --acc-ms + --dec-ms (the profile's rule), else it is refused with the least allowed.
        #[arg(long)]
        multi_turn: bool,
        /// With --multi-turn: acceleration time, 20 to 65535 ms (default 20).
        #[arg(long, value_parser = clap::value_parser!(u16).range(20..))]
        acc_ms: Option<u16>,
        /// With --multi-turn: deceleration time, 20 to 65535 ms (default 20).
        #[arg(long, value_parser = clap::value_parser!(u16).range(20..))]
        dec_ms: Option<u16>,
        /// Send the angle without first checking that the servo answers a ping (the servo
        /// sends no answer to the angle itself, so without the ping nothing says it is there).
        #[arg(long)]
        no_check: bool,
    },
    /// Provision fresh servos by a plan: find each (id 0, at any baud rate), give it the next
    /// free id, the plan's baud rate and parameters, verify everything, and log it.
    Provision {
        /// The plan (RON), e.g. presets/servo-provision-plan.ron.
        plan: PathBuf,
        /// Append one CSV line per servo to this file.
        #[arg(long)]
        log: Option<PathBuf>,
        /// How many servos, 1 to 10000; between them the operator swaps the servo and presses
        /// Enter.
        #[arg(long, default_value_t = 1, value_parser = checks::provision_count)]
        count: u32,
        /// Between servos, instead of waiting for Enter, look for a new fresh servo every MS ms,
        /// 1 to 600000.
        #[arg(long, value_name = "MS", value_parser = checks::wait_ms)]
        wait_ms: Option<u64>,
        #[command(flatten)]
        rec: super::records::RecordArgs,
    },
}

/// A servo baud rate or its option, as the option: both from `profile`'s baud table.
fn servo_baud(profile: &Profile, text: &str) -> Result<u8, CliError> {
    let (_, rates) = ops::baud_param(profile).map_err(op_error)?;
    let allowed = || {
        let options: Vec<u8> = rates.keys().copied().collect();
        let bauds: Vec<u32> = rates.values().copied().collect();
        format!("give a servo baud rate ({bauds:?}) or its option {options:?}")
    };
    let quoted = crate::document::quote(text);
    let v: u32 = text
        .trim()
        .parse()
        .map_err(|_| CliError::input(format!("'{quoted}' is not a number; {}", allowed())))?;
    match u8::try_from(v) {
        Ok(option) if rates.contains_key(&option) => Ok(option),
        _ => profile.option_of_baud(v).ok_or_else(|| {
            CliError::input(format!(
                "{v} is not a servo baud rate or option; {}",
                allowed()
            ))
        }),
    }
}

fn parse_ids(s: &str) -> Result<std::ops::RangeInclusive<u8>, CliError> {
    let bad = || {
        CliError::input(format!(
            "--ids '{s}': give an id or a range such as 0-254 (ids 0-254)"
        ))
    };
    let (a, b) = match s.split_once('-') {
        Some((a, b)) => (
            a.trim().parse::<u8>().map_err(|_| bad())?,
            b.trim().parse::<u8>().map_err(|_| bad())?,
        ),
        None => {
            let v = s.trim().parse::<u8>().map_err(|_| bad())?;
            (v, v)
        }
    };
    let broadcast = crate::protocol::servo::BROADCAST_ID;
    if b == broadcast {
        return Err(CliError::input(format!(
            "'{s}': id {broadcast} is the broadcast address: every servo acts on it and none answers; give ids 0-{}",
            broadcast - 1
        )));
    }
    if a > b {
        return Err(bad());
    }
    Ok(a..=b)
}

fn parse_id_list(s: &str) -> Result<Vec<u8>, CliError> {
    let mut ids = Vec::new();
    for part in s.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        for id in parse_ids(part)? {
            if !ids.contains(&id) {
                ids.push(id);
            }
        }
    }
    if ids.is_empty() {
        return Err(CliError::input(format!("'{s}' names no servo id")));
    }
    Ok(ids)
}

/// The rates `--bauds` names (`all`: the profile's servo baud rates; none: `current`).
fn parse_bauds(profile: &Profile, s: Option<&str>, current: u32) -> Result<Vec<u32>, CliError> {
    let bauds = profile.servo_bauds();
    match s {
        None => Ok(vec![current]),
        Some("all") => Ok(bauds),
        Some(list) => list
            .split(',')
            .map(|b| {
                let v: u32 = b
                    .trim()
                    .parse()
                    .map_err(|_| CliError::input(format!("'{b}' is not a baud rate")))?;
                if bauds.contains(&v) {
                    Ok(v)
                } else {
                    Err(CliError::input(format!(
                        "{v} is not a servo baud rate; allowed: {bauds:?}"
                    )))
                }
            })
            .collect(),
    }
}

fn param<'p>(profile: &'p Profile, name: &str) -> Result<&'p crate::profile::Param, CliError> {
    profile.find_param(name).ok_or_else(|| {
        let known: Vec<&str> = profile
            .params
            .iter()
            .map(|p| p.field.ident.as_str())
            .collect();
        CliError::input(format!(
            "no servo parameter '{name}'; known: {}",
            known.join(", ")
        ))
    })
}

/// A `servo` subcommand with everything it was given checked, before the port is opened.
enum Checked<'p> {
    Scan(ops::ScanPlan, bool),
    Monitor(Vec<u8>),
    Ping(u8),
    Read(u8, Vec<&'p crate::profile::Param>),
    /// The id, the parameter, its value, and whether it is broadcast (nothing read back).
    Write(u8, &'p crate::profile::Param, Value, bool),
    SetId(u8, u8),
    SetBaud(u8, u8),
    /// `servo angle`.
    Angle(Angle),
}

/// `servo angle`, checked: what ROTATE is sent with.
struct Angle {
    /// The servo id (255: every servo, a broadcast).
    id: u8,
    /// The command: ROTATE, or ROTATE_MTURN_BY_INTERVAL (`--multi-turn`).
    command: &'static str,
    /// Its inputs.
    inputs: Vec<(String, Input)>,
    /// The target angle as given, in degrees.
    deg: String,
    /// The time to get there, ms.
    ms: u16,
    /// Ping the servo first (not with --no-check, nor a broadcast).
    ping_first: bool,
}

/// The value `servo write` writes to `p`, from what was typed: a baud option may be given as
/// its rate, as set-baud takes it; anything else as the field reads it.
fn write_value(p: &crate::profile::Param, typed: &str) -> Result<Value, CliError> {
    match ops::baud_as_option(p, Input::Text(typed.to_string())) {
        Input::Raw(option) => Ok(option),
        Input::Text(text) => p.field.parse(&text).map_err(CliError::input),
    }
}

/// Checks every id, name and value of `cmd` against `profile`; `home` is the port's baud rate.
fn check<'p>(cmd: &ServoCmd, profile: &'p Profile, home: u32) -> Result<Checked<'p>, CliError> {
    Ok(match cmd {
        ServoCmd::Scan {
            ids,
            bauds,
            allow_empty,
        } => Checked::Scan(
            ops::ScanPlan {
                ids: parse_ids(ids)?,
                bauds: parse_bauds(profile, bauds.as_deref(), home)?,
                home_baud: home,
            },
            *allow_empty,
        ),
        ServoCmd::Monitor { ids } => Checked::Monitor(parse_id_list(ids)?),
        ServoCmd::Ping { id } => Checked::Ping(*id),
        ServoCmd::Read { id, param: name } => Checked::Read(
            *id,
            match name {
                Some(n) => vec![param(profile, n)?],
                None => profile.params.iter().collect(),
            },
        ),
        ServoCmd::Write {
            id,
            param: name,
            value,
            broadcast,
        } => {
            let p = param(profile, name)?;
            if p.access == crate::profile::Access::ReadOnly {
                return Err(op_error(crate::ops::OpError::ReadOnly {
                    param: p.field.ident.clone(),
                }));
            }
            let value = write_value(p, value)?;
            Checked::Write(*id, p, value, *broadcast)
        }
        ServoCmd::SetId { old, new } => {
            if old == new {
                return Err(op_error(crate::ops::OpError::SameId { id: *new }));
            }
            Checked::SetId(*old, *new)
        }
        ServoCmd::SetBaud { id, baud } => Checked::SetBaud(*id, servo_baud(profile, baud)?),
        ServoCmd::Angle {
            id,
            deg,
            ms,
            power,
            no_check,
            multi_turn,
            acc_ms,
            dec_ms,
            ..
        } => {
            if !*multi_turn && (acc_ms.is_some() || dec_ms.is_some()) {
                return Err(CliError::input(
                    "--acc-ms and --dec-ms are for a multi-turn move: add --multi-turn",
                ));
            }
            let command = if *multi_turn {
                "ROTATE_MTURN_BY_INTERVAL"
            } else {
                "ROTATE"
            };
            let rotate = profile.command(command).ok_or_else(|| {
                CliError::input(format!("profile '{}' has no {command}", profile.id))
            })?;
            let raw = |name: &str, v: u16| (name.to_string(), Input::Raw(Value::Int(v.into())));
            let mut inputs = vec![
                ("servo_id".to_string(), Input::Raw(Value::Int((*id).into()))),
                ("angle".to_string(), Input::Text(deg.clone())),
                raw("interval", *ms),
            ];
            if *multi_turn {
                let (acc, dec) = (acc_ms.unwrap_or(20), dec_ms.unwrap_or(20));
                inputs.extend([raw("t_acc", acc), raw("t_dec", dec)]);
            }
            inputs.push(raw("power", *power));
            // The profile's ranges and relations (a multi-turn interval below t_acc + t_dec):
            // refused here, before the port is opened.
            crate::ops::exchange::request(profile, rotate, &inputs, 1).map_err(|e| {
                let mut e = op_error(e);
                if *multi_turn {
                    e.message = format!("multi-turn move refused, nothing sent: {}", e.message);
                }
                e
            })?;
            Checked::Angle(Angle {
                id: *id,
                command,
                inputs,
                deg: deg.trim().to_string(),
                ms: *ms,
                ping_first: !*no_check && *id != crate::protocol::servo::BROADCAST_ID,
            })
        }
        ServoCmd::Provision { .. } => {
            return Err(CliError::input("provision is checked by its own plan"));
        }
    })
}

/// The broadcast address where an answer is expected (or a broadcast was not asked for), and
/// `--broadcast` with another id: refused before the port is opened.
fn check_broadcast(cmd: &ServoCmd) -> Result<(), CliError> {
    use crate::protocol::servo::BROADCAST_ID;
    let refuse = |what: &'static str, hint: &'static str| {
        Err(CliError::input(crate::ops::OpError::BroadcastAnswer {
            what,
            hint,
        }))
    };
    match *cmd {
        ServoCmd::Ping { id: BROADCAST_ID } => refuse("ping a servo", ""),
        ServoCmd::Read {
            id: BROADCAST_ID, ..
        } => refuse("read a parameter", ""),
        ServoCmd::SetId {
            old: BROADCAST_ID, ..
        } => refuse("give a servo a new id", ""),
        ServoCmd::SetBaud {
            id: BROADCAST_ID, ..
        } => refuse("change a servo's baud rate and follow it", ""),
        ServoCmd::Write {
            id: BROADCAST_ID,
            broadcast: false,
            ..
        } => refuse(
            "write a parameter and read it back",
            "; or add --broadcast to tell every servo, with nothing read back",
        ),
        ServoCmd::Angle {
            id: BROADCAST_ID,
            broadcast: false,
            ..
        } => refuse("turn a servo", "; or add --broadcast to turn every servo"),
        ServoCmd::Write {
            id,
            broadcast: true,
            ..
        }
        | ServoCmd::Angle {
            id,
            broadcast: true,
            ..
        } if id != BROADCAST_ID => Err(CliError::input(format!(
            "--broadcast goes with id 255 (every servo), not {id}"
        ))),
        ServoCmd::Monitor { ref ids } => parse_id_list(ids).map(|_| ()),
        _ => Ok(()),
    }
}

pub(crate) fn run(mut args: ServoArgs, ports: &PortOpener) -> CliResult {
    args.port = args.port.with_ports(ports);
    let json = args.port.json;
    // The broadcast id where an answer is expected is refused before the port is opened.
    check_broadcast(&args.cmd)?;
    if let ServoCmd::Provision {
        plan,
        log,
        count,
        wait_ms,
        rec,
    } = &args.cmd
    {
        return super::provision::run(&args.port, plan, log.as_deref(), *count, *wait_ms, rec);
    }
    // Everything given is checked before the port is opened.
    let profile = args.port.profile("servo", Protocol::Servo)?;
    let home = args.port.baud.unwrap_or(profile.baud);
    let checked = check(&args.cmd, &profile, home)?;
    let link = args.port.open_with(profile.clone(), false)?;
    let client = link.client();
    let cancel = super::port::cancel_on_ctrl_c();
    let dev = Device::new(&client, &profile);
    match checked {
        Checked::Scan(plan, allow_empty) => {
            let port = args.port.port.as_deref().unwrap_or("the port");
            super::servo_scan::run(dev, &plan, &cancel, port, allow_empty, json)
        }
        Checked::Monitor(ids) => monitor(&client, &profile, &ids, json),
        Checked::Ping(id) => {
            let p = ops::ping(&client, id, 3).map_err(op_error)?;
            if json {
                outln!("{}", serde_json::json!({"id": id, "presence": p}));
            } else {
                outln!("servo {id}: {p:?}");
            }
            Ok(u8::from(p != Presence::Present))
        }
        Checked::Read(id, params) => read(dev, id, &params, json),
        Checked::Write(id, p, value, true) => write_broadcast(dev, id, p, value, json),
        Checked::Write(id, p, value, false) => {
            let check = ops::write_param(dev, id, p, Input::Raw(value)).map_err(op_error)?;
            let field = p.field.clone();
            Ok(print_checks(&[check], |_| Some(field.clone()), json))
        }
        Checked::SetId(old, new) => {
            ops::set_id(dev, old, new, &cancel).map_err(op_error)?;
            let said = format!("servo {old} is now {new}: verified at the new id");
            said_or_json(
                json,
                serde_json::json!({"old": old, "new": new, "verified": true}),
                &said,
            )
        }
        Checked::SetBaud(id, option) => {
            let rate = ops::set_baud(dev, id, option).map_err(op_error)?;
            let said = format!("servo {id} now talks at {rate} baud: verified");
            said_or_json(
                json,
                serde_json::json!({"id": id, "baud": rate, "verified": true}),
                &said,
            )
        }
        Checked::Angle(angle) => turn(dev, &angle, json),
    }
}

/// `servo angle`: pings the servo first (unless told not to: the servo sends no answer to
/// ROTATE, so the ping is what says it is there), sends ROTATE, and says what is known: the
/// servo answered its ping, and acknowledged the angle only when its response switch is on.
/// Exit 1, with the wiring checklist, when the servo does not answer the ping.
fn turn(dev: Device<'_>, angle: &Angle, json: bool) -> CliResult {
    let id = angle.id;
    if angle.ping_first {
        match ops::ping(dev.client, id, 3).map_err(op_error)? {
            Presence::Present => {}
            Presence::Absent => {
                return Err(CliError::device(format!(
                    "servo {id} does not answer a ping, so the angle was not sent (the servo \
                     sends no answer to an angle: nothing else would tell that it is not there)\
                     {}; `--no-check` sends it anyway",
                    super::port::silent_hint()
                )));
            }
            Presence::PossibleDuplicate(e) => super::port::warn(&format!(
                "servo {id}'s ping came back damaged ({e}): two servos may share id {id}, and \
                 both will turn"
            )),
        }
    }
    let rotate = dev.profile.command(angle.command).ok_or_else(|| {
        CliError::input(format!(
            "profile '{}' has no {}",
            dev.profile.id, angle.command
        ))
    })?;
    let reply = crate::ops::exchange::send(dev, rotate, &angle.inputs).map_err(op_error)?;
    // An answer comes only with the servo's response switch on.
    let acknowledged = match reply.payload() {
        None => false,
        Some(payload) => {
            let answer = crate::ops::exchange::decode_answer(dev.profile, rotate, payload)
                .map_err(op_error)?;
            if answer.int("result") == Some(0) {
                return Err(CliError::device(format!(
                    "servo {id} answered {} with result 0 (failed): the angle was refused",
                    angle.command
                )));
            }
            true
        }
    };
    let (deg, ms) = (&angle.deg, angle.ms);
    if json {
        let doc = serde_json::json!({
            "servo": id, "angle": deg, "ms": ms, "broadcast": id == crate::protocol::servo::BROADCAST_ID,
            "pinged": angle.ping_first, "acknowledged": acknowledged,
        });
        outln!("{}", super::port::with_warnings(doc));
    } else if id == crate::protocol::servo::BROADCAST_ID {
        outln!(
            "every servo at this rate: turning to {deg}° over {ms} ms (a broadcast: no servo \
             answers it, nothing confirms the move)"
        );
    } else if acknowledged {
        outln!("servo {id}: turning to {deg}° over {ms} ms, acknowledged");
    } else {
        let pinged = if angle.ping_first {
            "it answered a ping just before"
        } else {
            "not pinged first (--no-check): nothing says it is there"
        };
        outln!(
            "servo {id}: turning to {deg}° over {ms} ms; the servo sends no answer to an angle \
             ({}), so nothing confirms the move; {pinged}",
            rotate.ident
        );
    }
    Ok(0)
}

/// Prints `doc` with `--json`, else `said`; exit code 0.
fn said_or_json(json: bool, doc: serde_json::Value, said: &str) -> CliResult {
    if json {
        outln!("{doc}");
    } else {
        outln!("{said}");
    }
    Ok(0)
}

/// `servo read`: each of `params` of servo `id`, with its display value (and unit, conversion
/// in JSON).
fn read(dev: Device<'_>, id: u8, params: &[&Param], json: bool) -> CliResult {
    let mut out = Vec::new();
    for p in params {
        let v = ops::read_param(dev, id, p).map_err(op_error)?;
        out.push((p, v));
    }
    if json {
        let doc: Vec<_> = out.iter().map(|(p, v)| serde_json::json!({
            "param": p.field.ident, "id": p.id, "value": v, "display": p.field.display(&Value::Int(*v)), "unit": p.field.unit,
            "converted": p.field.convert.and_then(|c| c.apply(*v)),
        })).collect();
        outln!("{}", serde_json::json!({"servo": id, "params": doc}));
    } else {
        for (p, v) in out {
            outln!(
                "{:>3} {:<22} {}",
                p.id,
                p.field.ident,
                p.field.display(&Value::Int(v))
            );
        }
    }
    Ok(0)
}

/// `servo write 255 ...`: `value` broadcast to every servo at this rate; none answers, so
/// nothing is read back.
fn write_broadcast(dev: Device<'_>, id: u8, p: &Param, value: Value, json: bool) -> CliResult {
    let written = ops::write_param_broadcast(dev, p, Input::Raw(value)).map_err(op_error)?;
    if json {
        outln!(
            "{}",
            serde_json::json!({"servo": id, "param": p.field.ident, "written": written, "broadcast": true, "verified": false})
        );
    } else {
        outln!(
            "{:<24} {:>12}  broadcast to every servo at this rate; none answers a broadcast, nothing read back",
            p.field.ident,
            p.field.format(&written)
        );
    }
    Ok(0)
}

fn monitor(client: &crate::link::Client, profile: &Profile, ids: &[u8], json: bool) -> CliResult {
    use crate::ops::servo::monitor::{Reading, monitor_all};
    let rows = monitor_all(Device::new(client, profile), ids).map_err(op_error)?;
    let missing = rows
        .iter()
        .any(|r| !matches!(r.reading, Reading::Values(_)));
    if json {
        outln!("{}", serde_json::json!({ "servos": rows }));
        return Ok(u8::from(missing));
    }
    outln!(
        "{:>3} {:>6} {:>6} {:>6} {:>18} {:>6} {:>10} {:>6}",
        "id",
        "mV",
        "mA",
        "mW",
        "temp °C (raw)",
        "status",
        "angle °",
        "turns"
    );
    for r in &rows {
        match &r.reading {
            Reading::Values(m) => outln!(
                "{:>3} {:>6} {:>6} {:>6} {:>18} {:>6} {:>10.1} {:>6}",
                r.id,
                m.voltage_mv,
                m.current_ma,
                m.power_mw,
                format!(
                    "{} ({})",
                    m.temperature_c.map_or("n/a".into(), |t| format!("{t:.1}")),
                    m.temperature_raw
                ),
                format!("{:#04x}", m.status),
                m.angle_deg,
                m.turns
            ),
            Reading::Misfit { error } => outln!("{:>3} !! {error}", r.id),
            Reading::NoData => outln!("{:>3} no data (the servo has no reading to give)", r.id),
            Reading::NoAnswer => outln!("{:>3} no answer", r.id),
        }
    }
    Ok(u8::from(missing))
}
