//! Data-point reports (0x07) read against the profile, one data point at a time, so that a
//! data point of another type or length than the profile's is shown with its raw bytes and the
//! mismatch instead of hiding the others (PROTOCOL_NOTES §4).

use crate::packet::Packet;
use crate::profile::{Profile, Value};
use crate::protocol::hex;
use crate::protocol::tuya::cmd;
use crate::protocol::tuya::dp::{self, DpError, DpType, DpValue, RawPoint};
use serde::Serialize;

/// Why a reported data point does not fit the profile.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, thiserror::Error)]
#[serde(tag = "misfit", rename_all = "snake_case")]
pub enum DpMisfit {
    /// The profile has no data point of this id.
    #[error("not in the profile")]
    NotInProfile,
    /// Another type byte than the profile's.
    #[error("type {} on the wire, the profile says {}", type_name(*wire), expected.name())]
    Type {
        /// The type byte reported.
        wire: u8,
        /// The profile's type.
        expected: DpType,
    },
    /// The profile's type, with a length that type does not have.
    #[error("{} of {len} byte(s) on the wire; a {} is {expected} byte(s)", ty.name(), ty.name())]
    Length {
        /// The type (the profile's and the wire's).
        ty: DpType,
        /// The length reported.
        len: usize,
        /// The lengths the type has.
        expected: &'static str,
    },
    /// A string that is not UTF-8.
    #[error("a string that is not UTF-8")]
    NotUtf8,
    /// The report's data ends inside this data point.
    #[error("cut short: {reason}")]
    Truncated {
        /// Where and how short.
        reason: String,
    },
}

/// A type byte's name, or the byte when it is none of the six.
fn type_name(ty: u8) -> String {
    DpType::from_byte(ty).map_or_else(|| format!("{ty:#04x}"), |t| t.name().to_string())
}

/// One data point as a report carried it, read against the profile.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReportedDp {
    /// The data point's id.
    pub id: u8,
    /// The profile's name for it, if the profile has it.
    pub ident: Option<String>,
    /// The type byte on the wire.
    pub wire_type: u8,
    /// The value's bytes as reported.
    #[serde(serialize_with = "ser_hex")]
    pub raw: Vec<u8>,
    /// Its value as the profile's field holds it (raw units), when it fits the profile.
    pub value: Option<Value>,
    /// Why it does not fit the profile.
    #[serde(flatten)]
    pub misfit: Option<DpMisfit>,
}

fn ser_hex<S: serde::Serializer>(bytes: &[u8], s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(&hex::format(bytes))
}

impl ReportedDp {
    /// The data point named as a person reads it: `mode (3)`, or `3` when the profile lacks it.
    pub fn name(&self) -> String {
        match &self.ident {
            Some(i) => format!("{i} ({})", self.id),
            None => self.id.to_string(),
        }
    }

    /// What was reported, as a person reads it: the value with its unit and label, or the raw
    /// bytes with the mismatch.
    pub fn shown(&self, profile: &Profile) -> String {
        match (&self.value, &self.misfit) {
            (Some(v), None) => match profile.data_point(self.id) {
                Some(def) => format!("{}{}", def.field.format(v), def.field.unit_suffix()),
                None => format!("{v:?}"),
            },
            (_, Some(m)) => format!("raw {} ({m})", hex::format(&self.raw)),
            (None, None) => format!("raw {}", hex::format(&self.raw)),
        }
    }
}

/// A data point on the wire checked against the profile's definition.
fn read_point(profile: &Profile, p: &RawPoint) -> ReportedDp {
    let def = profile.data_point(p.id);
    let mut out = ReportedDp {
        id: p.id,
        ident: def.map(|d| d.field.ident.clone()),
        wire_type: p.ty,
        raw: p.bytes.clone(),
        value: None,
        misfit: None,
    };
    let Some(def) = def else {
        out.misfit = Some(DpMisfit::NotInProfile);
        return out;
    };
    if p.ty != def.dp_type.byte() {
        out.misfit = Some(DpMisfit::Type {
            wire: p.ty,
            expected: def.dp_type,
        });
        return out;
    }
    match p.value() {
        Ok(v) => out.value = Some(field_value(&v)),
        Err(DpError::BadLength { expected, .. }) => {
            out.misfit = Some(DpMisfit::Length {
                ty: def.dp_type,
                len: p.bytes.len(),
                expected,
            })
        }
        Err(DpError::NotUtf8 { .. }) => out.misfit = Some(DpMisfit::NotUtf8),
        Err(e) => {
            out.misfit = Some(DpMisfit::Truncated {
                reason: e.to_string(),
            })
        }
    }
    out
}

