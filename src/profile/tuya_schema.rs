//! The Tuya IoT platform's data-point schema (TUYA_FIELD_NOTES §8) to and from a profile's data
//! points: `id`, `code`, `name`, `mode` (`rw`, `ro`, `wr`), `type` (`obj` or `raw`) and
//! `property` (`type` bool / value / enum / string / bitmap / raw; a value's `min`, `max`,
//! `step` and `scale` in transmitted units and its `unit`; an enum's `range`; a string's or raw's
//! `maxlen`; a bitmap's `label` and `maxlen` bits). Numbers may arrive as strings
//! (`"maxlen":"255"`) and unknown keys are ignored. A malformed or contradictory schema is
//! refused with the JSON path of the problem (`[3].property.max`).

use super::{Access, Bit, DataPointDef, Field, FieldType, Label, Len, Profile};
use crate::i18n::Text;
use crate::protocol::tuya::dp::DpType;
use serde_json::{Map, Value as Json, json};

/// Why a schema cannot be imported: where (a JSON path into the schema) and what.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{path}: {message}")]
pub struct SchemaError {
    /// The JSON path of the problem: `[3].property.max`, or `$` for the whole document.
    pub path: String,
    /// What is wrong, with the value found and what is expected.
    pub message: String,
}

fn err(path: &str, message: impl Into<String>) -> SchemaError {
    SchemaError {
        path: path.to_string(),
        message: message.into(),
    }
}

/// The data points a schema describes, checked: ids 1-255 and codes each used once, codes that
/// are identifiers, each property complete and consistent (min ≤ max, step > 0, scale 0-9, an
/// enum with labels, a bitmap's labels within its `maxlen` ≤ 32 bits, lengths 1-65535).
pub fn data_points(schema: &str) -> Result<Vec<DataPointDef>, SchemaError> {
    let doc: Json = serde_json::from_str(schema).map_err(|e| {
        err(
            &format!("$ (line {}, column {})", e.line(), e.column()),
            format!("not JSON: {e}"),
        )
    })?;
    let list = match &doc {
        Json::Array(a) => a,
        // The cloud's reply wraps the list: {"schema": [...]} (or the list as a string).
        Json::Object(o) => match o.get("schema") {
            Some(Json::Array(a)) => a,
            _ => {
                return Err(err(
                    "$",
                    "expected a list of data points (or {\"schema\": [...]})",
                ));
            }
        },
        _ => return Err(err("$", "expected a list of data points")),
    };
    if list.is_empty() {
        return Err(err("$", "the schema has no data points"));
    }
    let mut out: Vec<DataPointDef> = Vec::new();
    for (i, item) in list.iter().enumerate() {
        let path = format!("[{i}]");
        let dp = data_point(&path, item)?;
        if out.iter().any(|d| d.id == dp.id) {
            return Err(err(
                &format!("{path}.id"),
                format!("data point {} is defined twice", dp.id),
            ));
        }
        if out.iter().any(|d| d.field.ident == dp.field.ident) {
            return Err(err(
                &format!("{path}.code"),
                format!("code '{}' is used by two data points", dp.field.ident),
            ));
        }
        out.push(dp);
    }
    Ok(out)
}

/// A number, or a number written as a string.
fn int(path: &str, v: Option<&Json>, what: &str) -> Result<Option<i64>, SchemaError> {
    match v {
        None | Some(Json::Null) => Ok(None),
        Some(Json::Number(n)) => n
            .as_i64()
            .map(Some)
            .ok_or_else(|| err(path, format!("{what} {n} is not a whole number"))),
        Some(Json::String(s)) => s
            .trim()
            .parse()
            .map(Some)
            .map_err(|_| err(path, format!("{what} '{s}' is not a whole number"))),
        Some(other) => Err(err(path, format!("{what} {other} is not a number"))),
    }
}

fn text<'j>(
    path: &str,
    o: &'j Map<String, Json>,
    key: &str,
) -> Result<Option<&'j str>, SchemaError> {
    match o.get(key) {
        None | Some(Json::Null) => Ok(None),
        Some(Json::String(s)) => Ok(Some(s.as_str())),
        Some(other) => Err(err(
            &format!("{path}.{key}"),
            format!("{other} is not text"),
        )),
    }
}

