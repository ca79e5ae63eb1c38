//! Each kind of self-test step, measured and judged: a range, a stable reading, a rise when
//! something is turned on, bits the operator toggles, values read as expected. Each returns the
//! step's verdict and what was seen, or why it halts the run.

use super::measure::{Reader, means, send_action, show, sleep, tolerance, verdict};
use super::plan::{Action, DEFAULT_INTERVAL, Step, StepKind};
use super::run::{Halt, Operator};
use crate::ops::exchange as ops;
use crate::ops::records::Measurement;
use crate::ops::{Cancel, Device};
use crate::profile::{Field, Value};
use std::time::{Duration, Instant};

/// A step's verdict and what was seen, or why it halts the run (with what was seen).
pub(super) type StepOutcome = Result<(bool, String), (Halt, String)>;

/// `h`, with nothing seen.
fn halt(h: Halt) -> (Halt, String) {
    (h, String::new())
}

/// Runs `step` on the device; `operator` is asked when the step needs a hand. The values
/// measured, with their limits, go to `measured` (for the records).
pub(super) fn run_step(
    dev: Device<'_>,
    step: &Step,
    operator: &mut dyn Operator,
    cancel: &Cancel,
    measured: &mut Vec<Measurement>,
) -> StepOutcome {
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
            range(&r, (*samples, *interval), (*min, *max), cancel, measured)
        }
        StepKind::Stable {
            command,
            fields,
            max_spread,
            samples,
            interval,
        } => {
            let r = Reader::new(dev, command, fields).map_err(halt)?;
            stable(&r, (*samples, *interval), *max_spread, cancel, measured)
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
            let rise = Rise {
                action,
                min_rise: *min_rise,
                settle: *settle,
                samples: *samples,
                then,
            };
            rises_step(dev, &r, &rise, cancel, measured)
        }
        StepKind::Operator {
            prompt,
            command,
            field,
            bits,
            timeout,
        } => {
            let r = Reader::new(dev, command, std::slice::from_ref(field)).map_err(halt)?;
            toggled(&r, prompt, operator, *bits, *timeout, cancel)
        }
        StepKind::Reads { command, expect } => reads(dev, command, expect),
    }
}

/// Every sample of every field within `min` to `max` (each field's tolerance beyond).
fn range(
    r: &Reader,
    (samples, interval): (u32, Duration),
    (min, max): (f64, f64),
    cancel: &Cancel,
    measured: &mut Vec<Measurement>,
) -> StepOutcome {
    r.judge(samples, interval, cancel, |f, values, (lo, hi)| {
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
            show(f, min),
            show(f, max)
        );
        measured.push(Measurement {
            name: f.ident.clone(),
            unit: f.unit.clone(),
            low: Some(min),
            high: Some(max),
            value: values.iter().sum::<f64>() / values.len().max(1) as f64,
            pass: outside == 0,
        });
        (outside == 0, text)
    })
    .map_err(halt)
}

/// Each field's samples spread over no more than `max_spread`.
fn stable(
    r: &Reader,
    (samples, interval): (u32, Duration),
    max_spread: f64,
    cancel: &Cancel,
    measured: &mut Vec<Measurement>,
) -> StepOutcome {
    r.judge(samples, interval, cancel, |f, _, (lo, hi)| {
        let spread = hi - lo;
        let ok = spread <= max_spread + tolerance(f);
        let text = format!(
            "{} spread {} ({} to {}; max {}){}",
            f.ident,
            show(f, spread),
            show(f, lo),
            show(f, hi),
            show(f, max_spread),
            if ok { "" } else { " TOO NOISY" }
        );
        measured.push(Measurement {
            name: format!("{} spread", f.ident),
            unit: f.unit.clone(),
            low: None,
            high: Some(max_spread),
            value: spread,
            pass: ok,
        });
        (ok, text)
    })
    .map_err(halt)
}

/// A rise step: what turns something on, how much each field must rise, how long it settles,
/// how many samples before and after, and what turns it off again.
struct Rise<'a> {
    action: &'a Action,
    min_rise: f64,
    settle: Duration,
    samples: u32,
    then: &'a Action,
}

