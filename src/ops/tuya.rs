//! Tuya operations as the Wi-Fi module: status query, verified data-point commands, MCU firmware
//! update (OTA).

use super::{Cancel, Check, FieldValues, OpError, Progress};
use crate::link::{Client, ExchangeError, Match, ReplySpec, Request};
use crate::packet::Packet;
use crate::profile::{Command, DataPointDef, Input, Profile, Value};
use crate::protocol::Direction;
use crate::protocol::tuya::cmd;
use std::time::{Duration, Instant};

/// How long the MCU may take to ack one OTA packet.
pub const OTA_ACK_WAIT: Duration = Duration::from_secs(5);
/// Retries of an OTA packet whose ack did not come.
pub const OTA_RETRIES: u8 = 3;
/// How long a pause ends a burst of reports.
pub const REPORT_QUIET: Duration = Duration::from_millis(300);

/// The status query (0x08): its answer is the burst of reports (0x07) that ends with a pause of
/// [`REPORT_QUIET`].
pub fn query_request() -> Request {
    Request::new(cmd::QUERY_STATUS, Vec::new()).reply(ReplySpec::Burst {
        each: Match::command(cmd::DP_REPORT),
        quiet: REPORT_QUIET,
    })
}

/// The Wi-Fi state report (0x03) the module sends the MCU: `state` 0-6 (the profile's labels
/// name them). The MCU acks it; the ack is seen in the packet log.
pub fn wifi_state_request(state: u8) -> Request {
    Request::new(cmd::WIFI_STATE, vec![state])
}

/// Every data point, as the MCU reports them to a query (0x08).
pub fn query(client: &Client) -> Result<Vec<Packet>, OpError> {
    Ok(client.request(query_request())?.packets)
}

fn dp_command(profile: &Profile) -> Result<&Command, OpError> {
    profile
        .command_by_id(cmd::DP_COMMAND)
        .ok_or_else(|| OpError::unknown_command(profile, "0x06 (data-point command)"))
}

/// The 0x06 command that sets data point `def` to the raw `value`, checked against the profile
/// (type, range, writable) before anything is built. Sent without waiting: what the MCU makes
/// of it comes back as a report (0x07).
pub fn dp_request(profile: &Profile, def: &DataPointDef, value: Value) -> Result<Request, OpError> {
    let command = dp_command(profile)?;
    let payload = profile.encode(
        command,
        Direction::HostToDevice,
        &[(def.field.ident.clone(), Input::Raw(value))],
    )?;
    Ok(Request::send_only(cmd::DP_COMMAND, payload))
}

/// The data points of report frames as named raw values, in the order reported.
pub fn report_values(profile: &Profile, reports: &[Packet]) -> FieldValues {
    let Some(report) = profile.command_by_id(cmd::DP_REPORT) else {
        return FieldValues::new();
    };
    reports
        .iter()
        .filter_map(|p| {
            profile
                .decode(report, Direction::DeviceToHost, &p.payload)
                .ok()
        })
        .flat_map(|d| d.values.into_iter().map(|v| (v.ident, v.value)))
        .collect()
}

/// The payload of the 0x06 command that sends `inputs` (data points by name or dpid), checked
/// against the profile (each named once, writable, type, range) without sending anything.
pub fn set_dps_request(profile: &Profile, inputs: &[(String, Input)]) -> Result<Vec<u8>, OpError> {
    let command = dp_command(profile)?;
    if inputs.is_empty() {
        return Err(OpError::NothingGiven {
            what: "data point",
            hint: "use NAME=VALUE",
        });
    }
    Ok(profile.encode(command, Direction::HostToDevice, inputs)?)
}

/// Sends data points (0x06), checked against the profile before sending (type, range,
/// writable: [`set_dps_request`]), and compares what the MCU reports back for each.
pub fn set_dps(
    client: &Client,
    profile: &Profile,
    inputs: &[(String, Input)],
) -> Result<Vec<Check>, OpError> {
    let command = dp_command(profile)?;
    let payload = set_dps_request(profile, inputs)?;
    let written = profile
        .decode(command, Direction::HostToDevice, &payload)
        .map_err(|e| OpError::answer(&command.ident, e))?;
    let req = Request::new(cmd::DP_COMMAND, payload).reply(ReplySpec::Burst {
        each: Match::command(cmd::DP_REPORT),
        quiet: REPORT_QUIET,
    });
    let reports = match client.request(req) {
        Ok(r) => r.packets,
        Err(ExchangeError::Timeout { .. }) => Vec::new(),
        Err(e) => return Err(e.into()),
    };
    let reported = report_values(profile, &reports);
    Ok(written
        .values
        .iter()
        .map(|w| Check {
            field: w.ident.clone(),
            written: w.value.clone(),
            read: reported
                .iter()
                .rev()
                .find(|(k, _)| *k == w.ident)
                .map_or(Value::Bytes(Vec::new()), |(_, v)| v.clone()),
        })
        .collect())
}

