//! Finding the servos on a bus: every id at every chosen baud rate, with each one's details.
//! Pings go out at the pace of the bus, not of the host ([`Sweep`]): behind a USB adapter that
//! holds answers back for its latency timer, a 0-254 scan still takes about half a second.

use super::params::{read_request, read_value};
use super::{Presence, ping, read_param, switch};
use crate::link::{Client, Match, ReplySpec, Request, Sweep, SweepReply};
use crate::ops::{Cancel, OpError, Progress};
use crate::ops::{Device, Run};
use crate::packet::Packet;
use crate::profile::{ParamRole, Profile, Value};
use crate::protocol::Direction;
use crate::protocol::servo::cmd;
use serde::Serialize;
use std::collections::{BTreeMap, BTreeSet};
use std::ops::RangeInclusive;
use std::time::Duration;

/// One servo found by a scan, with what it says of itself: the parameters the profile gives
/// the roles of [`SCAN_ROLES`] (`None` where the profile has none, or the read failed).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ScanRow {
    /// Its id.
    pub id: u8,
    /// The baud rate it answered at.
    pub baud: u32,
    /// Present, or a possible duplicate.
    pub presence: Presence,
    /// Servo type (role ServoType: the seed's parameter 6).
    pub servo_type: Option<i64>,
    /// Firmware version (role FirmwareVersion: parameter 7).
    pub firmware: Option<i64>,
    /// Serial number (role SerialNumber: parameter 8).
    pub serial: Option<i64>,
    /// Voltage in mV (role Voltage: parameter 1).
    pub voltage_mv: Option<i64>,
    /// Temperature (role Temperature: parameter 4), raw: °C or a thermistor reading, as the
    /// profile says ([`ScanRow::temperature_text`] shows it).
    pub temperature: Option<i64>,
    /// The raw status byte (role Status: parameter 5); its bit order is published
    /// inconsistently.
    pub status: Option<i64>,
}

/// The parameter roles a scan reads for each servo found, in the order it reads them.
pub static SCAN_ROLES: [ParamRole; 6] = [
    ParamRole::ServoType,
    ParamRole::FirmwareVersion,
    ParamRole::SerialNumber,
    ParamRole::Voltage,
    ParamRole::Temperature,
    ParamRole::Status,
];

impl ScanRow {
    /// The temperature as the profile shows its Temperature parameter: `32 °C`, or
    /// `32.0 °C (raw 1779)` for a thermistor reading; `-` when not read.
    pub fn temperature_text(&self, profile: &Profile) -> String {
        match (
            self.temperature,
            profile.param_with_role(&ParamRole::Temperature),
        ) {
            (Some(v), Some(p)) => p.field.display(&Value::Int(v)),
            (Some(v), None) => v.to_string(),
            (None, _) => "-".into(),
        }
    }

    /// The status byte as hex, e.g. `0x00`.
    pub fn status_hex(&self) -> String {
        self.status.map_or("-".into(), |s| format!("{s:#04x}"))
    }

    /// Where the value of the parameter with `role` goes (one of [`SCAN_ROLES`]).
    fn column(&mut self, role: &ParamRole) -> Option<&mut Option<i64>> {
        match role {
            ParamRole::ServoType => Some(&mut self.servo_type),
            ParamRole::FirmwareVersion => Some(&mut self.firmware),
            ParamRole::SerialNumber => Some(&mut self.serial),
            ParamRole::Voltage => Some(&mut self.voltage_mv),
            ParamRole::Temperature => Some(&mut self.temperature),
            ParamRole::Status => Some(&mut self.status),
            ParamRole::ServoId | ParamRole::BaudOption { .. } => None,
        }
    }
}

/// What a scan found, and how it met the line.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ScanReport {
    /// The servos found, by baud rate (in the plan's order) and id.
    pub rows: Vec<ScanRow>,
    /// Ids pinged again: the ids a damaged answer can have come from (or whose ping it met on
    /// the bus, garbling both), and the ids whose answer came after its sweep had ended.
    pub asked_again: usize,
    /// Answers that came later than their window (counted for their ids all the same; each
    /// widens the automatic margin).
    pub late_answers: usize,
    /// The margin the last sweep waited with: `--margin-ms`, or the automatic one (the servo's
    /// 1.5 ms, the adapter's latency timer, the answer latency measured), in ms.
    pub margin_ms: f64,
    /// The most this computer ran behind a deadline of the scan's ping sweeps, in ms, when more
    /// [`crate::link::HELD_UP`] or more (a loaded computer: a servo may have been missed);
    /// `None`: on time throughout.
    pub host_late_ms: Option<f64>,
    /// The ids that stayed silent only in sweeps during which this computer was held up
    /// [`crate::link::HELD_UP`] or more past a deadline, however often asked again
    /// ([`HELD_UP_RESWEEPS`]): their answers may have come while it was not there to read them,
    /// so a servo may be there unseen. Empty when every silence was heard on time.
    pub unsure: Vec<Unsure>,
    /// Ids pinged again because they were silent in a sweep during which this computer was
    /// held up (not counted in [`Self::asked_again`], which is about the line).
    pub asked_after_hold_up: usize,
}

