//! Consistency rules that a profile must meet beyond its syntax.

use super::model::{Access, CommandKind, DataPointDef, Field, FieldType, Len, Profile, Protocol};
use crate::document::Step::{self, Index, Key};
use crate::protocol::tuya::dp::DpType;
use std::collections::HashSet;

mod layout;

use layout::{check_decoded_names, check_omitted, check_sync_field, inherit_set_layouts};

/// An inconsistency, with the path to the offending value.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Issue {
    /// Where in the document.
    pub path: Vec<Step>,
    /// What is wrong.
    pub message: String,
}

pub(super) fn issue(path: Vec<Step>, message: impl Into<String>) -> Issue {
    Issue {
        path,
        message: message.into(),
    }
}

/// Checks `profile` and completes it (a Set inherits its Get's reply layout; parameters are put in
/// id order). Returns the first inconsistency found.
pub fn validate(profile: &mut Profile) -> Result<(), Issue> {
    let valid_id = !profile.id.is_empty()
        && profile
            .id
            .chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-');
    if !valid_id {
        return Err(issue(
            vec![Key("id")],
            format!(
                "profile id '{}' must be lower-case letters, digits and dashes",
                profile.id
            ),
        ));
    }
    if profile.device_code.is_some() && profile.protocol != Protocol::Msp {
        return Err(issue(
            vec![Key("device_code")],
            "device_code is for MSP profiles only",
        ));
    }
    let mut groups = HashSet::new();
    for (i, g) in profile.groups.iter().enumerate() {
        if !groups.insert(g.id.as_str()) {
            return Err(issue(
                vec![Key("groups"), Index(i)],
                format!("duplicate group '{}'", g.id),
            ));
        }
    }
    check_commands(profile)?;
    inherit_set_layouts(profile)?;
    // Before `check_params` puts the parameters in id order: paths point into the source.
    check_decoded_names(profile)?;
    check_params(profile)?;
    check_data_points(profile)?;
    check_plots(profile)?;
    check_panels(profile)?;
    super::roles::check_panel_needs(profile)?;
    super::roles::check_roles(profile)?;
    super::relation::validate_relations(profile)?;
    super::stop::check_stop(profile)?;
    Ok(())
}

fn check_panels(p: &Profile) -> Result<(), Issue> {
    let mut seen = HashSet::new();
    for (i, rule) in p.panels.iter().enumerate() {
        let at = |k| vec![Key("panels"), Index(i), Key(k)];
        if !seen.insert(rule.panel) {
            return Err(issue(
                at("panel"),
                format!("{:?} is listed twice", rule.panel),
            ));
        }
        if rule.flag.is_some() && p.protocol != Protocol::Msp {
            return Err(issue(
                at("flag"),
                "a capability flag is an MSP CMD_VERSION bit: MSP profiles only",
            ));
        }
        if let Some(bit) = rule.flag
            && bit > 7
        {
            return Err(issue(
                at("flag"),
                format!("capability flag {bit}: CMD_VERSION has bits 0 to 7"),
            ));
        }
    }
    Ok(())
}

fn check_commands(p: &Profile) -> Result<(), Issue> {
    let mut ids = HashSet::new();
    let mut idents = HashSet::new();
    for (i, c) in p.commands.iter().enumerate() {
        let at = |k| vec![Key("commands"), Index(i), Key(k)];
        if !ids.insert(c.id) {
            return Err(issue(at("id"), format!("duplicate command id {}", c.id)));
        }
        if c.ident.is_empty() || !idents.insert(c.ident.to_ascii_lowercase()) {
            return Err(issue(
                at("ident"),
                format!("duplicate or empty command ident '{}'", c.ident),
            ));
        }
        if let Some(g) = &c.group
            && !p.groups.iter().any(|x| &x.id == g)
        {
            return Err(issue(
                at("group"),
                format!("{}: no group '{g}' in `groups`", c.ident),
            ));
        }
        if c.tunable && c.kind != CommandKind::Get {
            return Err(issue(
                at("tunable"),
                format!("{}: `tunable` marks a Get (its Set follows)", c.ident),
            ));
        }
        if c.device.is_some() && p.protocol != Protocol::Msp {
            return Err(issue(at("device"), "`device` is for MSP commands only"));
        }
        if c.reply_command.is_some() && p.protocol != Protocol::Tuya {
            return Err(issue(
                at("reply_command"),
                "`reply_command` is for Tuya commands only",
            ));
        }
        match (c.kind, c.pair) {
            (CommandKind::Set, None) => {
                return Err(issue(
                    at("pair"),
                    format!("{} is a Set without its Get (`pair`)", c.ident),
                ));
            }
            (CommandKind::Get | CommandKind::Set, Some(pair)) => {
                let want = if c.kind == CommandKind::Set {
                    CommandKind::Get
                } else {
                    CommandKind::Set
                };
                let partner = p.commands.iter().find(|x| x.id == pair);
                match partner {
                    Some(x) if x.kind == want && x.pair == Some(c.id) => {}
                    Some(x) => {
                        return Err(issue(
                            at("pair"),
                            format!(
                                "{} pairs with {} ({}), which is not a {:?} pairing back to {}",
                                c.ident, x.ident, x.id, want, c.id
                            ),
                        ));
                    }
                    None => {
                        return Err(issue(
                            at("pair"),
                            format!("{}: no command {pair} to pair with", c.ident),
                        ));
                    }
                }
            }
            (_, Some(_)) if c.kind != CommandKind::Get => {
                return Err(issue(
                    at("pair"),
                    format!("{}: only Get and Set commands pair", c.ident),
                ));
            }
            _ => {}
        }
        for (part, fields) in [("request", &c.request), ("reply", &c.reply)] {
            check_fields(p, fields, &|j, k| {
                let mut v = at(part);
                v.push(Index(j));
                if let Some(k) = k {
                    v.push(Key(k));
                }
                v
            })?;
        }
    }
    Ok(())
}

