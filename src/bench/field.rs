//! The field scan (issue 11): a default `servo scan` of ids 0-254, the command line's code path
//! ([`servo::scan`] with the automatic margin, a new connection each run), on the simulated bus
//! with servos 0, 1 and 5 (half-duplex, as `botbench sim servo-bus --servos 0,1,5` serves it),
//! 20 runs of each case: no adapter latency; behind a USB adapter with a 16 ms latency timer;
//! and that again with two CPU-bound processes beside it.

use super::{Figure, open, profile, scan_wire, timed_scan};
use crate::link::LinkOptions;
use crate::ops::servo::{Presence, ScanPlan};
use crate::sim::{Faults, Line, PtyServer, SimKind, SimOptions};
use serde::Serialize;
use std::time::Duration;

/// The servos on the simulated bus.
const SERVOS: [u8; 3] = [0, 1, 5];
/// Scans a case.
const RUNS: usize = 20;

/// One case of the field scan.
struct Case {
    name: &'static str,
    /// The simulated adapter's latency timer.
    latency_timer: Option<Duration>,
    /// CPU-bound processes running beside the scan.
    busy: usize,
    /// The limit on each run, seconds.
    target: Option<f64>,
}

const CASES: [Case; 3] = [
    Case {
        name: "field scan 0-254, servos 0 1 5, no adapter latency",
        latency_timer: None,
        busy: 0,
        target: Some(0.6),
    },
    Case {
        name: "field scan 0-254, servos 0 1 5, 16 ms latency-timer adapter",
        latency_timer: Some(Duration::from_millis(16)),
        busy: 0,
        target: Some(1.0),
    },
    Case {
        name: "field scan 0-254, servos 0 1 5, 16 ms adapter, 2 CPU-bound processes",
        latency_timer: Some(Duration::from_millis(16)),
        busy: 2,
        target: None,
    },
];

/// What the runs of one case came to (`botbench bench --json` gives it as the figure's `runs`).
#[derive(Debug, Clone, Serialize)]
pub struct ScanRuns {
    /// Scans made.
    pub runs: usize,
    /// Scans that found every servo on the bus (all three present, nothing else).
    pub found_all: usize,
    /// The median scan, seconds (from the scan's start to its report, as the command line
    /// times it).
    pub median_seconds: f64,
    /// The longest scan, seconds.
    pub max_seconds: f64,
    /// The limit on each scan, seconds, where it sets one.
    pub target_seconds: Option<f64>,
    /// Whether every scan kept that limit.
    pub target_met: Option<bool>,
    /// The least automatic margin a scan ended with, ms.
    pub margin_ms_min: f64,
    /// The most.
    pub margin_ms_max: f64,
    /// Ids asked again, over all runs.
    pub asked_again_total: usize,
    /// Most ids asked again in one run.
    pub asked_again_max: usize,
    /// Answers that came after their window, over all runs (each still counted for its id).
    pub late_answers_total: usize,
    /// Most late answers in one run.
    pub late_answers_max: usize,
    /// The simulated adapter's latency timer, ms (none: bytes reach the host as they arrive).
    pub latency_timer_ms: Option<u64>,
    /// CPU-bound processes (`sh -c 'while :; do :; done'`) running beside the scans.
    pub busy_processes: usize,
}

/// CPU-bound processes, killed when dropped.
struct Busy(Vec<std::process::Child>);

impl Busy {
    /// Starts `n` shell loops that never sleep.
    fn start(n: usize) -> Result<Self, String> {
        let mut busy = Busy(Vec::new());
        for _ in 0..n {
            let child = std::process::Command::new("sh")
                .args(["-c", "while :; do :; done"])
                .stdin(std::process::Stdio::null())
                .stdout(std::process::Stdio::null())
                .spawn()
                .map_err(|e| format!("cannot start a CPU-bound `sh` loop: {e}"))?;
            busy.0.push(child);
        }
        Ok(busy)
    }
}

impl Drop for Busy {
    fn drop(&mut self) {
        for child in &mut self.0 {
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

/// The three cases, 20 scans each (about a minute).
pub fn field_scans() -> Result<Vec<Figure>, String> {
    CASES.iter().map(field_scan).collect()
}

fn field_scan(case: &Case) -> Result<Figure, String> {
    let p = profile("servo")?;
    let opts = SimOptions {
        servos: SERVOS.to_vec(),
        ..SimOptions::default()
    };
    let bus = crate::sim::build(SimKind::ServoBus, &opts)?;
    let faults = Faults {
        line: Line {
            latency_timer: case.latency_timer,
            half_duplex: true,
            ..Line::default()
        },
        ..Faults::default()
    };
    let server = PtyServer::start(bus, faults).map_err(|e| e.to_string())?;
    let _busy = Busy::start(case.busy)?;
    let plan = ScanPlan {
        ids: 0..=254,
        bauds: vec![p.baud],
        home_baud: p.baud,
    };
    // As `botbench servo --port P scan` opens its port: no --margin-ms, no reconnect.
    let options = LinkOptions {
        margin: None,
        reconnect: false,
        start_session: false,
        ..LinkOptions::default()
    };
    let mut secs = Vec::with_capacity(RUNS);
    let mut margins = Vec::with_capacity(RUNS);
    let (mut found_all, mut again, mut again_max, mut late, mut late_max) = (0, 0, 0, 0, 0);
    for _ in 0..RUNS {
        let link = open(&server, p.clone(), p.baud, options.clone())?;
        let (report, took) = timed_scan(&link, &p, &plan)?;
        secs.push(took);
        let found: Vec<(u8, &Presence)> = report.rows.iter().map(|r| (r.id, &r.presence)).collect();
        if found == SERVOS.map(|id| (id, &Presence::Present)) {
            found_all += 1;
        }
        margins.push(report.margin_ms);
        again += report.asked_again;
        again_max = again_max.max(report.asked_again);
        late += report.late_answers;
        late_max = late_max.max(report.late_answers);
    }
    secs.sort_by(f64::total_cmp);
    let median = (secs[(RUNS - 1) / 2] + secs[RUNS / 2]) / 2.0;
    let max = secs.last().copied().unwrap_or_default();
    let runs = ScanRuns {
        runs: RUNS,
        found_all,
        median_seconds: median,
        max_seconds: max,
        target_seconds: case.target,
        target_met: case.target.map(|t| max <= t),
        margin_ms_min: margins.iter().copied().fold(f64::INFINITY, f64::min),
        margin_ms_max: margins.iter().copied().fold(0.0, f64::max),
        asked_again_total: again,
        asked_again_max: again_max,
        late_answers_total: late,
        late_answers_max: late_max,
        latency_timer_ms: case.latency_timer.map(|l| l.as_millis() as u64),
        busy_processes: case.busy,
    };
    let target = match (runs.target_seconds, runs.target_met) {
        (Some(t), Some(true)) => format!("target {RUNS} of {RUNS}, each ≤ {t} s: met"),
        (Some(t), _) => format!("target {RUNS} of {RUNS}, each ≤ {t} s: NOT met"),
        _ => format!("target {RUNS} of {RUNS}"),
    };
    let notes = format!(
        "{found_all}/{RUNS} found 0, 1, 5; median {median:.3} s, max {max:.3} s; margin \
         {:.1}-{:.1} ms; asked again {again} (≤ {again_max} a run); late answers {late} \
         (≤ {late_max} a run); {target}",
        runs.margin_ms_min, runs.margin_ms_max
    );
    let mut figure = Figure::new(case.name, median, scan_wire(&plan, SERVOS.len()), notes);
    figure.runs = Some(runs);
    Ok(figure)
}
