//! Production provisioning of bus servos: one factory-fresh servo at a time is found (at any baud
//! rate), given the next free id, switched to the plan's baud rate, given the plan's parameters,
//! verified, and logged.
//!
//! A plan is a RON file, checked against the servo profile before anything is written:
//!
//! ```ron
//! (
//!     target_baud: 1000000,
//!     ids: Start(1),            // or List([3, 4, 7])
//!     params: [
//!         ("stall_protect_mode", "limit_power"),
//!         ("over_temprature", "70"),
//!     ],
//!     record: ["firmware_version", "servo_type", "voltage"],
//! )
//! ```
//!
//! [`provision_next`] never reports half-done work as done: its [`Record`] is
//! [`Outcome::Pass`] only when every step was verified on the servo, and otherwise names the
//! step that failed and why.

mod log;
mod plan;

pub use log::{append_csv, check_log, log_columns, log_row};
pub use plan::{IdSequence, Issue, Plan, Resolved};

use crate::link::{Client, ExchangeError};
use crate::ops::servo::{self, Presence, switch};
use crate::ops::{Device, Run};
use crate::ops::{OpError, Progress};
use crate::profile::{Input, Param, Profile, Value};
use serde::Serialize;

/// The names of the steps, as records and progress messages give them.
pub mod step {
    /// Find the one fresh servo (at the profile's factory id) at any baud rate.
    pub const DETECT: &str = "detect";
    /// Read its serial number.
    pub const SERIAL: &str = "read serial";
    /// Give it the next free id.
    pub const ASSIGN_ID: &str = "assign id";
    /// Switch it to the plan's baud rate.
    pub const SET_BAUD: &str = "set baud";
    /// Write the plan's parameters, each read back.
    pub const APPLY: &str = "apply params";
    /// Read everything back at the new id and rate.
    pub const VERIFY: &str = "verify";
    /// Read the parameters the plan records.
    pub const RECORD: &str = "record";
    /// The plan does not fit the profile.
    pub const PLAN: &str = "plan";

    /// A step's name in both languages, for the window's progress line.
    pub fn said(step: &str) -> crate::i18n::Text {
        let zh = match step {
            DETECT => "检测新舵机",
            SERIAL => "读取序列号",
            ASSIGN_ID => "分配 ID",
            SET_BAUD => "设置波特率",
            APPLY => "写入参数",
            VERIFY => "校验",
            RECORD => "记录",
            PLAN => "计划",
            other => other,
        };
        crate::i18n::Text::new(step, zh)
    }
}

/// What provisioning remembers between servos.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ProvisionState {
    /// The index, in [`IdSequence::candidates`], of the next id to try.
    pub next: usize,
    /// The ids given out so far (in this session).
    pub assigned: Vec<u8>,
}

impl ProvisionState {
    /// A session that has given out no id yet.
    pub fn new() -> Self {
        Self::default()
    }
}

/// How provisioning one servo ended.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum Outcome {
    /// Every step was done and verified.
    Pass,
    /// A step failed; the steps after it were not done.
    Fail {
        /// The step, one of [`step`].
        step: String,
        /// Why.
        reason: String,
    },
}

impl Outcome {
    /// Whether it passed.
    pub fn is_pass(&self) -> bool {
        *self == Outcome::Pass
    }
}

/// What happened to one servo: one line of the log.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Record {
    /// When provisioning ended (RFC 3339).
    pub time: String,
    /// The servo's serial number, once read.
    pub serial: Option<u32>,
    /// Its id, once assigned and verified.
    pub id: Option<u8>,
    /// The baud rate it was last verified at (`None` when a baud change left it unknown).
    pub baud: Option<u32>,
    /// Pass, or the step that failed and why.
    pub result: Outcome,
    /// Values the servo does not hold as written: `ident: wrote X, servo holds Y`.
    pub mismatches: Vec<String>,
    /// The plan's recorded parameters, in display units (`None` when not read).
    pub recorded: Vec<(String, Option<String>)>,
}

