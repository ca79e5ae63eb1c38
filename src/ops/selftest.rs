//! Production self-test: a test plan in RON, checked against the profile when it loads, run
//! step by step over a link, and logged as one JSON line per run.
//!
//! A plan lists steps of five kinds. Thresholds are in display units ("11.5" volts, not 115),
//! written as text or bare numbers; a field may be named alone (`field:`) or several at once
//! (`fields:`), every one of them must pass.
//!
//! ```ron
//! (
//!     version: 1,
//!     profile: "window-cleaner",
//!     name: "Window cleaner line test",
//!     steps: [
//!         // Every sample of every field within [min, max].
//!         Range(name: "Battery voltage", command: "MSP_ADAPTER", field: "batteryVoltage",
//!               min: "11.5", max: "16.8", samples: 5),
//!         // At rest: the spread (max - min) of each field over the samples within bounds.
//!         Stable(name: "Gyro at rest", command: "MSP_RAW_IMU", fields: ["gyroX", "gyroY", "gyroZ"],
//!                max_spread: "30", samples: 10),
//!         // The mean rises by at least min_rise while the action is on; `then` always runs after.
//!         Rises(name: "Wheels forward", action: ("MSP_SET_MOTOR", {"motor": "forward"}),
//!               command: "MSP_ANALOG", fields: ["adcLeftWheel", "adcRightWheel"],
//!               min_rise: "200", settle_ms: 600, then: ("MSP_SET_MOTOR", {"motor": "stop"})),
//!         // Prompts the operator, then watches until every bit has been seen clear and set.
//!         Operator(name: "Corner switches", prompt: "Cover each corner switch in turn",
//!                  command: "MSP_FOURCORNER", field: "corners", expect_bits_seen: 15,
//!                  timeout_ms: 20000),
//!         // The command answers and decodes; `expect` values must match exactly.
//!         Reads(name: "Water box", command: "MSP_WATER_BOX", expect: {"status": "1"}),
//!     ],
//! )
//! ```
//!
//! A run goes on after a step fails, so that the report shows every check; it ends at once (as
//! FAIL, naming the step) when the link is lost, the device stops answering, the operator aborts
//! or the run is cancelled. A Rises step's `then` action is sent whatever happened before it.

use crate::document::{self, DocumentError, ErrorKind, Problem, Source, Step as At};
use crate::link::{Client, DeviceInfo};
use crate::ops::OpError;
use crate::ops::exchange as ops;
use crate::ops::{Cancel, Progress};
use crate::profile::value::Typed as Text;
use crate::profile::{Command, CommandKind, Field, Input, Profile, Value};
use crate::protocol::Direction;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;
use std::time::{Duration, Instant};

/// The newest plan format this build reads.
pub const VERSION: u32 = 1;

/// Time between samples when a step does not say.
const DEFAULT_INTERVAL: Duration = Duration::from_millis(20);

/// A checked test plan.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// What the plan is called (free text).
    pub name: String,
    /// The profile id it was checked against.
    pub profile: String,
    /// The steps, in order.
    pub steps: Vec<Step>,
}

/// One checked step.
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    /// Its name, unique in the plan.
    pub name: String,
    /// What it does.
    pub kind: StepKind,
}

/// What a step does. Commands are stored by canonical ident, fields by canonical ident.
#[derive(Debug, Clone, PartialEq)]
pub enum StepKind {
    /// Every sample of every field within `[min, max]` (display units).
    Range {
        /// The command read.
        command: String,
        /// The fields checked.
        fields: Vec<String>,
        /// The smallest value allowed.
        min: f64,
        /// The largest value allowed.
        max: f64,
        /// Reads made.
        samples: u32,
        /// Time between reads.
        interval: Duration,
    },
    /// The spread (max − min) of each field over the samples at most `max_spread`.
    Stable {
        /// The command read.
        command: String,
        /// The fields checked.
        fields: Vec<String>,
        /// The largest spread allowed (display units).
        max_spread: f64,
        /// Reads made (at least 2).
        samples: u32,
        /// Time between reads.
        interval: Duration,
    },
    /// Each field's mean rises by at least `min_rise` while `action` is on; `then` always
    /// follows.
    Rises {
        /// What turns it on.
        action: Action,
        /// The command read.
        command: String,
        /// The fields checked.
        fields: Vec<String>,
        /// The smallest rise allowed (display units).
        min_rise: f64,
        /// How long to wait after the action before measuring, and after `then` before the next
        /// step.
        settle: Duration,
        /// Reads averaged before and after.
        samples: u32,
        /// What turns it off; sent whatever happened.
        then: Action,
    },
    /// Prompts the operator, then watches a bit field until each bit of `bits` has been seen
    /// both clear and set.
    Operator {
        /// What the operator is asked to do.
        prompt: String,
        /// The command read.
        command: String,
        /// The bit field.
        field: String,
        /// The bits that must toggle.
        bits: u64,
        /// How long to watch after the prompt.
        timeout: Duration,
    },
    /// The command answers and its answer decodes; `expect`ed fields hold exactly these values.
    Reads {
        /// The command read.
        command: String,
        /// (field ident, raw value, as written in the plan).
        expect: Vec<(String, Value, String)>,
    },
}

