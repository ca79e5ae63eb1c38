//! One line step run over a slot's link: each calls the operation botbench already has and
//! returns the records of what it did (a self-test's own steps, a provisioning's, a single
//! step for the rest) with the reason it failed, if it did.

use super::event::{Answer, What};
use super::plan::Op;
use super::reason::Reason;
use crate::i18n::Text;
use crate::ops::records::record::{Record, RunKind, StepClock, StepRecord, Unit};
use crate::ops::records::runs::{self, Given};
use crate::ops::records::{Keeper, Kept};
use crate::ops::{Cancel, Device, Run};
use std::time::Duration;

/// The operator's side of a slot, as a step sees it.
pub trait Desk {
    /// Asks `text` (`kind`: `confirm`, `measure`, `scan`, `retry`) and waits at most `timeout`
    /// for the answer; `None` when none came, or the slot was stopped.
    fn ask(&mut self, kind: &'static str, text: &Text, timeout: Duration) -> Option<Answer>;
    /// A self-test's prompt to the operator (cover the corner switches), in both languages:
    /// shown, and acted out by a simulated fixture's hands; the step then watches for it.
    /// `false` aborts.
    fn prompt(&mut self, text: &Text) -> bool;
    /// Says something happened (a step's progress).
    fn tell(&mut self, what: What);
}

/// A unit's run so far: what the steps learn of it.
pub struct UnitRun<'a> {
    /// The device.
    pub dev: Device<'a>,
    /// STOP for this slot.
    pub cancel: &'a Cancel,
    /// The unit as the record gives it (a scanned serial, the identity).
    pub unit: Unit,
    /// Whether every step so far passed (what WriteResult writes).
    pub pass_so_far: bool,
    /// The servo provisioning's state across the tray's servos.
    pub provision: crate::ops::servo::provision::ProvisionState,
}

/// What a step did: its records and, when it failed, why (the same words for the same cause).
pub struct Done {
    /// The step's records (several for a self-test or a provisioning).
    pub records: Vec<StepRecord>,
    /// Why it failed; `None` on PASS.
    pub failure: Option<Reason>,
}

impl Done {
    fn one(
        name: &str,
        kind: &str,
        clock: &StepClock,
        failure: Option<Reason>,
        detail: String,
    ) -> Self {
        Self {
            records: vec![clock.end(name, kind, failure.as_ref().map(Reason::to_string), detail)],
            failure,
        }
    }

    /// From the steps of a sub-run's record (a self-test, a conformance run): FAIL, when the
    /// sub-run failed, with its reason typed by `typed` from the record (the record's own
    /// words as they are where `typed` knows them not).
    fn of_record(r: Record, typed: impl FnOnce(&Record) -> Option<Reason>) -> Self {
        let failure = (r.verdict == crate::ops::records::Verdict::Fail).then(|| {
            let words = r.reason.clone().unwrap_or_else(|| "failed".into());
            // Typed only where its English is the record's, word for word.
            typed(&r)
                .filter(|t| t.to_string() == words)
                .unwrap_or(Reason::Other(words))
        });
        Self {
            records: r.steps,
            failure,
        }
    }
}

/// Takes a sub-run's record instead of storing it: it becomes steps of the station's record.
#[derive(Default)]
struct Collect(Option<Record>);

impl Keeper for Collect {
    fn keep(&mut self, record: &mut Record) -> Kept {
        self.0 = Some(record.clone());
        Kept::Stored {
            place: "the station's record".into(),
        }
    }
}

/// Runs `op` (named `name`) for the unit.
pub fn run_step(u: &mut UnitRun<'_>, name: &str, op: &Op, desk: &mut dyn Desk) -> Done {
    let clock = StepClock::start();
    let kind = op.kind();
    match op {
        Op::Identify { hardware, firmware } => identify(u, name, hardware, firmware, &clock),
        Op::Scan { pattern, timeout } => scan(u, name, pattern.as_ref(), *timeout, desk, &clock),
        Op::Confirm { question, timeout } => {
            let answer = desk.ask("confirm", question, *timeout);
            confirm(u, name, answer, &clock)
        }
        Op::Measure {
            name: what,
            unit,
            min,
            max,
            timeout,
        } => {
            let q = Text::new(
                format!("Measure {what} ({min} to {max} {unit})"),
                format!("测量 {what}({min} 至 {max} {unit})"),
            );
            let answer = desk.ask("measure", &q, *timeout);
            measure(u, name, (what, unit, *min, *max), answer, &clock)
        }
        Op::SelfTest { plan, .. } => selftest(u, plan, desk),
        Op::Preset { preset, .. } => {
            let mut keep = Collect::default();
            let mut run = Run::quiet(u.cancel);
            let given = Given::default();
            let done =
                runs::preset_apply(u.dev, preset, &given, &mut run, &mut |_, _| {}, &mut keep);
            let error = done.outcome.err();
            collected(keep, name, kind, &clock, |r| preset_failure(r, error))
        }
        Op::Provision { plan, count, .. } => provision(u, plan, *count, &clock, name),
        Op::TuyaHandshake => handshake(u, name, &clock),
        Op::TuyaStatus => tuya_status(u, name, &clock),
        Op::TuyaConform => {
            let mut keep = Collect::default();
            let mut run = Run::quiet(u.cancel);
            let options = crate::ops::tuya::conform::Options {
                ota: None,
                ota_max: u.dev.profile.ota_max_bytes(),
            };
            let given = Given::default();
            let done =
                runs::tuya_conform(u.dev, &options, &given, &mut run, &mut |_| {}, &mut keep);
            let error = done.outcome.err();
            collected(keep, name, kind, &clock, |r| conform_failure(r, error))
        }
        Op::FirmwareUpdate { image, version, .. } => firmware(u, name, image, version, &clock),
        Op::WriteResult => write_result(u, name, &clock),
    }
}

