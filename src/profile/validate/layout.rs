//! Layout rules of a profile beyond one field: a Set's own layout, the names of a decoded
//! frame, the fields of a synchronous command, a field the firmware leaves out.

use super::super::model::{Access, CommandKind, Field, FieldType, Profile, Protocol};
use super::{Issue, PathFn, issue};
use crate::document::Step::{self, Index, Key};

pub(super) fn inherit_set_layouts(p: &mut Profile) -> Result<(), Issue> {
    for i in 0..p.commands.len() {
        let c = &p.commands[i];
        if c.kind != CommandKind::Set {
            continue;
        }
        let Some(get) = p.commands.iter().find(|x| Some(x.id) == c.pair) else {
            continue;
        };
        if c.request.is_empty() {
            let fields = get.reply.clone();
            p.commands[i].request = fields;
            continue;
        }
        // A Set of its own layout (firmware that takes fewer fields than its Get answers
        // with): every field it sends must be one its Get reads back, of the same type.
        for (j, f) in c.request.iter().enumerate() {
            let same = get
                .reply
                .iter()
                .any(|g| g.ident == f.ident && g.ty == f.ty && g.scale == f.scale);
            if !same {
                return Err(issue(
                    vec![
                        Key("commands"),
                        Index(i),
                        Key("request"),
                        Index(j),
                        Key("ident"),
                    ],
                    format!(
                        "{}: field '{}' is not a field of its Get {}'s reply with the same type and scale, so the write could not be read back",
                        c.ident, f.ident, get.ident
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// No decoded frame may carry two values of one name: a frame's own fields, the parameters a
/// parameter value or block expands to, and the data points of a Tuya list must all differ.
pub(super) fn check_decoded_names(p: &Profile) -> Result<(), Issue> {
    for (i, c) in p.commands.iter().enumerate() {
        for (part, fields) in [("request", &c.request), ("reply", &c.reply)] {
            let own: Vec<String> = fields
                .iter()
                .filter(|f| !matches!(f.ty, FieldType::ParamValue))
                .map(|f| f.ident.to_ascii_lowercase())
                .collect();
            let clash = |ident: &str| own.iter().any(|o| o.eq_ignore_ascii_case(ident));
            let has = |ty: FieldType| fields.iter().any(|f| f.ty == ty);
            let expands: Vec<(Vec<Step>, &str)> = if has(FieldType::ParamValue) {
                p.params
                    .iter()
                    .enumerate()
                    .map(|(k, x)| (param_path(k), x.field.ident.as_str()))
                    .collect()
            } else if has(FieldType::ParamBlock) {
                p.params
                    .iter()
                    .enumerate()
                    .filter(|(_, x)| x.access == Access::ReadWrite)
                    .map(|(k, x)| (param_path(k), x.field.ident.as_str()))
                    .collect()
            } else if has(FieldType::DataPoints) {
                p.data_points
                    .iter()
                    .enumerate()
                    .map(|(k, d)| {
                        (
                            vec![Key("data_points"), Index(k), Key("field"), Key("ident")],
                            d.field.ident.as_str(),
                        )
                    })
                    .collect()
            } else {
                Vec::new()
            };
            if let Some((path, ident)) = expands.into_iter().find(|(_, id)| clash(id)) {
                return Err(issue(
                    path,
                    format!(
                        "'{ident}' is also a field of {}'s {part} (command {} of the list): a decoded frame would carry two values named '{ident}'",
                        c.ident,
                        i + 1
                    ),
                ));
            }
        }
    }
    Ok(())
}

fn param_path(k: usize) -> Vec<Step> {
    vec![Key("params"), Index(k), Key("field"), Key("ident")]
}

/// The fields of a synchronous command (servo 25): a sub-command, a record length and a count
/// before the records, which come last.
pub(super) fn check_sync_field(
    p: &Profile,
    fields: &[Field],
    j: usize,
    at: &PathFn<'_>,
) -> Result<(), Issue> {
    let f = &fields[j];
    let sync = matches!(
        f.ty,
        FieldType::CommandId | FieldType::RecordLen | FieldType::RecordCount | FieldType::Records
    );
    if !sync {
        return Ok(());
    }
    if p.protocol != Protocol::Servo {
        return Err(issue(
            at(j, Some("type")),
            format!(
                "{}: synchronous-command fields are for servo profiles only",
                f.ident
            ),
        ));
    }
    if f.ty == FieldType::CommandId
        && let Some(l) = f
            .labels
            .iter()
            .find(|l| !u8::try_from(l.value).is_ok_and(|id| p.commands.iter().any(|c| c.id == id)))
    {
        return Err(issue(
            at(j, Some("labels")),
            format!(
                "{}: label '{}' = {} is not a command of the profile",
                f.ident, l.ident, l.value
            ),
        ));
    }
    if f.ty == FieldType::Records {
        let before = |ty: FieldType| fields[..j].iter().filter(|x| x.ty == ty).count() == 1;
        let ok = before(FieldType::CommandId)
            && before(FieldType::RecordLen)
            && before(FieldType::RecordCount)
            && j + 1 == fields.len();
        if !ok {
            return Err(issue(
                at(j, Some("type")),
                format!(
                    "{}: Records come last, after one CommandId, one RecordLen and one RecordCount",
                    f.ident
                ),
            ));
        }
    }
    Ok(())
}

/// A field the firmware leaves out (`omitted_when`) is found by the payload's length: at most
/// one per layout, in a layout of fixed-size, required fields.
pub(super) fn check_omitted(fields: &[Field], at: &PathFn<'_>) -> Result<(), Issue> {
    let omittable: Vec<usize> = (0..fields.len())
        .filter(|&j| fields[j].omitted_when.is_some())
        .collect();
    let Some(&j) = omittable.first() else {
        return Ok(());
    };
    let f = &fields[j];
    let fixed = fields.iter().all(|x| {
        !x.optional
            && x.ty.width().is_some()
            && !matches!(x.ty, FieldType::ParamId | FieldType::ParamBlock)
    });
    if omittable.len() > 1 || !fixed {
        return Err(issue(
            at(j, Some("omitted_when")),
            format!(
                "{}: a payload can leave out one field only, in a layout of fixed-size, required fields",
                f.ident
            ),
        ));
    }
    Ok(())
}
