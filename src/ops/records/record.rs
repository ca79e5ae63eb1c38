//! The record of one unit run, the same for every device kind and plan: the run, the unit, and
//! each step with its measurements and parameter writes. The README's "Records" section shows
//! its tables.

use serde::{Deserialize, Serialize};
use sha2::Digest;

/// Which operation made the record (`runs.kind`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RunKind {
    /// A window cleaner's line self-test (`msp selftest`, the Self-test panel).
    Selftest,
    /// A bus servo's production provisioning (`servo provision`, the Production tab).
    Provision,
    /// A preset applied with read-back (`preset apply`, the Presets panel).
    PresetApply,
    /// A Tuya MCU's conformance run.
    TuyaConform,
    /// A line station's plan (several operations as one run).
    Station,
    /// Not a unit's run: who reached a line station's engineer view (an unlock, a refused
    /// password, a lock, a slot opened in the engineer view and given back), kept beside the
    /// units' records so that a line can tell who changed what, when. No serial, no steps;
    /// FAIL for a refused password. Reports leave these out ([`super::query::Filter::access`]).
    Access,
}

impl RunKind {
    /// The name stored in `runs.kind`: `selftest`, `provision`, `preset-apply`, `tuya-conform`,
    /// `station`, `station-access`.
    pub fn name(self) -> &'static str {
        match self {
            RunKind::Selftest => "selftest",
            RunKind::Provision => "provision",
            RunKind::PresetApply => "preset-apply",
            RunKind::TuyaConform => "tuya-conform",
            RunKind::Station => "station",
            RunKind::Access => "station-access",
        }
    }

    /// The kind stored as `name`; `None` for a name this botbench does not know.
    pub fn from_name(name: &str) -> Option<RunKind> {
        [
            RunKind::Selftest,
            RunKind::Provision,
            RunKind::PresetApply,
            RunKind::TuyaConform,
            RunKind::Station,
            RunKind::Access,
        ]
        .into_iter()
        .find(|k| k.name() == name)
    }
}

/// PASS or FAIL, of a run or a step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Verdict {
    /// Done and verified.
    #[serde(rename = "PASS")]
    Pass,
    /// Not done, not verified, or out of limits.
    #[serde(rename = "FAIL")]
    Fail,
}

impl Verdict {
    /// `PASS` or `FAIL`, as stored.
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Pass => "PASS",
            Verdict::Fail => "FAIL",
        }
    }

    /// `Pass` when `pass`.
    pub fn of(pass: bool) -> Verdict {
        if pass { Verdict::Pass } else { Verdict::Fail }
    }

    /// The verdict stored as `name` (`PASS`; anything else is `Fail`).
    pub fn from_name(name: &str) -> Verdict {
        Verdict::of(name == "PASS")
    }
}

/// How the unit's serial number was obtained (`runs.serial_source`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SerialSource {
    /// Scanned from the unit's label by a barcode scanner (the station).
    Scanned,
    /// Read from the device itself (the servo's serial-number parameter).
    Device,
    /// Typed by a person (`--serial` on the command line, a field in the window).
    Typed,
}

impl SerialSource {
    /// `scanned`, `device` or `typed`, as stored.
    pub fn name(self) -> &'static str {
        match self {
            SerialSource::Scanned => "scanned",
            SerialSource::Device => "device",
            SerialSource::Typed => "typed",
        }
    }

    /// The source stored as `name`.
    pub fn from_name(name: &str) -> Option<SerialSource> {
        match name {
            "scanned" => Some(SerialSource::Scanned),
            "device" => Some(SerialSource::Device),
            "typed" => Some(SerialSource::Typed),
            _ => None,
        }
    }
}

/// Where and by whom a run was made: what the station (issue 27) or the command line's
/// `--station`, `--slot`, `--operator` options fill in. Every field is optional: a bench run
/// without a station leaves them empty.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RunContext {
    /// The station's id (`line3-st2`): its bundle's `id`, `--station` or `BOTBENCH_STATION`.
    pub station: Option<String>,
    /// The slot within the station (`1`, `A`).
    pub slot: Option<String>,
    /// The fixture's name on that slot.
    pub fixture: Option<String>,
    /// Who ran it: `--operator` or `BOTBENCH_OPERATOR`, or the station's login.
    pub operator: Option<String>,
    /// SHA-256 (lower-case hex, 64 digits) of the station bundle, over its text and every file
    /// it names; `None` outside a station.
    pub bundle_sha256: Option<String>,
}

