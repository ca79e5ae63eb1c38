//! Run, then record: the self-test, the servo provisioning and preset apply, each run, turned
//! into a [`Record`], saved by the [`Recorder`] and exported to its log (the self-test's JSON
//! lines, the provisioning CSV), in that order, before the caller shows the verdict. The
//! command line and the window both call these.

use super::record::{ParamWrite, Record, RunKind, SerialSource, StepClock, StepRecord, Verdict};
use super::recorder::{Keeper, Kept};
use crate::ops::selftest::{self, Operator, Report, StepResult};
use crate::ops::servo::provision::{self, Outcome, ProvisionState};
use crate::ops::station::Reason;
use crate::ops::{Check, Device, OpError, Run};
use crate::preset::Preset;
use std::path::Path;

/// What is known of a run before it starts.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Given {
    /// The unit's serial number and how it was obtained (typed with `--serial`, scanned at
    /// the station); `None` when the device tells it or nobody knows it.
    pub serial: Option<(String, SerialSource)>,
    /// SHA-256 of the plan or preset file (lower-case hex), see
    /// [`super::record::file_sha256`].
    pub plan_sha256: Option<String>,
    /// The plan's or preset's name in the record, where the plan has none of its own (a
    /// provisioning plan, a preset): its file's name, see [`plan_name`].
    pub plan_name: Option<String>,
}

/// A run's outcome with its record and where the record went.
#[derive(Debug)]
pub struct Recorded<T> {
    /// What the operation returned.
    pub outcome: T,
    /// The record saved.
    pub record: Record,
    /// Where it was kept.
    pub kept: Kept,
    /// The export log's result, when one was asked: `Err` says why the line was not appended.
    pub export: Option<std::io::Result<()>>,
}

impl<T> Recorded<T> {
    /// Whether the run passed.
    pub fn pass(&self) -> bool {
        self.record.verdict == Verdict::Pass
    }
}

fn with_serial(record: &mut Record, given: &Given) {
    if let Some((serial, source)) = &given.serial {
        record.unit.serial = Some(serial.clone());
        record.unit.serial_source = Some(*source);
    }
}

/// Runs the self-test `plan` ([`selftest::run_each`]), records it and appends it to the JSON
/// lines `log` when given.
#[allow(clippy::too_many_arguments)]
pub fn selftest(
    dev: Device<'_>,
    plan: &selftest::Plan,
    given: &Given,
    operator: &mut dyn Operator,
    run: &mut Run<'_>,
    each: &mut dyn FnMut(&StepResult),
    recorder: &mut dyn Keeper,
    log: Option<&Path>,
) -> Recorded<Report> {
    let report = selftest::run_each(dev, plan, operator, run, each);
    let mut record = selftest_record(&report, given);
    let kept = recorder.keep(&mut record);
    let export = log.map(|path| selftest::append_log(path, &report));
    Recorded {
        outcome: report,
        record,
        kept,
        export,
    }
}

/// A self-test report as a record.
pub fn selftest_record(report: &Report, given: &Given) -> Record {
    let mut r = Record::start(
        RunKind::Selftest,
        &report.plan,
        given.plan_sha256.clone(),
        &report.profile,
    );
    r.started_ms = chrono::DateTime::parse_from_rfc3339(&report.started)
        .map(|t| t.timestamp_millis())
        .unwrap_or(r.started_ms);
    with_serial(&mut r, given);
    if let Some(info) = &report.device_info {
        r.unit.hardware = Some(format!("{:#04x}", info.hw));
        r.unit.firmware = Some(info.firmware.clone());
        r.unit.build = Some(match &info.build_date {
            Some(d) => format!("{} ({d})", info.build),
            None => info.build.to_string(),
        });
    }
    r.steps = report
        .results
        .iter()
        .map(|s| StepRecord {
            name: s.name.clone(),
            kind: s.kind.clone(),
            started_ms: s.started_ms,
            duration_ms: s.duration_ms,
            verdict: Verdict::of(s.pass),
            reason: (!s.pass).then(|| selftest_reason(s)),
            detail: s.detail.clone(),
            measurements: s.measurements.clone(),
            writes: Vec::new(),
        })
        .collect();
    let aborted = report.aborted.as_ref().map(|a| {
        let step = r
            .steps
            .last()
            .map_or_else(|| "safe state".to_string(), |s| s.name.clone());
        (step, a.clone())
    });
    r.finish(aborted);
    r.ended_ms = r.started_ms + report.duration_ms as i64;
    r
}

