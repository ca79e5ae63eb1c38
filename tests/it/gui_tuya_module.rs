//! The window's Tuya console against MCUs as they are in the field (issue 26, item 9): a value
//! the profile does not allow is shown as a misfit, data points the profile lacks in their own
//! section, those still missing since the last query, commands the module does not know; the
//! conformance grade as a tab with its table, its verdict and Save report.

use botbench::protocol::tuya::dp::DpValue;
use botbench::sim::Faults;
use botbench::sim::tuya_mcu::{RawValue, TuyaConfig, TuyaMcu};
use botbench::ui::tuya_console::TuyaConsolePanel;
use egui_kittest::kittest::Queryable;
use std::collections::BTreeMap;

use crate::gui_tuya::{handshake, harness, tab};
use crate::support::gui::{H, app, has_label, settings, step_until, type_into};
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

fn console(b: &Served<TuyaMcu>) -> H {
    let mut h = harness(b, "tuya-vacuum");
    handshake(&mut h);
    h
}

#[test]
fn misfits_unknown_and_missing_data_points_and_unknown_commands_are_shown() {
    let b = mcu(TuyaConfig {
        report_out_of_range: BTreeMap::from([(6, RawValue::Int(150))]),
        report_unknown_dp: vec![(101, DpValue::Value(50))],
        never_report: vec![19],
        ..TuyaConfig::default()
    });
    let mut h = console(&b);
    tab(&mut h, "Data points");
    step_until(&mut h, "the reports of the handshake's query", |a| {
        let t = &a.station().device.tuya;
        t.unknown_dps.contains_key(&101) && t.misfits.contains_key(&6)
    });
    h.run_steps(2);
    assert!(has_label(
        &h,
        "150 % is out of range: the profile allows 0 to 100 %"
    ));
    assert!(has_label(&h, "Data points not in the profile"));
    assert!(has_label(&h, "value 50"));
    assert!(has_label(&h, "still missing: 19 Map parameters"));
    // A command the module does not know: said with its bytes, not answered.
    b.sim().send_frame(0x99, vec![1, 2, 3]);
    step_until(&mut h, "the unknown command", |a| {
        !a.station().device.tuya.unknown_commands.is_empty()
    });
    tab(&mut h, "MCU requests");
    assert!(has_label(&h, "Unknown commands, not answered"));
    assert!(has_label(&h, "command 0x99"));
    assert!(has_label(&h, "01 02 03"));
}

/// Runs the grade from the Conformance tab to its end.
fn grade(h: &mut H) {
    tab(h, "Conformance");
    h.get_by_label("Run conformance").click();
    step_until(h, "the grade to end", |a| {
        a.panel::<TuyaConsolePanel>().conform.result.is_some()
    });
    h.run_steps(2);
}

#[test]
fn the_conformance_tab_grades_the_mcu_and_saves_its_report() {
    let b = mcu(TuyaConfig::default());
    // Its own records file: the grade is recorded as `tuya conform` records it.
    let dir = temp_dir();
    let records = dir.path().join("records.sqlite");
    let mut saved = settings(
        b.path(),
        "tuya-vacuum",
        botbench::ui::PanelId::TUYA_CONSOLE,
        botbench::i18n::Lang::En,
    );
    saved.port_mut().baud = Some(115_200);
    saved.files.insert(
        botbench::ui::settings::FileKind::Records,
        records.display().to_string(),
    );
    let mut h = crate::support::gui::harness(saved, b.ports());
    handshake(&mut h);
    grade(&mut h);
    let grade = app(&h)
        .panel::<TuyaConsolePanel>()
        .conform
        .result
        .clone()
        .unwrap()
        .expect("graded");
    assert!(grade.pass(), "{:#?}", grade.failed());
    assert!(has_label(&h, "CONFORMS"));
    assert!(has_label(&h, "heartbeat"));
    assert!(has_label(&h, "read_only_refused"));
    // One record, kept before the verdict was shown: kind tuya-conform, PASS, a step per check
    // graded, the MCU's product id as the unit's hardware.
    let db = rusqlite::Connection::open(&records).unwrap();
    let (kind, verdict, steps, hardware): (String, String, i64, Option<String>) = db
        .query_row("SELECT kind, verdict, steps, hardware FROM runs", [], |r| {
            Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?))
        })
        .unwrap();
    assert_eq!((kind.as_str(), verdict.as_str()), ("tuya-conform", "PASS"));
    let graded = grade
        .checks
        .iter()
        .filter(|c| c.grade != botbench::ops::tuya::conform::Grade::Skip)
        .count();
    assert_eq!(steps as usize, graded);
    assert_eq!(hardware.as_deref(), grade.pid.as_deref());
    let file = dir.path().join("grade.json");
    type_into(&mut h, "Report file", &file.display().to_string());
    h.get_by_label("Save report").click();
    h.run_steps(2);
    let saved: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&file).expect("saved")).unwrap();
    assert_eq!(
        saved["checks"].as_array().unwrap().len(),
        grade.checks.len()
    );
    assert!(has_label(&h, "Saved to"));
}

#[test]
fn a_firmware_that_answers_a_bad_checksum_does_not_conform() {
    let b = mcu(TuyaConfig {
        ignore_checksum: true,
        ..TuyaConfig::default()
    });
    let mut h = console(&b);
    grade(&mut h);
    assert!(has_label(&h, "DOES NOT CONFORM: bad_checksum"));
    // The evidence: the corrupted heartbeat and the MCU's answer to it.
    assert!(has_label(
        &h,
        "55 aa 00 00 00 00 00 → 55 aa 03 00 00 01 01 04"
    ));
}
