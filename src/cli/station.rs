//! `botbench station ...`: the line station. `station new [FILE]` writes the commented example
//! bundle; `station BUNDLE --check` reads the bundle and every file it names, prints their
//! hashes and sends nothing; `station password` prints the SHA-256 a bundle pins for the
//! engineer's password.

use super::{CliError, CliResult, registry};
use crate::ops::station::{self, Bundle, LoadContext};
use crate::sim::SimKind;
use clap::Args;
use std::path::{Path, PathBuf};

#[derive(Debug, Args)]
pub(crate) struct StationArgs {
    /// The station bundle (a RON file); or `new` to write the commented example (to FILE,
    /// default station.ron), or `password` to print the SHA-256 of a password read from stdin.
    #[arg(value_name = "BUNDLE|new|password")]
    pub bundle: String,
    /// `new` only: where the example is written (default station.ron; never overwritten).
    #[arg(value_name = "FILE")]
    pub file: Option<PathBuf>,
    /// Check the bundle and every file it names, print the hashes, send nothing (exit 0, or 2
    /// with the problem).
    #[arg(long)]
    pub check: bool,
    /// Run without a window: events on stdout, Start and answers from stdin.
    #[arg(long, conflicts_with = "check")]
    pub headless: bool,
    /// Print JSON (one document a line).
    #[arg(long)]
    pub json: bool,
    /// Headless: one unit per slot, then exit 0 when every slot passed, 1 otherwise.
    #[arg(long, requires = "headless")]
    pub once: bool,
    /// Who operates the station, in every record (default: BOTBENCH_OPERATOR).
    #[arg(long, value_name = "NAME")]
    pub operator: Option<String>,
    /// Where records go, over the bundle's `records` (a SQLite file or postgres://...).
    #[arg(long, value_name = "FILE|URL")]
    pub records: Option<String>,
    /// The spool a line server's records wait in on this PC while it cannot be reached (a
    /// SQLite file). Default: BOTBENCH_SPOOL, else spool-<hash of the URL>.sqlite in the
    /// user's data folder.
    #[arg(long, value_name = "FILE")]
    pub spool: Option<PathBuf>,
    /// Headless: a barcode scanner that is its own device (a serial scanner's tty, e.g.
    /// /dev/ttyACM0): each code it sends, ended by Enter, is taken as a line typed on stdin
    /// (a serial to start a slot, an answer, `PASS`/`FAIL`). A scanner that types as a
    /// keyboard needs nothing: it types into stdin.
    #[arg(long, value_name = "DEVICE", requires = "headless")]
    pub scanner: Option<PathBuf>,
    /// The window's screenshot tour (`.ci/screenshot.sh`): one unit per slot, the window shot
    /// at 1280x800 and 1024x600 in English and 中文 with a question waiting and with the
    /// verdicts, as PNGs in DIR; then it closes.
    #[arg(long, value_name = "DIR", conflicts_with = "headless")]
    pub screenshots: Option<PathBuf>,
}

pub(crate) fn run(args: StationArgs, opener: &crate::link::PortOpener) -> CliResult {
    match args.bundle.as_str() {
        "new" => new(args.file.as_deref().unwrap_or(Path::new("station.ron"))),
        "password" => password(),
        _ => {
            if let Some(extra) = &args.file {
                return Err(CliError::input(format!(
                    "unexpected argument '{}': only `station new` takes a file",
                    extra.display()
                )));
            }
            let bundle = load(Path::new(&args.bundle))?;
            let ports = crate::system::list_ports();
            let missing = missing_ports(&bundle, &ports);
            if args.check {
                print_check(&bundle, &missing, args.json);
                return match missing.first() {
                    Some((slot, why)) => Err(CliError::input(format!("slot {slot}: {why}"))),
                    None => Ok(0),
                };
            }
            if let Some((slot, why)) = missing.first() {
                return Err(CliError::input(format!(
                    "slot {slot}: {why}; nothing was started"
                )));
            }
            if args.headless {
                super::station_headless::run(&bundle, &args, opener)
            } else {
                let once = args.screenshots.is_some();
                let started = super::station_headless::start(&bundle, &args, opener, once)?;
                crate::ui::line::run(&bundle, started, args.screenshots.clone())
                    .map_err(|e| CliError::device(format!("cannot open the window: {e}")))?;
                Ok(0)
            }
        }
    }
}

