//! A multi-turn move the servo cannot do in its interval (shorter than its acceleration and
//! deceleration times, the vendor SDK's rule, written in the servo profile's relations) is
//! refused before anything is sent, naming the interval given and the least allowed; one it
//! can do moves the servo.

use crate::support::cli::Sim;

/// Servo 1's multi-turn angle as `servo monitor` reads it, degrees.
fn angle(sim: &Sim) -> f64 {
    let ran = sim.cli("servo", &["monitor", "1", "--json"]);
    assert_eq!(ran.code, 0, "{ran:?}");
    let doc = ran.json();
    doc.pointer("/servos/0/angle_deg")
        .and_then(|v| v.as_f64())
        .unwrap_or_else(|| panic!("no angle in {doc}"))
}

#[test]
fn a_multi_turn_interval_shorter_than_acceleration_and_deceleration_is_refused() {
    let sim = Sim::start(&["servo-bus", "--servos", "1"]);
    let before = angle(&sim);

    // Servo 1 to 720° over `ms`, accelerating for 30 ms and decelerating for 40 ms.
    let move_over = |ms: &str| {
        let args = [
            "angle",
            "1",
            "720",
            "--multi-turn",
            "--ms",
            ms,
            "--acc-ms",
            "30",
            "--dec-ms",
            "40",
        ];
        sim.cli("servo", &args)
    };
    let ran = move_over("50");
    assert_eq!(ran.code, 2, "{ran:?}");
    assert!(ran.err.contains("nothing sent"), "{ran:?}");
    // The interval given and the least allowed (t_acc + t_dec).
    assert!(ran.err.contains("= 70 ms"), "{ran:?}");
    assert!(ran.err.contains("Interval (interval) 50 ms"), "{ran:?}");
    assert_eq!(angle(&sim), before, "nothing moved");

    let ran = move_over("70");
    assert_eq!(ran.code, 0, "{ran:?}");
    let deadline = std::time::Instant::now() + crate::support::PATIENCE;
    while angle(&sim) != 720.0 {
        assert!(
            std::time::Instant::now() < deadline,
            "the servo did not reach 720°"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}
