//! `botbench profiles`: the device profiles, listed, and one shown whole (its commands, their
//! fields, its servo parameters and Tuya data points), so that a command line's names can be
//! looked up where they are defined.

use super::{CliError, CliResult, registry};
use crate::profile::{Command, CommandKind, Field, FieldType, Len, Profile};
use clap::Subcommand;

/// `botbench profiles [show NAME]`.
#[derive(Debug, clap::Args)]
pub(crate) struct ProfilesArgs {
    #[command(subcommand)]
    cmd: Option<ProfilesCmd>,
    /// Print JSON.
    #[arg(long, global = true)]
    json: bool,
}

#[derive(Debug, Subcommand)]
enum ProfilesCmd {
    /// List the device profiles and where each comes from (the default).
    List,
    /// One profile whole: its commands (number, name, kind), each command's fields (type,
    /// unit, range, labels), its servo parameters and its Tuya data points.
    Show {
        /// A profile's id (`botbench profiles` lists them), or a .ron file.
        name: String,
    },
}

pub(crate) fn run(args: ProfilesArgs) -> CliResult {
    match args.cmd {
        None | Some(ProfilesCmd::List) => list(args.json),
        Some(ProfilesCmd::Show { name }) => show(&name, args.json),
    }
}

/// Where a profile comes from, as `profiles` says it.
fn source_text(source: &crate::profile::Source) -> String {
    match source {
        crate::profile::Source::Builtin => "built-in".to_string(),
        crate::profile::Source::File(path) => path.display().to_string(),
    }
}

/// The hardware code a profile is for (MSP's CMD_VERSION `hw`), as `0x04`.
fn hardware_code(profile: &Profile) -> Option<String> {
    profile.device_code.map(|c| format!("{:#04x}", c.initial()))
}

fn list(json: bool) -> CliResult {
    let reg = registry()?;
    for (p, source) in reg.iter() {
        let source = source_text(source);
        if json {
            let doc = serde_json::json!({
                "id": p.id, "name": p.name.en, "name_zh": p.name.zh,
                "protocol": p.protocol.name(), "baud": p.baud,
                "hardware_code": hardware_code(p),
                "commands": p.commands.len(), "source": source,
            });
            outln!("{doc}");
        } else {
            outln!(
                "{:<28} {:<6} {:>7} baud  {:>3} commands  {} / {}  ({source})",
                p.id,
                p.protocol.name(),
                p.baud,
                p.commands.len(),
                p.name.en,
                p.name.zh
            );
        }
    }
    if !json && super::console::stdout_is_terminal() {
        outln!(
            "(`botbench profiles show NAME` lists a profile's commands, fields and data points)"
        );
    }
    Ok(0)
}

/// The wire type of a field as `profiles show` says it: `U8`, `I16`, `text`, `text[16]`,
/// `bytes[4]`, `data points`...
fn type_text(ty: FieldType) -> String {
    match ty {
        FieldType::Str(Len::Fixed(n)) => format!("text[{n}]"),
        FieldType::Str(Len::Rest) => "text".into(),
        FieldType::Bytes(Len::Fixed(n)) => format!("bytes[{n}]"),
        FieldType::Bytes(Len::Rest) => "bytes".into(),
        FieldType::DataPoints => "data points".into(),
        FieldType::ParamId => "parameter id".into(),
        FieldType::ParamValue => "parameter value".into(),
        FieldType::ParamBlock => "parameter block".into(),
        other => format!("{other:?}"),
    }
}

/// What a field takes, for the text view: the range with its unit, or the labels.
fn allowed(field: &Field) -> String {
    match field.ty {
        FieldType::U8
        | FieldType::I8
        | FieldType::U16
        | FieldType::I16
        | FieldType::U32
        | FieldType::I32
        | FieldType::Bool
        | FieldType::Str(_)
        | FieldType::Bytes(_) => field.allowed_text(),
        _ => String::new(),
    }
}

/// A field as JSON: ident, names, type, unit, scale, range (raw), what it takes, labels.
fn field_json(field: &Field) -> serde_json::Value {
    serde_json::json!({
        "ident": field.ident, "name": field.name.en, "name_zh": field.name.zh,
        "type": type_text(field.ty), "unit": field.unit, "scale": field.scale,
        "range": field.range, "allowed": allowed(field),
        "labels": field.labels.iter().map(|l| serde_json::json!({
            "value": l.value, "ident": l.ident, "name": l.name.en,
        })).collect::<Vec<_>>(),
        "bits": field.bits.iter().map(|b| serde_json::json!({
            "bit": b.bit, "ident": b.ident, "name": b.name.en,
        })).collect::<Vec<_>>(),
    })
}

/// A command's kind as `profiles show` says it: `Get`, `Set`, `Telemetry`, `Action`, `Raw`.
fn kind_text(cmd: &Command) -> &'static str {
    match cmd.kind {
        CommandKind::Get => "Get",
        CommandKind::Set => "Set",
        CommandKind::Telemetry => "Telemetry",
        CommandKind::Action => "Action",
        CommandKind::Raw => "Raw",
    }
}

/// What more there is to say of a command: its Get or Set partner, an optional answer, a
/// device request.
fn command_notes(profile: &Profile, cmd: &Command) -> Vec<String> {
    let mut notes = Vec::new();
    if let Some(pair) = cmd.pair.and_then(|id| profile.command_by_id(id)) {
        let role = if cmd.kind == CommandKind::Get {
            "its Set"
        } else {
            "its Get"
        };
        notes.push(format!("{role}: {}", pair.ident));
    }
    if cmd.reply_optional {
        notes.push("answered only with the servo's response switch on".into());
    }
    if cmd.initiator == crate::profile::Initiator::Device {
        notes.push("sent by the device".into());
    }
    notes
}

