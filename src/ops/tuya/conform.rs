//! `botbench tuya conform`: grades an MCU firmware against the Tuya serial protocol as a module
//! sees it (PROTOCOL_NOTES §3, TUYA_FIELD_NOTES): each check passes or fails with the bytes that
//! show why, and the firmware conforms when every mandatory check passes. Advisory checks say
//! what field modules cope with but a firmware should not do (another frame version, data
//! points the profile lacks, a status answer slower than a module's request timeout).
//!
//! The link is opened without the module's own session: conformance drives the start-up itself
//! (heartbeat, product info, working mode, Wi-Fi state, status query) so that each answer is
//! its own evidence. The MCU's own requests are still answered as a module does.

use super::{Expect, OtaTiming, ReportedDp, read_reports, reported_dps};
use crate::link::session::tuya::{parse_product_info, reported_ids};
use crate::link::{Client, ExchangeError, Match, Reply, ReplySpec, Request, Watch, Watched};
use crate::ops::{Device, OpError, Run};
use crate::packet::Packet;
use crate::profile::{Input, Profile};
use crate::protocol::hex;
use crate::protocol::tuya::cmd;
use crate::protocol::tuya::dp::DpType;
use serde::Serialize;
use std::time::{Duration, Instant};

/// A command no Tuya document defines from module to MCU: the SDK ignores it.
pub const UNKNOWN_COMMAND: u8 = 0x99;
/// How long a check waits for an answer that must not come (a refused write, a corrupted frame,
/// an unknown command): the module's request timeout (TUYA_FIELD_NOTES §9: 1 s).
const SILENCE: Duration = Duration::from_secs(1);
/// How long the line stays quiet before a status answer's trailing reports are taken as all.
const TRAIL: Duration = Duration::from_millis(300);
/// The longest any answer may take (TUYA_FIELD_NOTES §2, §5.2: the 5 s rule).
const ANSWER_LIMIT: Duration = Duration::from_secs(5);
/// The heartbeat answer's limit: after 3 s the module marks the MCU offline (§9).
const HEARTBEAT_LIMIT: Duration = Duration::from_secs(3);
/// A status query's reports should all come within the module's request timeout (§9).
const BURST_LIMIT: Duration = Duration::from_secs(1);
/// At most this much of a frame is kept as evidence.
const EVIDENCE_BYTES: usize = 48;

/// A check's outcome.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "UPPERCASE")]
pub enum Grade {
    /// The firmware did what the protocol asks.
    Pass,
    /// It did not.
    Fail,
    /// Not run (an optional check not asked for, or one that needs an earlier one).
    Skip,
}

impl Grade {
    /// `PASS`, `FAIL`, `SKIP`.
    pub fn word(self) -> &'static str {
        match self {
            Grade::Pass => "PASS",
            Grade::Fail => "FAIL",
            Grade::Skip => "SKIP",
        }
    }

    fn of(pass: bool) -> Self {
        if pass { Grade::Pass } else { Grade::Fail }
    }
}

/// One check's result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Check {
    /// Its id (`heartbeat`, `status_range`): the same in every report.
    pub id: &'static str,
    /// What it checks, as a person reads it.
    pub name: &'static str,
    /// Whether the firmware must pass it to conform.
    pub mandatory: bool,
    /// PASS, FAIL or SKIP.
    pub grade: Grade,
    /// What was seen, values included.
    pub detail: String,
    /// The frames that show it (hex, each cut at 48 bytes), `sent → received`.
    pub evidence: String,
    /// How long it took, ms.
    pub duration_ms: u64,
}

/// A firmware's grade.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Conformance {
    /// The checks, in the order run.
    pub checks: Vec<Check>,
    /// The product info's pid and version, when it gave them.
    pub pid: Option<String>,
    /// See `pid`.
    pub version: Option<String>,
    /// Seconds the whole run took.
    pub seconds: f64,
}

impl Conformance {
    /// Whether every mandatory check passed.
    pub fn pass(&self) -> bool {
        self.checks
            .iter()
            .all(|c| !c.mandatory || c.grade != Grade::Fail)
    }

    /// The checks that failed, mandatory first.
    pub fn failed(&self) -> Vec<&Check> {
        let mut f: Vec<&Check> = self
            .checks
            .iter()
            .filter(|c| c.grade == Grade::Fail)
            .collect();
        f.sort_by_key(|c| !c.mandatory);
        f
    }
}