/// An id a scan cannot say is empty ([`ScanReport::unsure`]), at the baud rate it was asked at.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Unsure {
    /// The baud rate the id was pinged at.
    pub baud: u32,
    /// The servo id.
    pub id: u8,
}

/// Which ids a scan cannot vouch for ([`ScanReport::unsure`]), by baud rate, and the most this
/// computer was held up (`held_up_ms`), in both languages: `2 id(s) stayed silent only while
/// this computer was held up 31 ms past their answers' deadline, however often asked again (0,
/// 2 at 115200 baud): …`. `None` when there are none.
pub fn unsure_said(unsure: &[Unsure], held_up_ms: Option<f64>) -> Option<crate::i18n::Text> {
    if unsure.is_empty() {
        return None;
    }
    let mut by_baud: Vec<(u32, Vec<String>)> = Vec::new();
    for u in unsure {
        match by_baud.iter_mut().find(|(b, _)| *b == u.baud) {
            Some((_, ids)) => ids.push(u.id.to_string()),
            None => by_baud.push((u.baud, vec![u.id.to_string()])),
        }
    }
    let ids = |at: &str| {
        let each: Vec<String> = by_baud
            .iter()
            .map(|(baud, ids)| format!("{} {at} {baud} baud", ids.join(", ")))
            .collect();
        each.join("; ")
    };
    let (n, ms) = (unsure.len(), held_up_ms.unwrap_or_default());
    Some(crate::i18n::Text::new(
        format!(
            "{n} id(s) stayed silent only while this computer was held up {ms:.0} ms past their \
             answers' deadline, however often asked again ({}): a servo there may have been \
             missed; close other programs and scan again",
            ids("at")
        ),
        format!(
            "{n} 个ID无法确认({}):只在本机被拖慢 {ms:.0} ms(超过应答时限)时无应答,多次重新询问\
             均如此;那里可能有舵机被漏掉。请关闭其他程序后重新扫描。",
            ids("@")
        ),
    ))
}

impl ScanReport {
    /// [`unsure_said`] of this report.
    pub fn unsure_said(&self) -> Option<crate::i18n::Text> {
        unsure_said(&self.unsure, self.host_late_ms)
    }

    /// A report of nothing found yet.
    fn empty() -> Self {
        Self {
            rows: Vec::new(),
            asked_again: 0,
            late_answers: 0,
            margin_ms: 0.0,
            host_late_ms: None,
            unsure: Vec::new(),
            asked_after_hold_up: 0,
        }
    }

    /// Keeps the larger of the lateness so far and `late` (a sweep's
    /// [`SweepReply::host_late`]).
    fn held_up(&mut self, late: Option<Duration>) {
        self.held_up_ms(late.map(|l| l.as_secs_f64() * 1e3));
    }

    /// Keeps the larger of the lateness so far and `ms` (another report's).
    fn held_up_ms(&mut self, ms: Option<f64>) {
        if let Some(ms) = ms {
            self.host_late_ms = Some(self.host_late_ms.map_or(ms, |m| m.max(ms)));
        }
    }

    /// [`ScanReport::host_late_ms`] as a duration.
    pub fn host_late(&self) -> Option<Duration> {
        self.host_late_ms
            .map(|ms| Duration::from_secs_f64(ms / 1e3))
    }
}

/// How long a servo takes on the bus before it answers, at most (the vendor's: 0.2-1 ms).
pub(super) const BUS_LATENCY: Duration = Duration::from_millis(1);
/// The longest READ_DATA answer: header, command, length, id, parameter, 4 value bytes, sum.
const READ_ANSWER_BYTES: usize = 11;
/// A PING answer: header, command, length, id, sum.
const PING_ANSWER_BYTES: usize = 6;
/// Ids pinged in one sweep (progress and cancel come between sweeps).
const SWEEP_IDS: usize = 128;
/// How many times the ids to ask again are swept again, at most, before those whose answer is
/// still damaged are asked one by one.
const RESWEEPS: usize = 3;
/// How many times, at most, the ids silent while this computer was held up are swept again for
/// a sweep that runs on time ([`ScanReport::unsure`]).
const HELD_UP_RESWEEPS: usize = 3;

