//! The one field codec: payload bytes to named, typed values and back, per the profile.

use super::model::{
    Access, ByteOrder, Command, DataPointDef, Field, FieldType, Initiator, Param, Profile,
};
use super::value::{FieldError, Value};
use crate::protocol::Direction;
use crate::protocol::tuya::dp::{self, DataPoint, DpType, DpValue};
use serde::Serialize;

/// One decoded value and the field it belongs to.
#[derive(Debug, Clone, Serialize)]
pub struct FieldValue<'p> {
    /// The field's canonical ident (a parameter's or data point's for nested values).
    pub ident: String,
    /// The field's definition.
    #[serde(skip)]
    pub field: &'p Field,
    /// The raw value.
    pub value: Value,
}

impl FieldValue<'_> {
    /// The value as shown: scaled, labelled, with its unit.
    pub fn display(&self) -> String {
        let text = self.field.format(&self.value);
        match self.value {
            Value::Int(raw) if self.field.label(raw).is_none() => {
                format!("{text}{}", self.field.unit_suffix())
            }
            _ => text,
        }
    }
}

/// A decoded payload.
#[derive(Debug, Clone, Serialize)]
pub struct Decoded<'p> {
    /// The values, in wire order.
    pub values: Vec<FieldValue<'p>>,
    /// Bytes past the last field (firmware that sends more than the profile knows).
    pub trailing: Vec<u8>,
}

impl Decoded<'_> {
    /// The raw integer of a field, by ident.
    pub fn int(&self, ident: &str) -> Option<i64> {
        self.values.iter().find_map(|v| match v.value {
            Value::Int(i) if v.ident.eq_ignore_ascii_case(ident) => Some(i),
            _ => None,
        })
    }
}

/// A value to encode: typed by a person, or raw from a program.
#[derive(Debug, Clone, PartialEq)]
pub enum Input {
    /// Display units, labels, hex, as [`Field::parse`] reads them.
    Text(String),
    /// A raw value, checked against the field.
    Raw(Value),
}

impl From<&str> for Input {
    fn from(s: &str) -> Self {
        Input::Text(s.to_string())
    }
}

impl From<i64> for Input {
    fn from(v: i64) -> Self {
        Input::Raw(Value::Int(v))
    }
}

impl Input {
    fn resolve(&self, field: &Field) -> Result<Value, FieldError> {
        match self {
            Input::Text(t) => field.parse(t),
            Input::Raw(v) => {
                field.check(v)?;
                Ok(v.clone())
            }
        }
    }
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