/// Each field rises by at least `min_rise` when the action is on; whatever happened, the `then`
/// action turns it off again, and its failure halts the run.
fn rises_step(
    dev: Device<'_>,
    r: &Reader,
    rise: &Rise<'_>,
    cancel: &Cancel,
    measured: &mut Vec<Measurement>,
) -> StepOutcome {
    let rose = rises(r, dev, rise.action, rise.settle, rise.samples, cancel);
    // Whatever happened, turn it off.
    let stopped = send_action(dev, rise.then);
    let (pass, detail, halted) = match rose {
        Ok((before, after)) => {
            let (pass, detail) = rise_verdict(r, &before, &after, rise.min_rise, measured);
            (pass, detail, None)
        }
        Err(h) => (false, String::new(), Some(h)),
    };
    let joined = |note: String| {
        if detail.is_empty() {
            note
        } else {
            format!("{detail}; {note}")
        }
    };
    match stopped {
        Ok(()) => {
            if halted.is_none() {
                sleep(rise.settle, cancel);
            }
            let detail = joined(format!("then {}: sent", rise.then.text));
            match halted {
                Some(h) => Err((h, detail)),
                None => Ok((pass, detail)),
            }
        }
        Err(e) => {
            let failed = Halt::from(e);
            let detail = joined(format!(
                "then {} FAILED: {}",
                rise.then.text,
                failed.message()
            ));
            // A port that went is a lost link, not a robot that would not stop.
            let why = match failed {
                Halt::LinkLost(_) => failed,
                _ => Halt::Device("could not stop".into()),
            };
            Err((halted.unwrap_or(why), detail))
        }
    }
}

/// Each field's rise from its mean `before` to its mean `after`, against `min_rise`.
fn rise_verdict(
    r: &Reader,
    before: &[f64],
    after: &[f64],
    min_rise: f64,
    measured: &mut Vec<Measurement>,
) -> (bool, String) {
    verdict(r.fields.iter().zip(before).zip(after).map(|((f, b), a)| {
        let rise = a - b;
        let ok = rise >= min_rise - tolerance(f);
        let text = format!(
            "{} {} → {} (rise {}, min {}){}",
            f.ident,
            show(f, *b),
            show(f, *a),
            show(f, rise),
            show(f, min_rise),
            if ok { "" } else { " NO RISE" }
        );
        measured.push(Measurement {
            name: format!("{} rise", f.ident),
            unit: f.unit.clone(),
            low: Some(min_rise),
            high: None,
            value: rise,
            pass: ok,
        });
        (ok, text)
    }))
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
    send_action(dev, action).map_err(|e| {
        let halt = Halt::from(e);
        let said = format!("{}: {}", action.text, halt.message());
        // A port that went is a lost link, whichever command met it.
        match halt {
            Halt::LinkLost(_) => Halt::LinkLost(said),
            _ => Halt::Device(said),
        }
    })?;
    if !sleep(settle, cancel) {
        return Err(Halt::Cancelled);
    }
    let after = r.samples(samples, DEFAULT_INTERVAL, cancel)?;
    Ok((means(&before), means(&after)))
}

/// Every bit of `bits` of the field seen both set and clear: read once before the operator is
/// prompted (that reading counts), then, once they are ready, until each bit has been seen both
/// ways or `timeout` has passed.
fn toggled(
    r: &Reader,
    prompt: &str,
    operator: &mut dyn Operator,
    bits: u64,
    timeout: Duration,
    cancel: &Cancel,
) -> StepOutcome {
    let mut seen = (0u64, 0u64);
    let look = |raw: u64, seen: &mut (u64, u64)| {
        seen.0 |= raw & bits;
        seen.1 |= !raw & bits;
    };
    look(r.raw_once()?.0[0] as u64, &mut seen);
    if !operator.prompt(prompt) {
        return Err(halt(Halt::OperatorAborted));
    }
    let deadline = Instant::now() + timeout;
    loop {
        if cancel.is_cancelled() {
            return Err(halt(Halt::Cancelled));
        }
        look(r.raw_once()?.0[0] as u64, &mut seen);
        if seen.0 & seen.1 == bits || Instant::now() >= deadline {
            break;
        }
        std::thread::sleep(DEFAULT_INTERVAL);
    }
    Ok(toggled_verdict(r.fields[0], bits, seen, timeout))
}

/// The verdict of an operator step: every bit toggled, or which were never set and never clear.
fn toggled_verdict(
    f: &Field,
    bits: u64,
    (seen_set, seen_clear): (u64, u64),
    timeout: Duration,
) -> (bool, String) {
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
    if toggled == bits {
        return (true, format!("{} toggled: {}", f.ident, names(bits)));
    }
    let mut missing = Vec::new();
    if bits & !seen_set != 0 {
        missing.push(format!("never set: {}", names(bits & !seen_set)));
    }
    if bits & !seen_clear != 0 {
        missing.push(format!("never clear: {}", names(bits & !seen_clear)));
    }
    let seen = if toggled == 0 {
        "none".into()
    } else {
        names(toggled)
    };
    let text = format!(
        "{} within {} ms: toggled {seen}; {}",
        f.ident,
        timeout.as_millis(),
        missing.join("; ")
    );
    (false, text)
}

/// The command read once, each expected field's value compared.
fn reads(dev: Device<'_>, command: &str, expect: &[(String, Value, String)]) -> StepOutcome {
    let cmd = dev
        .profile
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