/// The ids that answer a ping at the port's rate, found by sweeps ([`Sweep`]): pinged at the
/// bus's pace, each answer counted for its id whenever it comes, then listened to for the grace
/// an exchange gives, for the answers still on their way; the ids a damaged frame can have come
/// from or destroyed, and ids whose answer came after its sweep, are pinged again, all at once
/// and then one by one where the answer was damaged again (a glitch is not a duplicate: an id
/// is a possible duplicate only when it answers garbled again and again). Returns each id that
/// answered with what answered, and the report's counters.
pub(super) fn find_ids(
    client: &Client,
    ids: &[u8],
    run: &mut Run<'_, (usize, u8)>,
) -> Result<(Vec<(u8, Presence)>, ScanReport), OpError> {
    let mut found = Found::sweep(client, ids, run)?;
    if found.cancelled {
        return Err(OpError::Cancelled);
    }
    // Answers still on their way after the last sweep.
    let tail = client.sweep(ping_sweep(&[]))?;
    found.take(&tail, &[]);
    found.resolve(client, run.cancel_flag())
}

/// What the ping sweeps of a scan have brought so far.
struct Found<'a> {
    /// The ids pinged.
    ids: &'a [u8],
    /// Those that answered cleanly.
    present: BTreeSet<u8>,
    /// Those to ask again: a damaged answer can have come from them (or met their ping), or
    /// theirs came late.
    again: BTreeSet<u8>,
    /// The ids pinged so far, in order.
    swept: Vec<u8>,
    report: ScanReport,
    /// The ids that were silent in a sweep during which this computer was held up: their
    /// silence is not heard on time ([`Found::vouch`]).
    held_silent: BTreeSet<u8>,
    /// Whether the sweeps stopped part way, cancelled: what they found so far is kept.
    cancelled: bool,
}

impl<'a> Found<'a> {
    /// Pings `ids` in sweeps of [`SWEEP_IDS`], with progress and cancel between them (a
    /// cancel stops the sweeps and sets [`Found::cancelled`], keeping what they found).
    fn sweep(
        client: &Client,
        ids: &'a [u8],
        run: &mut Run<'_, (usize, u8)>,
    ) -> Result<Self, OpError> {
        let mut found = Found {
            ids,
            present: BTreeSet::new(),
            again: BTreeSet::new(),
            swept: Vec::with_capacity(ids.len()),
            report: ScanReport::empty(),
            held_silent: BTreeSet::new(),
            cancelled: false,
        };
        for (k, chunk) in ids.chunks(SWEEP_IDS).enumerate() {
            if run.is_cancelled() {
                found.cancelled = true;
                break;
            }
            let reply = client.sweep(ping_sweep(chunk))?;
            found.take(&reply, chunk);
            run.report((k * SWEEP_IDS + chunk.len(), *chunk.last().unwrap_or(&0)));
        }
        Ok(found)
    }

    /// Takes what the ping sweep of `chunk` brought.
    fn take(&mut self, reply: &SweepReply, chunk: &[u8]) {
        self.report.margin_ms = reply.margin.as_secs_f64() * 1e3;
        for (i, a) in reply.answers.iter().enumerate() {
            if let Some(a) = a {
                self.present.insert(chunk[i]);
                self.report.late_answers += usize::from(a.late);
            }
        }
        for d in &reply.garbled {
            self.again.extend(d.candidates.iter().map(|&i| chunk[i]));
        }
        if reply.host_late.is_some() {
            let silent = chunk.iter().filter(|id| !self.present.contains(id));
            self.held_silent.extend(silent);
        }
        self.take_late(reply);
        self.swept.extend_from_slice(chunk);
    }

    /// What came after the pings' own sweeps, in `reply` (of another sweep): a ping answer is
    /// that servo's, however late; ask it again to be sure. A damaged frame that can be a late
    /// answer to a ping makes every id pinged without a clean answer one to ask again.
    fn take_late(&mut self, reply: &SweepReply) {
        self.report.held_up(reply.host_late);
        for id in pinged(&reply.strays) {
            if self.ids.contains(&id) {
                self.report.late_answers += 1;
                self.again.insert(id);
            }
        }
        if reply.garbled.iter().any(|d| d.maybe_earlier) {
            let silent = self.swept.iter().filter(|id| !self.present.contains(id));
            self.again.extend(silent);
        }
    }