fn confirm(u: &UnitRun<'_>, name: &str, answer: Option<Answer>, clock: &StepClock) -> Done {
    let (failure, detail) = match answer {
        Some(Answer::Yes) => (None, "yes".to_string()),
        Some(Answer::No) => (Some(Reason::OperatorSaidNo), "no".to_string()),
        Some(Answer::Text(t)) => (Some(Reason::NotYesNo), t),
        None => (Some(unanswered(u.cancel)), String::new()),
    };
    Done::one(name, "Confirm", clock, failure, detail)
}

/// A self-test plan run unchanged; its steps become the station record's.
fn selftest(u: &mut UnitRun<'_>, plan: &crate::ops::selftest::Plan, desk: &mut dyn Desk) -> Done {
    let mut run = Run::quiet(u.cancel);
    let mut prompt = |text: &str| {
        let zh = plan.said(text, crate::i18n::Lang::Zh).to_string();
        desk.prompt(&Text::new(text.to_string(), zh))
    };
    let report = crate::ops::selftest::run_each(u.dev, plan, &mut prompt, &mut run, &mut |_| {});
    if let Some(info) = &report.device_info {
        u.unit.hardware = Some(format!("{:#04x}", info.hw));
        u.unit.firmware = Some(info.firmware.clone());
    }
    let typed = selftest_failure(&report);
    Done::of_record(runs::selftest_record(&report, &Given::default()), |_| typed)
}

fn handshake(u: &mut UnitRun<'_>, name: &str, clock: &StepClock) -> Done {
    let (failure, detail) = match crate::ops::tuya::product_info(u.dev.client) {
        Some(info) if info.error.is_none() => {
            u.unit.hardware.clone_from(&info.pid);
            u.unit.firmware.clone_from(&info.version);
            (None, info.raw)
        }
        Some(info) => (
            Some(Reason::ProductInfoUnreadable),
            info.error.unwrap_or_default(),
        ),
        None => (
            Some(Reason::NoAnswer),
            "the MCU did not answer product info (0x01)".to_string(),
        ),
    };
    Done::one(name, "TuyaHandshake", clock, failure, detail)
}

/// A proven Tuya firmware update: the MCU names `version` after its restart.
fn firmware(
    u: &mut UnitRun<'_>,
    name: &str,
    image: &[u8],
    version: &str,
    clock: &StepClock,
) -> Done {
    let expect = crate::ops::tuya::Expect {
        version: version.to_string(),
        limit: crate::ops::tuya::COME_BACK_LIMIT,
    };
    let mut run = Run::quiet(u.cancel);
    let max = u.dev.profile.ota_max_bytes();
    let timing = crate::ops::tuya::OtaTiming::default();
    match crate::ops::tuya::update(u.dev.client, image, max, &expect, timing, &mut run) {
        Ok(_) => {
            u.unit.firmware = Some(version.to_string());
            Done::one(
                name,
                "FirmwareUpdate",
                clock,
                None,
                format!("updated to {version}"),
            )
        }
        Err(e) => Done::one(
            name,
            "FirmwareUpdate",
            clock,
            Some(Reason::of_error(&e)),
            e.to_string(),
        ),
    }
}

/// Why nothing was answered: the slot was stopped, or the time ran out.
fn unanswered(cancel: &Cancel) -> Reason {
    if cancel.is_cancelled() {
        Reason::Cancelled
    } else {
        Reason::NotAnsweredInTime
    }
}

fn collected(
    keep: Collect,
    name: &str,
    kind: &str,
    clock: &StepClock,
    typed: impl FnOnce(&Record) -> Option<Reason>,
) -> Done {
    match keep.0 {
        Some(r) => Done::of_record(r, typed),
        None => Done::one(name, kind, clock, Some(Reason::NotRun), String::new()),
    }
}