impl StepKind {
    /// `Range`, `Stable`, `Rises`, `Operator` or `Reads`.
    pub fn name(&self) -> &'static str {
        match self {
            StepKind::Range { .. } => "Range",
            StepKind::Stable { .. } => "Stable",
            StepKind::Rises { .. } => "Rises",
            StepKind::Operator { .. } => "Operator",
            StepKind::Reads { .. } => "Reads",
        }
    }
}

/// An action command with its payload, encoded and checked at load.
#[derive(Debug, Clone, PartialEq)]
pub struct Action {
    /// The command's canonical ident.
    pub command: String,
    /// The encoded payload.
    pub payload: Vec<u8>,
    /// As a person reads it: `MSP_SET_MOTOR motor=stop`.
    pub text: String,
}

impl Plan {
    /// Reads a plan file and checks it against `profile`.
    pub fn load(path: &Path, profile: &Profile) -> Result<Plan, DocumentError> {
        let text = document::read(path)?;
        Self::parse(&path.display().to_string(), &text, profile)
    }

    /// Parses plan text (`name` names it in errors) and checks it against `profile`. Every
    /// problem is reported, each where it is; the error's kind is the first one's.
    pub fn parse(name: &str, text: &str, profile: &Profile) -> Result<Plan, DocumentError> {
        let src = Source::new(name, text);
        let doc: Doc = src.parse()?;
        let mut problems: Vec<(ErrorKind, Problem)> = Vec::new();
        match doc.version {
            Some(VERSION) => {}
            Some(v) => problems.push((
                ErrorKind::Version,
                src.problem(
                    &[At::Key("version")],
                    format!("plan version {v}; this botbench reads version {VERSION}"),
                ),
            )),
            None => problems.push((
                ErrorKind::Version,
                Problem::at(
                    (1, 1),
                    format!("no `version`: a plan starts with `version: {VERSION},`"),
                ),
            )),
        }
        if doc.profile != profile.id {
            problems.push((
                ErrorKind::Profile,
                src.problem(
                    &[At::Key("profile")],
                    format!(
                        "this plan is for '{}'; the device uses {}",
                        doc.profile, profile.id
                    ),
                ),
            ));
        }
        if doc.steps.is_empty() {
            problems.push((
                ErrorKind::Value,
                src.problem(&[At::Key("steps")], "the plan has no steps"),
            ));
        }
        let mut steps = Vec::new();
        for (i, s) in doc.steps.iter().enumerate() {
            let mut cx = Check {
                src: &src,
                index: i,
                profile,
                problems: Vec::new(),
            };
            let step = cx.step(s);
            if steps.iter().any(|p: &Step| p.name == s.name()) {
                cx.at(
                    &[At::Key("name")],
                    format!("step '{}' is named twice", s.name()),
                );
            } else if s.name().trim().is_empty() {
                cx.at(&[At::Key("name")], "a step needs a name".into());
            }
            problems.extend(cx.problems.into_iter().map(|p| (ErrorKind::Value, p)));
            if let Some(kind) = step {
                steps.push(Step {
                    name: s.name().to_string(),
                    kind,
                });
            }
        }
        if let Some(&(kind, _)) = problems.first() {
            return Err(DocumentError {
                file: name.to_string(),
                kind,
                problems: problems.into_iter().map(|(_, p)| p).collect(),
            });
        }
        Ok(Plan {
            name: doc.name,
            profile: profile.id.clone(),
            steps,
        })
    }
}

