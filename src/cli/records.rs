//! Where runs are recorded (`--records`, `--station`, `--slot`, `--operator`, `--serial`: one
//! option set for every command that records a run), and `botbench records list|show|export`.

use super::{CliError, CliResult};
use crate::ops::records::query::{self, Filter};
use crate::ops::records::runs::Given;
use crate::ops::records::{Kept, Location, Recorder, RecordsError, RunContext, SerialSource};
use clap::{Args, Subcommand};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Where a run's record goes and what is known of the unit: beside the port options of every
/// command that records a run (`msp selftest`, `servo provision`, `preset apply`; the station
/// and Tuya conformance later).
#[derive(Debug, Clone, Args)]
pub(crate) struct RecordArgs {
    /// Where records go: a SQLite file, or a line server postgres://USER:PASSWORD@HOST/DB
    /// (records wait in a local spool while it cannot be reached). Default: BOTBENCH_RECORDS,
    /// else records.sqlite in the user's data folder (~/.local/share/botbench/).
    // Read as text and checked by `location()` before anything runs: clap's own message would
    // quote a URL's password.
    #[arg(long, value_name = "FILE|URL")]
    pub records: Option<String>,
    /// The spool a line server's records wait in on this PC while it cannot be reached (a
    /// SQLite file; records no store took go to FILE.unsaved). Default: BOTBENCH_SPOOL, else
    /// spool-<hash of the URL>.sqlite in the user's data folder.
    #[arg(long, value_name = "FILE")]
    pub spool: Option<PathBuf>,
    /// This station's id in the record (default: BOTBENCH_STATION).
    #[arg(long, value_name = "ID")]
    pub station: Option<String>,
    /// The slot or fixture in the record.
    #[arg(long, value_name = "SLOT")]
    pub slot: Option<String>,
    /// Who runs it, in the record (default: BOTBENCH_OPERATOR).
    #[arg(long, value_name = "NAME")]
    pub operator: Option<String>,
    /// The unit's serial number, typed or scanned (a servo's is read from the servo): says the
    /// unit's earlier runs before this one, and goes into the record.
    #[arg(long, value_name = "SERIAL", value_parser = serial)]
    pub serial: Option<String>,
}

/// Reads `--records` (a bad one is exit 2, its password never shown), or the default.
pub(crate) fn location(given: Option<&str>) -> Result<Location, CliError> {
    match given {
        Some(text) => Location::parse(text),
        None => Location::default_location(),
    }
    .map_err(CliError::input)
}

/// Reads `--serial`: 1 to 64 printable characters, no spaces at either end.
fn serial(text: &str) -> Result<String, String> {
    let t = text.trim();
    if t.is_empty() || t.len() > 64 || t.chars().any(char::is_control) {
        return Err(format!(
            "'{}' is not a serial number: 1 to 64 printable characters",
            crate::document::quote(text)
        ));
    }
    Ok(t.to_string())
}

fn env(name: &str) -> Option<String> {
    std::env::var(name).ok().filter(|v| !v.trim().is_empty())
}

impl RecordArgs {
    /// The location asked, or the default.
    pub fn location(&self) -> Result<Location, CliError> {
        location(self.records.as_deref())
    }

    /// Station, slot and operator, from the options or the environment.
    pub fn context(&self) -> RunContext {
        RunContext {
            station: self.station.clone().or_else(|| env("BOTBENCH_STATION")),
            slot: self.slot.clone(),
            fixture: None,
            operator: self.operator.clone().or_else(|| env("BOTBENCH_OPERATOR")),
            bundle_sha256: None,
        }
    }