/// What a conformance run does beyond the protocol checks.
#[derive(Debug, Clone, Default)]
pub struct Options {
    /// A firmware update to grade too: the image and the version it must bring.
    pub ota: Option<(Vec<u8>, Expect)>,
    /// The profile's OTA maximum (bytes).
    pub ota_max: u32,
}

/// The frames of an exchange as evidence: `sent → answer…` (or `→ no answer`).
fn evidence(sent: &[u8], got: &[Packet]) -> String {
    let cut = |b: &[u8]| {
        let mut s = hex::format(&b[..b.len().min(EVIDENCE_BYTES)]);
        if b.len() > EVIDENCE_BYTES {
            s.push_str(&format!(" … ({} bytes)", b.len()));
        }
        s
    };
    let answers: Vec<String> = got.iter().map(|p| cut(&p.wire)).collect();
    if answers.is_empty() {
        format!("{} → no answer", cut(sent))
    } else {
        format!("{} → {}", cut(sent), answers.join(" | "))
    }
}

/// The bytes a request puts on the wire (header 55 AA 00, command, length, data, checksum).
fn wire_of(request: &Request) -> Vec<u8> {
    let frame = crate::protocol::tuya::Frame {
        version: crate::protocol::tuya::VERSION_MODULE,
        command: request.command,
        data: request.payload.clone(),
    };
    let mut bytes = frame.encode().unwrap_or_default();
    if request.bad_checksum
        && let Some(last) = bytes.last_mut()
    {
        *last = last.wrapping_add(1);
    }
    bytes
}

/// A run under way: the client, what was learnt, the checks so far, the slowest answer.
struct Grader<'a> {
    client: &'a Client,
    profile: &'a Profile,
    watch: Watch,
    checks: Vec<Check>,
    slowest: (Duration, u8),
    refused: Vec<String>,
    each: &'a mut dyn FnMut(&Check),
}

impl Grader<'_> {
    /// Sends `request`: its answer (and its evidence), the slowest answer kept.
    fn ask(&mut self, request: Request) -> (Result<Reply, ExchangeError>, String) {
        let sent = wire_of(&request);
        let command = request.command;
        let result = self.client.request(request);
        let got = match &result {
            Ok(r) => {
                if r.rtt > self.slowest.0 {
                    self.slowest = (r.rtt, command);
                }
                r.packets.clone()
            }
            Err(_) => Vec::new(),
        };
        (result, evidence(&sent, &got))
    }

    fn record(&mut self, check: Check) {
        (self.each)(&check);
        self.checks.push(check);
    }

    /// Records a check that took from `started`.
    #[allow(clippy::too_many_arguments)]
    fn done(
        &mut self,
        id: &'static str,
        name: &'static str,
        mandatory: bool,
        pass: bool,
        detail: String,
        evidence: String,
        started: Instant,
    ) {
        let check = Check {
            id,
            name,
            mandatory,
            grade: Grade::of(pass),
            detail,
            evidence,
            duration_ms: u64::try_from(started.elapsed().as_millis()).unwrap_or(u64::MAX),
        };
        self.record(check);
    }

    fn skip(&mut self, id: &'static str, name: &'static str, mandatory: bool, why: &str) {
        self.record(Check {
            id,
            name,
            mandatory,
            grade: Grade::Skip,
            detail: why.to_string(),
            evidence: String::new(),
            duration_ms: 0,
        });
    }

    /// Takes what the watch saw: frames refused (kept for `frames_clean`), and the reports.
    fn take_watch(&mut self) -> Vec<Packet> {
        let mut reports = Vec::new();
        for w in self.watch.take() {
            match w {
                Watched::Report(p) => reports.push(p),
                Watched::Refused(e) => self.refused.push(e.to_string()),
                Watched::Tuya(_) => {}
            }
        }
        reports
    }
}

