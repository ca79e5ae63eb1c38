//! `botbench servo scan`: each servo's row printed as it is found, a progress bar (ids done,
//! servos found, time left) on a terminal and nothing on a pipe or with `--json`, and on
//! Ctrl-C the servos found before it, exit 130.

use super::CliResult;
use super::port::{EXIT_CANCELLED, op_error, silent_hint_after};
use crate::ops::servo::{self as ops, Presence, ScanPlan, ScanReport, ScanRow};
use crate::ops::{Cancel, Device, Progress, Run};
use crate::profile::Profile;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::cell::{Cell, RefCell};

/// The bar's look: ids done of all (ids × baud rates), servos found, time left.
const BAR_TEMPLATE: &str =
    "{spinner} {elapsed_precise} [{bar:30}] {pos}/{len} ids, {msg}, {eta} left";

/// Scans `plan` on `port` (its name, for the messages). Rows go to stdout as each servo is
/// found (text) or in one document at the end (`json`, with `"cancelled": true` when Ctrl-C
/// stopped it). Exit 0; 1 when no servo answered (unless `allow_empty`); 130 when cancelled,
/// after the servos found so far, with how far the scan got on stderr.
pub(super) fn run(
    dev: Device<'_>,
    plan: &ScanPlan,
    cancel: &Cancel,
    port: &str,
    allow_empty: bool,
    json: bool,
) -> CliResult {
    let profile = dev.profile;
    let bar = progress_bar(json);
    let started = std::time::Instant::now();
    let rows: RefCell<Vec<ScanRow>> = RefCell::new(Vec::new());
    let (done, total) = (Cell::new(0u64), Cell::new(0u64));
    let mut on_progress = |p: Progress| {
        done.set(p.done);
        total.set(p.total);
        if let Some(bar) = &bar {
            bar.set_length(p.total);
            bar.set_position(p.done);
        }
    };
    let mut on_found = |r: &ScanRow| {
        let mut rows = rows.borrow_mut();
        let first = rows.is_empty();
        rows.push(r.clone());
        if let Some(bar) = &bar {
            bar.set_message(format!("{} found", rows.len()));
        }
        if !json {
            let print = || {
                if first {
                    print_header();
                }
                print_row(profile, r);
            };
            match &bar {
                Some(bar) => bar.suspend(print),
                None => print(),
            }
        }
    };
    let result = ops::scan(
        dev,
        plan,
        &mut Run::new(cancel, &mut on_progress),
        &mut on_found,
    );
    if let Some(bar) = &bar {
        bar.finish_and_clear();
    }
    let seconds = started.elapsed().as_secs_f64();
    let found = rows.into_inner();
    let report = match result {
        Ok(report) => report,
        Err(e) if e.is_cancel() => {
            if json {
                print_json(profile, &found, None, seconds);
            }
            errln!(
                "botbench: scan cancelled after {} of {} ids: {} servo(s) found{}",
                done.get(),
                total.get(),
                found.len(),
                if json || found.is_empty() {
                    ""
                } else {
                    " (above)"
                }
            );
            return Ok(EXIT_CANCELLED);
        }
        Err(e) => return Err(op_error(e)),
    };
    if json {
        print_json(profile, &report.rows, Some(&report), seconds);
    } else {
        if found.is_empty() {
            print_header();
        }
        print_summary(&report, seconds);
    }
    if report.rows.is_empty() && !allow_empty {
        errln!(
            "botbench: no servo answered on {port} (ids {}-{}){}",
            plan.ids.start(),
            plan.ids.end(),
            silent_hint_after(report.host_late()),
        );
        return Ok(1);
    }
    // A scan that finds none exits 1 above, its checklist led by the loaded computer.
    if let Some(unsure) = report.unsure_said() {
        super::port::warn(&unsure.en);
    }
    Ok(0)
}

/// A bar on stderr when a person watches it (this process's own run, stderr a terminal, no
/// `--json`); `None` otherwise, so a pipe or a script gets no bar and no escape codes.
fn progress_bar(json: bool) -> Option<ProgressBar> {
    use std::io::IsTerminal;
    if json || !super::console::is_process() || !std::io::stderr().is_terminal() {
        return None;
    }
    let style = ProgressStyle::with_template(BAR_TEMPLATE)
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ");
    let bar = ProgressBar::with_draw_target(Some(0), ProgressDrawTarget::stderr())
        .with_style(style)
        .with_message("0 found");
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    Some(bar)
}

/// The scan's JSON document: each row as the scan has it (raw values) with its temperature as
/// the text view shows it (`temperature` is the raw reading: a thermistor's count on some
/// servos); with how it adapted when it ran to its end (`report`), `"cancelled": true` when not.
fn print_json(profile: &Profile, rows: &[ScanRow], report: Option<&ScanReport>, seconds: f64) {
    let servos: Vec<serde_json::Value> = rows
        .iter()
        .map(|r| {
            let mut row = serde_json::json!(r);
            row["temperature_text"] = serde_json::json!(r.temperature_text(profile));
            row
        })
        .collect();
    let doc = match report {
        Some(report) => serde_json::json!({
            "servos": servos,
            "seconds": seconds,
            "asked_again": report.asked_again,
            "late_answers": report.late_answers,
            "margin_ms": report.margin_ms,
            "host_late_ms": report.host_late_ms,
            "unsure": report.unsure,
            "asked_after_hold_up": report.asked_after_hold_up,
        }),
        None => serde_json::json!({
            "servos": servos,
            "seconds": seconds,
            "cancelled": true,
        }),
    };
    outln!("{doc}");
}

/// The table's header line.
fn print_header() {
    outln!(
        "{:>3} {:>7} {:>6} {:>8} {:>10} {:>8} {:>18} {:>6}  presence",
        "id",
        "baud",
        "type",
        "firmware",
        "serial",
        "mV",
        "temp",
        "status"
    );
}

/// One servo's line of the table ("-" for a detail not read).
fn print_row(profile: &Profile, r: &ScanRow) {
    let o = |v: Option<i64>| v.map_or("-".to_string(), |v| v.to_string());
    let presence = match &r.presence {
        Presence::Present => "ok".to_string(),
        Presence::PossibleDuplicate(e) => format!("possible duplicate id ({e})"),
        Presence::Absent => "absent".to_string(),
    };
    outln!(
        "{:>3} {:>7} {:>6} {:>8} {:>10} {:>8} {:>18} {:>6}  {presence}",
        r.id,
        r.baud,
        o(r.servo_type),
        o(r.firmware),
        o(r.serial),
        o(r.voltage_mv),
        r.temperature_text(profile),
        r.status_hex()
    );
}

/// How the scan adapted: ids asked again, late answers and the margin it ended with.
fn print_summary(report: &ScanReport, seconds: f64) {
    outln!(
        "{} found in {seconds:.2} s; {} id(s) asked again, {} late answer(s), margin {:.1} ms",
        report.rows.len(),
        report.asked_again,
        report.late_answers,
        report.margin_ms
    );
}