/// A code as an identifier: lower case, `-` and spaces as `_`; it must then be `[a-z_][a-z0-9_]*`.
fn ident(path: &str, code: &str) -> Result<String, SchemaError> {
    let id: String = code
        .trim()
        .to_ascii_lowercase()
        .chars()
        .map(|c| if c == '-' || c == ' ' { '_' } else { c })
        .collect();
    let ok = id
        .chars()
        .next()
        .is_some_and(|c| c.is_ascii_lowercase() || c == '_')
        && id
            .chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_');
    if ok {
        Ok(id)
    } else {
        Err(err(
            path,
            format!("'{code}' is not an identifier (letters, digits, _)"),
        ))
    }
}

/// A name in both languages: Chinese text is the Chinese name (the English one then the code
/// in words); other text is both.
fn names(name: Option<&str>, code: &str) -> Text {
    let words = || code.replace('_', " ");
    match name.map(str::trim).filter(|n| !n.is_empty()) {
        Some(n) if !n.is_ascii() => Text::new(words(), n.to_string()),
        Some(n) => Text::new(n.to_string(), n.to_string()),
        None => Text::new(words(), words()),
    }
}

fn data_point(path: &str, item: &Json) -> Result<DataPointDef, SchemaError> {
    let Json::Object(o) = item else {
        return Err(err(
            path,
            "expected an object with id, code, mode, type, property",
        ));
    };
    let id = int(&format!("{path}.id"), o.get("id"), "id")?.ok_or_else(|| err(path, "no id"))?;
    let id = u8::try_from(id)
        .ok()
        .filter(|i| *i > 0)
        .ok_or_else(|| err(&format!("{path}.id"), format!("id {id} is not 1 to 255")))?;
    let code = text(path, o, "code")?.ok_or_else(|| err(path, "no code"))?;
    let code = ident(&format!("{path}.code"), code)?;
    let access = match text(path, o, "mode")? {
        Some("rw") => Access::ReadWrite,
        Some("ro") => Access::ReadOnly,
        Some("wr") => Access::WriteOnly,
        Some(m) => {
            return Err(err(
                &format!("{path}.mode"),
                format!("'{m}' is none of rw, ro, wr"),
            ));
        }
        None => return Err(err(path, "no mode (rw, ro or wr)")),
    };
    let outer = text(path, o, "type")?;
    let empty = Map::new();
    let prop = match o.get("property") {
        Some(Json::Object(p)) => p,
        None | Some(Json::Null) => &empty,
        Some(other) => {
            return Err(err(
                &format!("{path}.property"),
                format!("{other} is not an object"),
            ));
        }
    };
    let ppath = format!("{path}.property");
    let ptype = text(&ppath, prop, "type")?;
    let kind = match (outer, ptype) {
        (Some("raw"), None | Some("raw")) => "raw",
        (Some("raw"), Some(t)) => {
            return Err(err(
                &format!("{ppath}.type"),
                format!("'{t}' contradicts the data point's type raw"),
            ));
        }
        (Some("obj") | None, Some("raw")) => {
            return Err(err(
                &format!("{path}.type"),
                "property type raw needs the data point's type raw",
            ));
        }
        (Some("obj") | None, Some(t)) => t,
        (Some("obj") | None, None) => {
            return Err(err(&ppath, "no type (bool, value, enum, string, bitmap)"));
        }
        (Some(t), _) => {
            return Err(err(
                &format!("{path}.type"),
                format!("'{t}' is neither obj nor raw"),
            ));
        }
    };
    let name = names(text(path, o, "name")?, &code);
    let mut field = Field::plain(&code, FieldType::Bool);
    field.name = name;
    let mut dp = DataPointDef {
        id,
        access,
        dp_type: DpType::Bool,
        field,
        max_len: None,
        step: None,
    };
    property(&ppath, kind, prop, &mut dp)?;
    Ok(dp)
}

