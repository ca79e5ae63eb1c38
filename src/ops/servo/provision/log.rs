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
/// mismatches joined with `; `.
pub fn log_row(record: &Record) -> Vec<String> {
    let opt = |v: Option<String>| v.unwrap_or_default();
    let (result, step, reason) = match &record.result {
        Outcome::Pass => ("PASS", "", ""),
        Outcome::Fail { step, reason } => ("FAIL", step.as_str(), reason.as_str()),
    };
    let mut cells = vec![
        record.time.clone(),
        opt(record.serial.map(|s| s.to_string())),
        opt(record.id.map(|s| s.to_string())),
        opt(record.baud.map(|s| s.to_string())),
        result.to_string(),
        step.to_string(),
        reason.to_string(),
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
        let mut first = csv::StringRecord::new();
        csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .from_path(path)?
            .read_record(&mut first)?;
        if !first.iter().eq(header.iter()) {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!(
                    "{} has another header ({}); this plan logs {}: use another log file",
                    path.display(),
                    first.iter().collect::<Vec<_>>().join(","),
                    header.join(",")
                ),
            ));
        }
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

/// Checks that the log at `path` can be appended to (created if missing), before any servo is
/// touched.
pub fn check_log(path: &Path) -> std::io::Result<()> {
    std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .map(drop)
}