/// A failed self-test step's reason, the same words for the same cause on every unit (the
/// values are in its measurements and detail): `out of limits: batteryVoltage`, `link lost`
/// ([`crate::ops::station::Reason::of_selftest_step`], typed, says it).
fn selftest_reason(s: &StepResult) -> String {
    Reason::of_selftest_step(s).to_string()
}

/// Provisions the next fresh servo ([`provision::provision_next`]), records it (the serial
/// read from the servo) and appends it to the CSV `log` when given.
pub fn provision(
    dev: Device<'_>,
    plan: &provision::Plan,
    state: &mut ProvisionState,
    given: &Given,
    run: &mut Run<'_>,
    recorder: &mut dyn Keeper,
    log: Option<&Path>,
) -> Recorded<provision::Record> {
    let started = StepClock::start();
    let mut record = Record::start(
        RunKind::Provision,
        given.plan_name.as_deref().unwrap_or("servo provisioning"),
        given.plan_sha256.clone(),
        &dev.profile.id,
    );
    let outcome = provision::provision_next(dev, plan, state, run);
    provision_into(&mut record, &outcome, given, &started);
    let kept = recorder.keep(&mut record);
    let export = log.map(|path| provision::append_csv(path, &outcome));
    Recorded {
        outcome,
        record,
        kept,
        export,
    }
}

/// The provisioning plan's name in records: its file's name.
pub fn plan_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string())
}

/// Fills `r` from a provisioning outcome: the servo's serial (read from it), its recorded
/// firmware version and type, each step with its time, and the writes. A step the link was
/// lost in is recorded as a self-test's interrupted step is: FAIL with the reason `link lost`
/// (the run FAIL at that step, the same words) and the link's words as its detail.
pub fn provision_into(r: &mut Record, p: &provision::Record, given: &Given, started: &StepClock) {
    with_serial(r, given);
    if let Some(serial) = p.serial {
        r.unit.serial = Some(serial.to_string());
        r.unit.serial_source = Some(SerialSource::Device);
    }
    for (name, value) in &p.recorded {
        match name.as_str() {
            "firmware_version" => r.unit.firmware.clone_from(value),
            "servo_type" => r.unit.hardware.clone_from(value),
            _ => {}
        }
    }
    let end = super::record::now_ms();
    // The failed step: its name, its reason, its detail.
    let failed = match &p.result {
        Outcome::Pass => None,
        Outcome::Fail { step, reason } => Some((step.clone(), reason.clone(), reason.clone())),
        Outcome::LinkLost { step, reason } => Some((
            step.clone(),
            Reason::LinkLost.to_string(),
            Reason::LinkLostBecause {
                why: reason.clone(),
            }
            .to_string(),
        )),
    };
    let timeline: Vec<(String, i64)> = if p.timeline.is_empty() {
        // Refused before any step (the plan): one step, the plan.
        vec![(
            provision::step::PLAN.to_string(),
            started.end("", "", None, String::new()).started_ms,
        )]
    } else {
        p.timeline.clone()
    };
    // A step named twice (apply params, once per parameter) is one step from its first start.
    let mut steps: Vec<(String, i64)> = Vec::new();
    for (name, at) in timeline {
        if steps.last().is_none_or(|(n, _)| *n != name) {
            steps.push((name, at));
        }
    }
    let mut out = Vec::new();
    for (i, (name, at)) in steps.iter().enumerate() {
        let next = steps.get(i + 1).map_or(end, |(_, t)| *t);
        let (reason, detail) = match failed.as_ref().filter(|(step, ..)| step == name) {
            Some((_, reason, detail)) => (Some(reason.clone()), detail.clone()),
            None => (None, String::new()),
        };
        out.push(StepRecord {
            name: name.clone(),
            kind: "Provision".into(),
            started_ms: *at,
            duration_ms: (next - at).max(0),
            verdict: Verdict::of(reason.is_none()),
            reason,
            detail,
            measurements: Vec::new(),
            writes: p
                .writes
                .iter()
                .filter(|(s, _)| s == name)
                .map(|(_, w)| w.clone())
                .collect(),
        });
    }
    if let Some((step, reason, detail)) = &failed
        && !out.iter().any(|s| &s.name == step)
    {
        out.push(StepRecord {
            name: step.clone(),
            kind: "Provision".into(),
            started_ms: end,
            duration_ms: 0,
            verdict: Verdict::Fail,
            reason: Some(reason.clone()),
            detail: detail.clone(),
            measurements: Vec::new(),
            writes: Vec::new(),
        });
    }
    if !p.mismatches.is_empty()
        && let Some(s) = out.iter_mut().find(|s| s.verdict == Verdict::Fail)
    {
        s.detail = format!("{}: {}", s.detail, p.mismatches.join("; "));
    }
    r.steps = out;
    r.finish(None);
}