pub(super) type PathFn<'a> = dyn Fn(usize, Option<&'static str>) -> Vec<Step> + 'a;

fn check_fields(p: &Profile, fields: &[Field], at: &PathFn<'_>) -> Result<(), Issue> {
    let mut idents = HashSet::new();
    let mut seen_optional = false;
    for (j, f) in fields.iter().enumerate() {
        let last = j + 1 == fields.len();
        if f.ident.is_empty() || !idents.insert(f.ident.to_ascii_lowercase()) {
            return Err(issue(
                at(j, Some("ident")),
                format!("duplicate or empty field ident '{}'", f.ident),
            ));
        }
        if f.ident.contains(['.', '[', ']', '=']) {
            return Err(issue(
                at(j, Some("ident")),
                format!(
                    "field ident '{}': '.', '[', ']' and '=' are kept for relations, records and FIELD=VALUE",
                    f.ident
                ),
            ));
        }
        check_field(f, &|k| at(j, k))?;
        if f.optional {
            seen_optional = true;
        } else if seen_optional {
            return Err(issue(
                at(j, Some("optional")),
                format!(
                    "{}: a required field cannot follow an optional one",
                    f.ident
                ),
            ));
        }
        let needs_last = matches!(
            f.ty,
            FieldType::Bytes(Len::Rest) | FieldType::Str(Len::Rest) | FieldType::DataPoints
        );
        if needs_last && !last {
            return Err(issue(
                at(j, Some("type")),
                format!(
                    "{}: a field that takes the rest of the payload must be last",
                    f.ident
                ),
            ));
        }
        let servo_only = matches!(
            f.ty,
            FieldType::ParamId | FieldType::ParamValue | FieldType::ParamBlock
        );
        if servo_only && (p.protocol != Protocol::Servo || p.params.is_empty()) {
            return Err(issue(
                at(j, Some("type")),
                format!(
                    "{}: parameter fields need a servo profile with `params`",
                    f.ident
                ),
            ));
        }
        if f.ty == FieldType::ParamValue && (j == 0 || fields[j - 1].ty != FieldType::ParamId) {
            return Err(issue(
                at(j, Some("type")),
                format!("{}: a ParamValue must follow a ParamId", f.ident),
            ));
        }
        if f.ty == FieldType::DataPoints && p.protocol != Protocol::Tuya {
            return Err(issue(
                at(j, Some("type")),
                format!("{}: DataPoints are for Tuya profiles only", f.ident),
            ));
        }
        check_sync_field(p, fields, j, at)?;
    }
    check_omitted(fields, at)
}