    /// The ids that answered cleanly and need not be asked again.
    fn sure(&self) -> impl Iterator<Item = u8> + '_ {
        self.present.difference(&self.again).copied()
    }

    /// Asks again the ids to ask again: all of them at once, in sweeps at the bus's pace that
    /// listen for the answers still on their way, up to [`RESWEEPS`] times for those whose
    /// answer was damaged again, then one by one those still damaged (two servos on one id
    /// garble every answer; a glitch rarely does, and not every time). Returns each id found,
    /// with what answered, in id order. An answer that comes late still counts: when an id
    /// stayed silent, the line is listened to once more at the end.
    fn resolve(
        mut self,
        client: &Client,
        cancel: &Cancel,
    ) -> Result<(Vec<(u8, Presence)>, ScanReport), OpError> {
        let mut found: BTreeMap<u8, Presence> =
            self.sure().map(|id| (id, Presence::Present)).collect();
        self.report.asked_again += self.again.len();
        let mut ask: Vec<u8> = self.again.iter().copied().collect();
        for _ in 0..RESWEEPS {
            if ask.is_empty() {
                break;
            }
            let reply = self.sweep_again(client, cancel, &ask, &mut found)?;
            self.found_late(&reply.strays, &mut found);
            let mut damaged: BTreeSet<u8> = BTreeSet::new();
            for d in &reply.garbled {
                damaged.extend(d.candidates.iter().map(|&i| ask[i]));
                if d.maybe_earlier {
                    // Maybe a late answer to one asked before.
                    damaged.extend(self.again.iter().copied());
                }
            }
            ask = damaged
                .into_iter()
                .filter(|id| !found.contains_key(id))
                .collect();
        }
        for &id in &ask {
            if cancel.is_cancelled() {
                return Err(OpError::Cancelled);
            }
            match ask_again(client, id)? {
                Presence::Absent => {}
                p => {
                    found.insert(id, p);
                }
            }
        }
        // Silent however asked: its clean answer came in a sweep before, or comes late now.
        let silent: Vec<u8> = self
            .again
            .iter()
            .copied()
            .filter(|id| !found.contains_key(id))
            .collect();
        for &id in &silent {
            if self.present.contains(&id) {
                found.insert(id, Presence::Present);
            }
        }
        if silent.iter().any(|id| !found.contains_key(id)) {
            let tail = client.sweep(ping_sweep(&[]))?;
            self.report.held_up(tail.host_late);
            self.found_late(&tail.strays, &mut found);
        }
        self.vouch(client, cancel, &mut found)?;
        Ok((found.into_iter().collect(), self.report))
    }

    /// Pings `ask` again in one sweep that listens for the answers still on their way (the
    /// hold-up it met kept for the report): each clean answer is its servo, present, however
    /// late. Returns the sweep's reply, for what else it brought.
    fn sweep_again(
        &mut self,
        client: &Client,
        cancel: &Cancel,
        ask: &[u8],
        found: &mut BTreeMap<u8, Presence>,
    ) -> Result<SweepReply, OpError> {
        if cancel.is_cancelled() {
            return Err(OpError::Cancelled);
        }
        let mut sweep = ping_sweep(ask);
        sweep.listen = true;
        let reply = client.sweep(sweep)?;
        self.report.held_up(reply.host_late);
        for (i, a) in reply.answers.iter().enumerate() {
            if let Some(a) = a {
                found.insert(ask[i], Presence::Present);
                self.report.late_answers += usize::from(a.late);
            }
        }
        Ok(reply)
    }

    /// Pings again the ids that were silent only while this computer was held up (their answer
    /// may have come while it was not there to read it), in sweeps that listen for late
    /// answers, until one runs on time or [`HELD_UP_RESWEEPS`] have not: those still silent
    /// then are [`ScanReport::unsure`] (their baud rate is the caller's to set). An id whose
    /// answer came damaged is asked on its own ([`ask_again`]).
    fn vouch(
        &mut self,
        client: &Client,
        cancel: &Cancel,
        found: &mut BTreeMap<u8, Presence>,
    ) -> Result<(), OpError> {
        let mut ask: Vec<u8> = self
            .held_silent
            .iter()
            .copied()
            .filter(|id| !found.contains_key(id))
            .collect();
        self.report.asked_after_hold_up += ask.len();
        let mut damaged: BTreeSet<u8> = BTreeSet::new();
        for _ in 0..HELD_UP_RESWEEPS {
            if ask.is_empty() {
                break;
            }
            let reply = self.sweep_again(client, cancel, &ask, found)?;
            for id in pinged(&reply.strays) {
                if ask.contains(&id) {
                    found.insert(id, Presence::Present);
                }
            }
            damaged.extend(
                reply
                    .garbled
                    .iter()
                    .flat_map(|d| d.candidates.iter().map(|&i| ask[i])),
            );
            ask.retain(|id| !found.contains_key(id) && !damaged.contains(id));
            if reply.host_late.is_none() {
                // Silent on time: nothing there.
                ask.clear();
            }
        }
        for id in damaged {
            if found.contains_key(&id) {
                continue;
            }
            match ask_again(client, id)? {
                Presence::Absent => {}
                p => {
                    found.insert(id, p);
                }
            }
        }
        self.report.unsure = ask.into_iter().map(|id| Unsure { baud: 0, id }).collect();
        Ok(())
    }

    /// Counts the ping answers among `strays` that answer ids asked again and not found yet:
    /// late, but clean, so those servos are there.
    fn found_late(&mut self, strays: &[Packet], found: &mut BTreeMap<u8, Presence>) {
        for id in pinged(strays) {
            if self.again.contains(&id) && !found.contains_key(&id) {
                self.report.late_answers += 1;
                found.insert(id, Presence::Present);
            }
        }
    }
}