/// A data point's value as the profile's fields hold it.
pub fn field_value(v: &DpValue) -> Value {
    match v {
        DpValue::Bool(b) => Value::Int(i64::from(*b)),
        DpValue::Value(x) => Value::Int(i64::from(*x)),
        DpValue::Enum(e) => Value::Int(i64::from(*e)),
        DpValue::Bitmap { bits, .. } => Value::Int(i64::from(*bits)),
        DpValue::String(s) => Value::Text(s.clone()),
        DpValue::Raw(b) => Value::Bytes(b.clone()),
    }
}

/// Every data point that report frames (0x07; other frames are skipped) carry, in the order
/// reported, each read against the profile. Bytes that end inside a data point are one more
/// entry, marked [`DpMisfit::Truncated`].
pub fn read_reports(profile: &Profile, reports: &[Packet]) -> Vec<ReportedDp> {
    let mut out = Vec::new();
    for p in reports.iter().filter(|p| p.command == cmd::DP_REPORT) {
        let walk = dp::walk(&p.payload);
        out.extend(walk.points.iter().map(|point| read_point(profile, point)));
        if let Some((error, rest)) = walk.rest {
            let id = rest.first().copied().unwrap_or(0);
            out.push(ReportedDp {
                id,
                ident: profile.data_point(id).map(|d| d.field.ident.clone()),
                wire_type: rest.get(1).copied().unwrap_or(0),
                raw: rest,
                value: None,
                misfit: Some(DpMisfit::Truncated {
                    reason: error.to_string(),
                }),
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::tuya::Frame;

    fn report(data: &[u8]) -> Packet {
        Packet::tuya_received(Frame::from_mcu(cmd::DP_REPORT, data.to_vec()))
    }

    #[test]
    fn a_data_point_of_another_type_or_length_is_kept_raw_with_the_mismatch() {
        let profile = crate::profile::Registry::builtin()
            .and_then(|r| r.get("tuya-vacuum"))
            .expect("the built-in vacuum profile");
        let got = read_reports(
            &profile,
            &[
                // DP 3 (an enum) as a 4-byte value, DP 1 (a bool) of length 4, DP 6 well.
                report(&[3, 2, 0, 4, 0, 0, 0, 1]),
                report(&[1, 1, 0, 4, 0, 0, 0, 1, 6, 2, 0, 4, 0, 0, 0, 42]),
                report(&[99, 1, 0, 1, 1]),
                report(&[13, 1, 0, 2, 1]),
            ],
        );
        assert_eq!(got.len(), 5);
        assert_eq!(
            got[0].misfit,
            Some(DpMisfit::Type {
                wire: 2,
                expected: DpType::Enum
            })
        );
        assert_eq!(got[0].raw, [0, 0, 0, 1]);
        assert_eq!(
            got[0].shown(&profile),
            "raw 00 00 00 01 (type value on the wire, the profile says enum)"
        );
        assert_eq!(
            got[1].misfit,
            Some(DpMisfit::Length {
                ty: DpType::Bool,
                len: 4,
                expected: "1"
            })
        );
        assert_eq!(got[1].name(), "power (1)");
        assert_eq!(
            (got[2].value.clone(), &got[2].misfit),
            (Some(Value::Int(42)), &None)
        );
        assert_eq!(got[3].misfit, Some(DpMisfit::NotInProfile));
        assert!(
            matches!(got[4].misfit, Some(DpMisfit::Truncated { .. })),
            "{got:?}"
        );
        let json = serde_json::to_value(&got[0]).unwrap();
        assert_eq!(json["raw"], "00 00 00 01");
        assert_eq!(json["misfit"], "type");
    }
}