/// The unit under test.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Unit {
    /// Its serial number, as text (a servo's 32-bit number in decimal, a scanned label as
    /// scanned); `None` when nobody knew it.
    pub serial: Option<String>,
    /// How the serial number was obtained; `None` with no serial.
    pub serial_source: Option<SerialSource>,
    /// The hardware code (`0x03` from MSP CMD_VERSION, a servo's type).
    pub hardware: Option<String>,
    /// The firmware version (`1.4.2`).
    pub firmware: Option<String>,
    /// The build (`7 (2025-06-01 10:00:00)`).
    pub build: Option<String>,
}

/// One measured value with its unit and limits.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Measurement {
    /// What was measured: the profile's field ident with what of it (`batteryVoltage`,
    /// `gyroX spread`, `adcLeftWheel rise`).
    pub name: String,
    /// Its unit as the profile gives it (`V`, `°/s`; empty when it has none).
    pub unit: String,
    /// The lowest value allowed, in `unit`; `None` when only an upper limit applies.
    pub low: Option<f64>,
    /// The highest value allowed, in `unit`; `None` when only a lower limit applies.
    pub high: Option<f64>,
    /// The value, in `unit` (a Range step's mean of its samples).
    pub value: f64,
    /// Whether it met its limits (a Range step's every sample, not only the mean).
    pub pass: bool,
}

/// One parameter written, with its value before and after.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ParamWrite {
    /// The parameter or field (`over_temprature`, `MSP_SET_FAN.pwm`).
    pub name: String,
    /// Its unit (empty when none).
    pub unit: String,
    /// The value written, in display units.
    pub value: String,
    /// The value the device held before, where it was read.
    pub before: Option<String>,
    /// The value read back after the write; `None` when it could not be read.
    pub after: Option<String>,
}

/// One step of a run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StepRecord {
    /// The step's name (`Battery voltage`, `assign id`).
    pub name: String,
    /// Its kind (`Range`, `Stable`, `Rises`, `Operator`, `Reads`, `Identify`; provisioning's
    /// and preset apply's `Provision`, `Write`).
    pub kind: String,
    /// When it started, ms since 1970-01-01 UTC.
    pub started_ms: i64,
    /// How long it took, ms.
    pub duration_ms: i64,
    /// PASS or FAIL.
    pub verdict: Verdict,
    /// Why it failed, said so that the same cause reads the same for every unit (the Pareto
    /// groups by it): `out of limits: batteryVoltage`, `link lost`; `None` on PASS.
    pub reason: Option<String>,
    /// What was seen, as shown to the operator, values included.
    pub detail: String,
    /// Every value measured, with its limits.
    pub measurements: Vec<Measurement>,
    /// Every parameter written.
    pub writes: Vec<ParamWrite>,
}

/// The record of one unit run: stored whole (one transaction) or not at all.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// A random UUID (v4): the record's key everywhere it is stored, so that forwarding from
    /// the spool never stores it twice.
    pub uuid: String,
    /// The operation.
    pub kind: RunKind,
    /// When the run started and ended, ms since 1970-01-01 UTC.
    pub started_ms: i64,
    /// See `started_ms`.
    pub ended_ms: i64,
    /// The recording PC's offset from UTC at the start, minutes (shifts are local time).
    pub utc_offset_min: i32,
    /// The run's verdict: PASS only when every step passed.
    pub verdict: Verdict,
    /// The first failed step's name, on FAIL.
    pub failed_step: Option<String>,
    /// Why the run failed (that step's reason, or why it ended early).
    pub reason: Option<String>,
    /// Station, slot, fixture, operator, bundle hash.
    pub context: RunContext,
    /// The PC's host name.
    pub host: String,
    /// The plan's (or preset's) name.
    pub plan: String,
    /// SHA-256 of the plan file as read (lower-case hex); `None` when the run had no file.
    pub plan_sha256: Option<String>,
    /// The device profile's id.
    pub profile: String,
    /// botbench's version (`0.1.0`).
    pub software: String,
    /// The git commit botbench was built from (`unknown` outside git).
    pub commit: String,
    /// The unit.
    pub unit: Unit,
    /// The steps, in the order run.
    pub steps: Vec<StepRecord>,
}

impl Record {
    /// A record of `kind` started now, with a fresh UUID and this botbench's version, PASS
    /// until [`Record::finish`] says otherwise.
    pub fn start(kind: RunKind, plan: &str, plan_sha256: Option<String>, profile: &str) -> Record {
        let now = chrono::Local::now();
        Record {
            uuid: uuid::Uuid::new_v4().to_string(),
            kind,
            started_ms: now.timestamp_millis(),
            ended_ms: now.timestamp_millis(),
            utc_offset_min: now.offset().local_minus_utc() / 60,
            verdict: Verdict::Pass,
            failed_step: None,
            reason: None,
            context: RunContext::default(),
            host: host_name(),
            plan: plan.to_string(),
            plan_sha256,
            profile: profile.to_string(),
            software: env!("CARGO_PKG_VERSION").to_string(),
            commit: env!("BOTBENCH_COMMIT").to_string(),
            unit: Unit::default(),
            steps: Vec::new(),
        }
    }

