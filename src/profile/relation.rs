//! Relations between fields (minimum ≤ default ≤ maximum): resolved and checked at load, and
//! checked again before every write. The smaller side may be a sum of fields of the same
//! command (`CMD.t_acc + CMD.t_dec` ≤ `CMD.interval`: a servo's multi-turn move takes at least
//! its acceleration and deceleration times).

use super::model::{Command, Field, Param, Profile, RelOp};
use super::validate::Issue;
use super::value::{Broken, FieldError, Value};
use crate::document::Step::{self, Index, Key};
use crate::protocol::Direction;

/// One side of a relation, resolved.
#[derive(Debug, Clone, Copy)]
pub enum Side<'p> {
    /// A field of a command's payload.
    Field(&'p Command, &'p Field),
    /// A servo parameter.
    Param(&'p Param),
}

impl<'p> Side<'p> {
    /// The field.
    pub fn field(self) -> &'p Field {
        match self {
            Side::Field(_, f) => f,
            Side::Param(p) => &p.field,
        }
    }
}

impl Profile {
    /// Resolves one side of a relation: `COMMAND.field` (the command's reply, else its
    /// request), or a parameter's ident.
    pub fn relation_side(&self, name: &str) -> Result<Side<'_>, String> {
        match name.split_once('.') {
            Some((c, f)) => {
                let cmd = self
                    .commands
                    .iter()
                    .find(|x| x.ident.eq_ignore_ascii_case(c))
                    .ok_or_else(|| format!("no command '{c}'"))?;
                let field = cmd
                    .reply
                    .iter()
                    .chain(&cmd.request)
                    .find(|x| x.ident.eq_ignore_ascii_case(f))
                    .ok_or_else(|| format!("{} has no field '{f}'", cmd.ident))?;
                Ok(Side::Field(cmd, field))
            }
            None => self
                .params
                .iter()
                .find(|p| p.field.ident.eq_ignore_ascii_case(name))
                .map(Side::Param)
                .ok_or_else(|| {
                    format!("no parameter '{name}' (name a command's field as COMMAND.field)")
                }),
        }
    }

    /// Resolves a side that may be a sum: `A + B` (each as [`Self::relation_side`]).
    pub fn relation_sides(&self, name: &str) -> Result<Vec<Side<'_>>, String> {
        name.split('+')
            .map(|term| self.relation_side(term.trim()))
            .collect()
    }

    /// Checks the relations that apply to a frame of `cmd` with this payload: relations between
    /// fields of `cmd` (or of the Get it is the Set of), and between parameters it carries.
    /// A side the frame does not carry is not checked.
    pub fn check_relations(
        &self,
        cmd: &Command,
        dir: Direction,
        payload: &[u8],
    ) -> Result<(), FieldError> {
        if self.relations.is_empty() {
            return Ok(());
        }
        let d = self.decode_lenient(cmd, dir, payload);
        let value_of = |side: Side<'_>| -> Option<i64> {
            d.values.iter().find_map(|v| {
                let hit = match side {
                    Side::Param(p) => std::ptr::eq(v.field, &p.field),
                    Side::Field(c, f) => {
                        (c.id == cmd.id || cmd.pair == Some(c.id))
                            && v.ident.eq_ignore_ascii_case(&f.ident)
                    }
                };
                match (hit, &v.value) {
                    (true, Value::Int(raw)) => Some(*raw),
                    _ => None,
                }
            })
        };
        self.check_each(&value_of)
    }

    /// Checks the relations between servo parameters whose values are given, (data_id, raw).
    pub fn check_param_relations(&self, values: &[(u8, i64)]) -> Result<(), FieldError> {
        let value_of = |side: Side<'_>| match side {
            Side::Param(p) => values.iter().find(|(id, _)| *id == p.id).map(|(_, v)| *v),
            Side::Field(..) => None,
        };
        self.check_each(&value_of)
    }

    /// The parameters that share a relation with parameter `id`: read them before writing it
    /// alone, so that the write can be checked.
    pub fn related_params(&self, id: u8) -> Vec<&Param> {
        let mut out: Vec<&Param> = Vec::new();
        for r in &self.relations {
            let (Ok(Side::Param(a)), Ok(Side::Param(b))) =
                (self.relation_side(&r.low), self.relation_side(&r.high))
            else {
                continue;
            };
            for (this, other) in [(a, b), (b, a)] {
                if this.id == id && !out.iter().any(|p| p.id == other.id) {
                    out.push(other);
                }
            }
        }
        out
    }

    fn check_each(&self, value_of: &dyn Fn(Side<'_>) -> Option<i64>) -> Result<(), FieldError> {
        for r in &self.relations {
            let (Ok(low), Ok(high)) = (self.relation_sides(&r.low), self.relation_side(&r.high))
            else {
                continue;
            };
            let terms: Option<Vec<(&Field, i64)>> = low
                .iter()
                .map(|s| value_of(*s).map(|v| (s.field(), v)))
                .collect();
            if let (Some(terms), Some(b)) = (terms, value_of(high)) {
                check_sum(r.op, &terms, high.field(), b)?;
            }
        }
        Ok(())
    }
}