/// Why a step failed: its reason, with the servo's id and baud rate when it went silent.
fn reason(e: &OpError, id: u8, baud: u32) -> String {
    match e {
        OpError::Exchange(ExchangeError::Timeout { .. }) => {
            format!("servo {id} did not answer at {baud} baud ({e})")
        }
        OpError::Exchange(ExchangeError::Garbled { .. }) => {
            format!("garbled answer from servo {id} at {baud} baud ({e})")
        }
        _ => e.to_string(),
    }
}

fn fail(record: &mut Record, step: &str, reason: String) {
    record.result = Outcome::Fail {
        step: step.to_string(),
        reason,
    };
}

/// Finds the fresh servos (at the factory id, [`servo::factory_location`]): searches `bauds`
/// for that id (the rates that a ping each hears first, then the others; see
/// `ops/servo/search.rs`) and returns each rate where something answered, and how, in the order
/// of `bauds`. Once the servo has answered, its answer latency is measured: the silent rates
/// after it cost the link's grace for that latency, not for an unknown connection.
pub fn find_fresh(dev: Device<'_>, bauds: &[u32]) -> Result<Vec<(u32, Presence)>, OpError> {
    let Device { client, profile } = dev;
    let fresh = servo::factory_location(profile).id;
    servo::search::search(client, fresh, bauds, false)
}

/// The plan's target rate first, then the profile's other servo baud rates.
pub fn search_order(profile: &Profile, target: u32) -> Vec<u32> {
    std::iter::once(target)
        .chain(profile.servo_bauds().into_iter().filter(|&b| b != target))
        .collect()
}

/// Provisions the one fresh servo on the bus: detect (the factory id, at any baud rate, exactly
/// one),
/// read its serial number, give it the next free id, switch it to the plan's rate, write the
/// plan's parameters, verify everything at the new id and rate, and read the recorded
/// parameters. Stops at the first step that fails; the record names it. `state` carries the ids
/// given out from one servo to the next.
pub fn provision_next(
    dev: Device<'_>,
    plan: &Plan,
    state: &mut ProvisionState,
    run: &mut Run<'_>,
) -> Record {
    let mut record = Record {
        time: String::new(),
        serial: None,
        id: None,
        baud: None,
        result: Outcome::Pass,
        mismatches: Vec::new(),
        recorded: plan.record.iter().map(|r| (r.clone(), None)).collect(),
    };
    match plan.resolve(dev.profile) {
        Ok(resolved) => steps(dev, plan, &resolved, state, run, &mut record),
        Err(issue) => fail(&mut record, step::PLAN, issue.message),
    }
    record.time = chrono::Local::now().to_rfc3339_opts(chrono::SecondsFormat::Secs, false);
    record
}

