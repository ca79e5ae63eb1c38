//! Production self-test: a test plan in RON, checked against the profile when it loads, run
//! step by step over a link, and logged as one JSON line per run.
//!
//! A plan lists steps of five kinds. Thresholds are in display units ("11.5" volts, not 115),
//! written as text or bare numbers; a field may be named alone (`field:`) or several at once
//! (`fields:`), every one of them must pass.
//!
//! ```ron
//! (
//!     version: 1,
//!     profile: "window-cleaner",
//!     name: "Window cleaner line test",
//!     steps: [
//!         // Every sample of every field within [min, max].
//!         Range(name: "Battery voltage", command: "MSP_ADAPTER", field: "batteryVoltage",
//!               min: "11.5", max: "16.8", samples: 5),
//!         // At rest: the spread (max - min) of each field over the samples within bounds.
//!         Stable(name: "Gyro at rest", command: "MSP_RAW_IMU", fields: ["gyroX", "gyroY", "gyroZ"],
//!                max_spread: "30", samples: 10),
//!         // The mean rises by at least min_rise while the action is on; `then` always runs after.
//!         Rises(name: "Wheels forward", action: ("MSP_SET_MOTOR", {"motor": "forward"}),
//!               command: "MSP_ANALOG", fields: ["adcLeftWheel", "adcRightWheel"],
//!               min_rise: "200", settle_ms: 600, then: ("MSP_SET_MOTOR", {"motor": "stop"})),
//!         // Prompts the operator, then watches until every bit has been seen clear and set.
//!         Operator(name: "Corner switches", prompt: "Cover each corner switch in turn",
//!                  command: "MSP_FOURCORNER", field: "corners", expect_bits_seen: 15,
//!                  timeout_ms: 20000),
//!         // The command answers and decodes; `expect` values must match exactly.
//!         Reads(name: "Water box", command: "MSP_WATER_BOX", expect: {"status": "1"}),
//!     ],
//! )
//! ```
//!
//! A run goes on after a step fails, so that the report shows every check; it ends at once (as
//! FAIL, naming the step) when the link is lost, the device stops answering, the operator aborts
//! or the run is cancelled. A Rises step's `then` action is sent whatever happened before it.

mod check;
mod measure;
mod plan;
mod record;
mod run;
mod steps;

pub use plan::{Action, Plan, Step, StepKind, VERSION};
pub use record::{Interruption, Report, StepResult, append_log};
pub use run::{Operator, SAFE_STATE, run, run_each};