    /// Decodes the payload of a frame of `cmd` travelling in `dir`.
    pub fn decode<'p>(
        &'p self,
        cmd: &'p Command,
        dir: Direction,
        payload: &[u8],
    ) -> Result<Decoded<'p>, FieldError> {
        self.decode_fields(self.fields(cmd, dir), payload)
    }

    /// Decodes `payload` by a field list.
    pub fn decode_fields<'p>(
        &'p self,
        fields: &'p [Field],
        payload: &[u8],
    ) -> Result<Decoded<'p>, FieldError> {
        let order = self.protocol.byte_order();
        let mut r = Reader {
            buf: payload,
            at: 0,
        };
        let mut values = Vec::new();
        let mut param: Option<u8> = None;
        for field in fields {
            if r.left() == 0 && field.optional {
                break;
            }
            match field.ty {
                FieldType::ParamId => {
                    let id = r.take(field, 1)?[0];
                    param = Some(id);
                    values.push(FieldValue {
                        ident: field.ident.clone(),
                        field,
                        value: Value::Int(id as i64),
                    });
                }
                FieldType::ParamValue => match param.and_then(|id| self.param(id)) {
                    Some(p) => values.push(FieldValue {
                        ident: p.field.ident.clone(),
                        field: &p.field,
                        value: read_scalar(&mut r, &p.field, order)?,
                    }),
                    None => values.push(FieldValue {
                        ident: field.ident.clone(),
                        field,
                        value: Value::Bytes(r.rest().to_vec()),
                    }),
                },
                FieldType::ParamBlock => {
                    let block = r.take(field, 32)?;
                    let mut br = Reader { buf: block, at: 0 };
                    for p in self.block_params() {
                        values.push(FieldValue {
                            ident: p.field.ident.clone(),
                            field: &p.field,
                            value: read_scalar(&mut br, &p.field, order)?,
                        });
                    }
                }
                FieldType::DataPoints => {
                    for point in dp::decode(r.rest())? {
                        values.push(self.dp_value(point)?);
                    }
                }
                _ => values.push(FieldValue {
                    ident: field.ident.clone(),
                    field,
                    value: read_scalar(&mut r, field, order)?,
                }),
            }
        }
        Ok(Decoded {
            values,
            trailing: r.rest().to_vec(),
        })
    }

    fn dp_value(&self, point: DataPoint) -> Result<FieldValue<'_>, FieldError> {
        let def = self.data_point(point.id).ok_or(FieldError::Unknown {
            what: "data point",
            id: point.id.to_string(),
        })?;
        let actual = point.value.dp_type();
        if actual != def.dp_type {
            return Err(FieldError::DpType {
                field: def.field.ident.clone(),
                expected: def.dp_type.name(),
                actual: actual.name(),
            });
        }
        let value = match point.value {
            DpValue::Bool(b) => Value::Int(b as i64),
            DpValue::Value(v) => Value::Int(v as i64),
            DpValue::Enum(e) => Value::Int(e as i64),
            DpValue::Bitmap { bits, .. } => Value::Int(bits as i64),
            DpValue::String(s) => Value::Text(s),
            DpValue::Raw(b) => Value::Bytes(b),
        };
        Ok(FieldValue {
            ident: def.field.ident.clone(),
            field: &def.field,
            value,
        })
    }

    /// Builds the payload of a frame of `cmd` travelling in `dir` from named inputs.
    ///
    /// Every input is checked against its field before a byte is produced; a name that is not a
    /// field, a missing field, or a read-only parameter or data point sent to the device is an
    /// error.
    pub fn encode(
        &self,
        cmd: &Command,
        dir: Direction,
        inputs: &[(String, Input)],
    ) -> Result<Vec<u8>, FieldError> {
        let fields = self.fields(cmd, dir);
        let to_device = dir == Direction::HostToDevice;
        let order = self.protocol.byte_order();
        let mut used = vec![false; inputs.len()];
        let mut find = |ident: &str| -> Option<&Input> {
            // The first unused input of that name: a block parameter may share a name with a
            // frame field (WRITE_BATCH_DATA's `servo_id`), and order then tells them apart.
            let i =
                (0..inputs.len()).find(|&i| !used[i] && inputs[i].0.eq_ignore_ascii_case(ident))?;
            used[i] = true;
            Some(&inputs[i].1)
        };
        let mut missing: Option<FieldError> = None;
        let mut note_missing = |f: &str| {
            missing.get_or_insert_with(|| FieldError::MissingField {
                command: cmd.ident.clone(),
                field: f.to_string(),
            });
        };
        let mut out = Vec::new();
        let mut param: Option<&Param> = None;
        let mut has_dps = false;
        for field in fields {
            match field.ty {
                FieldType::ParamId => {
                    let Some(input) = find(&field.ident) else {
                        note_missing(&field.ident);
                        continue;
                    };
                    let p = match input {
                        Input::Text(t) => self.find_param(t),
                        Input::Raw(Value::Int(i)) => {
                            u8::try_from(*i).ok().and_then(|i| self.param(i))
                        }
                        Input::Raw(_) => None,
                    }
                    .ok_or_else(|| FieldError::Unknown {
                        what: "parameter",
                        id: match input {
                            Input::Text(t) => t.clone(),
                            Input::Raw(v) => format!("{v:?}"),
                        },
                    })?;
                    param = Some(p);
                    out.push(p.id);
                }
                FieldType::ParamValue => {
                    let Some(p) = param else {
                        continue;
                    };
                    if to_device && p.access == Access::ReadOnly {
                        return Err(FieldError::ReadOnly {
                            field: p.field.ident.clone(),
                        });
                    }
                    let Some(input) = find(&field.ident).or_else(|| find(&p.field.ident)) else {
                        note_missing(&field.ident);
                        continue;
                    };
                    write_scalar(&mut out, &p.field, &input.resolve(&p.field)?, order);
                }
                FieldType::ParamBlock => {
                    for p in self.block_params() {
                        let Some(input) = find(&p.field.ident) else {
                            note_missing(&p.field.ident);
                            continue;
                        };
                        write_scalar(&mut out, &p.field, &input.resolve(&p.field)?, order);
                    }
                }
                FieldType::DataPoints => {
                    has_dps = true;
                }
                _ => match find(&field.ident) {
                    Some(input) => write_scalar(&mut out, field, &input.resolve(field)?, order),
                    None if field.optional => break,
                    None => note_missing(&field.ident),
                },
            }
        }
        if has_dps {
            let mut points = Vec::new();
            for (i, (name, input)) in inputs.iter().enumerate() {
                if used[i] {
                    continue;
                }
                let def = self
                    .find_data_point(name)
                    .ok_or_else(|| FieldError::UnknownField {
                        command: cmd.ident.clone(),
                        field: name.clone(),
                        known: self.known_dps(),
                    })?;
                if to_device && def.access == Access::ReadOnly {
                    return Err(FieldError::ReadOnly {
                        field: def.field.ident.clone(),
                    });
                }
                points.push(DataPoint {
                    id: def.id,
                    value: dp_value_of(def, input.resolve(&def.field)?),
                });
                used[i] = true;
            }
            out.extend(dp::encode(&points)?);
        }
        if let Some(i) = used.iter().position(|u| !u) {
            return Err(FieldError::UnknownField {
                command: cmd.ident.clone(),
                field: inputs[i].0.clone(),
                known: fields
                    .iter()
                    .map(|f| f.ident.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        }
        match missing {
            Some(e) => Err(e),
            None => Ok(out),
        }
    }

    fn known_dps(&self) -> String {
        self.data_points
            .iter()
            .map(|d| d.field.ident.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    }
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

struct Reader<'a> {
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

fn int_from(bytes: &[u8], ty: FieldType, order: ByteOrder) -> i64 {
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

fn write_scalar(out: &mut Vec<u8>, field: &Field, value: &Value, order: ByteOrder) {
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
