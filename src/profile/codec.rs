//! The one field codec, decoding side: payload bytes to named, typed values, per the profile.
//! Encoding is in [`super::encode`].

use super::model::{
    Access, ByteOrder, Command, DataPointDef, Field, FieldType, Initiator, Len, Param, Profile,
};
use super::value::{FieldError, Misfit, Value};
use crate::protocol::Direction;
use crate::protocol::hex;
use crate::protocol::tuya::dp::{self, DataPoint, DpType, DpValue};
use serde::Serialize;

pub use super::encode::Input;

/// One decoded value and the field it belongs to.
#[derive(Debug, Clone, Serialize)]
pub struct FieldValue<'p> {
    /// The field's canonical ident (a parameter's or data point's for nested values; `ident[i]`
    /// for record `i` of a synchronous command).
    pub ident: String,
    /// The field's definition.
    #[serde(skip)]
    pub field: &'p Field,
    /// The raw value.
    pub value: Value,
    /// The value lies outside the field's range, or (a Tuya data point) outside what the data
    /// point allows: a device sent what the field does not allow. It is shown with the mark
    /// ([`Field::display`], [`FieldValue::limit`]), never as a clean value.
    pub out_of_range: bool,
    /// A Tuya data point's value outside what the data point allows (no label, undefined bits,
    /// between steps, too long, out of range: [`super::DpLimit`]).
    #[serde(skip_serializing_if = "Option::is_none", serialize_with = "ser_limit")]
    pub limit: Option<super::DpLimit>,
    /// False for a Tuya data point the profile does not have: its value is read by its own
    /// type byte and length, its ident is `dp 101 (not in the profile)` and its field a
    /// stand-in of that type ([`unknown_dp_field`]).
    pub in_profile: bool,
}

fn ser_limit<S: serde::Serializer>(l: &Option<super::DpLimit>, s: S) -> Result<S::Ok, S::Error> {
    match l {
        Some(l) => s.serialize_some(&l.to_string()),
        None => s.serialize_none(),
    }
}

impl<'p> FieldValue<'p> {
    /// A field's value as read from its layout: in the profile, its range checked afterwards.
    fn plain(ident: String, field: &'p Field, value: Value) -> Self {
        FieldValue {
            ident,
            field,
            value,
            out_of_range: false,
            limit: None,
            in_profile: true,
        }
    }

    /// The value as shown: scaled or converted (raw beside it), labelled, with its unit, and
    /// marked when it is out of the field's range or the data point's limits; a data point the
    /// profile lacks as its type and value, `value 50`.
    pub fn display(&self) -> String {
        if !self.in_profile {
            return format!("{} {}", self.field.ident, self.field.format(&self.value));
        }
        match &self.limit {
            // The range's own mark says it: `150 % !! out of range 0 to 100 %`.
            Some(super::DpLimit::OutOfRange { .. }) | None => self.field.display(&self.value),
            Some(l) => format!("{} !! {l}", self.field.display_plain(&self.value)),
        }
    }

    /// The converted number, for a field with a conversion (`None` where it is undefined).
    pub fn converted(&self) -> Option<f64> {
        match (self.field.convert, &self.value) {
            (Some(c), Value::Int(raw)) => c.apply(*raw),
            _ => None,
        }
    }
}

fn ser_error<S: serde::Serializer>(e: &Option<FieldError>, s: S) -> Result<S::Ok, S::Error> {
    match e {
        Some(e) => s.serialize_some(&e.to_string()),
        None => s.serialize_none(),
    }
}

fn ser_hex<S: serde::Serializer>(bytes: &[u8], s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(&hex::format(bytes))
}

/// A decoded payload: the values read, and whether the payload fit the layout.
#[derive(Debug, Clone, Serialize)]
pub struct Decoded<'p> {
    /// The command's ident (empty for a bare field list).
    pub command: String,
    /// The values, in wire order: every value read before a fault.
    pub values: Vec<FieldValue<'p>>,
    /// Bytes past the last field (firmware that sends more than the profile knows).
    #[serde(serialize_with = "ser_hex")]
    pub trailing: Vec<u8>,
    /// The field that could not be read, where decoding stopped; `None` when all were read.
    #[serde(serialize_with = "ser_error")]
    pub error: Option<FieldError>,
    /// The payload as received.
    #[serde(serialize_with = "ser_hex")]
    pub payload: Vec<u8>,
    /// The payload lengths the layout takes: (fewest, most; `None`: no limit).
    pub expected: (usize, Option<usize>),
}