fn show(name: &str, json: bool) -> CliResult {
    let reg = registry()?;
    let profile = reg.get(name).map_err(CliError::input)?;
    let source = reg
        .iter()
        .find(|(p, _)| p.id == profile.id && !name.ends_with(".ron"))
        .map_or_else(|| name.to_string(), |(_, s)| source_text(s));
    if json {
        outln!("{}", show_json(&profile, &source));
        return Ok(0);
    }
    let code = hardware_code(&profile).map_or(String::new(), |c| format!(", hardware code {c}"));
    outln!(
        "{}: {} / {} ({}, {} baud{code}; {source})",
        profile.id,
        profile.name.en,
        profile.name.zh,
        profile.protocol.name(),
        profile.baud
    );
    outln!("\ncommands (number, name, kind):");
    let widths = Widths::of(&profile);
    for cmd in &profile.commands {
        show_command(&profile, cmd, widths);
    }
    if !profile.params.is_empty() {
        outln!("\nservo parameters (data_id, name, access, type, what it takes):");
        for p in &profile.params {
            outln!(
                "  {:>3}  {:<24} {:<10} {:<6} {}",
                p.id,
                p.field.ident,
                format!("{:?}", p.access),
                type_text(p.field.ty),
                allowed(&p.field)
            );
        }
    }
    if !profile.data_points.is_empty() {
        outln!("\ndata points (dpid, name, type, access, what it takes):");
        for dp in &profile.data_points {
            outln!(
                "  {:>3}  {:<24} {:<7} {:<3} {}",
                dp.id,
                dp.field.ident,
                format!("{:?}", dp.dp_type),
                dp.access.tuya_mode(),
                allowed(&dp.field)
            );
        }
    }
    Ok(0)
}

/// The columns of the text view: the longest command and field identifiers of a profile.
#[derive(Clone, Copy)]
struct Widths {
    command: usize,
    field: usize,
}

impl Widths {
    fn of(profile: &Profile) -> Self {
        let longest = |names: &mut dyn Iterator<Item = &String>| {
            names.map(|n| n.chars().count()).max().unwrap_or(0)
        };
        let fields = profile
            .commands
            .iter()
            .flat_map(|c| c.request.iter().chain(&c.reply));
        Self {
            command: longest(&mut profile.commands.iter().map(|c| &c.ident)),
            field: longest(&mut fields.map(|f| &f.ident)),
        }
    }
}

/// One command of the text view, with its request's and answer's fields beneath it.
fn show_command(profile: &Profile, cmd: &Command, w: Widths) {
    let notes = command_notes(profile, cmd);
    let notes = if notes.is_empty() {
        String::new()
    } else {
        format!(" ({})", notes.join("; "))
    };
    outln!(
        "  {:>3}  {:<cw$}  {:<9} {}{notes}",
        cmd.id,
        cmd.ident,
        kind_text(cmd),
        cmd.name.en,
        cw = w.command
    );
    for (part, fields) in [("sends", &cmd.request), ("answer", &cmd.reply)] {
        for f in fields.iter() {
            outln!(
                "         {part:<6} {:<fw$}  {:<15} {}",
                f.ident,
                type_text(f.ty),
                allowed(f),
                fw = w.field
            );
        }
    }
}

fn show_json(profile: &Profile, source: &str) -> serde_json::Value {
    let commands: Vec<serde_json::Value> = profile
        .commands
        .iter()
        .map(|c| {
            serde_json::json!({
                "id": c.id, "ident": c.ident, "name": c.name.en, "name_zh": c.name.zh,
                "kind": kind_text(c), "pair": c.pair.and_then(|id| profile.command_by_id(id)).map(|p| &p.ident),
                "reply_optional": c.reply_optional, "initiator": format!("{:?}", c.initiator),
                "request": c.request.iter().map(field_json).collect::<Vec<_>>(),
                "reply": c.reply.iter().map(field_json).collect::<Vec<_>>(),
            })
        })
        .collect();
    let params: Vec<serde_json::Value> = profile
        .params
        .iter()
        .map(|p| serde_json::json!({ "data_id": p.id, "access": format!("{:?}", p.access), "field": field_json(&p.field) }))
        .collect();
    let data_points: Vec<serde_json::Value> = profile
        .data_points
        .iter()
        .map(|d| {
            serde_json::json!({
                "dpid": d.id, "type": format!("{:?}", d.dp_type), "mode": d.access.tuya_mode(),
                "field": field_json(&d.field),
            })
        })
        .collect();
    serde_json::json!({
        "id": profile.id, "name": profile.name.en, "name_zh": profile.name.zh,
        "protocol": profile.protocol.name(), "baud": profile.baud,
        "hardware_code": hardware_code(profile), "source": source,
        "commands": commands, "params": params, "data_points": data_points,
    })
}

/// The error for a command name `profile` does not have: the nearest names it does have ("did
/// you mean MSP_GET_PWMVALUE?"), and where to see them all.
pub(crate) fn unknown_command(profile: &Profile, name: &str) -> CliError {
    let nearest = profile.nearest_commands(name);
    let guess = match nearest.as_slice() {
        [] => String::new(),
        [one] => format!("; did you mean {one}?"),
        [rest @ .., last] => format!("; did you mean {} or {last}?", rest.join(", ")),
    };
    CliError::input(format!(
        "{} has no command '{}'{guess} (`botbench profiles show {}` lists its commands; a \
         command is named as there, or by its number)",
        profile.id,
        crate::document::quote(name),
        profile.id
    ))
}
