//! Checking one step of a plan against the profile: every command, field, threshold and action,
//! each problem placed at its line and column.

use super::plan::{Action, DEFAULT_INTERVAL, DocAction, DocStep, StepKind};
use crate::document::{Problem, Source, Step as At};
use crate::profile::value::Typed as Text;
use crate::profile::{Command, CommandKind, Field, Input, Profile};
use crate::protocol::Direction;
use std::collections::BTreeMap;
use std::time::Duration;

/// Checks one step of the document, collecting problems with their place.
pub(super) struct StepCheck<'a> {
    /// The plan's text.
    pub(super) src: &'a Source<'a>,
    /// The step's index in `steps`.
    pub(super) index: usize,
    /// The profile it is checked against.
    pub(super) profile: &'a Profile,
    /// What is wrong, each where it is.
    pub(super) problems: Vec<Problem>,
}

impl<'a> StepCheck<'a> {
    pub(super) fn at(&mut self, path: &[At], message: String) {
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

    pub(super) fn step(&mut self, s: &DocStep) -> Option<StepKind> {
        let before = self.problems.len();
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
            } => self.range(
                (command, field, fields),
                (min, max),
                (*samples, *interval_ms),
            ),
            DocStep::Stable {
                command,
                field,
                fields,
                max_spread,
                samples,
                interval_ms,
                ..
            } => self.stable(
                (command, field, fields),
                max_spread,
                (*samples, *interval_ms),
            ),
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
            } => self.rises(
                (action, then),
                (command, field, fields),
                min_rise,
                (*samples, *settle_ms),
            ),
            DocStep::Operator {
                prompt,
                command,
                field,
                expect_bits_seen,
                timeout_ms,
                ..
            } => self.operator(prompt, (command, field), *expect_bits_seen, *timeout_ms),
            DocStep::Reads {
                command, expect, ..
            } => self.reads(command, expect),
        };
        (self.problems.len() == before).then_some(kind?)
    }

    /// The command a measuring step reads and its fields (`field`, or `fields`).
    fn measured(
        &mut self,
        (command, field, fields): Measured<'_>,
    ) -> (Option<&'a Command>, Vec<&'a Field>) {
        let cmd = self.readable(command);
        let fs = self.fields(cmd, field, fields);
        (cmd, fs)
    }

    /// A range step: `min` no higher than `max`.
    fn range(
        &mut self,
        what: Measured<'_>,
        (min, max): (&Text, &Text),
        (samples, interval_ms): (u32, Option<u64>),
    ) -> Option<StepKind> {
        let (cmd, fs) = self.measured(what);
        let min = self.number("min", min, &fs);
        let max = self.number("max", max, &fs);
        if let (Some(a), Some(b)) = (min, max)
            && a > b
        {
            self.at(&[At::Key("min")], format!("min {a} is above max {b}"));
        }
        Some(StepKind::Range {
            command: cmd?.ident.clone(),
            fields: idents(&fs),
            min: min?,
            max: max?,
            samples: self.samples(samples, 1),
            interval: self.interval(interval_ms),
        })
    }

    /// A stability step: at least two samples.
    fn stable(
        &mut self,
        what: Measured<'_>,
        max_spread: &Text,
        (samples, interval_ms): (u32, Option<u64>),
    ) -> Option<StepKind> {
        let (cmd, fs) = self.measured(what);
        let spread = self.number("max_spread", max_spread, &fs);
        Some(StepKind::Stable {
            command: cmd?.ident.clone(),
            fields: idents(&fs),
            max_spread: spread?,
            samples: self.samples(samples, 2),
            interval: self.interval(interval_ms),
        })
    }

    /// A rise step: its two actions, and a rise above 0.
    fn rises(
        &mut self,
        (action, then): (&DocAction, &DocAction),
        what: Measured<'_>,
        min_rise: &Text,
        (samples, settle_ms): (u32, u64),
    ) -> Option<StepKind> {
        let action = self.action("action", action);
        let then = self.action("then", then);
        let (cmd, fs) = self.measured(what);
        let rise = self.number("min_rise", min_rise, &fs);
        if rise == Some(0.0) {
            self.at(
                &[At::Key("min_rise")],
                "min_rise: 0 passes whatever happens; give a rise above 0".into(),
            );
        }
        Some(StepKind::Rises {
            action: action?,
            command: cmd?.ident.clone(),
            fields: idents(&fs),
            min_rise: rise?,
            settle: self.ms("settle_ms", settle_ms, 0),
            samples: self.samples(samples, 1),
            then: then?,
        })
    }

    /// An operator step: a prompt, and bits the field has.
    fn operator(
        &mut self,
        prompt: &str,
        (command, field): (&str, &str),
        bits: u64,
        timeout_ms: u64,
    ) -> Option<StepKind> {
        let cmd = self.readable(command);
        let f = cmd.and_then(|c| self.field(c, field, &[At::Key("field")]));
        if let Some(f) = f {
            self.bits_of(f, bits);
        }
        if prompt.trim().is_empty() {
            self.at(&[At::Key("prompt")], "the prompt is empty".into());
        }
        Some(StepKind::Operator {
            prompt: prompt.to_string(),
            command: cmd?.ident.clone(),
            field: f?.ident.clone(),
            bits,
            timeout: self.ms("timeout_ms", timeout_ms, 1),
        })
    }

    /// `expect_bits_seen`: not 0, and only bits `f` has (its named bits, else its width).
    fn bits_of(&mut self, f: &Field, expect_bits_seen: u64) {
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
        if expect_bits_seen == 0 || expect_bits_seen & !allowed != 0 {
            self.at(
                &[At::Key("expect_bits_seen")],
                format!(
                    "expect_bits_seen: {expect_bits_seen:#x}; {} has bits {allowed:#x}",
                    f.ident
                ),
            );
        }
    }

    /// A reads step: each expected value parsed by its field.
    fn reads(&mut self, command: &str, expect: &BTreeMap<String, Text>) -> Option<StepKind> {
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
        Some(StepKind::Reads {
            command: cmd?.ident.clone(),
            expect: out,
        })
    }
}

/// What a measuring step reads: the command, and its `field` or `fields`.
type Measured<'s> = (&'s str, &'s Option<String>, &'s [String]);

/// The fields' idents, in order.
fn idents(fs: &[&Field]) -> Vec<String> {
    fs.iter().map(|f| f.ident.clone()).collect()
}
