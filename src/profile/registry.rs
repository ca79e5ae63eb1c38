//! Loading profiles: the built-in ones, a user's overrides, and files named on the command line.

use super::model::{Command, DeviceCode, Profile, Relation};
use super::validate::validate;
use crate::document::{Step, locate};
use crate::i18n::Text;
use serde::Deserialize;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The profiles built into the binary, as (file stem, RON text).
pub const BUILTIN: &[(&str, &str)] = &[
    (
        "window-cleaner",
        include_str!("../../assets/profiles/window-cleaner.ron"),
    ),
    (
        "window-cleaner-configurator",
        include_str!("../../assets/profiles/window-cleaner-configurator.ron"),
    ),
    (
        "solar-cleanbot",
        include_str!("../../assets/profiles/solar-cleanbot.ron"),
    ),
    ("servo", include_str!("../../assets/profiles/servo.ron")),
    (
        "tuya-vacuum",
        include_str!("../../assets/profiles/tuya-vacuum.ron"),
    ),
];

/// The environment variable naming a folder of profile overrides.
pub const DIR_ENV: &str = "BOTBENCH_PROFILE_DIR";

/// A profile that cannot be used, with where and why: `file:line:col: message`, `file: message`
/// where the place is unknown (line 0), or the message alone where there is no file (a name
/// that is no profile).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ProfileError {
    /// The file (or `builtin:<name>`), empty when there is none.
    pub file: String,
    /// 1-based line, 0 when unknown.
    pub line: usize,
    /// 1-based column, 0 when unknown.
    pub col: usize,
    /// What is wrong.
    pub message: String,
}

impl std::fmt::Display for ProfileError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match (self.file.is_empty(), self.line) {
            (true, _) => write!(f, "{}", self.message),
            (false, 0) => write!(f, "{}: {}", self.file, self.message),
            (false, line) => write!(f, "{}:{line}:{}: {}", self.file, self.col, self.message),
        }
    }
}

impl std::error::Error for ProfileError {}

/// Where a loaded profile came from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Source {
    /// Built into the binary.
    Builtin,
    /// A file.
    File(PathBuf),
}

/// Parses and checks a profile. `file` names it in errors; `expected_id`, where given, must be
/// the profile's `id` (a file's stem). A profile with a `base` is a variant of that built-in
/// profile ([`Variant`]).
pub fn parse(file: &str, src: &str, expected_id: Option<&str>) -> Result<Profile, ProfileError> {
    let syntax = |file: &str, e: ron::error::SpannedError| ProfileError {
        file: file.to_string(),
        line: e.span.start.line,
        col: e.span.start.col,
        message: crate::document::clip_message(&e.code.to_string()),
    };
    // `base: "window-cleaner"` as written, without `Some(...)`. A file that cannot be read so
    // far is read as a whole profile below, which reports where it fails.
    let base = ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
        .from_str::<Head>(src)
        .ok()
        .and_then(|h| h.base);
    let (mut profile, origin) = match base {
        None => {
            let p: Profile = ron::Options::default()
                .from_str(src)
                .map_err(|e| syntax(file, e))?;
            (p, None)
        }
        Some(base) => {
            let v: Variant = ron::Options::default()
                .from_str(src)
                .map_err(|e| syntax(file, e))?;
            let (base_name, base_src) =
                BUILTIN
                    .iter()
                    .find(|(n, _)| *n == base)
                    .ok_or_else(|| ProfileError {
                        file: file.to_string(),
                        line: locate(src, &[Step::Key("base")]).0,
                        col: locate(src, &[Step::Key("base")]).1,
                        message: format!(
                            "no built-in profile '{base}' to be a variant of; built in: {}",
                            BUILTIN
                                .iter()
                                .map(|(n, _)| *n)
                                .collect::<Vec<_>>()
                                .join(", ")
                        ),
                    })?;
            let base_file = format!("builtin:assets/profiles/{base_name}.ron");
            let p: Profile = ron::Options::default()
                .from_str(base_src)
                .map_err(|e| syntax(&base_file, e))?;
            let (p, origin) = v.apply(p);
            (p, Some((base_file, *base_src, origin)))
        }
    };
    let at = |path: &[Step], message: String| {
        // An inconsistency in what a variant took from its base points into the base.
        let (where_file, where_src, path, message) = match &origin {
            Some((base_file, base_src, origin)) => match origin.locate(path) {
                Some(p) => (file.to_string(), src, p, message),
                None => (
                    base_file.clone(),
                    *base_src,
                    path.to_vec(),
                    format!("{message} (in the base of {file})"),
                ),
            },
            None => (file.to_string(), src, path.to_vec(), message),
        };
        let (line, col) = locate(where_src, &path);
        ProfileError {
            file: where_file,
            line,
            col,
            message,
        }
    };
    if let Some(id) = expected_id
        && profile.id != id
    {
        return Err(at(
            &[Step::Key("id")],
            format!(
                "the profile's id '{}' must match its file name '{id}'",
                profile.id
            ),
        ));
    }
    validate(&mut profile).map_err(|issue| at(&issue.path, issue.message))?;
    Ok(profile)
}