    /// Ends the run now: its verdict PASS when `aborted` is `None` and every step passed;
    /// otherwise FAIL at the first failed step (or `aborted`'s step and reason).
    pub fn finish(&mut self, aborted: Option<(String, String)>) {
        self.ended_ms = now_ms().max(self.started_ms);
        let failed = self
            .steps
            .iter()
            .find(|s| s.verdict == Verdict::Fail)
            .map(|s| (s.name.clone(), s.reason.clone().unwrap_or_default()));
        match failed.or(aborted) {
            None => {
                self.verdict = Verdict::Pass;
                self.failed_step = None;
                self.reason = None;
            }
            Some((step, reason)) => {
                self.verdict = Verdict::Fail;
                self.failed_step = Some(step);
                self.reason = Some(reason);
            }
        }
    }

    /// The unit's key: `profile:serial`, or the record's UUID when the serial is unknown (each
    /// such run is a unit of its own).
    pub fn unit_key(&self) -> String {
        match &self.unit.serial {
            Some(s) => format!("{}:{s}", self.profile),
            None => self.uuid.clone(),
        }
    }
}

/// A step being timed: [`StepClock::start`] when it begins, [`StepClock::end`] when its
/// verdict is known.
#[derive(Debug, Clone)]
pub struct StepClock {
    started_ms: i64,
    started: std::time::Instant,
}

impl StepClock {
    /// Starts timing now.
    pub fn start() -> StepClock {
        StepClock {
            started_ms: now_ms(),
            started: std::time::Instant::now(),
        }
    }

    /// The step's record: its start and duration from this clock, PASS when `reason` is `None`.
    pub fn end(
        &self,
        name: &str,
        kind: &str,
        reason: Option<String>,
        detail: String,
    ) -> StepRecord {
        StepRecord {
            name: name.to_string(),
            kind: kind.to_string(),
            started_ms: self.started_ms,
            duration_ms: i64::try_from(self.started.elapsed().as_millis()).unwrap_or(i64::MAX),
            verdict: Verdict::of(reason.is_none()),
            reason,
            detail,
            measurements: Vec::new(),
            writes: Vec::new(),
        }
    }
}

/// Now, ms since 1970-01-01 UTC.
pub fn now_ms() -> i64 {
    chrono::Utc::now().timestamp_millis()
}

/// SHA-256 of `bytes`, lower-case hex (64 digits).
pub fn sha256_hex(bytes: &[u8]) -> String {
    let digest = sha2::Sha256::digest(bytes);
    digest.iter().map(|b| format!("{b:02x}")).collect()
}

/// SHA-256 of the file at `path` as it is now (lower-case hex); `None` when it cannot be read
/// (the run itself has read it already, so this is only a file removed since).
pub fn file_sha256(path: &std::path::Path) -> Option<String> {
    std::fs::read(path).ok().map(|b| sha256_hex(&b))
}

/// This PC's host name (`/etc/hostname`, `HOSTNAME`, `COMPUTERNAME`), or `unknown`.
pub fn host_name() -> String {
    std::fs::read_to_string("/etc/hostname")
        .ok()
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty())
        .or_else(|| std::env::var("HOSTNAME").ok())
        .or_else(|| std::env::var("COMPUTERNAME").ok())
        .unwrap_or_else(|| "unknown".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finish_fails_at_the_first_failed_step() {
        let mut r = Record::start(RunKind::Selftest, "plan", None, "window-cleaner");
        let clock = StepClock::start();
        r.steps.push(clock.end("a", "Range", None, String::new()));
        r.steps
            .push(clock.end("b", "Range", Some("out of limits: x".into()), String::new()));
        r.steps
            .push(clock.end("c", "Range", Some("out of limits: y".into()), String::new()));
        r.finish(None);
        assert_eq!(r.verdict, Verdict::Fail);
        assert_eq!(r.failed_step.as_deref(), Some("b"));
        assert_eq!(r.reason.as_deref(), Some("out of limits: x"));
        let mut ok = Record::start(RunKind::Selftest, "plan", None, "window-cleaner");
        ok.steps.push(clock.end("a", "Range", None, String::new()));
        ok.finish(None);
        assert_eq!(ok.verdict, Verdict::Pass);
        ok.finish(Some(("cancel".into(), "cancelled".into())));
        assert_eq!(ok.verdict, Verdict::Fail);
    }

    #[test]
    fn sha256_of_abc_is_the_fips_vector() {
        assert_eq!(
            sha256_hex(b"abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }
}
