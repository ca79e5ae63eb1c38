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

use super::msp::OpError;
use super::servo::{self, BAUDS, PARAM_BAUD, PARAM_ID, Presence};
use super::{Cancel, Progress};
use crate::link::{Client, ExchangeError};
use crate::profile::locate::{Step, locate};
use crate::profile::value::Typed as DisplayText;
use crate::profile::{Access, Input, Param, Profile, Value};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::io::{BufRead, Write};
use std::path::Path;

/// The `data_id` of the serial number.
pub const PARAM_SERIAL: u8 = 8;

/// The names of the steps, as records and progress messages give them.
pub mod step {
    /// Find the one fresh servo (id 0) at any baud rate.
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
}

/// The ids a plan gives out.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub enum IdSequence {
    /// The next free id from this one upward (to 254).
    Start(u8),
    /// These ids, in order, skipping those in use.
    List(Vec<u8>),
}

impl IdSequence {
    /// Every id the sequence may give, in order.
    pub fn candidates(&self) -> Vec<u8> {
        match self {
            IdSequence::Start(first) => (*first..crate::protocol::servo::BROADCAST_ID).collect(),
            IdSequence::List(ids) => ids.clone(),
        }
    }
}

/// A provisioning plan, as written in its RON file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Plan {
    /// The baud rate every servo leaves with: one of [`BAUDS`].
    pub target_baud: u32,
    /// The ids to give out.
    pub ids: IdSequence,
    /// (parameter ident, display value) to write, in order, e.g. `("over_temprature", "70")`.
    pub params: Vec<(String, String)>,
    /// Further parameters to read and record in the log, e.g. `firmware_version`.
    pub record: Vec<String>,
}

/// A plan that does not parse or does not fit the profile. Nothing has been written.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlanError {
    /// The file (or the name given to [`Plan::parse`]).
    pub file: String,
    /// 1-based line, 0 when unknown.
    pub line: usize,
    /// 1-based column, 0 when unknown.
    pub col: usize,
    /// What is wrong.
    pub message: String,
}

/// A RON file's name (for errors) and text, or why it cannot be read.
pub(crate) fn read_source(path: &Path) -> Result<(String, String), PlanError> {
    let file = path.display().to_string();
    match std::fs::read_to_string(path) {
        Ok(text) => Ok((file, text)),
        Err(e) => Err(PlanError {
            file,
            line: 0,
            col: 0,
            message: format!("cannot read: {e}"),
        }),
    }
}

impl fmt::Display for PlanError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line == 0 {
            write!(f, "{}: {}", self.file, self.message)
        } else {
            write!(
                f,
                "{}:{}:{}: {}",
                self.file, self.line, self.col, self.message
            )
        }
    }
}

impl std::error::Error for PlanError {}

/// A problem with a plan and where it is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Issue {
    /// The path to the offending value.
    pub path: Vec<Step>,
    /// What is wrong.
    pub message: String,
}

/// A plan resolved against a profile: what [`provision_next`] writes and reads.
#[derive(Debug, Clone)]
pub struct Resolved<'p> {
    /// The baud option (1-8) of the target rate.
    pub option: u8,
    /// The parameters to write, with their raw values.
    pub writes: Vec<(&'p Param, i64)>,
    /// The parameters to record.
    pub record: Vec<&'p Param>,
}

/// The plan file's shape.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Doc {
    target_baud: u32,
    ids: IdSequence,
    #[serde(default)]
    params: Vec<(String, DisplayText)>,
    #[serde(default)]
    record: Vec<String>,
}

impl Plan {
    /// Reads a plan file and checks it against the servo `profile`.
    pub fn load(path: &Path, profile: &Profile) -> Result<Plan, PlanError> {
        let (file, text) = read_source(path)?;
        Self::parse(&file, &text, profile)
    }

    /// Parses plan text (`name` names it in errors) and checks it against `profile`.
    pub fn parse(name: &str, text: &str, profile: &Profile) -> Result<Plan, PlanError> {
        let doc: Doc = ron::Options::default()
            .from_str(text)
            .map_err(|e| PlanError {
                file: name.to_string(),
                line: e.span.start.line,
                col: e.span.start.col,
                message: e.code.to_string(),
            })?;
        let plan = Plan {
            target_baud: doc.target_baud,
            ids: doc.ids,
            params: doc.params.into_iter().map(|(k, v)| (k, v.0)).collect(),
            record: doc.record,
        };
        if let Err(issue) = plan.resolve(profile) {
            let (line, col) = locate(text, &issue.path);
            return Err(PlanError {
                file: name.to_string(),
                line,
                col,
                message: issue.message,
            });
        }
        Ok(plan)
    }

