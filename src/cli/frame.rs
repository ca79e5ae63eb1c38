//! `botbench frame decode|encode`: frames of the three protocols from and to hex.

use super::{CliError, CliResult, registry};
use crate::packet::{Header, Item, MspDirection, Packet, decode_all};
use crate::profile::{Command, FieldValue, Initiator, Input, Profile, Protocol};
use crate::protocol::{Direction, hex, msp, servo, tuya};
use clap::{Subcommand, ValueEnum};
use serde_json::{Value as Json, json};

#[derive(Debug, Clone, Copy, ValueEnum)]
pub(crate) enum Proto {
    Msp,
    Servo,
    Tuya,
}

impl Proto {
    fn protocol(self) -> Protocol {
        match self {
            Proto::Msp => Protocol::Msp,
            Proto::Servo => Protocol::Servo,
            Proto::Tuya => Protocol::Tuya,
        }
    }

    fn default_profile(self) -> &'static str {
        match self {
            Proto::Msp => "window-cleaner",
            Proto::Servo => "servo",
            Proto::Tuya => "tuya-vacuum",
        }
    }
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub(crate) enum MspDir {
    Request,
    Reply,
    Auto,
}

#[derive(Debug, Subcommand)]
pub(crate) enum FrameCmd {
    /// Print every frame (and every frame error) found in hex bytes.
    ///
    /// Hex may be written `12 4c 01`, `0x12,0x4C,0x01` or `124c01`. Exit code 1 when a frame
    /// error (bad checksum, junk, truncation) was found, or a payload that does not fit its
    /// command's layout (too short, too long: the fields read before the fault are printed,
    /// with the raw bytes); 2 when the input is not hex.
    ///
    /// With `--capture FILE`, prints every frame of a capture (both directions, with the time
    /// its last byte crossed), decoded with the capture's profile unless --profile is given.
    Decode {
        /// The protocol (with --capture: the capture profile's).
        #[arg(required_unless_present = "capture")]
        protocol: Option<Proto>,
        /// The bytes, in one or more arguments.
        #[arg(required_unless_present = "capture", num_args = 1..)]
        hex: Vec<String>,
        /// A capture file recorded with --capture (pcapng).
        #[arg(long, value_name = "FILE", conflicts_with = "hex")]
        capture: Option<std::path::PathBuf>,
        /// The device profile that names commands and fields (default: the protocol's usual one).
        #[arg(long)]
        profile: Option<String>,
        /// MSP only: read the bytes as requests, replies, or whichever fits (default).
        #[arg(long, value_enum, default_value = "auto")]
        msp_dir: MspDir,
        /// One JSON document a line.
        #[arg(long)]
        json: bool,
    },
    /// Build a frame from a command name or number and FIELD=VALUE pairs, and print its hex.
    ///
    /// Values are in display units (e.g. `angle=90.5` for 905 × 0.1°), or enum labels.
    Encode {
        /// The protocol.
        protocol: Proto,
        /// The command: canonical name (case-insensitive) or number.
        command: String,
        /// Field values, FIELD=VALUE.
        #[arg(value_name = "FIELD=VALUE")]
        fields: Vec<String>,
        /// The device profile (default: the protocol's usual one).
        #[arg(long)]
        profile: Option<String>,
        /// MSP: the device code, 0 to 255 (default: the command's, else the profile's).
        #[arg(long, value_parser = parse_u8)]
        device: Option<u8>,
        /// Build the answer to the command instead of the command itself.
        #[arg(long)]
        reply: bool,
        /// MSP replies: mark as an unsolicited (async) message.
        #[arg(long = "async")]
        is_async: bool,
        /// MSP requests: ask the device to act without answering (option 0xFE).
        #[arg(long)]
        silent: bool,
        /// The payload as hex, bypassing the fields (for commands the profile lacks).
        #[arg(long, conflicts_with = "fields")]
        payload: Option<String>,
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
}

fn parse_u8(s: &str) -> Result<u8, String> {
    crate::profile::codec::parse_id(s).ok_or_else(|| format!("'{s}' is not a number from 0 to 255"))
}

pub(crate) fn run(cmd: FrameCmd) -> CliResult {
    match cmd {
        FrameCmd::Decode {
            capture: Some(path),
            protocol,
            profile,
            json,
            ..
        } => decode_capture(&path, protocol, profile.as_deref(), json),
        FrameCmd::Decode {
            protocol,
            hex: parts,
            profile,
            msp_dir,
            json,
            ..
        } => {
            let protocol = protocol.ok_or_else(|| CliError::input("which protocol?"))?;
            let profile = load_profile(protocol, profile.as_deref())?;
            let bytes = hex::parse(&parts.join(" ")).map_err(CliError::input)?;
            let dir = match msp_dir {
                MspDir::Request => MspDirection::Requests,
                MspDir::Reply => MspDirection::Replies,
                MspDir::Auto => MspDirection::Auto,
            };
            let items = decode_all(protocol.protocol(), dir, &bytes);
            let mut errors = 0;
            for item in &items {
                let misfit = match &item.result {
                    Ok(p) => p.decode_lenient(&profile).is_some_and(|d| !d.fits()),
                    Err(_) => true,
                };
                if misfit {
                    errors += 1;
                }
                if json {
                    outln!("{}", item_json(&profile, item));
                } else {
                    out!("{}", item_text(&profile, item));
                }
            }
            if items.is_empty() && !json {
                outln!("no bytes");
            }
            Ok(u8::from(errors > 0))
        }
        FrameCmd::Encode {
            protocol,
            command,
            fields,
            profile,
            device,
            reply,
            is_async,
            silent,
            payload,
            json,
        } => {
            let profile = load_profile(protocol, profile.as_deref())?;
            let opts = EncodeOpts {
                device,
                reply,
                is_async,
                silent,
            };
            let (packet, cmd) = encode(
                &profile,
                protocol,
                &command,
                &fields,
                payload.as_deref(),
                opts,
            )?;
            if json {
                let doc = json!({
                    "protocol": protocol.protocol().name(),
                    "direction": packet.direction,
                    "command": packet.command,
                    "name": cmd.map(|c| c.ident.clone()),
                    "hex": hex::format(&packet.wire),
                    "bytes": packet.wire,
                });
                outln!("{doc}");
            } else {
                outln!("{}", hex::format(&packet.wire));
            }
            Ok(0)
        }
    }
}

/// `frame decode --capture FILE`: each frame of the capture, with its time since the first
/// chunk and its direction. Exit code 1 when a frame error or a misfit payload was found.
fn decode_capture(
    path: &std::path::Path,
    protocol: Option<Proto>,
    profile: Option<&str>,
    json: bool,
) -> CliResult {
    let file = crate::capture::read_path(path).map_err(CliError::input)?;
    let profile = match (profile, protocol) {
        (Some(_), Some(p)) | (None, Some(p)) => load_profile(p, profile)?,
        (Some(name), None) => registry()?.get(name).map_err(CliError::input)?,
        (None, None) if file.info.profile.is_empty() => {
            return Err(CliError::input(format!(
                "{} names no profile: give the protocol or --profile",
                path.display()
            )));
        }
        (None, None) => registry()?
            .get(&file.info.profile)
            .map_err(|e| CliError::input(format!("the capture's profile: {e} (give --profile)")))?,
    };
    if !json {
        outln!(
            "# {}: {}, profile {}, {} baud, {} chunks{}",
            path.display(),
            file.info.application,
            profile.id,
            file.info.baud,
            file.chunks.len(),
            file.truncated
                .as_ref()
                .map_or(String::new(), |t| format!(" (cut off: {t})"))
        );
    }
    let start = file.chunks.first().map_or(0, |c| c.at_us);
    let mut errors = 0;
    let frames = crate::capture::frames(&file, profile.protocol);
    for f in &frames {
        let misfit = match &f.item.result {
            Ok(p) => p.decode_lenient(&profile).is_some_and(|d| !d.fits()),
            Err(_) => true,
        };
        errors += usize::from(misfit);
        let seconds = f.at_us.saturating_sub(start) as f64 / 1e6;
        if json {
            let mut doc = item_json(&profile, &f.item);
            doc["at_us"] = json!(f.at_us);
            doc["t"] = json!(seconds);
            doc["wire_direction"] = json!(f.direction);
            outln!("{doc}");
        } else {
            out!("{seconds:>11.6} {}", item_text(&profile, &f.item));
        }
    }
    if frames.is_empty() && !json {
        outln!("no bytes");
    }
    Ok(u8::from(errors > 0 || file.truncated.is_some()))
}

fn load_profile(p: Proto, name: Option<&str>) -> Result<std::sync::Arc<Profile>, CliError> {
    let reg = registry()?;
    let profile = reg
        .get(name.unwrap_or(p.default_profile()))
        .map_err(CliError::input)?;
    if profile.protocol != p.protocol() {
        return Err(CliError::input(format!(
            "profile '{}' speaks {}, not {}",
            profile.id,
            profile.protocol.name(),
            p.protocol().name()
        )));
    }
    Ok(profile)
}

#[derive(Debug, Clone, Copy)]
struct EncodeOpts {
    device: Option<u8>,
    reply: bool,
    is_async: bool,
    silent: bool,
}

fn encode<'p>(
    profile: &'p Profile,
    proto: Proto,
    command: &str,
    fields: &[String],
    payload: Option<&str>,
    opts: EncodeOpts,
) -> Result<(Packet, Option<&'p Command>), CliError> {
    let cmd = profile.command(command);
    let (id, initiator) = match (cmd, payload) {
        (Some(c), _) => (c.id, c.initiator),
        (None, Some(_)) => (
            crate::profile::codec::parse_id(command).ok_or_else(|| {
                CliError::input(format!(
                    "'{command}' is not a command of {} nor a number",
                    profile.id
                ))
            })?,
            Initiator::Host,
        ),
        (None, None) => {
            return Err(super::profiles::unknown_command(profile, command));
        }
    };
    let forward = match initiator {
        Initiator::Host => Direction::HostToDevice,
        Initiator::Device => Direction::DeviceToHost,
    };
    let dir = match (opts.reply, forward) {
        (false, d) => d,
        (true, Direction::HostToDevice) => Direction::DeviceToHost,
        (true, Direction::DeviceToHost) => Direction::HostToDevice,
    };
    let data = match (payload, cmd) {
        (Some(h), _) => hex::parse(h).map_err(CliError::input)?,
        (None, Some(c)) => {
            let inputs = fields
                .iter()
                .map(|kv| {
                    kv.split_once('=')
                        .map(|(k, v)| (k.trim().to_string(), Input::Text(v.to_string())))
                        .ok_or_else(|| CliError::input(format!("'{kv}' is not FIELD=VALUE")))
                })
                .collect::<Result<Vec<_>, _>>()?;
            profile.encode(c, dir, &inputs).map_err(CliError::input)?
        }
        (None, None) => Vec::new(),
    };
    let encoded = match proto {
        Proto::Msp if dir == Direction::HostToDevice => {
            let device = opts
                .device
                .or(cmd.and_then(|c| c.device))
                .or(profile.device_code.map(|d| d.initial()))
                .unwrap_or(msp::DEVICE_CORE);
            let mut r = msp::Request::new(device, id, data);
            if opts.silent {
                r.option = msp::OPTION_SILENT;
            }
            r.encode().map(|_| Packet::msp_request(r))
        }
        Proto::Msp => {
            let mut r = msp::Reply::new(id, data);
            if opts.is_async {
                r.kind = msp::ReplyKind::Async;
            }
            r.encode().map(|_| Packet::msp_reply(r))
        }
        Proto::Servo => {
            let f = match dir {
                Direction::HostToDevice => servo::Frame::request(id, data),
                Direction::DeviceToHost => servo::Frame::reply(id, data),
            };
            f.encode().map(|_| Packet::servo(f))
        }
        Proto::Tuya => {
            let f = match dir {
                Direction::HostToDevice => tuya::Frame::from_module(id, data),
                Direction::DeviceToHost => tuya::Frame::from_mcu(id, data),
            };
            f.encode().map(|_| Packet::tuya(f))
        }
    };
    let packet = match encoded {
        Ok(p) => p,
        Err(e) => return Err(CliError::input(e)),
    };
    Ok((packet, cmd))
}

