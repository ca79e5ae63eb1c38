//! Boards that reboot when their port opens (issue 25, item 2): the port's DTR and RTS lines
//! and a boot wait after open, on the command line, in a station file and in the window.

use crate::support::cli::Sim;

#[test]
fn a_board_that_boots_on_open_is_identified_after_the_boot_wait() {
    // Silent for 1.5 s after each open of its port, as a board reset by DTR/RTS.
    let sim = Sim::start(&["window-cleaner", "--boot-ms", "1500"]);

    let args = [
        "--boot-wait-ms",
        "2000",
        "--dtr",
        "off",
        "--rts",
        "on",
        "version",
    ];
    let ran = sim.cli("msp", &args);
    assert_eq!(ran.code, 0, "{ran:?}");
    assert!(ran.out.contains("1.4.2"), "identified: {ran:?}");

    // Without a boot wait every request meets the booting board: the checklist names the
    // boot wait and the lines as the likely cause.
    let ran = sim.cli("msp", &["version"]);
    assert_eq!(ran.code, 1, "{ran:?}");
    assert!(ran.err.contains("is the device powered"), "{ran:?}");
    assert!(ran.err.contains("--boot-wait-ms"), "{ran:?}");
    assert!(ran.err.contains("DTR/RTS"), "{ran:?}");
}

#[test]
fn line_levels_and_boot_waits_out_of_range_are_refused_naming_what_is_accepted() {
    let sim = Sim::start(&["window-cleaner"]);
    let ran = sim.cli("msp", &["--dtr", "high", "version"]);
    assert_eq!(ran.code, 2, "{ran:?}");
    assert!(ran.err.contains("on, off or keep"), "{ran:?}");
    let ran = sim.cli("msp", &["--boot-wait-ms", "30001", "version"]);
    assert_eq!(ran.code, 2, "{ran:?}");
    assert!(ran.err.contains("0 to 30000"), "{ran:?}");
}

#[test]
fn the_window_keeps_port_options_per_profile_and_connects_with_them() {
    use crate::support::gui::{app, harness, has_label, settings, step_until, type_into};
    use crate::support::{ms, serve_with, window_cleaner};
    use botbench::link::LineLevel;
    use egui_kittest::kittest::Queryable;
    // A board that boots for 1.5 s after each open: found only with a boot wait.
    let served = serve_with(
        window_cleaner(),
        botbench::sim::Faults {
            boot: ms(1500),
            ..Default::default()
        },
    );
    let saved = settings(
        served.path(),
        "window-cleaner",
        botbench::ui::PanelId::TUNING,
        botbench::i18n::Lang::En,
    );
    let mut h = harness(saved, served.ports());
    step_until(&mut h, "the link", |a| a.station().connected());

    h.get_by_label("Port options").click();
    h.run_steps(2);
    // DTR's row comes first: its "off".
    h.get_all_by_label("off").next().unwrap().click();
    h.step();
    type_into(&mut h, "Boot wait", "2000");
    // The margin takes what --margin-ms takes, and refuses the rest in place.
    type_into(&mut h, "Margin (empty: auto)", "5001");
    assert!(has_label(&h, "give milliseconds from 1 to 5000"));
    type_into(&mut h, "Margin (empty: auto)", "5000");
    h.get_by_label("Port options").click();
    h.run_steps(2);
    h.get_by_label("Reconnect").click();
    step_until(&mut h, "the booted board identified", |a| {
        a.station().device.info.is_some()
    });

    let a = app(&h);
    let port = a.settings.port_of("window-cleaner");
    assert_eq!(
        (port.dtr, port.rts, port.boot_wait_ms, port.margin_ms),
        (LineLevel::Off, LineLevel::Keep, 2000, Some(5000)),
        "{port:?}"
    );
    let setup = a.station().link.options.setup;
    assert_eq!((setup.dtr, setup.boot_wait), (LineLevel::Off, ms(2000)));
    assert_eq!(a.station().link.options.margin, Some(ms(5000)));
    // Another profile keeps its own (none).
    assert_eq!(a.settings.port_of("servo"), Default::default());
}