/// Checks one step of the document, collecting problems with their place.
struct Check<'a> {
    src: &'a Source<'a>,
    index: usize,
    profile: &'a Profile,
    problems: Vec<Problem>,
}

impl<'a> Check<'a> {
    fn at(&mut self, path: &[At], message: String) {
        let mut full = vec![At::Key("steps"), At::Index(self.index)];
        full.extend_from_slice(path);
        self.problems.push(self.src.problem(&full, message));
    }

    /// A command that can be read with an empty request (Telemetry or Get).
    fn readable(&mut self, name: &str) -> Option<&'a Command> {
        let profile = self.profile;
        let Some(cmd) = profile.command(name) else {
            self.at(
                &[At::Key("command")],
                format!("{} has no command '{name}'", profile.id),
            );
            return None;
        };
        let readable = matches!(cmd.kind, CommandKind::Telemetry | CommandKind::Get)
            && cmd.request.iter().all(|f| f.optional)
            && cmd.initiator == crate::profile::Initiator::Host;
        if !readable {
            self.at(
                &[At::Key("command")],
                format!(
                    "{} is not a Telemetry or Get command that answers an empty request",
                    cmd.ident
                ),
            );
            return None;
        }
        Some(cmd)
    }

    /// A numeric field of the command's answer.
    fn field(&mut self, cmd: &'a Command, name: &str, path: &[At]) -> Option<&'a Field> {
        let Some(f) = cmd
            .reply
            .iter()
            .find(|f| f.ident.eq_ignore_ascii_case(name))
        else {
            let known: Vec<&str> = cmd.reply.iter().map(|f| f.ident.as_str()).collect();
            self.at(
                path,
                format!(
                    "{} has no field '{name}'; its fields: {}",
                    cmd.ident,
                    known.join(", ")
                ),
            );
            return None;
        };
        if f.ty.int_bounds().is_none() {
            self.at(path, format!("{}.{} is not a number", cmd.ident, f.ident));
            return None;
        }
        Some(f)
    }

    /// `field:` or `fields:`, exactly one of them, each a numeric field of `cmd`.
    fn fields(
        &mut self,
        cmd: Option<&'a Command>,
        field: &Option<String>,
        fields: &[String],
    ) -> Vec<&'a Field> {
        let named: Vec<(String, Vec<At>)> = match (field, fields.is_empty()) {
            (Some(f), true) => vec![(f.clone(), vec![At::Key("field")])],
            (None, false) => fields
                .iter()
                .enumerate()
                .map(|(j, f)| (f.clone(), vec![At::Key("fields"), At::Index(j)]))
                .collect(),
            (Some(_), false) => {
                self.at(
                    &[At::Key("fields")],
                    "give `field` or `fields`, not both".into(),
                );
                return Vec::new();
            }
            (None, true) => {
                self.at(&[], "give the field checked: `field: \"...\"`".into());
                return Vec::new();
            }
        };
        let Some(cmd) = cmd else {
            return Vec::new();
        };
        let mut out: Vec<&Field> = Vec::new();
        for (name, path) in named {
            if let Some(f) = self.field(cmd, &name, &path) {
                if out.iter().any(|o| o.ident == f.ident) {
                    self.at(&path, format!("field '{}' is named twice", f.ident));
                } else {
                    out.push(f);
                }
            }
        }
        out
    }

    /// A threshold in display units that each field can reach.
    fn number(&mut self, key: &'static str, text: &Text, fields: &[&Field]) -> Option<f64> {
        let Ok(x) = text.0.trim().parse::<f64>() else {
            self.at(
                &[At::Key(key)],
                format!("{key}: '{}' is not a number", text.0),
            );
            return None;
        };
        if !x.is_finite() {
            self.at(
                &[At::Key(key)],
                format!("{key}: '{}' is not finite", text.0),
            );
            return None;
        }
        for f in fields {
            let (lo, hi) = f.ty.int_bounds().unwrap_or((0, 0));
            let span = (hi - lo) as f64 * f.scale;
            let (lo, hi) = (lo as f64 * f.scale, hi as f64 * f.scale);
            let bad = match key {
                "min" | "max" => x < lo || x > hi,
                _ => x < 0.0 || x > span,
            };
            if bad {
                let (a, b) = match key {
                    "min" | "max" => (lo, hi),
                    _ => (0.0, span),
                };
                self.at(
                    &[At::Key(key)],
                    format!(
                        "{key}: {} is beyond what {} can read ({a} to {b}{}); thresholds are in display units",
                        text.0,
                        f.ident,
                        f.unit_suffix()
                    ),
                );
                return None;
            }
        }
        Some(x)
    }

    fn samples(&mut self, n: u32, least: u32) -> u32 {
        if n < least || n > 10_000 {
            self.at(
                &[At::Key("samples")],
                format!("samples: {n}; give {least} to 10000"),
            );
        }
        n
    }

    fn action(&mut self, key: &'static str, a: &DocAction) -> Option<Action> {
        let profile = self.profile;
        let Some(cmd) = profile.command(&a.0) else {
            self.at(
                &[At::Key(key)],
                format!("{key}: {} has no command '{}'", profile.id, a.0),
            );
            return None;
        };
        if !matches!(cmd.kind, CommandKind::Action | CommandKind::Set) {
            self.at(
                &[At::Key(key)],
                format!("{key}: {} is not an Action or Set command", cmd.ident),
            );
            return None;
        }
        let inputs: Vec<(String, Input)> =
            a.1.iter()
                .map(|(k, v)| (k.clone(), Input::Text(v.0.clone())))
                .collect();
        match profile.encode(cmd, Direction::HostToDevice, &inputs) {
            Ok(payload) => {
                let args: Vec<String> = a.1.iter().map(|(k, v)| format!("{k}={}", v.0)).collect();
                Some(Action {
                    command: cmd.ident.clone(),
                    payload,
                    text: format!("{} {}", cmd.ident, args.join(" "))
                        .trim_end()
                        .to_string(),
                })
            }
            Err(e) => {
                self.at(&[At::Key(key)], format!("{key}: {}: {e}", cmd.ident));
                None
            }
        }
    }

    fn interval(&mut self, ms: Option<u64>) -> Duration {
        ms.map_or(DEFAULT_INTERVAL, Duration::from_millis)
    }

    fn ms(&mut self, key: &'static str, ms: u64, least: u64) -> Duration {
        if ms < least || ms > 600_000 {
            self.at(
                &[At::Key(key)],
                format!("{key}: {ms}; give {least} to 600000 ms"),
            );
        }
        Duration::from_millis(ms)
    }

    fn step(&mut self, s: &DocStep) -> Option<StepKind> {
        let before = self.problems.len();
        let idents = |fs: &[&Field]| fs.iter().map(|f| f.ident.clone()).collect::<Vec<_>>();
        let kind = match s {
            DocStep::Range {
                command,
                field,
                fields,
                min,
                max,
                samples,
                interval_ms,
                ..
            } => {
                let cmd = self.readable(command);
                let fs = self.fields(cmd, field, fields);
                let min = self.number("min", min, &fs);
                let max = self.number("max", max, &fs);
                if let (Some(a), Some(b)) = (min, max)
                    && a > b
                {
                    self.at(&[At::Key("min")], format!("min {a} is above max {b}"));
                }
                StepKind::Range {
                    command: cmd?.ident.clone(),
                    fields: idents(&fs),
                    min: min?,
                    max: max?,
                    samples: self.samples(*samples, 1),
                    interval: self.interval(*interval_ms),
                }
            }
            DocStep::Stable {
                command,
                field,
                fields,
                max_spread,
                samples,
                interval_ms,
                ..
            } => {
                let cmd = self.readable(command);
                let fs = self.fields(cmd, field, fields);
                let spread = self.number("max_spread", max_spread, &fs);
                StepKind::Stable {
                    command: cmd?.ident.clone(),
                    fields: idents(&fs),
                    max_spread: spread?,
                    samples: self.samples(*samples, 2),
                    interval: self.interval(*interval_ms),
                }
            }
            DocStep::Rises {
                action,
                command,
                field,
                fields,
                min_rise,
                settle_ms,
                samples,
                then,
                ..
            } => {
                let action = self.action("action", action);
                let then = self.action("then", then);
                let cmd = self.readable(command);
                let fs = self.fields(cmd, field, fields);
                let rise = self.number("min_rise", min_rise, &fs);
                if rise == Some(0.0) {
                    self.at(
                        &[At::Key("min_rise")],
                        "min_rise: 0 passes whatever happens; give a rise above 0".into(),
                    );
                }
                StepKind::Rises {
                    action: action?,
                    command: cmd?.ident.clone(),
                    fields: idents(&fs),
                    min_rise: rise?,
                    settle: self.ms("settle_ms", *settle_ms, 0),
                    samples: self.samples(*samples, 1),
                    then: then?,
                }
            }
            DocStep::Operator {
                prompt,
                command,
                field,
                expect_bits_seen,
                timeout_ms,
                ..
            } => {
                let cmd = self.readable(command);
                let f = cmd.and_then(|c| self.field(c, field, &[At::Key("field")]));
                if let Some(f) = f {
                    let width = f.ty.width().unwrap_or(8) * 8;
                    let allowed: u64 = if f.bits.is_empty() {
                        if width >= 64 {
                            u64::MAX
                        } else {
                            (1u64 << width) - 1
                        }
                    } else {
                        f.bits
                            .iter()
                            .filter(|b| b.bit < 64)
                            .fold(0, |m, b| m | 1u64 << b.bit)
                    };
                    if *expect_bits_seen == 0 || expect_bits_seen & !allowed != 0 {
                        self.at(
                            &[At::Key("expect_bits_seen")],
                            format!(
                                "expect_bits_seen: {expect_bits_seen:#x}; {} has bits {allowed:#x}",
                                f.ident
                            ),
                        );
                    }
                }
                if prompt.trim().is_empty() {
                    self.at(&[At::Key("prompt")], "the prompt is empty".into());
                }
                StepKind::Operator {
                    prompt: prompt.clone(),
                    command: cmd?.ident.clone(),
                    field: f?.ident.clone(),
                    bits: *expect_bits_seen,
                    timeout: self.ms("timeout_ms", *timeout_ms, 1),
                }
            }
            DocStep::Reads {
                command, expect, ..
            } => {
                let cmd = self.readable(command);
                let mut out = Vec::new();
                if let Some(cmd) = cmd {
                    for (k, v) in expect {
                        let path = [At::Key("expect")];
                        let Some(f) = self.field(cmd, k, &path) else {
                            continue;
                        };
                        match f.parse(&v.0) {
                            Ok(raw) => out.push((f.ident.clone(), raw, v.0.clone())),
                            Err(e) => self.at(&path, format!("expect: {e}")),
                        }
                    }
                }
                StepKind::Reads {
                    command: cmd?.ident.clone(),
                    expect: out,
                }
            }
        };
        (self.problems.len() == before).then_some(kind)
    }
}