/// Checks one field's own consistency: scale, range, default, labels, bits.
pub fn check_field(f: &Field, at: &dyn Fn(Option<&'static str>) -> Vec<Step>) -> Result<(), Issue> {
    if !(f.scale.is_finite() && f.scale > 0.0) {
        return Err(issue(
            at(Some("scale")),
            format!("{}: scale must be a positive number", f.ident),
        ));
    }
    let bounds = f.ty.int_bounds();
    if let Some((lo, hi)) = f.range {
        let Some((tlo, thi)) = bounds else {
            return Err(issue(
                at(Some("range")),
                format!("{}: only integer fields have a range", f.ident),
            ));
        };
        if lo > hi {
            return Err(issue(
                at(Some("range")),
                format!("{}: range ({lo}, {hi}) is empty", f.ident),
            ));
        }
        if lo < tlo || hi > thi {
            return Err(issue(
                at(Some("range")),
                format!(
                    "{}: range ({lo}, {hi}) is wider than its type {:?} ({tlo} to {thi})",
                    f.ident, f.ty
                ),
            ));
        }
    }
    let mut values = HashSet::new();
    let mut names = HashSet::new();
    for l in &f.labels {
        let Some((tlo, thi)) = bounds else {
            return Err(issue(
                at(Some("labels")),
                format!("{}: only integer fields have labels", f.ident),
            ));
        };
        if !(tlo..=thi).contains(&l.value)
            || !values.insert(l.value)
            || !names.insert(l.ident.to_ascii_lowercase())
        {
            return Err(issue(
                at(Some("labels")),
                format!(
                    "{}: label '{}' = {} is duplicated or outside the type",
                    f.ident, l.ident, l.value
                ),
            ));
        }
    }
    let bits =
        f.ty.width()
            .filter(|_| bounds.is_some())
            .map_or(0, |w| w * 8);
    let mut seen = HashSet::new();
    for b in &f.bits {
        if b.bit as usize >= bits || !seen.insert(b.bit) {
            return Err(issue(
                at(Some("bits")),
                format!(
                    "{}: bit {} is duplicated or outside the type",
                    f.ident, b.bit
                ),
            ));
        }
    }
    if let Some(d) = f.default
        && let Err(e) = f.check(&super::Value::Int(d))
    {
        return Err(issue(at(Some("default")), format!("default: {e}")));
    }
    if let Some(v) = f.omitted_when
        && let Err(e) = f.check(&super::Value::Int(v))
    {
        return Err(issue(
            at(Some("omitted_when")),
            format!("omitted_when: {e}"),
        ));
    }
    if let Some(c) = f.convert {
        let super::model::Conversion::Ntc { beta, full_scale } = c;
        if bounds.is_none() || f.scale != 1.0 || !(beta.is_finite() && beta > 0.0) || full_scale < 2
        {
            return Err(issue(
                at(Some("convert")),
                format!(
                    "{}: a conversion needs an integer field of scale 1, a positive beta and a full scale of 2 or more",
                    f.ident
                ),
            ));
        }
    }
    Ok(())
}

fn check_params(p: &mut Profile) -> Result<(), Issue> {
    if p.params.is_empty() {
        return Ok(());
    }
    if p.protocol != Protocol::Servo {
        return Err(issue(
            vec![Key("params")],
            "`params` are for servo profiles only",
        ));
    }
    let mut ids = HashSet::new();
    let mut idents = HashSet::new();
    for (i, prm) in p.params.iter().enumerate() {
        let at = |k: Option<&'static str>| {
            let mut v = vec![Key("params"), Index(i)];
            match k {
                Some(k) => v.extend([Key("field"), Key(k)]),
                None => v.push(Key("id")),
            }
            v
        };
        if !ids.insert(prm.id) {
            return Err(issue(
                at(None),
                format!("duplicate parameter id {}", prm.id),
            ));
        }
        if !idents.insert(prm.field.ident.to_ascii_lowercase()) {
            return Err(issue(
                at(Some("ident")),
                format!("duplicate parameter ident '{}'", prm.field.ident),
            ));
        }
        if prm.field.ty.int_bounds().is_none() {
            return Err(issue(
                at(Some("type")),
                format!("{}: parameters are integers", prm.field.ident),
            ));
        }
        if prm.access == Access::WriteOnly {
            return Err(issue(
                vec![Key("params"), Index(i), Key("access")],
                format!(
                    "{}: a servo parameter is ReadOnly or ReadWrite (WriteOnly is for Tuya data points)",
                    prm.field.ident
                ),
            ));
        }
        check_field(&prm.field, &at)?;
    }
    p.params.sort_by_key(|x| x.id);
    let block: usize = p
        .params
        .iter()
        .filter(|x| x.access == Access::ReadWrite)
        .filter_map(|x| x.field.ty.width())
        .sum();
    if block != 0 && block != 32 {
        return Err(issue(
            vec![Key("params")],
            format!(
                "the read-write parameters make a user block of {block} bytes; the protocol's is 32"
            ),
        ));
    }
    Ok(())
}