/// The result of a firmware upload.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct OtaReport {
    /// Image size in bytes.
    pub size: usize,
    /// The packet size the MCU asked for.
    pub packet_size: usize,
    /// Data packets sent.
    pub packets: usize,
    /// Packets sent again after a missing ack.
    pub retries: u32,
    /// Seconds taken.
    pub seconds: f64,
}

/// The packet size of the MCU's answer to 0x0a: 0 → 256, 1 → 512, 2 → 1024, nothing → 256.
pub fn packet_size(answer: &[u8]) -> Result<usize, OpError> {
    match answer.first() {
        None | Some(0) => Ok(256),
        Some(1) => Ok(512),
        Some(2) => Ok(1024),
        Some(x) => Err(OpError::Verify(format!(
            "the MCU asked for unknown packet size option {x}"
        ))),
    }
}

/// How an upload waits for acks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OtaTiming {
    /// How long the MCU may take to ack a packet.
    pub ack_wait: Duration,
    /// How many times a packet is sent again when its ack does not come.
    pub retries: u8,
}

impl Default for OtaTiming {
    /// 5 s and 3 retries, as the Tuya MCU SDK expects.
    fn default() -> Self {
        Self {
            ack_wait: OTA_ACK_WAIT,
            retries: OTA_RETRIES,
        }
    }
}

/// Uploads `image` to the MCU: 0x0a with the size, then 0x0b packets of the size the MCU asked
/// for (never larger), each acked within `timing.ack_wait` and sent up to `timing.retries` more
/// times, then the final empty packet at offset == size.
pub fn ota(
    client: &Client,
    image: &[u8],
    timing: OtaTiming,
    cancel: &Cancel,
    progress: &mut dyn FnMut(Progress),
) -> Result<OtaReport, OpError> {
    let attempts = timing.retries.saturating_add(1);
    if image.is_empty() {
        return Err(OpError::EmptyImage);
    }
    let size =
        u32::try_from(image.len()).map_err(|_| OpError::ImageTooLarge { size: image.len() })?;
    let started = Instant::now();
    let start = Request::new(cmd::OTA_START, size.to_be_bytes().to_vec())
        .margin(timing.ack_wait)
        .attempts(attempts);
    let answer = client
        .request(start)
        .map_err(|e| OpError::Verify(format!("the MCU did not accept the update: {e}")))?;
    let chunk = packet_size(answer.payload().unwrap_or_default())?;
    let mut retries = 0u32;
    let mut packets = 0usize;
    let total = image.len() as u64;
    for (i, data) in image.chunks(chunk).enumerate() {
        if cancel.is_cancelled() {
            return Err(OpError::Cancelled);
        }
        let offset = (i * chunk) as u32;
        let mut payload = offset.to_be_bytes().to_vec();
        payload.extend_from_slice(data);
        let req = Request::new(cmd::OTA_PACKET, payload)
            .margin(timing.ack_wait)
            .attempts(attempts);
        let reply = client.request(req).map_err(|e| match e {
            ExchangeError::Disconnected(r) => OpError::Verify(format!("link lost at offset {offset}: {r}")),
            e => OpError::Verify(format!(
                "the MCU stopped acking at offset {offset} (of {size} bytes) after {attempts} attempts: {e}"
            )),
        })?;
        retries += u32::from(reply.attempts - 1);
        packets += 1;
        let done = (offset as u64) + data.len() as u64;
        let secs = started.elapsed().as_secs_f64().max(1e-6);
        let rate = done as f64 / secs;
        let left = (total - done) as f64 / rate.max(1.0);
        progress(Progress {
            done,
            total,
            message: format!(
                "offset {done} of {size}, {:.0} B/s, {:.0} s left",
                rate, left
            ),
        });
    }
    let last = Request::new(cmd::OTA_PACKET, size.to_be_bytes().to_vec())
        .reply(ReplySpec::Optional(Match::command(cmd::OTA_PACKET)))
        .margin(Duration::from_secs(1))
        .attempts(1);
    client.request(last)?;
    Ok(OtaReport {
        size: image.len(),
        packet_size: chunk,
        packets,
        retries,
        seconds: started.elapsed().as_secs_f64(),
    })
}
