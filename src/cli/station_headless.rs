//! `botbench station BUNDLE --headless [--json] [--once]`: the station without a window, for
//! automated lines. Events go to stdout (JSON lines with `--json`, else one line each); the
//! operator's side comes from stdin, one line each:
//!
//! - `start [SLOT]`: start SLOT (every slot when none is named);
//! - `yes` / `no` / `y` / `n` / a value / a scanned code: the answer to the oldest question
//!   waiting; `SLOT ANSWER` (`2 y`) answers that slot's; a code while a slot that starts by
//!   scan waits starts it;
//! - `stop [SLOT]`: STOP that slot, or every slot.
//!
//! A scanner that is its own device (`--scanner /dev/ttyACM0`) is read the same way, each
//! code a line.
//!
//! Ctrl-C stops every slot safely (exit 130, once each has said it stopped). `--once` runs one unit per slot and exits 0 when every slot
//! passed, 1 otherwise.

use super::station::StationArgs;
use super::{CliError, CliResult};
use crate::link::PortOpener;
use crate::ops::records::{Recorder, RunContext};
use crate::ops::station::{Answer, Bundle, Command, Event, SlotHandle, What};
use crate::sim::fixture::StartedStation;
use std::collections::VecDeque;
use std::sync::{Arc, Mutex};

/// Starts every slot of `bundle` ([`crate::sim::fixture::start_station`]), recording where
/// `--records`, else the bundle, says, as the operator `--operator` or `BOTBENCH_OPERATOR`.
/// With `once`, each slot ends after one unit.
pub(crate) fn start(
    bundle: &Bundle,
    args: &StationArgs,
    ports: &PortOpener,
    once: bool,
) -> Result<StartedStation, CliError> {
    let records = args.records.as_deref().or(bundle.records.as_deref());
    let location = super::records::location(records)?;
    let operator = args
        .operator
        .clone()
        .or_else(|| std::env::var("BOTBENCH_OPERATOR").ok());
    let context = RunContext {
        station: Some(bundle.id.clone()),
        operator: operator.clone(),
        bundle_sha256: Some(bundle.sha256.clone()),
        ..RunContext::default()
    };
    let recorder = Recorder::open_spooled(&location, context, args.spool.as_deref())
        .map_err(CliError::input)?;
    crate::sim::fixture::start_station(bundle, recorder, operator, ports, once)
        .map_err(CliError::device)
}

pub(crate) fn run(bundle: &Bundle, args: &StationArgs, ports: &PortOpener) -> CliResult {
    let StartedStation {
        slots,
        events: rx,
        forwarder,
        ..
    } = start(bundle, args, ports, args.once)?;
    say_start(bundle, args.json);
    let slots = Arc::new(slots);
    let routing: Arc<Mutex<Routing>> = Arc::default();
    spawn_stdin(slots.clone(), routing.clone(), bundle);
    if let Some(device) = &args.scanner {
        spawn_scanner(device, slots.clone(), routing.clone(), bundle)?;
    }
    let ctrl_c = super::port::cancel_on_ctrl_c();
    let (mut passed, mut failed) = (0usize, 0usize);
    let mut stopped = 0usize;
    while stopped < slots.len() {
        if ctrl_c.is_cancelled() {
            slots.iter().for_each(|s| s.cancel.cancel());
        }
        let Ok(ev) = rx.recv_timeout(std::time::Duration::from_millis(100)) else {
            continue;
        };
        track(&ev, &routing, &slots);
        match &ev.what {
            What::Verdict { pass: true, .. } => passed += 1,
            What::Verdict { pass: false, .. } => failed += 1,
            What::Stopped { .. } => stopped += 1,
            _ => {}
        }
        print_event(&ev, args.json);
    }
    forwarder.stop();
    let verdicts = passed + failed;
    if !args.json {
        outln!("{passed} PASS, {failed} FAIL");
    }
    if ctrl_c.is_cancelled() {
        // Every slot has stopped (each said so): a stop by Ctrl-C is never a success.
        errln!("botbench: station stopped by Ctrl-C; every slot stopped safely");
        return Ok(super::port::EXIT_CANCELLED);
    }
    Ok(u8::from(
        failed > 0 || (args.once && verdicts < slots.len()),
    ))
}

/// Who the operator's next line is for: the slots with a question waiting (oldest first), the
/// slots idle until a scan starts them, and lines typed ahead of any question (a `yes` given
/// before the Confirm is asked is its answer, as a keyboard's buffer keeps it).
#[derive(Default)]
struct Routing {
    asking: VecDeque<String>,
    scan_idle: Vec<String>,
    /// Lines typed before their question: for a slot (`2 y`), or for whichever asks first.
    typed_ahead: VecDeque<(Option<String>, String)>,
}