/// Grades the MCU on `dev` ([`Check`]s in the order of the module's start-up, then the
/// protocol's edges, then the optional update); `each` sees every check as it ends. Errors:
/// only a lost link or a cancel (then the checks so far are in the error's text).
pub fn conform(
    dev: Device<'_>,
    options: &Options,
    run: &mut Run<'_>,
    each: &mut dyn FnMut(&Check),
) -> Result<Conformance, OpError> {
    let started = Instant::now();
    let mut g = Grader {
        client: dev.client,
        profile: dev.profile,
        watch: dev.client.watch(),
        checks: Vec::new(),
        slowest: (Duration::ZERO, 0),
        refused: Vec::new(),
        each,
    };
    let alive = heartbeat(&mut g);
    run.go_on()?;
    let (pid, version) = if alive { startup(&mut g) } else { (None, None) };
    run.go_on()?;
    let reports = if alive { status(&mut g) } else { Vec::new() };
    run.go_on()?;
    if alive {
        writable(&mut g, &reports);
        run.go_on()?;
        read_only(&mut g, &reports);
        run.go_on()?;
        edges(&mut g);
    } else {
        for (id, name) in LATER {
            g.skip(id, name, true, "the MCU does not answer heartbeats");
        }
    }
    run.go_on()?;
    ota(&mut g, options, alive, run)?;
    finish(&mut g);
    Ok(Conformance {
        checks: g.checks,
        pid,
        version,
        seconds: started.elapsed().as_secs_f64(),
    })
}

/// The mandatory checks that need an MCU that answers, skipped when it does not.
const LATER: [(&str, &str); 8] = [
    ("product_info", "product info (0x01) well-formed"),
    ("work_mode", "working mode (0x02) answered"),
    ("wifi_state", "Wi-Fi state (0x03) acknowledged"),
    (
        "status_all",
        "every data point reported on a status query (0x08)",
    ),
    (
        "status_types",
        "each report of its declared type and length",
    ),
    (
        "status_range",
        "each reported value within its data point's limits",
    ),
    (
        "writable",
        "each writable data point accepted and re-reported (0x06)",
    ),
    (
        "read_only_refused",
        "report-only data points refused (no report)",
    ),
];

/// Two heartbeats: both answered within 3 s, the second with `01` (the first may be `00`, the
/// first since the MCU started); and the frame version byte.
fn heartbeat(g: &mut Grader<'_>) -> bool {
    let t = Instant::now();
    let (first, ev1) = g.ask(Request::new(cmd::HEARTBEAT, Vec::new()).attempts(3));
    let (second, ev2) = g.ask(Request::new(cmd::HEARTBEAT, Vec::new()).attempts(2));
    let answer = |r: &Result<Reply, ExchangeError>| {
        r.as_ref()
            .ok()
            .map(|r| (r.payload().unwrap_or_default().to_vec(), r.rtt))
    };
    let (a1, a2) = (answer(&first), answer(&second));
    let (pass, detail) = match (&a1, &a2) {
        (Some((b1, t1)), Some((b2, t2))) => {
            let slow = (*t1).max(*t2);
            let ok = matches!(b1.as_slice(), [0] | [1]) && b2.as_slice() == [1];
            let ok = ok && slow <= HEARTBEAT_LIMIT;
            (
                ok,
                format!(
                    "answers {} then {} (the second must be 01), slowest {} ms (limit 3000)",
                    hex::format(b1),
                    hex::format(b2),
                    slow.as_millis()
                ),
            )
        }
        _ => (false, "no answer to the heartbeat".to_string()),
    };
    g.done(
        "heartbeat",
        "heartbeat (0x00) answered 00/01 within 3 s",
        true,
        pass,
        detail,
        format!("{ev1}; {ev2}"),
        t,
    );
    let version = first
        .as_ref()
        .ok()
        .and_then(|r| r.packets.first())
        .map(|p| {
            (
                p.wire.get(2).copied().unwrap_or_default(),
                hex::format(&p.wire),
            )
        });
    match version {
        Some((v, wire)) => g.done(
            "frame_version",
            "MCU frames carry version 0x03",
            false,
            v == crate::protocol::tuya::VERSION_MCU,
            format!("version byte {v:#04x}"),
            wire,
            t,
        ),
        None => g.skip(
            "frame_version",
            "MCU frames carry version 0x03",
            false,
            "no frame",
        ),
    }
    a1.is_some() || a2.is_some()
}

