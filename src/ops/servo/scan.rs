//! Finding the servos on a bus: every id at every chosen baud rate, with each one's details.
//! Pings go out at the pace of the bus, not of the host ([`Sweep`]): behind a USB adapter that
//! holds answers back for its latency timer, a 0-254 scan still takes about half a second.

use super::params::{read_request, read_value};
use super::{Presence, param_by_id, ping, read_param, switch};
use crate::link::{Client, Match, ReplySpec, Request, Sweep, SweepReply};
use crate::ops::{Cancel, OpError, Progress};
use crate::profile::{Profile, Value};
use crate::protocol::servo::cmd;
use serde::Serialize;
use std::collections::BTreeSet;
use std::ops::RangeInclusive;
use std::time::Duration;

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

/// What a scan found, and how it met the line.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ScanReport {
    /// The servos found, by baud rate (in the plan's order) and id.
    pub rows: Vec<ScanRow>,
    /// Ids pinged again one by one: the ids a damaged answer can have come from, and the ids
    /// whose answer came after its sweep had ended.
    pub asked_again: usize,
    /// Answers that came later than their window (counted for their ids all the same; each
    /// widens the automatic margin).
    pub late_answers: usize,
    /// The margin the last sweep waited with: `--margin-ms`, or the automatic one (the servo's
    /// 1.5 ms, the adapter's latency timer, the answer latency measured), in ms.
    pub margin_ms: f64,
}

/// How long a servo takes on the bus before it answers, at most (the vendor's: 0.2-1 ms).
pub(super) const BUS_LATENCY: Duration = Duration::from_millis(1);
/// The longest READ_DATA answer: header, command, length, id, parameter, 4 value bytes, sum.
const READ_ANSWER_BYTES: usize = 11;
/// A PING answer: header, command, length, id, sum.
const PING_ANSWER_BYTES: usize = 6;
/// Ids pinged in one sweep (progress and cancel come between sweeps).
const SWEEP_IDS: usize = 128;

/// The ids that answer a ping at the port's rate, found by sweeps ([`Sweep`]): pinged at the
/// bus's pace, each answer counted for its id whenever it comes; the ids a damaged frame can
/// have come from, and ids whose answer came after its sweep, are pinged again one by one (a
/// glitch is not a duplicate: an id is a possible duplicate only when it answers garbled
/// again). Returns each id that answered with what answered, and the report's counters.
pub(super) fn find_ids(
    client: &Client,
    ids: &[u8],
    cancel: &Cancel,
    progress: &mut dyn FnMut(usize, u8),
) -> Result<(Vec<(u8, Presence)>, ScanReport), OpError> {
    let mut report = ScanReport {
        rows: Vec::new(),
        asked_again: 0,
        late_answers: 0,
        margin_ms: 0.0,
    };
    let mut present: BTreeSet<u8> = BTreeSet::new();
    let mut again: BTreeSet<u8> = BTreeSet::new();
    let mut take = |reply: &SweepReply, chunk: &[u8], report: &mut ScanReport| {
        report.margin_ms = reply.margin.as_secs_f64() * 1e3;
        for (i, a) in reply.answers.iter().enumerate() {
            if let Some(a) = a {
                present.insert(chunk[i]);
                report.late_answers += usize::from(a.late);
            }
        }
        for (_, candidates) in &reply.garbled {
            again.extend(candidates.iter().map(|&i| chunk[i]));
        }
        // A ping answer that came after its sweep: that servo is there; ask it again to be sure.
        for p in &reply.strays {
            if p.command == cmd::PING
                && let Some(&id) = p.payload.first()
                && ids.contains(&id)
            {
                report.late_answers += 1;
                again.insert(id);
            }
        }
    };
    for (k, chunk) in ids.chunks(SWEEP_IDS).enumerate() {
        if cancel.is_cancelled() {
            return Err(OpError::Cancelled);
        }
        let reply = client.sweep(ping_sweep(chunk))?;
        take(&reply, chunk, &mut report);
        progress(k * SWEEP_IDS + chunk.len(), *chunk.last().unwrap_or(&0));
    }
    // Answers still on their way after the last sweep.
    let tail = client.sweep(ping_sweep(&[]))?;
    take(&tail, &[], &mut report);
    let mut out: Vec<(u8, Presence)> = Vec::new();
    for &id in ids {
        if again.contains(&id) {
            if cancel.is_cancelled() {
                return Err(OpError::Cancelled);
            }
            report.asked_again += 1;
            match ask_again(client, id)? {
                Presence::Absent if present.contains(&id) => out.push((id, Presence::Present)),
                Presence::Absent => {}
                p => out.push((id, p)),
            }
        } else if present.contains(&id) {
            out.push((id, Presence::Present));
        }
    }
    Ok((out, report))
}

