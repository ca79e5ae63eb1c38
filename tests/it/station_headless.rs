//! The line station headless (issue 27): `station BUNDLE --headless --json --once` runs every
//! slot to its verdict, one record per unit (kind `station`, the bundle's hash in it) kept
//! before the verdict is said; the demo bundle's simulated fixtures play the operator's hands
//! and a Confirm takes `yes` from stdin; three slots on ptys (a window cleaner, a servo bus
//! with a fresh servo, a Tuya vacuum) reach their verdicts, and a `no` fails the unit and
//! writes that into the robot (147, read back with 148).

use crate::support::cli::{Sim, run_in_process_into};
use botbench::cli::Captured;
use botbench::link::PortOpener;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// The verdict events of a run's JSON lines, by slot.
fn verdicts(docs: &[Value]) -> Vec<(String, bool)> {
    let mut v: Vec<(String, bool)> = docs
        .iter()
        .filter(|d| d["event"] == "verdict")
        .map(|d| {
            (
                d["slot"].as_str().unwrap().to_string(),
                d["pass"].as_bool().unwrap(),
            )
        })
        .collect();
    v.sort();
    v
}

/// `(kind, verdict, slot, bundle_sha256, failed_step)` of every run in the records `file`.
fn runs(file: &Path) -> Vec<(String, String, String, String, Option<String>)> {
    let db = rusqlite::Connection::open(file).unwrap();
    let mut q = db
        .prepare("SELECT kind, verdict, slot, bundle_sha256, failed_step FROM runs ORDER BY slot")
        .unwrap();
    q.query_map([], |r| {
        Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?, r.get(4)?))
    })
    .unwrap()
    .map(Result::unwrap)
    .collect()
}

#[test]
fn the_demo_station_runs_headless_to_three_verdicts_with_no_hardware() {
    let dir = tempfile::tempdir().unwrap();
    let records = dir.path().join("records.sqlite");
    let bundle = Path::new(env!("CARGO_MANIFEST_DIR")).join("presets/demo-station.ron");
    let ran = run_in_process_into(
        &[
            "station",
            &bundle.display().to_string(),
            "--headless",
            "--json",
            "--once",
            "--records",
            &records.display().to_string(),
        ],
        &PortOpener::system(),
        Captured::typing("yes\n"),
    );
    assert_eq!(ran.code, 0, "{}", ran.text());
    let docs = ran.json_lines();
    assert_eq!(
        verdicts(&docs),
        [("1".into(), true), ("2".into(), true), ("3".into(), true)],
        "{}",
        ran.text()
    );
    let hash = docs[0]["bundle_sha256"].as_str().unwrap().to_string();
    let kept = runs(&records);
    assert_eq!(kept.len(), 3, "{kept:?}");
    for (kind, verdict, _, bundle_sha256, _) in &kept {
        assert_eq!((kind.as_str(), verdict.as_str()), ("station", "PASS"));
        assert_eq!(bundle_sha256, &hash);
    }
    // The simulated fixture's hands covered the corners: the self-test's Operator step passed
    // without anyone typing `corners`.
    let prompt = docs
        .iter()
        .position(|d| d["kind"] == "prompt")
        .expect("the corner prompt");
    let verdict_1 = docs
        .iter()
        .position(|d| d["event"] == "verdict" && d["slot"] == "1")
        .unwrap();
    assert!(prompt < verdict_1);
    // The servo's serial is read from it, and the record was kept before the verdict was said.
    let servo = docs
        .iter()
        .find(|d| d["event"] == "verdict" && d["slot"] == "2")
        .unwrap();
    assert_eq!(servo["serial"], "1001", "{servo}");
    assert!(
        servo["kept"]
            .as_str()
            .unwrap()
            .starts_with("record saved to"),
        "{servo}"
    );
    // Steps named for people, in both languages, as the records keep them.
    let names: Vec<(&str, &str)> = docs
        .iter()
        .filter(|d| d["event"] == "step")
        .map(|d| (d["name"].as_str().unwrap(), d["name_zh"].as_str().unwrap()))
        .collect();
    for want in [
        (
            "Self-test (window-cleaner-selftest)",
            "自检(window-cleaner-selftest)",
        ),
        (
            "Provision (servo-provision-plan)",
            "舵机配置(servo-provision-plan)",
        ),
        ("Tuya handshake", "涂鸦握手"),
        ("Write result", "写入测试结果"),
    ] {
        assert!(names.contains(&want), "{want:?} not in {names:?}");
    }
    let db = rusqlite::Connection::open(&records).unwrap();
    let recorded: i64 = db
        .query_row(
            "SELECT COUNT(*) FROM steps WHERE name = 'Write result'",
            [],
            |r| r.get(0),
        )
        .unwrap();
    assert_eq!(recorded, 1);
}

