//! The verdicts on the unit now on the fixture: the last self-test's report and the last
//! provisioning's record, each kept with the unit it is about (the device model's `unit`), so
//! that a verdict never outlives its unit: another connection, a lost link or a device answering
//! again after silence (maybe another unit) takes it away.

use crate::ops::selftest::Report;
use crate::ops::servo::provision::Record;

/// A verdict a job reports ([`crate::ui::jobs::JobOutput::Verdict`]).
#[derive(Debug, Clone)]
pub enum Verdict {
    /// A self-test ended (passed, failed or aborted).
    SelfTest(Box<Report>),
    /// A servo was provisioned, or failed a step.
    Provisioned(Box<Record>),
}

impl Verdict {
    /// Whether the unit passed.
    pub fn pass(&self) -> bool {
        match self {
            Verdict::SelfTest(r) => r.pass,
            Verdict::Provisioned(r) => r.result.is_pass(),
        }
    }
}

/// The verdicts on one unit.
#[derive(Debug, Clone, Default)]
pub struct Verdicts {
    /// The unit they are about (the device model's `unit` when they came).
    unit: u64,
    /// The last self-test's report.
    pub selftest: Option<Box<Report>>,
    /// The last provisioning's record.
    pub provisioned: Option<Box<Record>>,
}

impl Verdicts {
    /// Takes `verdict` on `unit`; verdicts on another unit go.
    pub fn take(&mut self, verdict: Verdict, unit: u64) {
        self.forget_other_unit(unit);
        self.unit = unit;
        match verdict {
            Verdict::SelfTest(r) => self.selftest = Some(r),
            Verdict::Provisioned(r) => self.provisioned = Some(r),
        }
    }

    /// Forgets the verdicts when they are about another unit than `unit`.
    pub fn forget_other_unit(&mut self, unit: u64) {
        if self.unit != unit {
            *self = Self {
                unit,
                ..Self::default()
            };
        }
    }

    /// Whether there is no verdict.
    pub fn is_empty(&self) -> bool {
        self.selftest.is_none() && self.provisioned.is_none()
    }

    /// Whether the unit passed everything it was given a verdict on (`None`: no verdict yet).
    pub fn pass(&self) -> Option<bool> {
        let all = [
            self.selftest.as_ref().map(|r| r.pass),
            self.provisioned.as_ref().map(|r| r.result.is_pass()),
        ];
        all.into_iter().flatten().reduce(|a, b| a && b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report(pass: bool) -> Box<Report> {
        Box::new(Report {
            plan: "plan".into(),
            profile: "window-cleaner".into(),
            device: None,
            device_info: None,
            started: String::new(),
            duration_ms: 0,
            safe_state: Vec::new(),
            results: Vec::new(),
            aborted: None,
            pass,
        })
    }

    #[test]
    fn a_verdict_belongs_to_its_unit_and_goes_when_another_unit_comes() {
        let mut v = Verdicts::default();
        assert_eq!(v.pass(), None);
        v.take(Verdict::SelfTest(report(true)), 3);
        assert_eq!(v.pass(), Some(true));
        v.forget_other_unit(3);
        assert_eq!(v.pass(), Some(true), "the same unit keeps it");
        v.forget_other_unit(4);
        assert!(v.is_empty(), "another unit has no verdict yet");
        v.take(Verdict::SelfTest(report(false)), 4);
        assert_eq!(v.pass(), Some(false));
    }
}