    /// Opens the records before anything is sent: a file that is not botbench's, of a newer
    /// schema, or that cannot be created is refused (exit 2, nothing run). A server that cannot
    /// be reached is said, and records wait in the spool.
    pub fn open(&self, quiet: bool) -> Result<Recorder, CliError> {
        let location = self.location()?;
        let mut recorder = Recorder::open_spooled(&location, self.context(), self.spool.as_deref())
            .map_err(CliError::input)?;
        let waiting = recorder.waiting();
        if let Some(e) = line_error(&mut recorder) {
            super::port::warn(&format!(
                "{e}; records wait in this PC's spool until it is back ({waiting} waiting)"
            ));
        } else if waiting > 0 && !quiet {
            errln!("botbench: {waiting} record(s) wait in the spool for {location}");
        }
        Ok(recorder)
    }

    /// What is known before the run: the serial typed, the plan file's hash and name.
    pub fn given(&self, plan: Option<&Path>) -> Given {
        Given {
            serial: self.serial.clone().map(|s| (s, SerialSource::Typed)),
            plan_sha256: plan.and_then(crate::ops::records::record::file_sha256),
            plan_name: plan.map(crate::ops::records::runs::plan_name),
        }
    }
}

/// Why the line server was not reached when the records were opened; what waited is sent
/// when it was.
fn line_error(recorder: &mut Recorder) -> Option<RecordsError> {
    match recorder.last_error() {
        Some(e) => Some(e),
        None if recorder.waiting() > 0 => recorder.forward_waiting().err(),
        None => None,
    }
}

/// Says the unit's earlier runs before a run: `serial 1234: already tested 2 times, last: FAIL
/// at Battery voltage on 2026-12-01 14:03 at line3-st2`, or that it is new.
pub(crate) fn say_history(recorder: &mut Recorder, profile: &str, serial: &str, json: bool) {
    let mut found = None;
    let result = recorder.store().read(&mut |db| {
        found = query::history(db, profile, serial)?;
        Ok(())
    });
    let line = match (result, found) {
        (Err(e), _) => format!("serial {serial}: earlier runs not known ({e})"),
        (Ok(()), Some(h)) => format!("serial {serial}: {}", h.line()),
        (Ok(()), None) => format!("serial {serial}: not tested before"),
    };
    if json {
        errln!("botbench: {line}");
    } else {
        outln!("{line}");
    }
}

/// Says where a record went: a line on stderr when stored, a warning when it waits, the record
/// itself when nothing could keep it. `Err` (exit 1) only then, after the verdict was shown.
pub(crate) fn say_kept(kept: &Kept, json: bool) -> Result<(), CliError> {
    match kept {
        Kept::Stored { .. } => {
            if !json {
                errln!("botbench: {}", kept.line());
            }
            Ok(())
        }
        Kept::Spooled { .. } => {
            super::port::warn(&kept.line());
            Ok(())
        }
        Kept::InMemory { .. } => Err(CliError::device(kept.line())),
    }
}

/// `botbench records`.
#[derive(Debug, Args)]
pub(crate) struct RecordsCmdArgs {
    /// Where records are read from (default as for runs: BOTBENCH_RECORDS, else the PC's file).
    #[arg(long, global = true, value_name = "FILE|URL")]
    records: Option<String>,
    #[command(subcommand)]
    cmd: RecordsCmd,
}

/// Which runs: `--since`, `--until`, `--station`, `--plan`.
#[derive(Debug, Clone, Args)]
pub(crate) struct FilterArgs {
    /// Runs started at or after: 2026-12-01, "2026-12-01 06:00", RFC 3339, or 8h / 7d back.
    #[arg(long, value_name = "TIME", value_parser = time)]
    pub since: Option<At>,
    /// Runs started before (same forms as --since).
    #[arg(long, value_name = "TIME", value_parser = time)]
    pub until: Option<At>,
    /// Runs at this station only.
    #[arg(long, value_name = "ID")]
    pub station: Option<String>,
    /// Runs of this plan only: its name, or the start of its SHA-256 (6+ hex digits).
    #[arg(long, value_name = "PLAN")]
    pub plan: Option<String>,
}