/// A bundle of three slots on the simulators' ptys, with a short self-test plan (no operator
/// step: on a pty nobody's hands cover the corners).
fn pty_bundle(dir: &Path, wc: &str, servo: &str, tuya: &str) -> PathBuf {
    let presets = Path::new(env!("CARGO_MANIFEST_DIR")).join("presets");
    std::fs::copy(
        presets.join("servo-provision-plan.ron"),
        dir.join("servo-provision-plan.ron"),
    )
    .unwrap();
    std::fs::write(
        dir.join("short-selftest.ron"),
        r#"(version: 1, profile: "window-cleaner", name: "Short line test", steps: [
            Range(name: "Battery voltage", command: "MSP_ADAPTER", field: "batteryVoltage",
                  min: "11.5", max: "16.8", samples: 3),
            Reads(name: "Water box", command: "MSP_WATER_BOX", expect: {"status": "1"}),
        ])"#,
    )
    .unwrap();
    let text = format!(
        r#"(version: 1, id: "pty-station",
    plans: {{
        "wc": (start: Button, steps: [
            Scan(pattern: "WC[0-9]{{6}}"),
            Identify(hardware: [3]),
            SelfTest("short-selftest.ron"),
            Confirm(question: "Did it spray?"),
            WriteResult,
        ]),
        "servo": (start: Auto, steps: [Provision(plan: "servo-provision-plan.ron")]),
        "tuya": (start: Auto, steps: [TuyaHandshake, TuyaStatus]),
    }},
    slots: [
        (name: "1", fixture: "WC", port: Path("{wc}"), profile: "window-cleaner", plan: "wc"),
        (name: "2", fixture: "Servos", port: Path("{servo}"), profile: "servo", plan: "servo"),
        (name: "3", fixture: "MCU", port: Path("{tuya}"), profile: "tuya-vacuum", plan: "tuya"),
    ],
)"#
    );
    let path = dir.join("pty-station.ron");
    std::fs::write(&path, text).unwrap();
    path
}

/// Runs the pty station once with the operator typing `input`.
fn run_pty_station(input: &str) -> (crate::support::cli::Ran, Vec<Value>, PathBuf, Sim) {
    let wc = Sim::start(&["window-cleaner"]);
    let servo = Sim::start(&["servo-bus", "--servos", "0"]);
    let tuya = Sim::start(&["tuya-vacuum"]);
    let dir = tempfile::tempdir().unwrap().keep();
    let bundle = pty_bundle(&dir, &wc.path, &servo.path, &tuya.path);
    let records = dir.join("records.sqlite");
    let ports = tuya.serve_in(servo.serve_in(wc.ports().clone()));
    let ran = run_in_process_into(
        &[
            "station",
            &bundle.display().to_string(),
            "--headless",
            "--json",
            "--once",
            "--records",
            &records.display().to_string(),
        ],
        &ports,
        Captured::typing(input),
    );
    let docs = ran.json_lines();
    (ran, docs, records, wc)
}