impl Decoded<'_> {
    /// The raw integer of a field, by ident.
    pub fn int(&self, ident: &str) -> Option<i64> {
        self.values.iter().find_map(|v| match v.value {
            Value::Int(i) if v.ident.eq_ignore_ascii_case(ident) => Some(i),
            _ => None,
        })
    }

    /// Whether the payload fit the layout exactly: every field read, nothing left over.
    pub fn fits(&self) -> bool {
        self.error.is_none() && self.trailing.is_empty()
    }

    /// The misfit, when the payload did not fit: the fault (a field it ends inside, or the
    /// bytes left over), the values read before it and the raw bytes.
    pub fn misfit(&self) -> Option<Misfit> {
        let fault = match (&self.error, self.trailing.is_empty()) {
            (Some(e), _) => e.clone(),
            (None, false) => FieldError::LongPayload {
                extra: self.trailing.clone(),
            },
            (None, true) => return None,
        };
        Some(Misfit {
            command: self.command.clone(),
            fault,
            decoded: self
                .values
                .iter()
                .map(|v| (v.ident.clone(), v.value.clone(), v.display()))
                .collect(),
            payload: self.payload.clone(),
            expected: self.expected,
        })
    }
}

/// The payload lengths a layout takes, (fewest, most; `None`: no limit). A parameter value
/// counts 1 to 4 bytes; optional and omittable fields count towards the most only.
pub fn layout_len(fields: &[Field]) -> (usize, Option<usize>) {
    let (mut lo, mut hi) = (0usize, Some(0usize));
    for f in fields {
        let (a, b) = match f.ty {
            FieldType::ParamValue => (1, Some(4)),
            FieldType::DataPoints | FieldType::Records => (0, None),
            FieldType::Bytes(Len::Rest) | FieldType::Str(Len::Rest) => (0, None),
            ty => {
                let w = ty.width().unwrap_or(0);
                (w, Some(w))
            }
        };
        if !f.optional && f.omitted_when.is_none() {
            lo += a;
        }
        hi = hi.zip(b).map(|(h, b)| h + b);
    }
    (lo, hi)
}