impl FilterArgs {
    /// The filter.
    pub fn filter(&self) -> Filter {
        Filter {
            since_ms: self.since.map(|t| t.0),
            until_ms: self.until.map(|t| t.0),
            station: self.station.clone(),
            plan: self.plan.clone(),
            serial: None,
            access: false,
        }
    }

    /// `since 2026-12-01 06:00, station line3` or `all records`.
    pub fn said(&self) -> String {
        let mut parts = Vec::new();
        if let Some(t) = self.since {
            parts.push(format!("since {}", query::local_time(t.0)));
        }
        if let Some(t) = self.until {
            parts.push(format!("until {}", query::local_time(t.0)));
        }
        if let Some(s) = &self.station {
            parts.push(format!("station {s}"));
        }
        if let Some(p) = &self.plan {
            parts.push(format!("plan {p}"));
        }
        if parts.is_empty() {
            "all records".into()
        } else {
            parts.join(", ")
        }
    }
}

/// A time given on the command line, ms since 1970 UTC (a time, not a number with a range).
#[derive(Debug, Clone, Copy)]
pub(crate) struct At(pub i64);

fn time(text: &str) -> Result<At, String> {
    query::parse_time(text).map(At)
}

#[derive(Debug, Subcommand)]
enum RecordsCmd {
    /// The newest runs, one a line.
    List {
        #[command(flatten)]
        filter: FilterArgs,
        /// How many, newest first: 1 to 100000.
        #[arg(long, default_value_t = 50, value_parser = clap::value_parser!(u64).range(1..=100_000))]
        limit: u64,
        /// Print JSON lines.
        #[arg(long)]
        json: bool,
    },
    /// Every run of one unit, whole: steps, measurements, writes.
    Show {
        /// The unit's serial number.
        serial: String,
        /// Print JSON lines (one record a line).
        #[arg(long)]
        json: bool,
    },
    /// Every record, oldest first, as CSV (a row per measurement) or JSON lines (a record per
    /// line), to stdout or --output.
    Export {
        #[command(flatten)]
        filter: FilterArgs,
        /// csv or jsonl.
        #[arg(long, value_parser = ["csv", "jsonl"])]
        format: String,
        /// Write here instead of stdout (replaced whole when complete).
        #[arg(long, short, value_name = "FILE")]
        output: Option<PathBuf>,
    },
    /// Forward the records waiting in this PC's spool to the line server now.
    Forward,
    /// Fill an EMPTY records file or database with generated records of a plausible line (two
    /// stations, four slots, ten measured steps, retests, a drifting fan current), to try
    /// `report` and the Yield view; refused where any record is stored.
    Demo {
        /// Units to generate, 1 to 1000000, spread over the last --days days.
        #[arg(long, default_value_t = 2000, value_parser = clap::value_parser!(u64).range(1..=1_000_000))]
        units: u64,
        /// Days the units are spread over, ending now: 1 to 365.
        #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u64).range(1..=365))]
        days: u64,
    },
}

/// Opens the records to read them (exit 2 for a file that is not botbench's or is newer).
pub(crate) fn open_for_reading(records: Option<&str>) -> Result<Recorder, CliError> {
    let location = location(records)?;
    if let Location::Sqlite(p) = &location
        && !p.exists()
    {
        return Err(CliError::input(format!(
            "{}: no records file there yet (runs create it; --records names another)",
            p.display()
        )));
    }
    Recorder::open(&location, RunContext::default()).map_err(CliError::input)
}

/// An error reading records: the server away is the data's failure (exit 1).
pub(crate) fn read_error(e: RecordsError) -> CliError {
    match e {
        RecordsError::Unreachable { .. } | RecordsError::LoginRefused { .. } => CliError::device(e),
        other => CliError::input(other),
    }
}