#[test]
fn three_slots_on_ptys_run_headless_to_their_verdicts() {
    // Slot 1 starts by the Start line, its serial scanned, its Confirm answered `1 y`.
    let (ran, docs, records, wc) = run_pty_station("start 1\nWC000123\n1 y\n");
    assert_eq!(ran.code, 0, "{}", ran.text());
    assert_eq!(
        verdicts(&docs),
        [("1".into(), true), ("2".into(), true), ("3".into(), true)],
        "{}",
        ran.text()
    );
    let verdict = docs
        .iter()
        .find(|d| d["event"] == "verdict" && d["slot"] == "1")
        .unwrap();
    assert_eq!(verdict["serial"], "WC000123", "{verdict}");
    let done: Vec<&Value> = docs
        .iter()
        .filter(|d| d["event"] == "step-done" && d["slot"] == "1")
        .collect();
    assert!(
        done.iter()
            .any(|d| d["name"] == "Write result" && d["pass"] == true),
        "{}",
        ran.text()
    );
    assert_eq!(runs(&records).len(), 3);
    // The robot holds its PASS (MSP_AUTO_TEST_RESULT 148 reads 1).
    assert_eq!(auto_test_result(&wc), 1);
}

/// What the window cleaner's MSP_AUTO_TEST_RESULT (148) reads now.
fn auto_test_result(wc: &Sim) -> i64 {
    let dev = wc.run(&[
        "msp",
        "--port",
        &wc.path,
        "get",
        "MSP_AUTO_TEST_RESULT",
        "--json",
    ]);
    assert_eq!(dev.code, 0, "{}", dev.text());
    dev.json()["fields"][0]["value"].as_i64().unwrap()
}

#[test]
fn an_operator_no_fails_the_unit_and_the_robot_is_told_it_failed() {
    let (ran, docs, records, wc) = run_pty_station("start 1\nWC000124\n1 n\n");
    assert_eq!(ran.code, 1, "{}", ran.text());
    let v = docs
        .iter()
        .find(|d| d["event"] == "verdict" && d["slot"] == "1")
        .unwrap();
    assert_eq!(v["pass"], false);
    assert_eq!(v["failed_step"], "Confirm: Did it spray?", "{v}");
    assert_eq!(v["reason"], "operator said no", "{v}");
    // WriteResult still ran after the failure: 0 written, read back 0.
    let write = docs
        .iter()
        .find(|d| d["event"] == "step-done" && d["name"] == "Write result")
        .expect("WriteResult ran after the failure");
    assert_eq!(write["pass"], true, "{write}");
    assert_eq!(auto_test_result(&wc), 0);
    let kept = runs(&records);
    let slot1 = kept.iter().find(|r| r.2 == "1").unwrap();
    assert_eq!(slot1.1, "FAIL");
    assert_eq!(slot1.4.as_deref(), Some("Confirm: Did it spray?"));
}

#[test]
fn a_scan_that_does_not_match_the_plan_s_pattern_fails_before_the_robot_is_touched() {
    let (ran, docs, _records, _wc) = run_pty_station("start 1\nXX1\n");
    assert_eq!(ran.code, 1, "{}", ran.text());
    let v = docs
        .iter()
        .find(|d| d["event"] == "verdict" && d["slot"] == "1")
        .unwrap();
    assert_eq!(v["failed_step"], "Scan serial", "{v}");
    assert_eq!(v["reason"], "serial does not match the pattern", "{v}");
    // Nothing after the scan ran but the result written into the robot.
    let ran_after: Vec<&str> = docs
        .iter()
        .filter(|d| d["event"] == "step" && d["slot"] == "1")
        .map(|d| d["name"].as_str().unwrap())
        .collect();
    assert_eq!(ran_after, ["Scan serial", "Write result"], "{}", ran.text());
}

/// Runs a one-slot station of a simulated window cleaner with `plan` (RON steps and options),
/// the operator typing `input`; its JSON lines and the records file.
fn one_slot(plan: &str, input: &str) -> (crate::support::cli::Ran, Vec<Value>, PathBuf) {
    let dir = tempfile::tempdir().unwrap().keep();
    let bundle = dir.join("one.ron");
    std::fs::write(
        &bundle,
        format!(
            r#"(version: 1, id: "one", plans: {{ "p": ({plan}) }},
                slots: [(name: "1", fixture: "F", port: Simulated("window-cleaner"),
                         profile: "window-cleaner", plan: "p")])"#
        ),
    )
    .unwrap();
    let records = dir.join("records.sqlite");
    let ran = run_in_process_into(
        &[
            "station",
            &bundle.display().to_string(),
            "--headless",
            "--json",
            "--once",
            "--records",
            &records.display().to_string(),
        ],
        &PortOpener::system(),
        Captured::typing(input),
    );
    let docs = ran.json_lines();
    (ran, docs, records)
}