/// Why a preset's apply failed: a write that did not read back, the error that stopped it, or
/// STOP.
fn preset_failure(r: &Record, error: Option<crate::ops::OpError>) -> Option<Reason> {
    let failed = r
        .steps
        .iter()
        .find(|s| s.verdict == crate::ops::records::Verdict::Fail);
    let differs = failed.and_then(|s| s.reason.as_deref()?.strip_prefix("read back differs: "));
    match (differs, error) {
        (Some(fields), _) => Some(Reason::ReadBackDiffers {
            fields: fields.split(", ").map(str::to_string).collect(),
        }),
        (None, Some(e)) => Some(Reason::Error(e)),
        (None, None) => Some(Reason::Cancelled),
    }
}

/// Why a Tuya conformance run failed: its first mandatory check that failed (the record's step
/// is the check's id, its reason the check's name), or the error that stopped it.
fn conform_failure(r: &Record, error: Option<crate::ops::OpError>) -> Option<Reason> {
    let failed = r
        .steps
        .iter()
        .find(|s| s.verdict == crate::ops::records::Verdict::Fail);
    match (failed, error) {
        (Some(s), _) => Some(Reason::Conformance {
            id: s.name.clone(),
            name: s.reason.clone()?,
        }),
        (None, Some(e)) => Some(Reason::Error(e)),
        (None, None) => None,
    }
}

/// Why a self-test failed: its first failed step's reason, else why it was aborted (as its
/// record says it, [`runs::selftest_record`]).
fn selftest_failure(report: &crate::ops::selftest::Report) -> Option<Reason> {
    match report.results.iter().find(|s| !s.pass) {
        Some(step) => Some(Reason::of_selftest_step(step)),
        None => report.aborted.as_deref().map(Reason::of_aborted),
    }
}

fn identify(
    u: &mut UnitRun<'_>,
    name: &str,
    hardware: &[u8],
    firmware: &[String],
    clock: &StepClock,
) -> Done {
    let info = match crate::ops::device::identify(u.dev.client) {
        Ok(i) => i,
        Err(e) => {
            return Done::one(
                name,
                "Identify",
                clock,
                Some(Reason::of_error(&e)),
                e.to_string(),
            );
        }
    };
    u.unit.hardware = Some(format!("{:#04x}", info.hw));
    u.unit.firmware = Some(info.firmware.clone());
    u.unit.build = Some(info.build.to_string());
    let detail = crate::ops::device::short_description(&info);
    let failure = if !hardware.is_empty() && !hardware.contains(&info.hw) {
        Some(Reason::HardwareNotAllowed { hw: info.hw })
    } else if !firmware.is_empty() && !firmware.contains(&info.firmware) {
        Some(Reason::FirmwareNotAllowed {
            firmware: info.firmware.clone(),
        })
    } else {
        None
    };
    Done::one(name, "Identify", clock, failure, detail)
}

fn scan(
    u: &mut UnitRun<'_>,
    name: &str,
    pattern: Option<&regex::Regex>,
    timeout: Duration,
    desk: &mut dyn Desk,
    clock: &StepClock,
) -> Done {
    let code = match &u.unit.serial {
        // Scanned to start the slot.
        Some(s) => s.clone(),
        None => {
            let q = Text::new("Scan the unit's serial number", "扫描产品序列号");
            match desk.ask("scan", &q, timeout) {
                Some(Answer::Text(t)) => t,
                Some(_) => {
                    return Done::one(
                        name,
                        "Scan",
                        clock,
                        Some(Reason::NoSerialScanned),
                        String::new(),
                    );
                }
                None => {
                    return Done::one(
                        name,
                        "Scan",
                        clock,
                        Some(unanswered(u.cancel)),
                        String::new(),
                    );
                }
            }
        }
    };
    if pattern.is_some_and(|p| !p.is_match(&code)) || code.is_empty() {
        u.unit.serial = None;
        return Done::one(name, "Scan", clock, Some(Reason::SerialMismatch), code);
    }
    u.unit.serial = Some(code.clone());
    u.unit.serial_source = Some(crate::ops::records::SerialSource::Scanned);
    Done::one(name, "Scan", clock, None, code)
}