pub(crate) fn run(args: RecordsCmdArgs) -> CliResult {
    if let RecordsCmd::Demo { units, days } = args.cmd {
        return demo(args.records.as_deref(), units, days);
    }
    let mut recorder = open_for_reading(args.records.as_deref())?;
    match args.cmd {
        RecordsCmd::List {
            filter,
            limit,
            json,
        } => {
            let mut lines = Vec::new();
            recorder
                .store()
                .read(&mut |db| {
                    // The list shows the station's access events too (an engineer's unlock,
                    // a refused password, a lock) among the units' runs.
                    let filter = query::Filter {
                        access: true,
                        ..filter.filter()
                    };
                    lines = query::list(db, &filter, limit)?;
                    Ok(())
                })
                .map_err(read_error)?;
            for l in &lines {
                if json {
                    outln!("{}", serde_json::to_string(l).unwrap_or_default());
                } else {
                    outln!(
                        "{}  {:<4}  {:<12}  {:<16}  {:<14}  {}{}",
                        query::local_time(l.started_ms),
                        l.verdict,
                        l.kind,
                        l.serial.as_deref().unwrap_or("-"),
                        l.station,
                        l.plan,
                        l.failed_step
                            .as_ref()
                            .map(|s| format!("  failed at {s}"))
                            .unwrap_or_default()
                    );
                }
            }
            if !json && lines.is_empty() {
                outln!("no records ({})", filter.said());
            }
            Ok(0)
        }
        RecordsCmd::Show { serial, json } => {
            let filter = Filter {
                serial: Some(serial.clone()),
                ..Filter::default()
            };
            let mut n = 0;
            recorder
                .store()
                .read(&mut |db| {
                    query::each_record(db, &filter, &mut |r| {
                        n += 1;
                        if json {
                            outln!("{}", serde_json::to_string(&r).unwrap_or_default());
                        } else {
                            print_record(&r);
                        }
                        Ok(())
                    })
                })
                .map_err(read_error)?;
            if n == 0 {
                return Err(CliError::device(format!("no records of serial {serial}")));
            }
            Ok(0)
        }
        RecordsCmd::Export {
            filter,
            format,
            output,
        } => export(&mut recorder, &filter.filter(), &format, output.as_deref()),
        RecordsCmd::Demo { .. } => Ok(0),
        RecordsCmd::Forward => {
            let left = recorder.forward_waiting().map_err(read_error)?;
            outln!("{left} record(s) still waiting");
            Ok(u8::from(left > 0))
        }
    }
}