impl Profile {
    /// The fields of a frame of `cmd` travelling in `dir`.
    pub fn fields<'c>(&self, cmd: &'c Command, dir: Direction) -> &'c [Field] {
        let from_initiator = matches!(
            (cmd.initiator, dir),
            (Initiator::Host, Direction::HostToDevice)
                | (Initiator::Device, Direction::DeviceToHost)
        );
        if from_initiator {
            &cmd.request
        } else {
            &cmd.reply
        }
    }

    /// A parameter by `data_id`.
    pub fn param(&self, id: u8) -> Option<&Param> {
        self.params.iter().find(|p| p.id == id)
    }

    /// A parameter by ident (case-insensitive) or number.
    pub fn find_param(&self, name: &str) -> Option<&Param> {
        let n = parse_id(name);
        self.params
            .iter()
            .find(|p| p.field.ident.eq_ignore_ascii_case(name) || Some(p.id) == n)
    }

    /// A data point by dpid.
    pub fn data_point(&self, id: u8) -> Option<&DataPointDef> {
        self.data_points.iter().find(|d| d.id == id)
    }

    /// A data point by ident (case-insensitive) or number.
    pub fn find_data_point(&self, name: &str) -> Option<&DataPointDef> {
        let n = parse_id(name);
        self.data_points
            .iter()
            .find(|d| d.field.ident.eq_ignore_ascii_case(name) || Some(d.id) == n)
    }

    /// The user parameters that make up the 32-byte block, in id order.
    pub fn block_params(&self) -> impl Iterator<Item = &Param> {
        self.params.iter().filter(|p| p.access == Access::ReadWrite)
    }

    /// Decodes the payload of a frame of `cmd` travelling in `dir`, strictly: a payload that
    /// does not fit the layout (too short, too long, a value that cannot be read) is
    /// [`FieldError::Misfit`], which carries the fault, the values read before it and the raw
    /// bytes. Use [`Profile::decode_lenient`] to show what could be read.
    pub fn decode<'p>(
        &'p self,
        cmd: &'p Command,
        dir: Direction,
        payload: &[u8],
    ) -> Result<Decoded<'p>, FieldError> {
        let d = self.decode_lenient(cmd, dir, payload);
        match d.misfit() {
            Some(m) => Err(FieldError::Misfit(Box::new(m))),
            None => Ok(d),
        }
    }

    /// Decodes as much of the payload as fits: the values before the first fault, the fault,
    /// and any bytes left over. Never fails; [`Decoded::fits`] tells whether it was clean.
    pub fn decode_lenient<'p>(
        &'p self,
        cmd: &'p Command,
        dir: Direction,
        payload: &[u8],
    ) -> Decoded<'p> {
        let mut d = self.decode_fields_lenient(self.fields(cmd, dir), payload);
        d.command = cmd.ident.clone();
        d
    }

    /// Decodes `payload` by a field list, strictly (see [`Profile::decode`]).
    pub fn decode_fields<'p>(
        &'p self,
        fields: &'p [Field],
        payload: &[u8],
    ) -> Result<Decoded<'p>, FieldError> {
        let d = self.decode_fields_lenient(fields, payload);
        match d.misfit() {
            Some(m) => Err(FieldError::Misfit(Box::new(m))),
            None => Ok(d),
        }
    }

    /// Decodes as much of `payload` as fits a field list (see [`Profile::decode_lenient`]).
    pub fn decode_fields_lenient<'p>(&'p self, fields: &'p [Field], payload: &[u8]) -> Decoded<'p> {
        let mut r = Reader {
            buf: payload,
            at: 0,
        };
        let mut values = Vec::new();
        let error = self.read_fields(fields, &mut r, &mut values, "").err();
        for v in &mut values {
            v.out_of_range = v.limit.is_some() || v.field.out_of_range(&v.value).is_some();
        }
        Decoded {
            command: String::new(),
            values,
            trailing: if error.is_none() {
                r.rest().to_vec()
            } else {
                Vec::new()
            },
            error,
            payload: payload.to_vec(),
            expected: layout_len(fields),
        }
    }

    /// Reads `fields` from `r` into `values`, each ident followed by `suffix` (`[i]` in a
    /// record). Stops at the first fault.
    fn read_fields<'p>(
        &'p self,
        fields: &'p [Field],
        r: &mut Reader<'_>,
        values: &mut Vec<FieldValue<'p>>,
        suffix: &str,
    ) -> Result<(), FieldError> {
        let order = self.protocol.byte_order();
        let named = |f: &Field| format!("{}{suffix}", f.ident);
        // A field the firmware leaves out holds its `omitted_when` value: the payload is then
        // exactly that field's width shorter than the layout.
        let omitted = fields
            .iter()
            .find(|f| f.omitted_when.is_some())
            .filter(|f| {
                let (_, full) = layout_len(fields);
                full.zip(f.ty.width())
                    .is_some_and(|(full, w)| r.left() + w == full)
            });
        let mut param: Option<u8> = None;
        let mut sub: Option<u8> = None;
        let mut record_len: Option<usize> = None;
        let mut count: Option<usize> = None;
        for field in fields {
            if r.left() == 0 && field.optional {
                break;
            }
            if let (Some(o), Some(v)) = (omitted, field.omitted_when)
                && std::ptr::eq(o, field)
            {
                values.push(FieldValue::plain(named(field), field, Value::Int(v)));
                continue;
            }
            match field.ty {
                FieldType::ParamId => {
                    let id = r.take(field, 1)?[0];
                    param = Some(id);
                    values.push(FieldValue::plain(
                        named(field),
                        field,
                        Value::Int(id as i64),
                    ));
                }
                FieldType::ParamValue => match param.and_then(|id| self.param(id)) {
                    Some(p) => values.push(FieldValue::plain(
                        named(&p.field),
                        &p.field,
                        read_scalar(r, &p.field, order)?,
                    )),
                    None => values.push(FieldValue::plain(
                        named(field),
                        field,
                        Value::Bytes(r.rest().to_vec()),
                    )),
                },
                FieldType::ParamBlock => {
                    let block = r.take(field, 32)?;
                    let mut br = Reader { buf: block, at: 0 };
                    for p in self.block_params() {
                        values.push(FieldValue::plain(
                            named(&p.field),
                            &p.field,
                            read_scalar(&mut br, &p.field, order)?,
                        ));
                    }
                }
                FieldType::DataPoints => {
                    for point in dp::decode(r.rest())? {
                        values.push(self.dp_value(point)?);
                    }
                }
                FieldType::Records => {
                    self.read_records(field, (sub, record_len, count), r, values)?;
                }
                _ => {
                    let value = read_scalar(r, field, order)?;
                    if let Value::Int(v) = value {
                        match field.ty {
                            FieldType::CommandId => sub = Some(v as u8),
                            FieldType::RecordLen => record_len = Some(v as usize),
                            FieldType::RecordCount => count = Some(v as usize),
                            _ => {}
                        }
                    }
                    values.push(FieldValue::plain(named(field), field, value));
                }
            }
        }
        Ok(())
    }

    /// Reads the records of a synchronous command: each as the request of command `sub`, its
    /// values named `ident[i]`; as raw bytes `records[i]` when the profile lacks `sub`.
    fn read_records<'p>(
        &'p self,
        field: &'p Field,
        (sub, len, count): (Option<u8>, Option<usize>, Option<usize>),
        r: &mut Reader<'_>,
        values: &mut Vec<FieldValue<'p>>,
    ) -> Result<(), FieldError> {
        let fault = |message: String| FieldError::Records {
            field: field.ident.clone(),
            message,
        };
        let (Some(sub), Some(len), Some(count)) = (sub, len, count) else {
            return Err(fault(
                "no sub-command, record length and count before the records".into(),
            ));
        };
        let rest = r.rest();
        let layout = self.command_by_id(sub).map(|c| (c, c.request.as_slice()));
        if let Some((c, fields)) = layout {
            let width = layout_len(fields);
            if width != (len, Some(len)) {
                return Err(fault(format!(
                    "records of {len} byte(s), but a {} ({sub}) request takes {}",
                    c.ident,
                    match width {
                        (lo, Some(hi)) if lo == hi => format!("{lo}"),
                        _ => "a variable length".into(),
                    }
                )));
            }
        }
        if len == 0 && count > 0 {
            return Err(fault(format!("{count} record(s) of 0 bytes")));
        }
        for i in 0..count {
            let Some(bytes) = rest.get(i * len..(i + 1) * len) else {
                return Err(fault(format!(
                    "{count} record(s) of {len} byte(s) take {} bytes, {} left",
                    count * len,
                    rest.len()
                )));
            };
            match layout {
                Some((_, fields)) => {
                    let mut rr = Reader { buf: bytes, at: 0 };
                    self.read_fields(fields, &mut rr, values, &format!("[{i}]"))?;
                }
                None => values.push(FieldValue {
                    ident: format!("{}[{i}]", field.ident),
                    field,
                    value: Value::Bytes(bytes.to_vec()),
                    out_of_range: false,
                    limit: None,
                    in_profile: true,
                }),
            }
        }
        if rest.len() > count * len {
            return Err(FieldError::LongPayload {
                extra: rest[count * len..].to_vec(),
            });
        }
        Ok(())
    }

    /// A data point read against the profile: one it lacks by its own type (with a stand-in
    /// field, [`unknown_dp_field`]); one of another type is an error; a value the data point
    /// does not allow is kept with its [`FieldValue::limit`].
    fn dp_value(&self, point: DataPoint) -> Result<FieldValue<'_>, FieldError> {
        let Some(def) = self.data_point(point.id) else {
            let value = super::data_point::value_of(&point.value);
            return Ok(FieldValue {
                ident: format!("dp {} (not in the profile)", point.id),
                field: unknown_dp_field(point.value.dp_type()),
                value,
                out_of_range: false,
                limit: None,
                in_profile: false,
            });
        };
        let actual = point.value.dp_type();
        if actual != def.dp_type {
            return Err(FieldError::DpType {
                field: def.field.ident.clone(),
                expected: def.dp_type.name(),
                actual: actual.name(),
            });
        }
        let value = super::data_point::value_of(&point.value);
        Ok(FieldValue {
            ident: def.field.ident.clone(),
            field: &def.field,
            limit: def.limit_of(&value),
            value,
            out_of_range: false,
            in_profile: true,
        })
    }

    pub(super) fn known_dps(&self) -> String {
        self.data_points
            .iter()
            .map(|d| d.field.ident.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// The stand-in field of a data point the profile lacks, by its wire type: its ident is the
/// type's name (`value`), so that the value reads `value 50`.
pub fn unknown_dp_field(ty: DpType) -> &'static Field {
    static FIELDS: std::sync::OnceLock<Vec<Field>> = std::sync::OnceLock::new();
    let all = FIELDS.get_or_init(|| {
        [
            (DpType::Raw, FieldType::Bytes(Len::Rest)),
            (DpType::Bool, FieldType::Bool),
            (DpType::Value, FieldType::I32),
            (DpType::String, FieldType::Str(Len::Rest)),
            (DpType::Enum, FieldType::U8),
            (DpType::Bitmap, FieldType::U32),
        ]
        .into_iter()
        .map(|(t, ty)| Field::plain(t.name(), ty))
        .collect()
    });
    &all[usize::from(ty.byte()).min(all.len() - 1)]
}

/// A checked value as the data point it is on the wire.
pub fn dp_value_of(def: &DataPointDef, value: Value) -> DpValue {
    let int = |v: &Value| match v {
        Value::Int(i) => *i,
        _ => 0,
    };
    match def.dp_type {
        DpType::Bool => DpValue::Bool(int(&value) != 0),
        DpType::Value => DpValue::Value(int(&value) as i32),
        DpType::Enum => DpValue::Enum(int(&value) as u8),
        DpType::Bitmap => DpValue::Bitmap {
            bits: int(&value) as u32,
            width: def.field.ty.width().unwrap_or(1) as u8,
        },
        DpType::String => match value {
            Value::Text(s) => DpValue::String(s),
            _ => DpValue::String(String::new()),
        },
        DpType::Raw => match value {
            Value::Bytes(b) => DpValue::Raw(b),
            _ => DpValue::Raw(Vec::new()),
        },
    }
}

/// Parses `130`, `0x82` as an id.
pub fn parse_id(text: &str) -> Option<u8> {
    let t = text.trim();
    match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(h) => u8::from_str_radix(h, 16).ok(),
        None => t.parse().ok(),
    }
}

