//! Tuya data points: `dpid u8, type u8, len u16 BE, value[len]`, several to a frame.

use serde::Serialize;

/// A data point's type byte.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, serde::Deserialize)]
pub enum DpType {
    /// 0: raw bytes.
    Raw,
    /// 1: bool, one byte.
    Bool,
    /// 2: value, 4 bytes big-endian signed.
    Value,
    /// 3: string.
    String,
    /// 4: enum, one byte.
    Enum,
    /// 5: bitmap of 1, 2 or 4 bytes.
    Bitmap,
}

impl DpType {
    /// The type byte.
    pub fn byte(self) -> u8 {
        match self {
            DpType::Raw => 0,
            DpType::Bool => 1,
            DpType::Value => 2,
            DpType::String => 3,
            DpType::Enum => 4,
            DpType::Bitmap => 5,
        }
    }

    /// The type for a byte, if it is one.
    pub fn from_byte(byte: u8) -> Option<Self> {
        Some(match byte {
            0 => DpType::Raw,
            1 => DpType::Bool,
            2 => DpType::Value,
            3 => DpType::String,
            4 => DpType::Enum,
            5 => DpType::Bitmap,
            _ => return None,
        })
    }

    /// A lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            DpType::Raw => "raw",
            DpType::Bool => "bool",
            DpType::Value => "value",
            DpType::String => "string",
            DpType::Enum => "enum",
            DpType::Bitmap => "bitmap",
        }
    }
}

/// A data point's value.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(tag = "type", content = "value", rename_all = "snake_case")]
pub enum DpValue {
    /// Raw bytes.
    Raw(Vec<u8>),
    /// A bool.
    Bool(bool),
    /// A signed 32-bit value.
    Value(i32),
    /// A UTF-8 string.
    String(String),
    /// An enum index.
    Enum(u8),
    /// A bitmap and its width in bytes (1, 2 or 4).
    Bitmap {
        /// The bits.
        bits: u32,
        /// Its width on the wire, in bytes.
        width: u8,
    },
}

impl DpValue {
    /// The value's type.
    pub fn dp_type(&self) -> DpType {
        match self {
            DpValue::Raw(_) => DpType::Raw,
            DpValue::Bool(_) => DpType::Bool,
            DpValue::Value(_) => DpType::Value,
            DpValue::String(_) => DpType::String,
            DpValue::Enum(_) => DpType::Enum,
            DpValue::Bitmap { .. } => DpType::Bitmap,
        }
    }
}

/// One data point.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct DataPoint {
    /// The data-point id.
    pub id: u8,
    /// Its value.
    pub value: DpValue,
}

/// Why a data-point list could not be read or built.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DpError {
    /// The bytes end inside a data point.
    #[error("data point at byte {offset} is truncated: {need} bytes needed, {have} present")]
    Truncated {
        /// Where the data point starts in the data.
        offset: usize,
        /// Bytes it needs.
        need: usize,
        /// Bytes present.
        have: usize,
    },
    /// A type byte that is none of the six.
    #[error("data point {id} has unknown type {ty}")]
    UnknownType {
        /// The data-point id.
        id: u8,
        /// The type byte.
        ty: u8,
    },
    /// A length that does not fit the type.
    #[error("data point {id} of type {ty} has length {len}, expected {expected}")]
    BadLength {
        /// The data-point id.
        id: u8,
        /// The type's name.
        ty: &'static str,
        /// The length on the wire.
        len: usize,
        /// The lengths the type allows.
        expected: &'static str,
    },
    /// A string that is not UTF-8.
    #[error("data point {id} holds a string that is not UTF-8")]
    NotUtf8 {
        /// The data-point id.
        id: u8,
    },
    /// A value too long for the length field.
    #[error("data point {id} is {len} bytes long, over the maximum of 65535")]
    TooLong {
        /// The data-point id.
        id: u8,
        /// Its length.
        len: usize,
    },
}

fn bitmap_bytes(bits: u32, width: u8) -> Option<Vec<u8>> {
    match width {
        1 => u8::try_from(bits).ok().map(|b| vec![b]),
        2 => u16::try_from(bits).ok().map(|b| b.to_be_bytes().to_vec()),
        4 => Some(bits.to_be_bytes().to_vec()),
        _ => None,
    }
}