/// A measured value as a person reads it: at most 4 decimals, trailing zeros dropped.
fn short(x: f64) -> String {
    let s = format!("{x:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

/// `records demo`: generated records into an empty store.
fn demo(records: Option<&str>, units: u64, days: u64) -> CliResult {
    let location = location(records)?;
    let mut recorder = Recorder::open(&location, RunContext::default()).map_err(CliError::input)?;
    let mut stored = 0i64;
    recorder
        .store()
        .read(&mut |db| {
            stored = db
                .rows("SELECT COUNT(*) FROM runs", &[])?
                .first()
                .and_then(|r| r.first())
                .and_then(|v| v.int())
                .unwrap_or(0);
            Ok(())
        })
        .map_err(read_error)?;
    if stored > 0 {
        return Err(CliError::input(format!(
            "{location} holds {stored} record(s): generated records go only into an empty one (name another with --records)"
        )));
    }
    let end = crate::ops::records::record::now_ms();
    let start = end - days as i64 * 86_400_000;
    let mut n = 0u64;
    let mut failed = None;
    crate::ops::records::demo::generate(units as usize, start, end, 28, &mut |mut r| {
        if failed.is_some() {
            return;
        }
        match recorder.save(&mut r) {
            Kept::Stored { .. } => n += 1,
            other => failed = Some(other.line()),
        }
    });
    if let Some(e) = failed {
        return Err(CliError::device(e));
    }
    outln!("{n} generated records of {units} units saved to {location}");
    Ok(0)
}

fn print_record(r: &crate::ops::records::Record) {
    let o = |v: &Option<String>| v.clone().unwrap_or_else(|| "-".into());
    outln!(
        "{} {}  {}  {}  serial {} ({})  plan {} {}",
        query::local_time(r.started_ms),
        r.verdict.name(),
        r.kind.name(),
        r.profile,
        o(&r.unit.serial),
        r.unit.serial_source.map_or("-", |s| s.name()),
        r.plan,
        r.plan_sha256
            .as_deref()
            .map_or("-", |h| &h[..h.len().min(12)]),
    );
    outln!(
        "  station {}  slot {}  operator {}  host {}  botbench {} ({})  hw {} fw {} build {}",
        o(&r.context.station),
        o(&r.context.slot),
        o(&r.context.operator),
        r.host,
        r.software,
        r.commit,
        o(&r.unit.hardware),
        o(&r.unit.firmware),
        o(&r.unit.build)
    );
    for s in &r.steps {
        outln!(
            "  {:<4} {:<28} {:>6} ms  {}",
            s.verdict.name(),
            s.name,
            s.duration_ms,
            s.reason.as_deref().unwrap_or("")
        );
        for m in &s.measurements {
            let lim = |v: Option<f64>| v.map_or("–".into(), short);
            outln!(
                "         {} = {} {} [{} .. {}]{}",
                m.name,
                short(m.value),
                m.unit,
                lim(m.low),
                lim(m.high),
                if m.pass { "" } else { " OUT" }
            );
        }
        for w in &s.writes {
            outln!(
                "         {} := {} {} (before {}, after {})",
                w.name,
                w.value,
                w.unit,
                w.before.as_deref().unwrap_or("?"),
                w.after.as_deref().unwrap_or("?")
            );
        }
    }
}

fn export(
    recorder: &mut Recorder,
    filter: &Filter,
    format: &str,
    output: Option<&Path>,
) -> CliResult {
    let csv_mode = format == "csv";
    let mut buffer: Vec<u8> = Vec::new();
    let mut stdout = super::console::Stdout;
    let sink: &mut dyn Write = if output.is_some() {
        &mut buffer
    } else {
        &mut stdout
    };
    let as_csv = |rows: &[Vec<String>]| -> Result<Vec<u8>, String> {
        let mut w = csv::Writer::from_writer(Vec::new());
        for row in rows {
            w.write_record(row).map_err(|e| e.to_string())?;
        }
        w.into_inner().map_err(|e| e.to_string())
    };
    let mut failed: Option<String> = None;
    if csv_mode {
        let header = vec![query::CSV_COLUMNS.iter().map(|c| c.to_string()).collect()];
        match as_csv(&header) {
            Ok(bytes) => {
                if let Err(e) = sink.write_all(&bytes) {
                    failed = Some(e.to_string());
                }
            }
            Err(e) => failed = Some(e),
        }
    }
    recorder
        .store()
        .read(&mut |db| {
            query::each_record(db, filter, &mut |r| {
                if failed.is_some() {
                    return Ok(());
                }
                let bytes = if csv_mode {
                    as_csv(&query::csv_rows(&r))
                } else {
                    serde_json::to_string(&r)
                        .map(|s| (s + "\n").into_bytes())
                        .map_err(|e| e.to_string())
                };
                match bytes.and_then(|b| sink.write_all(&b).map_err(|e| e.to_string())) {
                    Ok(()) => {}
                    Err(e) => failed = Some(e),
                }
                Ok(())
            })
        })
        .map_err(read_error)?;
    if let Err(e) = sink.flush() {
        failed.get_or_insert(e.to_string());
    }
    if let Some(e) = failed {
        return Err(CliError::input(format!("cannot write the export: {e}")));
    }
    if let Some(path) = output {
        crate::document::write_atomic(path, &buffer).map_err(CliError::input)?;
    }
    Ok(0)
}
