//! The test plan: its RON shape, and the checked plan a run follows.

use super::check::StepCheck;
use crate::document::{self, DocumentError, ErrorKind, Problem, Source, Step as At};
use crate::profile::value::Typed as Text;
use crate::profile::{Profile, Value};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;
use std::time::Duration;

/// The newest plan format this build reads.
pub const VERSION: u32 = 1;

/// Time between samples when a step does not say.
pub(super) const DEFAULT_INTERVAL: Duration = Duration::from_millis(20);

/// A checked test plan.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// What the plan is called (free text).
    pub name: String,
    /// The profile id it was checked against.
    pub profile: String,
    /// The steps, in order.
    pub steps: Vec<Step>,
    /// The plan's own words in Chinese, by the English text they translate (its name, a step's
    /// name, an operator prompt): the file's `zh: { "Gyro at rest": "静止陀螺仪", ... }`.
    /// Records and logs keep the English names; the window shows these in 中文.
    pub zh: BTreeMap<String, String>,
}

/// One checked step.
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    /// Its name, unique in the plan.
    pub name: String,
    /// What it does.
    pub kind: StepKind,
}

/// What a step does. Commands are stored by canonical ident, fields by canonical ident.
#[derive(Debug, Clone, PartialEq)]
pub enum StepKind {
    /// Every sample of every field within `[min, max]` (display units).
    Range {
        /// The command read.
        command: String,
        /// The fields checked.
        fields: Vec<String>,
        /// The smallest value allowed.
        min: f64,
        /// The largest value allowed.
        max: f64,
        /// Reads made.
        samples: u32,
        /// Time between reads.
        interval: Duration,
    },
    /// The spread (max − min) of each field over the samples at most `max_spread`.
    Stable {
        /// The command read.
        command: String,
        /// The fields checked.
        fields: Vec<String>,
        /// The largest spread allowed (display units).
        max_spread: f64,
        /// Reads made (at least 2).
        samples: u32,
        /// Time between reads.
        interval: Duration,
    },
    /// Each field's mean rises by at least `min_rise` while `action` is on; `then` always
    /// follows.
    Rises {
        /// What turns it on.
        action: Action,
        /// The command read.
        command: String,
        /// The fields checked.
        fields: Vec<String>,
        /// The smallest rise allowed (display units).
        min_rise: f64,
        /// How long to wait after the action before measuring, and after `then` before the next
        /// step.
        settle: Duration,
        /// Reads averaged before and after.
        samples: u32,
        /// What turns it off; sent whatever happened.
        then: Action,
    },
    /// Prompts the operator, then watches a bit field until each bit of `bits` has been seen
    /// both clear and set.
    Operator {
        /// What the operator is asked to do.
        prompt: String,
        /// The command read.
        command: String,
        /// The bit field.
        field: String,
        /// The bits that must toggle.
        bits: u64,
        /// How long to watch after the prompt.
        timeout: Duration,
    },
    /// The command answers and its answer decodes; `expect`ed fields hold exactly these values.
    Reads {
        /// The command read.
        command: String,
        /// (field ident, raw value, as written in the plan).
        expect: Vec<(String, Value, String)>,
    },
}

impl StepKind {
    /// The command the step reads (its canonical ident).
    pub fn command(&self) -> &str {
        match self {
            StepKind::Range { command, .. }
            | StepKind::Stable { command, .. }
            | StepKind::Rises { command, .. }
            | StepKind::Operator { command, .. }
            | StepKind::Reads { command, .. } => command,
        }
    }
}

impl StepKind {
    /// `Range`, `Stable`, `Rises`, `Operator` or `Reads`.
    pub fn name(&self) -> &'static str {
        match self {
            StepKind::Range { .. } => "Range",
            StepKind::Stable { .. } => "Stable",
            StepKind::Rises { .. } => "Rises",
            StepKind::Operator { .. } => "Operator",
            StepKind::Reads { .. } => "Reads",
        }
    }
}

