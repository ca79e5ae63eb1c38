//! The command line explains itself (issue 29, items 5-12): a command the device does not
//! answer says so and checks first that the device is there.

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