pub(super) struct Reader<'a> {
    buf: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn left(&self) -> usize {
        self.buf.len() - self.at
    }

    fn take(&mut self, field: &Field, n: usize) -> Result<&'a [u8], FieldError> {
        if self.left() < n {
            return Err(FieldError::ShortPayload {
                field: field.ident.clone(),
                need: n,
                have: self.left(),
            });
        }
        let s = &self.buf[self.at..self.at + n];
        self.at += n;
        Ok(s)
    }

    fn rest(&mut self) -> &'a [u8] {
        let s = &self.buf[self.at..];
        self.at = self.buf.len();
        s
    }
}

fn read_scalar(r: &mut Reader<'_>, field: &Field, order: ByteOrder) -> Result<Value, FieldError> {
    let bytes = match field.ty.width() {
        Some(n) => r.take(field, n)?,
        None => r.rest(),
    };
    Ok(match field.ty {
        FieldType::Str(_) => {
            Value::Text(
                String::from_utf8(bytes.to_vec()).map_err(|_| FieldError::NotUtf8 {
                    field: field.ident.clone(),
                })?,
            )
        }
        FieldType::Bytes(_) | FieldType::ParamBlock | FieldType::DataPoints => {
            Value::Bytes(bytes.to_vec())
        }
        FieldType::ParamValue => Value::Bytes(bytes.to_vec()),
        ty => Value::Int(int_from(bytes, ty, order)),
    })
}

/// An integer of type `ty` from its bytes in `order` (at most 4), sign-extended where signed.
pub fn int_from(bytes: &[u8], ty: FieldType, order: ByteOrder) -> i64 {
    let mut b = [0u8; 4];
    let n = bytes.len().min(4);
    b[..n].copy_from_slice(&bytes[..n]);
    if order == ByteOrder::Big {
        b[..n].reverse();
    }
    let u = u32::from_le_bytes(b);
    match ty {
        FieldType::I8 => u as u8 as i8 as i64,
        FieldType::I16 => u as u16 as i16 as i64,
        FieldType::I32 => u as i32 as i64,
        _ => u as i64,
    }
}

pub(super) fn write_scalar(out: &mut Vec<u8>, field: &Field, value: &Value, order: ByteOrder) {
    match value {
        Value::Int(v) => {
            let n = field.ty.width().unwrap_or(1).min(4);
            let le = (*v as u32).to_le_bytes();
            let mut bytes = le[..n].to_vec();
            if order == ByteOrder::Big {
                bytes.reverse();
            }
            out.extend_from_slice(&bytes);
        }
        Value::Text(s) => out.extend_from_slice(s.as_bytes()),
        Value::Bytes(b) => out.extend_from_slice(b),
    }
}
