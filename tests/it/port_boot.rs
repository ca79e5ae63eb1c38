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