// ---- Running ----

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

/// The result of one step.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StepResult {
    /// The step's name.
    pub name: String,
    /// Its kind (`Range`, `Stable`, `Rises`, `Operator`, `Reads`).
    pub kind: String,
    /// Whether it passed.
    pub pass: bool,
    /// Measured values against thresholds, or what went wrong.
    pub detail: String,
}

/// The result of a run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Report {
    /// The plan's name.
    pub plan: String,
    /// The profile.
    pub profile: String,
    /// "hw 0x03 fw 1.4.2 api 2.4 build 7 (2025-06-01 10:00:00)", from CMD_VERSION and
    /// CMD_BUILD_INFO; `None` when the device did not say.
    pub device: Option<String>,
    /// What CMD_VERSION and CMD_BUILD_INFO said.
    pub device_info: Option<DeviceInfo>,
    /// When the run started (RFC 3339).
    pub started: String,
    /// How long it took, in ms.
    pub duration_ms: u64,
    /// The steps run, in order.
    pub results: Vec<StepResult>,
    /// Why the run ended before its last step (link lost, no answer, cancelled, operator abort).
    pub aborted: Option<String>,
    /// Every step ran and passed.
    pub pass: bool,
}

impl Report {
    /// The steps that failed.
    pub fn failed(&self) -> impl Iterator<Item = &StepResult> {
        self.results.iter().filter(|r| !r.pass)
    }
}

