//! Hover hints (issue 14): what the window says of a widget when the pointer rests on it. A
//! field's wire name, an input's range, why Send is greyed out, what STOP sends, what setting the
//! USB adapter's latency timer does, why Browse cannot open a dialog.

use botbench::i18n::Lang;
use botbench::system::PortInfo;
use botbench::system::adapter::Adapter;
use botbench::ui::files::Dialogs;
use botbench::ui::station::PortLister;
use botbench::ui::{App, PanelId};
use eframe::egui::accesskit::Role;
use egui_kittest::kittest::Queryable;
use std::sync::Arc;

use crate::support::gui::{H, app_mut, harness_with, settings, step_until};
use crate::support::{serve, window_cleaner};

/// Rests the pointer on the (first) widget with `label` (a text's value) and `role`, then says
/// whether some text containing `hint` is shown; it is not before.
fn hint_on(h: &mut H, label: &str, role: Role, hint: &str) {
    assert!(
        h.query_all_by_label_contains(hint).next().is_none(),
        "'{hint}' is shown before the pointer rests on {label}"
    );
    // The tooltip shows once the pointer has rested on the widget for egui's delay (0.5 s; a
    // step is 0.25 s). The pointer follows the widget if it moves: a reading that arrives
    // meanwhile may move it (the window lays out what the link brings).
    let deadline = std::time::Instant::now() + crate::support::PATIENCE;
    let mut on = None;
    loop {
        let widget = h
            .query_all_by(|n| {
                n.role() == role
                    && (n.label().as_deref() == Some(label) || n.value().as_deref() == Some(label))
            })
            .next()
            .unwrap_or_else(|| panic!("no {role:?} {label}"));
        let at = widget.rect().center();
        if on != Some(at) {
            widget.hover();
            on = Some(at);
        }
        h.step();
        if h.query_all_by_label_contains(hint).next().is_some() {
            return;
        }
        assert!(
            std::time::Instant::now() < deadline,
            "no hint '{hint}' on {label}"
        );
    }
}

/// The pty's port as an FTDI adapter with a 16 ms latency timer that this user may set.
fn ftdi(path: &str) -> PortLister {
    let port = PortInfo {
        path: path.to_string(),
        kind: "usb",
        vid: Some(0x0403),
        pid: Some(0x6001),
        serial_number: None,
        manufacturer: None,
        product: None,
        adapter: Adapter {
            driver: Some("ftdi_sio".into()),
            latency_timer_ms: Some(16),
            latency_timer_writable: true,
            note: None,
        },
    };
    PortLister(Arc::new(move || vec![port.clone()]))
}

#[test]
fn hover_hints_say_the_wire_name_the_range_why_not_what_stop_sends_and_the_latency_timer() {
    let b = serve(window_cleaner());
    let path = b.path().to_string();
    let mut saved = settings(&path, "window-cleaner", PanelId::TUNING, Lang::En);
    saved.port_mut().margin_ms = Some(100);
    let lister = ftdi(&path);
    let mut h = harness_with(saved, b.ports(), move |a: &mut App| {
        a.station_mut().link.port_lister = lister.clone();
        a.station_mut().link.refresh_ports_now();
        a.station_mut().dialogs = Dialogs::Missing("no file dialog on this system (test)".into());
    });
    step_until(&mut h, "the link", |a| a.station().connected());
    h.run_steps(2);

    // Tuning: a field's name tells its wire name.
    hint_on(&mut h, "   Fan PWM", Role::Label, "pwmValue");
    // STOP says what it sends.
    hint_on(
        &mut h,
        "STOP",
        Role::Button,
        "Now: Motor motor=stop, Fan pwm=0",
    );
    // The adapter's latency timer: what 1 ms changes, with the timer's own value.
    hint_on(
        &mut h,
        "Set to 1 ms",
        Role::Button,
        "up to 1 ms after they arrive instead of 16 ms",
    );

    // Actions: an input's range, and why Send is greyed out.
    app_mut(&mut h).settings.panel = PanelId::ACTIONS;
    h.run_steps(2);
    hint_on(&mut h, "Fan PWM", Role::TextInput, "0 – 100 %");
    // The Fan's comes first.
    hint_on(
        &mut h,
        "⚠ Send…",
        Role::Button,
        "pwm: give a value (0 – 100 %)",
    );

    // A Browse that cannot open a dialog says why before it is clicked.
    app_mut(&mut h).settings.panel = PanelId::MONITOR;
    h.run_steps(2);
    hint_on(
        &mut h,
        "Browse…",
        Role::Button,
        "no file dialog on this system (test)",
    );
}
