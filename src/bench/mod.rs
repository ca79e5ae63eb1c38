//! `botbench bench`: end-to-end speed through real pseudo-terminals against the simulators,
//! reported against the wire limit (the time the bytes themselves take at the port's baud rate).
//! Run it on a release build: `cargo run --release -- bench --json`.

mod adapter;
mod field;
mod records;
mod station;
mod tuya;

pub use field::{ScanRuns, field_scans};
pub use tuya::{tuya_dp_report, tuya_handshake, tuya_ota};

use crate::link::{Link, LinkCommand, LinkEvent, LinkOptions, Poll, Request, serial, wire_time};
use crate::ops::Cancel;
use crate::ops::servo::provision;
use crate::ops::servo::{self, ScanPlan};
use crate::ops::{Device, Progress, Run};
use crate::profile::{Profile, Registry};
use crate::sim::servo_bus::{ServoBus, SimServo};
use crate::sim::window_cleaner::WindowCleaner;
use crate::sim::{Faults, PtyServer, SharedDevice, SimOptions};
use serde::Serialize;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// One measurement.
#[derive(Debug, Clone, Serialize)]
pub struct Figure {
    /// What was measured.
    pub name: String,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Seconds the bytes alone take on the wire.
    pub wire_seconds: f64,
    /// wire_seconds / seconds: 1.0 is the wire limit.
    pub wire_ratio: f64,
    /// Other numbers (a limit the issue sets, a rate, the vendor SDK's time).
    pub notes: String,
    /// A figure of repeated runs (the field scan): what they came to; `seconds` is their median.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub runs: Option<ScanRuns>,
    /// Whether the figure met the target its issue set (`notes` says which, ending `met` or
    /// `NOT met`); `None` for a figure without one (the handshakes).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub target_met: Option<bool>,
    /// Why the case could not be measured (a simulator that did not start, a run that
    /// failed); `None` for a figure measured. The other cases still run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub failed: Option<String>,
}

impl Figure {
    fn new(name: &str, seconds: f64, wire_seconds: f64, notes: String) -> Self {
        Self {
            name: name.to_string(),
            seconds,
            wire_seconds,
            wire_ratio: if seconds > 0.0 {
                wire_seconds / seconds
            } else {
                0.0
            },
            notes,
            runs: None,
            target_met: None,
            failed: None,
        }
    }

    /// The case `name` could not be measured: `why`.
    fn failed(name: &str, why: String) -> Self {
        let mut f = Self::new(name, 0.0, 0.0, format!("FAILED: {why}"));
        f.target_met = Some(false);
        f.failed = Some(why);
        f
    }

    /// Held to at most `max` seconds: says `target ≤ MAX ms: met` (or `NOT met`) in the notes.
    fn at_most_seconds(self, max: f64) -> Self {
        let met = self.seconds <= max;
        self.judged(format!("target ≤ {}", ms(max)), met)
    }

    /// Held to at least `min` of the wire limit (wire seconds / seconds).
    fn at_least_ratio(self, min: f64) -> Self {
        let met = self.wire_ratio >= min;
        self.judged(format!("target ≥ {min:.2} of the wire limit"), met)
    }

    fn judged(mut self, target: String, met: bool) -> Self {
        self.target_met = Some(met);
        self.notes = format!(
            "{}; {target}: {}",
            self.notes,
            if met { "met" } else { "NOT met" }
        );
        self
    }
}

/// A time in seconds as every figure says it: in ms (`12.34 ms`, `2044 ms`), the same
/// convention as the bench's columns.
pub fn ms(seconds: f64) -> String {
    let ms = seconds * 1e3;
    if ms < 100.0 {
        format!("{ms:.2} ms")
    } else {
        format!("{ms:.0} ms")
    }
}

fn profile(name: &str) -> Result<Arc<Profile>, String> {
    Registry::builtin()
        .and_then(|r| r.get(name))
        .map_err(|e| e.to_string())
}

fn open(
    server: &PtyServer,
    profile: Arc<Profile>,
    baud: u32,
    options: LinkOptions,
) -> Result<Link, String> {
    Link::open(serial::opener(server.path(), baud), profile, options, None)
        .map_err(|e| e.to_string())
}

