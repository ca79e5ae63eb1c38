//! Choosing files (issue 14 item 9): every file choice is a typed path with a Browse… beside it;
//! a Browse that cannot open a dialog says so; the paths used come back on the next start.
//! The servo preset and provisioning rows, the Tuya firmware row and the tuning presets are
//! checked in their panels' tests; here the packet monitor's capture row and the start-up.

use botbench::i18n::Lang;
use botbench::link::PortOpener;
use botbench::ui::files::Dialogs;
use botbench::ui::monitor::MonitorPanel;
use botbench::ui::selftest::SelfTestPanel;
use botbench::ui::servo_bench::ServoBenchPanel;
use botbench::ui::settings::FileKind;
use botbench::ui::tuya_console::TuyaConsolePanel;
use botbench::ui::{App, PanelId, Settings, Target};
use egui_kittest::kittest::Queryable;

use crate::support::gui::{H, app, app_mut, harness_with, step_until, type_into};
use crate::support::temp_dir;

/// The app on the built-in simulated window cleaner (no port), on `panel`, with `files`
/// remembered and no file dialog on the system.
fn demo(panel: PanelId, files: &[(FileKind, &str)]) -> H {
    let mut saved = Settings {
        target: Target::Demo("window-cleaner".into()),
        panel,
        lang: Lang::En,
        ..Settings::default()
    };
    for (kind, path) in files {
        saved.files.insert(*kind, path.to_string());
    }
    harness_with(saved, PortOpener::system(), |a: &mut App| {
        a.station_mut().dialogs = Dialogs::Missing("no file dialog here (test)".into());
    })
}

fn notice(h: &H) -> String {
    app(h)
        .station()
        .notice
        .as_ref()
        .map_or(String::new(), |n| n.text.clone())
}

#[test]
fn a_capture_is_recorded_to_and_opened_from_a_typed_path_and_browse_says_it_has_no_dialog() {
    let dir = temp_dir();
    let path = dir.path().join("unit-1.pcapng");
    let path_text = path.display().to_string();
    let mut h = demo(PanelId::MONITOR, &[]);
    step_until(&mut h, "the link", |a| a.station().connected());
    h.step();

    // The capture row's Browse comes first.
    h.query_all_by_label("Browse…").next().unwrap().click();
    h.step();
    assert_eq!(notice(&h), "no file dialog here (test)");

    type_into(&mut h, "Capture", &path_text);
    h.get_by_label("Record").click();
    step_until(&mut h, "recording", |a| a.station().recording().is_some());
    assert_eq!(
        app(&h).settings.file(FileKind::Capture),
        Some(path_text.as_str())
    );
    h.step();
    h.get_by_label("Stop recording").click();
    step_until(&mut h, "recording to stop", |a| {
        a.station().recording().is_none()
    });
    let size = std::fs::metadata(&path).unwrap().len();
    assert!(size > 0);

    // A recording replaces no file.
    h.step();
    h.get_by_label("Record").click();
    h.step();
    assert!(app(&h).station().recording().is_none());
    assert!(notice(&h).contains("exists"), "{}", notice(&h));
    assert_eq!(std::fs::metadata(&path).unwrap().len(), size);

    h.get_by_label("Open capture").click();
    h.step();
    let offline = app(&h).station().packets.offline.as_ref().expect("opened");
    assert_eq!(offline.name, "unit-1.pcapng");
}

#[test]
fn the_paths_used_come_back_in_their_boxes_and_the_shipped_plans_are_found() {
    let files = [
        (FileKind::ServoPreset, "/bench/servo-params.ron"),
        (FileKind::ProvisionLog, "/bench/provision.csv"),
        (FileKind::Firmware, "/bench/mcu-1.2.bin"),
        (FileKind::Capture, "/bench/unit.pcapng"),
        (FileKind::SelfTestLog, "/bench/selftest.jsonl"),
        (FileKind::Packets, "/bench/packets.txt"),
    ];
    let mut h = demo(PanelId::MONITOR, &files);
    h.step();
    let a = app_mut(&mut h);
    assert_eq!(
        [
            a.panel::<ServoBenchPanel>().params.preset_path.as_str(),
            a.panel::<ServoBenchPanel>().production.log_path.as_str(),
            a.panel::<TuyaConsolePanel>().ota.path.as_str(),
            a.panel::<MonitorPanel>().capture_path.as_str(),
            a.panel::<SelfTestPanel>().log_path.as_str(),
            a.panel::<MonitorPanel>().save_path.as_str(),
        ],
        files.map(|(_, p)| p)
    );
    // No plan used yet: the shipped ones, wherever the binary runs.
    for (path, name) in [
        (
            &a.panel::<SelfTestPanel>().path,
            "window-cleaner-selftest.ron",
        ),
        (
            &a.panel::<ServoBenchPanel>().production.plan_path,
            "servo-provision-plan.ron",
        ),
    ] {
        assert!(path.ends_with(name), "{path}");
        assert!(std::path::Path::new(path).is_file(), "{path}");
    }
}
