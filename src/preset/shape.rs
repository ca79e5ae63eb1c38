//! The preset file's shape as serde reads it: `values` keeps the file's order and refuses a
//! command or field given twice.

use super::CommandValues;
use crate::profile::value::Typed as Text;
use serde::Deserialize;
use serde::de::{self, Deserializer, MapAccess, Visitor};
use std::fmt;

/// The document as written; `version` is optional here so that its absence gets a clear message.
#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "preset")]
pub(super) struct Doc {
    #[serde(default)]
    pub(super) version: Option<u32>,
    pub(super) profile: String,
    #[serde(default)]
    pub(super) note: String,
    #[serde(default)]
    pub(super) created: String,
    #[serde(default)]
    pub(super) device: Option<String>,
    pub(super) values: Values,
}

/// Just the version, to explain a newer file that does not parse as this version.
#[derive(Deserialize)]
pub(super) struct Head {
    #[serde(default)]
    pub(super) version: Option<u32>,
}

/// `{ "COMMAND": { "field": "value", ... }, ... }`, in the file's order.
pub(super) struct Values(pub(super) Vec<CommandValues>);

impl<'de> Deserialize<'de> for Values {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Values;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str(
                    r#"a map of Set commands, e.g. { "MSP_SET_PWMVALUE": { "pwmValue": "85" } }"#,
                )
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Values, A::Error> {
                let mut out: Vec<CommandValues> = Vec::new();
                while let Some(command) = map.next_key::<String>()? {
                    if out.iter().any(|c| c.command.eq_ignore_ascii_case(&command)) {
                        return Err(de::Error::custom(format!(
                            "command \"{command}\" is given twice"
                        )));
                    }
                    let Fields(fields) = map.next_value()?;
                    out.push(CommandValues { command, fields });
                }
                Ok(Values(out))
            }
        }
        d.deserialize_map(V)
    }
}

struct Fields(Vec<(String, String)>);

impl<'de> Deserialize<'de> for Fields {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Fields;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str(r#"a map of fields to values, e.g. { "pwmValue": "85" }"#)
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Fields, A::Error> {
                let mut out: Vec<(String, String)> = Vec::new();
                while let Some(field) = map.next_key::<String>()? {
                    if out.iter().any(|(k, _)| k.eq_ignore_ascii_case(&field)) {
                        return Err(de::Error::custom(format!(
                            "field \"{field}\" is given twice"
                        )));
                    }
                    let Text(value) = map.next_value()?;
                    out.push((field, value));
                }
                Ok(Fields(out))
            }
        }
        d.deserialize_map(V)
    }
}