/// An action command with its payload, encoded and checked at load.
#[derive(Debug, Clone, PartialEq)]
pub struct Action {
    /// The command's canonical ident.
    pub command: String,
    /// The encoded payload.
    pub payload: Vec<u8>,
    /// As a person reads it: `MSP_SET_MOTOR motor=stop`.
    pub text: String,
}

impl Plan {
    /// `text` (the plan's name, a step's name or a prompt) as the window shows it in `lang`:
    /// its [`Plan::zh`] translation in Chinese where the plan gives one, else as written.
    pub fn said<'a>(&'a self, text: &'a str, lang: crate::i18n::Lang) -> &'a str {
        match lang {
            crate::i18n::Lang::Zh => self.zh.get(text).map_or(text, String::as_str),
            crate::i18n::Lang::En => text,
        }
    }

    /// Reads a plan file and checks it against `profile`.
    pub fn load(path: &Path, profile: &Profile) -> Result<Plan, DocumentError> {
        document::load(path, document::Limit::SELFTEST_PLAN, |name, text| {
            Self::parse(name, text, profile)
        })
    }

    /// Parses plan text (`name` names it in errors) and checks it against `profile`. Every
    /// problem is reported, each where it is; the error's kind is the first one's.
    pub fn parse(name: &str, text: &str, profile: &Profile) -> Result<Plan, DocumentError> {
        let src = Source::new(name, text);
        let doc: Doc = src.parse()?;
        let mut problems: Vec<(ErrorKind, Problem)> = Vec::new();
        match doc.version {
            Some(VERSION) => {}
            Some(v) => problems.push((
                ErrorKind::Version,
                src.problem(
                    &[At::Key("version")],
                    format!("plan version {v}; this botbench reads version {VERSION}"),
                ),
            )),
            None => problems.push((
                ErrorKind::Version,
                Problem::at(
                    (1, 1),
                    format!("no `version`: a plan starts with `version: {VERSION},`"),
                ),
            )),
        }
        if doc.profile != profile.id {
            problems.push((
                ErrorKind::Profile,
                src.problem(
                    &[At::Key("profile")],
                    format!(
                        "this plan is for '{}'; the device uses {}",
                        doc.profile, profile.id
                    ),
                ),
            ));
        }
        if doc.steps.is_empty() {
            problems.push((
                ErrorKind::Value,
                src.problem(&[At::Key("steps")], "the plan has no steps"),
            ));
        }
        let mut steps = Vec::new();
        for (i, s) in doc.steps.iter().enumerate() {
            let mut cx = StepCheck {
                src: &src,
                index: i,
                profile,
                problems: Vec::new(),
            };
            let step = cx.step(s);
            if steps.iter().any(|p: &Step| p.name == s.name()) {
                cx.at(
                    &[At::Key("name")],
                    format!("step '{}' is named twice", s.name()),
                );
            } else if s.name().trim().is_empty() {
                cx.at(&[At::Key("name")], "a step needs a name".into());
            }
            problems.extend(cx.problems.into_iter().map(|p| (ErrorKind::Value, p)));
            if let Some(kind) = step {
                steps.push(Step {
                    name: s.name().to_string(),
                    kind,
                });
            }
        }
        for (english, chinese) in &doc.zh {
            let own = english == &doc.name
                || doc.steps.iter().any(|s| {
                    s.name() == english
                        || matches!(s, DocStep::Operator { prompt, .. } if prompt == english)
                });
            let at = [At::Key("zh"), At::Entry(english.clone())];
            if !own {
                problems.push((
                    ErrorKind::Value,
                    src.problem(
                        &at,
                        format!(
                            "zh translates '{english}', which is not the plan's name, a step's name or a prompt"
                        ),
                    ),
                ));
            } else if chinese.trim().is_empty() {
                problems.push((
                    ErrorKind::Value,
                    src.problem(&at, format!("zh gives '{english}' an empty translation")),
                ));
            }
        }
        if let Some(&(kind, _)) = problems.first() {
            return Err(DocumentError {
                file: name.to_string(),
                kind,
                problems: problems.into_iter().map(|(_, p)| p).collect(),
            });
        }
        Ok(Plan {
            name: doc.name,
            profile: profile.id.clone(),
            steps,
            zh: doc.zh,
        })
    }
}