/// Polls the window cleaner's attitude as fast as the wire allows for `secs`, with up to
/// `pipeline` requests in flight.
pub fn msp_polling(secs: f64, pipeline: usize) -> Result<Figure, String> {
    let p = profile("window-cleaner")?;
    let wc: SharedDevice = Arc::new(Mutex::new(WindowCleaner::new(&SimOptions::default())?));
    let server = PtyServer::start(wc, Faults::default()).map_err(|e| e.to_string())?;
    let opts = LinkOptions {
        start_session: false,
        poll_pipeline: pipeline,
        ..LinkOptions::default()
    };
    let link = open(&server, p.clone(), 115_200, opts)?;
    let attitude = p.command("MSP_ATTITUDE").ok_or("no MSP_ATTITUDE")?;
    let request = Request::for_command(&p, attitude, Vec::new()).attempts(1);
    link.send(LinkCommand::SetPolls(vec![Poll {
        request,
        interval: None,
    }]));
    let mut answers = 0u64;
    let mut first: Option<Instant> = None;
    let mut last = Instant::now();
    let end = Instant::now() + Duration::from_secs_f64(secs);
    while Instant::now() < end {
        if let Ok(LinkEvent::Telemetry {
            result: Ok(_), at, ..
        }) = link.events().recv_timeout(Duration::from_millis(100))
        {
            match first {
                None => first = Some(at),
                Some(_) => answers += 1,
            }
            last = at;
        }
    }
    let elapsed = first.map_or(0.0, |f| last.duration_since(f).as_secs_f64());
    // Request: FF opt dev cmd size crc = 6 bytes; reply: FF kind cmd size 6 data crc = 11.
    let per_poll = wire_time(6 + 11, 115_200).as_secs_f64();
    let (name, note) = if pipeline > 1 {
        (
            format!("msp attitude polling, 115200 baud, pty, {pipeline} requests in flight"),
            "above 1.0 because requests cross the line while answers come back (full duplex): \
             the answers' own bytes are then the limit, 17/11 = 1.55",
        )
    } else {
        (
            "msp attitude polling, 115200 baud, pty, one request at a time".to_string(),
            "each request waits for the last answer: the device's 0.1 ms latency caps it at 0.94",
        )
    };
    Ok(Figure::new(
        &name,
        elapsed,
        answers as f64 * per_poll,
        format!(
            "{answers} polls, {:.0} Hz; the wire limit: (request + reply bytes) × 10 bits / \
             baud a poll; {note}",
            answers as f64 / elapsed.max(1e-9)
        ),
    )
    .at_least_ratio(0.90))
}

fn servo_scan(
    name: &str,
    servos: Vec<SimServo>,
    bauds: Vec<u32>,
    limit_seconds: f64,
) -> Result<Figure, String> {
    let p = profile("servo")?;
    let bus: SharedDevice = Arc::new(Mutex::new(ServoBus::new(servos)));
    let server = PtyServer::start(bus, Faults::default()).map_err(|e| e.to_string())?;
    let link = open(&server, p.clone(), 115_200, LinkOptions::default())?;
    let plan = ScanPlan {
        ids: 0..=254,
        bauds: bauds.clone(),
        home_baud: 115_200,
    };
    let (report, secs) = timed_scan(&link, &p, &plan)?;
    let rows = report.rows;
    let sdk = 0.1 * 254.0 * bauds.len() as f64;
    Ok(Figure::new(
        name,
        secs,
        scan_wire(&plan, rows.len()),
        format!(
            "{} found; vendor SDK {} ({:.0}× faster)",
            rows.len(),
            ms(sdk),
            sdk / secs.max(1e-9)
        ),
    )
    .at_most_seconds(limit_seconds))
}

/// A scan of `plan` as the command line makes it, and how long it took, seconds.
fn timed_scan(
    link: &Link,
    profile: &Profile,
    plan: &ScanPlan,
) -> Result<(servo::ScanReport, f64), String> {
    let started = Instant::now();
    let report = servo::scan(
        Device::new(&link.client(), profile),
        plan,
        &mut Run::quiet(&Cancel::new()),
        &mut |_| {},
    )
    .map_err(|e| e.to_string())?;
    Ok((report, started.elapsed().as_secs_f64()))
}