/// Product info, working mode and the Wi-Fi state, as a module starts up: each answered, the
/// product info a JSON object with a string `p` and a dot-decimal `v`.
fn startup(g: &mut Grader<'_>) -> (Option<String>, Option<String>) {
    let t = Instant::now();
    let (r, ev) = g.ask(Request::new(cmd::PRODUCT_INFO, Vec::new()));
    let (mut pid, mut version) = (None, None);
    let (pass, detail) = match &r {
        Ok(reply) => {
            let info = parse_product_info(reply.payload().unwrap_or_default());
            pid.clone_from(&info.pid);
            version.clone_from(&info.version);
            let v_ok = info.version.as_deref().is_some_and(super::is_version);
            let ok = info.error.is_none() && info.pid.is_some() && v_ok;
            let why = match (&info.error, &info.pid, v_ok) {
                (Some(e), _, _) => format!("not JSON: {e}"),
                (None, None, _) => "no \"p\" (product id)".to_string(),
                (None, Some(_), false) => "no dot-decimal \"v\" (x.y.z)".to_string(),
                _ => "well-formed".to_string(),
            };
            (ok, format!("{why}: {}", info.raw))
        }
        Err(e) => (false, format!("no answer: {e}")),
    };
    g.done("product_info", LATER[0].1, true, pass, detail, ev, t);
    let t = Instant::now();
    let (r, ev) = g.ask(Request::new(cmd::WORK_MODE, Vec::new()));
    let (pass, detail) = match &r {
        Ok(reply) => match reply.payload().unwrap_or_default() {
            [] => (true, "empty: the MCU drives the Wi-Fi LED".to_string()),
            [led, reset] => (
                true,
                format!("the module drives the LED: GPIO {led}, reset {reset}"),
            ),
            other => (
                false,
                format!(
                    "{} byte(s): neither empty nor two GPIO numbers",
                    other.len()
                ),
            ),
        },
        Err(e) => (false, format!("no answer: {e}")),
    };
    g.done("work_mode", LATER[1].1, true, pass, detail, ev, t);
    let t = Instant::now();
    let (r, ev) = g.ask(Request::new(cmd::WIFI_STATE, vec![4]));
    let (pass, detail) = match &r {
        Ok(reply) if reply.payload().unwrap_or_default().is_empty() => {
            (true, "state 04 (cloud connected) acknowledged".to_string())
        }
        Ok(reply) => (
            false,
            format!(
                "acknowledged with data {} (an ack is empty)",
                hex::format(reply.payload().unwrap_or_default())
            ),
        ),
        Err(e) => (false, format!("no answer: {e}")),
    };
    g.done("wifi_state", LATER[2].1, true, pass, detail, ev, t);
    (pid, version)
}

/// One status query: every data point reported (late reports listened for a second after the
/// last), each of its declared type and length and within its limits; the burst's time; data
/// points the profile lacks. Returns the reports read.
fn status(g: &mut Grader<'_>) -> Vec<ReportedDp> {
    let t = Instant::now();
    let heard = query(g, t);
    let read = read_reports(g.profile, &heard.reports);
    let burst = heard.last_at.saturating_duration_since(t);
    if burst > g.slowest.0 {
        g.slowest = (burst, cmd::QUERY_STATUS);
    }
    grade_status(g, &heard, &read, burst, t);
    read
}

/// What one status query brought.
struct Heard {
    /// The query's bytes.
    sent: Vec<u8>,
    /// Every report, the query's answer and what trailed it.
    reports: Vec<Packet>,
    /// The profile's reported data points, and those never heard.
    ids: Vec<u8>,
    /// See `ids`.
    missing: Vec<u8>,
    /// When the last report that brought a data point not yet heard came.
    last_at: Instant,
}

/// Sends the status query at `t` and listens to what trails its answer.
fn query(g: &mut Grader<'_>, t: Instant) -> Heard {
    let ids = reported_dps(g.profile);
    g.take_watch();
    let request = super::query_request(g.profile);
    let sent = wire_of(&request);
    let result = g.client.request(request);
    let mut last_at = result.as_ref().map(|r| t + r.rtt).unwrap_or(t);
    let mut reports = g.take_watch();
    let mut missing: Vec<u8> = ids.clone();
    missing.retain(|id| !reported_ids(&reports).contains(id));
    // Listened for until quiet: a second while data points are missing, then 300 ms for what
    // trails the burst (data points the profile lacks come last); 10 s at most (a chatty MCU).
    let cap = Instant::now() + super::LISTEN_CAP;
    let quiet = |missing: &[u8]| if missing.is_empty() { TRAIL } else { SILENCE };
    let mut quiet_until = Instant::now() + quiet(&missing);
    while let Some(item) = g.watch.next(
        quiet_until
            .min(cap)
            .saturating_duration_since(Instant::now()),
    ) {
        match item {
            Watched::Report(p) => {
                let ids = reported_ids(std::slice::from_ref(&p));
                let news = ids
                    .iter()
                    .any(|id| missing.contains(id) || !reported_ids(&reports).contains(id));
                if news {
                    last_at = Instant::now();
                    missing.retain(|id| !ids.contains(id));
                }
                quiet_until = Instant::now() + quiet(&missing);
                reports.push(p);
            }
            Watched::Refused(e) => g.refused.push(e.to_string()),
            Watched::Tuya(_) => {}
        }
    }
    Heard {
        sent,
        reports,
        ids,
        missing,
        last_at,
    }
}

