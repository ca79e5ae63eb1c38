//! The steps of provisioning one fresh servo, in order: detect it, read its serial number, give
//! it the next free id, switch it to the plan's rate, write the plan's parameters, verify
//! everything at the new id and rate, and read what the plan records. Each step ends the run at
//! its first failure, which names the step ([`Failure`]) and says whether the port went.

use super::{ProvisionState, Record, Resolved, find_fresh, reason, search_order, step};
use crate::ops::records::ParamWrite;
use crate::ops::servo::{self, Presence, switch};
use crate::ops::{Cancel, Device, OpError, Progress, Run};
use crate::profile::{Input, Param, Value};

/// The step that ended the run, and why: a failure of the servo's, or the port lost.
#[derive(Debug)]
pub(super) struct Failure {
    /// The step, one of [`step`].
    pub(super) step: &'static str,
    /// Why, as the record says it.
    pub(super) why: String,
    /// What the link said when the port went away during the step (`None`: it did not).
    pub(super) lost: Option<String>,
}

impl Failure {
    /// `step` failed: `why`.
    fn new(step: &'static str, why: String) -> Self {
        Self {
            step,
            why,
            lost: None,
        }
    }

    /// `step` met the operation's error `e`, said `why`: the port lost when that is what `e`
    /// is ([`OpError::lost_port`]), else a failure.
    fn of(step: &'static str, e: &OpError, why: String) -> Self {
        Self {
            step,
            why,
            lost: e.lost_port().map(str::to_string),
        }
    }
}

/// A provisioning under way: the servo, the plan resolved against the profile, the run's
/// cancel flag and progress.
pub(super) struct Provisioning<'a, 'r> {
    pub(super) dev: Device<'a>,
    pub(super) resolved: &'a Resolved<'a>,
    /// The plan's rate.
    pub(super) target: u32,
    /// The plan's ids, in the order they are given out.
    pub(super) candidates: Vec<u8>,
    pub(super) run: &'a mut Run<'r>,
    pub(super) cancel: &'r Cancel,
    /// Steps reported so far, of `total`.
    pub(super) done: u64,
    pub(super) total: u64,
    /// Each step begun, with when (ms since 1970 UTC): the records' step times.
    pub(super) timeline: Vec<(String, i64)>,
}

impl Provisioning<'_, '_> {
    /// Reports `step` (with `detail`) as under way; refuses to go on once cancelled.
    fn at(&mut self, step: &'static str, detail: String) -> Result<(), Failure> {
        self.timeline
            .push((step.to_string(), crate::ops::records::record::now_ms()));
        let said = step::said(step);
        let message = if detail.is_empty() {
            said
        } else {
            said.then(": ", &crate::i18n::Text::same(detail))
        };
        self.run.report(Progress {
            done: self.done,
            total: self.total,
            message,
        });
        self.done += 1;
        self.go_on(step)
    }

    /// [`Failure`] at `step` once cancelled.
    fn go_on(&self, step: &'static str) -> Result<(), Failure> {
        if self.cancel.is_cancelled() {
            Err(Failure::new(step, "cancelled by the operator".into()))
        } else {
            Ok(())
        }
    }

    /// Every step, into `record`; the port is left at the rate the servo was last found at.
    pub(super) fn steps(
        &mut self,
        state: &mut ProvisionState,
        record: &mut Record,
    ) -> Result<(), Failure> {
        let fresh = servo::factory_location(self.dev.profile).id;
        let baud = self.detect(fresh)?;
        record.baud = Some(baud);
        let serial = self.serial(fresh, baud)?;
        record.serial = Some(serial);
        let id = self.assign_id(state, fresh, baud)?;
        record.id = Some(id);
        record.writes.push((
            step::ASSIGN_ID.into(),
            ParamWrite {
                name: "id".into(),
                unit: String::new(),
                value: id.to_string(),
                before: Some(fresh.to_string()),
                after: Some(id.to_string()),
            },
        ));
        self.set_baud(id, baud, record)?;
        let apply_mismatch = self.apply(id, record)?;
        self.verify(id, serial, record, apply_mismatch)?;
        self.record(id, record)?;
        self.run.report(Progress {
            done: self.total,
            total: self.total,
            message: crate::i18n::Text::new("done", "完成"),
        });
        Ok(())
    }

