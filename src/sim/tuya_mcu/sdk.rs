//! The data-point handling of Tuya's MCU SDK (v2.5.x, C), which the simulated firmware is built
//! on: how a 0x06 command is walked and answered, and how a report is put on the wire.
//!
//! Read from the SDK's public source (`mcu_sdk/system.c` `data_handle` and `data_point_handle`,
//! `mcu_sdk/mcu_api.c` `mcu_dp_*_update` and `mcu_get_dp_download_*`, and the generated
//! `dp_download_*_handle` templates of `protocol.c`; e.g. Tuya-Community's
//! tuya-iotos-embeded-mcu-demo-wifi-ble-stm32_lcd_wb3s, SDK v2.5.6):
//! - the data points of a 0x06 frame are handled in frame order, each on its own;
//! - a data point whose type byte is not its definition's gets no handler, hence no report;
//! - a handler reports the value it received, once (`mcu_dp_bool_update(DPID, value)` after
//!   handling): one 0x07 frame per data point, `dpid, type, len, value`, with the MCU's version
//!   byte; a bool is reported 0 or 1, a value as 4 bytes big-endian, an enum as 1 byte, a
//!   bitmap in 1, 2 or 4 bytes as its value needs (`mcu_dp_fault_update`).
//!
//! Beyond the SDK, the simulated firmware refuses (answers nothing to) a data point that is
//! report-only, not in the profile, of a length its type does not allow (where the SDK would
//! read past the value), or out of the profile's range.

use super::TuyaMcu;
use super::vacuum::as_value;
use crate::protocol::tuya::dp::{self, DpType, DpValue, RawPoint};
use crate::protocol::tuya::{Frame, cmd};
use std::collections::BTreeMap;
use std::str::FromStr;

/// How a misreporting firmware puts a data point on the wire: another type byte, another
/// length, or both (PROTOCOL_NOTES §4). The value goes big-endian into `len` bytes (a number),
/// or is cut or padded with zeros to `len` bytes (a string or raw bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WireForm {
    /// The type byte sent.
    pub ty: u8,
    /// The length sent, in bytes.
    pub len: u16,
}

impl WireForm {
    /// `value`'s bytes in this form.
    fn bytes(self, value: &DpValue) -> Vec<u8> {
        let len = usize::from(self.len);
        let number = |n: u64| {
            let be = n.to_be_bytes();
            let mut out = vec![0u8; len.saturating_sub(8)];
            out.extend_from_slice(&be[8 - len.min(8)..]);
            out
        };
        match value {
            DpValue::Bool(b) => number(u64::from(*b)),
            DpValue::Value(v) => number(*v as u32 as u64),
            DpValue::Enum(e) => number(u64::from(*e)),
            DpValue::Bitmap { bits, .. } => number(u64::from(*bits)),
            DpValue::String(s) => fit(s.as_bytes(), len),
            DpValue::Raw(b) => fit(b, len),
        }
    }
}

fn fit(bytes: &[u8], len: usize) -> Vec<u8> {
    let mut out = bytes[..bytes.len().min(len)].to_vec();
    out.resize(len, 0);
    out
}

/// Reads `ID:TYPE:LEN` (`3:value:4`: data point 3 reported as a 4-byte value; TYPE is a type
/// name or its byte), as `botbench sim tuya-vacuum --misreport` takes it.
pub fn parse_misreport(text: &str) -> Result<(u8, WireForm), String> {
    let bad = || format!("'{text}': expected ID:TYPE:LEN such as 3:value:4");
    let mut parts = text.trim().split(':');
    let (Some(id), Some(ty), Some(len), None) =
        (parts.next(), parts.next(), parts.next(), parts.next())
    else {
        return Err(bad());
    };
    let id = u8::from_str(id.trim()).map_err(|_| bad())?;
    let ty = [
        DpType::Raw,
        DpType::Bool,
        DpType::Value,
        DpType::String,
        DpType::Enum,
        DpType::Bitmap,
    ]
    .into_iter()
    .find(|t| t.name().eq_ignore_ascii_case(ty.trim()))
    .map(DpType::byte)
    .or_else(|| u8::from_str(ty.trim()).ok())
    .ok_or_else(|| {
        format!(
            "'{text}': type '{ty}' is none of raw, bool, value, string, enum, bitmap or a number"
        )
    })?;
    let len = u16::from_str(len.trim()).map_err(|_| bad())?;
    Ok((id, WireForm { ty, len }))
}

/// The SDK's bytes for a value: as `mcu_dp_*_update` writes them.
fn sdk_bytes(value: &DpValue) -> Vec<u8> {
    match value {
        DpValue::Bool(b) => vec![u8::from(*b)],
        DpValue::Value(v) => v.to_be_bytes().to_vec(),
        DpValue::Enum(e) => vec![*e],
        // mcu_dp_fault_update: as many bytes as the value needs.
        DpValue::Bitmap { bits, .. } => match *bits {
            b if b <= 0xFF => vec![b as u8],
            b if b <= 0xFFFF => (b as u16).to_be_bytes().to_vec(),
            b => b.to_be_bytes().to_vec(),
        },
        DpValue::String(s) => s.as_bytes().to_vec(),
        DpValue::Raw(b) => b.clone(),
    }
}