/// Whether `low_raw` and `high_raw` keep `op`, compared as displayed.
pub fn check_pair(
    op: RelOp,
    low: &Field,
    low_raw: i64,
    high: &Field,
    high_raw: i64,
) -> Result<(), FieldError> {
    let (Some(a), Some(b)) = (low.display_number(low_raw), high.display_number(high_raw)) else {
        return Ok(());
    };
    let keeps = match op {
        RelOp::Le => a <= b,
        RelOp::Lt => a < b,
    };
    if keeps {
        return Ok(());
    }
    Err(FieldError::Relation(Box::new(Broken {
        low: low.ident.clone(),
        low_name: low.name.en.clone(),
        low_value: low.display(&Value::Int(low_raw)),
        sign: op.sign(),
        high: high.ident.clone(),
        high_name: high.name.en.clone(),
        high_value: high.display(&Value::Int(high_raw)),
    })))
}

/// Whether the sum of `terms` (each field with its raw value) and `high_raw` keep `op`,
/// compared as displayed; one term is [`check_pair`]. The error names each term and the sum
/// (`Acceleration time + Deceleration time (t_acc + t_dec) 20 ms + 30 ms = 50 ms must be ≤
/// Interval (interval) 40 ms`): the value given and the least allowed.
pub fn check_sum(
    op: RelOp,
    terms: &[(&Field, i64)],
    high: &Field,
    high_raw: i64,
) -> Result<(), FieldError> {
    let [(low, low_raw)] = terms else {
        return check_terms(op, terms, high, high_raw);
    };
    check_pair(op, low, *low_raw, high, high_raw)
}

fn check_terms(
    op: RelOp,
    terms: &[(&Field, i64)],
    high: &Field,
    high_raw: i64,
) -> Result<(), FieldError> {
    let numbers: Option<Vec<f64>> = terms.iter().map(|(f, v)| f.display_number(*v)).collect();
    let (Some(numbers), Some(b)) = (numbers, high.display_number(high_raw)) else {
        return Ok(());
    };
    let a: f64 = numbers.iter().sum();
    let keeps = match op {
        RelOp::Le => a <= b,
        RelOp::Lt => a < b,
    };
    if keeps {
        return Ok(());
    }
    let join =
        |f: &dyn Fn(&(&Field, i64)) -> String| terms.iter().map(f).collect::<Vec<_>>().join(" + ");
    let unit = high.unit_suffix();
    Err(FieldError::Relation(Box::new(Broken {
        low: join(&|(f, _)| f.ident.clone()),
        low_name: join(&|(f, _)| f.name.en.clone()),
        low_value: format!(
            "{} = {:.*}{unit}",
            join(&|(f, v)| f.display(&Value::Int(*v))),
            high.decimals(),
            a
        ),
        sign: op.sign(),
        high: high.ident.clone(),
        high_name: high.name.en.clone(),
        high_value: high.display(&Value::Int(high_raw)),
    })))
}

/// Checks every relation of a profile at load: both sides exist, are numbers, belong to one
/// command (or are both parameters), and their defaults keep the relation.
pub(super) fn validate_relations(p: &Profile) -> Result<(), Issue> {
    for (i, r) in p.relations.iter().enumerate() {
        let at = |k: &'static str| -> Vec<Step> { vec![Key("relations"), Index(i), Key(k)] };
        let issue = |k: &'static str, m: String| Issue {
            path: at(k),
            message: format!("relation {}: {m}", i + 1),
        };
        let lows = p.relation_sides(&r.low).map_err(|m| issue("low", m))?;
        let high = p.relation_side(&r.high).map_err(|m| issue("high", m))?;
        for &low in &lows {
            check_sides(low, high, lows.len() > 1).map_err(|(k, m)| issue(k, m))?;
        }
        let defaults: Option<Vec<(&Field, i64)>> = lows
            .iter()
            .map(|s| s.field().default.map(|d| (s.field(), d)))
            .collect();
        if let (Some(terms), Some(b)) = (defaults, high.field().default)
            && let Err(e) = check_sum(r.op, &terms, high.field(), b)
        {
            return Err(issue("low", format!("the defaults break it: {e}")));
        }
    }
    Ok(())
}

/// One term of a relation's smaller side against its larger side: fields of one command (or
/// two parameters; a sum takes fields only), numbers, not the same field. The error: the key
/// (`low`, `high`) and what is wrong.
fn check_sides(low: Side<'_>, high: Side<'_>, sum: bool) -> Result<(), (&'static str, String)> {
    let describe = |s: Side<'_>| match s {
        Side::Field(c, f) => format!("{}.{}", c.ident, f.ident),
        Side::Param(x) => format!("parameter {}", x.field.ident),
    };
    let same = match (low, high) {
        (Side::Field(a, _), Side::Field(b, _)) => a.id == b.id,
        (Side::Param(_), Side::Param(_)) => !sum,
        _ => false,
    };
    if !same {
        let m = format!(
            "{} and {} are not fields of one command (nor two parameters)",
            describe(low),
            describe(high)
        );
        return Err(("high", m));
    }
    for (k, s) in [("low", low), ("high", high)] {
        if s.field().ty.int_bounds().is_none() {
            return Err((k, format!("{} is not a number", describe(s))));
        }
    }
    if std::ptr::eq(low.field(), high.field()) {
        return Err(("high", "a field against itself".to_string()));
    }
    Ok(())
}