    /// Detect: exactly one fresh servo (at id `fresh`), at one baud rate; the port is left
    /// there. Returns that rate.
    fn detect(&mut self, fresh: u8) -> Result<u32, Failure> {
        self.at(step::DETECT, String::new())?;
        let fail = |why: String| Failure::new(step::DETECT, why);
        let op = |e: OpError| Failure::of(step::DETECT, &e, e.to_string());
        let order = search_order(self.dev.profile, self.target);
        let found = find_fresh(self.dev, &order).map_err(op)?;
        let baud = match found.as_slice() {
            [] => {
                return Err(fail(format!(
                    "no fresh servo (id {fresh}) answers at any baud rate"
                )));
            }
            [(b, Presence::Present)] => *b,
            [(b, Presence::PossibleDuplicate(e))] => {
                return Err(fail(format!(
                    "more than one servo answers at id {fresh} at {b} baud (garbled answers: {e}); leave one fresh servo on the bus"
                )));
            }
            many => {
                let rates: Vec<String> = many.iter().map(|(b, _)| b.to_string()).collect();
                return Err(fail(format!(
                    "more than one servo: fresh servos (id {fresh}) answer at {} baud; leave one on the bus",
                    rates.join(" and ")
                )));
            }
        };
        switch(self.dev.client, baud).map_err(op)?;
        Ok(baud)
    }

    /// Its serial number, so that even a failure names the servo.
    fn serial(&mut self, fresh: u8, baud: u32) -> Result<u32, Failure> {
        self.at(step::SERIAL, String::new())?;
        let serial = servo::serial_param(self.dev.profile)
            .and_then(|p| super::read(self.dev, fresh, p.id))
            .map_err(|e| Failure::of(step::SERIAL, &e, reason(&e, fresh, baud)))?;
        u32::try_from(serial).map_err(|_| {
            Failure::new(
                step::SERIAL,
                format!("the servo reports serial number {serial}, which does not fit 32 bits"),
            )
        })
    }

    /// The next free id (not given out before, and silent at every rate: a servo at another
    /// rate is still on the bus, and would share the id once moved), given to the fresh servo
    /// found at `baud`.
    fn assign_id(
        &mut self,
        state: &mut ProvisionState,
        fresh: u8,
        baud: u32,
    ) -> Result<u8, Failure> {
        self.at(step::ASSIGN_ID, String::new())?;
        let chosen = self.free_id(state)?;
        let op = |e: &OpError, why: String| Failure::of(step::ASSIGN_ID, e, why);
        switch(self.dev.client, baud).map_err(|e| op(&e, e.to_string()))?;
        let Some((index, id)) = chosen else {
            let why = "no free id left in the plan's ids".into();
            return Err(Failure::new(step::ASSIGN_ID, why));
        };
        servo::set_id(self.dev, fresh, id, self.cancel)
            .map_err(|e| op(&e, reason(&e, fresh, baud)))?;
        state.next = index + 1;
        state.assigned.push(id);
        Ok(id)
    }

    /// The first of the plan's ids from `state.next` on that was not given out and is silent at
    /// every rate (an id found in use is never offered again), with its index.
    fn free_id(&self, state: &mut ProvisionState) -> Result<Option<(usize, u8)>, Failure> {
        let order = search_order(self.dev.profile, self.target);
        for (i, &id) in self.candidates.iter().enumerate().skip(state.next) {
            self.go_on(step::ASSIGN_ID)?;
            if state.assigned.contains(&id) {
                state.next = i + 1;
                continue;
            }
            match super::id_is_free(self.dev.client, id, &order) {
                Ok(true) => return Ok(Some((i, id))),
                // In use: never offered again.
                Ok(false) => state.next = i + 1,
                Err(e) => return Err(Failure::of(step::ASSIGN_ID, &e, e.to_string())),
            }
        }
        Ok(None)
    }

    /// The plan's rate for servo `id`, now at `baud` (nothing to do when they are the same);
    /// `record` holds the rate the servo is at, none while it is not known.
    fn set_baud(&mut self, id: u8, baud: u32, record: &mut Record) -> Result<(), Failure> {
        let target = self.target;
        self.at(step::SET_BAUD, format!("{baud} → {target}"))?;
        if baud == target {
            return Ok(());
        }
        let fail = |why: String| Failure::new(step::SET_BAUD, why);
        match servo::ping(self.dev.client, id, 3) {
            Ok(Presence::Present) => {}
            Ok(other) => {
                return Err(fail(format!(
                    "servo {id} did not answer at {baud} baud before the change ({other:?})"
                )));
            }
            Err(e) => return Err(Failure::of(step::SET_BAUD, &e, reason(&e, id, baud))),
        }
        record.baud = None;
        let now = servo::set_baud(self.dev, id, self.resolved.option)
            .map_err(|e| Failure::of(step::SET_BAUD, &e, reason(&e, id, target)))?;
        record.baud = Some(now);
        record.writes.push((
            step::SET_BAUD.into(),
            ParamWrite {
                name: "baud".into(),
                unit: "baud".into(),
                value: target.to_string(),
                before: Some(baud.to_string()),
                after: Some(now.to_string()),
            },
        ));
        Ok(())
    }

