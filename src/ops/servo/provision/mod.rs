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
//! step that failed and why; a port that went away during a step is [`Outcome::LinkLost`], no
//! verdict on the servo (`link lost during <step>`), never that step failing.

mod log;
mod plan;
mod steps;

pub use log::{append_csv, check_log, log_columns, log_row};
pub use plan::{IdSequence, Issue, Plan, Resolved};

use crate::link::{Client, ExchangeError};
use crate::ops::servo::{self, Presence, switch};
use crate::ops::{Device, OpError, Run};
use crate::profile::{Param, Profile, Value};
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

    /// Every step, in the order a servo goes through them (the plan's check first).
    pub const ALL: [&str; 8] = [
        PLAN, DETECT, SERIAL, ASSIGN_ID, SET_BAUD, APPLY, VERIFY, RECORD,
    ];

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
    /// The port went away (unplugged, the adapter reset) during a step: no verdict on the
    /// servo, `link lost during <step>`; the steps after it were not done. Serialised with
    /// `"status": "link_lost"`.
    LinkLost {
        /// The step under way, one of [`step`].
        step: String,
        /// What the link said (`port disconnected: ...`).
        reason: String,
    },
}

impl Outcome {
    /// Whether it passed.
    pub fn is_pass(&self) -> bool {
        *self == Outcome::Pass
    }

    /// Whether a step failed (not [`Outcome::LinkLost`], which says nothing of the servo).
    pub fn is_fail(&self) -> bool {
        matches!(self, Outcome::Fail { .. })
    }

    /// The step the link was lost in, when it was: `Some((step, what the link said))`.
    pub fn link_lost(&self) -> Option<(&str, &str)> {
        match self {
            Outcome::LinkLost { step, reason } => Some((step, reason)),
            _ => None,
        }
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
    /// Pass, the step that failed and why, or the step the link was lost in.
    pub result: Outcome,
    /// Values the servo does not hold as written: `ident: wrote X, servo holds Y`.
    pub mismatches: Vec<String>,
    /// The plan's recorded parameters, in display units (`None` when not read).
    pub recorded: Vec<(String, Option<String>)>,
    /// Each step begun, with when (ms since 1970 UTC), in order: the records' step times.
    #[serde(skip)]
    pub timeline: Vec<(String, i64)>,
    /// Each parameter written, in the step that wrote it, with its value before and after.
    #[serde(skip)]
    pub writes: Vec<(String, crate::ops::records::ParamWrite)>,
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

/// `failure` into the record's result: [`Outcome::LinkLost`] when the port went, else
/// [`Outcome::Fail`].
fn ended(record: &mut Record, failure: steps::Failure) {
    let steps::Failure { step, why, lost } = failure;
    match lost {
        Some(link) => {
            record.result = Outcome::LinkLost {
                step: step.to_string(),
                reason: link,
            }
        }
        None => fail(record, step, why),
    }
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
        timeline: Vec::new(),
        writes: Vec::new(),
    };
    match plan.resolve(dev.profile) {
        Ok(resolved) => steps(dev, plan, &resolved, state, run, &mut record),
        Err(issue) => fail(&mut record, step::PLAN, issue.message),
    }
    record.time = chrono::Local::now().to_rfc3339_opts(chrono::SecondsFormat::Secs, false);
    record
}

/// The steps ([`steps::Provisioning`]); on failure, sets the record's result.
fn steps(
    dev: Device<'_>,
    plan: &Plan,
    resolved: &Resolved<'_>,
    state: &mut ProvisionState,
    run: &mut Run<'_>,
    record: &mut Record,
) {
    let cancel = run.cancel_flag();
    let mut p = steps::Provisioning {
        dev,
        resolved,
        target: plan.target_baud,
        candidates: plan.ids.candidates(),
        cancel,
        run,
        done: 0,
        total: 6 + resolved.writes.len() as u64,
        timeline: Vec::new(),
    };
    let outcome = p.steps(state, record);
    record.timeline = std::mem::take(&mut p.timeline);
    if let Err(failure) = outcome {
        ended(record, failure);
    }
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