/// The bytes' own time of a scan of `plan` that found `found` servos at the plan's home rate:
/// a 6-byte ping for each id at each rate, and for each servo found its 6-byte answer and the
/// reads of its details (7-byte request, about 9-byte answer each).
fn scan_wire(plan: &ScanPlan, found: usize) -> f64 {
    let ids = plan
        .ids
        .clone()
        .filter(|&i| i != crate::protocol::servo::BROADCAST_ID)
        .count() as f64;
    let pings: f64 = plan
        .bauds
        .iter()
        .map(|&b| wire_time(6, b).as_secs_f64() * ids)
        .sum();
    let details = (6 + servo::SCAN_ROLES.len() * (7 + 9)) * found;
    pings + wire_time(details, plan.home_baud).as_secs_f64()
}

/// Scans ids 0-254 at 115200 with no servo, and with ten.
pub fn servo_scans(all_bauds: bool) -> Result<Vec<Figure>, String> {
    let mut out = vec![
        servo_scan(
            "servo scan 0-254, 1 baud, none present",
            Vec::new(),
            vec![115_200],
            1.0,
        )?,
        servo_scan(
            "servo scan 0-254, 1 baud, 10 present",
            (0..10)
                .map(|i| SimServo::fresh(100 + i).with_id(i as u8 * 20 + 1))
                .collect(),
            vec![115_200],
            1.1,
        )?,
    ];
    if all_bauds {
        out.push(servo_scan(
            "servo scan 0-254, all 8 bauds, 10 present",
            (0..10)
                .map(|i| SimServo::fresh(100 + i).with_id(i as u8 * 20 + 1))
                .collect(),
            profile("servo")?.servo_bauds(),
            8.0,
        )?);
    }
    Ok(out)
}

/// Provisions one fresh servo found at 57600 baud (not the factory rate) with the example
/// 10-parameter plan: detect at every rate, id (with the whole-bus check), baud change to the
/// plan's 500000, 10 verified writes, the full read-back and the recorded parameters.
pub fn servo_provision() -> Result<Figure, String> {
    let p = profile("servo")?;
    let plan = provision::Plan::parse(
        "presets/servo-provision-plan.ron",
        include_str!("../../presets/servo-provision-plan.ron"),
        &p,
    )
    .map_err(|e| e.to_string())?;
    let found_at = 57_600;
    let bus = Arc::new(Mutex::new(ServoBus::new(vec![
        SimServo::fresh(1).with_baud(found_at),
    ])));
    let shared: SharedDevice = bus.clone();
    let server = PtyServer::start(shared, Faults::default()).map_err(|e| e.to_string())?;
    let link = open(&server, p.clone(), 115_200, LinkOptions::default())?;
    let started = Instant::now();
    let mut steps = StepTimes::new(started);
    let record = provision::provision_next(
        Device::new(&link.client(), &p),
        &plan,
        &mut provision::ProvisionState::new(),
        &mut Run::new(&Cancel::new(), |progress: Progress| {
            steps.at(&progress.message.en)
        }),
    );
    let secs = started.elapsed().as_secs_f64();
    steps.at("");
    if let provision::Outcome::Fail { step, reason } = &record.result {
        return Err(format!("servo provisioning failed at {step}: {reason}"));
    }
    // The bytes, roughly: id 0 pinged once at each rate the search asks before the servo
    // answers (its hint pass), then id 0 and the new id pinged twice at each of the 8 rates
    // (6 bytes each way; silent rates send only), and 12 pings answered where id 0 was found
    // (its answer latency measured); the whole-bus check before the id is written, 255 pings
    // at the rate found; at the plan's rate, each write (8 out, 6 back) and its read-back
    // (7 out, 8-10 back), then the 13 reads of the verification and the 3 recorded ones.
    let ping = |b: u32| wire_time(6, b).as_secs_f64();
    let order = provision::search_order(&p, plan.target_baud);
    let hints: f64 = order
        .iter()
        .take_while(|&&b| b != found_at)
        .map(|&b| ping(b))
        .sum::<f64>()
        + ping(found_at);
    let sweeps: f64 = p.servo_bauds().iter().map(|&b| 4.0 * ping(b)).sum();
    let reads = (plan.params.len() + 13 + plan.record.len()) as f64;
    let wire = hints
        + sweeps
        + 12.0 * 2.0 * ping(found_at)
        + 255.0 * ping(found_at)
        + plan.params.len() as f64 * wire_time(8 + 6, plan.target_baud).as_secs_f64()
        + reads * wire_time(7 + 9, plan.target_baud).as_secs_f64();
    Ok(Figure::new(
        "servo provision, found at 57600 → 500000, 10 params",
        secs,
        wire,
        steps.said(),
    )
    .at_most_seconds(2.0))
}

