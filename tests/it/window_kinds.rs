//! Issue 14, each value shown as what it is: an enum beside a plot by its names, never as a line
//! of its codes.

use botbench::i18n::Lang;
use botbench::sim::SimOptions;
use botbench::sim::solar_cleanbot::SolarCleanbot;
use botbench::ui::{App, PanelId};
use egui_kittest::kittest::Queryable;

use crate::support::gui::{app, harness, settings, step_until};
use crate::support::serve;

#[test]
fn the_battery_state_is_named_beside_its_plot_and_is_no_line() {
    let b = serve(SolarCleanbot::new(&SimOptions::default()).unwrap());
    let mut saved = settings(b.path(), "solar-cleanbot", PanelId::Telemetry, Lang::En);
    saved.port_mut().margin_ms = Some(100);
    let mut h = harness(saved);
    let voltage = |a: &App| {
        a.state
            .device
            .plots
            .get("battery")
            .is_some_and(|s| s.iter().any(|(name, s)| name == "voltage" && !s.is_empty()))
    };
    step_until(&mut h, "the battery plotted", voltage);
    h.step();
    let series: Vec<String> = app(&h).state.device.plots["battery"]
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
        a.state.device.value(130, "state") == Some(&botbench::profile::Value::Int(1))
    });
    h.step();
    assert!(h.query_by_label("Battery state: Warning (1)").is_some());
    assert!(h.query_by_label("Battery state: OK (0)").is_none());
}