/// Fills the type, range, scale, unit, labels, bits and maximum length from the property.
fn property(
    path: &str,
    kind: &str,
    p: &Map<String, Json>,
    dp: &mut DataPointDef,
) -> Result<(), SchemaError> {
    let at = |k: &str| format!("{path}.{k}");
    let maxlen = |dp_max: i64| -> Result<Option<u16>, SchemaError> {
        match int(&at("maxlen"), p.get("maxlen"), "maxlen")? {
            None => Ok(None),
            Some(n) if (1..=dp_max).contains(&n) => Ok(Some(n as u16)),
            Some(n) => Err(err(
                &at("maxlen"),
                format!("maxlen {n} is not 1 to {dp_max}"),
            )),
        }
    };
    match kind {
        "bool" => dp.dp_type = DpType::Bool,
        "value" => value(path, p, dp)?,
        "enum" => {
            dp.dp_type = DpType::Enum;
            dp.field.ty = FieldType::U8;
            let labels = strings(&at("range"), p.get("range"))?;
            if labels.is_empty() || labels.len() > 256 {
                return Err(err(
                    &at("range"),
                    format!("{} labels: an enum has 1 to 256", labels.len()),
                ));
            }
            dp.field.labels = labelled(&at("range"), &labels)?
                .into_iter()
                .enumerate()
                .map(|(i, (ident, name))| Label {
                    value: i as i64,
                    ident,
                    name,
                })
                .collect();
        }
        "string" | "raw" => {
            let string = kind == "string";
            dp.dp_type = if string { DpType::String } else { DpType::Raw };
            dp.field.ty = if string {
                FieldType::Str(Len::Rest)
            } else {
                FieldType::Bytes(Len::Rest)
            };
            dp.max_len = maxlen(65_535)?;
        }
        "bitmap" => {
            dp.dp_type = DpType::Bitmap;
            let labels = strings(&at("label"), p.get("label"))?;
            let bits = maxlen(32)?.map_or(labels.len(), usize::from);
            if labels.len() > bits || bits == 0 || bits > 32 {
                return Err(err(
                    &at("label"),
                    format!(
                        "{} labels for a bitmap of {bits} bits (maxlen; at most 32)",
                        labels.len()
                    ),
                ));
            }
            dp.field.ty = match bits {
                ..=8 => FieldType::U8,
                9..=16 => FieldType::U16,
                _ => FieldType::U32,
            };
            dp.field.bits = labelled(&at("label"), &labels)?
                .into_iter()
                .enumerate()
                .map(|(i, (ident, name))| Bit {
                    bit: i as u8,
                    ident,
                    name,
                })
                .collect();
        }
        other => {
            return Err(err(
                &at("type"),
                format!("'{other}' is none of bool, value, enum, string, bitmap, raw"),
            ));
        }
    }
    Ok(())
}

/// A value's range, step, scale and unit: min ≤ max, step ≥ 1, scale 0-9 (real = raw ÷ 10^scale).
fn value(path: &str, p: &Map<String, Json>, dp: &mut DataPointDef) -> Result<(), SchemaError> {
    let at = |k: &str| format!("{path}.{k}");
    dp.dp_type = DpType::Value;
    dp.field.ty = FieldType::I32;
    let min =
        int(&at("min"), p.get("min"), "min")?.ok_or_else(|| err(path, "a value needs min"))?;
    let max =
        int(&at("max"), p.get("max"), "max")?.ok_or_else(|| err(path, "a value needs max"))?;
    let i32_ok = |v: i64| i32::try_from(v).is_ok();
    if !i32_ok(min) || !i32_ok(max) {
        return Err(err(
            &at("max"),
            format!("{min} to {max} does not fit a 32-bit value"),
        ));
    }
    if min > max {
        return Err(err(&at("max"), format!("max {max} is below min {min}")));
    }
    let step = int(&at("step"), p.get("step"), "step")?.unwrap_or(1);
    if step < 1 || step > (max - min).max(1) {
        return Err(err(
            &at("step"),
            format!("step {step} is not 1 to max − min ({})", max - min),
        ));
    }
    let scale = int(&at("scale"), p.get("scale"), "scale")?.unwrap_or(0);
    if !(0..=9).contains(&scale) {
        return Err(err(
            &at("scale"),
            format!("scale {scale} is not 0 to 9 (a power of ten)"),
        ));
    }
    dp.field.range = Some((min, max));
    dp.step = (step > 1).then_some(step);
    dp.field.scale = 10f64.powi(-(scale as i32));
    dp.field.unit = text(path, p, "unit")?
        .unwrap_or_default()
        .trim()
        .to_string();
    Ok(())
}

fn strings(path: &str, v: Option<&Json>) -> Result<Vec<String>, SchemaError> {
    match v {
        Some(Json::Array(a)) => a
            .iter()
            .enumerate()
            .map(|(i, s)| match s {
                Json::String(s) => Ok(s.clone()),
                other => Err(err(&format!("{path}[{i}]"), format!("{other} is not text"))),
            })
            .collect(),
        None | Some(Json::Null) => Err(err(path, "missing: a list of labels")),
        Some(other) => Err(err(path, format!("{other} is not a list of labels"))),
    }
}

/// Labels as (ident, name), each ident once.
fn labelled(path: &str, labels: &[String]) -> Result<Vec<(String, Text)>, SchemaError> {
    let mut out: Vec<(String, Text)> = Vec::new();
    for (i, l) in labels.iter().enumerate() {
        let at = format!("{path}[{i}]");
        let id = ident(&at, l)?;
        if out.iter().any(|(x, _)| *x == id) {
            return Err(err(&at, format!("label '{l}' is given twice")));
        }
        out.push((id, names(Some(l), l)));
    }
    Ok(out)
}

