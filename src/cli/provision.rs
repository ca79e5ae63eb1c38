//! `botbench servo provision PLAN`: production provisioning, one fresh servo after another, with
//! a PASS or FAIL line for each (NO VERDICT when the port went away during a step: the run ends
//! there, exit 1 as a self-test's) and a CSV log.

use super::port::PortArgs;
use super::{CliError, CliResult};
use crate::link::Client;
use crate::ops::servo::provision::{self as ops, Outcome, Plan, ProvisionState, Record};
use crate::ops::servo::{self as servo_ops, Presence};
use crate::ops::{Device, Progress, Run};
use crate::profile::{Profile, Protocol};
use std::path::Path;
use std::time::Duration;

pub(crate) fn run(
    port: &PortArgs,
    plan_path: &Path,
    log: Option<&Path>,
    count: u32,
    wait_ms: Option<u64>,
    rec: &super::records::RecordArgs,
) -> CliResult {
    // Everything that can be checked is checked before the port is opened (--count and
    // --wait-ms by their parsers).
    let profile = port.profile("servo", Protocol::Servo)?;
    let plan = Plan::load(plan_path, &profile).map_err(CliError::input)?;
    if let Some(log) = log {
        ops::check_log(log, &plan.record).map_err(CliError::input)?;
    }
    let mut recorder = rec.open(port.json)?;
    let given = rec.given(Some(plan_path));
    let link = port.open_with(profile.clone(), false)?;
    let client = link.client();
    let cancel = super::port::cancel_on_ctrl_c();
    let mut state = ProvisionState::new();
    let (mut passed, mut failed, mut lost) = (0u32, 0u32, 0u32);
    let mut last: Option<Record> = None;
    for n in 1..=count {
        if let Some(prev) = &last {
            let tally = Tally {
                n,
                count,
                passed,
                failed,
            };
            let waiting = Waiting {
                client: &client,
                profile: &profile,
                port: port.path().ok(),
                cancel: &cancel,
            };
            let go_on = next_servo(&waiting, prev, wait_ms, &tally)?;
            if !go_on {
                errln!("botbench: stopped by the operator (q) before servo {n} of {count}");
                break;
            }
        }
        let mut run = Run::new(&cancel, |p: Progress| {
            if !port.json {
                errln!("  {}", p.message.en);
            }
        });
        let recorded = crate::ops::records::runs::provision(
            Device::new(&client, &profile),
            &plan,
            &mut state,
            &given,
            &mut run,
            &mut recorder,
            log,
        );
        let record = recorded.outcome;
        match &record.result {
            Outcome::Pass => passed += 1,
            Outcome::Fail { .. } => failed += 1,
            Outcome::LinkLost { .. } => lost += 1,
        }
        if let Some(serial) = &recorded.record.unit.serial {
            say_earlier(&mut recorder, &profile.id, serial, &recorded.record.uuid);
        }
        print_record(&record, n, count, plan.params.len(), port.json);
        let kept = super::records::say_kept(&recorded.kept, port.json);
        if let Some(Err(e)) = recorded.export {
            let e = format!(
                "the servo was not logged: cannot append to {}: {e}",
                log.map(|p| p.display().to_string()).unwrap_or_default()
            );
            // The exit code names who failed: a failed servo (or its lost link) first, else the
            // log.
            return Err(if failed > 0 || lost > 0 {
                CliError::device(e)
            } else {
                CliError::input(e)
            });
        }
        kept?;
        // A cancel that came after the last servo's last step cancelled nothing.
        if cancel.is_cancelled() && (!record.result.is_pass() || n < count) {
            return Err(cancelled_provisioning(&record, n, count));
        }
        if record.result.link_lost().is_some() {
            // The port is gone: no further servo can be provisioned on it.
            if n < count {
                errln!("botbench: servos {} to {count} not provisioned", n + 1);
            }
            break;
        }
        last = Some(record);
    }
    if !port.json && count > 1 {
        match lost {
            0 => outln!("{passed} PASS, {failed} FAIL"),
            _ => outln!("{passed} PASS, {failed} FAIL, {lost} NO VERDICT"),
        }
    }
    // As the self-test: a run with no verdict (the link lost) exits 1, as a failure does.
    Ok(u8::from(failed > 0 || lost > 0))
}