/// Pings `id` on its own, once at a time, up to three times: present at the first clean answer,
/// absent at the first clean silence, a possible duplicate when it answers garbled twice (two
/// servos on one id garble every answer; stray junk on the line rarely twice).
fn ask_again(client: &Client, id: u8) -> Result<Presence, OpError> {
    let mut garbled = None;
    for _ in 0..3 {
        match ping(client, id, 1)? {
            Presence::PossibleDuplicate(e) if garbled.is_some() => {
                return Ok(Presence::PossibleDuplicate(e));
            }
            Presence::PossibleDuplicate(e) => garbled = Some(e),
            p => return Ok(p),
        }
    }
    Ok(garbled.map_or(Presence::Absent, Presence::PossibleDuplicate))
}

/// A sweep of pings to `ids`.
fn ping_sweep(ids: &[u8]) -> Sweep {
    Sweep {
        requests: ids
            .iter()
            .map(|&id| {
                Request::new(cmd::PING, vec![id])
                    .reply(ReplySpec::Required(Match::servo(cmd::PING, &[id])))
            })
            .collect(),
        answer_bytes: PING_ANSWER_BYTES,
        device_latency: BUS_LATENCY,
    }
}

/// Reads each present servo's details (type, firmware, serial number, voltage, temperature,
/// status) in one sweep; a value that did not come is read again on its own.
fn details(client: &Client, profile: &Profile, rows: &mut [ScanRow]) -> Result<(), OpError> {
    const PARAMS: [u8; 6] = [6, 7, 8, 1, 4, 5];
    let mut asked: Vec<(usize, &crate::profile::Param)> = Vec::new();
    let mut requests = Vec::new();
    for (r, row) in rows.iter().enumerate() {
        if row.presence != Presence::Present {
            continue;
        }
        for pid in PARAMS {
            if let Ok(p) = param_by_id(profile, pid) {
                requests.push(read_request(profile, row.id, p)?);
                asked.push((r, p));
            }
        }
    }
    if requests.is_empty() {
        return Ok(());
    }
    let reply = client.sweep(Sweep {
        requests,
        answer_bytes: READ_ANSWER_BYTES,
        device_latency: BUS_LATENCY,
    })?;
    for ((r, p), answer) in asked.into_iter().zip(reply.answers) {
        let row = &mut rows[r];
        let value = match answer {
            Some(a) => read_value(profile, row.id, p, &a.packet.payload).ok(),
            None => read_param(client, profile, row.id, p).ok(),
        };
        match p.id {
            6 => row.servo_type = value,
            7 => row.firmware = value,
            8 => row.serial = value,
            1 => row.voltage_mv = value,
            4 => row.temperature = value,
            _ => row.status = value,
        }
    }
    Ok(())
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

/// Scans the plan's ids at each of its bauds ([`find_ids`]), reading each found servo's
/// details, then returns the port to the plan's home rate. `found` sees each row as it is found.
pub fn scan(
    client: &Client,
    profile: &Profile,
    plan: &ScanPlan,
    cancel: &Cancel,
    progress: &mut dyn FnMut(Progress),
    found: &mut dyn FnMut(&ScanRow),
) -> Result<ScanReport, OpError> {
    let (bauds, home_baud) = (&plan.bauds, plan.home_baud);
    let ids: Vec<u8> = plan
        .ids
        .clone()
        .filter(|&i| i != crate::protocol::servo::BROADCAST_ID)
        .collect();
    let total = (ids.len() * bauds.len()) as u64;
    let mut report = ScanReport {
        rows: Vec::new(),
        asked_again: 0,
        late_answers: 0,
        margin_ms: 0.0,
    };
    let result = (|| {
        for (b, &baud) in bauds.iter().enumerate() {
            switch(client, baud)?;
            let before = (b * ids.len()) as u64;
            let (answered, at_baud) = find_ids(client, &ids, cancel, &mut |done, id| {
                progress(Progress {
                    done: before + done as u64,
                    total,
                    message: crate::profile::Text::new(
                        format!("id {id} at {baud} baud"),
                        format!("ID {id},波特率 {baud}"),
                    ),
                })
            })?;
            report.asked_again += at_baud.asked_again;
            report.late_answers += at_baud.late_answers;
            report.margin_ms = at_baud.margin_ms;
            let mut rows: Vec<ScanRow> = answered
                .into_iter()
                .map(|(id, presence)| ScanRow {
                    id,
                    baud,
                    presence,
                    servo_type: None,
                    firmware: None,
                    serial: None,
                    voltage_mv: None,
                    temperature: None,
                    status: None,
                })
                .collect();
            details(client, profile, &mut rows)?;
            for row in &rows {
                found(row);
            }
            report.rows.extend(rows);
        }
        Ok(())
    })();
    let _ = client.set_baud(home_baud);
    report
        .rows
        .sort_by_key(|r| (bauds.iter().position(|&b| b == r.baud), r.id));
    result.map(|()| report)
}
