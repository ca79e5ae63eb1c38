//! The provisioning plan: its RON shape, and its check against the servo profile.

use crate::document::{self, DocumentError, ErrorKind, Source, Step};
use crate::ops::{OpError, servo};
use crate::profile::value::Typed as DisplayText;
use crate::profile::{Access, Param, Profile, Value};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The ids a plan gives out.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub enum IdSequence {
    /// The next free id from this one upward (to 254).
    Start(u8),
    /// These ids, in order, skipping those in use.
    List(Vec<u8>),
}

impl IdSequence {
    /// Every id the sequence may give, in order.
    pub fn candidates(&self) -> Vec<u8> {
        match self {
            IdSequence::Start(first) => (*first..crate::protocol::servo::BROADCAST_ID).collect(),
            IdSequence::List(ids) => ids.clone(),
        }
    }
}

/// A provisioning plan, as written in its RON file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Plan {
    /// The baud rate every servo leaves with: one of the profile's servo baud rates.
    pub target_baud: u32,
    /// The ids to give out.
    pub ids: IdSequence,
    /// (parameter ident, display value) to write, in order, e.g. `("over_temprature", "70")`.
    pub params: Vec<(String, String)>,
    /// Further parameters to read and record in the log, e.g. `firmware_version`.
    pub record: Vec<String>,
}

/// A problem with a plan and where it is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Issue {
    /// The path to the offending value.
    pub path: Vec<Step>,
    /// What is wrong.
    pub message: String,
}

/// A plan resolved against a profile: what [`provision_next`] writes and reads.
#[derive(Debug, Clone)]
pub struct Resolved<'p> {
    /// The baud option (1-8) of the target rate.
    pub option: u8,
    /// The parameters to write, with their raw values.
    pub writes: Vec<(&'p Param, i64)>,
    /// The parameters to record.
    pub record: Vec<&'p Param>,
}

/// The plan file's shape.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Doc {
    target_baud: u32,
    ids: IdSequence,
    #[serde(default)]
    params: Vec<(String, DisplayText)>,
    #[serde(default)]
    record: Vec<String>,
}

impl Plan {
    /// Reads a plan file and checks it against the servo `profile`. Nothing has been written
    /// when it is refused.
    pub fn load(path: &Path, profile: &Profile) -> Result<Plan, DocumentError> {
        document::load(path, document::Limit::PROVISION_PLAN, |name, text| {
            Self::parse(name, text, profile)
        })
    }

    /// Parses plan text (`name` names it in errors) and checks it against `profile`.
    pub fn parse(name: &str, text: &str, profile: &Profile) -> Result<Plan, DocumentError> {
        let src = Source::new(name, text);
        let doc: Doc = src.parse()?;
        let plan = Plan {
            target_baud: doc.target_baud,
            ids: doc.ids,
            params: doc.params.into_iter().map(|(k, v)| (k, v.0)).collect(),
            record: doc.record,
        };
        if let Err(issue) = plan.resolve(profile) {
            return Err(src.error(ErrorKind::Value, &issue.path, issue.message));
        }
        Ok(plan)
    }

    /// Checks the plan against the servo `profile`: the baud rate, the ids, every parameter
    /// (known, writable, not the id or baud rate, its value in range) and every recorded one.
    pub fn resolve<'p>(&self, profile: &'p Profile) -> Result<Resolved<'p>, Issue> {
        let issue = |path: Vec<Step>, message: String| Issue { path, message };
        let role_issue = |e: OpError| issue(vec![Step::Key("target_baud")], e.to_string());
        let id_pid = servo::id_param(profile).map_err(role_issue)?.id;
        let (baud, _) = servo::baud_param(profile).map_err(role_issue)?;
        let Some(option) = profile.option_of_baud(self.target_baud) else {
            return Err(issue(
                vec![Step::Key("target_baud")],
                format!(
                    "{} is not a servo baud rate; allowed: {}",
                    self.target_baud,
                    profile
                        .servo_bauds()
                        .iter()
                        .map(|b| b.to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        };
        baud.field
            .check(&Value::Int(option.into()))
            .map_err(|e| issue(vec![Step::Key("target_baud")], e.to_string()))?;
        let ids_at = vec![Step::Key("ids")];
        let fresh = servo::factory_location(profile).id;
        let broadcast = crate::protocol::servo::BROADCAST_ID;
        match &self.ids {
            IdSequence::Start(first) if *first == fresh => {
                return Err(issue(
                    ids_at,
                    format!(
                        "ids cannot start at {fresh}: {fresh} is the factory id of a fresh servo"
                    ),
                ));
            }
            IdSequence::Start(first) if *first == broadcast => {
                return Err(issue(
                    ids_at,
                    format!("id {broadcast} is the broadcast address and cannot be assigned"),
                ));
            }
            IdSequence::Start(_) => {}
            IdSequence::List(ids) => {
                if ids.is_empty() {
                    return Err(issue(ids_at, "the id list is empty".into()));
                }
                for (i, &id) in ids.iter().enumerate() {
                    if id == fresh || id == broadcast {
                        return Err(issue(
                            ids_at,
                            format!(
                                "id {id} cannot be assigned: {fresh} is the factory id and {broadcast} the broadcast address"
                            ),
                        ));
                    }
                    if ids[..i].contains(&id) {
                        return Err(issue(ids_at, format!("id {id} is listed twice")));
                    }
                }
            }
        }
        let known = || {
            profile
                .params
                .iter()
                .map(|p| p.field.ident.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        };
        let mut writes: Vec<(&Param, i64)> = Vec::new();
        for (i, (name, value)) in self.params.iter().enumerate() {
            let at = vec![Step::Key("params"), Step::Index(i)];
            let Some(param) = profile.find_param(name) else {
                return Err(issue(
                    at,
                    format!("no servo parameter '{name}'; known: {}", known()),
                ));
            };
            let ident = &param.field.ident;
            if param.access == Access::ReadOnly {
                return Err(issue(
                    at,
                    format!("{ident} is read-only and cannot be written"),
                ));
            }
            if param.id == id_pid || param.id == baud.id {
                return Err(issue(
                    at,
                    format!("{ident} is set by the plan's `ids` and `target_baud`, not by params"),
                ));
            }
            if writes.iter().any(|(p, _)| p.id == param.id) {
                return Err(issue(at, format!("{ident} is given twice")));
            }
            let raw = match param.field.parse(value) {
                Ok(Value::Int(raw)) => raw,
                Ok(_) => {
                    return Err(issue(at, format!("{ident}: '{value}' is not a number")));
                }
                Err(e) => return Err(issue(at, e.to_string())),
            };
            writes.push((param, raw));
            // The profile's relations between the plan's own values (voltage low ≤ high).
            let values: Vec<(u8, i64)> = writes.iter().map(|(p, v)| (p.id, *v)).collect();
            if let Err(e) = profile.check_param_relations(&values) {
                return Err(issue(at, e.to_string()));
            }
        }
        let mut record: Vec<&Param> = Vec::new();
        for (i, name) in self.record.iter().enumerate() {
            let at = vec![Step::Key("record"), Step::Index(i)];
            let Some(param) = profile.find_param(name) else {
                return Err(issue(
                    at,
                    format!("no servo parameter '{name}' to record; known: {}", known()),
                ));
            };
            if record.iter().any(|p| p.id == param.id) {
                return Err(issue(
                    at,
                    format!("{} is recorded twice", param.field.ident),
                ));
            }
            record.push(param);
        }
        Ok(Resolved {
            option,
            writes,
            record,
        })
    }
}