/// A preset apply's step that reads the device's values before anything is written (the
/// record's "before" of each write), as the records name it.
pub const READ_BEFORE: &str = "read before";
/// The step a preset apply that stopped part way stopped in, as the records name it (each
/// command written is a step of its own, by its wire name).
pub const APPLY: &str = "apply";
/// The 中文 names of a preset apply's own steps, for reports.
pub const PRESET_STEPS_ZH: [(&str, &str); 2] = [(READ_BEFORE, "写入前读取"), (APPLY, "写入预设")];

/// Applies `preset` with read-back ([`crate::ops::preset::apply_each`]) after reading what the
/// device held, and records each command written as a step with its fields before and after.
/// The run fails on an error (the record too) or a field that does not read back as written.
pub fn preset_apply(
    dev: Device<'_>,
    preset: &Preset,
    given: &Given,
    run: &mut Run<'_>,
    written: &mut dyn FnMut(&str, &[Check]),
    recorder: &mut dyn Keeper,
) -> Recorded<Result<Vec<Check>, OpError>> {
    let profile = dev.profile;
    let mut record = Record::start(
        RunKind::PresetApply,
        given.plan_name.as_deref().unwrap_or("preset"),
        given.plan_sha256.clone(),
        &profile.id,
    );
    with_serial(&mut record, given);
    if profile.protocol == crate::profile::Protocol::Msp
        && let Ok(info) = crate::ops::device::identify(dev.client)
    {
        record.unit.hardware = Some(format!("{:#04x}", info.hw));
        record.unit.firmware = Some(info.firmware.clone());
        record.unit.build = Some(info.build.to_string());
    }
    let mut clock = StepClock::start();
    let before = crate::ops::preset::read_device(dev, &mut Run::quiet(run.cancel_flag()));
    let before = match before {
        Ok(b) => {
            record
                .steps
                .push(clock.end(READ_BEFORE, "Read", None, String::new()));
            b
        }
        Err(e) => {
            // A cancel while the values are read first is a batch cancelled before its first
            // command: "cancelled after 0 of N commands", every one of them not done.
            let e = match preset.validate(profile) {
                Ok(writes) if e.is_cancel() => {
                    OpError::cancelled_after(&writes, 0, "commands", |w| w.command.clone())
                }
                _ => e,
            };
            record
                .steps
                .push(clock.end(READ_BEFORE, "Read", Some(e.to_string()), e.to_string()));
            record.finish(None);
            let kept = recorder.keep(&mut record);
            return Recorded {
                outcome: Err(e),
                record,
                kept,
                export: None,
            };
        }
    };
    let mut all = Vec::new();
    clock = StepClock::start();
    let outcome = crate::ops::preset::apply_each(dev, preset, run, &mut |command, checks| {
        written(command, checks);
        all.extend_from_slice(checks);
        let set = profile.command(command);
        let field = |ident: &str| set.and_then(|s| s.request.iter().find(|f| f.ident == ident));
        let held = before.iter().find(|v| v.command == command);
        let writes: Vec<ParamWrite> = checks
            .iter()
            .map(|c| {
                let show = |v| field(&c.field).map_or_else(|| format!("{v:?}"), |f| f.format(v));
                ParamWrite {
                    name: format!("{command}.{}", c.field),
                    unit: field(&c.field).map(|f| f.unit.clone()).unwrap_or_default(),
                    value: show(&c.written),
                    before: held.and_then(|h| h.get(&c.field).map(str::to_string)),
                    after: Some(show(&c.read)),
                }
            })
            .collect();
        let bad: Vec<&str> = checks
            .iter()
            .filter(|c| !c.ok())
            .map(|c| c.field.as_str())
            .collect();
        let reason = (!bad.is_empty()).then(|| format!("read back differs: {}", bad.join(", ")));
        let mut step = clock.end(command, "Write", reason.clone(), reason.unwrap_or_default());
        step.writes = writes;
        record.steps.push(step);
        clock = StepClock::start();
    });
    let aborted = match &outcome {
        Ok(()) if run.is_cancelled() => Some((APPLY.to_string(), "cancelled".to_string())),
        Ok(()) => None,
        Err(e) => Some((APPLY.to_string(), e.to_string())),
    };
    record.finish(aborted);
    let kept = recorder.keep(&mut record);
    Recorded {
        outcome: outcome.map(|()| all),
        record,
        kept,
        export: None,
    }
}

