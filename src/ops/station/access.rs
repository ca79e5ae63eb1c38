//! Who reached a station's engineer view, kept in the station's records store beside the units'
//! records: each unlock, each refused password, each lock, and each slot opened in the engineer
//! view and given back. One record per event ([`RunKind::Access`]: the time, the station's id,
//! the bundle's hash, the slot if any, what happened), saved whole or not at all through the
//! station's [`crate::ops::records::Recorder`] (its spool when the line server is away), on a
//! thread of its own so that a slow store never holds the window. `botbench records list`
//! shows them (kind `station-access`); the yield reports leave them out.

use super::runner::StationContext;
use crate::ops::records::record::{Record, RunKind, Verdict};

/// What happened at the engineer's lock.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Access {
    /// The right password: the engineer view is open.
    Unlock,
    /// A wrong password (or none in the bundle): still locked.
    Refused {
        /// Why (`wrong password`).
        why: String,
    },
    /// Locked again (the Lock button).
    Lock,
    /// A slot lent to the engineer view (its runner closed its port and waits).
    SlotOpened {
        /// The slot's name.
        slot: String,
    },
    /// The slot given back to its runner (which opens its port again).
    SlotReturned {
        /// The slot's name.
        slot: String,
    },
}

impl Access {
    /// What the record's plan column says: `engineer unlock`, `engineer password refused`,
    /// `engineer lock`, `engineer view of slot 2`, `slot 2 back from the engineer view`.
    pub fn said(&self) -> String {
        match self {
            Access::Unlock => "engineer unlock".into(),
            Access::Refused { .. } => "engineer password refused".into(),
            Access::Lock => "engineer lock".into(),
            Access::SlotOpened { slot } => format!("engineer view of slot {slot}"),
            Access::SlotReturned { slot } => format!("slot {slot} back from the engineer view"),
        }
    }

    /// The slot concerned, if any.
    pub fn slot(&self) -> Option<&str> {
        match self {
            Access::SlotOpened { slot } | Access::SlotReturned { slot } => Some(slot),
            _ => None,
        }
    }
}

/// The record of `access` at `station` now: kind `station-access`, plan [`Access::said`],
/// profile `station`, the station's id and bundle hash, the slot if any; FAIL with the reason
/// for a refused password, PASS otherwise.
pub fn record(station: &StationContext, access: &Access) -> Record {
    let mut r = Record::start(RunKind::Access, &access.said(), None, "station");
    r.context.station = Some(station.id.clone());
    r.context.slot = access.slot().map(str::to_string);
    r.context.operator.clone_from(&station.operator);
    r.context.bundle_sha256 = Some(station.bundle_sha256.clone());
    r.plan_sha256 = Some(station.bundle_sha256.clone());
    if let Access::Refused { why } = access {
        r.verdict = Verdict::Fail;
        r.failed_step = Some("engineer unlock".into());
        r.reason = Some(why.clone());
    }
    r
}

/// Keeps the record of `access` at `station`, on a thread of its own (`station-access`): the
/// window goes on at once. Where it went is logged when it did not reach its store. Errors:
/// none returned; a thread that cannot start is logged (the event is then not recorded).
pub fn keep(station: &StationContext, access: &Access) {
    let mut record = record(station, access);
    let recorder = station.recorder.clone();
    let id = station.id.clone();
    let said = access.said();
    log::warn!("station {id}: {said}");
    let (id_then, said_then) = (id.clone(), said.clone());
    let spawned = std::thread::Builder::new()
        .name("station-access".into())
        .spawn(move || {
            let (id, said) = (id_then, said_then);
            let mut recorder = recorder.lock().unwrap_or_else(|e| e.into_inner());
            let kept = recorder.save(&mut record);
            if !kept.stored() {
                log::warn!("station {id}: {said}: {}", kept.line());
            }
        });
    if let Err(e) = spawned {
        log::error!("station {id}: {said} not recorded: cannot start a thread: {e}");
    }
}