/// Whether a profile file names a base.
#[derive(Deserialize)]
struct Head {
    #[serde(default)]
    base: Option<String>,
}

/// A firmware variant of a built-in profile: its own id and name, and the commands (and, if
/// given, the device code and relations) that differ. A command replaces the base's command of
/// the same id; a new id is added. Everything else is the base's.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Variant {
    id: String,
    /// Read through [`Head`]; here so that the file may hold it.
    #[serde(rename = "base")]
    _base: String,
    name: Text,
    #[serde(default)]
    device_code: Option<DeviceCode>,
    #[serde(default)]
    commands: Vec<Command>,
    #[serde(default)]
    relations: Option<Vec<Relation>>,
}

/// Which parts of a merged profile came from the variant's file.
struct Origin {
    /// For each command of the merged profile, its index in the variant's `commands`.
    commands: Vec<Option<usize>>,
    relations: bool,
}

impl Origin {
    /// The path in the variant's file of a merged profile's path, or `None` if it is the
    /// base's.
    fn locate(&self, path: &[Step]) -> Option<Vec<Step>> {
        match path {
            [Step::Key("commands"), Step::Index(k), rest @ ..] => {
                let j = self.commands.get(*k).copied().flatten()?;
                let mut p = vec![Step::Key("commands"), Step::Index(j)];
                p.extend_from_slice(rest);
                Some(p)
            }
            [Step::Key("relations"), ..] if self.relations => Some(path.to_vec()),
            [Step::Key("id" | "name" | "device_code" | "base"), ..] => Some(path.to_vec()),
            _ => None,
        }
    }
}

impl Variant {
    fn apply(self, mut p: Profile) -> (Profile, Origin) {
        p.id = self.id;
        p.name = self.name;
        if self.device_code.is_some() {
            p.device_code = self.device_code;
        }
        let mut commands: Vec<Option<usize>> = vec![None; p.commands.len()];
        for (j, c) in self.commands.into_iter().enumerate() {
            match p.commands.iter().position(|x| x.id == c.id) {
                Some(k) => {
                    p.commands[k] = c;
                    commands[k] = Some(j);
                }
                None => {
                    p.commands.push(c);
                    commands.push(Some(j));
                }
            }
        }
        let relations = self.relations.is_some();
        if let Some(r) = self.relations {
            p.relations = r;
        }
        (
            p,
            Origin {
                commands,
                relations,
            },
        )
    }
}

/// Reads and checks a profile file; its stem must be its id. A file that is not a regular file,
/// is larger than [`Limit::PROFILE`](crate::document::Limit::PROFILE) or is not UTF-8 is
/// refused before it is parsed.
pub fn load_file(path: &Path) -> Result<Profile, ProfileError> {
    let file = path.display().to_string();
    let src = crate::document::read_text(path, crate::document::Limit::PROFILE).map_err(|e| {
        let (line, col) = e.at();
        ProfileError {
            file: file.clone(),
            line,
            col,
            message: e.message().to_string(),
        }
    })?;
    let stem = path.file_stem().and_then(|s| s.to_str());
    parse(&file, &src, stem)
}

/// A set of profiles by id.
#[derive(Debug, Clone)]
pub struct Registry {
    entries: Vec<(Arc<Profile>, Source)>,
}

impl Registry {
    /// The built-in profiles only.
    pub fn builtin() -> Result<Self, ProfileError> {
        let mut entries = Vec::new();
        for (name, src) in BUILTIN {
            let p = parse(
                &format!("builtin:assets/profiles/{name}.ron"),
                src,
                Some(name),
            )?;
            entries.push((Arc::new(p), Source::Builtin));
        }
        Ok(Self { entries })
    }

    /// The built-in profiles, each overridden by a user's file of the same name in the folder
    /// named by `BOTBENCH_PROFILE_DIR`, else `$XDG_CONFIG_HOME/botbench/profiles` or
    /// `~/.config/botbench/profiles`. A user's file that is malformed is an error, not skipped.
    pub fn load() -> Result<Self, ProfileError> {
        Self::load_from(user_dir().as_deref())
    }

    /// The built-in profiles, each overridden by a file of the same name in `dir` (none: the
    /// built-ins alone; a missing folder is an empty one). Errors as [`Self::load`].
    pub fn load_from(dir: Option<&Path>) -> Result<Self, ProfileError> {
        let mut reg = Self::builtin()?;
        if let Some(dir) = dir {
            reg.add_dir(dir)?;
        }
        Ok(reg)
    }

