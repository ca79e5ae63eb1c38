//! The line station's figures (issue 27): slots run side by side as they do on a line PC, each
//! on its own thread and link, against simulated fixtures on the simulated wire (its bytes
//! timed at the baud rate). Four servo slots provisioning a fresh servo each at once, against
//! one slot alone (target: the whole at most 1.5×); four window-cleaner slots running the
//! shipped self-test at once, each slot's time against one alone (target: within 10 %).

use super::Figure;
use crate::ops::records::{Recorder, RunContext, SqliteStore};
use crate::ops::station::{self, LoadContext, What};
use crate::sim::SimKind;
use std::time::{Duration, Instant};

/// The most a station run may take before the bench gives up on it.
const GIVE_UP: Duration = Duration::from_secs(300);

/// Runs `slots` simulated slots of `kind` with the plan `steps` (RON) at once, one unit each;
/// each slot's seconds from its unit's start to its verdict, and the whole's wall time.
/// Errors: the bundle, a slot that did not pass, or a run past [`GIVE_UP`].
fn run_slots(kind: SimKind, steps: &str, slots: usize) -> Result<(Vec<f64>, f64), String> {
    let dir = tempfile::tempdir().map_err(|e| e.to_string())?;
    let presets = crate::system::presets_dir()
        .or_else(|| Some(std::path::PathBuf::from("presets")))
        .filter(|d| d.is_dir())
        .ok_or("the shipped presets folder is not found (run from the checkout)")?;
    for f in ["window-cleaner-selftest.ron", "servo-provision-plan.ron"] {
        std::fs::copy(presets.join(f), dir.path().join(f)).map_err(|e| format!("{f}: {e}"))?;
    }
    let slot_list: Vec<String> = (1..=slots)
        .map(|i| {
            format!(
                r#"(name: "{i}", fixture: "F{i}", port: Simulated("{}"),
                    profile: "{}", plan: "p")"#,
                kind.name(),
                kind.profile_id()
            )
        })
        .collect();
    let text = format!(
        r#"(version: 1, id: "bench", plans: {{ "p": (start: Auto, steps: [{steps}]) }},
            slots: [{}])"#,
        slot_list.join(",\n")
    );
    let path = dir.path().join("bench-station.ron");
    std::fs::write(&path, text).map_err(|e| e.to_string())?;
    let registry = crate::profile::Registry::builtin().map_err(|e| e.to_string())?;
    let sims: Vec<(&str, &str)> = SimKind::ALL
        .iter()
        .map(|k| (k.name(), k.profile_id()))
        .collect();
    let cx = LoadContext {
        registry: &registry,
        simulated: &sims,
    };
    let bundle = station::load(&path, &cx).map_err(|e| e.to_string())?;
    let store = SqliteStore::open(&dir.path().join("records.sqlite")).map_err(|e| e.to_string())?;
    let recorder = Recorder::with_store(Box::new(store), RunContext::default(), None);
    let context = station::StationContext::new(&bundle, None, recorder);
    let (tx, rx) = crossbeam_channel::unbounded();
    let started = Instant::now();
    let mut handles = Vec::new();
    let ports = crate::link::PortOpener::system();
    for slot in &bundle.slots {
        let h = crate::sim::fixture::start_slot(slot, context.clone(), &ports, tx.clone(), true)?;
        handles.push(h);
    }
    drop(tx);
    let mut unit_start = std::collections::BTreeMap::new();
    let mut times = Vec::new();
    while times.len() < slots {
        let left = GIVE_UP.saturating_sub(started.elapsed());
        let ev = rx
            .recv_timeout(left)
            .map_err(|_| "the station bench did not end".to_string())?;
        match ev.what {
            What::Unit { .. } => {
                unit_start.insert(ev.slot, Instant::now());
            }
            What::Verdict { pass, reason, .. } => {
                if !pass {
                    return Err(format!(
                        "slot {} failed: {}",
                        ev.slot,
                        reason.unwrap_or_default()
                    ));
                }
                let t0 = unit_start.get(&ev.slot).copied().unwrap_or(started);
                times.push(t0.elapsed().as_secs_f64());
            }
            _ => {}
        }
    }
    let whole = started.elapsed().as_secs_f64();
    for h in handles {
        let _ = h.thread.join();
    }
    Ok((times, whole))
}

/// The station's figures: four servo slots against one, four self-tests against one.
pub fn station_figures() -> Result<Vec<Figure>, String> {
    let provision = r#"Provision(plan: "servo-provision-plan.ron")"#;
    let (_, alone) = run_slots(SimKind::ServoBus, provision, 1)?;
    let (_, four) = run_slots(SimKind::ServoBus, provision, 4)?;
    let servo = Figure::new(
        "station-4-servo-slots-provisioning",
        four,
        0.0,
        format!(
            "one slot alone {}; 4 slots at once {:.2}× that",
            super::ms(alone),
            four / alone
        ),
    )
    .judged("target ≤ 1.5× one slot alone".into(), four <= 1.5 * alone);
    let selftest = r#"SelfTest("window-cleaner-selftest.ron")"#;
    let (one, _) = run_slots(SimKind::WindowCleaner, selftest, 1)?;
    let alone = one.first().copied().unwrap_or_default();
    let (each, whole) = run_slots(SimKind::WindowCleaner, selftest, 4)?;
    let worst = each.iter().copied().fold(0.0, f64::max);
    let wc = Figure::new(
        "station-4-window-cleaner-selftests",
        whole,
        0.0,
        format!(
            "one slot alone {}; each of 4 at once {}; worst {:+.1} %",
            super::ms(alone),
            each.iter()
                .map(|t| super::ms(*t))
                .collect::<Vec<_>>()
                .join(", "),
            (worst / alone - 1.0) * 100.0
        ),
    )
    .judged(
        "target each slot within 10 % of one alone".into(),
        worst <= 1.1 * alone,
    );
    Ok(vec![servo, wc])
}
