//! The servo bench panel of the app against a simulated servo bus served in lockstep: the bus,
//! the app on the panel, and the steps a technician takes there more than once.

use super::gui::{self, H, idle, settings, step_until, type_into};
use super::{Served, serve};
use botbench::i18n::Lang;
use botbench::sim::servo_bus::{ServoBus, SimServo};
use botbench::ui::PanelId;
use botbench::ui::servo_bench::ServoBenchPanel;
use egui_kittest::kittest::Queryable;

/// The simulated bus on its pty, in lockstep with the app's link.
pub type Bench = Served<ServoBus>;

/// A bus of `servos`, served.
pub fn bench(servos: Vec<SimServo>) -> Bench {
    serve(ServoBus::new(servos))
}

/// The app on the servo bench panel, connected with the servo protocol's own answer margin.
pub fn harness(b: &Bench, lang: Lang) -> H {
    let mut h = gui::harness(
        settings(b.path(), "servo", PanelId::SERVO_BENCH, lang),
        b.ports(),
    );
    step_until(&mut h, "the link", |a| a.station().connected());
    h
}

/// Selects `servo` in the scan table and asks for the baud option labelled `option`.
pub fn set_baud(h: &mut H, servo: &str, option: &str) {
    h.get_by_label(servo).click();
    h.step();
    h.get_by_label("ID & baud rate").click();
    h.step();
    h.get_by_label("New baud rate").click();
    h.run_steps(2);
    h.get_by_label(option).click();
    h.step();
    h.get_by_label("Set baud rate").click();
    h.step();
}

/// Scans ids `first`-`last` at the checked rates and waits for the end.
pub fn scan(h: &mut H, first: &str, last: &str) {
    type_into(h, "First id", first);
    type_into(h, "Last id", last);
    h.get_by_label("Scan").click();
    h.step();
    step_until(h, "the scan", |a| {
        idle(a) && a.panel::<ServoBenchPanel>().scan.outcome.is_some()
    });
    h.step();
}