/// Provisioning the operator cancelled (Ctrl-C) during servo `n` of `count`: `cancelled after
/// N of M servos`, what was written to servo `n` (each value with what it held before) and
/// what was not, exit 130.
fn cancelled_provisioning(record: &Record, n: u32, count: u32) -> CliError {
    let written: Vec<String> = record
        .writes
        .iter()
        .map(|(_, w)| match &w.before {
            Some(before) => format!("{} = {} (was {before})", w.name, w.value),
            None => format!("{} = {}", w.name, w.value),
        })
        .collect();
    let written = if written.is_empty() {
        "nothing".to_string()
    } else {
        written.join(", ")
    };
    let (done, this) = match &record.result {
        Outcome::Pass => (n, format!("servo {n} provisioned whole")),
        Outcome::Fail { step, .. } | Outcome::LinkLost { step, .. } => (
            n - 1,
            format!(
                "servo {n} stopped at {step}, written to it: {written}; not done: the rest of its plan"
            ),
        ),
    };
    let rest = if n < count {
        format!("; servos {} to {count} not provisioned", n + 1)
    } else {
        String::new()
    };
    CliError {
        code: super::port::EXIT_CANCELLED,
        message: format!("cancelled after {done} of {count} servos: {this}{rest}"),
    }
}

/// Says what the records held of this servo before this run (its serial is read during the
/// run, so this comes with its verdict): `servo serial 1234: already tested 2 times, last: ...`.
fn say_earlier(
    recorder: &mut crate::ops::records::Recorder,
    profile: &str,
    serial: &str,
    this: &str,
) {
    let mut found = None;
    let _ = recorder.store().read(&mut |db| {
        let filter = crate::ops::records::Filter {
            serial: Some(serial.to_string()),
            ..Default::default()
        };
        let (cond, mut params) = filter.sql("");
        params.push(crate::ops::records::sql::Val::text_of(this));
        params.push(crate::ops::records::sql::Val::text_of(profile));
        let n = params.len();
        let rows = db.rows(
            &format!(
                "SELECT COUNT(*) FROM runs WHERE {cond} AND uuid <> ?{} AND profile = ?{n}",
                n - 1
            ),
            &params,
        )?;
        found = rows.first().and_then(|r| r.first()).and_then(|v| v.int());
        Ok(())
    });
    if let Some(earlier) = found.filter(|n| *n > 0) {
        // On stderr: stdout keeps one verdict line per servo for the scripts that read it.
        errln!("botbench: servo serial {serial}: provisioned {earlier} time(s) before this run");
    }
}

/// Where a run of `count` servos stands before servo `n`.
#[derive(Clone, Copy)]
struct Tally {
    n: u32,
    count: u32,
    passed: u32,
    failed: u32,
}

/// Waits for servo `n` after `prev`: a new fresh servo looked for every `wait_ms`, or the
/// operator's Enter. False when the operator stops (q); an error when the wait is cancelled
/// (exit 130), the link is lost (1) or nobody can answer (stdin closed: 2).
fn next_servo(
    waiting: &Waiting<'_>,
    prev: &Record,
    wait_ms: Option<u64>,
    tally: &Tally,
) -> Result<bool, CliError> {
    let Tally {
        n,
        count,
        passed,
        failed,
    } = *tally;
    let Some(ms) = wait_ms else {
        return match prompt(n, count) {
            Swap::Go => Ok(true),
            Swap::Quit => Ok(false),
            Swap::Closed => Err(CliError::input(format!(
                "stdin is closed before servo {n} of {count}: no operator to press Enter; \
                 {passed} PASS, {failed} FAIL, servos {n} to {count} not provisioned (--wait-ms \
                 MS looks for each new servo without an operator)"
            ))),
        };
    };
    errln!("Swap the servo: waiting for a new fresh servo (id 0) for servo {n} of {count}…");
    match wait_for_new(waiting, prev.serial, Duration::from_millis(ms)) {
        Waited::New => Ok(true),
        Waited::Cancelled => Err(CliError {
            code: super::port::EXIT_CANCELLED,
            message: format!(
                "cancelled after {} of {count} servos, while waiting for servo {n}: {passed} \
                 PASS, {failed} FAIL; servos {n} to {count} not provisioned",
                n - 1
            ),
        }),
        Waited::Lost(reason) => Err(CliError::device(format!(
            "link lost while waiting for servo {n} of {count}: {reason}; {passed} PASS, \
             {failed} FAIL"
        ))),
    }
}

/// What the operator answered when asked to swap the servo.
enum Swap {
    /// Enter: the next servo is plugged in.
    Go,
    /// q: stop here.
    Quit,
    /// Nobody can answer: stdin is closed (or unreadable).
    Closed,
}

/// Asks the operator to swap the servo.
fn prompt(n: u32, count: u32) -> Swap {
    errln!(
        "Swap the servo: plug in servo {n} of {count} (fresh, id 0), then press Enter (q then Enter to stop)."
    );
    let mut line = String::new();
    match super::console::read_line(&mut line) {
        Ok(0) | Err(_) => Swap::Closed,
        Ok(_) if line.trim().eq_ignore_ascii_case("q") => Swap::Quit,
        Ok(_) => Swap::Go,
    }
}

/// How a wait for the next servo ended.
enum Waited {
    /// A new fresh servo answers.
    New,
    /// The operator pressed Ctrl-C.
    Cancelled,
    /// The port went away (why).
    Lost(String),
}

