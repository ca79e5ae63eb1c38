//! Verified data-point commands. A command (0x06) is verified for a data point when a report
//! received after it carries the value sent and no later report in the window contradicts it;
//! the window ends with a read-back status query, so that a change the MCU made on its own and
//! whose report was lost (power off resetting the mode just set) is still seen.

use super::reports::{ReportedDp, read_reports};
use super::{QUERIES, dp_command, gather};
use crate::link::session::tuya::command_ids;
use crate::link::{ExchangeError, Request};
use crate::ops::Device;
use crate::ops::OpError;
use crate::profile::{Input, Profile, Value};
use crate::protocol::Direction;
use serde::Serialize;

/// What the MCU made of one data point of a command.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DpCheck {
    /// The data point's id.
    pub id: u8,
    /// Its name in the profile.
    pub ident: String,
    /// The value sent (raw).
    pub sent: Value,
    /// Reports of it received after the command, up to the read-back.
    pub reports: usize,
    /// The last of them: what the MCU holds, by its own word.
    pub last: Option<ReportedDp>,
}

impl DpCheck {
    /// Whether the MCU's last report of it carries the value sent.
    pub fn verified(&self) -> bool {
        self.last
            .as_ref()
            .is_some_and(|r| r.misfit.is_none() && r.value.as_ref() == Some(&self.sent))
    }
}

/// The payload of the 0x06 command that sends `inputs` (data points by name or dpid), checked
/// against the profile (each named once, writable, type, range) without sending anything: the
/// command line checks what it was given with it before it opens the port.
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
/// writable), waits for the MCU's report of each (bounded), then reads them back with status
/// queries (asked again for reports that were lost, up to [`QUERIES`]), and checks each data
/// point by its last report in that window.
pub fn set_dps(dev: Device<'_>, inputs: &[(String, Input)]) -> Result<Vec<DpCheck>, OpError> {
    let Device { client, profile } = dev;
    let command = dp_command(profile)?;
    let payload = set_dps_request(profile, inputs)?;
    let written = profile
        .decode(command, Direction::HostToDevice, &payload)
        .map_err(|e| OpError::answer(&command.ident, e))?;
    let ids = command_ids(&payload);
    let request = Request::for_command(profile, command, payload);
    let mut window = match client.request(request) {
        Ok(r) => r.packets,
        // No report at all: the read-back still says what the MCU holds.
        Err(ExchangeError::Timeout { .. } | ExchangeError::Garbled { .. }) => Vec::new(),
        Err(e) => return Err(e.into()),
    };
    window.extend(gather(dev, &ids, QUERIES)?.reports);
    let reported = read_reports(profile, &window);
    Ok(written
        .values
        .iter()
        .filter_map(|w| Some((w, profile.find_data_point(&w.ident)?.id)))
        .map(|(w, id)| {
            let of_it: Vec<&ReportedDp> = reported.iter().filter(|r| r.id == id).collect();
            DpCheck {
                id,
                ident: w.ident.clone(),
                sent: w.value.clone(),
                reports: of_it.len(),
                last: of_it.last().map(|r| (*r).clone()),
            }
        })
        .collect())
}
