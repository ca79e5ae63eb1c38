//! Reading a station bundle whole before anything runs: the bundle file, every file it names
//! (self-test and provisioning plans, presets, profiles, firmware images) read once and hashed
//! (SHA-256), each plan checked against each slot's profile, pins compared, ports found. A
//! bundle with any problem is refused with the problem's `file:line:col` (or its slot) and
//! nothing is sent.

use super::doc::{BundleDoc, PlanDoc, PortLocator, SlotDoc, StepDoc, VERSION};
use super::plan::{LinePlan, LineStep, Op};
use crate::document::{self, DocumentError, ErrorKind, Limit, Source, Step as At};
use crate::profile::{Profile, Registry};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The most bytes of a bundle file.
pub const BUNDLE_LIMIT: Limit = Limit::new("station bundle", 1 << 20);

/// A file the bundle names, as read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HashedFile {
    /// The path as written in the bundle.
    pub name: String,
    /// Where it was read from (relative paths are taken from the bundle's folder).
    pub path: PathBuf,
    /// What it is: `self-test plan`, `preset`, `provisioning plan`, `profile`,
    /// `firmware image`.
    pub what: &'static str,
    /// Its size, bytes.
    pub bytes: u64,
    /// SHA-256 of its bytes, 64 lower-case hex digits.
    pub sha256: String,
}

/// A slot, resolved: its profile loaded, its plan checked against that profile.
#[derive(Debug, Clone)]
pub struct Slot {
    /// The slot's name (`1`).
    pub name: String,
    /// The fixture's name.
    pub fixture: String,
    /// The fixture's name in 中文 (`fixture_zh`, else `fixture`).
    pub fixture_zh: String,
    /// How its port is found.
    pub port: PortLocator,
    /// The device profile.
    pub profile: Arc<Profile>,
    /// The plan's name in the bundle.
    pub plan_name: String,
    /// The plan, its files parsed and checked against `profile`.
    pub plan: Arc<LinePlan>,
    /// What is done to its port right after each open: DTR, RTS, the boot wait.
    pub setup: crate::link::PortSetup,
}

/// A station bundle checked whole: what [`load`] returns.
#[derive(Debug, Clone)]
pub struct Bundle {
    /// The bundle file.
    pub path: PathBuf,
    /// The station's id.
    pub id: String,
    /// The operator view's language.
    pub language: crate::i18n::Lang,
    /// Where records go (`--records` syntax); `None`: this PC's default file.
    pub records: Option<String>,
    /// SHA-256 of the engineer's password (64 lower-case hex digits), if the bundle gives one.
    pub engineer_password_sha256: Option<String>,
    /// Whether the window sounds each verdict unless its operator chose otherwise (`sound`,
    /// default `true`).
    pub sound: bool,
    /// SHA-256 of the bundle file's own bytes.
    pub text_sha256: String,
    /// The bundle's hash: SHA-256 over its text and every file it names (see
    /// [`bundle_sha256`]); in every record the station makes.
    pub sha256: String,
    /// Every file named, in the order first named, each once.
    pub files: Vec<HashedFile>,
    /// The slots, in the bundle's order.
    pub slots: Vec<Slot>,
}

/// What [`load`] needs besides the file: the profiles, and which simulated devices exist (the
/// simulators are a layer above; the caller names them).
pub struct LoadContext<'a> {
    /// The device profiles (ids the slots name).
    pub registry: &'a Registry,
    /// The names `Simulated(...)` takes, each with its device profile's id.
    pub simulated: &'a [(&'a str, &'a str)],
}

/// The bundle's hash: SHA-256 over `botbench station bundle 1\n`, the bundle's bytes, then
/// for each named file in order `\n`, its name as written, a NUL and its SHA-256 in hex. So
/// an edit of the bundle or of any file it names changes it, and the same files give the same
/// hash on every PC.
pub fn bundle_sha256(text: &[u8], files: &[HashedFile]) -> String {
    let mut all = format!("botbench station bundle {VERSION}\n").into_bytes();
    all.extend_from_slice(text);
    for f in files {
        all.push(b'\n');
        all.extend_from_slice(f.name.as_bytes());
        all.push(0);
        all.extend_from_slice(f.sha256.as_bytes());
    }
    crate::ops::records::record::sha256_hex(&all)
}

