//! The one field codec, encoding side: named values to payload bytes, per the profile. Every
//! frame botbench builds (the CLI, tuning, presets, provisioning, the simulators' replies) goes
//! through [`Profile::encode`], so its checks (ranges, defaults, relations) hold for all of them.

use super::codec::write_scalar;
use super::model::{Access, Command, Field, FieldType, Param, Profile};
use super::value::{FieldError, Value};
use crate::protocol::Direction;
use crate::protocol::tuya::dp::{self, DataPoint};

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
    pub(super) fn resolve(&self, field: &Field) -> Result<Value, FieldError> {
        match self {
            Input::Text(t) => field.parse(t),
            Input::Raw(v) => {
                field.check(v)?;
                Ok(v.clone())
            }
        }
    }
}

/// Named inputs, each taken once.
struct Inputs<'a> {
    list: &'a [(String, Input)],
    used: Vec<bool>,
}

impl<'a> Inputs<'a> {
    fn new(list: &'a [(String, Input)]) -> Self {
        Self {
            list,
            used: vec![false; list.len()],
        }
    }

    /// The first unused input of that name.
    fn take(&mut self, ident: &str) -> Option<&'a Input> {
        let i = (0..self.list.len())
            .find(|&i| !self.used[i] && self.list[i].0.eq_ignore_ascii_case(ident))?;
        self.used[i] = true;
        Some(&self.list[i].1)
    }

    /// The record index of an unused input named `ident[i]`.
    fn index_of(name: &str) -> Option<usize> {
        let (_, rest) = name.rsplit_once('[')?;
        rest.strip_suffix(']')?.trim().parse().ok()
    }

    /// How many records the unused `ident[i]` inputs call for (the highest `i` + 1).
    fn record_count(&self) -> usize {
        (0..self.list.len())
            .filter(|&i| !self.used[i])
            .filter_map(|i| Self::index_of(&self.list[i].0))
            .map(|i| i + 1)
            .max()
            .unwrap_or(0)
    }

    /// Takes every unused `ident[i]` input, as `ident`.
    fn take_record(&mut self, index: usize) -> Vec<(String, Input)> {
        let mut out = Vec::new();
        for i in 0..self.list.len() {
            let (name, input) = &self.list[i];
            if !self.used[i] && Self::index_of(name) == Some(index) {
                self.used[i] = true;
                let bare = name.rsplit_once('[').map_or(name.as_str(), |(b, _)| b);
                out.push((bare.trim().to_string(), input.clone()));
            }
        }
        out
    }

    fn first_unused(&self) -> Option<&'a str> {
        let i = self.used.iter().position(|u| !u)?;
        Some(self.list[i].0.as_str())
    }

    /// Whether an input named `name` was taken (the name is then given twice).
    fn was_taken(&self, name: &str) -> bool {
        (0..self.list.len()).any(|i| self.used[i] && self.list[i].0.eq_ignore_ascii_case(name))
    }
}