impl Routing {
    /// Takes the oldest line typed ahead for `slot` (named for it, or for whichever asks first).
    fn take_typed_for(&mut self, slot: &str) -> Option<String> {
        let i = self
            .typed_ahead
            .iter()
            .position(|(to, _)| to.as_deref().is_none_or(|to| to == slot))?;
        self.typed_ahead.remove(i).map(|(_, line)| line)
    }
}

/// Follows `ev`: a question waiting, answered, or a slot idle for a scan; a question gets
/// the oldest line typed ahead.
fn track(ev: &Event, routing: &Mutex<Routing>, slots: &[SlotHandle]) {
    let mut r = routing.lock().unwrap_or_else(|e| e.into_inner());
    match &ev.what {
        What::Ask { kind, .. } if *kind != "prompt" => match r.take_typed_for(&ev.slot) {
            Some(line) => send_answer(slots, &ev.slot, &line),
            None => r.asking.push_back(ev.slot.clone()),
        },
        What::Waiting { how: "scan" } => {
            // A code scanned before the slot was ready for it starts it now.
            match r.take_typed_for(&ev.slot) {
                Some(line) => send_answer(slots, &ev.slot, &line),
                None => r.scan_idle.push(ev.slot.clone()),
            }
        }
        What::Unit { .. } | What::StepDone { .. } | What::Verdict { .. } | What::Stopped { .. } => {
            r.asking.retain(|s| s != &ev.slot);
            r.scan_idle.retain(|s| s != &ev.slot);
        }
        _ => {}
    }
}

/// Gives slot `name` the answer `line`.
fn send_answer(slots: &[SlotHandle], name: &str, line: &str) {
    if let Some(s) = slots.iter().find(|s| s.name == name) {
        let _ = s.commands.try_send(Command::Answer(Answer::parse(line)));
    }
}

fn say_start(bundle: &Bundle, json: bool) {
    if json {
        outln!(
            "{}",
            serde_json::json!({"event": "station", "station": bundle.id,
                "bundle_sha256": bundle.sha256, "slots": bundle.slots.len()})
        );
    } else {
        outln!(
            "station {} ({} slots), bundle SHA-256 {}",
            bundle.id,
            bundle.slots.len(),
            bundle.sha256
        );
    }
}

fn print_event(ev: &Event, json: bool) {
    if json {
        match serde_json::to_string(ev) {
            Ok(s) => outln!("{s}"),
            Err(e) => errln!("botbench: cannot print an event as JSON: {e}"),
        }
        return;
    }
    let s = &ev.slot;
    match &ev.what {
        What::Port { present, detail } => outln!(
            "slot {s}: port {} {detail}",
            if *present { "open" } else { "MISSING" }
        ),
        What::Waiting { how } => outln!("slot {s}: waiting for a unit ({how})"),
        What::Unit { serial } => outln!(
            "slot {s}: unit {}",
            serial.as_deref().unwrap_or("(serial not yet known)")
        ),
        What::Step {
            index,
            of,
            name,
            attempt,
            ..
        } => {
            let retry = if *attempt > 1 { " (retry)" } else { "" };
            outln!("slot {s}: step {index}/{of} {name}{retry}")
        }
        What::Ask { kind, text, .. } => outln!("slot {s}: {kind}? {text}"),
        What::StepDone {
            name, pass, detail, ..
        } => outln!(
            "slot {s}: {name}: {} {detail}",
            if *pass { "PASS" } else { "FAIL" }
        ),
        What::Verdict {
            pass,
            serial,
            failed_step,
            reason,
            earlier_runs,
            kept,
            ..
        } => {
            let unit = serial.as_deref().unwrap_or("unit");
            if *pass {
                outln!("==== PASS ==== slot {s} {unit}");
            } else {
                outln!(
                    "#### FAIL #### slot {s} {unit} at {}: {}",
                    failed_step.as_deref().unwrap_or("?"),
                    reason
                        .as_ref()
                        .map_or_else(|| "?".into(), ToString::to_string)
                );
            }
            if let Some(n) = earlier_runs.filter(|n| *n > 0) {
                outln!("slot {s}: {unit} already tested {n} times");
            }
            outln!("slot {s}: {kept}");
        }
        What::Stopped { why } => outln!("slot {s}: stopped: {why}"),
        What::Lent { port } => outln!("slot {s}: {port} lent to the engineer view"),
        What::Records {
            waiting: 0, store, ..
        } => outln!("records: none waiting, every record is in {store}"),
        What::Records {
            waiting,
            store,
            why,
        } => outln!(
            "records: {waiting} waiting to be forwarded to {store}: {}",
            why.as_deref().unwrap_or("not yet sent")
        ),
    }
}

