//! What a run records: each step's result, the run's report, and the JSON-lines log it is
//! appended to.

use crate::link::DeviceInfo;
use serde::Serialize;
use std::io::Write;
use std::path::Path;

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
    /// Each value measured with its unit and limits (Range: a field's mean of its samples;
    /// Stable: its spread; Rises: its rise), for the records.
    pub measurements: Vec<crate::ops::records::Measurement>,
    /// When the step started, ms since 1970 UTC.
    pub started_ms: i64,
    /// How long it took, ms.
    pub duration_ms: i64,
    /// Why the step ended the run without the unit failing it (the link was lost, the run
    /// cancelled, the operator aborted); `None` for a step that ran to its verdict (`pass`),
    /// and for one the device failed (no answer, an impossible value). An interrupted step
    /// has `pass` false, as the run did not pass, but says nothing of the part it checks.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub interrupted: Option<Interruption>,
}

/// Why a run stopped in a step without the unit failing it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Interruption {
    /// The port went away (unplugged, the adapter reset): `link lost during <step>`.
    LinkLost,
    /// Cancelled (Ctrl-C, the window's Cancel).
    Cancelled,
    /// The operator aborted at a prompt.
    OperatorAborted,
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
    /// The safe state set before the first step (the profile's STOP: motor, fan, spray off),
    /// one line per command: `MSP_SET_FAN pwm=0: acknowledged`. Empty when the run ended before
    /// it, or the profile names no STOP.
    pub safe_state: Vec<String>,
    /// The steps run, in order.
    pub results: Vec<StepResult>,
    /// Why the run ended before its last step (link lost, no answer, cancelled, operator abort).
    pub aborted: Option<String>,
    /// Every step ran and passed.
    pub pass: bool,
}

impl Report {
    /// The steps the unit failed (not those the run was interrupted in: see
    /// [`Self::interrupted`]).
    pub fn failed(&self) -> impl Iterator<Item = &StepResult> {
        self.results
            .iter()
            .filter(|r| !r.pass && r.interrupted.is_none())
    }

    /// The step the run was interrupted in, and why: the run has no verdict on the unit then
    /// (`link lost during <step>`), unless a step before it failed.
    pub fn interrupted(&self) -> Option<(&StepResult, Interruption)> {
        self.results
            .iter()
            .find_map(|r| r.interrupted.map(|why| (r, why)))
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