impl Profile {
    /// Builds the payload of a frame of `cmd` travelling in `dir` from named inputs.
    ///
    /// Every input is checked against its field before a byte is produced. An omitted field
    /// takes its `default` where it has one; a synchronous command's record length and count
    /// are computed. A name that is not a field, a missing field without a default, or a
    /// read-only parameter or data point sent to the device is an error, and so is a request
    /// whose values break one of the profile's relations ([`FieldError::Relation`]).
    pub fn encode(
        &self,
        cmd: &Command,
        dir: Direction,
        inputs: &[(String, Input)],
    ) -> Result<Vec<u8>, FieldError> {
        let fields = self.fields(cmd, dir);
        let mut ins = Inputs::new(inputs);
        let mut missing: Option<FieldError> = None;
        let out = self.encode_fields(cmd, fields, dir, &mut ins, &mut missing)?;
        if let Some(name) = ins.first_unused() {
            if ins.was_taken(name) {
                return Err(FieldError::Duplicate {
                    command: cmd.ident.clone(),
                    field: crate::document::quote(name),
                });
            }
            return Err(FieldError::UnknownField {
                command: cmd.ident.clone(),
                field: crate::document::quote(name),
                known: fields
                    .iter()
                    .map(|f| f.ident.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        }
        if let Some(e) = missing {
            return Err(e);
        }
        if dir == Direction::HostToDevice {
            self.check_relations(cmd, dir, &out)?;
        }
        Ok(out)
    }

    fn encode_fields(
        &self,
        cmd: &Command,
        fields: &[Field],
        dir: Direction,
        ins: &mut Inputs<'_>,
        missing: &mut Option<FieldError>,
    ) -> Result<Vec<u8>, FieldError> {
        let to_device = dir == Direction::HostToDevice;
        let order = self.protocol.byte_order();
        let mut note_missing = |f: &str| {
            missing.get_or_insert_with(|| FieldError::MissingField {
                command: cmd.ident.clone(),
                field: f.to_string(),
            });
        };
        let mut out = Vec::new();
        let mut param: Option<&Param> = None;
        let mut sub: Option<u8> = None;
        let mut len_at: Option<(usize, Option<Value>, &Field)> = None;
        let mut count_at: Option<(usize, Option<Value>)> = None;
        let mut has_dps = false;
        for field in fields {
            match field.ty {
                FieldType::ParamId => {
                    let Some(input) = ins.take(&field.ident) else {
                        note_missing(&field.ident);
                        continue;
                    };
                    let p = self.param_named(input)?;
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
                    let Some(input) = ins.take(&field.ident).or_else(|| ins.take(&p.field.ident))
                    else {
                        note_missing(&field.ident);
                        continue;
                    };
                    write_scalar(&mut out, &p.field, &input.resolve(&p.field)?, order);
                }
                FieldType::ParamBlock => {
                    for p in self.block_params() {
                        let Some(input) = ins.take(&p.field.ident) else {
                            note_missing(&p.field.ident);
                            continue;
                        };
                        write_scalar(&mut out, &p.field, &input.resolve(&p.field)?, order);
                    }
                }
                FieldType::DataPoints => {
                    has_dps = true;
                }
                FieldType::RecordLen => {
                    let given = ins
                        .take(&field.ident)
                        .map(|i| i.resolve(field))
                        .transpose()?;
                    len_at = Some((out.len(), given, field));
                    out.push(0);
                }
                FieldType::RecordCount => {
                    let given = ins
                        .take(&field.ident)
                        .map(|i| i.resolve(field))
                        .transpose()?;
                    count_at = Some((out.len(), given));
                    out.push(0);
                }
                FieldType::Records => {
                    let records = self.encode_records(field, sub, count_at.as_ref(), ins)?;
                    put_records(&mut out, field, records, len_at.as_ref(), count_at.as_ref())?;
                }
                _ => {
                    let value = match ins.take(&field.ident) {
                        Some(input) => input.resolve(field)?,
                        None if field.optional => break,
                        None => match field.default {
                            Some(d) => Value::Int(d),
                            None => {
                                note_missing(&field.ident);
                                continue;
                            }
                        },
                    };
                    if let (FieldType::CommandId, Value::Int(v)) = (field.ty, &value) {
                        sub = u8::try_from(*v).ok();
                    }
                    if matches!(value, Value::Int(v) if Some(v) == field.omitted_when) {
                        continue;
                    }
                    write_scalar(&mut out, field, &value, order);
                }
            }
        }
        if has_dps {
            out.extend(self.encode_dps(to_device, ins)?);
        }
        Ok(out)
    }

    /// The parameter an input names: by name, or by its number.
    fn param_named(&self, input: &Input) -> Result<&Param, FieldError> {
        match input {
            Input::Text(t) => self.find_param(t),
            Input::Raw(Value::Int(i)) => u8::try_from(*i).ok().and_then(|i| self.param(i)),
            Input::Raw(_) => None,
        }
        .ok_or_else(|| FieldError::Unknown {
            what: "parameter",
            id: match input {
                Input::Text(t) => t.clone(),
                Input::Raw(v) => format!("{v:?}"),
            },
        })
    }

    /// The records of a synchronous command: each the request of command `sub`, from the
    /// inputs named `ident[i]`.
    fn encode_records(
        &self,
        field: &Field,
        sub: Option<u8>,
        count_at: Option<&(usize, Option<Value>)>,
        ins: &mut Inputs<'_>,
    ) -> Result<Records, FieldError> {
        let fault = |message: String| FieldError::Records {
            field: field.ident.clone(),
            message,
        };
        let sub = sub.ok_or_else(|| fault("no sub-command before the records".into()))?;
        let sub_cmd = self.command_by_id(sub).ok_or(FieldError::Unknown {
            what: "command",
            id: sub.to_string(),
        })?;
        let count = match count_at.and_then(|(_, g)| g.as_ref()) {
            Some(Value::Int(n)) => usize::try_from(*n).unwrap_or(0),
            _ => ins.record_count(),
        };
        let (lo, hi) = super::codec::layout_len(&sub_cmd.request);
        let mut bytes = Vec::new();
        for i in 0..count {
            let inputs = ins.take_record(i);
            let record = self
                .encode(sub_cmd, Direction::HostToDevice, &inputs)
                .map_err(|e| match e {
                    // A record that breaks a relation (a multi-turn interval shorter than its
                    // acceleration and deceleration) is refused as such, its values said.
                    FieldError::Relation(_) => e,
                    e => fault(format!("record {i} ({}): {e}", sub_cmd.ident)),
                })?;
            if hi != Some(lo) || record.len() != lo {
                return Err(fault(format!(
                    "{} has no fixed-size request to make records of",
                    sub_cmd.ident
                )));
            }
            bytes.extend(record);
        }
        Ok(Records {
            len: lo,
            count,
            bytes,
        })
    }

    fn encode_dps(&self, to_device: bool, ins: &mut Inputs<'_>) -> Result<Vec<u8>, FieldError> {
        let mut points: Vec<DataPoint> = Vec::new();
        for i in 0..ins.list.len() {
            if ins.used[i] {
                continue;
            }
            let (name, input) = &ins.list[i];
            let def = self
                .find_data_point(name)
                .ok_or_else(|| FieldError::UnknownDataPoint {
                    name: crate::document::quote(name),
                    known: self.known_dps(),
                })?;
            // By name or number, one data point once: which value was meant is not known.
            if points.iter().any(|p| p.id == def.id) {
                return Err(FieldError::Duplicate {
                    command: "data points".into(),
                    field: def.field.ident.clone(),
                });
            }
            if to_device && def.access == Access::ReadOnly {
                return Err(FieldError::ReadOnly {
                    field: def.field.ident.clone(),
                });
            }
            let value = input.resolve(&def.field)?;
            if let Some(limit) = def.limit_of(&value) {
                return Err(FieldError::DataPointLimit {
                    field: def.field.ident.clone(),
                    limit: Box::new(limit),
                });
            }
            points.push(DataPoint {
                id: def.id,
                value: super::codec::dp_value_of(def, value),
            });
            ins.used[i] = true;
        }
        Ok(dp::encode(&points)?)
    }
}

/// Encoded records: each `len` bytes, `count` of them.
struct Records {
    len: usize,
    count: usize,
    bytes: Vec<u8>,
}

/// Appends the records of a synchronous command (`field`) to `out`, and fills in the record
/// length at `len_at` (checked against the one given, if any) and the record count at
/// `count_at`: each one byte.
fn put_records(
    out: &mut Vec<u8>,
    field: &Field,
    records: Records,
    len_at: Option<&(usize, Option<Value>, &Field)>,
    count_at: Option<&(usize, Option<Value>)>,
) -> Result<(), FieldError> {
    if let Some((at, given, len_field)) = len_at {
        let want = Value::Int(records.len as i64);
        if given.as_ref().is_some_and(|g| *g != want) {
            return Err(FieldError::Records {
                field: len_field.ident.clone(),
                message: format!(
                    "{given:?} given, but each record takes {} byte(s)",
                    records.len
                ),
            });
        }
        out[*at] = u8::try_from(records.len).map_err(|_| FieldError::Records {
            field: len_field.ident.clone(),
            message: format!("records of {} bytes", records.len),
        })?;
    }
    if let Some((at, _)) = count_at {
        out[*at] = u8::try_from(records.count).map_err(|_| FieldError::Records {
            field: field.ident.clone(),
            message: format!("{} records; at most 255", records.count),
        })?;
    }
    out.extend(records.bytes);
    Ok(())
}
