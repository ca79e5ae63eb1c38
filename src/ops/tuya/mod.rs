//! Tuya operations as the Wi-Fi module: the status query (asked again for data points whose
//! reports were lost), verified data-point commands, and the MCU firmware update (OTA).
//!
//! Reports are read one data point at a time against the profile ([`reports`]); a command is
//! verified by the reports received after it, up to a read-back query ([`verify`]).

pub mod confirm;
pub mod conform;
mod ota;
mod reports;
mod verify;

pub use confirm::{COME_BACK_LIMIT, product_info};
pub use ota::{
    DEFAULT_PACKET, Expect, FirmwareFileError, OTA_ACK_WAIT, OTA_RETRIES, OtaReport, OtaTiming,
    check_file, duration_text, expected_text, image_version, is_version, ota, packet_size,
    read_image, transfer_bytes, transfer_time, update,
};
pub use reports::{DpMisfit, ReportedDp, field_value, is_report, read_reports};
pub use verify::{DpCheck, set_dps, set_dps_request};

use super::OpError;
use crate::link::session::tuya::{reported_ids, reports_reply};
use crate::link::{ExchangeError, Request, Watch, Watched};
use crate::ops::Device;
use crate::packet::Packet;
use crate::profile::{Command, DataPointDef, Input, Profile, Value};
use crate::protocol::tuya::cmd;
use crate::protocol::{Direction, FrameError};
use serde::Serialize;
use std::time::{Duration, Instant};

/// How many status queries one read asks at most: the first, and two more for data points
/// whose reports were lost.
pub const QUERIES: u8 = 3;

/// The status query (0x08): its answer is the reports (0x07) of every data point of the
/// profile the MCU reports, complete when each has reported.
pub fn query_request(profile: &Profile) -> Request {
    let ids = reported_dps(profile);
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

/// How long a read listens, after a status query whose answer left data points out, for more
/// reports before it asks again: the time a Wi-Fi module waits before it resends a request
/// (TUYA_FIELD_NOTES §9: 1 s). Each report of a missing data point starts it again.
pub const LISTEN_QUIET: Duration = Duration::from_secs(1);
/// The longest a read listens between two queries, however the reports trickle in.
pub const LISTEN_CAP: Duration = Duration::from_secs(10);

/// Reports gathered by status queries.
#[derive(Debug, Clone, PartialEq)]
pub struct Gathered {
    /// Every report frame received (0x07 and 0x22), in order: the queries' answers and those
    /// that came between them.
    pub reports: Vec<Packet>,
    /// Queries sent.
    pub queries: u8,
    /// Report frames that came outside a query's answer (after it ended, before the next: a
    /// slow MCU), kept all the same.
    pub between: usize,
    /// Frames refused meanwhile: over the protocol's maximum length, a bad checksum, cut short.
    pub refused: Vec<FrameError>,
}

impl Gathered {
    fn take(&mut self, watch: &Watch) {
        for item in watch.take() {
            self.keep(item);
        }
    }

    fn keep(&mut self, item: Watched) {
        match item {
            Watched::Report(p) => self.reports.push(p),
            Watched::Refused(e) => self.refused.push(e),
            Watched::Tuya(_) => {}
        }
    }

    /// Listens for reports of `missing` until none came for [`LISTEN_QUIET`] (or
    /// [`LISTEN_CAP`]), keeping all.
    fn listen(&mut self, watch: &Watch, missing: &mut Vec<u8>) {
        let cap = Instant::now() + LISTEN_CAP;
        let mut quiet_until = Instant::now() + LISTEN_QUIET;
        while !missing.is_empty() {
            let now = Instant::now();
            let Some(item) = watch.next(quiet_until.min(cap).saturating_duration_since(now)) else {
                return;
            };
            if let Watched::Report(p) = &item {
                let news = reported_ids(std::slice::from_ref(p));
                if missing.iter().any(|id| news.contains(id)) {
                    missing.retain(|id| !news.contains(id));
                    quiet_until = Instant::now() + LISTEN_QUIET;
                }
            }
            self.keep(item);
        }
    }
}

/// Sends status queries (0x08), at most `queries`, until each of `ids` has been reported. Every
/// report is kept, those that come after a query's answer ended too (a slow MCU); when an
/// answer left data points out, the read listens while their reports still come
/// ([`LISTEN_QUIET`]) and asks again only for those still missing. Errors: the first query got
/// no answer at all, or the link failed.
pub fn gather(dev: Device<'_>, ids: &[u8], queries: u8) -> Result<Gathered, OpError> {
    let Device { client, profile } = dev;
    let watch = client.watch();
    let mut out = Gathered {
        reports: Vec::new(),
        queries: 0,
        between: 0,
        refused: Vec::new(),
    };
    let mut answered = 0;
    let mut missing: Vec<u8> = ids.to_vec();
    while out.queries < queries.max(1) && (out.queries == 0 || !missing.is_empty()) {
        let request = read_back_request(profile, if missing.is_empty() { ids } else { &missing });
        out.queries += 1;
        match client.request(request) {
            Ok(reply) => answered += reply.packets.len(),
            // Asked again: one that brings nothing leaves the data points missing.
            Err(ExchangeError::Timeout { .. } | ExchangeError::Garbled { .. })
                if out.queries > 1 => {}
            Err(e) => return Err(e.into()),
        }
        out.take(&watch);
        let reported = reported_ids(&out.reports);
        missing.retain(|id| !reported.contains(id));
        out.listen(&watch, &mut missing);
    }
    out.between = out.reports.len().saturating_sub(answered);
    Ok(out)
}

/// The MCU's status: each data point's last report, checked against the profile.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Status {
    /// Each data point reported, its last report, in the profile's order; then those the
    /// profile lacks, read by their own type.
    pub data_points: Vec<ReportedDp>,
    /// The profile's data points that were never reported, by id, after every query. A
    /// write-only data point is never reported and never missing.
    pub missing: Vec<u8>,
    /// Queries sent.
    pub queries: u8,
    /// Report frames that came between queries (kept and counted: a slow MCU).
    pub between: usize,
    /// Frames refused meanwhile, as a person reads why (over the protocol's maximum length, a
    /// bad checksum): their data points were not read.
    pub refused: Vec<String>,
}