fn check_data_points(p: &Profile) -> Result<(), Issue> {
    if !p.data_points.is_empty() && p.protocol != Protocol::Tuya {
        return Err(issue(
            vec![Key("data_points")],
            "`data_points` are for Tuya profiles only",
        ));
    }
    let mut ids = HashSet::new();
    let mut idents = HashSet::new();
    for (i, d) in p.data_points.iter().enumerate() {
        let at = |k: Option<&'static str>| {
            let mut v = vec![Key("data_points"), Index(i)];
            match k {
                Some(k) => v.extend([Key("field"), Key(k)]),
                None => v.push(Key("id")),
            }
            v
        };
        if !ids.insert(d.id) {
            return Err(issue(at(None), format!("duplicate data point id {}", d.id)));
        }
        if !idents.insert(d.field.ident.to_ascii_lowercase()) {
            return Err(issue(
                at(Some("ident")),
                format!("duplicate data point ident '{}'", d.field.ident),
            ));
        }
        let fits = matches!(
            (d.dp_type, d.field.ty),
            (DpType::Raw, FieldType::Bytes(_))
                | (DpType::Bool, FieldType::Bool)
                | (DpType::Value, FieldType::I32)
                | (DpType::String, FieldType::Str(_))
                | (DpType::Enum, FieldType::U8)
                | (
                    DpType::Bitmap,
                    FieldType::U8 | FieldType::U16 | FieldType::U32
                )
        );
        if !fits {
            return Err(issue(
                at(Some("type")),
                format!(
                    "{}: field type {:?} does not suit a {} data point",
                    d.field.ident,
                    d.field.ty,
                    d.dp_type.name()
                ),
            ));
        }
        check_field(&d.field, &at)?;
        check_dp_limits(d, i)?;
    }
    Ok(())
}

/// A data point's own limits: `max_len` on strings and raw bytes only, `step` on values only
/// (positive), and a value's scale a power of ten as the Tuya schema's is.
fn check_dp_limits(d: &DataPointDef, i: usize) -> Result<(), Issue> {
    let at = |k: &'static str| vec![Key("data_points"), Index(i), Key(k)];
    let ident = &d.field.ident;
    if d.max_len.is_some() && !matches!(d.dp_type, DpType::String | DpType::Raw) {
        return Err(issue(
            at("max_len"),
            format!("{ident}: `max_len` is for string and raw data points"),
        ));
    }
    match d.step {
        Some(_) if d.dp_type != DpType::Value => Err(issue(
            at("step"),
            format!("{ident}: `step` is for value data points"),
        )),
        Some(s) if s < 1 => Err(issue(
            at("step"),
            format!("{ident}: `step` is 1 or more (raw units), not {s}"),
        )),
        _ if d.dp_type == DpType::Value
            && super::data_point::decimal_scale(d.field.scale).is_none() =>
        {
            Err(issue(
                vec![Key("data_points"), Index(i), Key("field"), Key("scale")],
                format!(
                    "{ident}: a value data point's scale is a power of ten (1, 0.1, 0.01 …), not {}",
                    d.field.scale
                ),
            ))
        }
        _ => Ok(()),
    }
}

fn check_plots(p: &Profile) -> Result<(), Issue> {
    for (i, plot) in p.plots.iter().enumerate() {
        let Some(cmd) = p
            .commands
            .iter()
            .find(|c| c.ident.eq_ignore_ascii_case(&plot.command))
        else {
            return Err(issue(
                vec![Key("plots"), Index(i), Key("command")],
                format!("plot '{}': no command '{}'", plot.id, plot.command),
            ));
        };
        let reply = |name: &str| {
            cmd.reply
                .iter()
                .find(|f| f.ident.eq_ignore_ascii_case(name))
        };
        for (j, name) in plot.fields.iter().enumerate() {
            let at = vec![Key("plots"), Index(i), Key("fields"), Index(j)];
            match reply(name) {
                Some(f) if f.is_measurement() => {}
                Some(f) if f.is_state() => {
                    return Err(issue(
                        at,
                        format!(
                            "plot '{}': {}'s '{name}' is {} (its codes are no quantity to draw \
                             as a line): list it under states, to show its names beside the plot",
                            plot.id,
                            cmd.ident,
                            state_kind(f)
                        ),
                    ));
                }
                _ => {
                    return Err(issue(
                        at,
                        format!(
                            "plot '{}': {} has no numeric reply field '{name}'",
                            plot.id, cmd.ident
                        ),
                    ));
                }
            }
        }
        for (j, name) in plot.states.iter().enumerate() {
            if !reply(name).is_some_and(Field::is_state) {
                return Err(issue(
                    vec![Key("plots"), Index(i), Key("states"), Index(j)],
                    format!(
                        "plot '{}': {} has no enum, flag or bit field '{name}' (a measurement \
                         goes under fields)",
                        plot.id, cmd.ident
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// What kind of state field `f` is, for a message.
fn state_kind(f: &Field) -> &'static str {
    if !f.bits.is_empty() {
        "a bit field"
    } else if !f.labels.is_empty() {
        "an enum (named values)"
    } else {
        "a flag"
    }
}
