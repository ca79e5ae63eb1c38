//! The real app, driven through egui_kittest against the simulated window cleaner on a pty.

use botbench::i18n::Lang;
use botbench::profile::Value;
use botbench::sim::Faults;
use botbench::ui::presets::PresetsPanel;
use botbench::ui::station::Reading;
use botbench::ui::tuning::TuningPanel;
use botbench::ui::{App, PanelId};
use eframe::egui::accesskit::Role;
use egui_kittest::kittest::{By, Queryable};
use std::time::Duration;

use crate::support::gui::{
    self, H, app, app_mut, edit_value, idle, settings, step_until, tuning_values,
};
use crate::support::{Port, serve_with, served_window_cleaner as bench, temp_dir, window_cleaner};

/// The app on the window cleaner at `path`, with the protocol's own answer margin.
fn harness(port: &impl Port, panel: PanelId) -> H {
    gui::on_window_cleaner(port, panel, None)
}

fn all_read(a: &App) -> bool {
    tuning_values(a, None).is_some()
}

#[test]
fn read_all_brings_every_parameter_from_the_device() {
    let b = bench();
    b.sim
        .lock()
        .unwrap()
        .set_param("waterPumpDuration", 4321)
        .unwrap();
    let mut h = harness(&b, PanelId::TUNING);
    gui::read_all(&mut h);
    let want = b.sim().param("waterPumpDuration").unwrap();
    let got = match app(&h).station().device.readings.get(&135) {
        Some(Reading::Values(v, _)) => v.get("waterPumpDuration").cloned(),
        _ => None,
    };
    assert_eq!(got, Some(Value::Int(want)));
    h.step();
    assert!(
        h.query_all_by_label("not read yet").next().is_none(),
        "every field now has a device value"
    );
}

#[test]
fn an_out_of_range_edit_is_refused_for_writing() {
    let b = bench();
    b.sim().set_param("pwmValue", 33).unwrap();
    let mut h = harness(&b, PanelId::TUNING);
    gui::read_all(&mut h);
    h.step();
    edit_value(&mut h, "33", "101");
    let a = app(&h);
    assert_eq!(
        a.panel::<TuningPanel>()
            .edits
            .values()
            .cloned()
            .collect::<Vec<_>>(),
        vec!["101".to_string()]
    );
    assert!(
        a.panel::<TuningPanel>().pending(a.station()).is_err(),
        "an invalid edit blocks writing"
    );
    assert!(
        h.query_all_by_label_contains("0 – 100 %").next().is_some(),
        "the allowed range is shown"
    );
    assert!(h.query_all_by_label_contains("invalid").next().is_some());
    // The button is there but disabled: clicking it writes nothing.
    h.get_by_label_contains("Write changes").click();
    h.run_steps(5);
    assert_eq!(b.sim().param("pwmValue"), Some(33));
}

#[test]
fn a_valid_edit_is_written_and_the_simulator_then_holds_it() {
    let b = bench();
    b.sim().set_param("pwmValue", 33).unwrap();
    let mut h = harness(&b, PanelId::TUNING);
    gui::read_all(&mut h);
    h.step();
    edit_value(&mut h, "33", "64");
    h.get_by_label_contains("Write changes (1)").click();
    h.run_steps(3);
    // The diff is shown first.
    assert!(h.query_by_label("Write these changes?").is_some());
    h.get_by_label("Write").click();
    step_until(&mut h, "the write to be verified", |a| {
        a.station().device.marks.get(&(130, "pwmValue".to_string()))
            == Some(&botbench::ui::station::Mark::Verified)
    });
    assert_eq!(b.sim().param("pwmValue"), Some(64));
    h.step();
    assert!(h.query_all_by_label_contains("verified").next().is_some());
}

/// A named value (the water pump's Off / On) is chosen by its name, in the window's language,
/// not typed as its ident; the choice is written and verified like any edit.
#[test]
fn a_named_value_is_chosen_by_its_name_and_written() {
    let b = bench();
    b.sim().set_param("waterPump", 1).unwrap();
    let mut h = harness(&b, PanelId::TUNING);
    gui::read_all(&mut h);
    h.step();
    assert!(
        h.query(By::new().role(Role::TextInput).label_contains("Water pump"))
            .is_none(),
        "no box to type an ident into"
    );
    h.get(By::new().role(Role::ComboBox).label_contains("Water pump"))
        .click();
    h.run_steps(2);
    h.get_by_label("Off (off)").click();
    h.run_steps(2);
    assert_eq!(
        app(&h)
            .panel::<TuningPanel>()
            .edits
            .get(&(135, "waterPump".to_string()))
            .map(String::as_str),
        Some("off")
    );
    h.get_by_label_contains("Write changes (1)").click();
    h.run_steps(3);
    h.get_by_label("Write").click();
    step_until(&mut h, "the write to be verified", |a| {
        a.station()
            .device
            .marks
            .get(&(135, "waterPump".to_string()))
            == Some(&botbench::ui::station::Mark::Verified)
    });
    assert_eq!(b.sim().param("waterPump"), Some(0));
}

#[test]
fn the_plots_receive_points() {
    let b = bench();
    let mut h = harness(&b, PanelId::TELEMETRY);
    step_until(&mut h, "attitude and battery points", |a| {
        let n = |id: &str, f: &str| {
            a.station()
                .device
                .plots
                .get(id)
                .and_then(|s| s.get(f))
                .map_or(0, |s| s.len())
        };
        n("attitude", "eulerX") > 20 && n("battery", "batteryVoltage") > 20
    });
}