/// How long each step of an operation took, from its progress messages (`step: detail`; a
/// step's messages with different details count as one step).
struct StepTimes {
    /// The step under way and when it began.
    current: Option<(String, Instant)>,
    /// Each step's seconds, in the order the steps began.
    took: Vec<(String, f64)>,
    started: Instant,
}

impl StepTimes {
    fn new(started: Instant) -> Self {
        Self {
            current: None,
            took: Vec::new(),
            started,
        }
    }

    /// A progress message: `message`'s step begins now (an empty one, or "done", ends the last
    /// step).
    fn at(&mut self, message: &str) {
        let step = message.split(':').next().unwrap_or_default().to_string();
        let now = Instant::now();
        if self.current.as_ref().is_some_and(|(s, _)| *s == step) {
            return;
        }
        let since = self.current.as_ref().map_or(self.started, |(_, t)| *t);
        if let Some((s, _)) = self.current.take() {
            let secs = now.duration_since(since).as_secs_f64();
            match self.took.iter_mut().find(|(t, _)| *t == s) {
                Some((_, total)) => *total += secs,
                None => self.took.push((s, secs)),
            }
        }
        // The operation's last message ("done") ends its last step.
        if !step.is_empty() && step != "done" {
            self.current = Some((step, now));
        }
    }

    /// `detect 412 ms, read serial 4.00 ms, …`.
    fn said(&self) -> String {
        let each: Vec<String> = self
            .took
            .iter()
            .map(|(s, secs)| format!("{s} {}", ms(*secs)))
            .collect();
        each.join(", ")
    }
}

/// The cases [`run_all`] runs, by the names `bench --only` takes.
pub const CASES: [&str; 10] = [
    "msp-polling",
    "msp-bad-adapter",
    "servo-scan",
    "servo-field-scan",
    "servo-provision",
    "tuya-ota",
    "tuya-dp-report",
    "tuya-handshake",
    "records-report",
    "station",
];

/// Whether `only` (of `bench --only`) selects a case that runs (the field scan's with `field`
/// only); the error names the cases.
pub fn check_only(only: Option<&str>, field: bool) -> Result<(), String> {
    let Some(only) = only else {
        return Ok(());
    };
    if CASES
        .iter()
        .any(|c| c.contains(only) && (field || *c != "servo-field-scan"))
    {
        return Ok(());
    }
    Err(format!(
        "no bench case to run is named like '{only}'; the cases: {} (servo-field-scan with \
         --field only)",
        CASES.join(", ")
    ))
}

/// Everything, or the cases whose name (one of [`CASES`]) contains `only`; `long` adds the
/// 8-baud scan and the 9600-baud OTA (about 80 s), `field` the field scan's 340 runs
/// ([`field_scans`], stopped between runs by `cancel`). Errors when `only` names no case; a
/// case that fails is reported as a [`Figure`] with `failed` set, and the others still run.
pub fn run_all(
    long: bool,
    field: bool,
    only: Option<&str>,
    cancel: &Cancel,
    report: &mut dyn FnMut(&Figure),
) -> Result<Vec<Figure>, String> {
    check_only(only, field)?;
    let wanted = |case: &str| only.is_none_or(|o| case.contains(o));
    let one = |f: Result<Figure, String>| f.map(|f| vec![f]);
    let mut cases: Vec<Case> = vec![
        ("msp-polling", Box::new(|| one(msp_polling(3.0, 2)))),
        ("msp-polling", Box::new(|| one(msp_polling(3.0, 1)))),
        (
            "msp-bad-adapter",
            Box::new(|| adapter::bad_adapter_polling(5.0)),
        ),
        ("servo-scan", Box::new(move || servo_scans(long))),
    ];
    if field {
        cases.push(("servo-field-scan", Box::new(|| field_scans(cancel))));
    }
    cases.extend::<[Case; 8]>([
        ("servo-provision", Box::new(|| one(servo_provision()))),
        ("tuya-ota", Box::new(|| one(tuya_ota(115_200, 2)))),
        (
            "tuya-dp-report",
            Box::new(|| one(tuya_dp_report(115_200, 50))),
        ),
        ("tuya-dp-report", Box::new(|| one(tuya_dp_report(9600, 20)))),
        (
            "tuya-handshake",
            Box::new(|| one(tuya_handshake(9600, None))),
        ),
        (
            "tuya-handshake",
            Box::new(|| one(tuya_handshake(9600, Some(Duration::from_millis(30))))),
        ),
        ("records-report", Box::new(records::records_report)),
        ("station", Box::new(station::station_figures)),
    ]);
    if long {
        cases.push(("tuya-ota", Box::new(|| one(tuya_ota(9600, 2)))));
    }
    cases.retain(|(name, _)| wanted(name));
    Ok(run_each(cases, report))
}