/// The status checks from what the query brought (`read`: its reports against the profile).
fn grade_status(g: &mut Grader<'_>, h: &Heard, read: &[ReportedDp], burst: Duration, t: Instant) {
    let (sent, reports, ids, missing) = (&h.sent, &h.reports, &h.ids, &h.missing);
    let of = |d: &ReportedDp| {
        reports
            .iter()
            .find(|p| reported_ids(std::slice::from_ref(p)).contains(&d.id))
    };
    let ev_of = |list: &[&ReportedDp]| {
        let frames: Vec<Packet> = list.iter().filter_map(|d| of(d).cloned()).collect();
        evidence(sent, &frames)
    };
    let names = |list: &[u8]| {
        list.iter()
            .map(|id| {
                g.profile
                    .data_point(*id)
                    .map_or(id.to_string(), |d| format!("{} ({id})", d.field.ident))
            })
            .collect::<Vec<_>>()
            .join(", ")
    };
    let heard = ids.len() - missing.len();
    let detail = if missing.is_empty() {
        format!("all {heard} reported")
    } else {
        format!(
            "{heard} of {} reported; never: {}",
            ids.len(),
            names(missing)
        )
    };
    g.done(
        "status_all",
        LATER[3].1,
        true,
        missing.is_empty(),
        detail,
        format!("{} → {} report(s)", hex::format(sent), reports.len()),
        t,
    );
    let shape: Vec<&ReportedDp> = read
        .iter()
        .filter(|d| {
            d.in_profile()
                && d.misfit
                    .as_ref()
                    .is_some_and(|m| !matches!(m, super::DpMisfit::Limit(_)))
        })
        .collect();
    let detail = misfit_text(&shape, heard);
    g.done(
        "status_types",
        LATER[4].1,
        true,
        shape.is_empty(),
        detail,
        ev_of(&shape),
        t,
    );
    let limits: Vec<&ReportedDp> = read
        .iter()
        .filter(|d| d.in_profile() && matches!(d.misfit, Some(super::DpMisfit::Limit(_))))
        .collect();
    let detail = misfit_text(&limits, heard);
    g.done(
        "status_range",
        LATER[5].1,
        true,
        limits.is_empty(),
        detail,
        ev_of(&limits),
        t,
    );
    advisory_status(g, h, read, burst, t);
}

/// The advisory status checks: the burst's time, data points the profile lacks.
fn advisory_status(
    g: &mut Grader<'_>,
    h: &Heard,
    read: &[ReportedDp],
    burst: Duration,
    t: Instant,
) {
    let frames: Vec<Packet> = h
        .reports
        .iter()
        .filter(|p| {
            reported_ids(std::slice::from_ref(p))
                .iter()
                .any(|id| read.iter().any(|d| d.id == *id && !d.in_profile()))
        })
        .cloned()
        .collect();
    let ev_of = |_: &[&ReportedDp]| evidence(&h.sent, &frames);
    g.done(
        "status_burst",
        "status reports all within 1 s of the query",
        false,
        burst <= BURST_LIMIT,
        format!(
            "last report {} ms after the query (a module's request timeout: 1000 ms)",
            burst.as_millis()
        ),
        String::new(),
        t,
    );
    let unknown: Vec<&ReportedDp> = read.iter().filter(|d| !d.in_profile()).collect();
    let detail = if unknown.is_empty() {
        "none".to_string()
    } else {
        unknown
            .iter()
            .map(|d| format!("{} {}", d.name(), d.shown(g.profile)))
            .collect::<Vec<_>>()
            .join("; ")
    };
    g.done(
        "status_unknown",
        "no data points the profile lacks",
        false,
        unknown.is_empty(),
        detail,
        ev_of(&unknown),
        t,
    );
}