/// Reads and checks the bundle at `path`: its syntax and version, every slot (unique names,
/// a known profile and plan, a port named once, a simulated device of the profile's kind),
/// every plan step against the slot's profile, every file it names (read once, parsed,
/// hashed), the pins. Errors: the first problems found, each as `file:line:col: message`
/// naming the slot or step; nothing has been sent.
pub fn load(path: &Path, cx: &LoadContext<'_>) -> Result<Bundle, DocumentError> {
    let bytes = document::read_bytes(path, BUNDLE_LIMIT)?;
    let name = path.display().to_string();
    let text = String::from_utf8(bytes.clone()).map_err(|e| {
        DocumentError::one(
            &name,
            ErrorKind::Syntax,
            (0, 0),
            format!("not UTF-8 text: {e}"),
        )
    })?;
    if text.trim().is_empty() {
        return Err(DocumentError::one(
            &name,
            ErrorKind::Syntax,
            (0, 0),
            "the file is empty: it holds no station bundle",
        ));
    }
    let src = Source::new(&name, &text);
    let doc: BundleDoc = src.parse()?;
    let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut reader = Reader::new(base, &src);
    check_head(&doc, &src)?;
    let mut slots = Vec::new();
    for (i, slot) in doc.slots.iter().enumerate() {
        slots.push(reader.slot(&doc, i, slot, cx)?);
    }
    check_ports(&doc, &src)?;
    check_pins(&doc, &src, &reader.files)?;
    let files = reader.files;
    Ok(Bundle {
        path: path.to_path_buf(),
        id: doc.id.clone(),
        language: doc.language.unwrap_or_default(),
        records: doc.records.clone(),
        engineer_password_sha256: doc.engineer_password_sha256.clone(),
        sound: doc.sound.unwrap_or(true),
        text_sha256: crate::ops::records::record::sha256_hex(&bytes),
        sha256: bundle_sha256(&bytes, &files),
        files,
        slots,
    })
}

/// The version, the id, the password hash and that there are slots.
fn check_head(doc: &BundleDoc, src: &Source<'_>) -> Result<(), DocumentError> {
    match doc.version {
        Some(VERSION) => {}
        Some(v) => {
            return Err(src.error(
                ErrorKind::Version,
                &[At::Key("version")],
                format!("bundle version {v}; this botbench reads version {VERSION}"),
            ));
        }
        None => {
            return Err(DocumentError::one(
                src.name,
                ErrorKind::Version,
                (1, 1),
                format!("no `version`: a bundle starts with `version: {VERSION},`"),
            ));
        }
    }
    let id = doc.id.trim();
    if id.is_empty() || id.len() > 64 || id != doc.id {
        return Err(src.error(
            ErrorKind::Value,
            &[At::Key("id")],
            "the station id is 1 to 64 characters, no spaces around it (`line3-st2`)",
        ));
    }
    if let Some(h) = &doc.engineer_password_sha256
        && !is_sha256(h)
    {
        return Err(src.error(
            ErrorKind::Value,
            &[At::Key("engineer_password_sha256")],
            "not a SHA-256: 64 lower-case hex digits (`botbench station password` prints one)",
        ));
    }
    if doc.slots.is_empty() {
        return Err(src.error(ErrorKind::Value, &[At::Key("slots")], "no slots"));
    }
    let mut names = BTreeMap::new();
    for (i, s) in doc.slots.iter().enumerate() {
        if s.name.trim().is_empty() || s.name.contains(char::is_whitespace) {
            return Err(src.error(
                ErrorKind::Value,
                &[At::Key("slots"), At::Index(i), At::Key("name")],
                "a slot's name is a word without spaces (`1`, `A`)",
            ));
        }
        if let Some(first) = names.insert(s.name.as_str(), i) {
            return Err(src.error(
                ErrorKind::Value,
                &[At::Key("slots"), At::Index(i), At::Key("name")],
                format!("slot {}: the name is taken by slot #{}", s.name, first + 1),
            ));
        }
    }
    Ok(())
}

