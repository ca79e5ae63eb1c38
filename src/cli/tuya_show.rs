//! What `botbench tuya` prints: a status (each data point's value, or why it does not fit and
//! what the profile allows; those the profile lacks; those missing; reports heard between
//! queries; refused frames), and a data-point command's verification.

use crate::link::session::tuya::version_text;
use crate::ops::tuya::{DpCheck, ReportedDp, Status};
use crate::profile::{Profile, Value};
use crate::protocol::tuya::dp::DpType;
use serde_json::json;

/// A raw value as the data point's field shows it, with its unit.
pub(super) fn shown(profile: &Profile, id: u8, v: &Value) -> String {
    profile.data_point(id).map_or(format!("{v:?}"), |d| {
        format!("{}{}", d.field.format(v), d.field.unit_suffix())
    })
}

/// A report as JSON: `dp`, `id`, `value` (raw units, or null), `raw`, `misfit` (its kind),
/// `mismatch` (why, in words), `allowed` (what the profile allows), `in_profile`.
pub(super) fn report_json(profile: &Profile, r: &ReportedDp) -> serde_json::Value {
    let mut doc = serde_json::to_value(r).unwrap_or_default();
    doc["dp"] = json!(r.ident);
    doc["in_profile"] = json!(r.in_profile());
    doc["mismatch"] = json!(r.misfit.as_ref().map(ToString::to_string));
    doc["allowed"] = json!(profile.data_point(r.id).map(|d| d.allowed_text()));
    doc["shown"] = json!(r.shown(profile));
    if !r.in_profile() {
        doc["type"] = json!(DpType::from_byte(r.wire_type).map(DpType::name));
        doc["len"] = json!(r.raw.len());
    }
    doc
}

/// A data point by id as a person reads it: `battery (6)`.
fn name(profile: &Profile, id: u8) -> String {
    profile
        .data_point(id)
        .map_or(id.to_string(), |d| format!("{} ({id})", d.field.ident))
}

/// The status as one JSON document: `complete`, `suspect` (ids whose report does not fit),
/// `unknown` (ids the profile lacks), `missing`, `between_queries`, `refused`, every data
/// point.
pub(super) fn status_json(
    profile: &Profile,
    status: &Status,
    version: Option<u8>,
) -> serde_json::Value {
    json!({
        "frame_version": version,
        "complete": status.complete(),
        "queries": status.queries,
        "between_queries": status.between,
        "data_points": status.data_points.iter().map(|d| report_json(profile, d)).collect::<Vec<_>>(),
        "suspect": status.suspect().iter().map(|d| d.id).collect::<Vec<_>>(),
        "unknown": status.unknown().iter().map(|d| d.id).collect::<Vec<_>>(),
        "missing": status.missing.iter().map(|id| json!({
            "id": id, "dp": profile.data_point(*id).map(|d| &d.field.ident),
        })).collect::<Vec<_>>(),
        "refused": status.refused,
    })
}

/// Prints the status: a line a data point (a misfit marked `MISFIT`, with its raw bytes, why
/// and what the profile allows), then the data points the profile lacks, those missing, the
/// reports heard between queries and the frames refused.
pub(super) fn print_status(profile: &Profile, status: &Status, version: Option<u8>, json: bool) {
    if json {
        outln!("{}", status_json(profile, status, version));
        return;
    }
    if let Some(v) = version {
        outln!("{}", version_text(v));
    }
    // One column for the values, however long the names (`clean_area_total_lifetime (31)`).
    let width = status
        .data_points
        .iter()
        .map(|d| d.name().chars().count())
        .max()
        .unwrap_or(0)
        .max(24);
    for d in status.data_points.iter().filter(|d| d.in_profile()) {
        match &d.misfit {
            None => outln!("{:<width$} {}", d.name(), d.shown(profile)),
            Some(_) => outln!("{:<width$} MISFIT {}", d.name(), d.shown(profile)),
        }
    }
    print_status_notes(profile, status);
}

/// What a status says beyond its values: the data points the profile lacks, those missing,
/// the reports heard between queries, the frames refused.
pub(super) fn print_status_notes(profile: &Profile, status: &Status) {
    let unknown = status.unknown();
    if !unknown.is_empty() {
        outln!("not in the profile (read by their own type and length):");
        let width = unknown
            .iter()
            .map(|d| d.name().chars().count())
            .max()
            .unwrap_or(0)
            .max(22);
        for d in unknown {
            outln!("  {:<width$} {}", d.name(), d.shown(profile));
        }
    }
    if !status.missing.is_empty() {
        let names: Vec<String> = status.missing.iter().map(|id| name(profile, *id)).collect();
        outln!(
            "not reported after {} status queries: {}",
            status.queries,
            names.join(", ")
        );
    }
    if status.between > 0 {
        outln!(
            "{} report(s) came between status queries (a slow MCU): kept",
            status.between
        );
    }
    for r in &status.refused {
        outln!("refused: {r}");
    }
}

/// Prints a data-point command's checks; returns 1 unless each is verified.
pub(super) fn print_checks(profile: &Profile, checks: &[DpCheck], json: bool) -> u8 {
    let bad = checks.iter().filter(|c| !c.verified()).count();
    if json {
        let doc = json!({
            "verified": bad == 0,
            "data_points": checks.iter().map(|c| json!({
                "dp": c.ident, "id": c.id, "sent": c.sent, "ok": c.verified(),
                "reports": c.reports, "last": c.last.as_ref().map(|r| report_json(profile, r)),
            })).collect::<Vec<_>>(),
        });
        outln!("{doc}");
    } else {
        for c in checks {
            let sent = shown(profile, c.id, &c.sent);
            let verdict = match &c.last {
                _ if c.verified() => "verified".to_string(),
                Some(r) => format!("MISMATCH: the MCU reports {}", r.shown(profile)),
                None => "NOT VERIFIED: the MCU reported nothing of it after the command".into(),
            };
            outln!("{:<20} {sent:>12}  {verdict}", c.ident);
        }
    }
    u8::from(bad > 0)
}