    /// Adds or overrides profiles from every `*.ron` file in `dir` (a missing folder is fine).
    pub fn add_dir(&mut self, dir: &Path) -> Result<(), ProfileError> {
        let Ok(read) = std::fs::read_dir(dir) else {
            return Ok(());
        };
        let mut paths: Vec<PathBuf> = read
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "ron"))
            .collect();
        paths.sort();
        for path in paths {
            let p = load_file(&path)?;
            self.insert(p, Source::File(path));
        }
        Ok(())
    }

    /// Adds a profile, replacing one of the same id.
    pub fn insert(&mut self, profile: Profile, source: Source) {
        let p = Arc::new(profile);
        match self.entries.iter_mut().find(|(x, _)| x.id == p.id) {
            Some(slot) => *slot = (p, source),
            None => self.entries.push((p, source)),
        }
    }

    /// A profile by id, or a path to a `.ron` file.
    pub fn get(&self, name: &str) -> Result<Arc<Profile>, ProfileError> {
        if name.ends_with(".ron") || name.contains('/') {
            return load_file(Path::new(name)).map(Arc::new);
        }
        self.entries
            .iter()
            .find(|(p, _)| p.id == name)
            .map(|(p, _)| p.clone())
            .ok_or_else(|| ProfileError {
                file: String::new(),
                line: 0,
                col: 0,
                message: format!(
                    "no profile '{}'; known: {} (or a path to a .ron file)",
                    crate::document::quote(name),
                    self.names().join(", ")
                ),
            })
    }

    /// Every profile and where it came from.
    pub fn iter(&self) -> impl Iterator<Item = (&Arc<Profile>, &Source)> {
        self.entries.iter().map(|(p, s)| (p, s))
    }

    /// Each profile with characters in its texts (names, labels, units) that the bundled CJK
    /// font has no glyph for ([`crate::i18n::glyphs::bundled_lacks`]): (profile id, the
    /// characters). Empty when every text can be drawn with the bundled font.
    pub fn lacking_glyphs(&self) -> Vec<(String, Vec<char>)> {
        self.entries
            .iter()
            .filter_map(|(p, _)| {
                let text = ron::to_string(p.as_ref()).ok()?;
                let lacks = crate::i18n::glyphs::bundled_lacks(&text);
                (!lacks.is_empty()).then(|| (p.id.clone(), lacks))
            })
            .collect()
    }

    /// The profile ids.
    pub fn names(&self) -> Vec<String> {
        self.entries.iter().map(|(p, _)| p.id.clone()).collect()
    }
}

/// The folder of a user's profiles: `BOTBENCH_PROFILE_DIR`, else
/// `$XDG_CONFIG_HOME/botbench/profiles` or `~/.config/botbench/profiles`.
pub fn user_dir() -> Option<PathBuf> {
    if let Some(dir) = std::env::var_os(DIR_ENV) {
        return Some(PathBuf::from(dir));
    }
    let config = std::env::var_os("XDG_CONFIG_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".config")))?;
    Some(config.join("botbench").join("profiles"))
}

impl Profile {
    /// A command by canonical ident (case-insensitive) or number (`130`, `0x82`).
    pub fn command(&self, name: &str) -> Option<&Command> {
        let n = super::codec::parse_id(name);
        self.commands
            .iter()
            .find(|c| c.ident.eq_ignore_ascii_case(name) || Some(c.id) == n)
    }

    /// A command by number.
    pub fn command_by_id(&self, id: u8) -> Option<&Command> {
        self.commands.iter().find(|c| c.id == id)
    }

    /// The identifiers of the commands nearest to `name`, a name this profile does not have,
    /// at most three: those fewest edits from it (case aside; Levenshtein distance, at most a
    /// third of its length and at least 2: `MSP_GET_PWMVALU` gives `MSP_GET_PWMVALUE` only),
    /// else those that hold it whole (`PWMVALUE`: `MSP_GET_PWMVALUE` and `MSP_SET_PWMVALUE`).
    /// Empty when none is near.
    pub fn nearest_commands(&self, name: &str) -> Vec<&str> {
        let wanted = name.trim().to_ascii_uppercase();
        if wanted.is_empty() {
            return Vec::new();
        }
        let most = (wanted.chars().count() / 3).max(2);
        let distance = |c: &Command| strsim::levenshtein(&wanted, &c.ident.to_ascii_uppercase());
        let best = self
            .commands
            .iter()
            .map(distance)
            .min()
            .unwrap_or(usize::MAX);
        let near: Vec<&str> = if best <= most {
            self.commands
                .iter()
                .filter(|c| distance(c) == best)
                .map(|c| c.ident.as_str())
                .collect()
        } else if wanted.chars().count() >= 3 {
            self.commands
                .iter()
                .filter(|c| c.ident.to_ascii_uppercase().contains(&wanted))
                .map(|c| c.ident.as_str())
                .collect()
        } else {
            Vec::new()
        };
        near.into_iter().take(3).collect()
    }
}
