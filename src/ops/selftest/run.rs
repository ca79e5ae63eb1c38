//! Running a plan step by step over a link: each step measured against its thresholds, the run
//! ended at once when the link, the device, the operator or a cancel stops it.

use super::measure::sleep;
use super::plan::{Plan, StepKind};
use super::record::{Interruption, Report, StepResult};
use super::steps::run_step;
use crate::ops::{Cancel, Device, OpError, Progress, Run};
use std::time::Instant;

/// Who stands at the station.
pub trait Operator {
    /// Shows `text` and waits until the operator is ready; `false` when they abort.
    fn prompt(&mut self, text: &str) -> bool;
}

impl<F: FnMut(&str) -> bool> Operator for F {
    fn prompt(&mut self, text: &str) -> bool {
        self(text)
    }
}

/// Why a step ends the run.
pub(super) enum Halt {
    /// The device failed (no answer, an answer without the field asked for).
    Device(String),
    /// The port went away (`link lost: ` and why).
    LinkLost(String),
    /// Cancelled.
    Cancelled,
    /// The operator said no.
    OperatorAborted,
}

impl Halt {
    pub(super) fn message(&self) -> String {
        match self {
            Halt::Device(m) | Halt::LinkLost(m) => m.clone(),
            Halt::Cancelled => "cancelled".into(),
            Halt::OperatorAborted => "the operator aborted".into(),
        }
    }
}

impl Halt {
    /// The run was stopped from outside the unit: the unit did not fail the step.
    pub(super) fn interruption(&self) -> Option<Interruption> {
        match self {
            Halt::Device(_) => None,
            Halt::LinkLost(_) => Some(Interruption::LinkLost),
            Halt::Cancelled => Some(Interruption::Cancelled),
            Halt::OperatorAborted => Some(Interruption::OperatorAborted),
        }
    }
}

impl From<OpError> for Halt {
    fn from(e: OpError) -> Self {
        match e {
            OpError::Cancelled | OpError::CancelledAfter { .. } => Halt::Cancelled,
            other => match other.lost_port() {
                Some(m) => Halt::LinkLost(format!("link lost: {m}")),
                None => Halt::Device(other.to_string()),
            },
        }
    }
}

/// How the progress message that says the safe state set before the first step begins (then
/// `: ` and one `COMMAND fields: acknowledged` a command, joined by `; `): reported once the
/// safe state is reached, before the first step, so that a command line can say it first.
pub const SAFE_STATE: &str = "safe state before the first step";

/// Runs the plan. Never returns PASS unless every step ran and passed.
pub fn run(dev: Device<'_>, plan: &Plan, operator: &mut dyn Operator, run: &mut Run<'_>) -> Report {
    run_each(dev, plan, operator, run, &mut |_| {})
}

/// [`run`], telling `each` every step's result as it comes.
pub fn run_each(
    dev: Device<'_>,
    plan: &Plan,
    operator: &mut dyn Operator,
    run: &mut Run<'_>,
    each: &mut dyn FnMut(&StepResult),
) -> Report {
    let t0 = Instant::now();
    let mut report = Report {
        plan: plan.name.clone(),
        profile: dev.profile.id.clone(),
        device: None,
        device_info: None,
        started: chrono::Local::now().to_rfc3339_opts(chrono::SecondsFormat::Millis, false),
        duration_ms: 0,
        safe_state: Vec::new(),
        results: Vec::new(),
        aborted: None,
        pass: false,
    };
    let total = plan.steps.len() as u64 + 1;
    let said = |en: &str, zh: &str, done| Progress {
        done,
        total,
        message: crate::i18n::Text::new(en, zh),
    };
    run.report(said("identifying the device", "正在识别设备", 0));
    identify(dev, &mut report, each);
    if report.aborted.is_none() {
        run.report(said("setting the safe state", "正在设为安全状态", 0));
        report.aborted = safe_state(dev, plan, run.cancel_flag(), &mut report.safe_state);
        if report.aborted.is_none() && !report.safe_state.is_empty() {
            let lines = report.safe_state.join("; ");
            run.report(said(
                &format!("{SAFE_STATE}: {lines}"),
                &format!("第一步之前的安全状态:{lines}"),
                0,
            ));
        }
    }
    if report.aborted.is_none() {
        run_steps(dev, plan, operator, run, each, &mut report);
    }
    run.report(said("done", "完成", total));
    report.pass = report.aborted.is_none()
        && report.results.len() == plan.steps.len()
        && report.results.iter().all(|r| r.pass);
    report.duration_ms = t0.elapsed().as_millis() as u64;
    report
}

