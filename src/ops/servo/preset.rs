//! Servo parameter presets: a servo's user parameters (32-53, without its id and baud rate) in a
//! RON file, in display units, checked against the servo profile when loaded.
//!
//! ```ron
//! (
//!     version: 1,
//!     note: "gripper servos",
//!     params: [
//!         ("over_temprature", "70"),
//!         ("angle_limit_switch", "on"),
//!     ],
//! )
//! ```

use super::follows_servo;
use crate::document::{self, DocumentError, ErrorKind, Source, Step};
use crate::profile::value::Typed;
use crate::profile::{Access, Profile, Value};
use serde::Deserialize;
use std::path::Path;

/// The preset format this build reads and writes.
pub const VERSION: u32 = 1;

/// A checked servo parameter preset.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParamPreset {
    /// Free text.
    pub note: String,
    /// (parameter ident, display value), in file order.
    pub params: Vec<(String, String)>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Doc {
    version: u32,
    #[serde(default)]
    note: String,
    params: Vec<(String, Typed)>,
}

/// Whether a parameter belongs in a preset: a user parameter other than the id and baud rate.
pub fn in_preset(p: &crate::profile::Param) -> bool {
    p.access == Access::ReadWrite && !follows_servo(p)
}

impl ParamPreset {
    /// Reads a preset file and checks it against the servo `profile`.
    pub fn load(path: &Path, profile: &Profile) -> Result<Self, DocumentError> {
        document::load(path, document::Limit::SERVO_PRESET, |name, text| {
            Self::parse(name, text, profile)
        })
    }

    /// Parses preset text (`name` names it in errors) and checks every value against `profile`.
    pub fn parse(name: &str, text: &str, profile: &Profile) -> Result<Self, DocumentError> {
        let src = Source::new(name, text);
        let doc: Doc = src.parse()?;
        if doc.version != VERSION {
            return Err(src.error(
                ErrorKind::Version,
                &[Step::Key("version")],
                format!(
                    "version {} is not one this build reads (it reads {VERSION})",
                    doc.version
                ),
            ));
        }
        let preset = ParamPreset {
            note: doc.note,
            params: doc.params.into_iter().map(|(k, v)| (k, v.0)).collect(),
        };
        if let Err((i, message)) = preset.resolve(profile) {
            return Err(src.error(
                ErrorKind::Value,
                &[Step::Key("params"), Step::Index(i)],
                message,
            ));
        }
        Ok(preset)
    }

    /// The raw values by `data_id`, or the index of the first bad entry and why.
    pub fn resolve(&self, profile: &Profile) -> Result<Vec<(u8, i64)>, (usize, String)> {
        let mut out: Vec<(u8, i64)> = Vec::new();
        for (i, (name, value)) in self.params.iter().enumerate() {
            let Some(p) = profile.find_param(name) else {
                let known: Vec<&str> = profile
                    .params
                    .iter()
                    .filter(|p| in_preset(p))
                    .map(|p| p.field.ident.as_str())
                    .collect();
                return Err((
                    i,
                    format!("no servo parameter '{name}'; known: {}", known.join(", ")),
                ));
            };
            let ident = &p.field.ident;
            if p.access == Access::ReadOnly {
                return Err((i, format!("{ident} is read-only")));
            }
            if !in_preset(p) {
                return Err((
                    i,
                    format!("{ident} is set with Set ID / Set baud rate, not by a preset"),
                ));
            }
            if out.iter().any(|(id, _)| *id == p.id) {
                return Err((i, format!("{ident} is given twice")));
            }
            match p.field.parse(value) {
                Ok(Value::Int(raw)) => out.push((p.id, raw)),
                Ok(_) => return Err((i, format!("{ident}: '{value}' is not a number"))),
                Err(e) => return Err((i, e.to_string())),
            }
        }
        Ok(out)
    }

    /// A preset of these raw values (by `data_id`); parameters not in a preset are left out.
    pub fn from_values(profile: &Profile, note: &str, values: &[(u8, i64)]) -> Self {
        let params = profile
            .params
            .iter()
            .filter(|p| in_preset(p))
            .filter_map(|p| {
                let raw = values.iter().find(|(id, _)| *id == p.id)?.1;
                Some((p.field.ident.clone(), p.field.format(&Value::Int(raw))))
            })
            .collect();
        Self {
            note: note.to_string(),
            params,
        }
    }

    /// The preset as RON, each parameter annotated with its name and unit.
    pub fn to_ron(&self, profile: &Profile) -> String {
        let q = |s: &str| format!("{s:?}");
        let mut out = String::from("// botbench servo parameter preset\n(\n");
        out.push_str(&format!("    version: {VERSION},\n"));
        out.push_str(&format!("    note: {},\n", q(&self.note)));
        out.push_str("    params: [\n");
        for (k, v) in &self.params {
            let comment = profile
                .find_param(k)
                .map(|p| format!(" // {}{}", p.field.name.en, p.field.unit_suffix()))
                .unwrap_or_default();
            out.push_str(&format!("        ({}, {}),{comment}\n", q(k), q(v)));
        }
        out.push_str("    ],\n)\n");
        out
    }

    /// Saves the preset, atomically.
    pub fn save(&self, path: &Path, profile: &Profile) -> Result<(), DocumentError> {
        document::write_atomic(path, self.to_ron(profile).as_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::profile::Registry;

    fn profile() -> std::sync::Arc<Profile> {
        Registry::builtin().unwrap().get("servo").unwrap()
    }

    #[test]
    fn a_saved_preset_loads_back_the_same() {
        let p = profile();
        let id = p.servo_id_param().expect("id").id;
        let baud = p.baud_option_param().expect("baud").0.id;
        let values = vec![(41, 70), (48, 1), (53, -15), (id, 9), (baud, 8)];
        let preset = ParamPreset::from_values(&p, "note \"x\"", &values);
        assert!(
            preset
                .params
                .iter()
                .all(|(k, _)| k != "assigned_id" && k != "baudrate")
        );
        let back = ParamPreset::parse("t.ron", &preset.to_ron(&p), &p).unwrap();
        assert_eq!(back, preset);
        assert_eq!(
            back.resolve(&p).unwrap(),
            vec![(41, 70), (48, 1), (53, -15)]
        );
    }

    #[test]
    fn a_bad_value_is_reported_at_its_line_and_column() {
        let p = profile();
        let text = "(\n    version: 1,\n    params: [\n        (\"over_temprature\", \"70\"),\n        (\"angle_limit_switch\", \"maybe\"),\n    ],\n)\n";
        let e = ParamPreset::parse("t.ron", text, &p).unwrap_err();
        assert_eq!(e.at(), (5, 9), "{e}");
        assert!(e.message().contains("angle_limit_switch"), "{e}");
        let e = ParamPreset::parse("t.ron", "(version: 1, params: [(\"assigned_id\", 3)])", &p)
            .unwrap_err();
        assert!(e.message().contains("Set ID"), "{e}");
        let e = ParamPreset::parse("t.ron", "(version: 1, params: [(\"x\" 3)])", &p).unwrap_err();
        assert_eq!(e.at().0, 1, "{e}");
    }
}
