//! The command line explains itself (issue 29, items 5-12): a command the device does not
//! answer says so and checks first that the device is there; errors name commands by name.

use crate::support::cli::Sim;

#[test]
fn servo_angle_pings_first_and_says_the_servo_sends_no_answer() {
    let sim = Sim::start(&["servo-bus", "--servos", "1"]);

    let ran = sim.cli("servo", &["angle", "1", "90"]);
    assert_eq!(ran.code, 0, "{ran:?}");
    assert!(ran.out.contains("turning to 90°"), "{ran:?}");
    assert!(ran.out.contains("sends no answer"), "{ran:?}");
    assert!(ran.out.contains("answered a ping"), "{ran:?}");

    // Servo 7 is not on the bus: the angle would have gone nowhere and said nothing.
    let ran = sim.cli("servo", &["angle", "7", "90"]);
    assert_eq!(ran.code, 1, "{ran:?}");
    assert!(
        ran.err
            .starts_with("botbench: servo 7 does not answer a ping"),
        "{ran:?}"
    );
    assert!(
        ran.err.contains("is the device powered"),
        "the checklist: {ran:?}"
    );
    assert!(ran.out.is_empty(), "{ran:?}");

    // --no-check sends it anyway, and says that nothing tells it is there.
    let ran = sim.cli("servo", &["angle", "7", "90", "--no-check"]);
    assert_eq!(ran.code, 0, "{ran:?}");
    assert!(ran.out.contains("not pinged first"), "{ran:?}");

    let ran = sim.cli("servo", &["angle", "1", "-45.5", "--json"]);
    assert_eq!(ran.code, 0, "{ran:?}");
    let doc = ran.json();
    assert_eq!(doc["pinged"], true, "{doc}");
    assert_eq!(doc["acknowledged"], false, "{doc}");

    let ran = sim.cli("servo", &["angle", "255", "10", "--broadcast"]);
    assert_eq!(ran.code, 0, "{ran:?}");
    assert!(ran.out.contains("no servo answers it"), "{ran:?}");
}

#[test]
fn errors_name_the_command_that_got_no_answer() {
    // Every reply lost: the first exchange times out.
    let sim = Sim::start(&["window-cleaner", "--drop", "1"]);
    let ran = sim.cli("msp", &["--margin-ms", "5", "get", "MSP_GET_PWMVALUE"]);
    assert_eq!(ran.code, 1, "{ran:?}");
    assert!(
        ran.err
            .contains("no answer to MSP_GET_PWMVALUE (130) after"),
        "{ran:?}"
    );
    assert!(!ran.err.contains("command 130"), "{ran:?}");
    let last = ran.err.lines().last().unwrap_or_default();
    assert!(last.starts_with("botbench: "), "one style: {ran:?}");

    let sim = Sim::start(&["servo-bus", "--servos", "1", "--drop", "1"]);
    let ran = sim.cli("servo", &["read", "1", "voltage"]);
    assert_eq!(ran.code, 1, "{ran:?}");
    assert!(
        ran.err.contains("no answer to READ_DATA (3) after"),
        "{ran:?}"
    );
}

#[test]
fn a_closed_stdin_at_the_self_tests_prompt_is_said_as_such() {
    // No --yes and nothing on stdin: nobody can press Enter at the operator's step.
    let sim = Sim::start(&["window-cleaner"]);
    let ran = sim.cli("msp", &["selftest", "presets/window-cleaner-selftest.ron"]);
    assert_eq!(ran.code, 1, "{ran:?}");
    assert!(
        ran.err.contains(
            "botbench: stdin is closed: no operator to press Enter, so the self-test stops here"
        ),
        "{ran:?}"
    );
}
