//! The first launch (issue 18): the window's title names botbench and its version, and on the
//! demo device one line says how to pick a real port, in both languages; on a real port it is
//! gone.

use botbench::i18n::Lang;
use botbench::link::PortOpener;
use botbench::ui::{PanelId, Settings, demo_hint};
use egui_kittest::kittest::Queryable;

use crate::support::gui::{app, app_mut, harness, settings, step_until};
use crate::support::{serve, window_cleaner};

#[test]
fn the_demo_says_how_to_pick_a_real_port_and_the_title_names_the_version() {
    // The first launch: nothing saved, so the built-in demo window cleaner.
    let mut h = harness(Settings::default(), PortOpener::system());
    step_until(&mut h, "the demo device", |a| a.station().connected());
    h.run_steps(2);
    let version = format!("botbench {} — ", env!("CARGO_PKG_VERSION"));
    assert!(app(&h).title().starts_with(&version), "{}", app(&h).title());
    h.get_by_label(demo_hint::text(Lang::En));
    app_mut(&mut h).settings.lang = Lang::Zh;
    h.run_steps(2);
    h.get_by_label(demo_hint::text(Lang::Zh));
    assert!(h.query_by_label(demo_hint::text(Lang::En)).is_none());

    // A real port (a pty here): no hint.
    let b = serve(window_cleaner());
    let mut h = harness(
        settings(b.path(), "window-cleaner", PanelId::TUNING, Lang::En),
        b.ports(),
    );
    step_until(&mut h, "the link", |a| a.station().connected());
    h.run_steps(2);
    assert!(app(&h).title().starts_with(&version), "{}", app(&h).title());
    assert!(h.query_by_label(demo_hint::text(Lang::En)).is_none());
}
