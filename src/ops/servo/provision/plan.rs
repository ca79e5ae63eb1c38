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
        let option = self.baud_option(profile)?;
        self.check_ids(profile)?;
        Ok(Resolved {
            option,
            writes: self.writes(profile)?,
            record: self.recorded(profile)?,
        })
    }

    /// The baud option of the plan's rate, which the servo's baud parameter takes (the profile
    /// names its id and baud parameters).
    fn baud_option(&self, profile: &Profile) -> Result<u8, Issue> {
        let at = || vec![Step::Key("target_baud")];
        let role_issue = |e: OpError| issue(at(), e.to_string());
        servo::id_param(profile).map_err(role_issue)?;
        let (baud, _) = servo::baud_param(profile).map_err(role_issue)?;
        let Some(option) = profile.option_of_baud(self.target_baud) else {
            let allowed: Vec<String> = profile
                .servo_bauds()
                .iter()
                .map(|b| b.to_string())
                .collect();
            return Err(issue(
                at(),
                format!(
                    "{} is not a servo baud rate; allowed: {}",
                    self.target_baud,
                    allowed.join(", ")
                ),
            ));
        };
        baud.field
            .check(&Value::Int(option.into()))
            .map_err(|e| issue(at(), e.to_string()))?;
        Ok(option)
    }

    /// The ids given out: never the factory id of a fresh servo or the broadcast address, a
    /// list neither empty nor with an id twice.
    fn check_ids(&self, profile: &Profile) -> Result<(), Issue> {
        let at = || vec![Step::Key("ids")];
        let fresh = servo::factory_location(profile).id;
        let broadcast = crate::protocol::servo::BROADCAST_ID;
        match &self.ids {
            IdSequence::Start(first) if *first == fresh => Err(issue(
                at(),
                format!("ids cannot start at {fresh}: {fresh} is the factory id of a fresh servo"),
            )),
            IdSequence::Start(first) if *first == broadcast => Err(issue(
                at(),
                format!("id {broadcast} is the broadcast address and cannot be assigned"),
            )),
            IdSequence::Start(_) => Ok(()),
            IdSequence::List(ids) if ids.is_empty() => {
                Err(issue(at(), "the id list is empty".into()))
            }
            IdSequence::List(ids) => {
                for (i, &id) in ids.iter().enumerate() {
                    if id == fresh || id == broadcast {
                        return Err(issue(
                            at(),
                            format!(
                                "id {id} cannot be assigned: {fresh} is the factory id and {broadcast} the broadcast address"
                            ),
                        ));
                    }
                    if ids[..i].contains(&id) {
                        return Err(issue(at(), format!("id {id} is listed twice")));
                    }
                }
                Ok(())
            }
        }
    }

    /// The plan's parameters with their raw values, in order: each known, writable, not the id
    /// or the baud rate (the plan sets those), given once, in range, and the values so far
    /// within the profile's relations (voltage low ≤ high).
    fn writes<'p>(&self, profile: &'p Profile) -> Result<Vec<(&'p Param, i64)>, Issue> {
        let role_issue = |e: OpError| issue(vec![Step::Key("target_baud")], e.to_string());
        let id_pid = servo::id_param(profile).map_err(role_issue)?.id;
        let baud_pid = servo::baud_param(profile).map_err(role_issue)?.0.id;
        let mut writes: Vec<(&Param, i64)> = Vec::new();
        for (i, (name, value)) in self.params.iter().enumerate() {
            let at = vec![Step::Key("params"), Step::Index(i)];
            let Some(param) = profile.find_param(name) else {
                let known = known_params(profile);
                let message = format!("no servo parameter '{name}'; known: {known}");
                return Err(issue(at, message));
            };
            let ident = &param.field.ident;
            let refused = if param.access == Access::ReadOnly {
                Some(format!("{ident} is read-only and cannot be written"))
            } else if param.id == id_pid || param.id == baud_pid {
                Some(format!(
                    "{ident} is set by the plan's `ids` and `target_baud`, not by params"
                ))
            } else if writes.iter().any(|(p, _)| p.id == param.id) {
                Some(format!("{ident} is given twice"))
            } else {
                None
            };
            if let Some(message) = refused {
                return Err(issue(at, message));
            }
            let raw = match param.field.parse(value) {
                Ok(Value::Int(raw)) => raw,
                Ok(_) => return Err(issue(at, format!("{ident}: '{value}' is not a number"))),
                Err(e) => return Err(issue(at, e.to_string())),
            };
            writes.push((param, raw));
            // The profile's relations between the plan's own values (voltage low ≤ high).
            let values: Vec<(u8, i64)> = writes.iter().map(|(p, v)| (p.id, *v)).collect();
            if let Err(e) = profile.check_param_relations(&values) {
                return Err(issue(at, e.to_string()));
            }
        }
        Ok(writes)
    }

    /// The parameters the plan records, in order: each known, and recorded once.
    fn recorded<'p>(&self, profile: &'p Profile) -> Result<Vec<&'p Param>, Issue> {
        let mut record: Vec<&Param> = Vec::new();
        for (i, name) in self.record.iter().enumerate() {
            let at = vec![Step::Key("record"), Step::Index(i)];
            let Some(param) = profile.find_param(name) else {
                let known = known_params(profile);
                let message = format!("no servo parameter '{name}' to record; known: {known}");
                return Err(issue(at, message));
            };
            if record.iter().any(|p| p.id == param.id) {
                let message = format!("{} is recorded twice", param.field.ident);
                return Err(issue(at, message));
            }
            record.push(param);
        }
        Ok(record)
    }
}

/// A problem at `path` of the plan.
fn issue(path: Vec<Step>, message: String) -> Issue {
    Issue { path, message }
}

/// The profile's servo parameters, by name, for a message.
fn known_params(profile: &Profile) -> String {
    profile
        .params
        .iter()
        .map(|p| p.field.ident.as_str())
        .collect::<Vec<_>>()
        .join(", ")
}
