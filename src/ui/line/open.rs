//! File > Open station in the ordinary window: a station bundle read and checked whole (every
//! file it names, every slot's port), its slots started, and the station shown in the window
//! in place of the panels. A bundle refused by the checks starts nothing and leaves the window
//! as it was; the problem is said as the checks say it (`file:line:column: ...`, or `slot 2:
//! ...`). The station closes (back to the panels) only while no slot runs a unit.

use super::LineStation;
use crate::link::PortOpener;
use crate::ops::records::{Location, Recorder, RunContext};
use crate::ops::station::{self, LoadContext};
use crate::profile::Registry;
use std::path::Path;

/// The station of the bundle at `path`, started: profiles from `registry`, ports opened with
/// `ports`, records to the bundle's `records`, else `records` (the window's records file),
/// else the default store; shown in `lang` unless the bundle asks for its own.
/// Errors: the bundle's problem (`file:line:column: ...`), a slot whose port is missing
/// (`slot 2: ...`), the records store, a slot that cannot start; nothing is started then.
pub fn open(
    path: &Path,
    registry: &Registry,
    ports: &PortOpener,
    records: Option<&str>,
) -> Result<LineStation, String> {
    let sims: Vec<(&str, &str)> = crate::sim::SimKind::ALL
        .iter()
        .map(|k| (k.name(), k.profile_id()))
        .collect();
    let cx = LoadContext {
        registry,
        simulated: &sims,
    };
    let bundle = station::load(path, &cx).map_err(|e| e.to_string())?;
    let listed = crate::system::list_ports();
    for slot in &bundle.slots {
        if let Err(why) = station::port::resolve(&slot.port, &slot.name, &listed) {
            return Err(format!("slot {}: {why}; nothing was started", slot.name));
        }
    }
    let location = match bundle.records.as_deref().or(records) {
        Some(text) => Location::parse(text),
        None => Location::default_location(),
    }
    .map_err(|e| e.to_string())?;
    let operator = std::env::var("BOTBENCH_OPERATOR").ok();
    let context = RunContext {
        station: Some(bundle.id.clone()),
        operator: operator.clone(),
        bundle_sha256: Some(bundle.sha256.clone()),
        ..RunContext::default()
    };
    let recorder = Recorder::open(&location, context).map_err(|e| e.to_string())?;
    let started = crate::sim::fixture::start_station(&bundle, recorder, operator, ports, false)?;
    Ok(LineStation::started(&bundle, started))
}

impl LineStation {
    /// Whether a slot runs a unit now (the station may be closed only when none does).
    pub fn running(&self) -> bool {
        self.tiles
            .iter()
            .any(|t| t.stopped.is_none() && t.waiting.is_none() && t.port.is_some())
    }
}
