//! Waiting for data-point reports (0x07): the data points a frame names, and the answer a query
//! or a data-point command waits for (PROTOCOL_NOTES §3: the MCU answers each accepted data
//! point of a 0x06 with its own report, and a 0x08 with a report of every data point).

use crate::link::request::{Match, ReplySpec};
use crate::packet::Packet;
use crate::profile::Profile;
use crate::protocol::tuya::cmd;
use crate::protocol::tuya::dp::{self, DpType};

/// The bytes assumed for a string or raw value whose length the profile does not bound.
const OPEN_VALUE_BYTES: usize = 32;

/// The data points a 0x06 command's data sets, in order, each once.
pub fn command_ids(data: &[u8]) -> Vec<u8> {
    let mut ids = Vec::new();
    for p in dp::walk(data).points {
        if !ids.contains(&p.id) {
            ids.push(p.id);
        }
    }
    ids
}

/// The data points that `reports` (0x07 frames, and 0x22 synchronous reports) carry, whatever
/// their type or length.
pub fn reported_ids(reports: &[Packet]) -> Vec<u8> {
    reports
        .iter()
        .filter(|p| p.command == cmd::DP_REPORT || p.command == cmd::DP_REPORT_SYNC)
        .flat_map(|p| dp::walk(&p.payload).points)
        .map(|p| p.id)
        .collect()
}

/// A report frame's size on the wire for data point `id` of `profile`: header, length and
/// checksum (7), the data point's own header (4) and its value.
fn report_bytes(profile: &Profile, id: u8) -> usize {
    let value = profile
        .data_point(id)
        .map_or(OPEN_VALUE_BYTES, |d| match d.dp_type {
            DpType::Bool | DpType::Enum => 1,
            DpType::Value => 4,
            DpType::Bitmap => d.field.ty.width().unwrap_or(4),
            DpType::String | DpType::Raw => OPEN_VALUE_BYTES,
        });
    7 + 4 + value
}

/// The answer to wait for when the MCU reports data points `ids`: their reports, complete when
/// each has been reported, and bounded in time by their size on the wire.
pub fn reports_reply(profile: &Profile, ids: &[u8]) -> ReplySpec {
    ReplySpec::Reports {
        each: Match::command(cmd::DP_REPORT),
        ids: ids.to_vec(),
        bytes: ids.iter().map(|id| report_bytes(profile, *id)).sum(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ids_of_a_command_and_of_reports_whatever_their_form() {
        // power=off, mode=8, power again.
        let data = [1, 1, 0, 1, 0, 3, 4, 0, 1, 8, 1, 1, 0, 1, 1];
        assert_eq!(command_ids(&data), [1, 3]);
        // DP 3 as a 4-byte value and DP 1 as a 4-byte bool are still reports of 3 and 1.
        let report = |data: &[u8]| {
            Packet::tuya_received(crate::protocol::tuya::Frame::from_mcu(
                cmd::DP_REPORT,
                data.to_vec(),
            ))
        };
        let got = [
            report(&[3, 2, 0, 4, 0, 0, 0, 1]),
            report(&[1, 1, 0, 4, 0, 0, 0, 1]),
        ];
        assert_eq!(reported_ids(&got), [3, 1]);
    }

    #[test]
    fn a_query_of_the_vacuum_waits_for_its_19_data_points() {
        let profile = crate::profile::Registry::builtin()
            .and_then(|r| r.get("tuya-vacuum"))
            .expect("the built-in vacuum profile");
        let ids: Vec<u8> = profile.data_points.iter().map(|d| d.id).collect();
        let ReplySpec::Reports {
            ids: want, bytes, ..
        } = reports_reply(&profile, &ids)
        else {
            panic!("reports");
        };
        assert_eq!(want.len(), 19);
        // Bools and enums 12 bytes each, values 15, the string and the raw 43.
        assert!(bytes > 19 * 12 && bytes < 19 * 43, "{bytes}");
    }
}