/// A profile's data points as the platform's schema (the inverse of [`data_points`]): what a
/// profile exports, and what the round trip is tested with.
pub fn schema_of(profile: &Profile) -> Json {
    let dps: Vec<Json> = profile.data_points.iter().map(schema_dp).collect();
    Json::Array(dps)
}

fn schema_dp(d: &DataPointDef) -> Json {
    let f = &d.field;
    let property = match d.dp_type {
        DpType::Bool => json!({"type": "bool"}),
        DpType::Value => {
            let (min, max) = f.range.unwrap_or((i32::MIN as i64, i32::MAX as i64));
            let scale = (-f.scale.log10()).round() as i64;
            json!({"type": "value", "min": min, "max": max, "step": d.step.unwrap_or(1),
                   "scale": scale, "unit": f.unit})
        }
        DpType::Enum => {
            json!({"type": "enum", "range": f.labels.iter().map(|l| &l.ident).collect::<Vec<_>>()})
        }
        DpType::String => json!({"type": "string", "maxlen": d.max_len.unwrap_or(255)}),
        DpType::Raw => json!({"type": "raw", "maxlen": d.max_len.unwrap_or(255)}),
        DpType::Bitmap => {
            let width = match f.ty {
                FieldType::U8 => 8,
                FieldType::U16 => 16,
                _ => 32,
            };
            let bits = f.bits.iter().map(|b| b.bit + 1).max().unwrap_or(0).max(1);
            let mut labels: Vec<String> = (0..bits).map(|i| format!("bit{i}")).collect();
            for b in &f.bits {
                labels[usize::from(b.bit)].clone_from(&b.ident);
            }
            json!({"type": "bitmap", "maxlen": bits.min(width), "label": labels})
        }
    };
    let ty = if d.dp_type == DpType::Raw {
        "raw"
    } else {
        "obj"
    };
    json!({"id": d.id, "code": f.ident, "name": f.name.en, "mode": d.access.tuya_mode(),
           "type": ty, "property": property})
}

/// A Tuya profile named `id` for the product `schema` describes: the base protocol's commands,
/// panels and limits of `template` (the built-in Tuya profile), the schema's data points.
/// Checked as any profile file is (the RON it writes is read back, [`to_ron`]).
pub fn import(schema: &str, id: &str, template: &Profile) -> Result<Profile, SchemaError> {
    let mut p = template.clone();
    p.id = id.to_string();
    p.name = Text::new(
        format!("{id} (Tuya MCU, imported schema)"),
        format!("{id}(涂鸦MCU,导入的功能定义)"),
    );
    p.data_points = data_points(schema)?;
    let ron = to_ron(&p);
    super::registry::parse(&format!("{id}.ron"), &ron, Some(id))
        .map_err(|e| err("$", format!("the profile made of it does not load: {e}")))
}

/// A profile as RON text, with a header saying where it came from.
pub fn to_ron(p: &Profile) -> String {
    let config = ron::ser::PrettyConfig::new()
        .depth_limit(6)
        .struct_names(false);
    let body = ron::ser::to_string_pretty(p, config).unwrap_or_default();
    format!(
        "// {} — made by `botbench profile import tuya` from the product's data-point schema\n// (TUYA_FIELD_NOTES §8); the base protocol's commands are the built-in Tuya profile's.\n{body}\n",
        p.id
    )
}

/// One data point as a line: `16 clean_area ro value 0 to 9999 ×0.1 m²`.
pub fn summary(d: &DataPointDef) -> String {
    let f = &d.field;
    let mut s = format!(
        "{} {} {} {}",
        d.id,
        f.ident,
        d.access.tuya_mode(),
        d.dp_type.name()
    );
    if let Some((lo, hi)) = f.range {
        s.push_str(&format!(" {lo} to {hi}"));
    }
    if (f.scale - 1.0).abs() > 1e-12 {
        s.push_str(&format!(" ×{}", f.scale));
    }
    if !f.unit.is_empty() {
        s.push_str(&format!(" {}", f.unit));
    }
    if let Some(step) = d.step {
        s.push_str(&format!(" step {step}"));
    }
    if !f.labels.is_empty() {
        let l: Vec<&str> = f.labels.iter().map(|l| l.ident.as_str()).collect();
        s.push_str(&format!(" [{}]", l.join(", ")));
    }
    if !f.bits.is_empty() {
        let b: Vec<String> = f
            .bits
            .iter()
            .map(|b| format!("{}:{}", b.bit, b.ident))
            .collect();
        s.push_str(&format!(" bits [{}]", b.join(", ")));
    }
    if let Some(m) = d.max_len {
        s.push_str(&format!(" max {m} bytes"));
    }
    s
}