/// The ids whose ping answers are among `frames`.
pub(super) fn pinged(frames: &[Packet]) -> impl Iterator<Item = u8> + '_ {
    frames
        .iter()
        .filter(|p| p.command == cmd::PING && p.direction == Direction::DeviceToHost)
        .filter_map(|p| p.payload.first().copied())
}

/// Pings `id` on its own, once at a time, up to three times: present at the first clean answer,
/// absent at the first clean silence, a possible duplicate when it answers garbled twice (two
/// servos on one id garble every answer; stray junk on the line rarely twice).
pub(super) fn ask_again(client: &Client, id: u8) -> Result<Presence, OpError> {
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

/// A sweep of pings to `ids` at the bus's pace (each servo's answer names its id); a sweep of
/// none listens for the answers still on their way ([`Sweep::listen`]).
pub fn ping_sweep(ids: &[u8]) -> Sweep {
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
        listen: ids.is_empty(),
    }
}

/// Reads each present servo's details (the parameters with the roles of [`SCAN_ROLES`] the
/// profile gives: type, firmware, serial number, voltage, temperature, status) in one sweep; a
/// value that did not come is read again on its own. With `listen`, the sweep also listens for
/// the grace an exchange gives, for the pings' answers still on their way (and goes out empty
/// when there is nothing to read); returns the sweep's reply, if it went out.
fn details(
    dev: Device<'_>,
    rows: &mut [ScanRow],
    listen: bool,
) -> Result<Option<SweepReply>, OpError> {
    let Device { client, profile } = dev;
    let params: Vec<(&ParamRole, &crate::profile::Param)> = SCAN_ROLES
        .iter()
        .filter_map(|role| Some((role, profile.param_with_role(role)?)))
        .collect();
    let mut asked: Vec<(usize, &ParamRole, &crate::profile::Param)> = Vec::new();
    let mut requests = Vec::new();
    for (r, row) in rows.iter().enumerate() {
        if row.presence != Presence::Present {
            continue;
        }
        for &(role, p) in &params {
            requests.push(read_request(profile, row.id, p)?);
            asked.push((r, role, p));
        }
    }
    if requests.is_empty() && !listen {
        return Ok(None);
    }
    let reply = client.sweep(Sweep {
        requests,
        answer_bytes: READ_ANSWER_BYTES,
        device_latency: BUS_LATENCY,
        listen,
    })?;
    for ((r, role, p), answer) in asked.into_iter().zip(reply.answers.iter().cloned()) {
        let row = &mut rows[r];
        let value = match answer {
            Some(a) => read_value(profile, row.id, p, &a.packet.payload).ok(),
            None => read_param(dev, row.id, p).ok(),
        };
        if let Some(column) = row.column(role) {
            *column = value;
        }
    }
    Ok(Some(reply))
}

/// A row for servo `id` at `baud`, details not read yet.
fn row(id: u8, baud: u32, presence: Presence) -> ScanRow {
    ScanRow {
        id,
        baud,
        presence,
        servo_type: None,
        firmware: None,
        serial: None,
        voltage_mv: None,
        temperature: None,
        status: None,
    }
}