/// The steps; on failure, sets the record's result and returns.
fn steps(
    dev: Device<'_>,
    plan: &Plan,
    resolved: &Resolved<'_>,
    state: &mut ProvisionState,
    run: &mut Run<'_>,
    record: &mut Record,
) {
    let Device { client, profile } = dev;
    let cancel = run.cancel_flag();
    let total = 6 + resolved.writes.len() as u64;
    let mut done = 0u64;
    let mut at = |step: &str, detail: String, done: &mut u64| {
        run.report(Progress {
            done: *done,
            total,
            message: {
                let step = step::said(step);
                if detail.is_empty() {
                    step
                } else {
                    step.then(": ", &crate::i18n::Text::same(detail))
                }
            },
        });
        *done += 1;
    };
    macro_rules! check_cancel {
        ($step:expr) => {
            if cancel.is_cancelled() {
                return fail(record, $step, "cancelled by the operator".into());
            }
        };
    }
    let target = plan.target_baud;

    // Detect: exactly one fresh servo, at one baud rate.
    at(step::DETECT, String::new(), &mut done);
    check_cancel!(step::DETECT);
    let fresh = servo::factory_location(profile).id;
    let found = match find_fresh(dev, &search_order(profile, target)) {
        Ok(f) => f,
        Err(e) => return fail(record, step::DETECT, e.to_string()),
    };
    let baud = match found.as_slice() {
        [] => {
            return fail(
                record,
                step::DETECT,
                format!("no fresh servo (id {fresh}) answers at any baud rate"),
            );
        }
        [(b, Presence::Present)] => *b,
        [(b, Presence::PossibleDuplicate(e))] => {
            return fail(
                record,
                step::DETECT,
                format!(
                    "more than one servo answers at id {fresh} at {b} baud (garbled answers: {e}); leave one fresh servo on the bus"
                ),
            );
        }
        many => {
            let rates: Vec<String> = many.iter().map(|(b, _)| b.to_string()).collect();
            return fail(
                record,
                step::DETECT,
                format!(
                    "more than one servo: fresh servos (id {fresh}) answer at {} baud; leave one on the bus",
                    rates.join(" and ")
                ),
            );
        }
    };
    if let Err(e) = switch(client, baud) {
        return fail(record, step::DETECT, e.to_string());
    }
    record.baud = Some(baud);

    // Its serial number, so that even a failure names the servo.
    at(step::SERIAL, String::new(), &mut done);
    check_cancel!(step::SERIAL);
    let serial = match servo::serial_param(profile).and_then(|p| read(dev, fresh, p.id)) {
        Ok(v) => v,
        Err(e) => return fail(record, step::SERIAL, reason(&e, fresh, baud)),
    };
    let Ok(serial) = u32::try_from(serial) else {
        return fail(
            record,
            step::SERIAL,
            format!("the servo reports serial number {serial}, which does not fit 32 bits"),
        );
    };
    record.serial = Some(serial);

    // The next free id: not given out before, and silent at every rate (a servo at another
    // rate is still on the bus, and would share the id once moved).
    at(step::ASSIGN_ID, String::new(), &mut done);
    check_cancel!(step::ASSIGN_ID);
    let candidates = plan.ids.candidates();
    let mut chosen = None;
    for (i, &id) in candidates.iter().enumerate().skip(state.next) {
        if cancel.is_cancelled() {
            return fail(record, step::ASSIGN_ID, "cancelled by the operator".into());
        }
        if state.assigned.contains(&id) {
            state.next = i + 1;
            continue;
        }
        match id_is_free(client, id, &search_order(profile, target)) {
            Ok(true) => {
                chosen = Some((i, id));
                break;
            }
            // In use: never offered again.
            Ok(false) => state.next = i + 1,
            Err(e) => return fail(record, step::ASSIGN_ID, e.to_string()),
        }
    }
    if let Err(e) = switch(client, baud) {
        return fail(record, step::ASSIGN_ID, e.to_string());
    }
    let Some((index, id)) = chosen else {
        return fail(
            record,
            step::ASSIGN_ID,
            "no free id left in the plan's ids".into(),
        );
    };
    if let Err(e) = servo::set_id(dev, fresh, id, cancel) {
        return fail(record, step::ASSIGN_ID, reason(&e, fresh, baud));
    }
    state.next = index + 1;
    state.assigned.push(id);
    record.id = Some(id);

    // The target rate.
    at(step::SET_BAUD, format!("{baud} → {target}"), &mut done);
    check_cancel!(step::SET_BAUD);
    if baud != target {
        match servo::ping(client, id, 3) {
            Ok(Presence::Present) => {}
            Ok(other) => {
                return fail(
                    record,
                    step::SET_BAUD,
                    format!(
                        "servo {id} did not answer at {baud} baud before the change ({other:?})"
                    ),
                );
            }
            Err(e) => return fail(record, step::SET_BAUD, reason(&e, id, baud)),
        }
        record.baud = None;
        match servo::set_baud(dev, id, resolved.option) {
            Ok(now) => record.baud = Some(now),
            Err(e) => return fail(record, step::SET_BAUD, reason(&e, id, target)),
        }
    }

    // The plan's parameters, each read back.
    let mut apply_mismatch = false;
    for &(param, raw) in &resolved.writes {
        let ident = &param.field.ident;
        at(step::APPLY, ident.clone(), &mut done);
        check_cancel!(step::APPLY);
        match servo::write_param(dev, id, param, Input::Raw(Value::Int(raw))) {
            Ok(check) if check.ok() => {}
            Ok(check) => {
                apply_mismatch = true;
                record
                    .mismatches
                    .push(mismatch(param, &check.written, &check.read));
            }
            Err(e) => {
                return fail(
                    record,
                    step::APPLY,
                    format!("{ident}: {}", reason(&e, id, target)),
                );
            }
        }
    }

    // Everything again, at the new id and rate.
    at(step::VERIFY, String::new(), &mut done);
    check_cancel!(step::VERIFY);
    match servo::ping(client, id, 3) {
        Ok(Presence::Present) => {}
        Ok(other) => {
            return fail(
                record,
                step::VERIFY,
                format!("servo {id} did not answer cleanly at {target} baud ({other:?})"),
            );
        }
        Err(e) => return fail(record, step::VERIFY, reason(&e, id, target)),
    }
    let roles = servo::serial_param(profile).and_then(|s| {
        Ok((
            s.id,
            servo::id_param(profile)?.id,
            servo::baud_param(profile)?.0.id,
        ))
    });
    let (serial_pid, id_pid, baud_pid) = match roles {
        Ok(ids) => ids,
        Err(e) => return fail(record, step::VERIFY, e.to_string()),
    };
    let mut expected: Vec<(u8, i64)> = vec![
        (serial_pid, i64::from(serial)),
        (id_pid, i64::from(id)),
        (baud_pid, i64::from(resolved.option)),
    ];
    expected.extend(resolved.writes.iter().map(|(p, raw)| (p.id, *raw)));
    for (pid, want) in expected {
        let Some(param) = profile.param(pid) else {
            return fail(
                record,
                step::VERIFY,
                format!("the profile has no parameter {pid}"),
            );
        };
        let got = match read(dev, id, pid) {
            Ok(v) => v,
            Err(e) => {
                return fail(
                    record,
                    step::VERIFY,
                    format!("{}: {}", param.field.ident, reason(&e, id, target)),
                );
            }
        };
        if got != want {
            let line = mismatch(param, &Value::Int(want), &Value::Int(got));
            if !record.mismatches.contains(&line) {
                record.mismatches.push(line);
            }
        }
    }
    if !record.mismatches.is_empty() {
        let step = if apply_mismatch {
            step::APPLY
        } else {
            step::VERIFY
        };
        let n = record.mismatches.len();
        return fail(
            record,
            step,
            format!("{n} value(s) do not read back as written"),
        );
    }

    // What the plan records.
    at(step::RECORD, String::new(), &mut done);
    check_cancel!(step::RECORD);
    for (i, param) in resolved.record.iter().enumerate() {
        match servo::read_param(dev, id, param) {
            Ok(v) => {
                if let Some(slot) = record.recorded.get_mut(i) {
                    slot.1 = Some(param.field.format(&Value::Int(v)));
                }
            }
            Err(e) => {
                return fail(
                    record,
                    step::RECORD,
                    format!("{}: {}", param.field.ident, reason(&e, id, target)),
                );
            }
        }
    }
    run.report(Progress {
        done: total,
        total,
        message: crate::i18n::Text::new("done", "完成"),
    });
}

fn read(dev: Device<'_>, id: u8, pid: u8) -> Result<i64, OpError> {
    let profile = dev.profile;
    let param = profile
        .param(pid)
        .ok_or_else(|| OpError::unknown_param(profile, pid))?;
    servo::read_param(dev, id, param)
}

/// Whether `id` is silent at every one of `bauds`.
fn id_is_free(client: &Client, id: u8, bauds: &[u32]) -> Result<bool, OpError> {
    for &b in bauds {
        switch(client, b)?;
        if servo::ping(client, id, 2)? != Presence::Absent {
            return Ok(false);
        }
    }
    Ok(true)
}

fn mismatch(param: &Param, written: &Value, read: &Value) -> String {
    let f = &param.field;
    format!(
        "{}: wrote {}{}, servo holds {}{}",
        f.ident,
        f.format(written),
        f.unit_suffix(),
        f.format(read),
        f.unit_suffix()
    )
}