/// One data point's report data (`dpid, type, len, value`): the SDK's, or the misreporting
/// firmware's `forms`.
pub(super) fn report_data(id: u8, value: &DpValue, forms: &BTreeMap<u8, WireForm>) -> Vec<u8> {
    let (ty, bytes) = match forms.get(&id) {
        Some(form) => (form.ty, form.bytes(value)),
        None => (value.dp_type().byte(), sdk_bytes(value)),
    };
    let len = u16::try_from(bytes.len()).unwrap_or(u16::MAX);
    let mut data = vec![id, ty];
    data.extend_from_slice(&len.to_be_bytes());
    data.extend_from_slice(&bytes[..usize::from(len)]);
    data
}

impl TuyaMcu {
    /// A data point of a 0x06 as the SDK hands it to its handler, read as the firmware takes
    /// it; `None` when it gets no answer.
    fn accepted(&self, raw: &RawPoint) -> Option<DpValue> {
        let def = self.profile.data_point(raw.id)?;
        let writable = def.access.writable() || self.config.accept_read_only;
        if !writable || raw.ty != def.dp_type.byte() {
            return None;
        }
        let value = raw.value().ok()?;
        let value = match value {
            // The profile's width, whatever the bytes sent.
            DpValue::Bitmap { bits, width } => DpValue::Bitmap {
                bits,
                width: def.field.ty.width().map_or(width, |w| w.min(4) as u8),
            },
            v => v,
        };
        def.field.check(&as_value(&value)).ok()?;
        Some(value)
    }

    /// A 0x06 frame: each data point in order, as the SDK walks them; each accepted one is
    /// stored and answered by the SDK's one report of the value received, and the firmware's
    /// rules follow it. What the rules changed is reported afterwards, from the next tick, in
    /// the order it changed, when the module has not heard it already.
    pub(super) fn dp_command(&mut self, data: &[u8]) -> Vec<Vec<u8>> {
        let mut answers = Vec::new();
        let mut heard = self.dps.clone();
        let mut commanded: Vec<u8> = Vec::new();
        let mut changed: Vec<u8> = Vec::new();
        for raw in dp::walk(data).points {
            let Some(value) = self.accepted(&raw) else {
                continue;
            };
            self.dps.insert(raw.id, value.clone());
            answers.extend(self.report(raw.id));
            heard.insert(raw.id, value);
            commanded.push(raw.id);
            self.follow(raw.id, &commanded, &mut changed);
        }
        let mut reported = Vec::new();
        for id in changed {
            if reported.contains(&id) || self.dps.get(&id) == heard.get(&id) {
                continue;
            }
            reported.push(id);
            if !self.config.lose_rule_reports {
                self.own_report(id);
            }
        }
        answers
    }

    /// A 0x07 frame reporting one data point, with the MCU's version byte.
    pub(super) fn report(&self, id: u8) -> Option<Vec<u8>> {
        let data = self.report_data_of(id)?;
        self.encode(cmd::DP_REPORT, data)
    }

    /// A frame from the MCU, with its version byte.
    pub(super) fn encode(&self, command: u8, data: Vec<u8>) -> Option<Vec<u8>> {
        Frame {
            version: self.config.frame_version,
            command,
            data,
        }
        .encode()
        .ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_misreport_is_read_and_shapes_the_value() {
        let (id, form) = parse_misreport("3:value:4").unwrap();
        assert_eq!((id, form), (3, WireForm { ty: 2, len: 4 }));
        assert_eq!(
            report_data(3, &DpValue::Enum(1), &BTreeMap::from([(3, form)])),
            [3, 2, 0, 4, 0, 0, 0, 1]
        );
        let (_, bool4) = parse_misreport("1:bool:4").unwrap();
        assert_eq!(
            report_data(1, &DpValue::Bool(true), &BTreeMap::from([(1, bool4)])),
            [1, 1, 0, 4, 0, 0, 0, 1]
        );
        let (_, text2) = parse_misreport("15:3:2").unwrap();
        assert_eq!(text2.bytes(&DpValue::String("abc".into())), b"ab");
        for bad in [
            "3:value",
            "x:value:4",
            "3:float:4",
            "3:value:4:1",
            "3:value:-1",
        ] {
            assert!(parse_misreport(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn a_bitmap_is_reported_in_as_many_bytes_as_it_needs() {
        let bits = |b| DpValue::Bitmap { bits: b, width: 4 };
        assert_eq!(sdk_bytes(&bits(0x44)), [0x44]);
        assert_eq!(sdk_bytes(&bits(0x1234)), [0x12, 0x34]);
        assert_eq!(sdk_bytes(&bits(0x12345)), [0, 1, 0x23, 0x45]);
    }
}