/// Appends one data point to `out`.
pub fn encode_one(dp: &DataPoint, out: &mut Vec<u8>) -> Result<(), DpError> {
    let value: Vec<u8> = match &dp.value {
        DpValue::Raw(bytes) => bytes.clone(),
        DpValue::Bool(b) => vec![u8::from(*b)],
        DpValue::Value(v) => v.to_be_bytes().to_vec(),
        DpValue::String(s) => s.as_bytes().to_vec(),
        DpValue::Enum(e) => vec![*e],
        DpValue::Bitmap { bits, width } => {
            bitmap_bytes(*bits, *width).ok_or(DpError::BadLength {
                id: dp.id,
                ty: "bitmap",
                len: *width as usize,
                expected: "1, 2 or 4 and wide enough for the bits",
            })?
        }
    };
    let len = u16::try_from(value.len()).map_err(|_| DpError::TooLong {
        id: dp.id,
        len: value.len(),
    })?;
    out.push(dp.id);
    out.push(dp.value.dp_type().byte());
    out.extend_from_slice(&len.to_be_bytes());
    out.extend_from_slice(&value);
    Ok(())
}

/// The bytes of a list of data points (the data of a 0x06 or 0x07 frame).
pub fn encode(dps: &[DataPoint]) -> Result<Vec<u8>, DpError> {
    let mut out = Vec::new();
    for dp in dps {
        encode_one(dp, &mut out)?;
    }
    Ok(out)
}

/// One data point as it is on the wire, before its value is read: id, type byte, value bytes.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct RawPoint {
    /// The data-point id.
    pub id: u8,
    /// The type byte (0-5 are the six types; anything else is kept as it came).
    pub ty: u8,
    /// The value's bytes, as many as the length field said.
    pub bytes: Vec<u8>,
    /// Where the data point starts in the data.
    pub offset: usize,
}

impl RawPoint {
    /// Its value read by its own type byte and length: an unknown type, a length the type does
    /// not allow and a string that is not UTF-8 are errors.
    pub fn value(&self) -> Result<DpValue, DpError> {
        let (id, v) = (self.id, self.bytes.as_slice());
        let ty = DpType::from_byte(self.ty).ok_or(DpError::UnknownType { id, ty: self.ty })?;
        let bad = |expected| DpError::BadLength {
            id,
            ty: ty.name(),
            len: v.len(),
            expected,
        };
        Ok(match ty {
            DpType::Raw => DpValue::Raw(v.to_vec()),
            DpType::Bool => match v {
                [b] => DpValue::Bool(*b != 0),
                _ => return Err(bad("1")),
            },
            DpType::Value => match v {
                [a, b, c, d] => DpValue::Value(i32::from_be_bytes([*a, *b, *c, *d])),
                _ => return Err(bad("4")),
            },
            DpType::String => {
                DpValue::String(String::from_utf8(v.to_vec()).map_err(|_| DpError::NotUtf8 { id })?)
            }
            DpType::Enum => match v {
                [e] => DpValue::Enum(*e),
                _ => return Err(bad("1")),
            },
            DpType::Bitmap => {
                let bits = match v {
                    [a] => *a as u32,
                    [a, b] => u16::from_be_bytes([*a, *b]) as u32,
                    [a, b, c, d] => u32::from_be_bytes([*a, *b, *c, *d]),
                    _ => return Err(bad("1, 2 or 4")),
                };
                DpValue::Bitmap {
                    bits,
                    width: v.len() as u8,
                }
            }
        })
    }
}

/// A data-point list read leniently: every whole data point, whatever its type byte and length,
/// and why the bytes after the last one are not a data point (cut short).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Walk {
    /// The data points, in order.
    pub points: Vec<RawPoint>,
    /// The list ends inside a data point: [`DpError::Truncated`], and the bytes left.
    pub rest: Option<(DpError, Vec<u8>)>,
}

/// Splits a data-point list (the data of a 0x06 or 0x07 frame) into its data points without
/// reading their values, so that one data point of an unexpected type or length does not hide
/// the others.
pub fn walk(data: &[u8]) -> Walk {
    let mut out = Walk::default();
    let mut at = 0;
    while at < data.len() {
        let rest = &data[at..];
        let need = match rest {
            [_, _, hi, lo, ..] => 4 + u16::from_be_bytes([*hi, *lo]) as usize,
            _ => 4,
        };
        if rest.len() < need {
            let error = DpError::Truncated {
                offset: at,
                need,
                have: rest.len(),
            };
            out.rest = Some((error, rest.to_vec()));
            break;
        }
        out.points.push(RawPoint {
            id: rest[0],
            ty: rest[1],
            bytes: rest[4..need].to_vec(),
            offset: at,
        });
        at += need;
    }
    out
}

/// Reads a list of data points; the first data point that does not read is the error.
pub fn decode(data: &[u8]) -> Result<Vec<DataPoint>, DpError> {
    let walk = walk(data);
    let mut out = Vec::with_capacity(walk.points.len());
    for p in &walk.points {
        out.push(DataPoint {
            id: p.id,
            value: p.value()?,
        });
    }
    match walk.rest {
        Some((e, _)) => Err(e),
        None => Ok(out),
    }
}
