//! Running a plan step by step over a link: each step measured against its thresholds, the run
//! ended at once when the link, the device, the operator or a cancel stops it.

use super::measure::{Reader, means, send_action, show, sleep, tolerance, verdict};
use super::plan::{Action, DEFAULT_INTERVAL, Plan, Step, StepKind};
use super::record::{Report, StepResult};
use crate::ops::exchange as ops;
use crate::ops::{Cancel, OpError, Progress};
use crate::ops::{Device, Run};
use std::time::{Duration, Instant};

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
    /// The link or the device failed.
    Device(String),
    /// Cancelled.
    Cancelled,
    /// The operator said no.
    OperatorAborted,
}

impl Halt {
    pub(super) fn message(&self) -> String {
        match self {
            Halt::Device(m) => m.clone(),
            Halt::Cancelled => "cancelled".into(),
            Halt::OperatorAborted => "the operator aborted".into(),
        }
    }
}

impl From<OpError> for Halt {
    fn from(e: OpError) -> Self {
        match e {
            OpError::Cancelled => Halt::Cancelled,
            OpError::Exchange(crate::link::ExchangeError::Disconnected(m)) => {
                Halt::Device(format!("link lost: {m}"))
            }
            other => Halt::Device(other.to_string()),
        }
    }
}

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
    let Device { client, profile } = dev;
    let t0 = Instant::now();
    let mut report = Report {
        plan: plan.name.clone(),
        profile: profile.id.clone(),
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
    run.report(Progress {
        done: 0,
        total,
        message: crate::i18n::Text::new("identifying the device", "正在识别设备"),
    });
    match crate::ops::device::identify(client) {
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
            };
            each(&r);
            report.aborted = Some(format!("step 'Device identity': {}", r.detail));
            report.results.push(r);
        }
    }
    if report.aborted.is_none() {
        run.report(Progress {
            done: 0,
            total,
            message: crate::i18n::Text::new("setting the safe state", "正在设为安全状态"),
        });
        report.aborted = safe_state(dev, plan, run.cancel_flag(), &mut report.safe_state);
    }
    if report.aborted.is_none() {
        for (i, step) in plan.steps.iter().enumerate() {
            run.report(Progress {
                done: i as u64 + 1,
                total,
                message: crate::i18n::Text::same(&step.name),
            });
            let (pass, detail, halt) = if run.is_cancelled() {
                (false, "cancelled before it started".into(), true)
            } else {
                match run_step(dev, step, operator, run.cancel_flag()) {
                    Ok((pass, detail)) => (pass, detail, false),
                    Err((halt, detail)) => {
                        let d = if detail.is_empty() {
                            halt.message()
                        } else {
                            format!("{}; {detail}", halt.message())
                        };
                        (false, d, true)
                    }
                }
            };
            let r = StepResult {
                name: step.name.clone(),
                kind: step.kind.name().into(),
                pass,
                detail,
            };
            each(&r);
            if halt {
                let left = plan.steps.len() - i - 1;
                report.aborted = Some(format!(
                    "step '{}': {}{}",
                    r.name,
                    r.detail,
                    if left > 0 {
                        format!("; {left} step(s) not run")
                    } else {
                        String::new()
                    }
                ));
                report.results.push(r);
                break;
            }
            report.results.push(r);
        }
    }
    run.report(Progress {
        done: total,
        total,
        message: crate::i18n::Text::new("done", "完成"),
    });
    report.pass = report.aborted.is_none()
        && report.results.len() == plan.steps.len()
        && report.results.iter().all(|r| r.pass);
    report.duration_ms = t0.elapsed().as_millis() as u64;
    report
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

type StepOutcome = Result<(bool, String), (Halt, String)>;

