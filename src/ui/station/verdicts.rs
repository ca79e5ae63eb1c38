//! The verdicts on the unit on the fixture: the last self-test's report and the last
//! provisioning's record. A verdict stays until the next run on this station replaces it, the
//! operator dismisses it, or the device identifies itself as another unit (hardware code,
//! firmware, API, build number, build date: CMD_VERSION and CMD_BUILD_INFO). A lost link, a
//! silent spell or a new connection alone say nothing of which unit is there: the verdict shown
//! then is still the last unit's, and says which unit that was.

use crate::link::DeviceInfo;
use crate::ops::selftest::Report;
use crate::ops::servo::provision::Record;

/// A verdict a job reports ([`crate::ui::jobs::JobOutput::Verdict`]).
#[derive(Debug, Clone)]
pub enum Verdict {
    /// A self-test ended (passed, failed, aborted or interrupted).
    SelfTest(Box<Report>),
    /// A servo was provisioned, failed a step, or its link was lost during one (no verdict).
    Provisioned(Box<Record>),
}

/// The verdicts on one unit.
#[derive(Debug, Clone, Default)]
pub struct Verdicts {
    /// The identity of the unit they are about, as the device gave it during the run (`None`:
    /// it did not identify itself, or a servo, which is known by its serial in its record).
    identity: Option<DeviceInfo>,
    /// The last self-test's report.
    pub selftest: Option<Box<Report>>,
    /// The last provisioning's record.
    pub provisioned: Option<Box<Record>>,
}

impl Verdicts {
    /// Takes `verdict`, the newest on the unit on the fixture; a verdict on another unit (the
    /// report names another identity) goes.
    pub fn take(&mut self, verdict: Verdict) {
        if let Verdict::SelfTest(r) = &verdict
            && let Some(info) = &r.device_info
        {
            self.identified(info);
            self.identity = Some(info.clone());
        }
        match verdict {
            Verdict::SelfTest(r) => self.selftest = Some(r),
            Verdict::Provisioned(r) => self.provisioned = Some(r),
        }
    }

    /// The device identified itself as `info`: the verdicts go when they are about a unit
    /// that identified itself otherwise.
    pub fn identified(&mut self, info: &DeviceInfo) {
        if self.identity.as_ref().is_some_and(|known| known != info) {
            *self = Self::default();
        }
    }

    /// The operator dismissed the verdicts.
    pub fn dismiss(&mut self) {
        *self = Self::default();
    }

    /// Whether there is no verdict.
    pub fn is_empty(&self) -> bool {
        self.selftest.is_none() && self.provisioned.is_none()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The self-test verdict kept on the unit: passed or not (`None`: none kept).
    fn pass(v: &Verdicts) -> Option<bool> {
        v.selftest.as_ref().map(|r| r.pass)
    }

    fn info(build: u8) -> DeviceInfo {
        DeviceInfo {
            hw: 0x03,
            firmware: "1.4.2".into(),
            api: "1.2".into(),
            build,
            flags: Some(0x0F),
            build_date: Some("2024-05-17 14:03:52".into()),
            extra: None,
        }
    }

    fn report(pass: bool, build: Option<u8>) -> Box<Report> {
        Box::new(Report {
            plan: "plan".into(),
            profile: "window-cleaner".into(),
            device: None,
            device_info: build.map(info),
            started: String::new(),
            duration_ms: 0,
            safe_state: Vec::new(),
            results: Vec::new(),
            aborted: None,
            pass,
        })
    }

    #[test]
    fn a_verdict_stays_with_its_unit_and_goes_when_another_identifies_itself() {
        let mut v = Verdicts::default();
        assert_eq!(pass(&v), None);
        v.take(Verdict::SelfTest(report(true, Some(37))));
        assert_eq!(pass(&v), Some(true));
        v.identified(&info(37));
        assert_eq!(
            pass(&v),
            Some(true),
            "the same unit, identified again, keeps it"
        );
        v.identified(&info(38));
        assert!(
            v.is_empty(),
            "another build is another unit: no verdict yet"
        );
        v.take(Verdict::SelfTest(report(false, Some(38))));
        assert_eq!(pass(&v), Some(false));
        v.dismiss();
        assert!(v.is_empty(), "dismissed");
    }

    #[test]
    fn a_provisioning_whose_link_was_lost_is_kept_until_the_next_run_replaces_it() {
        use crate::ops::servo::provision::Outcome;
        let record = |result| {
            Box::new(Record {
                time: String::new(),
                serial: Some(1),
                id: None,
                baud: None,
                result,
                mismatches: Vec::new(),
                recorded: Vec::new(),
                timeline: Vec::new(),
                writes: Vec::new(),
            })
        };
        let mut v = Verdicts::default();
        v.take(Verdict::Provisioned(record(Outcome::LinkLost {
            step: "set baud".into(),
            reason: "port lost".into(),
        })));
        assert!(
            v.provisioned
                .as_ref()
                .is_some_and(|r| r.result.link_lost().is_some()),
            "the no-verdict record is kept, shown until dismissed"
        );
        v.identified(&info(37));
        assert!(!v.is_empty(), "a servo's record outlives an identification");
        v.take(Verdict::Provisioned(record(Outcome::Pass)));
        assert!(
            v.provisioned.as_ref().is_some_and(|r| r.result.is_pass()),
            "the next run's record replaces it"
        );
    }

    #[test]
    fn a_verdict_on_a_unit_that_never_identified_stays_until_the_next_run() {
        let mut v = Verdicts::default();
        v.take(Verdict::SelfTest(report(false, None)));
        v.identified(&info(37));
        assert_eq!(pass(&v), Some(false), "nothing says it is another unit");
        v.take(Verdict::SelfTest(report(true, Some(37))));
        assert_eq!(pass(&v), Some(true), "the next run's verdict replaces it");
    }
}