// ---- The file's shape ----

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Doc {
    #[serde(default)]
    version: Option<u32>,
    profile: String,
    #[serde(default)]
    name: String,
    steps: Vec<DocStep>,
    #[serde(default)]
    zh: BTreeMap<String, String>,
}

fn one() -> u32 {
    1
}

fn ten() -> u32 {
    10
}

fn three() -> u32 {
    3
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) enum DocStep {
    Range {
        name: String,
        command: String,
        #[serde(default)]
        field: Option<String>,
        #[serde(default)]
        fields: Vec<String>,
        min: Text,
        max: Text,
        #[serde(default = "one")]
        samples: u32,
        #[serde(default)]
        interval_ms: Option<u64>,
    },
    Stable {
        name: String,
        command: String,
        #[serde(default)]
        field: Option<String>,
        #[serde(default)]
        fields: Vec<String>,
        max_spread: Text,
        #[serde(default = "ten")]
        samples: u32,
        #[serde(default)]
        interval_ms: Option<u64>,
    },
    Rises {
        name: String,
        action: DocAction,
        command: String,
        #[serde(default)]
        field: Option<String>,
        #[serde(default)]
        fields: Vec<String>,
        min_rise: Text,
        settle_ms: u64,
        #[serde(default = "three")]
        samples: u32,
        then: DocAction,
    },
    Operator {
        name: String,
        prompt: String,
        command: String,
        field: String,
        expect_bits_seen: u64,
        timeout_ms: u64,
    },
    Reads {
        name: String,
        command: String,
        #[serde(default)]
        expect: BTreeMap<String, Text>,
    },
}

impl DocStep {
    pub(super) fn name(&self) -> &str {
        match self {
            DocStep::Range { name, .. }
            | DocStep::Stable { name, .. }
            | DocStep::Rises { name, .. }
            | DocStep::Operator { name, .. }
            | DocStep::Reads { name, .. } => name,
        }
    }
}

/// `("MSP_SET_MOTOR", {"motor": "forward"})`
#[derive(Deserialize)]
pub(super) struct DocAction(
    pub(super) String,
    #[serde(default)] pub(super) BTreeMap<String, Text>,
);

#[cfg(test)]
mod tests {
    use super::*;

    fn profile() -> std::sync::Arc<Profile> {
        crate::profile::Registry::builtin()
            .unwrap()
            .get("window-cleaner")
            .unwrap()
    }

    #[test]
    fn the_example_plan_loads() {
        let p = profile();
        let plan = Plan::load(Path::new("presets/window-cleaner-selftest.ron"), &p).unwrap();
        assert!(plan.steps.len() >= 8, "{plan:?}");
    }

    #[test]
    fn problems_carry_their_line() {
        let p = profile();
        let text = "(\n  version: 1,\n  profile: \"window-cleaner\",\n  steps: [\n    Range(name: \"a\", command: \"MSP_ADAPTER\", field: \"nope\", min: \"1\", max: \"2\"),\n    Reads(name: \"b\", command: \"MSP_NOPE\"),\n    Range(name: \"c\", command: \"MSP_ADAPTER\", field: \"batteryVoltage\", min: \"x\", max: \"2\"),\n  ],\n)\n";
        let e = Plan::parse("t.ron", text, &p).unwrap_err();
        let s = e.to_string();
        assert_eq!(e.problems.len(), 3, "{s}");
        assert_eq!(e.problems[0].line, 5, "{s}");
        assert!(e.problems[0].message.contains("no field 'nope'"), "{s}");
        assert_eq!(e.problems[1].line, 6, "{s}");
        assert!(
            e.problems[1].message.contains("no command 'MSP_NOPE'"),
            "{s}"
        );
        assert_eq!(e.problems[2].line, 7, "{s}");
        assert!(e.problems[2].message.contains("not a number"), "{s}");
    }
}