/// Loads and checks `path` whole (exit 2 with the problem).
pub(crate) fn load(path: &Path) -> Result<Bundle, CliError> {
    let registry = registry()?;
    let sims = SimKind::names_with_profiles();
    let cx = LoadContext {
        registry: &registry,
        simulated: &sims,
    };
    station::load(path, &cx).map_err(CliError::input)
}

/// The slots whose port is not there now, with why.
fn missing_ports(bundle: &Bundle, ports: &[crate::system::PortInfo]) -> Vec<(String, String)> {
    bundle
        .slots
        .iter()
        .filter_map(|s| {
            station::port::resolve(&s.port, &s.name, ports)
                .err()
                .map(|why| (s.name.clone(), why))
        })
        .collect()
}

fn print_check(bundle: &Bundle, missing: &[(String, String)], json: bool) {
    let port_of = |slot: &str| missing.iter().find(|(s, _)| s == slot).map(|(_, w)| w);
    if json {
        let doc = serde_json::json!({
            "station": bundle.id,
            "bundle": bundle.path.display().to_string(),
            "bundle_sha256": bundle.sha256,
            "text_sha256": bundle.text_sha256,
            "files": bundle.files.iter().map(|f| serde_json::json!({
                "name": f.name, "path": f.path.display().to_string(), "what": f.what,
                "bytes": f.bytes, "sha256": f.sha256,
            })).collect::<Vec<_>>(),
            "slots": bundle.slots.iter().map(|s| serde_json::json!({
                "slot": s.name, "fixture": s.fixture, "port": s.port.said(),
                "port_missing": port_of(&s.name), "profile": s.profile.id, "plan": s.plan_name,
                "steps": s.plan.steps.iter().map(|st| st.name.clone()).collect::<Vec<_>>(),
            })).collect::<Vec<_>>(),
        });
        outln!("{doc}");
        return;
    }
    outln!(
        "station {}: {} slots, bundle SHA-256 {}",
        bundle.id,
        bundle.slots.len(),
        bundle.sha256
    );
    outln!(
        "  {:<20} {}  {}",
        "station bundle",
        bundle.text_sha256,
        bundle.path.display()
    );
    for f in &bundle.files {
        outln!(
            "  {:<20} {}  {} ({} bytes)",
            f.what,
            f.sha256,
            f.path.display(),
            f.bytes
        );
    }
    for s in &bundle.slots {
        let port = match port_of(&s.name) {
            Some(why) => format!("MISSING: {why}"),
            None => "present".to_string(),
        };
        outln!(
            "  slot {:<4} {:<28} {} ({port})  profile {}  plan {}: {}",
            s.name,
            s.fixture,
            s.port.said(),
            s.profile.id,
            s.plan_name,
            s.plan.step_names()
        );
    }
    if missing.is_empty() {
        outln!("bundle checked: nothing was sent");
    }
}

/// Writes the example bundle to `path`, never over a file.
fn new(path: &Path) -> CliResult {
    if path.exists() {
        return Err(CliError::input(format!(
            "{} exists: choose another name (it is never overwritten)",
            path.display()
        )));
    }
    crate::document::write_atomic(path, station::example::EXAMPLE.as_bytes())
        .map_err(CliError::input)?;
    outln!(
        "wrote {}: a station of three simulated slots; edit its slots and plans, then \
         `botbench station {} --check`",
        path.display(),
        path.display()
    );
    Ok(0)
}

/// Reads a password from stdin (one line) and prints its SHA-256 for `engineer_password_sha256`.
fn password() -> CliResult {
    let mut line = String::new();
    match super::console::read_line(&mut line) {
        Ok(n) if n > 0 && !line.trim_end_matches(['\r', '\n']).is_empty() => {
            let pw = line.trim_end_matches(['\r', '\n']);
            outln!("{}", crate::ops::records::record::sha256_hex(pw.as_bytes()));
            Ok(0)
        }
        _ => Err(CliError::input(
            "no password on stdin: `echo -n SECRET | botbench station password`",
        )),
    }
}
