//! Finding the servos on a bus: every id at every chosen baud rate, with each one's details.

use super::{Presence, param_by_id, ping, ping_detail, read_param, switch};
use crate::link::Client;
use crate::ops::{Cancel, OpError, Progress};
use crate::profile::{Profile, Value};
use serde::Serialize;
use std::ops::RangeInclusive;

/// One servo found by a scan.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ScanRow {
    /// Its id.
    pub id: u8,
    /// The baud rate it answered at.
    pub baud: u32,
    /// Present, or a possible duplicate.
    pub presence: Presence,
    /// Servo type (parameter 6).
    pub servo_type: Option<i64>,
    /// Firmware version (parameter 7).
    pub firmware: Option<i64>,
    /// Serial number (parameter 8).
    pub serial: Option<i64>,
    /// Voltage in mV (parameter 1).
    pub voltage_mv: Option<i64>,
    /// Temperature (parameter 4), raw: °C or a thermistor reading, as the profile says
    /// ([`ScanRow::temperature_text`] shows it).
    pub temperature: Option<i64>,
    /// The raw status byte (parameter 5); its bit order is published inconsistently.
    pub status: Option<i64>,
}

impl ScanRow {
    /// The temperature as the profile shows parameter 4: `32 °C`, or `32.0 °C (raw 1779)` for a
    /// thermistor reading; `-` when not read.
    pub fn temperature_text(&self, profile: &Profile) -> String {
        match (self.temperature, profile.param(4)) {
            (Some(v), Some(p)) => p.field.display(&Value::Int(v)),
            (Some(v), None) => v.to_string(),
            (None, _) => "-".into(),
        }
    }

    /// The status byte as hex, e.g. `0x00`.
    pub fn status_hex(&self) -> String {
        self.status.map_or("-".into(), |s| format!("{s:#04x}"))
    }
}

fn details(client: &Client, profile: &Profile, row: &mut ScanRow) {
    let get = |pid: u8| {
        param_by_id(profile, pid)
            .ok()
            .and_then(|p| read_param(client, profile, row.id, p).ok())
    };
    row.servo_type = get(6);
    row.firmware = get(7);
    row.serial = get(8);
    row.voltage_mv = get(1);
    row.temperature = get(4);
    row.status = get(5);
}

/// What a scan covers.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ScanPlan {
    /// The ids to ping (255, broadcast, is skipped).
    pub ids: RangeInclusive<u8>,
    /// The baud rates to try, in order.
    pub bauds: Vec<u32>,
    /// The rate to leave the port at afterwards.
    pub home_baud: u32,
}

/// Scans the plan's ids at each of its bauds, reading each found servo's details, then returns
/// the port to the plan's home rate. `found` sees each row as it is found.
pub fn scan(
    client: &Client,
    profile: &Profile,
    plan: &ScanPlan,
    cancel: &Cancel,
    progress: &mut dyn FnMut(Progress),
    found: &mut dyn FnMut(&ScanRow),
) -> Result<Vec<ScanRow>, OpError> {
    let (bauds, home_baud) = (&plan.bauds, plan.home_baud);
    let ids: Vec<u8> = plan
        .ids
        .clone()
        .filter(|&i| i != crate::protocol::servo::BROADCAST_ID)
        .collect();
    let total = (ids.len() * bauds.len()) as u64;
    let mut rows = Vec::new();
    let mut done = 0;
    let result = (|| {
        for &baud in bauds.iter() {
            switch(client, baud)?;
            for &id in &ids {
                if cancel.is_cancelled() {
                    return Err(OpError::Cancelled);
                }
                let (mut presence, late) = ping_detail(client, id, 1)?;
                // A glitch is not a duplicate: an id is reported as one only when it answers
                // garbled again.
                if matches!(presence, Presence::PossibleDuplicate(_)) {
                    presence = ping(client, id, 2)?;
                }
                let mut here = vec![(id, presence)];
                if let Some(other) =
                    late.filter(|o| !rows.iter().any(|r: &ScanRow| r.id == *o && r.baud == baud))
                {
                    here.push((other, ping(client, other, 3)?));
                }
                for (id, presence) in here {
                    if presence == Presence::Absent {
                        continue;
                    }
                    let mut row = ScanRow {
                        id,
                        baud,
                        presence: presence.clone(),
                        servo_type: None,
                        firmware: None,
                        serial: None,
                        voltage_mv: None,
                        temperature: None,
                        status: None,
                    };
                    if presence == Presence::Present {
                        details(client, profile, &mut row);
                    }
                    found(&row);
                    rows.push(row);
                }
                done += 1;
                if done % 8 == 0 || done == total {
                    progress(Progress {
                        done,
                        total,
                        message: format!("id {id} at {baud} baud"),
                    });
                }
            }
        }
        Ok(())
    })();
    let _ = client.set_baud(home_baud);
    rows.sort_by_key(|r| (bauds.iter().position(|&b| b == r.baud), r.id));
    result.map(|()| rows)
}
