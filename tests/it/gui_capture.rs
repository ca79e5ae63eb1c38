//! Recording from the window and replaying the capture: the window shows the same values.

use botbench::capture::{self, ReplayDevice};
use botbench::i18n::Lang;
use botbench::profile::Value;
use botbench::protocol::Direction;
use botbench::ui::state::Reading;
use botbench::ui::{Action, App, PanelId};
use egui_kittest::kittest::Queryable;
use std::collections::BTreeMap;

use crate::support::gui::{self, H, app, app_mut, settings, step_until};
use crate::support::{serve_plain, temp_dir, window_cleaner};
use botbench::sim::Faults;

fn harness(path: &str, panel: PanelId) -> H {
    let mut saved = settings(path, "window-cleaner", panel, Lang::En);
    saved.port_mut().margin_ms = Some(100);
    gui::harness(saved)
}

/// The tuning parameters (commands 130-136) as the window holds them, once all are read.
fn values(a: &App) -> Option<BTreeMap<u8, BTreeMap<String, Value>>> {
    (130..=136)
        .map(|id| match a.state.device.readings.get(&id) {
            Some(Reading::Values(v, _)) => Some((
                id,
                v.iter().map(|(k, v)| (k.to_string(), v.clone())).collect(),
            )),
            _ => None,
        })
        .collect()
}

fn read_all(h: &mut H) -> BTreeMap<u8, BTreeMap<String, Value>> {
    step_until(h, "the link", |a| a.state.connected());
    h.get_by_label("Read all").click();
    step_until(h, "every parameter read", |a| {
        values(a).is_some() && a.state.job_progress().is_none()
    });
    values(app(h)).expect("read")
}

#[test]
fn a_capture_recorded_from_the_window_replays_with_the_window_showing_the_same_values() {
    let dir = temp_dir();
    let path = dir.path().join("window.pcapng");
    // Plain ptys: the replay keeps the recorded timing, as `botbench sim replay` does.
    let b = serve_plain(window_cleaner(), Faults::default());
    b.sim
        .lock()
        .unwrap()
        .set_param("waterPumpDuration", 4321)
        .unwrap();
    let mut h = harness(b.path(), PanelId::Tuning);
    step_until(&mut h, "the link", |a| a.state.connected());
    app_mut(&mut h).apply(Action::StartCapture(path.clone()));
    let recorded = read_all(&mut h);

    // The monitor shows the recording and its size; Stop there ends it.
    app_mut(&mut h).apply(Action::ShowPanel(PanelId::Monitor));
    step_until(&mut h, "the file to hold the replies", |a| {
        a.state
            .recording()
            .is_some_and(|c| c.summary().chunks >= 14)
    });
    h.step();
    assert!(h.query_all_by_label_contains("KiB").next().is_some());
    h.get_by_label("Stop recording").click();
    step_until(&mut h, "recording to stop", |a| {
        a.state.recording().is_none()
    });
    drop(h);

    // The device changes; the replay answers as it did.
    b.sim
        .lock()
        .unwrap()
        .set_param("waterPumpDuration", 1234)
        .unwrap();
    let file = capture::read_path(&path).expect("reads");
    assert_eq!(file.info.profile, "window-cleaner");
    let replay = serve_plain(
        ReplayDevice::new(&file).expect("replayable"),
        Faults::default(),
    );
    let mut h = harness(replay.path(), PanelId::Tuning);
    let replayed = read_all(&mut h);
    assert_eq!(replayed, recorded);
    assert_eq!(
        replayed[&135].get("waterPumpDuration"),
        recorded[&135].get("waterPumpDuration")
    );

    // And the monitor opens the file offline, decoded with its profile.
    app_mut(&mut h).apply(Action::OpenCapture(path.clone()));
    app_mut(&mut h).apply(Action::ShowPanel(PanelId::Monitor));
    h.step();
    let offline = app(&h).state.packets.offline.as_ref().expect("opened");
    assert_eq!(offline.profile.id, "window-cleaner");
    // Recording starts and stops while the link runs: only a frame cut at either end of a
    // direction's stream may be incomplete.
    for dir in [Direction::HostToDevice, Direction::DeviceToHost] {
        let frames: Vec<_> = offline
            .entries
            .iter()
            .filter(|e| e.direction == dir)
            .collect();
        let bad: Vec<_> = frames
            .iter()
            .enumerate()
            .filter(|(i, e)| e.frame.is_err() && *i != 0 && *i != frames.len() - 1)
            .collect();
        assert!(bad.is_empty(), "{bad:?}");
    }
    assert!(offline.entries.len() >= 14);
    assert!(
        h.query_all_by_label_contains("viewing window.pcapng")
            .next()
            .is_some()
    );
}