    /// Checks the plan against the servo `profile`: the baud rate, the ids, every parameter
    /// (known, writable, not the id or baud rate, its value in range) and every recorded one.
    pub fn resolve<'p>(&self, profile: &'p Profile) -> Result<Resolved<'p>, Issue> {
        let issue = |path: Vec<Step>, message: String| Issue { path, message };
        let Some(option) = servo::option_of_baud(self.target_baud) else {
            return Err(issue(
                vec![Step::Key("target_baud")],
                format!(
                    "{} is not a servo baud rate; allowed: {}",
                    self.target_baud,
                    BAUDS.map(|b| b.to_string()).join(", ")
                ),
            ));
        };
        if let Some(baud) = profile.param(PARAM_BAUD) {
            baud.field
                .check(&Value::Int(option.into()))
                .map_err(|e| issue(vec![Step::Key("target_baud")], e.to_string()))?;
        }
        let ids_at = vec![Step::Key("ids")];
        match &self.ids {
            IdSequence::Start(0) => {
                return Err(issue(
                    ids_at,
                    "ids cannot start at 0: 0 is the factory id of a fresh servo".into(),
                ));
            }
            IdSequence::Start(255) => {
                return Err(issue(
                    ids_at,
                    "id 255 is the broadcast address and cannot be assigned".into(),
                ));
            }
            IdSequence::Start(_) => {}
            IdSequence::List(ids) => {
                if ids.is_empty() {
                    return Err(issue(ids_at, "the id list is empty".into()));
                }
                for (i, &id) in ids.iter().enumerate() {
                    if id == 0 || id == 255 {
                        return Err(issue(
                            ids_at,
                            format!("id {id} cannot be assigned: give ids 1 to 254"),
                        ));
                    }
                    if ids[..i].contains(&id) {
                        return Err(issue(ids_at, format!("id {id} is listed twice")));
                    }
                }
            }
        }
        let known = || {
            profile
                .params
                .iter()
                .map(|p| p.field.ident.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        };
        let mut writes: Vec<(&Param, i64)> = Vec::new();
        for (i, (name, value)) in self.params.iter().enumerate() {
            let at = vec![Step::Key("params"), Step::Index(i)];
            let Some(param) = profile.find_param(name) else {
                return Err(issue(
                    at,
                    format!("no servo parameter '{name}'; known: {}", known()),
                ));
            };
            let ident = &param.field.ident;
            if param.access == Access::ReadOnly {
                return Err(issue(
                    at,
                    format!("{ident} is read-only and cannot be written"),
                ));
            }
            if param.id == PARAM_ID || param.id == PARAM_BAUD {
                return Err(issue(
                    at,
                    format!("{ident} is set by the plan's `ids` and `target_baud`, not by params"),
                ));
            }
            if writes.iter().any(|(p, _)| p.id == param.id) {
                return Err(issue(at, format!("{ident} is given twice")));
            }
            let raw = match param.field.parse(value) {
                Ok(Value::Int(raw)) => raw,
                Ok(_) => {
                    return Err(issue(at, format!("{ident}: '{value}' is not a number")));
                }
                Err(e) => return Err(issue(at, e.to_string())),
            };
            writes.push((param, raw));
            // The profile's relations between the plan's own values (voltage low ≤ high).
            let values: Vec<(u8, i64)> = writes.iter().map(|(p, v)| (p.id, *v)).collect();
            if let Err(e) = profile.check_param_relations(&values) {
                return Err(issue(at, e.to_string()));
            }
        }
        let mut record: Vec<&Param> = Vec::new();
        for (i, name) in self.record.iter().enumerate() {
            let at = vec![Step::Key("record"), Step::Index(i)];
            let Some(param) = profile.find_param(name) else {
                return Err(issue(
                    at,
                    format!("no servo parameter '{name}' to record; known: {}", known()),
                ));
            };
            if record.iter().any(|p| p.id == param.id) {
                return Err(issue(
                    at,
                    format!("{} is recorded twice", param.field.ident),
                ));
            }
            record.push(param);
        }
        Ok(Resolved {
            option,
            writes,
            record,
        })
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

fn switch(client: &Client, baud: u32) -> Result<(), String> {
    client
        .set_baud(baud)
        .map_err(|e| format!("cannot switch the port to {baud} baud: {e}"))
}

fn fail(record: &mut Record, step: &str, reason: String) {
    record.result = Outcome::Fail {
        step: step.to_string(),
        reason,
    };
}

/// Finds the fresh servos (id 0): pings id 0 at `bauds` in order and returns each rate where
/// something answered, and how.
pub fn find_fresh(client: &Client, bauds: &[u32]) -> Result<Vec<(u32, Presence)>, String> {
    let mut out = Vec::new();
    for &b in bauds {
        switch(client, b)?;
        let presence = servo::ping(client, 0, 2).map_err(|e| e.to_string())?;
        if presence != Presence::Absent {
            out.push((b, presence));
        }
    }
    Ok(out)
}

/// The plan's target rate first, then the others.
pub fn search_order(target: u32) -> Vec<u32> {
    std::iter::once(target)
        .chain(BAUDS.iter().copied().filter(|&b| b != target))
        .collect()
}

/// Provisions the one fresh servo on the bus: detect (id 0, at any baud rate, exactly one),
/// read its serial number, give it the next free id, switch it to the plan's rate, write the
/// plan's parameters, verify everything at the new id and rate, and read the recorded
/// parameters. Stops at the first step that fails; the record names it. `state` carries the ids
/// given out from one servo to the next.
pub fn provision_next(
    client: &Client,
    profile: &Profile,
    plan: &Plan,
    state: &mut ProvisionState,
    cancel: &Cancel,
    progress: &mut dyn FnMut(Progress),
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
    match plan.resolve(profile) {
        Ok(resolved) => run(
            client,
            profile,
            plan,
            &resolved,
            state,
            cancel,
            progress,
            &mut record,
        ),
        Err(issue) => fail(&mut record, step::PLAN, issue.message),
    }
    record.time = chrono::Local::now().to_rfc3339_opts(chrono::SecondsFormat::Secs, false);
    record
}

/// The steps; on failure, sets the record's result and returns.
#[allow(clippy::too_many_arguments)]
fn run(
    client: &Client,
    profile: &Profile,
    plan: &Plan,
    resolved: &Resolved<'_>,
    state: &mut ProvisionState,
    cancel: &Cancel,
    progress: &mut dyn FnMut(Progress),
    record: &mut Record,
) {
    let total = 6 + resolved.writes.len() as u64;
    let mut done = 0u64;
    let mut at = |step: &str, detail: String, done: &mut u64| {
        progress(Progress {
            done: *done,
            total,
            message: if detail.is_empty() {
                step.to_string()
            } else {
                format!("{step}: {detail}")
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
    let found = match find_fresh(client, &search_order(target)) {
        Ok(f) => f,
        Err(e) => return fail(record, step::DETECT, e),
    };
    let baud = match found.as_slice() {
        [] => {
            return fail(
                record,
                step::DETECT,
                "no fresh servo (id 0) answers at any baud rate".into(),
            );
        }
        [(b, Presence::Present)] => *b,
        [(b, Presence::PossibleDuplicate(e))] => {
            return fail(
                record,
                step::DETECT,
                format!(
                    "more than one servo answers at id 0 at {b} baud (garbled answers: {e}); leave one fresh servo on the bus"
                ),
            );
        }
        many => {
            let rates: Vec<String> = many.iter().map(|(b, _)| b.to_string()).collect();
            return fail(
                record,
                step::DETECT,
                format!(
                    "more than one servo: fresh servos (id 0) answer at {} baud; leave one on the bus",
                    rates.join(" and ")
                ),
            );
        }
    };
    if let Err(e) = switch(client, baud) {
        return fail(record, step::DETECT, e);
    }
    record.baud = Some(baud);

    // Its serial number, so that even a failure names the servo.
    at(step::SERIAL, String::new(), &mut done);
    check_cancel!(step::SERIAL);
    let serial = match read(client, profile, 0, PARAM_SERIAL) {
        Ok(v) => v,
        Err(e) => return fail(record, step::SERIAL, reason(&e, 0, baud)),
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
        match id_is_free(client, id, &search_order(target)) {
            Ok(true) => {
                chosen = Some((i, id));
                break;
            }
            // In use: never offered again.
            Ok(false) => state.next = i + 1,
            Err(e) => return fail(record, step::ASSIGN_ID, e),
        }
    }
    if let Err(e) = switch(client, baud) {
        return fail(record, step::ASSIGN_ID, e);
    }
    let Some((index, id)) = chosen else {
        return fail(
            record,
            step::ASSIGN_ID,
            "no free id left in the plan's ids".into(),
        );
    };
    if let Err(e) = servo::set_id(client, profile, 0, id, cancel) {
        return fail(record, step::ASSIGN_ID, reason(&e, 0, baud));
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
        match servo::set_baud(client, profile, id, resolved.option) {
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
        match servo::write_param(client, profile, id, param, Input::Raw(Value::Int(raw))) {
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
    let mut expected: Vec<(u8, i64)> = vec![
        (PARAM_SERIAL, i64::from(serial)),
        (PARAM_ID, i64::from(id)),
        (PARAM_BAUD, i64::from(resolved.option)),
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
        let got = match read(client, profile, id, pid) {
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
        match servo::read_param(client, profile, id, param) {
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
    progress(Progress {
        done: total,
        total,
        message: "done".into(),
    });
}

fn read(client: &Client, profile: &Profile, id: u8, pid: u8) -> Result<i64, OpError> {
    let param = profile
        .param(pid)
        .ok_or_else(|| OpError::Input(format!("the profile has no parameter {pid}")))?;
    servo::read_param(client, profile, id, param)
}

/// Whether `id` is silent at every one of `bauds`.
fn id_is_free(client: &Client, id: u8, bauds: &[u32]) -> Result<bool, String> {
    for &b in bauds {
        switch(client, b)?;
        if servo::ping(client, id, 2).map_err(|e| e.to_string())? != Presence::Absent {
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

// ---- The log ----

/// The log's header for a plan that records `recorded`.
pub fn csv_header(recorded: &[String]) -> String {
    let mut cols: Vec<String> = [
        "time",
        "serial",
        "id",
        "baud",
        "result",
        "step",
        "reason",
        "mismatches",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    cols.extend(recorded.iter().map(|r| csv_field(r)));
    cols.join(",")
}

/// One record as a log line (without its newline).
pub fn csv_line(record: &Record) -> String {
    let opt = |v: Option<String>| v.unwrap_or_default();
    let (result, step, reason) = match &record.result {
        Outcome::Pass => ("PASS", "", ""),
        Outcome::Fail { step, reason } => ("FAIL", step.as_str(), reason.as_str()),
    };
    let mut cols = vec![
        csv_field(&record.time),
        opt(record.serial.map(|s| s.to_string())),
        opt(record.id.map(|s| s.to_string())),
        opt(record.baud.map(|s| s.to_string())),
        result.to_string(),
        csv_field(step),
        csv_field(reason),
        csv_field(&record.mismatches.join("; ")),
    ];
    cols.extend(
        record
            .recorded
            .iter()
            .map(|(_, v)| csv_field(v.as_deref().unwrap_or(""))),
    );
    cols.join(",")
}

/// A CSV field, quoted when it holds a comma, a quote, a line break or edge spaces.
pub fn csv_field(s: &str) -> String {
    let needs = s.contains([',', '"', '\n', '\r']) || s.trim() != s;
    if needs {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// Appends `record` to the CSV log at `path`, writing the header first when the file is new or
/// empty, and syncs it to disk. A log whose header is for other recorded parameters is refused
/// rather than mixed.
pub fn append_csv(path: &Path, record: &Record) -> std::io::Result<()> {
    let names: Vec<String> = record.recorded.iter().map(|(k, _)| k.clone()).collect();
    let header = csv_header(&names);
    let mut file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .read(true)
        .open(path)?;
    let len = file.metadata()?.len();
    let mut text = String::new();
    if len == 0 {
        text.push_str(&header);
        text.push('\n');
    } else {
        let mut first = String::new();
        std::io::BufReader::new(std::fs::File::open(path)?).read_line(&mut first)?;
        let first = first.trim_end_matches(['\n', '\r']);
        if first != header {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!(
                    "{} has another header ({first}); this plan logs {header}: use another log file",
                    path.display()
                ),
            ));
        }
    }
    text.push_str(&csv_line(record));
    text.push('\n');
    file.write_all(text.as_bytes())?;
    file.sync_all()
}

/// Checks that the log at `path` can be appended to (created if missing), before any servo is
/// touched.
pub fn check_log(path: &Path) -> std::io::Result<()> {
    std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .map(drop)
}