/// What one run of a case gives: its figures, or why it could not be measured.
type CaseResult = Result<Vec<Figure>, String>;
/// A case to run: its name (one of [`CASES`]) and the run that measures it.
type Case<'a> = (&'static str, Box<dyn FnOnce() -> CaseResult + 'a>);

/// Runs `cases` in order, each figure given to `report` as its case ends. A case that fails
/// is one [`Figure`] with `failed` set (named after the case, saying why), and the cases after
/// it still run.
fn run_each(cases: Vec<Case<'_>>, report: &mut dyn FnMut(&Figure)) -> Vec<Figure> {
    let mut out = Vec::new();
    for (name, run) in cases {
        let figures = run().unwrap_or_else(|why| vec![Figure::failed(name, why)]);
        for f in figures {
            report(&f);
            out.push(f);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_figure_says_whether_it_met_its_target() {
        let fast = Figure::new("scan", 0.68, 0.13, "0 found".into()).at_most_seconds(1.0);
        assert_eq!(fast.target_met, Some(true));
        assert!(
            fast.notes.ends_with("0 found; target ≤ 1000 ms: met"),
            "{}",
            fast.notes
        );
        let slow = Figure::new("dp", 0.00425, 0.00408, "mean".into()).at_most_seconds(0.00408);
        assert_eq!(slow.target_met, Some(false));
        assert!(
            slow.notes.ends_with("target ≤ 4.08 ms: NOT met"),
            "{}",
            slow.notes
        );
        let ratio = Figure::new("ota", 5.94, 5.79, "0 retries".into()).at_least_ratio(0.85);
        assert_eq!(ratio.target_met, Some(true));
        assert!(
            ratio
                .notes
                .ends_with("target ≥ 0.85 of the wire limit: met")
        );
        assert_eq!(
            Figure::new("handshake", 0.4, 0.39, String::new()).target_met,
            None
        );
    }

    #[test]
    fn a_case_that_fails_is_reported_failed_and_the_cases_after_it_still_run() {
        let measured = || Ok(vec![Figure::new("scan", 0.5, 0.4, String::new())]);
        let cases: Vec<Case> = vec![
            (
                "tuya-ota",
                Box::new(|| Err("the simulator did not start".into())),
            ),
            ("servo-scan", Box::new(measured)),
            ("station", Box::new(|| Err("slot 2 failed".into()))),
        ];
        let mut reported = Vec::new();
        let figures = run_each(cases, &mut |f| reported.push(f.name.clone()));
        assert_eq!(reported, ["tuya-ota", "scan", "station"], "each as it ends");
        let failed: Vec<Option<&str>> = figures.iter().map(|f| f.failed.as_deref()).collect();
        assert_eq!(
            failed,
            [
                Some("the simulator did not start"),
                None,
                Some("slot 2 failed")
            ]
        );
        assert_eq!(figures[0].target_met, Some(false));
        assert!(
            figures[0].notes.starts_with("FAILED: "),
            "{}",
            figures[0].notes
        );
    }

    #[test]
    fn step_times_take_a_steps_messages_as_one_step_and_done_ends_the_last() {
        let mut steps = StepTimes::new(Instant::now());
        for m in [
            "detect",
            "apply params: a",
            "apply params: b",
            "verify",
            "done",
        ] {
            steps.at(m);
        }
        steps.at("");
        let names: Vec<&str> = steps.took.iter().map(|(s, _)| s.as_str()).collect();
        assert_eq!(names, ["detect", "apply params", "verify"]);
        assert!(steps.said().starts_with("detect "), "{}", steps.said());
    }
}