/// Why a step ends the run.
enum Halt {
    /// The link or the device failed.
    Device(String),
    /// Cancelled.
    Cancelled,
    /// The operator said no.
    OperatorAborted,
}

impl Halt {
    fn message(&self) -> String {
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
pub fn run(
    client: &Client,
    profile: &Profile,
    plan: &Plan,
    operator: &mut dyn Operator,
    cancel: &Cancel,
    progress: &mut dyn FnMut(Progress),
) -> Report {
    run_each(
        client,
        profile,
        plan,
        operator,
        cancel,
        progress,
        &mut |_| {},
    )
}

/// [`run`], telling `each` every step's result as it comes.
pub fn run_each(
    client: &Client,
    profile: &Profile,
    plan: &Plan,
    operator: &mut dyn Operator,
    cancel: &Cancel,
    progress: &mut dyn FnMut(Progress),
    each: &mut dyn FnMut(&StepResult),
) -> Report {
    let t0 = Instant::now();
    let mut report = Report {
        plan: plan.name.clone(),
        profile: profile.id.clone(),
        device: None,
        device_info: None,
        started: chrono::Local::now().to_rfc3339_opts(chrono::SecondsFormat::Millis, false),
        duration_ms: 0,
        results: Vec::new(),
        aborted: None,
        pass: false,
    };
    let total = plan.steps.len() as u64 + 1;
    progress(Progress {
        done: 0,
        total,
        message: "identifying the device".into(),
    });
    match super::device::identify(client, profile) {
        Ok(info) => {
            report.device = Some(super::device::description(&info));
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
        for (i, step) in plan.steps.iter().enumerate() {
            progress(Progress {
                done: i as u64 + 1,
                total,
                message: step.name.clone(),
            });
            let (pass, detail, halt) = if cancel.is_cancelled() {
                (false, "cancelled before it started".into(), true)
            } else {
                match run_step(client, profile, step, operator, cancel) {
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
    progress(Progress {
        done: total,
        total,
        message: "done".into(),
    });
    report.pass = report.aborted.is_none()
        && report.results.len() == plan.steps.len()
        && report.results.iter().all(|r| r.pass);
    report.duration_ms = t0.elapsed().as_millis() as u64;
    report
}

type StepOutcome = Result<(bool, String), (Halt, String)>;

fn run_step(
    client: &Client,
    profile: &Profile,
    step: &Step,
    operator: &mut dyn Operator,
    cancel: &Cancel,
) -> StepOutcome {
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
            let r = Reader::new(client, profile, command, fields).map_err(halt)?;
            let series = r.samples(*samples, *interval, cancel).map_err(halt)?;
            Ok(verdict(r.fields.iter().zip(&series).map(|(f, values)| {
                let (lo, hi) = span(values);
                let tol = f.scale.abs() * 1e-6;
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
            })))
        }
        StepKind::Stable {
            command,
            fields,
            max_spread,
            samples,
            interval,
        } => {
            let r = Reader::new(client, profile, command, fields).map_err(halt)?;
            let series = r.samples(*samples, *interval, cancel).map_err(halt)?;
            Ok(verdict(r.fields.iter().zip(&series).map(|(f, values)| {
                let (lo, hi) = span(values);
                let spread = hi - lo;
                let ok = spread <= max_spread + f.scale.abs() * 1e-6;
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
            })))
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
            let r = Reader::new(client, profile, command, fields).map_err(halt)?;
            let measured = rises(&r, client, profile, action, *settle, *samples, cancel);
            // Whatever happened, turn it off.
            let stopped = send_action(client, profile, then);
            let (pass, mut detail, halted) = match measured {
                Ok((before, after)) => {
                    let (pass, detail) =
                        verdict(r.fields.iter().zip(&before).zip(&after).map(|((f, b), a)| {
                            let rise = a - b;
                            let ok = rise >= min_rise - f.scale.abs() * 1e-6;
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
            let r =
                Reader::new(client, profile, command, std::slice::from_ref(field)).map_err(halt)?;
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
            let values = ops::read(client, profile, cmd, &[]).map_err(|e| halt(e.into()))?;
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
    client: &Client,
    profile: &Profile,
    action: &Action,
    settle: Duration,
    samples: u32,
    cancel: &Cancel,
) -> Result<(Vec<f64>, Vec<f64>), Halt> {
    let before = r.samples(samples, DEFAULT_INTERVAL, cancel)?;
    send_action(client, profile, action)
        .map_err(|e| Halt::Device(format!("{}: {}", action.text, Halt::from(e).message())))?;
    if !sleep(settle, cancel) {
        return Err(Halt::Cancelled);
    }
    let after = r.samples(samples, DEFAULT_INTERVAL, cancel)?;
    Ok((means(&before), means(&after)))
}

fn means(series: &[Vec<f64>]) -> Vec<f64> {
    series
        .iter()
        .map(|v| v.iter().sum::<f64>() / v.len().max(1) as f64)
        .collect()
}

fn send_action(client: &Client, profile: &Profile, action: &Action) -> Result<(), OpError> {
    let cmd = profile
        .command(&action.command)
        .ok_or_else(|| OpError::unknown_command(profile, &action.command))?;
    client.request(crate::link::Request::for_command(
        profile,
        cmd,
        action.payload.clone(),
    ))?;
    Ok(())
}

/// Sleeps `d`, waking early when cancelled; false when cancelled.
fn sleep(d: Duration, cancel: &Cancel) -> bool {
    let end = Instant::now() + d;
    loop {
        if cancel.is_cancelled() {
            return false;
        }
        let now = Instant::now();
        if now >= end {
            return true;
        }
        std::thread::sleep((end - now).min(Duration::from_millis(10)));
    }
}

/// A value in display units, with the field's decimals (one more for means; at most 4) and unit.
fn show(f: &Field, x: f64) -> String {
    let d = f.decimals();
    let d = if (x / f.scale - (x / f.scale).round()).abs() < 1e-6 {
        d
    } else {
        d + 1
    };
    let text = format!("{x:.*}", d.min(4));
    format!("{text}{}", f.unit_suffix())
}

/// Reads fields of one command, in display units.
/// A step's verdict over its fields: it passes when every field does; their texts joined.
fn verdict(fields: impl Iterator<Item = (bool, String)>) -> (bool, String) {
    let mut pass = true;
    let mut texts = Vec::new();
    for (ok, text) in fields {
        pass &= ok;
        texts.push(text);
    }
    (pass, texts.join("; "))
}

/// The lowest and the highest of `values`.
fn span(values: &[f64]) -> (f64, f64) {
    values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(*v), hi.max(*v))
        })
}

struct Reader<'a> {
    client: &'a Client,
    profile: &'a Profile,
    cmd: &'a Command,
    fields: Vec<&'a Field>,
}

impl<'a> Reader<'a> {
    fn new(
        client: &'a Client,
        profile: &'a Profile,
        command: &str,
        fields: &[String],
    ) -> Result<Self, Halt> {
        let cmd = profile
            .command(command)
            .ok_or_else(|| Halt::Device(format!("{} has no command {command}", profile.id)))?;
        let fields = fields
            .iter()
            .map(|name| {
                cmd.reply
                    .iter()
                    .find(|f| f.ident.eq_ignore_ascii_case(name))
                    .ok_or_else(|| Halt::Device(format!("{} has no field {name}", cmd.ident)))
            })
            .collect::<Result<_, _>>()?;
        Ok(Self {
            client,
            profile,
            cmd,
            fields,
        })
    }

    /// One read: each field's raw value.
    fn raw_once(&self) -> Result<(Vec<i64>,), (Halt, String)> {
        let values = ops::read(self.client, self.profile, self.cmd, &[])
            .map_err(|e| (e.into(), String::new()))?;
        self.fields
            .iter()
            .map(|f| {
                values.int(&f.ident).ok_or_else(|| {
                    (
                        Halt::Device(format!("{}: the answer has no {}", self.cmd.ident, f.ident)),
                        String::new(),
                    )
                })
            })
            .collect::<Result<Vec<_>, _>>()
            .map(|v| (v,))
    }

    /// `n` reads `interval` apart: per field, its display values.
    fn samples(&self, n: u32, interval: Duration, cancel: &Cancel) -> Result<Vec<Vec<f64>>, Halt> {
        let mut out = vec![Vec::with_capacity(n as usize); self.fields.len()];
        for i in 0..n {
            if i > 0 && !sleep(interval, cancel) {
                return Err(Halt::Cancelled);
            }
            if cancel.is_cancelled() {
                return Err(Halt::Cancelled);
            }
            let (raw,) = self.raw_once().map_err(|(h, _)| h)?;
            for ((col, f), x) in out.iter_mut().zip(&self.fields).zip(raw) {
                col.push(x as f64 * f.scale);
            }
        }
        Ok(out)
    }
}

/// Appends the report to a JSON-lines log: one JSON document per run.
pub fn append_log(path: &Path, report: &Report) -> std::io::Result<()> {
    let line = serde_json::to_string(report).map_err(std::io::Error::other)?;
    let mut f = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)?;
    // One write per line, so that two stations appending to a shared log do not interleave.
    f.write_all(format!("{line}\n").as_bytes())?;
    f.sync_all()
}

// ---- The file's shape ----

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Doc {
    #[serde(default)]
    version: Option<u32>,
    profile: String,
    #[serde(default)]
    name: String,
    steps: Vec<DocStep>,
}

fn one() -> u32 {
    1
}

fn ten() -> u32 {
    10
}

fn three() -> u32 {
    3
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
enum DocStep {
    Range {
        name: String,
        command: String,
        #[serde(default)]
        field: Option<String>,
        #[serde(default)]
        fields: Vec<String>,
        min: Text,
        max: Text,
        #[serde(default = "one")]
        samples: u32,
        #[serde(default)]
        interval_ms: Option<u64>,
    },
    Stable {
        name: String,
        command: String,
        #[serde(default)]
        field: Option<String>,
        #[serde(default)]
        fields: Vec<String>,
        max_spread: Text,
        #[serde(default = "ten")]
        samples: u32,
        #[serde(default)]
        interval_ms: Option<u64>,
    },
    Rises {
        name: String,
        action: DocAction,
        command: String,
        #[serde(default)]
        field: Option<String>,
        #[serde(default)]
        fields: Vec<String>,
        min_rise: Text,
        settle_ms: u64,
        #[serde(default = "three")]
        samples: u32,
        then: DocAction,
    },
    Operator {
        name: String,
        prompt: String,
        command: String,
        field: String,
        expect_bits_seen: u64,
        timeout_ms: u64,
    },
    Reads {
        name: String,
        command: String,
        #[serde(default)]
        expect: BTreeMap<String, Text>,
    },
}

impl DocStep {
    fn name(&self) -> &str {
        match self {
            DocStep::Range { name, .. }
            | DocStep::Stable { name, .. }
            | DocStep::Rises { name, .. }
            | DocStep::Operator { name, .. }
            | DocStep::Reads { name, .. } => name,
        }
    }
}

/// `("MSP_SET_MOTOR", {"motor": "forward"})`
#[derive(Deserialize)]
struct DocAction(String, #[serde(default)] BTreeMap<String, Text>);

#[cfg(test)]
mod tests {
    use super::*;

    fn profile() -> std::sync::Arc<Profile> {
        crate::profile::Registry::builtin()
            .unwrap()
            .get("window-cleaner")
            .unwrap()
    }

    #[test]
    fn the_example_plan_loads() {
        let p = profile();
        let plan = Plan::load(Path::new("presets/window-cleaner-selftest.ron"), &p).unwrap();
        assert!(plan.steps.len() >= 8, "{plan:?}");
    }

    #[test]
    fn problems_carry_their_line() {
        let p = profile();
        let text = "(\n  version: 1,\n  profile: \"window-cleaner\",\n  steps: [\n    Range(name: \"a\", command: \"MSP_ADAPTER\", field: \"nope\", min: \"1\", max: \"2\"),\n    Reads(name: \"b\", command: \"MSP_NOPE\"),\n    Range(name: \"c\", command: \"MSP_ADAPTER\", field: \"batteryVoltage\", min: \"x\", max: \"2\"),\n  ],\n)\n";
        let e = Plan::parse("t.ron", text, &p).unwrap_err();
        let s = e.to_string();
        assert_eq!(e.problems.len(), 3, "{s}");
        assert_eq!(e.problems[0].line, 5, "{s}");
        assert!(e.problems[0].message.contains("no field 'nope'"), "{s}");
        assert_eq!(e.problems[1].line, 6, "{s}");
        assert!(
            e.problems[1].message.contains("no command 'MSP_NOPE'"),
            "{s}"
        );
        assert_eq!(e.problems[2].line, 7, "{s}");
        assert!(e.problems[2].message.contains("not a number"), "{s}");
    }
}