/// Reads the operator's lines on a thread of its own and hands them to the slots.
fn spawn_stdin(slots: Arc<Vec<SlotHandle>>, routing: Arc<Mutex<Routing>>, bundle: &Bundle) {
    let names: Vec<String> = bundle.slots.iter().map(|s| s.name.clone()).collect();
    let console = super::console::handle();
    let _ = std::thread::Builder::new()
        .name("station-stdin".into())
        .spawn(move || {
            super::console::scoped(console, || {
                let mut line = String::new();
                loop {
                    line.clear();
                    match super::console::read_line(&mut line) {
                        Ok(0) | Err(_) => return,
                        Ok(_) => operator_line(line.trim(), &slots, &routing, &names),
                    }
                }
            });
        });
}

/// Reads the codes of a scanner that is its own device (`--scanner`) on a thread of its own:
/// each line (ended by CR or LF) as if typed on stdin. Errors: the device cannot be opened
/// (said with its path; the slots, started already, are stopped).
fn spawn_scanner(
    device: &std::path::Path,
    slots: Arc<Vec<SlotHandle>>,
    routing: Arc<Mutex<Routing>>,
    bundle: &Bundle,
) -> Result<(), CliError> {
    use std::io::BufRead;
    let file = std::fs::File::open(device).map_err(|e| {
        slots.iter().for_each(|s| s.cancel.cancel());
        CliError::input(format!("--scanner {}: {e}", device.display()))
    })?;
    let names: Vec<String> = bundle.slots.iter().map(|s| s.name.clone()).collect();
    let shown = device.display().to_string();
    std::thread::Builder::new()
        .name("station-scanner".into())
        .spawn(move || {
            let mut reader = std::io::BufReader::new(file);
            let mut code = Vec::new();
            loop {
                code.clear();
                match reader.read_until(b'\n', &mut code) {
                    Ok(0) => return,
                    Ok(_) => {
                        // A scanner may end a code with CR, LF or both.
                        for part in code.split(|b| *b == b'\r') {
                            let line = String::from_utf8_lossy(part);
                            operator_line(line.trim(), &slots, &routing, &names);
                        }
                    }
                    Err(e) => {
                        log::warn!("scanner {shown}: {e}; its codes are no longer read");
                        return;
                    }
                }
            }
        })
        .map_err(|e| CliError::device(format!("the scanner's thread cannot start: {e}")))?;
    Ok(())
}

/// One line the operator typed or scanned.
fn operator_line(line: &str, slots: &[SlotHandle], routing: &Mutex<Routing>, names: &[String]) {
    if line.is_empty() {
        return;
    }
    let mut words = line.splitn(2, char::is_whitespace);
    let first = words.next().unwrap_or_default();
    let rest = words.next().map(str::trim).unwrap_or_default();
    let slot = |name: &str| slots.iter().find(|s| s.name == name);
    match first.to_ascii_lowercase().as_str() {
        "start" if rest.is_empty() => slots
            .iter()
            .for_each(|s| drop(s.commands.try_send(Command::Start))),
        "start" => {
            if let Some(s) = slot(rest) {
                let _ = s.commands.try_send(Command::Start);
            }
        }
        "stop" if rest.is_empty() => slots.iter().for_each(|s| s.cancel.cancel()),
        "stop" => {
            if let Some(s) = slot(rest) {
                s.cancel.cancel();
            }
        }
        _ if names.iter().any(|n| n == first) && !rest.is_empty() => {
            let mut r = routing.lock().unwrap_or_else(|e| e.into_inner());
            let asking = r.asking.iter().position(|s| s == first);
            let idle = r.scan_idle.iter().position(|s| s == first);
            if let Some(i) = asking {
                r.asking.remove(i);
            } else if let Some(i) = idle {
                r.scan_idle.remove(i);
            } else {
                r.typed_ahead
                    .push_back((Some(first.to_string()), rest.to_string()));
                return;
            }
            send_answer(slots, first, rest);
        }
        _ => {
            let mut r = routing.lock().unwrap_or_else(|e| e.into_inner());
            if let Some(name) = r.asking.pop_front() {
                send_answer(slots, &name, line);
            } else if !r.scan_idle.is_empty() {
                // A code with no question waiting starts the first slot idle for a scan.
                let name = r.scan_idle.remove(0);
                send_answer(slots, &name, line);
            } else {
                r.typed_ahead.push_back((None, line.to_string()));
            }
        }
    }
}