#[test]
fn a_failed_step_retried_once_passes_and_the_record_keeps_both_tries() {
    let plan = r#"start: Button, retry_once: true, steps: [
        Measure(name: "Suction", unit: "kPa", min: 2.0, max: 3.5)]"#;
    // Start; 5.0 kPa is out of limits; retry: yes; 2.5 kPa passes.
    let (ran, docs, records) = one_slot(plan, "start\n5.0\nyes\n2.5\n");
    assert_eq!(ran.code, 0, "{}", ran.text());
    let asked: Vec<&str> = docs
        .iter()
        .filter(|d| d["event"] == "ask")
        .map(|d| d["kind"].as_str().unwrap())
        .collect();
    assert_eq!(asked, ["measure", "retry", "measure"], "{}", ran.text());
    let db = rusqlite::Connection::open(&records).unwrap();
    let tries: Vec<(String, String, Option<String>)> = db
        .prepare("SELECT name, verdict, reason FROM steps ORDER BY idx")
        .unwrap()
        .query_map([], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)))
        .unwrap()
        .map(Result::unwrap)
        .collect();
    assert_eq!(
        tries,
        [
            (
                "Measure Suction".to_string(),
                "FAIL".to_string(),
                Some("out of limits: Suction".to_string())
            ),
            ("Measure Suction".to_string(), "PASS".to_string(), None),
        ]
    );
    let verdict: String = db
        .query_row("SELECT verdict FROM runs", [], |r| r.get(0))
        .unwrap();
    assert_eq!(verdict, "PASS");
}

#[test]
fn a_retry_refused_leaves_the_unit_failed_at_that_step() {
    let plan = r#"start: Button, retry_once: true, steps: [
        Measure(name: "Suction", unit: "kPa", min: 2.0, max: 3.5)]"#;
    let (ran, docs, _) = one_slot(plan, "start\n1.0\nno\n");
    assert_eq!(ran.code, 1, "{}", ran.text());
    let v = docs.iter().find(|d| d["event"] == "verdict").unwrap();
    assert_eq!(v["failed_step"], "Measure Suction", "{v}");
    assert_eq!(v["reason"], "out of limits: Suction", "{v}");
}