/// What changes from `old`'s data points to `new`'s, a line each: `+ …` added, `- …` removed,
/// `~ old → new` changed; empty when they are the same.
pub fn diff(old: &Profile, new: &Profile) -> Vec<String> {
    let mut out = Vec::new();
    for d in &old.data_points {
        match new.data_points.iter().find(|n| n.id == d.id) {
            None => out.push(format!("- {}", summary(d))),
            Some(n) if summary(n) != summary(d) => {
                out.push(format!("~ {} → {}", summary(d), summary(n)));
            }
            Some(_) => {}
        }
    }
    for n in &new.data_points {
        if !old.data_points.iter().any(|d| d.id == n.id) {
            out.push(format!("+ {}", summary(n)));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one(json: &str) -> Result<Vec<DataPointDef>, SchemaError> {
        data_points(json)
    }

    #[test]
    fn the_notes_example_reads_with_scales_labels_bits_and_maxima() {
        let dps = one(
            r#"[{"id":16,"code":"clean_area","name":"清扫面积","mode":"ro","type":"obj",
                "property":{"type":"value","min":0,"max":"9999","step":1,"scale":1,"unit":"m²"}},
               {"id":19,"code":"map_config","mode":"ro","type":"raw","property":{"type":"raw","maxlen":"128"}},
               {"id":18,"code":"fault","mode":"ro","type":"obj","scope":"fault",
                "property":{"type":"bitmap","maxlen":7,"label":["a","b","c"]}}]"#,
        )
        .unwrap();
        assert_eq!(dps[0].field.range, Some((0, 9999)));
        assert!((dps[0].field.scale - 0.1).abs() < 1e-12);
        assert_eq!(dps[0].field.name.zh, "清扫面积");
        assert_eq!(dps[0].field.name.en, "clean area");
        assert_eq!(dps[1].max_len, Some(128));
        assert_eq!(dps[2].field.bits.len(), 3);
        assert_eq!(dps[2].field.ty, FieldType::U8);
    }

    #[test]
    fn a_malformed_or_contradictory_schema_is_refused_with_the_path() {
        for (json, path, said) in [
            ("{", "$ (line 1, column 1)", "not JSON"),
            ("[]", "$", "no data points"),
            (
                r#"[{"id":1,"code":"a","mode":"rw","type":"obj","property":{"type":"value","min":5,"max":1}}]"#,
                "[0].property.max",
                "below min",
            ),
            (
                r#"[{"id":1,"code":"a","mode":"rw","type":"obj","property":{"type":"bool"}},
               {"id":1,"code":"b","mode":"rw","type":"obj","property":{"type":"bool"}}]"#,
                "[1].id",
                "defined twice",
            ),
            (
                r#"[{"id":1,"code":"a","mode":"xx","type":"obj","property":{"type":"bool"}}]"#,
                "[0].mode",
                "none of rw",
            ),
            (
                r#"[{"id":1,"code":"a","mode":"ro","type":"raw","property":{"type":"enum"}}]"#,
                "[0].property.type",
                "contradicts",
            ),
            (
                r#"[{"id":1,"code":"a","mode":"ro","type":"obj","property":{"type":"bitmap","maxlen":2,"label":["x","y","z"]}}]"#,
                "[0].property.label",
                "3 labels for a bitmap of 2 bits",
            ),
            (
                r#"[{"id":1,"code":"a","mode":"ro","type":"obj","property":{"type":"enum","range":["x","x"]}}]"#,
                "[0].property.range[1]",
                "given twice",
            ),
            (
                r#"[{"id":300,"code":"a","mode":"ro","type":"obj","property":{"type":"bool"}}]"#,
                "[0].id",
                "not 1 to 255",
            ),
            (
                r#"[{"id":1,"code":"9a","mode":"ro","type":"obj","property":{"type":"bool"}}]"#,
                "[0].code",
                "not an identifier",
            ),
            (
                r#"[{"id":1,"code":"a","mode":"ro","type":"obj","property":{"type":"value","min":0,"max":9,"scale":-1}}]"#,
                "[0].property.scale",
                "not 0 to 9",
            ),
        ] {
            let e = one(json).expect_err(json);
            assert_eq!(e.path, path, "{json}: {e}");
            assert!(e.message.contains(said), "{json}: {e}");
        }
    }
}