fn misfit_text(list: &[&ReportedDp], heard: usize) -> String {
    if list.is_empty() {
        return format!("all {heard} fit");
    }
    list.iter()
        .map(|d| {
            format!(
                "{}: {}",
                d.name(),
                d.misfit
                    .as_ref()
                    .map(ToString::to_string)
                    .unwrap_or_default()
            )
        })
        .collect::<Vec<_>>()
        .join("; ")
}

/// Whether a module frame sending this data point stays clear of the sizes that lock an SDK
/// MCU's receive path (TUYA_FIELD_NOTES §6: 32-38 bytes with the default buffers): a frame of
/// the fixed-size types (at most 15 bytes) always does.
fn small_enough(ty: DpType) -> bool {
    !matches!(ty, DpType::String | DpType::Raw)
}

/// Each writable data point sent the value it reports (so that nothing at the bench moves) and
/// re-reported with it in answer to the command.
fn writable(g: &mut Grader<'_>, reports: &[ReportedDp]) {
    let t = Instant::now();
    let mut bad = Vec::new();
    let mut good = 0;
    let mut evidence = Vec::new();
    let defs: Vec<_> = g
        .profile
        .data_points
        .iter()
        .filter(|d| d.access.writable())
        .cloned()
        .collect();
    for def in defs {
        let Some(held) = reports
            .iter()
            .find(|r| r.id == def.id && r.misfit.is_none())
            .and_then(|r| r.value.clone())
        else {
            bad.push(format!("{}: no good report to send back", def.field.ident));
            continue;
        };
        if !small_enough(def.dp_type) {
            continue;
        }
        let inputs = [(def.field.ident.clone(), Input::Raw(held.clone()))];
        let Ok(payload) = super::set_dps_request(g.profile, &inputs) else {
            bad.push(format!(
                "{}: its value {held:?} cannot be sent",
                def.field.ident
            ));
            continue;
        };
        let Some(command) = g.profile.commands.iter().find(|c| c.id == cmd::DP_COMMAND) else {
            return;
        };
        let request = Request::for_command(g.profile, command, payload);
        let (r, ev) = g.ask(request);
        let answer = r
            .map(|r| read_reports(g.profile, &r.packets))
            .unwrap_or_default();
        match answer.iter().find(|a| a.id == def.id) {
            Some(a) if a.misfit.is_none() && a.value.as_ref() == Some(&held) => good += 1,
            Some(a) => {
                bad.push(format!(
                    "{}: re-reported {}",
                    def.field.ident,
                    a.shown(g.profile)
                ));
                evidence.push(ev);
            }
            None => {
                bad.push(format!("{}: not re-reported", def.field.ident));
                evidence.push(ev);
            }
        }
    }
    let detail = if bad.is_empty() {
        format!("{good} accepted and re-reported with the value sent")
    } else {
        bad.join("; ")
    };
    g.done(
        "writable",
        LATER[6].1,
        true,
        bad.is_empty(),
        detail,
        evidence.join("; "),
        t,
    );
}

/// Each report-only data point of a fixed-size type, sent its own reported value: no report
/// may answer (the SDK drops a command for a data point it only reports).
fn read_only(g: &mut Grader<'_>, reports: &[ReportedDp]) {
    let t = Instant::now();
    let mut taken = Vec::new();
    let mut evidence = Vec::new();
    let mut sent = 0;
    let defs: Vec<_> = g
        .profile
        .data_points
        .iter()
        .filter(|d| !d.access.writable() && small_enough(d.dp_type))
        .cloned()
        .collect();
    for def in defs {
        let Some(r) = reports
            .iter()
            .find(|r| r.id == def.id && r.misfit.is_none())
        else {
            continue;
        };
        let mut payload = vec![def.id, def.dp_type.byte()];
        payload.extend_from_slice(&(r.raw.len() as u16).to_be_bytes());
        payload.extend_from_slice(&r.raw);
        let request = Request::new(cmd::DP_COMMAND, payload)
            .reply(ReplySpec::Optional(Match::command(cmd::DP_REPORT)))
            .margin(SILENCE / 2)
            .attempts(1);
        sent += 1;
        let (result, ev) = g.ask(request);
        if let Ok(reply) = result
            && read_reports(g.profile, &reply.packets)
                .iter()
                .any(|a| a.id == def.id)
        {
            taken.push(def.field.ident.clone());
            evidence.push(ev);
        }
    }
    let detail = if taken.is_empty() {
        format!("{sent} report-only data point(s) sent: none answered")
    } else {
        format!("taken and re-reported: {}", taken.join(", "))
    };
    g.done(
        "read_only_refused",
        LATER[7].1,
        true,
        taken.is_empty(),
        detail,
        evidence.join("; "),
        t,
    );
}

