//! `botbench report`: first-pass and final yield per shift, station, slot and plan version, the
//! Pareto of failing steps, each measurement's histogram with Cpk, and drift, on the terminal,
//! as JSON, or as one self-contained HTML file.

use super::records::{FilterArgs, open_for_reading, read_error};
use super::{CliError, CliResult};
use crate::ops::records::report::{self, Query, Report, Shifts, Yield};
use clap::Args;
use std::path::PathBuf;

/// `botbench report`.
#[derive(Debug, Args)]
pub(crate) struct ReportArgs {
    /// Where records are read from (default: BOTBENCH_RECORDS, else this PC's file).
    #[arg(long, value_name = "FILE|URL")]
    records: Option<String>,
    #[command(flatten)]
    filter: FilterArgs,
    /// Shift starts, local time, HH:MM separated by commas; shifts are named A, B, C... from
    /// the first (default 06:00,14:00,22:00: A 06-14, B 14-22, C 22-06 counted on its first day).
    #[arg(long, value_name = "HH:MM,...", value_parser = Shifts::parse)]
    shifts: Option<Shifts>,
    /// Units per drift window, 2 to 10000 (default 50): drift is the means of the last three
    /// windows walking toward a limit.
    #[arg(long, value_name = "N", default_value_t = 50, value_parser = clap::value_parser!(u64).range(2..=10_000))]
    drift_window: u64,
    /// Also write the report as one HTML file with its plots inline (no script, no network).
    #[arg(long, value_name = "FILE")]
    html: Option<PathBuf>,
    /// Print the report as one JSON document.
    #[arg(long)]
    json: bool,
}

pub(crate) fn run(args: ReportArgs) -> CliResult {
    if let Some(path) = &args.html {
        crate::document::check_destination(path).map_err(CliError::input)?;
    }
    let mut recorder = open_for_reading(args.records.as_deref())?;
    let q = Query {
        filter: args.filter.filter(),
        shifts: args.shifts.clone().unwrap_or_default(),
        drift_window: args.drift_window as usize,
        bins: 20,
    };
    let mut r = report::of_store(recorder.store(), &q).map_err(read_error)?;
    r.waiting = recorder.waiting();
    if args.json {
        outln!("{}", serde_json::to_string(&r).unwrap_or_default());
    } else {
        print(&r, &args.filter.said());
    }
    if let Some(path) = &args.html {
        let page = report::html::page(&r, &args.filter.said());
        crate::document::write_atomic(path, page.as_bytes()).map_err(CliError::input)?;
        if !args.json {
            outln!("HTML report written to {}", path.display());
        }
    }
    Ok(0)
}

fn pct(x: f64) -> String {
    if x.is_finite() {
        format!("{:5.1} %", 100.0 * x)
    } else {
        "    – ".into()
    }
}

fn table(title: &str, rows: &[Yield]) {
    if rows.is_empty() {
        return;
    }
    outln!("\n{title}");
    outln!(
        "  {:<28} {:>7} {:>7} {:>10} {:>10}",
        "",
        "units",
        "runs",
        "first-pass",
        "final"
    );
    for y in rows {
        outln!(
            "  {:<28} {:>7} {:>7} {:>10} {:>10}",
            y.label(),
            y.units,
            y.runs,
            pct(y.fpy()),
            pct(y.final_yield())
        );
    }
}

/// The report on the terminal.
fn print(r: &Report, period: &str) {
    outln!("records: {}  ({period}; shifts {})", r.source, r.shifts);
    if r.waiting > 0 {
        outln!(
            "note: {} record(s) wait in this PC's spool and are not in this report",
            r.waiting
        );
    }
    for m in r.measurements.iter().filter(|m| m.drift.is_some()) {
        if let Some(d) = &m.drift {
            outln!(
                "DRIFT: {} walks toward its {} limit {} {}: means of the last 3 × {} units {:.4} → {:.4} → {:.4} (moved {:.1} σ, {:.1} σ left)",
                m.name,
                d.toward,
                d.limit,
                m.unit,
                d.window,
                d.means[0],
                d.means[1],
                d.means[2],
                d.moved_sigma,
                d.left_sigma
            );
        }
    }
    let o = &r.overall;
    outln!(
        "\n{} units, {} runs: first-pass yield {}, final yield {}",
        o.units,
        o.runs,
        pct(o.fpy()).trim(),
        pct(o.final_yield()).trim()
    );
    table("per shift", &r.by_shift);
    table("per station", &r.by_station);
    table("per slot", &r.by_slot);
    table("per plan version", &r.by_plan);
    if !r.pareto.is_empty() {
        outln!("\nfailing steps (Pareto)");
        for p in &r.pareto {
            outln!(
                "  {:<32} {:>7}  {}  cumulative {}",
                p.step,
                p.count,
                pct(p.share),
                pct(p.cumulative)
            );
        }
        outln!("\nfailing steps by reason");
        for c in &r.causes {
            outln!("  {:>7}  {}: {}", c.count, c.step, c.reason);
        }
    }
    if !r.measurements.is_empty() {
        outln!("\nmeasurements");
        outln!(
            "  {:<28} {:>6} {:>10} {:>10} {:>7} {:>10} {:>10} {:>6}  drift",
            "",
            "n",
            "low",
            "high",
            "failed",
            "mean",
            "sigma",
            "Cpk"
        );
        for m in &r.measurements {
            let lim = |v: Option<f64>| v.map_or("–".to_string(), |x| format!("{x}"));
            outln!(
                "  {:<28} {:>6} {:>10} {:>10} {:>7} {:>10.4} {:>10.4} {:>6}  {}",
                if m.unit.is_empty() {
                    m.name.clone()
                } else {
                    format!("{} ({})", m.name, m.unit)
                },
                m.n,
                lim(m.low),
                lim(m.high),
                m.failed,
                m.mean,
                m.sigma,
                m.cpk.map_or("–".to_string(), |c| format!("{c:.2}")),
                m.drift
                    .as_ref()
                    .map_or("none".to_string(), |d| format!("toward {}", d.toward))
            );
        }
    }
}
