//! Measuring: reads of one command's fields in display units, and the arithmetic of a verdict.

use super::plan::Action;
use super::run::Halt;
use crate::ops::Device;
use crate::ops::exchange as ops;
use crate::ops::{Cancel, OpError};
use crate::profile::{Command, Field};
use std::time::{Duration, Instant};

pub(super) fn means(series: &[Vec<f64>]) -> Vec<f64> {
    series
        .iter()
        .map(|v| v.iter().sum::<f64>() / v.len().max(1) as f64)
        .collect()
}

pub(super) fn send_action(dev: Device<'_>, action: &Action) -> Result<(), OpError> {
    let Device { client, profile } = dev;
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
pub(super) fn sleep(d: Duration, cancel: &Cancel) -> bool {
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
pub(super) fn show(f: &Field, x: f64) -> String {
    let d = f.decimals();
    let d = if (x / f.scale - (x / f.scale).round()).abs() < 1e-6 {
        d
    } else {
        d + 1
    };
    let text = format!("{x:.*}", d.min(4));
    format!("{text}{}", f.unit_suffix())
}

/// A step's verdict over its fields: it passes when every field does; their texts joined.
pub(super) fn verdict(fields: impl Iterator<Item = (bool, String)>) -> (bool, String) {
    let mut pass = true;
    let mut texts = Vec::new();
    for (ok, text) in fields {
        pass &= ok;
        texts.push(text);
    }
    (pass, texts.join("; "))
}

/// How far a measured value may pass a limit and still meet it: a millionth of the field's
/// step, so that a value equal to the limit as shown is not failed by floating-point rounding.
pub(super) fn tolerance(f: &Field) -> f64 {
    f.scale.abs() * 1e-6
}

/// The lowest and the highest of `values`.
pub(super) fn span(values: &[f64]) -> (f64, f64) {
    values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(*v), hi.max(*v))
        })
}

/// Reads fields of one command, in display units.
pub(super) struct Reader<'a> {
    dev: Device<'a>,
    cmd: &'a Command,
    /// The fields read, in the order asked.
    pub(super) fields: Vec<&'a Field>,
}

impl<'a> Reader<'a> {
    pub(super) fn new(dev: Device<'a>, command: &str, fields: &[String]) -> Result<Self, Halt> {
        let profile = dev.profile;
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
        Ok(Self { dev, cmd, fields })
    }

    /// One read: each field's raw value.
    pub(super) fn raw_once(&self) -> Result<(Vec<i64>,), (Halt, String)> {
        let values = ops::read(self.dev, self.cmd, &[]).map_err(|e| (e.into(), String::new()))?;
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
    pub(super) fn samples(
        &self,
        n: u32,
        interval: Duration,
        cancel: &Cancel,
    ) -> Result<Vec<Vec<f64>>, Halt> {
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

    /// `n` reads `interval` apart, each field's display values judged by `judge` (the field,
    /// its values, their lowest and highest): the step's [`verdict`].
    pub(super) fn judge(
        &self,
        n: u32,
        interval: Duration,
        cancel: &Cancel,
        mut judge: impl FnMut(&Field, &[f64], (f64, f64)) -> (bool, String),
    ) -> Result<(bool, String), Halt> {
        let series = self.samples(n, interval, cancel)?;
        Ok(verdict(
            self.fields
                .iter()
                .zip(&series)
                .map(|(f, values)| judge(f, values, span(values))),
        ))
    }
}
