//! `botbench profile import tuya SCHEMA.json [--name NAME]`: a product's data-point schema from
//! the Tuya IoT platform becomes a checked profile ([`crate::profile::tuya_schema`]), written to
//! the user's profile folder (or `--out`), with the difference from a profile of the same name
//! shown first.

use super::{CliError, CliResult};
use crate::profile::tuya_schema;
use clap::{Subcommand, ValueEnum};
use std::path::{Path, PathBuf};

/// `botbench profile …`.
#[derive(Debug, Subcommand)]
pub(crate) enum ProfileCmd {
    /// Make a profile from a vendor's data-point schema: `profile import tuya SCHEMA.json`.
    Import {
        /// Whose schema.
        #[arg(value_enum)]
        kind: SchemaKind,
        /// The schema file (JSON: a list of data points with id, code, name, mode, type,
        /// property).
        schema: PathBuf,
        /// The profile's id and file name (default: the schema file's name without .json).
        #[arg(long, value_name = "NAME", value_parser = profile_name)]
        name: Option<String>,
        /// Where to write it (default: NAME.ron in the user's profile folder, which overrides
        /// a built-in profile of the same name).
        #[arg(long, value_name = "FILE")]
        out: Option<PathBuf>,
        /// Overwrite a profile file that exists and differs (its difference is shown either way).
        #[arg(long)]
        replace: bool,
        /// Print JSON: the file written and the difference.
        #[arg(long)]
        json: bool,
    },
}

/// Schema formats `profile import` reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum SchemaKind {
    /// The Tuya IoT platform's data-point schema (TUYA_FIELD_NOTES §8).
    Tuya,
}

/// A profile name: 1 to 64 of a-z, 0-9, `-`, `_`.
fn profile_name(text: &str) -> Result<String, String> {
    let ok = !text.is_empty()
        && text.len() <= 64
        && text
            .chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-' || c == '_');
    if ok {
        Ok(text.to_string())
    } else {
        Err(format!(
            "'{}' is not a profile name: 1 to 64 of a-z, 0-9, -, _",
            crate::document::quote(text)
        ))
    }
}

pub(crate) fn run(cmd: ProfileCmd) -> CliResult {
    let ProfileCmd::Import {
        kind: SchemaKind::Tuya,
        schema,
        name,
        out,
        replace,
        json,
    } = cmd;
    let name = match name {
        Some(n) => n,
        None => profile_name(&stem(&schema))
            .map_err(|e| CliError::input(format!("{e}; give the profile's name with --name")))?,
    };
    let text = crate::document::read_text(&schema, crate::document::Limit::PROFILE)
        .map_err(CliError::input)?;
    let reg = super::registry()?;
    // The base protocol comes from the built-in profile, never from a user's override.
    let builtin = crate::profile::Registry::builtin().map_err(CliError::input)?;
    let template = builtin.get("tuya-vacuum").map_err(CliError::input)?;
    let profile = tuya_schema::import(&text, &name, &template)
        .map_err(|e| CliError::input(format!("{}: {e}", schema.display())))?;
    let path = match out {
        Some(p) => p,
        None => super::console::user_profiles()
            .ok_or_else(|| CliError::input("no profile folder (no HOME); give --out FILE"))?
            .join(format!("{name}.ron")),
    };
    let existing = reg
        .iter()
        .find(|(p, _)| p.id == name)
        .map(|(p, _)| p.clone());
    let diff = existing
        .as_ref()
        .map(|old| tuya_schema::diff(old, &profile));
    let ron = tuya_schema::to_ron(&profile);
    let differs = std::fs::read_to_string(&path).is_ok_and(|old| old != ron);
    say(
        &name,
        &path,
        diff.as_deref(),
        profile.data_points.len(),
        json,
    );
    if differs && !replace {
        return Err(CliError::input(format!(
            "{} exists and differs; --replace to overwrite it",
            path.display()
        )));
    }
    write(&path, &ron)?;
    if !json {
        outln!("wrote {}", path.display());
    }
    Ok(0)
}

fn stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// The difference from the profile of the same name (or that it is new).
fn say(name: &str, path: &Path, diff: Option<&[String]>, count: usize, json: bool) {
    if json {
        let doc = serde_json::json!({
            "profile": name, "path": path, "data_points": count,
            "existing": diff.is_some(), "diff": diff,
        });
        outln!("{doc}");
        return;
    }
    match diff {
        None => outln!("{name}: a new profile, {count} data point(s)"),
        Some([]) => outln!("{name}: the same data points as the existing profile ({count})"),
        Some(lines) => {
            outln!(
                "{name}: differs from the existing profile in {} data point(s):",
                lines.len()
            );
            for l in lines {
                outln!("  {l}");
            }
        }
    }
}

/// Writes the file whole: a temporary file beside it, then renamed over it.
fn write(path: &Path, ron: &str) -> Result<(), CliError> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| CliError::input(format!("{}: {e}", dir.display())))?;
    }
    let tmp = path.with_extension("ron.tmp");
    std::fs::write(&tmp, ron)
        .and_then(|()| std::fs::rename(&tmp, path))
        .map_err(|e| CliError::input(format!("{}: {e}", path.display())))
}