    /// The plan's parameters, each read back; a value read back otherwise is a mismatch in
    /// `record` (and the returned `true`), not a failure yet.
    fn apply(&mut self, id: u8, record: &mut Record) -> Result<bool, Failure> {
        let mut apply_mismatch = false;
        for &(param, raw) in &self.resolved.writes {
            let ident = &param.field.ident;
            self.at(step::APPLY, ident.clone())?;
            let before = servo::read_param(self.dev, id, param)
                .ok()
                .map(|v| param.field.format(&Value::Int(v)));
            let written = |check: &crate::ops::Check| ParamWrite {
                name: ident.clone(),
                unit: param.field.unit.clone(),
                value: param.field.format(&check.written),
                before: before.clone(),
                after: Some(param.field.format(&check.read)),
            };
            match servo::write_param(self.dev, id, param, Input::Raw(Value::Int(raw))) {
                Ok(check) if check.ok() => {
                    record.writes.push((step::APPLY.into(), written(&check)));
                }
                Ok(check) => {
                    record.writes.push((step::APPLY.into(), written(&check)));
                    apply_mismatch = true;
                    record
                        .mismatches
                        .push(super::mismatch(param, &check.written, &check.read));
                }
                Err(e) => {
                    let why = format!("{ident}: {}", reason(&e, id, self.target));
                    return Err(Failure::of(step::APPLY, &e, why));
                }
            }
        }
        Ok(apply_mismatch)
    }

    /// Everything again, at the new id and rate: the servo answers cleanly, and its serial
    /// number, id, baud option and the plan's parameters read back as given. A value that does
    /// not fails the run (at apply when a write already read back otherwise).
    fn verify(
        &mut self,
        id: u8,
        serial: u32,
        record: &mut Record,
        apply_mismatch: bool,
    ) -> Result<(), Failure> {
        self.at(step::VERIFY, String::new())?;
        let target = self.target;
        let fail = |why: String| Failure::new(step::VERIFY, why);
        let op = |e: &OpError, why: String| Failure::of(step::VERIFY, e, why);
        match servo::ping(self.dev.client, id, 3) {
            Ok(Presence::Present) => {}
            Ok(other) => {
                return Err(fail(format!(
                    "servo {id} did not answer cleanly at {target} baud ({other:?})"
                )));
            }
            Err(e) => return Err(op(&e, reason(&e, id, target))),
        }
        let expected = self
            .expected(id, serial)
            .map_err(|e| op(&e, e.to_string()))?;
        for (pid, want) in expected {
            let got = self.read_back(id, pid)?;
            if got.1 != want {
                let line = super::mismatch(got.0, &Value::Int(want), &Value::Int(got.1));
                if !record.mismatches.contains(&line) {
                    record.mismatches.push(line);
                }
            }
        }
        if record.mismatches.is_empty() {
            return Ok(());
        }
        let step = if apply_mismatch {
            step::APPLY
        } else {
            step::VERIFY
        };
        let n = record.mismatches.len();
        Err(Failure::new(
            step,
            format!("{n} value(s) do not read back as written"),
        ))
    }

    /// What servo `id` must hold after provisioning: its serial number, its id, the plan's baud
    /// option and parameters, by parameter id.
    fn expected(&self, id: u8, serial: u32) -> Result<Vec<(u8, i64)>, OpError> {
        let profile = self.dev.profile;
        let mut expected = vec![
            (servo::serial_param(profile)?.id, i64::from(serial)),
            (servo::id_param(profile)?.id, i64::from(id)),
            (
                servo::baud_param(profile)?.0.id,
                i64::from(self.resolved.option),
            ),
        ];
        expected.extend(self.resolved.writes.iter().map(|(p, raw)| (p.id, *raw)));
        Ok(expected)
    }

    /// Parameter `pid` of servo `id`, as it reads now (at verify).
    fn read_back(&self, id: u8, pid: u8) -> Result<(&Param, i64), Failure> {
        let param = self.dev.profile.param(pid).ok_or_else(|| {
            Failure::new(step::VERIFY, format!("the profile has no parameter {pid}"))
        })?;
        let got = super::read(self.dev, id, pid).map_err(|e| {
            let why = format!("{}: {}", param.field.ident, reason(&e, id, self.target));
            Failure::of(step::VERIFY, &e, why)
        })?;
        Ok((param, got))
    }

    /// What the plan records, read from servo `id` into `record`.
    fn record(&mut self, id: u8, record: &mut Record) -> Result<(), Failure> {
        self.at(step::RECORD, String::new())?;
        for (i, param) in self.resolved.record.iter().enumerate() {
            let v = servo::read_param(self.dev, id, param).map_err(|e| {
                let why = format!("{}: {}", param.field.ident, reason(&e, id, self.target));
                Failure::of(step::RECORD, &e, why)
            })?;
            if let Some(slot) = record.recorded.get_mut(i) {
                slot.1 = Some(param.field.format(&Value::Int(v)));
            }
        }
        Ok(())
    }
}