fn run_step(
    dev: Device<'_>,
    step: &Step,
    operator: &mut dyn Operator,
    cancel: &Cancel,
) -> StepOutcome {
    let profile = dev.profile;
    let halt = |h: Halt| (h, String::new());
    match &step.kind {
        StepKind::Range {
            command,
            fields,
            min,
            max,
            samples,
            interval,
        } => {
            let r = Reader::new(dev, command, fields).map_err(halt)?;
            r.judge(*samples, *interval, cancel, |f, values, (lo, hi)| {
                let tol = tolerance(f);
                let outside = values
                    .iter()
                    .filter(|v| **v < min - tol || **v > max + tol)
                    .count();
                let seen = if lo == hi {
                    show(f, lo)
                } else {
                    format!("{} to {}", show(f, lo), show(f, hi))
                };
                let note = if outside == 0 {
                    String::new()
                } else {
                    format!(", {outside} of {} samples outside", values.len())
                };
                let text = format!(
                    "{} {seen} (allowed {} to {}){note}",
                    f.ident,
                    show(f, *min),
                    show(f, *max)
                );
                (outside == 0, text)
            })
            .map_err(halt)
        }
        StepKind::Stable {
            command,
            fields,
            max_spread,
            samples,
            interval,
        } => {
            let r = Reader::new(dev, command, fields).map_err(halt)?;
            r.judge(*samples, *interval, cancel, |f, _, (lo, hi)| {
                let spread = hi - lo;
                let ok = spread <= max_spread + tolerance(f);
                let text = format!(
                    "{} spread {} ({} to {}; max {}){}",
                    f.ident,
                    show(f, spread),
                    show(f, lo),
                    show(f, hi),
                    show(f, *max_spread),
                    if ok { "" } else { " TOO NOISY" }
                );
                (ok, text)
            })
            .map_err(halt)
        }
        StepKind::Rises {
            action,
            command,
            fields,
            min_rise,
            settle,
            samples,
            then,
        } => {
            let r = Reader::new(dev, command, fields).map_err(halt)?;
            let measured = rises(&r, dev, action, *settle, *samples, cancel);
            // Whatever happened, turn it off.
            let stopped = send_action(dev, then);
            let (pass, mut detail, halted) = match measured {
                Ok((before, after)) => {
                    let (pass, detail) =
                        verdict(r.fields.iter().zip(&before).zip(&after).map(|((f, b), a)| {
                            let rise = a - b;
                            let ok = rise >= min_rise - tolerance(f);
                            let text = format!(
                                "{} {} → {} (rise {}, min {}){}",
                                f.ident,
                                show(f, *b),
                                show(f, *a),
                                show(f, rise),
                                show(f, *min_rise),
                                if ok { "" } else { " NO RISE" }
                            );
                            (ok, text)
                        }));
                    (pass, detail, None)
                }
                Err(h) => (false, String::new(), Some(h)),
            };
            match stopped {
                Ok(()) => {
                    if halted.is_none() {
                        sleep(*settle, cancel);
                    }
                    let note = format!("then {}: sent", then.text);
                    detail = if detail.is_empty() {
                        note
                    } else {
                        format!("{detail}; {note}")
                    };
                }
                Err(e) => {
                    let note = format!("then {} FAILED: {}", then.text, Halt::from(e).message());
                    let detail = if detail.is_empty() {
                        note
                    } else {
                        format!("{detail}; {note}")
                    };
                    return Err((
                        halted.unwrap_or(Halt::Device("could not stop".into())),
                        detail,
                    ));
                }
            }
            match halted {
                Some(h) => Err((h, detail)),
                None => Ok((pass, detail)),
            }
        }
        StepKind::Operator {
            prompt,
            command,
            field,
            bits,
            timeout,
        } => {
            let r = Reader::new(dev, command, std::slice::from_ref(field)).map_err(halt)?;
            let f = r.fields[0];
            let (mut seen_set, mut seen_clear) = (0u64, 0u64);
            let raw = r.raw_once()?.0[0] as u64;
            seen_set |= raw & bits;
            seen_clear |= !raw & bits;
            if !operator.prompt(prompt) {
                return Err(halt(Halt::OperatorAborted));
            }
            let deadline = Instant::now() + *timeout;
            loop {
                if cancel.is_cancelled() {
                    return Err(halt(Halt::Cancelled));
                }
                let raw = r.raw_once()?.0[0] as u64;
                seen_set |= raw & bits;
                seen_clear |= !raw & bits;
                if seen_set & seen_clear == *bits || Instant::now() >= deadline {
                    break;
                }
                std::thread::sleep(DEFAULT_INTERVAL);
            }
            let toggled = seen_set & seen_clear;
            let names = |mask: u64| -> String {
                (0..64)
                    .filter(|b| mask >> b & 1 == 1)
                    .map(|b| {
                        f.bits
                            .iter()
                            .find(|x| u32::from(x.bit) == b)
                            .map_or_else(|| format!("bit {b}"), |x| x.ident.clone())
                    })
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            if toggled == *bits {
                Ok((true, format!("{} toggled: {}", f.ident, names(*bits))))
            } else {
                let never_set = bits & !seen_set;
                let never_clear = bits & !seen_clear;
                let mut missing = Vec::new();
                if never_set != 0 {
                    missing.push(format!("never set: {}", names(never_set)));
                }
                if never_clear != 0 {
                    missing.push(format!("never clear: {}", names(never_clear)));
                }
                Ok((
                    false,
                    format!(
                        "{} within {} ms: toggled {}; {}",
                        f.ident,
                        timeout.as_millis(),
                        if toggled == 0 {
                            "none".into()
                        } else {
                            names(toggled)
                        },
                        missing.join("; ")
                    ),
                ))
            }
        }
        StepKind::Reads { command, expect } => {
            let cmd = profile
                .command(command)
                .ok_or_else(|| halt(Halt::Device(format!("no command {command}"))))?;
            let values = ops::read(dev, cmd, &[]).map_err(|e| halt(e.into()))?;
            let mut pass = true;
            let mut parts = Vec::new();
            for (k, v) in &values {
                let Some(f) = cmd.reply.iter().find(|f| f.ident == k) else {
                    continue;
                };
                let mut part = format!("{k} {}", f.format(v));
                if let Some((_, want, text)) = expect.iter().find(|(e, _, _)| e == k) {
                    if want == v {
                        part.push_str(&format!(" (expected {text})"));
                    } else {
                        pass = false;
                        part.push_str(&format!(" (expected {text}) WRONG"));
                    }
                }
                parts.push(part);
            }
            for (k, _, text) in expect {
                if !values.contains(k) {
                    pass = false;
                    parts.push(format!("{k} missing from the answer (expected {text})"));
                }
            }
            Ok((pass, parts.join(", ")))
        }
    }
}

/// Measures before and after turning `action` on: the means of `samples` reads each.
fn rises(
    r: &Reader,
    dev: Device<'_>,
    action: &Action,
    settle: Duration,
    samples: u32,
    cancel: &Cancel,
) -> Result<(Vec<f64>, Vec<f64>), Halt> {
    let before = r.samples(samples, DEFAULT_INTERVAL, cancel)?;
    send_action(dev, action)
        .map_err(|e| Halt::Device(format!("{}: {}", action.text, Halt::from(e).message())))?;
    if !sleep(settle, cancel) {
        return Err(Halt::Cancelled);
    }
    let after = r.samples(samples, DEFAULT_INTERVAL, cancel)?;
    Ok((means(&before), means(&after)))
}