#[test]
fn ctrl_c_stops_every_slot_safely_and_exits_130() {
    let dir = tempfile::tempdir().unwrap();
    let records = dir.path().join("records.sqlite");
    let bundle = Path::new(env!("CARGO_MANIFEST_DIR")).join("presets/demo-station.ron");
    let bundle = bundle.display().to_string();
    let args = [
        "station",
        &bundle,
        "--headless",
        "--json",
        "--records",
        &records.display().to_string(),
    ];
    // No --once: the slots run unit after unit until stopped; nobody answers the Confirm.
    let captured = Captured::default();
    let ports = PortOpener::system();
    let run = crate::support::cli::start_in_process(&args, &ports, &captured);
    let deadline = std::time::Instant::now() + crate::support::PATIENCE;
    // Every slot busy with a unit: slot 1 asking about the spray, 2 and 3 past a step.
    let busy = |out: &str| {
        let docs: Vec<Value> = out
            .lines()
            .filter_map(|l| serde_json::from_str(l).ok())
            .collect();
        ["1", "2", "3"].iter().all(|s| {
            docs.iter()
                .any(|d| d["slot"] == *s && (d["event"] == "step" || d["event"] == "ask"))
        })
    };
    while !busy(&captured.out()) {
        assert!(
            !run.is_finished() && std::time::Instant::now() < deadline,
            "{}{}",
            captured.out(),
            captured.err()
        );
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    captured.interrupt();
    let code = crate::support::cli::finish_in_process(run, &captured, "the station");
    let out = captured.out();
    let text = format!("exit {code}\n{out}{}", captured.err());
    assert_eq!(code, 130, "{text}");
    let docs: Vec<Value> = out
        .lines()
        .filter_map(|l| serde_json::from_str(l).ok())
        .collect();
    let mut stopped: Vec<&str> = docs
        .iter()
        .filter(|d| d["event"] == "stopped")
        .map(|d| d["slot"].as_str().unwrap())
        .collect();
    stopped.sort_unstable();
    assert_eq!(stopped, ["1", "2", "3"], "{text}");
    assert!(
        captured.err().contains("every slot stopped safely"),
        "{text}"
    );
    // A unit cut short is never a PASS: its record, if any, says FAIL.
    let db = rusqlite::Connection::open(&records).unwrap();
    let cut_short_passed: i64 = db
        .query_row(
            "SELECT COUNT(*) FROM runs WHERE verdict = 'PASS' AND reason = 'cancelled'",
            [],
            |r| r.get(0),
        )
        .unwrap_or(0);
    assert_eq!(cut_short_passed, 0);
}

#[test]
fn preset_conformance_and_firmware_update_steps_run_in_a_station_and_are_recorded() {
    let wc = Sim::start(&["window-cleaner"]);
    let tuya = Sim::start(&["tuya-vacuum", "--ota-restart-ms", "300"]);
    let dir = tempfile::tempdir().unwrap();
    let presets = Path::new(env!("CARGO_MANIFEST_DIR")).join("presets");
    std::fs::copy(
        presets.join("window-cleaner-factory.ron"),
        dir.path().join("window-cleaner-factory.ron"),
    )
    .unwrap();
    // A 4 KiB image whose MCU_VER string is 1.2.3, as an SDK build holds it.
    let mut image: Vec<u8> = (0..4096u32).map(|i| (i * 13 % 251) as u8 | 0x80).collect();
    image[100..106].copy_from_slice(b"1.2.3\0");
    std::fs::write(dir.path().join("vacuum-1.2.3.bin"), &image).unwrap();
    let text = format!(
        r#"(version: 1, id: "steps-station",
    plans: {{
        "wc": (start: Auto, steps: [Identify(hardware: [3]), Preset("window-cleaner-factory.ron"), WriteResult]),
        "tuya": (start: Auto, steps: [TuyaHandshake, TuyaConform, FirmwareUpdate(image: "vacuum-1.2.3.bin")]),
    }},
    slots: [
        (name: "1", fixture: "WC", port: Path("{}"), profile: "window-cleaner", plan: "wc"),
        (name: "2", fixture: "MCU", port: Path("{}"), profile: "tuya-vacuum", plan: "tuya"),
    ],
)"#,
        wc.path, tuya.path
    );
    let bundle = dir.path().join("steps.ron");
    std::fs::write(&bundle, text).unwrap();
    let records = dir.path().join("records.sqlite");
    let ports = tuya.serve_in(wc.ports().clone());
    let ran = run_in_process_into(
        &[
            "station",
            &bundle.display().to_string(),
            "--headless",
            "--json",
            "--once",
            "--records",
            &records.display().to_string(),
        ],
        &ports,
        Captured::default(),
    );
    assert_eq!(ran.code, 0, "{}", ran.text());
    let docs = ran.json_lines();
    assert_eq!(
        verdicts(&docs),
        [("1".into(), true), ("2".into(), true)],
        "{}",
        ran.text()
    );
    let done: Vec<(&str, &str, bool)> = docs
        .iter()
        .filter(|d| d["event"] == "step-done")
        .map(|d| {
            (
                d["slot"].as_str().unwrap(),
                d["name"].as_str().unwrap(),
                d["pass"].as_bool().unwrap(),
            )
        })
        .collect();
    for want in [
        ("1", "Preset (window-cleaner-factory)", true),
        ("1", "Write result", true),
        ("2", "Tuya conformance", true),
        ("2", "Firmware update (vacuum-1.2.3)", true),
    ] {
        assert!(done.contains(&want), "{want:?} not in {done:?}");
    }
    let db = rusqlite::Connection::open(&records).unwrap();
    // The preset's writes, each with the value before and after (read back).
    let writes: i64 = db
        .query_row(
            "SELECT COUNT(*) FROM writes w JOIN runs r ON r.id = w.run \
             WHERE r.slot = '1' AND w.after IS NOT NULL",
            [],
            |r| r.get(0),
        )
        .unwrap();
    assert!(writes > 0, "no preset writes recorded");
    // The conformance checks as steps, and the MCU on the image's version after the update.
    let (checks, firmware): (i64, Option<String>) = db
        .query_row(
            "SELECT (SELECT COUNT(*) FROM steps s WHERE s.run = r.id AND s.name = 'heartbeat'), \
             r.firmware FROM runs r WHERE r.slot = '2'",
            [],
            |r| Ok((r.get(0)?, r.get(1)?)),
        )
        .unwrap();
    assert_eq!((checks, firmware.as_deref()), (1, Some("1.2.3")));
}

