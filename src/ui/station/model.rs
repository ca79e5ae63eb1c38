//! The device as its replies brought it: what each command last answered, what the last writes
//! left, the plotted telemetry, the reports it sent on its own, and (Tuya) what the module
//! session reported. Nothing is here before a reply brings it.

use super::running::RunningSet;
use super::tuya::TuyaModel;
use crate::link::{DeviceInfo, ExchangeError, Reply};
use crate::ops::{Check, FieldValues, OpError};
use crate::packet::Packet;
use crate::profile::{Profile, Value};
use crate::series::SeriesSet;
use std::collections::{HashMap, VecDeque};
use std::sync::Arc;
use std::time::Instant;

/// How many reports the device sent on its own are kept.
pub const REPORTS_CAPACITY: usize = 2000;
/// How many results of requests answered as events are kept.
pub const REPLIES_CAPACITY: usize = 256;

/// A reading of one command: the values its reply brought, or why there are none.
#[derive(Debug, Clone, PartialEq)]
pub enum Reading {
    /// Values, raw, in wire order, and when they came.
    Values(FieldValues, Instant),
    /// The read failed, or a write left the values unknown.
    Failed(ReadingError),
}

/// Why a command has no values to show.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ReadingError {
    /// The read (or the poll) failed.
    #[error("{0}")]
    Read(OpError),
    /// A write failed: nothing is known of what the device holds now.
    #[error("write failed: {0}; read again")]
    WriteFailed(OpError),
}

/// What a field shows after a write.
#[derive(Debug, Clone, PartialEq)]
pub enum Mark {
    /// The device holds what was written.
    Verified,
    /// The device holds something else.
    Mismatch(Value),
}

/// The device model.
pub struct DeviceModel {
    /// The profile in use.
    pub profile: Arc<Profile>,
    /// MSP: what CMD_VERSION said when the link came up.
    pub info: Option<Result<DeviceInfo, OpError>>,
    /// The latest reading of each command, by command id.
    pub readings: HashMap<u8, Reading>,
    /// Marks left by the last write, by (Get command id, field ident).
    pub marks: HashMap<(u8, String), Mark>,
    /// Plotted telemetry, by plot id.
    pub plots: HashMap<String, SeriesSet>,
    /// The last write to each Get's Set refused before anything was sent (a value or a
    /// relation the profile refuses), by Get command id, until the next write or read of it.
    pub refused: HashMap<u8, OpError>,
    /// Each plot's polling pace, by plot id: a poll slower than usual is a gap in it.
    pace: HashMap<String, crate::series::Pace>,
    /// When plotting started (t = 0 of the series); also marks the connection.
    pub t0: Instant,
    /// The wall-clock time of `t0`: the plots' time axis reads as the packet monitor's clock.
    pub t0_wall: std::time::SystemTime,
    /// Reports the device sent on its own (Tuya data points, MSP async), oldest first.
    pub reports: VecDeque<(Instant, Packet)>,
    /// Results of requests sent with `ReplyTo::Event(id)` (see
    /// [`super::LinkStatus::reply_id`]), by id; the oldest are dropped beyond
    /// [`REPLIES_CAPACITY`].
    pub replies: HashMap<u64, Result<Reply, ExchangeError>>,
    /// Tuya: what the module session has reported.
    pub tuya: TuyaModel,
    /// What the robot may be doing because this window told it to (fan on, motor running).
    pub running: RunningSet,
    /// Counts the spells in which what is shown was read: changes whenever it may no longer
    /// hold (a new connection, a lost link, a device that answers again after silence: maybe
    /// another unit, or the same one changed). Panels keep what they read (a ping, a power
    /// state) with the number it was read under. Verdicts on a unit outlive it: they go by
    /// the unit's identity ([`super::Verdicts`]).
    pub epoch: u64,
}