fn measure(
    u: &UnitRun<'_>,
    name: &str,
    (what, unit, min, max): (&str, &str, f64, f64),
    answer: Option<Answer>,
    clock: &StepClock,
) -> Done {
    let text = match answer {
        Some(Answer::Text(t)) => t,
        Some(_) => {
            return Done::one(
                name,
                "Measure",
                clock,
                Some(Reason::NotAValue),
                String::new(),
            );
        }
        None => {
            return Done::one(
                name,
                "Measure",
                clock,
                Some(unanswered(u.cancel)),
                String::new(),
            );
        }
    };
    let Ok(value) = text.trim().parse::<f64>() else {
        return Done::one(name, "Measure", clock, Some(Reason::NotANumber), text);
    };
    let pass = value.is_finite() && (min..=max).contains(&value);
    let measured = crate::ops::records::Measurement {
        name: what.to_string(),
        unit: unit.to_string(),
        low: Some(min),
        high: Some(max),
        value,
        pass,
    };
    let failure = (!pass).then(|| Reason::OutOfLimits {
        values: vec![measured.clone()],
    });
    let mut done = Done::one(name, "Measure", clock, failure, format!("{value} {unit}"));
    done.records[0].measurements.push(measured);
    done
}

fn provision(
    u: &mut UnitRun<'_>,
    plan: &crate::ops::servo::provision::Plan,
    count: u32,
    clock: &StepClock,
    name: &str,
) -> Done {
    let mut all = Vec::new();
    let mut failure = None;
    for _ in 0..count {
        let started = StepClock::start();
        let mut run = Run::quiet(u.cancel);
        let outcome =
            crate::ops::servo::provision::provision_next(u.dev, plan, &mut u.provision, &mut run);
        let mut r = Record::start(RunKind::Provision, name, None, &u.dev.profile.id);
        runs::provision_into(&mut r, &outcome, &Given::default(), &started);
        if u.unit.serial.is_none() {
            u.unit.serial.clone_from(&r.unit.serial);
            u.unit.serial_source = r.unit.serial_source;
            u.unit.firmware.clone_from(&r.unit.firmware);
            u.unit.hardware.clone_from(&r.unit.hardware);
        }
        let done = Done::of_record(r, |_| match &outcome.result {
            crate::ops::servo::provision::Outcome::Fail { step, reason } => {
                Some(Reason::Provision {
                    step: step.clone(),
                    why: reason.clone(),
                })
            }
            // The port went: the runner says `link lost during <step>`, not the unit failing.
            crate::ops::servo::provision::Outcome::LinkLost { .. } => Some(Reason::LinkLost),
            crate::ops::servo::provision::Outcome::Pass => None,
        });
        all.extend(done.records);
        if done.failure.is_some() {
            failure = done.failure;
            break;
        }
    }
    if all.is_empty() {
        return Done::one(
            name,
            "Provision",
            clock,
            Some(Reason::NoServo),
            String::new(),
        );
    }
    Done {
        records: all,
        failure,
    }
}

fn tuya_status(u: &UnitRun<'_>, name: &str, clock: &StepClock) -> Done {
    match crate::ops::tuya::query_status(u.dev) {
        Ok(s) if s.complete() => Done::one(
            name,
            "TuyaStatus",
            clock,
            None,
            format!("{} data points reported", s.data_points.len()),
        ),
        Ok(s) => {
            let missing: Vec<String> = s.missing.iter().map(u8::to_string).collect();
            let suspect: Vec<String> = s.suspect().iter().map(|d| d.id.to_string()).collect();
            Done::one(
                name,
                "TuyaStatus",
                clock,
                Some(Reason::DataPointsMissing),
                format!(
                    "missing [{}], impossible [{}]",
                    missing.join(", "),
                    suspect.join(", ")
                ),
            )
        }
        Err(e) => Done::one(
            name,
            "TuyaStatus",
            clock,
            Some(Reason::of_error(&e)),
            e.to_string(),
        ),
    }
}

fn write_result(u: &UnitRun<'_>, name: &str, clock: &StepClock) -> Done {
    let Some(set) = u.dev.profile.command("MSP_SET_AUTO_TEST_RESULT") else {
        return Done::one(
            name,
            "WriteResult",
            clock,
            Some(Reason::NoResultCommand),
            String::new(),
        );
    };
    let value = if u.pass_so_far { "1" } else { "0" };
    let inputs = [(
        "result".to_string(),
        crate::profile::Input::Text(value.into()),
    )];
    match crate::ops::exchange::write_verified(u.dev, set, &inputs) {
        Ok(checks) if !checks.is_empty() && checks.iter().all(crate::ops::Check::ok) => Done::one(
            name,
            "WriteResult",
            clock,
            None,
            format!("result {value} written, read back {value}"),
        ),
        Ok(checks) => Done::one(
            name,
            "WriteResult",
            clock,
            Some(Reason::ReadBackDiffers { fields: Vec::new() }),
            format!("{checks:?}"),
        ),
        Err(e) => Done::one(
            name,
            "WriteResult",
            clock,
            Some(Reason::of_error(&e)),
            e.to_string(),
        ),
    }
}