#[test]
fn an_auto_slot_starts_when_the_simulator_presents_the_next_unit_after_a_silence() {
    // `botbench sim ... next`: the unit lifted off (silent for 1.5 s), a fresh one placed.
    let mut wc = Sim::start(&["window-cleaner"]);
    let mut servo = Sim::start(&["servo-bus", "--servos", "0"]);
    let dir = tempfile::tempdir().unwrap();
    let presets = Path::new(env!("CARGO_MANIFEST_DIR")).join("presets");
    std::fs::copy(
        presets.join("servo-provision-plan.ron"),
        dir.path().join("servo-provision-plan.ron"),
    )
    .unwrap();
    let text = format!(
        r#"(version: 1, id: "auto-station",
    plans: {{
        "wc": (start: Auto, steps: [Identify(hardware: [3]), WriteResult]),
        "servo": (start: Auto, steps: [Provision(plan: "servo-provision-plan.ron")]),
    }},
    slots: [
        (name: "1", fixture: "WC", port: Path("{}"), profile: "window-cleaner", plan: "wc"),
        (name: "2", fixture: "Servos", port: Path("{}"), profile: "servo", plan: "servo"),
    ],
)"#,
        wc.path, servo.path
    );
    let bundle = dir.path().join("auto.ron");
    std::fs::write(&bundle, text).unwrap();
    let records = dir.path().join("records.sqlite");
    let bundle = bundle.display().to_string();
    let records = records.display().to_string();
    let args = [
        "station",
        &bundle,
        "--headless",
        "--json",
        "--records",
        &records,
    ];
    let ports = servo.serve_in(wc.ports().clone());
    let captured = Captured::default();
    let run = crate::support::cli::start_in_process(&args, &ports, &captured);
    let verdicts_of = |slot: &str| {
        captured
            .out()
            .lines()
            .filter_map(|l| serde_json::from_str::<Value>(l).ok())
            .filter(|d| d["event"] == "verdict" && d["slot"] == slot)
            .count()
    };
    let wait_for = |what: &str, done: &dyn Fn() -> bool| {
        let deadline = std::time::Instant::now() + crate::support::PATIENCE;
        while !done() {
            assert!(
                !run.is_finished() && std::time::Instant::now() < deadline,
                "{what}: {}{}",
                captured.out(),
                captured.err()
            );
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
    };
    // The first units start at once (Auto: a unit answers).
    wait_for("the first verdicts", &|| {
        verdicts_of("1") == 1 && verdicts_of("2") == 1
    });
    // The same unit still on the fixture is not tested again; the next one is.
    wc.type_line("next");
    servo.type_line("next");
    wait_for("the second units' verdicts", &|| {
        verdicts_of("1") == 2 && verdicts_of("2") == 2
    });
    captured.interrupt();
    let code = crate::support::cli::finish_in_process(run, &captured, "the station");
    assert_eq!(code, 130, "{}{}", captured.out(), captured.err());
    // Two units per slot, each PASS; the servos with their own serial numbers.
    let db = rusqlite::Connection::open(&records).unwrap();
    let servos: Vec<String> = db
        .prepare("SELECT serial FROM runs WHERE slot = '2' AND verdict = 'PASS' ORDER BY id")
        .unwrap()
        .query_map([], |r| r.get(0))
        .unwrap()
        .map(Result::unwrap)
        .collect();
    assert_eq!(servos.len(), 2, "{servos:?}");
    assert_ne!(servos[0], servos[1]);
    let wc_passed: i64 = db
        .query_row(
            "SELECT COUNT(*) FROM runs WHERE slot = '1' AND verdict = 'PASS'",
            [],
            |r| r.get(0),
        )
        .unwrap();
    assert_eq!(wc_passed, 2);
}