/// A heartbeat with a bad checksum and an unknown command: neither answered, and the MCU still
/// answers a heartbeat after each.
fn edges(g: &mut Grader<'_>) {
    let cases = [
        (
            "bad_checksum",
            "a frame with a bad checksum is dropped",
            Request::new(cmd::HEARTBEAT, Vec::new()).bad_checksum(),
        ),
        (
            "unknown_command",
            "an unknown command (0x99) is ignored",
            Request::new(UNKNOWN_COMMAND, Vec::new()),
        ),
    ];
    for (id, name, request) in cases {
        let t = Instant::now();
        let answer = Match::command(request.command);
        let request = request
            .reply(ReplySpec::Optional(answer))
            .margin(SILENCE)
            .attempts(1);
        let (r, ev) = g.ask(request);
        let answered = r.as_ref().is_ok_and(|r| !r.packets.is_empty());
        let (after, ev2) = g.ask(Request::new(cmd::HEARTBEAT, Vec::new()).attempts(2));
        let alive = after.is_ok();
        let detail = match (answered, alive) {
            (false, true) => "no answer; the next heartbeat answered".to_string(),
            (true, _) => "answered (a conforming MCU drops it)".to_string(),
            (false, false) => "no answer, and no heartbeat answer after it".to_string(),
        };
        g.done(
            id,
            name,
            true,
            !answered && alive,
            detail,
            format!("{ev}; {ev2}"),
            t,
        );
    }
}

/// The optional update: proven as [`super::update`] does, or skipped.
fn ota(
    g: &mut Grader<'_>,
    options: &Options,
    alive: bool,
    run: &mut Run<'_>,
) -> Result<(), OpError> {
    let name = "firmware update proven (0x0a/0x0b, then 0x01 names the version)";
    let Some((image, expect)) = &options.ota else {
        g.skip("ota", name, false, "not asked (--ota FILE)");
        return Ok(());
    };
    if !alive {
        g.skip("ota", name, true, "the MCU does not answer heartbeats");
        return Ok(());
    }
    let t = Instant::now();
    match super::update(
        g.client,
        image,
        options.ota_max,
        expect,
        OtaTiming::default(),
        run,
    ) {
        Ok(r) => g.done(
            "ota",
            name,
            true,
            true,
            format!(
                "{} bytes in {:.1} s; version {} → {}, back {:.1} s after the last packet",
                r.size,
                r.seconds,
                r.before_version.as_deref().unwrap_or("unknown"),
                r.after_version.as_deref().unwrap_or("unknown"),
                r.back_seconds.unwrap_or_default()
            ),
            String::new(),
            t,
        ),
        Err(OpError::Cancelled) => return Err(OpError::Cancelled),
        Err(e) => g.done("ota", name, true, false, e.to_string(), String::new(), t),
    }
    Ok(())
}

/// The checks over the whole run: the slowest answer within 5 s, no frame refused.
fn finish(g: &mut Grader<'_>) {
    let t = Instant::now();
    g.take_watch();
    let (slowest, command) = g.slowest;
    g.done(
        "answer_time",
        "every answer within 5 s",
        true,
        slowest <= ANSWER_LIMIT,
        format!(
            "slowest {} ms (command {command:#04x})",
            slowest.as_millis()
        ),
        String::new(),
        t,
    );
    let refused = std::mem::take(&mut g.refused);
    let detail = if refused.is_empty() {
        "none".to_string()
    } else {
        refused.join("; ")
    };
    g.done(
        "frames_clean",
        "no malformed MCU frame (checksum, length, cut short)",
        true,
        refused.is_empty(),
        detail,
        String::new(),
        t,
    );
}