/// Grades a Tuya MCU firmware ([`crate::ops::tuya::conform::conform`]) and records the run:
/// one step a check, its evidence in the detail; an advisory check that fails is recorded PASS
/// with `advisory, not met:` before its detail (the firmware conforms without it), a skipped
/// one is left out. The unit's firmware is the product info's version, its hardware the pid.
pub fn tuya_conform(
    dev: Device<'_>,
    options: &crate::ops::tuya::conform::Options,
    given: &Given,
    run: &mut Run<'_>,
    each: &mut dyn FnMut(&crate::ops::tuya::conform::Check),
    recorder: &mut dyn Keeper,
) -> Recorded<Result<crate::ops::tuya::conform::Conformance, OpError>> {
    let mut record = Record::start(
        RunKind::TuyaConform,
        given.plan_name.as_deref().unwrap_or("tuya conformance"),
        given.plan_sha256.clone(),
        &dev.profile.id,
    );
    with_serial(&mut record, given);
    let outcome = crate::ops::tuya::conform::conform(dev, options, run, each);
    match &outcome {
        Ok(c) => conform_into(&mut record, c),
        Err(e) => record.finish(Some(("conformance".to_string(), e.to_string()))),
    }
    let kept = recorder.keep(&mut record);
    Recorded {
        outcome,
        record,
        kept,
        export: None,
    }
}

/// A conformance run's checks as the record's steps.
fn conform_into(record: &mut Record, c: &crate::ops::tuya::conform::Conformance) {
    use crate::ops::tuya::conform::Grade;
    record.unit.hardware.clone_from(&c.pid);
    record.unit.firmware.clone_from(&c.version);
    let start = record.started_ms;
    let mut at = start;
    for check in c.checks.iter().filter(|c| c.grade != Grade::Skip) {
        let failed = check.grade == Grade::Fail;
        let detail = match (failed, check.mandatory, check.evidence.is_empty()) {
            (true, false, _) => format!("advisory, not met: {}", check.detail),
            (_, _, true) => check.detail.clone(),
            (_, _, false) => format!("{} [{}]", check.detail, check.evidence),
        };
        let detail = if failed && !check.evidence.is_empty() && !check.mandatory {
            format!("{detail} [{}]", check.evidence)
        } else {
            detail
        };
        let fail = failed && check.mandatory;
        record.steps.push(StepRecord {
            name: check.id.to_string(),
            kind: if check.mandatory {
                "Mandatory"
            } else {
                "Advisory"
            }
            .to_string(),
            started_ms: at,
            duration_ms: i64::try_from(check.duration_ms).unwrap_or(i64::MAX),
            verdict: Verdict::of(!fail),
            reason: fail.then(|| check.name.to_string()),
            detail,
            measurements: Vec::new(),
            writes: Vec::new(),
        });
        at += i64::try_from(check.duration_ms).unwrap_or(0);
    }
    record.finish(None);
    record.ended_ms = start + (c.seconds * 1000.0) as i64;
}
