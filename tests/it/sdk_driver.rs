//! The servo vendor's own SDK drives `botbench sim servo-bus` through a pty
//! (`tests/sdk/sdk_drive_sim.py`, tests/sdk/README.md) and every check it makes must pass.
//!
//! Needs the SDK in a Python virtual environment, so it is `#[ignore]`d: `cargo test` alone never
//! passes it without running it. `.ci/run` installs the SDK (`fashionstar-uart-sdk` and
//! `pyserial`, with pip, in a venv under `target/`) and runs it with `--ignored`;
//! `BOTBENCH_SDK_PYTHON` names the venv's interpreter, else `/work/sdk-venv/bin/python` (the
//! README's set-up) is tried. Run with `--ignored` and no SDK, it fails saying so. It takes
//! about 20 s (the SDK waits up to 100 ms for every reply).

use std::path::PathBuf;
use std::process::{Command, Stdio};

use crate::support::cli::{SimProcess, try_watched, watched};

/// The SDK's interpreter, if it is installed.
fn sdk_python() -> Result<PathBuf, String> {
    let python = std::env::var_os("BOTBENCH_SDK_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("/work/sdk-venv/bin/python"));
    let mut check = Command::new(&python);
    check
        .args(["-c", "import fashionstar_uart_sdk, serial"])
        .stdin(Stdio::null());
    let ok = try_watched(&mut check, "the SDK's python").is_ok_and(|r| r.code == 0);
    if ok {
        Ok(python)
    } else {
        Err(format!(
            "{} cannot import fashionstar_uart_sdk and serial (set BOTBENCH_SDK_PYTHON; set-up in tests/sdk/README.md)",
            python.display()
        ))
    }
}

#[test]
#[ignore = "needs the servo SDK"]
fn the_vendor_sdk_gets_correct_answers_from_the_servo_bus_simulator() {
    let python = sdk_python().unwrap_or_else(|why| panic!("no servo SDK: {why}"));
    let sim = SimProcess::start(&["servo-bus", "--servos", "1,2,3"]);
    let pty = sim.path.as_str();
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/sdk/sdk_drive_sim.py");
    let out = watched(
        Command::new(&python)
            .args([script, pty, "--ids", "1,2,3"])
            .stdin(Stdio::null()),
        "the SDK's driver",
    );
    let summary: serde_json::Value = out
        .out
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .find(|d| d["kind"] == "summary")
        .unwrap_or_else(|| panic!("no summary; stderr:\n{}", out.err));
    eprintln!("{summary}");
    let failed: Vec<&str> = out
        .out
        .lines()
        .filter(|l| l.contains("\"ok\": false"))
        .collect();
    assert_eq!(summary["failed"], serde_json::json!([]), "{failed:#?}");
    assert_eq!(out.code, 0, "driver exit: {}", out.text());
    // Every step the SDK can do was checked: only the SDK's own defects and steps with nothing
    // to observe are unchecked.
    assert!(summary["ok"].as_u64().unwrap_or(0) >= 59, "{summary}");
}
