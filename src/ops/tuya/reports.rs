//! Data-point reports (0x07) read against the profile, one data point at a time, so that a
//! data point of another type or length than the profile's is shown with its raw bytes and the
//! mismatch instead of hiding the others (PROTOCOL_NOTES §4).

use crate::packet::Packet;
use crate::profile::{DpLimit, Profile, Value};
use crate::protocol::hex;
use crate::protocol::tuya::cmd;
use crate::protocol::tuya::dp::{self, DpError, DpType, DpValue, RawPoint};
use serde::Serialize;

/// Why a reported data point does not fit the profile (or, for a data point the profile lacks,
/// why its bytes are no value of the type they name).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, thiserror::Error)]
#[serde(tag = "misfit", rename_all = "snake_case")]
pub enum DpMisfit {
    /// Another type byte than the profile's.
    #[error("type {} on the wire, the profile says {}", type_name(*wire), expected.name())]
    Type {
        /// The type byte reported.
        wire: u8,
        /// The profile's type.
        expected: DpType,
    },
    /// A type byte that is none of the six (a data point the profile lacks).
    #[error("type byte {wire:#04x} is none of the six data-point types")]
    UnknownType {
        /// The type byte reported.
        wire: u8,
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
    /// A bool whose byte is neither 0 nor 1.
    #[error("bool byte {byte:#04x}: a bool is 0x00 or 0x01")]
    NotBool {
        /// The byte reported.
        byte: u8,
    },
    /// A string that is not UTF-8.
    #[error("a string that is not UTF-8")]
    NotUtf8,
    /// A value of the right type and length that the data point does not allow: out of range,
    /// between steps, an enum index without a label, undefined bitmap bits, too long
    /// ([`DpLimit`]). The value is kept ([`ReportedDp::value`]) but never taken as good.
    #[error("{0}")]
    Limit(DpLimit),
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
    /// The profile's name for it; `None` when the profile does not have it (it is then read by
    /// its own type byte and length, TUYA_FIELD_NOTES §7).
    pub ident: Option<String>,
    /// The type byte on the wire.
    pub wire_type: u8,
    /// The value's bytes as reported.
    #[serde(serialize_with = "ser_hex")]
    pub raw: Vec<u8>,
    /// Its value as the profile's field holds it (raw units): when it fits the profile, when it
    /// is of the right type but outside the data point's limits ([`DpMisfit::Limit`]), and for
    /// a data point the profile lacks, read by its own type.
    pub value: Option<Value>,
    /// Why it does not fit the profile.
    #[serde(flatten)]
    pub misfit: Option<DpMisfit>,
}

fn ser_hex<S: serde::Serializer>(bytes: &[u8], s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(&hex::format(bytes))
}

impl ReportedDp {
    /// The data point named as a person reads it: `mode (3)`, or `dp 101 (not in the profile)`.
    pub fn name(&self) -> String {
        match &self.ident {
            Some(i) => format!("{i} ({})", self.id),
            None => format!("dp {} (not in the profile)", self.id),
        }
    }

    /// Whether the profile has this data point.
    pub fn in_profile(&self) -> bool {
        self.ident.is_some()
    }

    /// Whether it is a value the product can hold: in the profile, of its type and length,
    /// within its limits.
    pub fn fits(&self) -> bool {
        self.in_profile() && self.misfit.is_none()
    }

    /// What was reported, as a person reads it: the value with its unit and label; a misfit
    /// as its raw bytes, why, and what the profile allows (`raw 00 00 00 96 (150 % is out of
    /// range: the profile allows 0 to 100 %)`); a data point the profile lacks by its own type,
    /// `value 50`.
    pub fn shown(&self, profile: &Profile) -> String {
        let def = profile.data_point(self.id);
        match (&self.value, &self.misfit, def) {
            (Some(v), None, Some(def)) => {
                format!("{}{}", def.field.format(v), def.field.unit_suffix())
            }
            (Some(v), None, None) => {
                let ty = DpType::from_byte(self.wire_type).map_or("?", DpType::name);
                format!("{ty} {}", plain(v))
            }
            (_, Some(m @ DpMisfit::Limit(_)), _) => {
                format!("raw {} ({m})", hex::format(&self.raw))
            }
            (_, Some(m), Some(def)) => format!(
                "raw {} ({m}; allowed: {} {})",
                hex::format(&self.raw),
                def.dp_type.name(),
                def.allowed_text()
            ),
            (_, Some(m), None) => format!("raw {} ({m})", hex::format(&self.raw)),
            (None, None, _) => format!("raw {}", hex::format(&self.raw)),
        }
    }
}

/// A value read by its own type, as a person reads it: a number, `true`, `"text"`, hex bytes.
fn plain(v: &Value) -> String {
    match v {
        Value::Int(i) => i.to_string(),
        Value::Text(s) => format!("{s:?}"),
        Value::Bytes(b) => hex::format(b),
    }
}

/// A data point's bytes read by their own type byte: a misfit names why they are no value.
fn by_own_type(p: &RawPoint, ty: DpType) -> Result<Value, DpMisfit> {
    if ty == DpType::Bool
        && let [b] = p.bytes.as_slice()
        && *b > 1
    {
        return Err(DpMisfit::NotBool { byte: *b });
    }
    match p.value() {
        Ok(v) => Ok(field_value(&v)),
        Err(DpError::BadLength { expected, .. }) => Err(DpMisfit::Length {
            ty,
            len: p.bytes.len(),
            expected,
        }),
        Err(DpError::NotUtf8 { .. }) => Err(DpMisfit::NotUtf8),
        Err(e) => Err(DpMisfit::Truncated {
            reason: e.to_string(),
        }),
    }
}

/// A data point on the wire checked against the profile's definition: its type byte, its
/// length for that type, then the data point's limits (range, step, labels, bits, length). One
/// the profile lacks is read by its own type byte and length.
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
        match DpType::from_byte(p.ty) {
            None => out.misfit = Some(DpMisfit::UnknownType { wire: p.ty }),
            Some(ty) => match by_own_type(p, ty) {
                Ok(v) => out.value = Some(v),
                Err(m) => out.misfit = Some(m),
            },
        }
        return out;
    };
    if p.ty != def.dp_type.byte() {
        out.misfit = Some(DpMisfit::Type {
            wire: p.ty,
            expected: def.dp_type,
        });
        return out;
    }
    match by_own_type(p, def.dp_type) {
        Ok(v) => {
            out.misfit = def.limit_of(&v).map(DpMisfit::Limit);
            out.value = Some(v);
        }
        Err(m) => out.misfit = Some(m),
    }
    out
}