#[test]
fn a_scanner_that_is_its_own_device_starts_a_slot_with_the_code_it_sends() {
    let wc = Sim::start(&["window-cleaner"]);
    let dir = tempfile::tempdir().unwrap();
    let text = format!(
        r#"(version: 1, id: "scan-station",
    plans: {{ "wc": (start: Scan, steps: [Scan(pattern: "WC[0-9]{{6}}"), WriteResult]) }},
    slots: [(name: "1", fixture: "WC", port: Path("{}"), profile: "window-cleaner", plan: "wc")],
)"#,
        wc.path
    );
    let bundle = dir.path().join("scan.ron");
    std::fs::write(&bundle, text).unwrap();
    // What a serial barcode scanner sends: the code and a carriage return.
    let scanner = dir.path().join("scanner");
    std::fs::write(&scanner, "WC004711\r").unwrap();
    let records = dir.path().join("records.sqlite");
    let ran = run_in_process_into(
        &[
            "station",
            &bundle.display().to_string(),
            "--headless",
            "--json",
            "--once",
            "--records",
            &records.display().to_string(),
            "--scanner",
            &scanner.display().to_string(),
        ],
        wc.ports(),
        Captured::default(),
    );
    assert_eq!(ran.code, 0, "{}", ran.text());
    let docs = ran.json_lines();
    let v = docs.iter().find(|d| d["event"] == "verdict").unwrap();
    assert_eq!(
        (v["pass"].as_bool(), v["serial"].as_str()),
        (Some(true), Some("WC004711")),
        "{v}"
    );
    // A scanner that is not there is refused, naming it.
    let ran = run_in_process_into(
        &[
            "station",
            &bundle.display().to_string(),
            "--headless",
            "--once",
            "--records",
            &records.display().to_string(),
            "--scanner",
            "/dev/no-such-scanner",
        ],
        wc.ports(),
        Captured::default(),
    );
    assert_eq!(ran.code, 2, "{}", ran.text());
    assert!(
        ran.err.contains("--scanner /dev/no-such-scanner"),
        "{}",
        ran.text()
    );
}

/// Issue 25, item 2, the station's part: a board that reboots when its port opens (silent for
/// 1.5 s after each open) is identified on a slot whose bundle gives it a boot wait; on a slot
/// without one its first request goes to a board still booting, and the unit does not pass.
#[test]
fn a_slot_with_a_boot_wait_identifies_a_board_that_boots_when_its_port_opens() {
    let verdict = |boot_ms: &str, boot_wait: &str| {
        let sim = Sim::start(&["window-cleaner", "--boot-ms", boot_ms]);
        let dir = tempfile::tempdir().unwrap();
        let bundle = dir.path().join("boot.ron");
        std::fs::write(
            &bundle,
            format!(
                r#"(version: 1, id: "boot", plans: {{ "p": (start: Button, steps: [Identify(hardware: [3])]) }},
                    slots: [(name: "1", fixture: "F", port: Path("{}"), profile: "window-cleaner",
                             plan: "p"{boot_wait})])"#,
                sim.path
            ),
        )
        .unwrap();
        let records = dir.path().join("records.sqlite");
        let ran = sim.run_typing(
            &[
                "station",
                &bundle.display().to_string(),
                "--headless",
                "--json",
                "--once",
                "--records",
                &records.display().to_string(),
            ],
            "start\n",
        );
        let docs = ran.json_lines();
        let v = docs
            .iter()
            .find(|d| d["event"] == "verdict")
            .unwrap_or_else(|| panic!("no verdict: {}", ran.text()))
            .clone();
        (v["pass"].as_bool(), ran.text())
    };
    let (waited, text) = verdict("1500", ", boot_wait_ms: 2000");
    assert_eq!(waited, Some(true), "{text}");
    // Without the wait (a board booting for 10 s: however late this computer comes to it, the
    // first request finds it booting).
    let (hasty, text) = verdict("10000", "");
    assert_eq!(hasty, Some(false), "{text}");
}