/// What a wait between servos works with: the link, its profile, the port's path (to see it
/// go while nothing is exchanged; `None` for a built-in simulator) and the operator's Ctrl-C.
struct Waiting<'a> {
    client: &'a Client,
    profile: &'a Profile,
    port: Option<&'a str>,
    cancel: &'a crate::ops::Cancel,
}

impl Waiting<'_> {
    /// Why the port is gone (unplugged, renamed after a replug, taken by brltty), when its
    /// device node is: the link itself hears of it only at its next exchange.
    fn port_gone(&self) -> Option<String> {
        let path = self.port?;
        if std::path::Path::new(path).exists() {
            return None;
        }
        Some(crate::system::vanished(path, None).unwrap_or_else(|| format!("{path} is gone")))
    }
}

/// How often a wait between servos looks at the cancel flag and for its port.
const WAIT_SLICE: Duration = Duration::from_millis(20);

/// Sleeps `every`, in slices that look at the cancel flag and for the port: `None` when the
/// whole time passed, else how it ended.
fn nap(every: Duration, waiting: &Waiting<'_>) -> Option<Waited> {
    let until = std::time::Instant::now() + every;
    loop {
        if waiting.cancel.is_cancelled() {
            return Some(Waited::Cancelled);
        }
        if let Some(why) = waiting.port_gone() {
            return Some(Waited::Lost(why));
        }
        let left = until.saturating_duration_since(std::time::Instant::now());
        if left.is_zero() {
            return None;
        }
        std::thread::sleep(left.min(WAIT_SLICE));
    }
}

/// Waits until one fresh servo answers whose serial number is not `previous` (when the previous
/// servo's serial is unknown, until the bus has held no fresh servo once), polling every
/// `every`; leaves at once on Ctrl-C or when the port is gone.
fn wait_for_new(waiting: &Waiting<'_>, previous: Option<u32>, every: Duration) -> Waited {
    let Waiting {
        client, profile, ..
    } = *waiting;
    let serial = profile.serial_number_param();
    let bauds = profile.servo_bauds();
    let mut emptied = previous.is_some();
    loop {
        if let Some(ended) = nap(every, waiting) {
            return ended;
        }
        let found = match ops::find_fresh(Device::new(client, profile), &bauds) {
            Ok(found) => found,
            // A port that went (in the exchange or at a baud switch) ends the wait at once.
            Err(e) => match e.lost_port() {
                Some(why) => return Waited::Lost(why.to_string()),
                None if e.is_cancel() => return Waited::Cancelled,
                None => continue,
            },
        };
        match found.as_slice() {
            [] => emptied = true,
            [(baud, Presence::Present)] if emptied => {
                let Some(param) = serial else {
                    return Waited::New;
                };
                if client.set_baud(*baud).is_err() {
                    continue;
                }
                let fresh = servo_ops::factory_location(profile).id;
                match servo_ops::read_param(Device::new(client, profile), fresh, param) {
                    Ok(s) if previous.is_some_and(|p| i64::from(p) == s) => {}
                    Ok(_) => return Waited::New,
                    Err(_) => {}
                }
            }
            _ => {}
        }
    }
}

fn print_record(r: &Record, n: u32, count: u32, params: usize, json: bool) {
    if json {
        match serde_json::to_string(r) {
            Ok(s) => outln!("{s}"),
            Err(e) => errln!("botbench: cannot print the record as JSON: {e}"),
        }
        return;
    }
    let opt = |v: Option<String>| v.unwrap_or_else(|| "?".into());
    let serial = opt(r.serial.map(|s| s.to_string()));
    let recorded: Vec<String> = r
        .recorded
        .iter()
        .map(|(k, v)| format!("{k}={}", v.as_deref().unwrap_or("?")))
        .collect();
    match &r.result {
        Outcome::Pass => outln!(
            "==== PASS ==== servo {n}/{count}  serial {serial}  id {}  {} baud  {params} params verified  {}",
            opt(r.id.map(|i| i.to_string())),
            opt(r.baud.map(|b| b.to_string())),
            recorded.join(" ")
        ),
        Outcome::Fail { step, reason } => {
            outln!(
                "#### FAIL #### servo {n}/{count}  serial {serial}  id {}  baud {}  at step \"{step}\": {reason}",
                opt(r.id.map(|i| i.to_string())),
                opt(r.baud.map(|b| b.to_string())),
            );
            for m in &r.mismatches {
                outln!("               mismatch: {m}");
            }
        }
        Outcome::LinkLost { step, reason } => outln!(
            "NO VERDICT: link lost during {step}: {reason} (servo {n}/{count}  serial {serial}  id {}  baud {}); nothing is known of its steps not done: provision this servo again",
            opt(r.id.map(|i| i.to_string())),
            opt(r.baud.map(|b| b.to_string())),
        ),
    }
}