/// Whether `s` is 64 lower-case hex digits.
pub fn is_sha256(s: &str) -> bool {
    s.len() == 64
        && s.bytes()
            .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b))
}

/// Two slots on one port: the same locator, or two that name the same device file.
fn check_ports(doc: &BundleDoc, src: &Source<'_>) -> Result<(), DocumentError> {
    let key = |p: &PortLocator| match p {
        PortLocator::Simulated(_) => None,
        PortLocator::UsbPath(p) | PortLocator::Path(p) => Some(
            std::fs::canonicalize(p)
                .map(|c| c.display().to_string())
                .unwrap_or_else(|_| p.clone()),
        ),
        PortLocator::AdapterSerial(s) => Some(format!("sn:{s}")),
    };
    let mut seen: BTreeMap<String, &SlotDoc> = BTreeMap::new();
    for (i, s) in doc.slots.iter().enumerate() {
        let Some(k) = key(&s.port) else { continue };
        if let Some(other) = seen.insert(k, s) {
            return Err(src.error(
                ErrorKind::Value,
                &[At::Key("slots"), At::Index(i), At::Key("port")],
                format!(
                    "slot {}: two slots on one port: {} is slot {}'s port too",
                    s.name,
                    s.port.said(),
                    other.name
                ),
            ));
        }
    }
    Ok(())
}

/// Every pin names a file the bundle reads, and that file's hash.
fn check_pins(
    doc: &BundleDoc,
    src: &Source<'_>,
    files: &[HashedFile],
) -> Result<(), DocumentError> {
    let mut problems = Vec::new();
    for (name, pinned) in &doc.pins {
        let at = [At::Key("pins"), At::Entry(name.clone())];
        match files.iter().find(|f| &f.name == name) {
            None => problems.push(src.problem(
                &at,
                format!("pins {name}, which no step or slot of the bundle names"),
            )),
            Some(f) if !f.sha256.eq_ignore_ascii_case(pinned.trim()) => problems.push(src.problem(
                &at,
                format!(
                    "{name} has changed since the bundle was made: its SHA-256 begins {}, \
                         the pin {} (`--check` prints the whole hashes)",
                    &f.sha256[..16],
                    pinned.get(..16).unwrap_or(pinned)
                ),
            )),
            Some(_) => {}
        }
    }
    src.check(ErrorKind::Value, problems)
}

/// Reads each named file once and resolves slots and their plans.
struct Reader<'s> {
    base: PathBuf,
    src: &'s Source<'s>,
    files: Vec<HashedFile>,
    read: BTreeMap<String, Arc<Vec<u8>>>,
}

impl<'s> Reader<'s> {
    fn new(base: PathBuf, src: &'s Source<'s>) -> Self {
        Self {
            base,
            src,
            files: Vec::new(),
            read: BTreeMap::new(),
        }
    }

    /// The file `name` (as written; relative to the bundle's folder, else a shipped example),
    /// read once whatever the number of steps naming it. `at`: where the bundle names it.
    fn file(
        &mut self,
        name: &str,
        limit: Limit,
        at: &[At],
    ) -> Result<(String, Arc<Vec<u8>>), DocumentError> {
        let path = self.path_of(name);
        let shown = path.display().to_string();
        if let Some(b) = self.read.get(name) {
            return Ok((shown, b.clone()));
        }
        let bytes = document::read_bytes(&path, limit).map_err(|e| {
            self.src
                .error(ErrorKind::Io, at, format!("{name}: {}", e.message()))
        })?;
        self.files.push(HashedFile {
            name: name.to_string(),
            path,
            what: limit.what,
            bytes: bytes.len() as u64,
            sha256: crate::ops::records::record::sha256_hex(&bytes),
        });
        let bytes = Arc::new(bytes);
        self.read.insert(name.to_string(), bytes.clone());
        Ok((shown, bytes))
    }