fn header_json(h: &Header) -> Json {
    match h {
        Header::MspRequest { option, device } => json!({"option": option, "device": device}),
        Header::MspReply { kind } => json!({"kind": kind}),
        Header::Servo => json!({}),
        Header::Tuya { version } => json!({"version": version}),
    }
}

fn value_json(v: &FieldValue<'_>) -> Json {
    let mut doc = json!({
        "field": v.ident,
        "value": v.value,
        "display": v.display(),
        "unit": v.field.unit,
        "in_profile": v.in_profile,
        "limit": v.limit.as_ref().map(ToString::to_string),
    });
    // A converted field (a thermistor reading): `value` is the raw reading, `converted` the
    // value it stands for in `unit` (null where the conversion is undefined).
    if v.field.convert.is_some() {
        doc["converted"] = json!(v.converted());
    }
    doc
}

fn item_json(profile: &Profile, item: &Item) -> Json {
    match &item.result {
        Ok(p) => {
            let cmd = p.command_in(profile);
            let decoded = p.decode_lenient(profile);
            let misfit = decoded.as_ref().and_then(|d| d.misfit());
            let fields = decoded
                .as_ref()
                .map_or_else(Vec::new, |d| d.values.iter().map(value_json).collect());
            let trailing = match decoded.as_ref() {
                Some(d) if !d.trailing.is_empty() => json!(hex::format(&d.trailing)),
                _ => Json::Null,
            };
            let mut doc = json!({
                "offset": item.offset,
                "len": item.len,
                // A valid frame whose payload does not fit its layout is not clean: `ok` is
                // false, `error` is "layout", and `fields` are those read before the fault.
                "ok": misfit.is_none(),
                "direction": p.direction,
                "header": header_json(&p.header),
                "command": p.command,
                "name": cmd.map(|c| c.ident.clone()),
                "name_en": cmd.map(|c| c.name.en.clone()),
                "name_zh": cmd.map(|c| c.name.zh.clone()),
                "payload": hex::format(&p.payload),
                "fields": fields,
                "field_error": misfit.as_ref().map(|m| m.fault.to_string()),
                "trailing": trailing,
                "hex": hex::format(&p.wire),
            });
            if let Some(m) = &misfit {
                doc["error"] = json!("layout");
                doc["message"] = json!(m.to_string());
                doc["payload_len"] = json!(m.payload.len());
                doc["expected_len"] = json!({"min": m.expected.0, "max": m.expected.1});
            }
            if let Some(t) = p.servo_target() {
                doc["target"] = json!(t);
            }
            doc
        }
        Err(e) => {
            let mut doc = json!({
                "offset": item.offset,
                "len": item.len,
                "ok": false,
                "error": e.kind(),
                "message": e.to_string(),
                "hex": hex::format(e.bytes()),
            });
            if let crate::protocol::FrameError::Checksum {
                expected, actual, ..
            } = e
            {
                doc["expected"] = json!(expected);
                doc["actual"] = json!(actual);
            }
            doc
        }
    }
}