/// Finds the servos at the port's rate, `baud` ([`find_ids`]), with each one's details: the
/// servos that answered cleanly have theirs read while the answers still on their way come in
/// (that sweep is the scan's last listen), those asked again after it. `found` sees each row
/// once its details are read; a cancel during the sweeps gives it the servos that answered
/// cleanly so far (details not read) before [`OpError::Cancelled`].
fn scan_at(
    dev: Device<'_>,
    ids: &[u8],
    baud: u32,
    run: &mut Run<'_, (usize, u8)>,
    found_row: &mut dyn FnMut(&ScanRow),
) -> Result<ScanReport, OpError> {
    let client = dev.client;
    let mut found = Found::sweep(client, ids, run)?;
    let mut rows: Vec<ScanRow> = found
        .sure()
        .map(|id| row(id, baud, Presence::Present))
        .collect();
    if found.cancelled {
        rows.iter().for_each(&mut *found_row);
        return Err(OpError::Cancelled);
    }
    if let Some(reply) = details(dev, &mut rows, true)? {
        found.take_late(&reply);
    }
    rows.iter().for_each(&mut *found_row);
    let (answered, mut report) = found.resolve(client, run.cancel_flag())?;
    let mut more: Vec<ScanRow> = answered
        .into_iter()
        .filter(|(id, _)| !rows.iter().any(|r| r.id == *id))
        .map(|(id, presence)| row(id, baud, presence))
        .collect();
    details(dev, &mut more, false)?;
    more.iter().for_each(&mut *found_row);
    rows.extend(more);
    rows.sort_by_key(|r| r.id);
    report.rows = rows;
    report.unsure.iter_mut().for_each(|u| u.baud = baud);
    Ok(report)
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
/// details, then returns the port to the plan's home rate. `found` sees each row as it is found
/// (at once, not when its baud rate is done), so a run cancelled part way ([`OpError::Cancelled`])
/// has already handed out every servo found before the cancel.
pub fn scan(
    dev: Device<'_>,
    plan: &ScanPlan,
    run: &mut Run<'_>,
    found: &mut dyn FnMut(&ScanRow),
) -> Result<ScanReport, OpError> {
    let client = dev.client;
    let (bauds, home_baud) = (&plan.bauds, plan.home_baud);
    let ids: Vec<u8> = plan
        .ids
        .clone()
        .filter(|&i| i != crate::protocol::servo::BROADCAST_ID)
        .collect();
    let total = (ids.len() * bauds.len()) as u64;
    let mut report = ScanReport::empty();
    let result = (|| {
        for (b, &baud) in bauds.iter().enumerate() {
            switch(client, baud)?;
            let before = (b * ids.len()) as u64;
            let cancel = run.cancel_flag();
            let mut at = Run::new(cancel, |(done, id): (usize, u8)| {
                run.report(Progress {
                    done: before + done as u64,
                    total,
                    message: crate::i18n::Text::new(
                        format!("id {id} at {baud} baud"),
                        format!("ID {id},波特率 {baud}"),
                    ),
                })
            });
            let at_baud = scan_at(dev, &ids, baud, &mut at, &mut *found)?;
            report.asked_again += at_baud.asked_again;
            report.late_answers += at_baud.late_answers;
            report.margin_ms = at_baud.margin_ms;
            report.held_up_ms(at_baud.host_late_ms);
            report.rows.extend(at_baud.rows);
            report.unsure.extend(at_baud.unsure);
            report.asked_after_hold_up += at_baud.asked_after_hold_up;
        }
        Ok(())
    })();
    let _ = client.set_baud(home_baud);
    report
        .rows
        .sort_by_key(|r| (bauds.iter().position(|&b| b == r.baud), r.id));
    result.map(|()| report)
}

#[cfg(test)]
mod tests {
    use super::SCAN_ROLES;
    use crate::profile::Registry;

    #[test]
    fn a_scan_reads_type_firmware_serial_voltage_temperature_and_status_by_role() {
        let servo = Registry::builtin()
            .and_then(|r| r.get("servo"))
            .expect("the built-in servo profile");
        let scanned: Vec<Option<u8>> = SCAN_ROLES
            .iter()
            .map(|r| servo.param_with_role(r).map(|p| p.id))
            .collect();
        assert_eq!(
            scanned,
            [Some(6), Some(7), Some(8), Some(1), Some(4), Some(5)]
        );
    }
}
