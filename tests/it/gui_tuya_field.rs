//! The Tuya console against MCUs as they behave in the field, and the built-in demo MCU: the
//! real app through egui_kittest, the MCUs on pseudo-terminals (or in process, for the demo).

use botbench::link::{LinkState, PortOpener};
use botbench::profile::Value;
use botbench::sim::Faults;
use botbench::sim::tuya_mcu::{TuyaConfig, TuyaMcu, WireForm};
use botbench::ui::tuya_console::TuyaConsolePanel;
use botbench::ui::{PanelId, Settings, Target, launch_settings};
use eframe::egui::accesskit::Role;
use egui_kittest::kittest::Queryable;
use std::collections::BTreeMap;

use crate::gui_tuya::{handshake, harness, reported, tab};
use crate::support::gui::{app, app_mut, has_label, step_until};
use crate::support::{Served, serve_with, temp_dir};

fn mcu(cfg: TuyaConfig) -> Served<TuyaMcu> {
    serve_with(
        TuyaMcu::new(TuyaConfig {
            baud: Some(115_200),
            ..cfg
        }),
        Faults::default(),
    )
}

#[test]
fn the_demo_mcu_runs_at_the_profiles_rate_and_sends_its_requests_when_asked() {
    let saved = launch_settings(
        Settings::default(),
        Some(Target::Demo("tuya-vacuum".into())),
        None,
        Some("tuya-vacuum".into()),
        Some(PanelId::TUYA_CONSOLE),
    );
    assert_eq!(
        saved.port_of("tuya-vacuum").baud,
        Some(9600),
        "the profile's rate"
    );
    let mut h = crate::support::gui::harness(saved, PortOpener::system());
    handshake(&mut h);
    assert!(
        matches!(
            app(&h).station().link.state,
            Some(LinkState::Connected { baud: 9600, .. })
        ),
        "{:?}",
        app(&h).station().link.state
    );
    tab(&mut h, "MCU requests");
    for button in [
        "Ask the local time (0x1c)",
        "Ask to reset the Wi-Fi (0x04)",
        "Ask the module's MAC (0x2d)",
    ] {
        h.get_by_label(button).click();
        h.run_steps(1);
    }
    step_until(&mut h, "three requests answered", |a| {
        a.station().device.tuya.requests.len() == 3
    });
    h.run_steps(2);
    assert!(has_label(&h, "The MCU asked to reset the Wi-Fi, times: 1"));
    assert!(h.query_by_label("02:b0:7b:00:00:01").is_some());
}

#[test]
fn the_console_shows_the_mcus_frame_version_and_data_points_that_do_not_fit_raw() {
    let b = mcu(TuyaConfig {
        frame_version: 0,
        misreport: BTreeMap::from([(3, WireForm { ty: 2, len: 4 })]),
        ..TuyaConfig::default()
    });
    let mut h = harness(&b, "tuya-vacuum");
    handshake(&mut h);
    assert!(has_label(
        &h,
        "0x00 (the protocol document says 0x03; accepted)"
    ));
    tab(&mut h, "Data points");
    assert!(
        has_label(
            &h,
            "raw 00 00 00 00: type value on the wire, the profile says enum"
        ),
        "the mode, raw with the mismatch"
    );
    assert_eq!(reported(app(&h), 3), None, "no value is made up for it");
    assert_eq!(reported(app(&h), 1), Some(Value::Int(1)), "the others fit");
}

#[test]
fn after_a_command_the_console_shows_what_the_mcu_holds_though_the_report_of_a_change_was_lost() {
    // Power off resets the mode; the report of that change is lost.
    let b = mcu(TuyaConfig {
        rules_override_command: true,
        lose_rule_reports: true,
        ..TuyaConfig::default()
    });
    let mut h = harness(&b, "tuya-vacuum");
    handshake(&mut h);
    tab(&mut h, "Data points");
    h.get_by(|n| n.role() == Role::ComboBox && n.label().as_deref() == Some("3 Work mode"))
        .click();
    h.run_steps(2);
    h.get_by_label("Right zigzag").click();
    step_until(&mut h, "the mode read back", |a| {
        format!("{:?}", a.panel::<TuyaConsolePanel>().dps.marks.get(&3)) == "Some(Confirmed)"
    });
    assert_eq!(reported(app(&h), 3), Some(Value::Int(8)));
    h.get_by(|n| n.role() == Role::CheckBox && n.label().as_deref() == Some("1 Power"))
        .click();
    step_until(&mut h, "the power read back", |a| {
        a.panel::<TuyaConsolePanel>().dps.pending.is_empty()
            && a.panel::<TuyaConsolePanel>().dps.marks.contains_key(&1)
    });
    assert_eq!(
        format!(
            "{:?}",
            app(&h).panel::<TuyaConsolePanel>().dps.marks.get(&1)
        ),
        "Some(Confirmed)"
    );
    // The read-back brought the mode the MCU holds, whose own report was lost.
    assert_eq!(reported(app(&h), 3), Some(Value::Int(0)));
    assert_eq!(
        format!("{:?}", b.sim.lock().unwrap().dp(3)),
        "Some(Enum(0))"
    );
}

#[test]
fn an_image_over_the_profiles_maximum_is_refused_and_one_that_fits_shows_its_expected_time() {
    let tmp = temp_dir();
    let dir = tmp.path();
    let big = crate::tuya_field::twenty_mb_image(dir);
    let fw = dir.join("fw.bin");
    std::fs::write(&fw, vec![0xa5; 65_536]).unwrap();
    let b = mcu(TuyaConfig::default());
    let mut h = harness(&b, "tuya-vacuum");
    handshake(&mut h);
    tab(&mut h, "Firmware update");
    app_mut(&mut h).panel_mut::<TuyaConsolePanel>().ota.path = big.display().to_string();
    h.step();
    h.get_by_label("Start update").click();
    h.run_steps(2);
    assert!(has_label(
        &h,
        "20000000 bytes is over the largest image the profile allows (524288 bytes)"
    ));
    assert!(h.query_by_label("Update the MCU firmware?").is_none());
    app_mut(&mut h).panel_mut::<TuyaConsolePanel>().ota.path = fw.display().to_string();
    h.step();
    h.get_by_label("Start update").click();
    h.run_steps(2);
    assert!(h.query_by_label("Update the MCU firmware?").is_some());
    // 64 KiB at 115200 baud in 256-byte packets: 70181 bytes, 6.1 s on the wire.
    assert!(
        has_label(&h, "Expected transfer time: 6 s at 115200 baud"),
        "the time at the port's rate"
    );
    h.get_by_label("Do not update").click();
    h.run_steps(2);
    assert!(app(&h).station().job.is_none(), "nothing started");
}
