//! What the servo's answers leave in the parameters tab: the values read, the marks of a write
//! (each kept only while the parameter reads what it was made on), the messages of a write and a
//! reset.

use super::params::{ParamMark, ParamsState};
use crate::ops::servo::Location;
use crate::ops::{Check, OpError};
use crate::profile::Value;

impl ParamsState {
    /// Takes values read; a write's mark stays on a parameter only while it reads what the
    /// mark was made on.
    pub(super) fn on_values(&mut self, values: Vec<(u8, Result<i64, OpError>)>) {
        for (id, v) in values {
            let same = matches!((self.values.get(&id), &v), (Some(Ok(a)), Ok(b)) if a == b);
            if !same {
                self.marks.remove(&id);
            }
            self.values.insert(id, v);
        }
    }

    pub(super) fn on_written(&mut self, checks: Vec<(u8, Result<Check, OpError>)>) {
        let (mut good, mut bad) = (0, 0);
        for (id, c) in checks {
            match c {
                Ok(c) => {
                    let read = match c.read {
                        Value::Int(v) => Some(v),
                        _ => None,
                    };
                    match read {
                        Some(r) => {
                            self.values.insert(id, Ok(r));
                        }
                        None => {
                            self.values.remove(&id);
                        }
                    }
                    if c.ok() {
                        good += 1;
                        self.marks.insert(id, ParamMark::Verified);
                    } else {
                        bad += 1;
                        self.marks
                            .insert(id, ParamMark::Mismatch(read.unwrap_or_default()));
                    }
                }
                Err(e) => {
                    bad += 1;
                    // Nothing is known of what the servo holds now.
                    self.values.remove(&id);
                    self.marks.insert(id, ParamMark::Failed(e));
                }
            }
        }
        let lang = self.lang;
        self.message = Some((
            bad == 0,
            format!(
                "{good} {}, {bad} {}",
                lang.tr("written and verified", "个已写入并校验"),
                lang.tr("not verified", "个未通过校验")
            ),
        ));
    }

    pub(super) fn on_reset(&mut self, result: Result<Location, OpError>) {
        let lang = self.lang;
        self.message = Some(match result {
            Ok(at) => (
                true,
                format!(
                    "{} {} @ {} baud ({})",
                    lang.tr(
                        "user data reset: the servo is now id",
                        "用户数据已重置: 舵机现在为ID"
                    ),
                    at.id,
                    at.baud,
                    lang.tr(
                        "verified; its parameters were read again",
                        "已校验; 参数已重新读取"
                    )
                ),
            ),
            Err(e) => (false, format!("{}: {e}", lang.tr("reset", "重置"))),
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn written(p: &mut ParamsState, id: u8, v: i64) {
        let check = Check {
            field: "f".into(),
            written: Value::Int(v),
            read: Value::Int(v),
        };
        p.on_written(vec![(id, Ok(check))]);
    }

    #[test]
    fn a_writes_mark_stays_while_the_parameter_reads_its_value_and_goes_with_another() {
        let mut p = ParamsState::default();
        written(&mut p, 41, 70);
        assert_eq!(p.marks.get(&41), Some(&ParamMark::Verified));
        p.on_values(vec![(41, Ok(70))]);
        assert_eq!(p.marks.get(&41), Some(&ParamMark::Verified), "the same");
        p.on_values(vec![(41, Ok(66))]);
        assert_eq!(p.marks.get(&41), None, "another value, no mark");
        written(&mut p, 41, 70);
        p.on_values(vec![(41, Err(OpError::Cancelled))]);
        assert_eq!(p.marks.get(&41), None, "a failed read, no mark");
    }
}