fn item_text(profile: &Profile, item: &Item) -> String {
    let mut s = String::new();
    match &item.result {
        Ok(p) => {
            let cmd = p.command_in(profile);
            let head = match &p.header {
                Header::MspRequest { option, device } => {
                    format!(
                        "request device {device:#04x}{}",
                        if *option == msp::OPTION_SILENT {
                            " silent"
                        } else {
                            ""
                        }
                    )
                }
                Header::MspReply {
                    kind: msp::ReplyKind::Reply,
                } => "reply".into(),
                Header::MspReply {
                    kind: msp::ReplyKind::Async,
                } => "async".into(),
                Header::Servo if p.direction == Direction::HostToDevice => match p.servo_target() {
                    Some(servo::Target::Servo { id }) => format!("request to servo {id}"),
                    Some(servo::Target::Broadcast) => "request to every servo (broadcast)".into(),
                    Some(servo::Target::Bus) => "request to every servo (bus-wide command)".into(),
                    Some(servo::Target::Sync { sub_command, ids }) => {
                        format!("synchronous request: command {sub_command} to servos {ids:?}")
                    }
                    None => "request".into(),
                },
                Header::Servo => "reply".into(),
                Header::Tuya { .. } if p.direction == Direction::HostToDevice => "module".into(),
                Header::Tuya { .. } => "mcu".into(),
            };
            let name = cmd.map_or_else(
                || "(not in profile; raw)".to_string(),
                |c| format!("{} ({} / {})", c.ident, c.name.en, c.name.zh),
            );
            s.push_str(&format!(
                "@{:<4} {} {head} {} {name}\n       {}\n",
                item.offset,
                p.direction.arrow(),
                p.command,
                hex::format(&p.wire)
            ));
            match p.decode_lenient(profile) {
                Some(d) => {
                    for v in &d.values {
                        // A data point the profile lacks: `dp 101 (not in the profile): value 50`.
                        let sep = if v.in_profile { " =" } else { ":" };
                        s.push_str(&format!("       {}{sep} {}\n", v.ident, v.display()));
                    }
                    if let Some(m) = d.misfit() {
                        s.push_str(&format!(
                            "       !! payload of {} byte(s), the layout takes {}: {}\n       payload = {}\n",
                            m.payload.len(),
                            m.expected_text(),
                            m.fault,
                            hex::format(&p.payload)
                        ));
                    }
                }
                None if !p.payload.is_empty() => {
                    s.push_str(&format!("       payload = {}\n", hex::format(&p.payload)))
                }
                None => {}
            }
        }
        Err(e) => {
            s.push_str(&format!(
                "@{:<4} !! {e}\n       {}\n",
                item.offset,
                hex::format(e.bytes())
            ));
        }
    }
    s
}