    fn path_of(&self, name: &str) -> PathBuf {
        let given = Path::new(name);
        let beside = self.base.join(given);
        if given.is_absolute() || beside.exists() {
            return beside;
        }
        // A bundle written by `station new` elsewhere names the shipped examples.
        crate::system::presets_dir()
            .map(|d| d.join(given))
            .filter(|p| p.is_file())
            .unwrap_or(beside)
    }

    /// A text file named by the bundle, as text.
    fn text(
        &mut self,
        name: &str,
        limit: Limit,
        at: &[At],
    ) -> Result<(String, String), DocumentError> {
        let (shown, bytes) = self.file(name, limit, at)?;
        let text = String::from_utf8(bytes.to_vec()).map_err(|_| {
            self.src
                .error(ErrorKind::Syntax, at, format!("{name}: not UTF-8 text"))
        })?;
        Ok((shown, text))
    }

    fn slot(
        &mut self,
        doc: &BundleDoc,
        i: usize,
        s: &SlotDoc,
        cx: &LoadContext<'_>,
    ) -> Result<Slot, DocumentError> {
        let at = |k: &'static str| [At::Key("slots"), At::Index(i), At::Key(k)];
        let profile = self.profile(s, cx, &at("profile"))?;
        if let PortLocator::Simulated(kind) = &s.port {
            match cx.simulated.iter().find(|(k, _)| k == kind) {
                None => {
                    let known: Vec<&str> = cx.simulated.iter().map(|(k, _)| *k).collect();
                    return Err(self.src.error(
                        ErrorKind::Value,
                        &at("port"),
                        format!(
                            "slot {}: no simulated device '{kind}'; known: {}",
                            s.name,
                            known.join(", ")
                        ),
                    ));
                }
                Some((_, id)) if profile.protocol != sim_protocol(cx.registry, id) => {
                    return Err(self.src.error(
                        ErrorKind::Value,
                        &at("profile"),
                        format!(
                            "slot {}: profile '{}' speaks {}, the simulated {kind} does not",
                            s.name,
                            profile.id,
                            profile.protocol.name()
                        ),
                    ));
                }
                Some(_) => {}
            }
        }
        let Some(plan_doc) = doc.plans.get(&s.plan) else {
            let known: Vec<&str> = doc.plans.keys().map(String::as_str).collect();
            return Err(self.src.error(
                ErrorKind::Value,
                &at("plan"),
                format!(
                    "slot {}: no plan '{}' in `plans`; the bundle has: {}",
                    s.name,
                    s.plan,
                    known.join(", ")
                ),
            ));
        };
        let plan = self.plan(&s.name, &s.plan, plan_doc, &profile)?;
        let setup = self.setup(s, &at)?;
        Ok(Slot {
            name: s.name.clone(),
            fixture: s.fixture.clone(),
            fixture_zh: s.fixture_zh.clone().unwrap_or_else(|| s.fixture.clone()),
            port: s.port.clone(),
            profile,
            plan_name: s.plan.clone(),
            plan: Arc::new(plan),
            setup,
        })
    }