#[test]
fn a_preset_saves_and_applies_in_a_round_trip() {
    let b = bench();
    let dir = temp_dir();
    let path = dir.path().join("preset.ron");
    let mut h = harness(&b, PanelId::PRESETS);
    step_until(&mut h, "the first read", |a| all_read(a) && idle(a));
    app_mut(&mut h).panel_mut::<PresetsPanel>().path = path.display().to_string();
    h.step();
    h.get_by_label("Save device to file").click();
    step_until(&mut h, "the preset saved", |_| path.exists());
    step_until(&mut h, "the job to end", |a| {
        a.station().job_progress().is_none()
    });
    let saved_pwm = b.sim().param("pwmValue").unwrap();
    let saved_target = b.sim().param("defaultTarget").unwrap();
    // The device drifts from the preset.
    b.sim
        .lock()
        .unwrap()
        .set_param("pwmValue", (saved_pwm + 7) % 100)
        .unwrap();
    b.sim
        .lock()
        .unwrap()
        .set_param("defaultTarget", saved_target - 5)
        .unwrap();
    h.get_by_label("Open").click();
    h.run_steps(2);
    h.get_by_label("Compare with device").click();
    step_until(&mut h, "the device read", |a| {
        a.station().job_progress().is_none()
            && matches!(
                a.station().device.readings.get(&130),
                Some(Reading::Values(..))
            )
    });
    h.step();
    assert!(
        h.query_by_label_contains("Apply (2)").is_some(),
        "two fields differ"
    );
    h.get_by_label_contains("Apply (").click();
    h.run_steps(3);
    // Asked first, as Tuning asks: nothing is written before the yes.
    assert!(h.query_by_label("Apply this preset?").is_some());
    assert_ne!(b.sim.lock().unwrap().param("pwmValue"), Some(saved_pwm));
    h.get_by_label("Write").click();
    step_until(&mut h, "the preset applied", |a| {
        a.station().job_progress().is_none()
            && a.station()
                .device
                .marks
                .contains_key(&(130, "pwmValue".to_string()))
    });
    assert_eq!(b.sim().param("pwmValue"), Some(saved_pwm));
    assert_eq!(b.sim().param("defaultTarget"), Some(saved_target));
}

#[test]
fn a_malformed_preset_is_shown_with_its_line_and_column() {
    let b = bench();
    let dir = temp_dir();
    let path = dir.path().join("bad.ron");
    std::fs::write(&path, "(\n  version: 1,\n  profile: \"window-cleaner\",\n  values: {\n    \"MSP_SET_PWMVALUE\": { \"pwmValue\": \"101\" },\n  },\n)\n").unwrap();
    let mut h = harness(&b, PanelId::PRESETS);
    step_until(&mut h, "the link", |a| a.station().connected());
    app_mut(&mut h).panel_mut::<PresetsPanel>().path = path.display().to_string();
    h.step();
    h.get_by_label("Open").click();
    h.run_steps(2);
    let err = app(&h)
        .panel::<PresetsPanel>()
        .error
        .clone()
        .expect("refused")
        .to_string();
    assert!(err.contains(":5:") && err.contains("out of range"), "{err}");
    assert!(app(&h).panel::<PresetsPanel>().loaded.is_none());
}

#[test]
fn every_panel_renders_in_english_and_chinese() {
    // A glyph missing from the bundled fonts panics while drawing, so drawing every panel in both
    // languages checks the font as well as the layout.
    let b = bench();
    let mut h = harness(&b, PanelId::TUNING);
    step_until(&mut h, "the link", |a| a.station().connected());
    let panels = app(&h).panels();
    assert!(panels.len() >= 5, "{panels:?}");
    for lang in [Lang::En, Lang::Zh] {
        for panel in &panels {
            let a = app_mut(&mut h);
            a.settings.lang = lang;
            a.settings.panel = *panel;
            h.run_steps(3);
        }
    }
    h.get_by_label("English").click();
    h.run_steps(2);
    assert_eq!(app(&h).settings.lang, Lang::En);
}

#[test]
fn nothing_is_shown_before_a_reply_and_a_failed_read_says_so_in_place() {
    let silent = Faults {
        silent: true,
        ..Faults::default()
    };
    let b = serve_with(window_cleaner(), silent);
    let mut h = harness(&b, PanelId::TUNING);
    step_until(&mut h, "the reads to fail", |a| {
        matches!(
            a.station().device.readings.get(&130),
            Some(Reading::Failed(_))
        )
    });
    h.step();
    assert!(h.query_all_by_label("not read yet").next().is_some());
    assert!(
        h.query_all_by_label_contains("read failed: no answer")
            .next()
            .is_some()
    );
    assert!(
        h.query_all_by_label("85").next().is_none(),
        "no default stands in for a value"
    );
}

#[test]
fn the_parameters_are_read_as_soon_as_the_link_is_up() {
    let b = bench();
    let mut h = harness(&b, PanelId::TUNING);
    step_until(&mut h, "every parameter read without a click", all_read);
}

#[test]
fn a_slow_device_is_read_with_the_automatic_margin_it_learns() {
    let slow = Faults {
        extra_latency: Duration::from_millis(150),
        ..Faults::default()
    };
    let served = serve_with(window_cleaner(), slow);
    // Far beyond the protocol's own 20 ms: the automatic margin learns the device's answer
    // latency from its late answers, and every parameter is read without a margin chosen by
    // hand.
    let saved = settings(served.path(), "window-cleaner", PanelId::TUNING, Lang::En);
    assert_eq!(
        saved.port_of("window-cleaner").margin_ms,
        None,
        "the automatic margin"
    );
    let mut h = crate::support::gui::harness(saved, served.ports());
    step_until(&mut h, "every parameter read", all_read);
}
