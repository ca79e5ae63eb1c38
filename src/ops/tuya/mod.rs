//! Tuya operations as the Wi-Fi module: the status query (asked again for data points whose
//! reports were lost), verified data-point commands, and the MCU firmware update (OTA).
//!
//! Reports are read one data point at a time against the profile ([`reports`]); a command is
//! verified by the reports received after it, up to a read-back query ([`verify`]).

mod ota;
mod reports;
mod verify;

pub use ota::{
    DEFAULT_PACKET, FirmwareFileError, OTA_ACK_WAIT, OTA_RETRIES, OtaReport, OtaTiming, check_file,
    duration_text, expected_text, ota, packet_size, read_image, transfer_bytes, transfer_time,
};
pub use reports::{DpMisfit, ReportedDp, field_value, read_reports};
pub use verify::{DpCheck, set_dps, set_dps_request};

use super::OpError;
use crate::link::session::tuya::{reported_ids, reports_reply};
use crate::link::{ExchangeError, Request};
use crate::ops::Device;
use crate::packet::Packet;
use crate::profile::{Command, DataPointDef, Input, Profile, Value};
use crate::protocol::Direction;
use crate::protocol::tuya::cmd;
use serde::Serialize;

/// How many status queries one read asks at most: the first, and two more for data points
/// whose reports were lost.
pub const QUERIES: u8 = 3;

/// The status query (0x08): its answer is the reports (0x07) of every data point of the
/// profile, complete when each has reported.
pub fn query_request(profile: &Profile) -> Request {
    let ids: Vec<u8> = profile.data_points.iter().map(|d| d.id).collect();
    Request::new(cmd::QUERY_STATUS, Vec::new()).reply(reports_reply(profile, &ids))
}

/// A status query (0x08) that reads back data points `ids` (after a command): complete when
/// each of them has reported.
pub fn read_back_request(profile: &Profile, ids: &[u8]) -> Request {
    Request::new(cmd::QUERY_STATUS, Vec::new()).reply(reports_reply(profile, ids))
}

/// The Wi-Fi state report (0x03) the module sends the MCU: `state` 0-6 (the profile's labels
/// name them). The MCU acks it; the ack is seen in the packet log.
pub fn wifi_state_request(state: u8) -> Request {
    Request::new(cmd::WIFI_STATE, vec![state])
}

fn dp_command(profile: &Profile) -> Result<&Command, OpError> {
    profile.command_by_id(cmd::DP_COMMAND).ok_or_else(|| {
        OpError::unknown_command(
            profile,
            format!("{:#04x} (data-point command)", cmd::DP_COMMAND),
        )
    })
}

/// The 0x06 command that sets data point `def` to the raw `value`, checked against the profile
/// (type, range, writable) before anything is built. It waits for the MCU's report of that data
/// point (bounded), which the link passes on as a report.
pub fn dp_request(profile: &Profile, def: &DataPointDef, value: Value) -> Result<Request, OpError> {
    let command = dp_command(profile)?;
    let payload = profile.encode(
        command,
        Direction::HostToDevice,
        &[(def.field.ident.clone(), Input::Raw(value))],
    )?;
    Ok(Request::for_command(profile, command, payload))
}

/// Reports gathered by status queries.
#[derive(Debug, Clone, PartialEq)]
pub struct Gathered {
    /// Every report frame received, in order.
    pub reports: Vec<Packet>,
    /// Queries sent.
    pub queries: u8,
}

/// Sends status queries (0x08), at most `queries`, until each of `ids` has been reported: a
/// query whose answer lost some reports is asked again for them. Errors: the first query got no
/// answer at all, or the link failed.
pub fn gather(dev: Device<'_>, ids: &[u8], queries: u8) -> Result<Gathered, OpError> {
    let Device { client, profile } = dev;
    let mut out = Gathered {
        reports: Vec::new(),
        queries: 0,
    };
    let mut missing: Vec<u8> = ids.to_vec();
    while out.queries < queries.max(1) && (out.queries == 0 || !missing.is_empty()) {
        let request = read_back_request(profile, if missing.is_empty() { ids } else { &missing });
        out.queries += 1;
        match client.request(request) {
            Ok(reply) => out.reports.extend(reply.packets),
            // Asked again: one that brings nothing leaves the data points missing.
            Err(ExchangeError::Timeout { .. } | ExchangeError::Garbled { .. })
                if out.queries > 1 => {}
            Err(e) => return Err(e.into()),
        }
        let reported = reported_ids(&out.reports);
        missing.retain(|id| !reported.contains(id));
    }
    Ok(out)
}

/// The MCU's status: each data point's last report, checked against the profile.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Status {
    /// Each data point reported, its last report, in the profile's order; then those the
    /// profile lacks.
    pub data_points: Vec<ReportedDp>,
    /// The profile's data points that were never reported, by id, after every query.
    pub missing: Vec<u8>,
    /// Queries sent.
    pub queries: u8,
}

impl Status {
    /// Whether every data point of the profile reported a value that fits it.
    pub fn complete(&self) -> bool {
        self.missing.is_empty() && self.data_points.iter().all(|d| d.misfit.is_none())
    }
}

/// Every data point, as the MCU reports them to status queries (0x08): a data point whose
/// report was lost is asked again, up to [`QUERIES`] queries; those still missing are named.
pub fn query_status(dev: Device<'_>) -> Result<Status, OpError> {
    let profile = dev.profile;
    let ids: Vec<u8> = profile.data_points.iter().map(|d| d.id).collect();
    let gathered = gather(dev, &ids, QUERIES)?;
    let mut last: Vec<ReportedDp> = Vec::new();
    for dp in read_reports(profile, &gathered.reports) {
        last.retain(|d| d.id != dp.id);
        last.push(dp);
    }
    let rank = |id: u8| ids.iter().position(|i| *i == id).unwrap_or(usize::MAX);
    last.sort_by_key(|d| (rank(d.id), d.id));
    Ok(Status {
        missing: ids
            .iter()
            .copied()
            .filter(|id| !last.iter().any(|d| d.id == *id))
            .collect(),
        data_points: last,
        queries: gathered.queries,
    })
}