    /// The slot's port setup (`dtr`, `rts`, `boot_wait_ms`); a bad value is refused where it
    /// is written, the slot named, with what is accepted.
    fn setup(
        &self,
        s: &SlotDoc,
        at: &dyn Fn(&'static str) -> [At; 3],
    ) -> Result<crate::link::PortSetup, DocumentError> {
        let bad = |key: &'static str, why: String| {
            self.src.error(
                ErrorKind::Value,
                &at(key),
                format!("slot {}: {key}: {why}", s.name),
            )
        };
        let line = |key: &'static str, given: &Option<String>| match given {
            None => Ok(crate::link::LineLevel::Keep),
            Some(text) => text.parse().map_err(|why| bad(key, why)),
        };
        let range = crate::link::BOOT_WAIT_MS;
        let boot_wait_ms = s.boot_wait_ms.unwrap_or(0);
        if !range.contains(&boot_wait_ms) {
            return Err(bad(
                "boot_wait_ms",
                format!(
                    "{boot_wait_ms} is out of range; give milliseconds from {} to {}",
                    range.start(),
                    range.end()
                ),
            ));
        }
        Ok(crate::link::PortSetup {
            dtr: line("dtr", &s.dtr)?,
            rts: line("rts", &s.rts)?,
            boot_wait: std::time::Duration::from_millis(boot_wait_ms),
        })
    }

    /// The slot's profile: an id in the registry, or a `.ron` file (read and hashed).
    fn profile(
        &mut self,
        s: &SlotDoc,
        cx: &LoadContext<'_>,
        at: &[At],
    ) -> Result<Arc<Profile>, DocumentError> {
        if s.profile.ends_with(".ron") || s.profile.contains('/') {
            let (shown, text) = self.text(&s.profile, Limit::PROFILE, at)?;
            let p = crate::profile::registry::parse(&shown, &text, None).map_err(|e| {
                DocumentError::one(&e.file, ErrorKind::Value, (e.line, e.col), e.message)
            })?;
            return Ok(Arc::new(p));
        }
        let p = cx.registry.get(&s.profile).map_err(|e| {
            self.src.error(
                ErrorKind::Value,
                at,
                format!("slot {}: {}", s.name, e.message),
            )
        })?;
        // A user's profile file overriding a built-in one is part of the configuration.
        if let Some((_, crate::profile::Source::File(path))) =
            cx.registry.iter().find(|(q, _)| q.id == p.id)
        {
            let name = path.display().to_string();
            self.file(&name, Limit::PROFILE, at)?;
        }
        Ok(p)
    }

    fn plan(
        &mut self,
        slot: &str,
        name: &str,
        doc: &PlanDoc,
        profile: &Arc<Profile>,
    ) -> Result<LinePlan, DocumentError> {
        if doc.steps.is_empty() {
            return Err(self.src.error(
                ErrorKind::Value,
                &[
                    At::Key("plans"),
                    At::Entry(name.to_string()),
                    At::Key("steps"),
                ],
                format!("plan {name}: no steps"),
            ));
        }
        let mut steps = Vec::new();
        for (i, step) in doc.steps.iter().enumerate() {
            let at = [
                At::Key("plans"),
                At::Entry(name.to_string()),
                At::Key("steps"),
                At::Index(i),
            ];
            if let Some(p) = step.protocol()
                && p != profile.protocol
            {
                return Err(self.src.error(
                    ErrorKind::Value,
                    &at,
                    format!(
                        "slot {slot}: plan {name}, step {} ({}): takes a device speaking {}; \
                         profile '{}' speaks {}",
                        i + 1,
                        step.kind(),
                        p.name(),
                        profile.id,
                        profile.protocol.name()
                    ),
                ));
            }
            let op = self.op(step, profile, &at)?;
            steps.push(LineStep::new(op));
        }
        Ok(LinePlan {
            name: name.to_string(),
            start: doc.start,
            retry_once: doc.retry_once,
            steps,
        })
    }

    fn op(&mut self, step: &StepDoc, profile: &Profile, at: &[At]) -> Result<Op, DocumentError> {
        let secs = |s: Option<u32>, default: u64| {
            std::time::Duration::from_secs(s.map_or(default, u64::from).clamp(1, 3600))
        };
        Ok(match step {
            StepDoc::Identify { hardware, firmware } => Op::Identify {
                hardware: hardware.clone(),
                firmware: firmware.clone(),
            },
            StepDoc::Scan { pattern, timeout_s } => {
                self.scan(pattern.as_deref(), at, secs(*timeout_s, 120))?
            }
            StepDoc::Preset(file) => {
                let (shown, text) = self.text(file, Limit::PRESET, at)?;
                let loaded = crate::preset::Preset::parse(&shown, &text, profile)?;
                Op::Preset {
                    file: file.clone(),
                    preset: loaded.preset,
                }
            }
            StepDoc::SelfTest(file) => {
                let (shown, text) = self.text(file, Limit::SELFTEST_PLAN, at)?;
                let plan = crate::ops::selftest::Plan::parse(&shown, &text, profile)?;
                Op::SelfTest {
                    file: file.clone(),
                    plan,
                }
            }
            StepDoc::Provision { plan, count } => {
                let (shown, text) = self.text(plan, Limit::PROVISION_PLAN, at)?;
                let parsed = crate::ops::servo::provision::Plan::parse(&shown, &text, profile)?;
                Op::Provision {
                    file: plan.clone(),
                    plan: parsed,
                    count: count.unwrap_or(1).clamp(1, 253),
                }
            }
            StepDoc::TuyaHandshake => Op::TuyaHandshake,
            StepDoc::TuyaStatus => Op::TuyaStatus,
            StepDoc::TuyaConform => Op::TuyaConform,
            StepDoc::FirmwareUpdate { image, version } => {
                self.firmware(image, version.as_deref(), profile, at)?
            }
            StepDoc::WriteResult => {
                if profile.command("MSP_SET_AUTO_TEST_RESULT").is_none()
                    || profile.command("MSP_AUTO_TEST_RESULT").is_none()
                {
                    return Err(self.src.error(
                        ErrorKind::Value,
                        at,
                        format!(
                            "WriteResult: profile '{}' has no MSP_SET_AUTO_TEST_RESULT (147) and \
                             MSP_AUTO_TEST_RESULT (148)",
                            profile.id
                        ),
                    ));
                }
                Op::WriteResult
            }
            StepDoc::Confirm {
                question,
                question_zh,
                timeout_s,
            } => Op::Confirm {
                question: crate::i18n::Text::new(
                    question.clone(),
                    question_zh.clone().unwrap_or_else(|| question.clone()),
                ),
                timeout: secs(*timeout_s, 60),
            },
            StepDoc::Measure {
                name,
                unit,
                min,
                max,
                timeout_s,
            } => {
                if !(min.is_finite() && max.is_finite() && min <= max) {
                    return Err(self.src.error(
                        ErrorKind::Value,
                        at,
                        format!("Measure {name}: min {min} must be at most max {max}"),
                    ));
                }
                Op::Measure {
                    name: name.clone(),
                    unit: unit.clone(),
                    min: *min,
                    max: *max,
                    timeout: secs(*timeout_s, 120),
                }
            }
        })
    }

    fn scan(
        &mut self,
        pattern: Option<&str>,
        at: &[At],
        timeout: std::time::Duration,
    ) -> Result<Op, DocumentError> {
        let pattern = match pattern {
            None => None,
            Some(p) => Some(regex::Regex::new(&format!("^(?:{p})$")).map_err(|e| {
                let first = e.to_string().lines().last().unwrap_or_default().to_string();
                self.src
                    .error(ErrorKind::Value, at, format!("Scan pattern {p:?}: {first}"))
            })?),
        };
        Ok(Op::Scan { pattern, timeout })
    }

    fn firmware(
        &mut self,
        image: &str,
        version: Option<&str>,
        profile: &Profile,
        at: &[At],
    ) -> Result<Op, DocumentError> {
        let (_, bytes) = self.file(image, Limit::FIRMWARE, at)?;
        let max = profile.ota_max_bytes();
        if bytes.is_empty() || bytes.len() as u64 > u64::from(max) {
            return Err(self.src.error(
                ErrorKind::Value,
                at,
                format!(
                    "{image}: {} bytes; profile '{}' takes 1 to {max}",
                    bytes.len(),
                    profile.id
                ),
            ));
        }
        let version = match version
            .map(str::to_string)
            .or_else(|| crate::ops::tuya::image_version(&bytes))
        {
            Some(v) if crate::ops::tuya::is_version(&v) => v,
            _ => {
                return Err(self.src.error(
                    ErrorKind::Value,
                    at,
                    format!(
                        "{image}: the image names no version; give the version it brings \
                         (`version: \"1.0.1\"`)"
                    ),
                ));
            }
        };
        Ok(Op::FirmwareUpdate {
            file: image.to_string(),
            image: bytes,
            version,
        })
    }
}

/// The protocol of the simulated device whose profile is `id`.
fn sim_protocol(registry: &Registry, id: &str) -> crate::profile::Protocol {
    registry
        .get(id)
        .map(|p| p.protocol)
        .unwrap_or(crate::profile::Protocol::Msp)
}