/// The device's identity into `report`; when it does not identify itself, a failed step that
/// ends the run.
fn identify(dev: Device<'_>, report: &mut Report, each: &mut dyn FnMut(&StepResult)) {
    match crate::ops::device::identify(dev.client) {
        Ok(info) => {
            report.device = Some(crate::ops::device::description(&info));
            report.device_info = Some(info);
        }
        Err(e) => {
            let r = StepResult {
                name: "Device identity".into(),
                kind: "Identify".into(),
                pass: false,
                detail: format!("CMD_VERSION: {e}"),
                measurements: Vec::new(),
                started_ms: crate::ops::records::record::now_ms(),
                duration_ms: 0,
                interrupted: None,
            };
            each(&r);
            report.aborted = Some(format!("step 'Device identity': {}", r.detail));
            report.results.push(r);
        }
    }
}

/// The plan's steps in order into `report`, progress after each; a step that halts ends the run
/// (the steps left are said in why it was aborted).
fn run_steps(
    dev: Device<'_>,
    plan: &Plan,
    operator: &mut dyn Operator,
    run: &mut Run<'_>,
    each: &mut dyn FnMut(&StepResult),
    report: &mut Report,
) {
    let total = plan.steps.len() as u64 + 1;
    for (i, step) in plan.steps.iter().enumerate() {
        run.report(Progress {
            done: i as u64 + 1,
            total,
            // The plan's own Chinese name for the step, where it gives one.
            message: crate::i18n::Text::new(
                &step.name,
                plan.said(&step.name, crate::i18n::Lang::Zh),
            ),
        });
        let clock = crate::ops::records::StepClock::start();
        let mut measured = Vec::new();
        // (passed, what was measured or went wrong, the run ends here, why not the unit's doing)
        let (pass, detail, halt, interrupted) = if run.is_cancelled() {
            let why = Some(Interruption::Cancelled);
            (false, "cancelled before it started".into(), true, why)
        } else {
            match run_step(dev, step, operator, run.cancel_flag(), &mut measured) {
                Ok((pass, detail)) => (pass, detail, false, None),
                Err((halt, detail)) => {
                    let said = match detail.is_empty() {
                        true => halt.message(),
                        false => format!("{}; {detail}", halt.message()),
                    };
                    (false, said, true, halt.interruption())
                }
            }
        };
        let timed = clock.end(&step.name, step.kind.name(), None, String::new());
        let r = StepResult {
            name: step.name.clone(),
            kind: step.kind.name().into(),
            pass,
            detail,
            measurements: measured,
            started_ms: timed.started_ms,
            duration_ms: timed.duration_ms,
            interrupted,
        };
        each(&r);
        if halt {
            let left = plan.steps.len() - i - 1;
            let not_run = if left > 0 {
                format!("; {left} step(s) not run")
            } else {
                String::new()
            };
            report.aborted = Some(format!("step '{}': {}{not_run}", r.name, r.detail));
            report.results.push(r);
            return;
        }
        report.results.push(r);
    }
}

/// Brings the robot to rest before the first step, whatever an earlier session left running
/// (a fan left on from the actions panel would make "Fan current" fail): sends the profile's
/// STOP, each command acknowledged, then waits as long as the plan's longest settle so that
/// what ran has spun down before anything is measured. Each command's outcome goes to `lines`;
/// returns why the run cannot start, if it cannot.
fn safe_state(
    dev: Device<'_>,
    plan: &Plan,
    cancel: &Cancel,
    lines: &mut Vec<String>,
) -> Option<String> {
    let stopped = crate::ops::stop::stop(dev);
    for s in &stopped {
        lines.push(match &s.result {
            Ok(()) => format!("{}: acknowledged", s.what),
            Err(e) => format!("{}: {e}", s.what),
        });
    }
    if let Some(s) = stopped.iter().find(|s| s.result.is_err()) {
        let e = s.result.clone().err().map(Halt::from);
        return Some(format!(
            "safe state not reached: {}: {}; no step run",
            s.what,
            e.map_or_else(String::new, |h| h.message())
        ));
    }
    let settle = plan
        .steps
        .iter()
        .filter_map(|s| match &s.kind {
            StepKind::Rises { settle, .. } => Some(*settle),
            _ => None,
        })
        .max()
        .unwrap_or_default();
    if !stopped.is_empty() && !sleep(settle, cancel) {
        return Some("cancelled while setting the safe state; no step run".into());
    }
    None
}
