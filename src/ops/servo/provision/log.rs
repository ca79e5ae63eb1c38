//! The provisioning log: one CSV line per servo, written with the `csv` crate.

use super::{Outcome, Record};
use std::io::Write;
use std::path::Path;

/// The log's columns for a plan that records `recorded`: `time, serial, id, baud, result, step,
/// reason, mismatches`, then each recorded parameter.
pub fn log_columns(recorded: &[String]) -> Vec<String> {
    [
        "time",
        "serial",
        "id",
        "baud",
        "result",
        "step",
        "reason",
        "mismatches",
    ]
    .iter()
    .map(|s| s.to_string())
    .chain(recorded.iter().cloned())
    .collect()
}

/// One record as the log's cells, in [`log_columns`] order: unknown values as empty cells,
/// mismatches joined with `; `. The result is `PASS`, `FAIL`, or `NO VERDICT` when the link was
/// lost during the step (its reason then `link lost: ` and what the link said).
pub fn log_row(record: &Record) -> Vec<String> {
    let opt = |v: Option<String>| v.unwrap_or_default();
    let (result, step, reason) = match &record.result {
        Outcome::Pass => ("PASS", "", String::new()),
        Outcome::Fail { step, reason } => ("FAIL", step.as_str(), reason.clone()),
        Outcome::LinkLost { step, reason } => {
            let why = crate::ops::station::Reason::LinkLostBecause {
                why: reason.clone(),
            };
            ("NO VERDICT", step.as_str(), why.to_string())
        }
    };
    let mut cells = vec![
        record.time.clone(),
        opt(record.serial.map(|s| s.to_string())),
        opt(record.id.map(|s| s.to_string())),
        opt(record.baud.map(|s| s.to_string())),
        result.to_string(),
        step.to_string(),
        reason,
        record.mismatches.join("; "),
    ];
    cells.extend(
        record
            .recorded
            .iter()
            .map(|(_, v)| v.clone().unwrap_or_default()),
    );
    cells
}

/// Appends `record` to the CSV log at `path` (RFC 4180, written with the `csv` crate), writing
/// the header first when the file is new or empty, and syncs it to disk. A log whose header is
/// for other recorded parameters is refused rather than mixed.
pub fn append_csv(path: &Path, record: &Record) -> std::io::Result<()> {
    let names: Vec<String> = record.recorded.iter().map(|(k, _)| k.clone()).collect();
    let header = log_columns(&names);
    let mut file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)?;
    let new = file.metadata()?.len() == 0;
    if !new {
        check_header(path, &header)?;
    }
    let mut out = csv::Writer::from_writer(Vec::new());
    if new {
        out.write_record(&header)?;
    }
    out.write_record(log_row(record))?;
    let bytes = out.into_inner().map_err(|e| e.into_error())?;
    // One write, so that two stations appending to a shared log do not interleave.
    file.write_all(&bytes)?;
    file.sync_all()
}

/// The most bytes of a log's first line read to compare its header.
const HEADER_MAX: u64 = 64 << 10;

/// Refuses a log whose first line is not `header` (another plan's log, or not a log at all).
fn check_header(path: &Path, header: &[String]) -> std::io::Result<()> {
    use std::io::{BufRead, Read};
    let mut line = String::new();
    let file = std::fs::File::open(path)?;
    // A line longer than any header is not one: read no more of it.
    std::io::BufReader::new(file.take(HEADER_MAX)).read_line(&mut line)?;
    let mut first = csv::StringRecord::new();
    csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_reader(line.as_bytes())
        .read_record(&mut first)?;
    if first.iter().eq(header.iter()) {
        return Ok(());
    }
    Err(std::io::Error::new(
        std::io::ErrorKind::InvalidData,
        format!(
            "{} has another header ({}); this plan logs {}: use another log file",
            path.display(),
            crate::document::quote(&first.iter().collect::<Vec<_>>().join(",")),
            header.join(",")
        ),
    ))
}

/// Checks, before any servo is touched, that the log at `path` can be appended to (created if
/// missing; a folder, a device or a pipe is refused) and that an existing one is a log of a plan
/// that records `recorded` (its header).
pub fn check_log(path: &Path, recorded: &[String]) -> Result<(), crate::document::DocumentError> {
    crate::document::check_append(path)?;
    let empty = std::fs::metadata(path).is_ok_and(|m| m.len() == 0);
    if empty {
        return Ok(());
    }
    check_header(path, &log_columns(recorded))
        .map_err(|e| crate::document::DocumentError::io(path, "use it as the log", &e))
}