impl Status {
    /// Whether every data point of the profile reported a value that fits it. A refused frame
    /// alone does not make a status incomplete (its data points may have come again); one
    /// whose data points never came leaves them missing, and says why.
    pub fn complete(&self) -> bool {
        self.missing.is_empty() && self.suspect().is_empty()
    }

    /// The data points whose last report does not fit: another type or length, or a value the
    /// data point does not allow (out of range, no label, undefined bits, too long).
    pub fn suspect(&self) -> Vec<&ReportedDp> {
        self.data_points
            .iter()
            .filter(|d| d.misfit.is_some())
            .collect()
    }

    /// The data points the profile does not have, read by their own type.
    pub fn unknown(&self) -> Vec<&ReportedDp> {
        self.data_points
            .iter()
            .filter(|d| !d.in_profile())
            .collect()
    }
}

/// The data points a status query waits for: every one the MCU reports (not write-only).
pub fn reported_dps(profile: &Profile) -> Vec<u8> {
    profile
        .data_points
        .iter()
        .filter(|d| d.access.reported())
        .map(|d| d.id)
        .collect()
}

/// Every data point, as the MCU reports them to status queries (0x08): a data point whose
/// report was lost is asked again, up to [`QUERIES`] queries, after listening for a slow MCU's
/// late reports; those still missing are named.
pub fn query_status(dev: Device<'_>) -> Result<Status, OpError> {
    let ids = reported_dps(dev.profile);
    let gathered = gather(dev, &ids, QUERIES)?;
    Ok(status_of(dev.profile, &ids, &gathered))
}

/// The status that `gathered` reports of data points `ids`: each one's last report, in the
/// profile's order, then the unknown ones.
pub fn status_of(profile: &Profile, ids: &[u8], gathered: &Gathered) -> Status {
    let mut last: Vec<ReportedDp> = Vec::new();
    for dp in read_reports(profile, &gathered.reports) {
        last.retain(|d| d.id != dp.id);
        last.push(dp);
    }
    let rank = |id: u8| ids.iter().position(|i| *i == id).unwrap_or(usize::MAX);
    last.sort_by_key(|d| (rank(d.id), d.id));
    Status {
        missing: ids
            .iter()
            .copied()
            .filter(|id| !last.iter().any(|d| d.id == *id))
            .collect(),
        data_points: last,
        queries: gathered.queries,
        between: gathered.between,
        refused: gathered.refused.iter().map(ToString::to_string).collect(),
    }
}