impl DeviceModel {
    /// The answers that have come for requests in `sent` (reply id → what the caller keeps of
    /// the request): each taken out of `sent` with its answer, so that it is handled once.
    pub fn take_answered<'a, T>(
        &'a self,
        sent: &mut HashMap<u64, T>,
    ) -> Vec<(T, &'a Result<Reply, ExchangeError>)> {
        let answered: Vec<u64> = sent
            .keys()
            .filter(|id| self.replies.contains_key(id))
            .copied()
            .collect();
        answered
            .into_iter()
            .filter_map(|id| Some((sent.remove(&id)?, self.replies.get(&id)?)))
            .collect()
    }

    /// A model of a device with `profile`, knowing nothing yet.
    pub fn new(profile: Arc<Profile>) -> Self {
        Self {
            profile,
            info: None,
            readings: HashMap::new(),
            marks: HashMap::new(),
            plots: HashMap::new(),
            refused: HashMap::new(),
            pace: HashMap::new(),
            t0: Instant::now(),
            t0_wall: std::time::SystemTime::now(),
            reports: VecDeque::new(),
            replies: HashMap::new(),
            tuya: TuyaModel::default(),
            running: RunningSet::default(),
            epoch: 0,
        }
    }

    /// Forgets everything for a new connection with `profile`.
    pub fn reset(&mut self, profile: Arc<Profile>) {
        self.profile = profile;
        self.forget_values();
        self.plots.clear();
        self.pace.clear();
        self.running.clear();
        self.tuya = self.tuya.next();
        self.t0 = Instant::now();
        self.t0_wall = std::time::SystemTime::now();
    }

    /// Forgets what the last unit showed (its values, the marks of writes to it, its version)
    /// when the connection ends or another unit may be answering; the plots keep their history
    /// (with a break), and what was left running stays shown.
    pub fn forget_values(&mut self) {
        self.readings.clear();
        self.refused.clear();
        self.marks.clear();
        self.info = None;
        self.epoch += 1;
        self.mark_gap();
    }

    /// Marks a gap in every plot now (the link was lost, polling paused): no line joins the
    /// samples on either side of it.
    pub fn mark_gap(&mut self) {
        let t = self.t0.elapsed().as_secs_f64();
        for set in self.plots.values_mut() {
            set.mark_break(t);
        }
        self.pace.clear();
    }

    /// Marks a gap at `at` in the plots of telemetry command `command` (its poll failed).
    fn mark_gap_of(&mut self, command: u8, at: Instant) {
        let t = at.saturating_duration_since(self.t0).as_secs_f64();
        let Some(cmd) = self.profile.command_by_id(command) else {
            return;
        };
        for plot in &self.profile.plots {
            if plot.command.eq_ignore_ascii_case(&cmd.ident)
                && let Some(set) = self.plots.get_mut(&plot.id)
            {
                set.mark_break(t);
            }
        }
    }

    /// The device's value of field `field` of command `get`, if a reply has brought one.
    pub fn value(&self, get: u8, field: &str) -> Option<&Value> {
        match self.readings.get(&get) {
            Some(Reading::Values(values, _)) => values.get(field),
            _ => None,
        }
    }

    /// The mark the last write left on field `field` of command `get`, while the field shows a
    /// value: a mark never stands beside a field that reads nothing.
    pub fn mark(&self, get: u8, field: &str) -> Option<&Mark> {
        self.value(get, field)?;
        self.marks.get(&(get, field.to_string()))
    }

    /// Takes a read's result (a job's). A write's mark stays on a field only while the field
    /// reads what the mark was made on: a read that brings another value (or none) drops it.
    pub fn on_read(&mut self, command: u8, result: Result<FieldValues, OpError>) {
        let before = match self.readings.get(&command) {
            Some(Reading::Values(values, _)) => Some(values),
            _ => None,
        };
        let after = result.as_ref().ok();
        self.refused.remove(&command);
        self.marks.retain(|(get, field), _| {
            *get != command
                || matches!(
                    (&before, after),
                    (Some(b), Some(a)) if b.get(field).is_some() && b.get(field) == a.get(field)
                )
        });
        let reading = match result {
            Ok(values) => Reading::Values(values, Instant::now()),
            Err(e) => Reading::Failed(ReadingError::Read(e)),
        };
        self.readings.insert(command, reading);
    }

    /// Takes a polled telemetry answer: its values, and the plotted fields' samples.
    pub fn on_telemetry(
        &mut self,
        command: u8,
        at: Instant,
        result: Result<Packet, ExchangeError>,
    ) {
        let p = match result {
            Ok(p) => p,
            Err(e) => {
                self.mark_gap_of(command, at);
                self.readings
                    .insert(command, Reading::Failed(ReadingError::Read(e.into())));
                return;
            }
        };
        let profile = self.profile.clone();
        let Some(cmd) = profile.command_by_id(command) else {
            return;
        };
        let d = match profile.decode(cmd, p.direction, &p.payload) {
            Ok(d) => d,
            Err(e) => {
                let e = OpError::answer(&cmd.ident, e);
                self.mark_gap_of(command, at);
                self.readings
                    .insert(command, Reading::Failed(ReadingError::Read(e)));
                return;
            }
        };
        let t = at.saturating_duration_since(self.t0).as_secs_f64();
        for plot in &profile.plots {
            if !plot.command.eq_ignore_ascii_case(&cmd.ident) {
                continue;
            }
            let set = self.plots.entry(plot.id.clone()).or_default();
            // A poll slower than usual: a gap before this sample, no line across it.
            if let Some(gap) = self.pace.entry(plot.id.clone()).or_default().sample(t) {
                set.mark_break(gap);
            }
            for name in &plot.fields {
                // As the readouts show it: scaled, or converted (a thermistor's °C); no point
                // where a conversion is undefined.
                if let Some(v) = d.values.iter().find(|v| v.ident.eq_ignore_ascii_case(name))
                    && let Value::Int(raw) = v.value
                    && let Some(y) = v.field.display_number(raw)
                {
                    let _ = set.push(name, t, y);
                }
            }
        }
        self.readings
            .insert(command, Reading::Values(FieldValues::from(d), at));
    }

    /// Takes a write's checks (or why it failed): the Get's values as read back, and a mark
    /// on each field.
    pub fn on_written(&mut self, set: u8, result: Result<Vec<Check>, OpError>) {
        let Some(get) = self.profile.command_by_id(set).and_then(|s| s.pair) else {
            return;
        };
        self.refused.remove(&get);
        match result {
            Ok(checks) => {
                let values: FieldValues = checks
                    .iter()
                    .map(|c| (c.field.clone(), c.read.clone()))
                    .collect();
                for c in &checks {
                    let mark = if c.ok() {
                        Mark::Verified
                    } else {
                        Mark::Mismatch(c.read.clone())
                    };
                    self.marks.insert((get, c.field.clone()), mark);
                }
                self.readings
                    .insert(get, Reading::Values(values, Instant::now()));
            }
            // Refused before anything was sent: the device holds what was last read, which
            // stays shown (with the edits); the refusal is said beside it.
            Err(e) if e.nothing_sent() => {
                self.refused.insert(get, e);
            }
            Err(e) => {
                // Nothing is known of what the device holds now: read it again before trusting it.
                self.readings
                    .insert(get, Reading::Failed(ReadingError::WriteFailed(e)));
            }
        }
    }

    /// Keeps a report the device sent on its own (and gives a Tuya report to the module model).
    pub fn on_report(&mut self, p: Packet) {
        self.tuya.on_report(&self.profile, &p);
        if self.reports.len() >= REPORTS_CAPACITY {
            self.reports.pop_front();
        }
        self.reports.push_back((Instant::now(), p));
    }

    /// Keeps the result of a request answered as an event.
    pub fn on_reply(&mut self, id: u64, result: Result<Reply, ExchangeError>) {
        if self.replies.len() >= REPLIES_CAPACITY
            && let Some(oldest) = self.replies.keys().min().copied()
        {
            self.replies.remove(&oldest);
        }
        self.replies.insert(id, result);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ops::Check;

    fn pwm(v: i64) -> FieldValues {
        let mut f = FieldValues::new();
        f.push("pwmValue", Value::Int(v));
        f
    }

    fn written(m: &mut DeviceModel, v: i64) {
        let check = Check {
            field: "pwmValue".into(),
            written: Value::Int(v),
            read: Value::Int(v),
        };
        m.on_written(220, Ok(vec![check]));
    }

    /// A write refused before anything was sent keeps what was read (issue 25, item 9); one
    /// that failed on the wire does not (the device may hold either).
    #[test]
    fn a_write_refused_before_sending_keeps_the_readings_and_a_failed_one_does_not() {
        let profile = crate::sim::msp_device::builtin_profile("window-cleaner").unwrap();
        let mut m = DeviceModel::new(profile);
        m.on_read(130, Ok(pwm(60)));
        let refused = OpError::OutOfRange {
            what: "pwm",
            value: 700,
            min: 0,
            max: 100,
            note: String::new(),
        };
        m.on_written(220, Err(refused));
        assert_eq!(m.value(130, "pwmValue"), Some(&Value::Int(60)));
        assert!(m.refused.contains_key(&130), "the refusal is said");
        m.on_read(130, Ok(pwm(60)));
        assert!(m.refused.is_empty(), "a read ends it");
        m.on_written(220, Err(OpError::Cancelled));
        assert_eq!(
            m.value(130, "pwmValue"),
            None,
            "after a failed write, read again"
        );
    }

    #[test]
    fn a_writes_mark_stays_while_the_field_reads_its_value_and_goes_with_another() {
        let profile = crate::sim::msp_device::builtin_profile("window-cleaner").unwrap();
        let mut m = DeviceModel::new(profile);
        written(&mut m, 60);
        assert_eq!(m.mark(130, "pwmValue"), Some(&Mark::Verified));
        m.on_read(130, Ok(pwm(60)));
        assert_eq!(
            m.mark(130, "pwmValue"),
            Some(&Mark::Verified),
            "read again, the same value"
        );
        m.on_read(130, Ok(pwm(85)));
        assert_eq!(m.mark(130, "pwmValue"), None, "another value, no mark");
        written(&mut m, 60);
        m.on_read(130, Err(OpError::Cancelled));
        m.on_read(130, Ok(pwm(60)));
        assert_eq!(
            m.mark(130, "pwmValue"),
            None,
            "after a failed read nothing tells that the value is the one written"
        );
    }
}
