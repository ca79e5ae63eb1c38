//! Issue 14, each value shown as what it is: an enum beside a plot by its names, never as a line
//! of its codes; a logged frame decoded with the profile it came under, after the device changed.

use botbench::i18n::Lang;
use botbench::i18n::Text;
use botbench::sim::SimOptions;
use botbench::sim::solar_cleanbot::SolarCleanbot;
use botbench::ui::monitor::MonitorPanel;
use botbench::ui::{Action, App, Job, PanelId, Target};
use egui_kittest::kittest::Queryable;

use crate::support::gui::{H, app, app_mut, harness, settings, step_until};
use crate::support::{serve, window_cleaner};

#[test]
fn the_battery_state_is_named_beside_its_plot_and_is_no_line() {
    let b = serve(SolarCleanbot::new(&SimOptions::default()).unwrap());
    let mut saved = settings(b.path(), "solar-cleanbot", PanelId::TELEMETRY, Lang::En);
    saved.port_mut().margin_ms = Some(100);
    let mut h = harness(saved, b.ports());
    let voltage = |a: &App| {
        a.station()
            .device
            .plots
            .get("battery")
            .is_some_and(|s| s.iter().any(|(name, s)| name == "voltage" && !s.is_empty()))
    };
    step_until(&mut h, "the battery plotted", voltage);
    h.step();
    let series: Vec<String> = app(&h).station().device.plots["battery"]
        .iter()
        .map(|(name, _)| name.to_string())
        .collect();
    assert_eq!(series, ["voltage"], "the state is no plotted series");
    assert!(
        h.query_by_label("Battery state: OK (0)").is_some(),
        "the state by its name beside the plot"
    );
    // The state follows the battery: a low one names its new state.
    b.sim().set_battery(21.5);
    step_until(&mut h, "the warning read", |a| {
        a.station().device.value(130, "state") == Some(&botbench::profile::Value::Int(1))
    });
    h.step();
    assert!(h.query_by_label("Battery state: Warning (1)").is_some());
    assert!(h.query_by_label("Battery state: OK (0)").is_none());
}

/// The log's frames of `profile`.
fn logged(a: &App, profile: &str) -> usize {
    a.station()
        .packets
        .entries
        .iter()
        .filter(|l| l.profile.id == profile)
        .count()
}

#[test]
fn frames_logged_before_a_device_change_keep_the_profile_they_came_under() {
    let b = serve(window_cleaner());
    let mut saved = settings(b.path(), "window-cleaner", PanelId::MONITOR, Lang::En);
    saved.port_mut().margin_ms = Some(100);
    let mut h = harness(saved, b.ports());
    let attitude = |a: &App| {
        a.station().packets.entries.iter().any(|l| {
            l.frame().is_some_and(|e| {
                e.frame
                    .as_ref()
                    .is_ok_and(|p| p.command == 108 && l.profile.id == "window-cleaner")
            })
        })
    };
    step_until(&mut h, "an MSP_ATTITUDE frame", attitude);
    // To the servo bench: one ping goes out on it.
    app_mut(&mut h).apply(Action::Connect {
        target: Target::Demo("servo-bus".into()),
        profile: "servo".into(),
        port: botbench::ui::settings::PortSettings {
            baud: Some(115_200),
            ..Default::default()
        },
    });
    step_until(&mut h, "the servo link", |a| a.station().connected());
    app_mut(&mut h).apply(Action::StartJob(Job::new(
        Text::new("ping", "ping"),
        |client, _, _| {
            botbench::ops::servo::ping(client, 1, 1)
                .map(|p| {
                    let said = format!("{p:?}");
                    Text::new(said.clone(), said)
                })
                .map_err(Into::into)
        },
    )));
    step_until(&mut h, "a servo frame", |a| logged(a, "servo") > 0);
    let old = logged(app(&h), "window-cleaner");
    assert!(old > 0, "the window cleaner's frames are kept");

    // The old frames still read as the window cleaner's commands, marked with its profile.
    let rows = filtered(&mut h, "MSP_ATTITUDE");
    assert!(
        !rows.is_empty(),
        "the old frames are found by their MSP names"
    );
    assert!(
        rows.iter()
            .all(|r| r.starts_with("[window-cleaner] ") && r.contains("MSP_ATTITUDE")),
        "{rows:?}"
    );
    // The servo's own frames, by the servo's names, unmarked.
    let rows = filtered(&mut h, "PING");
    assert!(
        rows.iter()
            .any(|r| r.contains("PING") && !r.starts_with('[')),
        "{rows:?}"
    );
}

/// The monitor's rows with `filter` typed in its box.
fn filtered(h: &mut H, filter: &str) -> Vec<String> {
    app_mut(h).panel_mut::<MonitorPanel>().filter = filter.into();
    h.run_steps(2);
    // Each row holds its frame's time: hh:mm:ss.mmm.
    h.query_all_by_label_contains(":")
        .filter_map(|n| n.value())
        .filter(|v| v.contains(" >> ") || v.contains(" << "))
        .collect()
}
