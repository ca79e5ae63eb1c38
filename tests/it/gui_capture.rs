//! Recording from the window and replaying the capture: the window shows the same values.

use botbench::capture::{self, ReplayDevice};
use botbench::packet::Item;
use botbench::profile::Protocol;
use botbench::protocol::Direction;
use botbench::ui::{Action, PanelId};
use egui_kittest::kittest::Queryable;

use crate::support::gui::{self, H, app, app_mut, step_until};
use crate::support::{Port, serve_with, temp_dir, window_cleaner};
use botbench::sim::Faults;

/// The app on the window cleaner at `path`, with 100 ms for it to start answering.
fn harness(port: &impl Port, panel: PanelId) -> H {
    gui::on_window_cleaner(port, panel, Some(100))
}

#[test]
fn a_capture_recorded_from_the_window_replays_with_the_window_showing_the_same_values() {
    let dir = temp_dir();
    let path = dir.path().join("window.pcapng");
    // In lockstep with the window's link, so that a loaded machine never starves the device; the
    // replay keeps the recorded timing, as `botbench sim replay` does.
    let b = serve_with(window_cleaner(), Faults::default());
    b.sim
        .lock()
        .unwrap()
        .set_param("waterPumpDuration", 4321)
        .unwrap();
    let mut h = harness(&b, PanelId::TUNING);
    // The app reads every value on connecting: the recording starts after that read, and holds
    // the whole of the one asked for.
    gui::read_on_connecting(&mut h);
    app_mut(&mut h).apply(Action::StartCapture(path.clone()));
    let recorded = gui::read_all(&mut h);

    // The monitor shows the recording and its size; Stop there ends it.
    app_mut(&mut h).apply(Action::ShowPanel(PanelId::MONITOR));
    step_until(&mut h, "the file to hold the replies", |a| {
        a.station()
            .recording()
            .is_some_and(|c| c.summary().chunks >= 14)
    });
    h.step();
    assert!(h.query_all_by_label_contains("KiB").next().is_some());
    h.get_by_label("Stop recording").click();
    step_until(&mut h, "recording to stop", |a| {
        a.station().recording().is_none()
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
    let replay = serve_with(
        ReplayDevice::new(&file).expect("replayable"),
        Faults::default(),
    );
    let mut h = harness(&replay, PanelId::TUNING);
    // The recording began after connecting, and still holds the identification: the replay
    // identifies as the device did (issue 25, item 4).
    step_until(&mut h, "the replay to be identified", |a| {
        matches!(&a.station().device.info, Some(Ok(_)))
    });
    let replayed = gui::read_all(&mut h);
    assert_eq!(replayed, recorded);
    assert_eq!(
        replayed[&135].get("waterPumpDuration"),
        recorded[&135].get("waterPumpDuration")
    );

    // And the monitor opens the file offline, decoded with its profile.
    app_mut(&mut h).apply(Action::OpenCapture(path.clone()));
    app_mut(&mut h).apply(Action::ShowPanel(PanelId::MONITOR));
    h.step();
    let offline = app(&h).station().packets.offline.as_ref().expect("opened");
    assert_eq!(offline.profile.id, "window-cleaner");
    // Recording starts and stops while the link runs: a frame cut at either end of a
    // direction's stream shows as junk, truncated, or a false header whose checksum fails once
    // the length it announced has come (so it is reported after frames behind it). Every error
    // lies before the first whole frame or after the last; the frames behind it all decode.
    let frames = capture::frames(&file, Protocol::Msp);
    assert_eq!(offline.entries.len(), frames.len());
    for dir in [Direction::HostToDevice, Direction::DeviceToHost] {
        let items: Vec<&Item> = frames
            .iter()
            .filter(|f| f.direction == dir)
            .map(|f| &f.item)
            .collect();
        let whole: Vec<(u64, u64)> = items
            .iter()
            .filter(|i| i.result.is_ok())
            .map(|i| (i.offset, i.offset + i.len as u64))
            .collect();
        let (Some(&(first, _)), Some(&(_, end))) = (whole.first(), whole.last()) else {
            panic!("no whole frame {dir:?}: {items:?}");
        };
        let bad: Vec<_> = items
            .iter()
            .filter(|i| i.result.is_err() && i.offset >= first && i.offset < end)
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
