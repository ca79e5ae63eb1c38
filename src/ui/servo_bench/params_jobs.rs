//! The parameters tab's jobs: read every parameter or the user block, write changed values
//! (each read back) or the whole block, reset the user data; each reports to the panel.

use super::{Output, Servo, send};
use crate::i18n::Text;
use crate::ops::servo as ops;
use crate::ops::{Device, Run};
use crate::ui::Action;
use crate::ui::jobs::{Job, JobError};
use crate::ui::station::Station;

pub(super) fn read_all_job(rt: &Station, servo: Servo) -> Action {
    let profile = rt.device.profile.clone();
    Action::StartJob(Job::new(
        Text::new("read parameters", "读取参数"),
        move |client, _, sink| {
            ops::switch(client, servo.baud)?;
            let values = ops::read_all(Device::new(client, &profile), servo.id);
            let failed = values.iter().filter(|(_, v)| v.is_err()).count();
            let total = values.len();
            send(sink, Output::Values { servo, values });
            if failed == 0 {
                Ok(Text::new(
                    format!("servo {} read", servo.id),
                    format!("已读取舵机 {}", servo.id),
                ))
            } else {
                Err(JobError::Incomplete {
                    failed,
                    total,
                    what: Text::new(
                        format!("parameter(s) of servo {} not read", servo.id),
                        format!("舵机 {} 的参数未能读取", servo.id),
                    ),
                })
            }
        },
    ))
}

pub(super) fn read_block_job(rt: &Station, servo: Servo) -> Action {
    let profile = rt.device.profile.clone();
    Action::StartJob(Job::new(
        Text::new("read user block", "读取用户参数区"),
        move |client, _, sink| {
            ops::switch(client, servo.baud)?;
            match ops::read_block(Device::new(client, &profile), servo.id) {
                Ok(block) => {
                    let values = block.into_iter().map(|(pid, v)| (pid, Ok(v))).collect();
                    send(sink, Output::Values { servo, values });
                    Ok(Text::new(
                        format!("user block of servo {} read", servo.id),
                        format!("已读取舵机 {} 的用户参数区", servo.id),
                    ))
                }
                Err(e) => {
                    let values = profile
                        .block_params()
                        .map(|p| (p.id, Err(e.clone())))
                        .collect();
                    send(sink, Output::Values { servo, values });
                    Err(e.into())
                }
            }
        },
    ))
}

pub(super) fn write_job(rt: &Station, servo: Servo, values: Vec<(u8, i64)>) -> Action {
    let profile = rt.device.profile.clone();
    Action::StartJob(Job::new(
        Text::new("write parameters", "写入参数"),
        move |client, cancel, sink| {
            ops::switch(client, servo.baud)?;
            let mut run = Run::new(cancel, |p| sink.progress(p));
            let checks =
                ops::write_params(Device::new(client, &profile), servo.id, &values, &mut run);
            let bad = checks
                .iter()
                .filter(|(_, c)| !matches!(c, Ok(c) if c.ok()))
                .count();
            let n = checks.len();
            send(sink, Output::Written { servo, checks });
            if cancel.is_cancelled() {
                Err(JobError::CancelledAfter {
                    done: n,
                    total: values.len(),
                    what: "parameters",
                })
            } else if bad == 0 {
                Ok(Text::new(
                    format!("{n} parameter(s) written and verified"),
                    format!("{n} 个参数已写入并校验"),
                ))
            } else {
                Err(JobError::Incomplete {
                    failed: bad,
                    total: n,
                    what: Text::new("parameter(s) not verified", "参数未通过校验"),
                })
            }
        },
    ))
}

pub(super) fn block_job(rt: &Station, servo: Servo, values: Vec<(u8, i64)>) -> Action {
    let profile = rt.device.profile.clone();
    Action::StartJob(Job::new(
        Text::new("write user block", "写入用户参数区"),
        move |client, _, sink| {
            ops::switch(client, servo.baud)?;
            match ops::write_block(Device::new(client, &profile), servo.id, &values) {
                Ok(checks) => {
                    let bad = checks.iter().filter(|c| !c.ok()).count();
                    let total = checks.len();
                    let checks = checks
                        .into_iter()
                        .filter_map(|c| Some((profile.find_param(&c.field)?.id, Ok(c))))
                        .collect();
                    send(sink, Output::Written { servo, checks });
                    if bad == 0 {
                        Ok(Text::new(
                            "user block written and verified",
                            "用户参数区已写入并校验",
                        ))
                    } else {
                        Err(JobError::Incomplete {
                            failed: bad,
                            total,
                            what: Text::new("value(s) of the block not verified", "参数块中的值未通过校验"),
                        })
                    }
                }
                Err(e) => {
                    let checks = values
                        .iter()
                        .map(|(pid, _)| (*pid, Err(e.clone())))
                        .collect();
                    send(sink, Output::Written { servo, checks });
                    Err(e.into())
                }
            }
        },
    ))
}

pub(super) fn reset_job(rt: &Station, servo: Servo) -> Action {
    let profile = rt.device.profile.clone();
    Action::StartJob(Job::new(
        Text::new("reset user data", "恢复出厂设置"),
        move |client, _, sink| {
            ops::switch(client, servo.baud)?;
            let result = ops::reset_user_data(Device::new(client, &profile), servo.id, servo.baud);
            send(
                sink,
                Output::Reset {
                    servo,
                    result: result.clone(),
                },
            );
            let at = result?;
            let values = ops::read_all(Device::new(client, &profile), at.id);
            let now = Servo {
                id: at.id,
                baud: at.baud,
            };
            send(sink, Output::Values { servo: now, values });
            Ok(Text::new(
                format!(
                    "servo {} reset: now id {} at {} baud",
                    servo.id, at.id, at.baud
                ),
                format!(
                    "舵机 {} 已恢复出厂:现为 ID {},波特率 {}",
                    servo.id, at.id, at.baud
                ),
            ))
        },
    ))
}