/// Whether `p` carries data-point reports: 0x07, or 0x22 (the synchronous report the module
/// answers with 0x23, TUYA_FIELD_NOTES §2).
pub fn is_report(p: &Packet) -> bool {
    p.command == cmd::DP_REPORT || p.command == cmd::DP_REPORT_SYNC
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

/// Every data point that report frames (0x07, and 0x22 synchronous reports; other frames are
/// skipped) carry, in the order
/// reported, each read against the profile. Bytes that end inside a data point are one more
/// entry, marked [`DpMisfit::Truncated`].
pub fn read_reports(profile: &Profile, reports: &[Packet]) -> Vec<ReportedDp> {
    let mut out = Vec::new();
    for p in reports.iter().filter(|p| is_report(p)) {
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
            "raw 00 00 00 01 (type value on the wire, the profile says enum; \
             allowed: enum labels 0 to 11)"
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
        // DP 99 is not in the profile: read by its own type, a bool.
        assert_eq!(
            (got[3].value.clone(), &got[3].misfit),
            (Some(Value::Int(1)), &None)
        );
        assert!(!got[3].fits());
        assert_eq!(got[3].shown(&profile), "bool 1");
        assert!(
            matches!(got[4].misfit, Some(DpMisfit::Truncated { .. })),
            "{got:?}"
        );
        let json = serde_json::to_value(&got[0]).unwrap();
        assert_eq!(json["raw"], "00 00 00 01");
        assert_eq!(json["misfit"], "type");
    }

    #[test]
    fn impossible_values_are_misfits_with_what_the_profile_allows() {
        let profile = crate::profile::Registry::builtin()
            .and_then(|r| r.get("tuya-vacuum"))
            .expect("the built-in vacuum profile");
        let long = [vec![15, 3, 1, 44], vec![b'1'; 300]].concat();
        let got = read_reports(
            &profile,
            &[
                // Battery 150 %, mode 32, fault bit 7, area -5.0 m², a 300-byte record, a bool 2.
                report(&[6, 2, 0, 4, 0, 0, 0, 150]),
                report(&[3, 4, 0, 1, 32]),
                report(&[18, 5, 0, 1, 0x84]),
                report(&[16, 2, 0, 4, 0xff, 0xff, 0xff, 0xce]),
                report(&long),
                report(&[1, 1, 0, 1, 2]),
                // DP 101, unknown, a value of 50.
                report(&[101, 2, 0, 4, 0, 0, 0, 50]),
            ],
        );
        let shown: Vec<String> = got.iter().map(|d| d.shown(&profile)).collect();
        assert_eq!(
            shown[0],
            "raw 00 00 00 96 (150 % is out of range: the profile allows 0 to 100 %)"
        );
        assert_eq!(
            shown[1],
            "raw 20 (enum index 32 has no label: the profile labels 0 to 11)"
        );
        assert_eq!(
            shown[2],
            "raw 84 (bits 0x80 are not defined: the profile defines bits 0 to 6)"
        );
        assert_eq!(
            shown[3],
            "raw ff ff ff ce (-5.0 m² is out of range: the profile allows 0.0 to 999.9 m²)"
        );
        assert!(
            shown[4].ends_with("(300 bytes, over the profile's maximum of 255)"),
            "{}",
            shown[4]
        );
        assert_eq!(
            shown[5],
            "raw 02 (bool byte 0x02: a bool is 0x00 or 0x01; allowed: bool false or true)"
        );
        assert_eq!(got[6].name(), "dp 101 (not in the profile)");
        assert_eq!(shown[6], "value 50");
        // The value is kept, but nothing of it fits.
        assert_eq!(got[0].value, Some(Value::Int(150)));
        assert!(got[..6].iter().all(|d| !d.fits()));
        let json = serde_json::to_value(&got[0]).unwrap();
        assert_eq!(json["misfit"], "limit");
        assert_eq!(json["limit"], "out_of_range");
        assert_eq!(json["max"], "100");
    }
}
