//! A cancelled operation never reports success (issue 25, item 4a): Ctrl-C part of the way
//! through a batch ends it as "cancelled after N of M", exit 130, with what was and was not
//! written. The operator's Ctrl-C reaches a run in this process through
//! `Captured::interrupt`, as the process's own first Ctrl-C does.

use crate::support::PATIENCE;
use crate::support::cli::{Sim, finish_in_process, start_in_process};
use std::time::Instant;

fn preset(name: &str) -> String {
    format!("{}/presets/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// Runs `args` against `sim`, pressing Ctrl-C once stdout has `after` lines; `None` when the
/// run had ended before (a loaded machine can let a short batch finish first: that run proves
/// nothing about a cancel, and the caller runs again).
fn interrupted(sim: &Sim, args: &[&str], after: usize) -> Option<(u8, String, String)> {
    interrupted_once(sim, args, |c| c.out().lines().count() >= after)
}

/// As [`interrupted`], pressing Ctrl-C once `ready` holds of what the run has written.
fn interrupted_once(
    sim: &Sim,
    args: &[&str],
    ready: impl Fn(&botbench::cli::Captured) -> bool,
) -> Option<(u8, String, String)> {
    let captured = botbench::cli::Captured::default();
    let run = start_in_process(args, sim.ports(), &captured);
    let deadline = Instant::now() + PATIENCE;
    while !ready(&captured) {
        if run.is_finished() {
            let _ = finish_in_process(run, &captured, "the run");
            return None;
        }
        assert!(Instant::now() < deadline, "no output: {}", captured.err());
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    captured.interrupt();
    let code = finish_in_process(run, &captured, &format!("botbench {args:?}"));
    Some((code, captured.out(), captured.err()))
}

#[test]
fn a_preset_apply_cancelled_part_way_says_so_and_exits_130() {
    // Each answer waits for the adapter's 20 ms latency timer: the apply takes a while.
    let sim = Sim::start(&["window-cleaner", "--latency-timer-ms", "20"]);
    let factory = preset("window-cleaner-factory.ron");
    let args = ["preset", "apply", &factory, "--port", &sim.path];
    let (code, out, err) = (0..5)
        // The first command's name and its first check are printed: cancel then.
        .find_map(|_| interrupted(&sim, &args, 2))
        .expect("a run still under way when Ctrl-C came, in 5 tries");
    let text = format!("exit {code}\n--- stdout\n{out}--- stderr\n{err}");
    assert_eq!(code, 130, "{text}");
    assert!(!out.contains("every field verified"), "{text}");
    assert!(err.contains("cancelled after "), "{text}");
    assert!(
        err.contains("of 7 commands") && err.contains("not done: "),
        "says how many of the preset's commands were written, and which were not: {text}"
    );
}

/// A cancelled `preset apply --json` prints one JSON document (what was written and checked,
/// the error and the exit code), not its result and then an error document after it.
#[test]
fn a_preset_apply_cancelled_with_json_prints_one_document_saying_so() {
    let (sim, heard) = Sim::start_heard(&["window-cleaner", "--latency-timer-ms", "20"]);
    let factory = preset("window-cleaner-factory.ron");
    let args = ["preset", "apply", &factory, "--port", &sim.path, "--json"];
    // Ctrl-C once the device has heard more than the identification (CMD_VERSION and
    // CMD_BUILD_INFO, 6 bytes each): while the values are read first, or during the writes.
    let (code, out, err) = (0..5)
        .find_map(|_| {
            let from = heard.load(std::sync::atomic::Ordering::SeqCst);
            interrupted_once(&sim, &args, |_| {
                heard.load(std::sync::atomic::Ordering::SeqCst) > from + 12
            })
        })
        .expect("a run still under way when Ctrl-C came, in 5 tries");
    let text = format!("exit {code}\n--- stdout\n{out}--- stderr\n{err}");
    assert_eq!(code, 130, "{text}");
    let doc: serde_json::Value = serde_json::from_str(out.trim())
        .unwrap_or_else(|e| panic!("stdout is one JSON document ({e}): {text}"));
    assert_eq!(doc["verified"], false, "{text}");
    assert_eq!(doc["exit"], 130, "{text}");
    assert!(
        doc["error"]
            .as_str()
            .is_some_and(|e| e.starts_with("cancelled after ")),
        "{text}"
    );
}

#[test]
fn a_self_test_cancelled_part_way_says_which_steps_ran_and_exits_130() {
    let dir = crate::support::temp_dir();
    let plan = dir.path().join("plan.ron");
    // The corner step waits up to 10 minutes for the corners: the run is still under way
    // when Ctrl-C comes after the second step's line.
    std::fs::write(&plan, crate::support::selftest_plan(600_000)).unwrap();
    let sim = Sim::start(&["window-cleaner"]);
    let args = [
        "msp",
        "--port",
        &sim.path,
        "selftest",
        plan.to_str().unwrap(),
        "--yes",
    ];
    // The plan's line, the safe state's, then two steps.
    let (code, out, err) = (0..5)
        .find_map(|_| interrupted(&sim, &args, 4))
        .expect("a run still under way when Ctrl-C came, in 5 tries");
    let text = format!("exit {code}\n--- stdout\n{out}--- stderr\n{err}");
    assert_eq!(code, 130, "{text}");
    assert!(!out.contains("PASS: all"), "{text}");
    assert!(
        err.contains("cancelled after ") && err.contains(" of 9 steps"),
        "{text}"
    );
    assert!(
        err.contains("done: Gyro at rest") && err.contains("Corner switches"),
        "says which steps ran and which did not: {text}"
    );
}

#[test]
fn a_firmware_update_cancelled_part_way_says_what_was_sent_and_exits_130() {
    let dir = crate::support::temp_dir();
    let image = dir.path().join("fw.bin");
    // 64 KiB: some hundreds of packets, some seconds at 115200 baud.
    std::fs::write(&image, crate::support::image(64 * 1024)).unwrap();
    let sim = Sim::start(&["tuya-vacuum"]);
    let args = [
        "tuya",
        "--port",
        &sim.path,
        "ota",
        "--expect-version",
        "1.0.1",
        image.to_str().unwrap(),
    ];
    // The update is under way once it has said the firmware's size: Ctrl-C then.
    let (code, out, err) = interrupted_once(&sim, &args, |c| c.err().contains("firmware: "))
        .expect("the update still under way when Ctrl-C came");
    let text = format!("exit {code}\n--- stdout\n{out}--- stderr\n{err}");
    assert_eq!(code, 130, "{text}");
    assert!(!out.contains("update done"), "{text}");
    assert!(
        err.contains("cancelled after ")
            && err.contains(" packets")
            && err.contains("not done: bytes"),
        "says how far it got: {text}"
    );
}

#[test]
fn a_provisioning_cancelled_part_way_says_what_was_written_and_exits_130() {
    // Behind a 16 ms latency timer each exchange takes a tick: the parameters take a while.
    let sim = Sim::start(&["servo-bus", "--servos", "0", "--latency-timer-ms", "16"]);
    let plan = preset("servo-provision-plan.ron");
    let args = ["servo", "--port", &sim.path, "provision", &plan];
    // Its id is set and checked, its rate is being set: Ctrl-C then.
    let (code, out, err) = (0..5)
        .find_map(|_| interrupted_once(&sim, &args, |c| c.err().contains("set baud")))
        .expect("a run still under way when Ctrl-C came, in 5 tries");
    let text = format!("exit {code}\n--- stdout\n{out}--- stderr\n{err}");
    assert_eq!(code, 130, "{text}");
    assert!(
        err.contains("cancelled after 0 of 1 servos: servo 1 stopped at "),
        "{text}"
    );
    assert!(
        err.contains("written to it: id = 1") && err.contains("not done: the rest of its plan"),
        "says what was written and what was not: {text}"
    );
}

#[test]
fn the_wait_between_servos_leaves_on_ctrl_c() {
    // One fresh servo, never swapped: the wait for the second one would last for ever. The
    // bus is looked at every 10 minutes: only the cancel can end the wait in this test's time.
    let sim = Sim::start(&["servo-bus", "--servos", "0"]);
    let plan = preset("servo-provision-plan.ron");
    let args = [
        "servo",
        "--port",
        &sim.path,
        "provision",
        &plan,
        "--count",
        "2",
        "--wait-ms",
        "600000",
    ];
    let captured = botbench::cli::Captured::default();
    let run = start_in_process(&args, sim.ports(), &captured);
    let deadline = Instant::now() + PATIENCE;
    while !captured.err().contains("waiting for a new fresh servo") {
        assert!(
            !run.is_finished() && Instant::now() < deadline,
            "the first servo, then the wait: {}{}",
            captured.out(),
            captured.err()
        );
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    captured.interrupt();
    let code = finish_in_process(run, &captured, "provisioning");
    let text = format!("exit {code}\n{}{}", captured.out(), captured.err());
    assert_eq!(code, 130, "{text}");
    // The first servo's verdict was given (PASS, or on a loaded machine maybe FAIL: not what
    // this test is about), and the tally with it.
    assert!(
        captured.out().contains("servo 1/2"),
        "the first servo's verdict: {text}"
    );
    assert!(
        captured
            .err()
            .contains("cancelled after 1 of 2 servos, while waiting for servo 2: "),
        "{text}"
    );
}

#[test]
fn a_named_pipe_given_as_a_capture_is_refused_before_it_is_opened() {
    let dir = crate::support::temp_dir();
    let fifo = dir.path().join("capture.pcapng");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("runs mkfifo");
    assert!(made.success());
    let fifo = fifo.display().to_string();
    let sim = Sim::start(&["window-cleaner"]);
    // Opening a named pipe waits for its other end: both would hang without the check.
    let recording = sim.cli("msp", &["--capture", &fifo, "version"]);
    assert_ne!(recording.code, 0, "{}", recording.text());
    assert!(recording.err.contains("named pipe"), "{}", recording.text());
    let decoding = sim.run(&["frame", "decode", "--capture", &fifo]);
    assert_ne!(decoding.code, 0, "{}", decoding.text());
    assert!(decoding.err.contains("named pipe"), "{}", decoding.text());
}

/// Issue 25, 4c: `servo write ID assigned_id N` and `servo write ID baudrate B` go through the
/// checks of `set-id` and `set-baud`: no duplicate id is made, and the port follows a servo to
/// its new rate.
#[test]
fn an_id_or_baud_written_as_a_parameter_goes_through_set_id_and_set_baud() {
    let sim = Sim::start(&["servo-bus", "--servos", "1,2"]);
    // Id 2 is taken: refused before anything is written, as set-id refuses it.
    let dup = sim.cli("servo", &["write", "1", "assigned_id", "2"]);
    assert_ne!(dup.code, 0, "{}", dup.text());
    assert!(dup.err.contains("2"), "{}", dup.text());
    let scan = sim.cli("servo", &["--json", "scan", "--ids", "0-5"]);
    let ids: Vec<u64> = scan.json_docs()[0]["servos"]
        .as_array()
        .expect("servos")
        .iter()
        .filter_map(|s| s["id"].as_u64())
        .collect();
    assert_eq!(ids, vec![1, 2], "no duplicate id was made: {}", scan.text());
    // A free id is given and verified at the new id.
    let moved = sim.cli("servo", &["write", "1", "assigned_id", "7"]);
    assert_eq!(moved.code, 0, "{}", moved.text());
    let ping = sim.cli("servo", &["ping", "7"]);
    assert_eq!(ping.code, 0, "{}", ping.text());
    // A broadcast of an id would give every servo the same one: refused.
    let all = sim.cli(
        "servo",
        &["write", "255", "assigned_id", "9", "--broadcast"],
    );
    assert_eq!(all.code, 2, "{}", all.text());
    assert!(all.err.contains("set-id"), "{}", all.text());

    // The baud option as a parameter: the port follows servo 2 to 1 Mbaud and verifies it there,
    // as set-baud does (a plain write would leave it answering at a rate the port is not at).
    let fast = sim.cli("servo", &["write", "2", "baudrate", "8"]);
    assert_eq!(fast.code, 0, "{}", fast.text());
    assert!(
        fast.out.contains("b1000000") && fast.out.contains("verified"),
        "{}",
        fast.text()
    );
    let there = sim.cli("servo", &["--baud", "1000000", "ping", "2"]);
    assert_eq!(there.code, 0, "servo 2 at its new rate: {}", there.text());
    let before = sim.cli("servo", &["ping", "2"]);
    assert_ne!(before.code, 0, "servo 2 left 115200: {}", before.text());
    // An option the table lacks is refused before anything is sent, naming the table.
    let bad = sim.cli(
        "servo",
        &["--baud", "1000000", "write", "2", "baudrate", "9"],
    );
    assert_eq!(bad.code, 2, "{}", bad.text());
    assert!(bad.err.contains("b1000000 (8)"), "{}", bad.text());
    let still = sim.cli("servo", &["--baud", "1000000", "ping", "2"]);
    assert_eq!(still.code, 0, "nothing was sent: {}", still.text());
    // The rate itself, as set-baud takes it, is its option: back to 115200.
    let back = sim.cli(
        "servo",
        &["--baud", "1000000", "write", "2", "baudrate", "115200"],
    );
    assert_eq!(back.code, 0, "{}", back.text());
    assert!(back.out.contains("b115200"), "{}", back.text());
    let home = sim.cli("servo", &["ping", "2"]);
    assert_eq!(home.code, 0, "servo 2 back at 115200: {}", home.text());
    // A baud option broadcast would scatter the bus: refused, naming the checked way.
    let all = sim.cli("servo", &["write", "255", "baudrate", "8", "--broadcast"]);
    assert_eq!(all.code, 2, "{}", all.text());
    assert!(all.err.contains("set-baud"), "{}", all.text());
}

/// Issue 25, 4d: with the window cleaner's profile, a device that identifies as hardware 0x04
/// (the solar cleanbot) gets nothing written, with or without `--strict`, and is not called
/// unpowered.
#[test]
fn a_device_of_another_kind_than_its_profile_is_refused_before_any_write() {
    let sim = Sim::start(&["solar-cleanbot"]);
    for strict in [false, true] {
        let mut args = vec!["msp", "--port", &sim.path];
        if strict {
            args.push("--strict");
        }
        args.extend(["set", "MSP_SET_PWMVALUE", "pwmValue=40"]);
        let run = sim.run(&args);
        assert_eq!(run.code, 1, "{}", run.text());
        assert!(
            run.err.contains("identifies as hardware 0x04")
                && run
                    .err
                    .contains("profile window-cleaner is for hardware 0x03"),
            "{}",
            run.text()
        );
        assert!(!run.err.contains("powered"), "{}", run.text());
    }
    // What it is can still be asked.
    let version = sim.cli("msp", &["version"]);
    assert_eq!(version.code, 0, "{}", version.text());
}

/// Issue 29, item 9: a scan hands out each servo once its details are read, not when its baud
/// rate is done, so Ctrl-C part way prints the servos found before it, says how far the scan
/// got, and exits 130. Servo 1 answers cleanly; ids 6 to 9 each have two servos on them, whose
/// answers collide and are asked again one by one (each answer waiting for the adapter's 20 ms
/// latency timer): Ctrl-C comes while those are asked, after servo 1's row.
#[test]
fn a_servo_scan_cancelled_part_way_prints_the_servos_found_and_exits_130() {
    let sim = Sim::start(&[
        "servo-bus",
        "--servos",
        "1,6,6,7,7,8,8,9,9",
        "--latency-timer-ms",
        "20",
    ]);
    let args = ["servo", "--port", &sim.path, "scan", "--ids", "0-20"];
    let (code, out, err) = (0..5)
        // The table's header and servo 1's row: cancel then.
        .filter_map(|_| interrupted(&sim, &args, 2))
        // A Ctrl-C that came after the last step that looks at it proves nothing: again.
        .find(|(code, out, _)| *code != 0 || !out.contains(" found in "))
        .expect("a scan still under way when Ctrl-C came, in 5 tries");
    let text = format!("exit {code}\n--- stdout\n{out}--- stderr\n{err}");
    assert_eq!(code, 130, "{text}");
    let row_1 = out
        .lines()
        .find(|l| l.split_whitespace().next() == Some("1"))
        .unwrap_or_else(|| panic!("servo 1's row: {text}"));
    assert!(row_1.ends_with("ok"), "{text}");
    assert!(
        !out.contains(" found in "),
        "no summary of a whole scan: {text}"
    );
    assert!(
        err.contains("scan cancelled after ") && err.contains(" of 21 ids: 1 servo(s) found"),
        "{text}"
    );
}

/// Issue 29, item 9: the scan's progress bar is for a person at a terminal: a run whose stderr
/// is a pipe (a script, a log) gets none of it, neither drawn nor as escape codes, in text or
/// with `--json`.
#[test]
fn a_piped_servo_scan_prints_no_progress_bar() {
    // The command is a process of its own (its stderr a pipe is what is under test), and so is
    // its device: a loaded machine can hold either up, so the margin is PROCESS_MARGIN_MS, and
    // the scan asks few ids (each silent one waits the margin out once per rate).
    let sim = crate::support::cli::SimProcess::start(&["servo-bus", "--servos", "1,2"]);
    let margin = crate::support::cli::PROCESS_MARGIN_MS;
    for json in [false, true] {
        let mut args = vec!["servo", "--port", &sim.path, "--margin-ms", margin];
        if json {
            args.push("--json");
        }
        args.extend(["scan", "--ids", "0-3", "--bauds", "1000000,115200"]);
        let run = crate::support::cli::run_watched(&args);
        assert_eq!(run.code, 0, "{}", run.text());
        assert!(run.out.contains('2'), "{}", run.text());
        for bar in ["\u{1b}", "\r", "=>", " ids, ", " left"] {
            assert!(!run.err.contains(bar), "{bar:?} on a pipe: {}", run.text());
        }
    }
}

#[test]
fn a_port_that_vanishes_during_the_wait_between_servos_ends_it_saying_so() {
    // One fresh servo, never swapped: the wait for the second one would last for ever; the
    // adapter is pulled during it. The bus is looked at every 10 minutes: the wait must see the
    // port go between two looks (it once noticed only at the next look).
    let mut sim = Sim::start(&["servo-bus", "--servos", "0"]);
    let plan = preset("servo-provision-plan.ron");
    let path = sim.path.clone();
    let args = [
        "servo",
        "--port",
        &path,
        "provision",
        &plan,
        "--count",
        "2",
        "--wait-ms",
        "600000",
    ];
    let captured = botbench::cli::Captured::default();
    let run = start_in_process(&args, sim.ports(), &captured);
    let deadline = Instant::now() + PATIENCE;
    while !captured.err().contains("waiting for a new fresh servo") {
        assert!(
            !run.is_finished() && Instant::now() < deadline,
            "the first servo, then the wait: {}{}",
            captured.out(),
            captured.err()
        );
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    sim.vanish_now();
    let code = finish_in_process(run, &captured, "provisioning");
    let text = format!("exit {code}\n{}{}", captured.out(), captured.err());
    assert_eq!(code, 1, "{text}");
    assert!(
        captured
            .err()
            .contains("link lost while waiting for servo 2 of 2: "),
        "{text}"
    );
    assert!(captured.err().contains(&path), "names the port: {text}");
}

/// Issue 25, 4a: the tuning panel's Write (ops::tuning::write_commands, as the window runs it)
/// cancelled after its first command ends as "cancelled after 1 of 3 commands", naming what was
/// written and what was not, and the device holds only the first.
#[test]
fn tuning_writes_cancelled_after_the_first_command_say_so_and_write_no_more() {
    use botbench::ops::{Cancel, Device, OpError, Progress, Run, tuning};
    use botbench::profile::Input;
    let p = crate::support::profile("window-cleaner");
    let wc = crate::support::serve(crate::support::window_cleaner());
    let link = crate::support::connect(&wc, &p);
    let text = |f: &str, v: &str| (f.to_string(), Input::Text(v.into()));
    let writes: Vec<tuning::SetWrite> = vec![
        (220, vec![text("pwmValue", "60")]),
        (
            221,
            vec![text("pwmvalueMax", "95"), text("pwmvalueMin", "70")],
        ),
        (
            223,
            vec![text("minPwmValue", "50"), text("upMinPwmValue", "55")],
        ),
    ];
    let cancel = Cancel::new();
    let c2 = cancel.clone();
    let mut run = Run::new(&cancel, |pr: Progress| {
        if pr.done == 1 {
            c2.cancel();
        }
    });
    let mut seen = Vec::new();
    let e = tuning::write_commands(
        Device::new(&link.client(), &p),
        &writes,
        &mut run,
        &mut |id, r| seen.push((id, r.is_ok())),
    )
    .unwrap_err();
    let OpError::CancelledAfter {
        done,
        total,
        done_items,
        not_done,
        ..
    } = &e
    else {
        panic!("not a cancel after some: {e:?}");
    };
    assert_eq!((*done, *total), (1, 3), "{e}");
    assert_eq!(done_items, &["MSP_SET_PWMVALUE"], "{e}");
    assert_eq!(
        not_done,
        &["MSP_SET_USE_FAN_LEVEL_DYNAMIC_COMP", "MSP_SET_MOTOR_VALUE"],
        "{e}"
    );
    assert!(
        e.to_string().starts_with("cancelled after 1 of 3 commands"),
        "{e}"
    );
    assert_eq!(
        seen,
        [(220, true)],
        "the window saw the first verified only"
    );
    let sim = wc.sim();
    assert_eq!(sim.param("pwmValue"), Some(60));
    assert_eq!(sim.param("pwmvalueMax"), Some(100), "not written");
    assert_eq!(sim.param("minPwmValue"), Some(75), "not written");
}

/// Issue 25, 4a: the servo parameter table's Write (ops::servo::write_params, as the window
/// runs it) stops at a cancel between parameters: the ones after it are not written.
#[test]
fn a_servo_parameter_batch_cancelled_part_way_writes_no_more() {
    use botbench::ops::{Cancel, Device, Progress, Run, servo};
    use botbench::sim::servo_bus::SimServo;
    let bench = crate::support::servo::Bench::new(vec![
        SimServo::fresh(31)
            .with_id(1)
            .with_param(41, 80)
            .with_param(42, 9000)
            .with_param(43, 2000),
    ]);
    let cancel = Cancel::new();
    let c2 = cancel.clone();
    // Progress names each parameter as its write begins: cancel as the second begins.
    let mut run = Run::new(&cancel, |pr: Progress| {
        if pr.done == 1 {
            c2.cancel();
        }
    });
    let values = [(41, 70), (42, 12_000), (43, 3000)];
    let checks = servo::write_params(
        Device::new(&bench.client(), &bench.profile),
        1,
        &values,
        &mut run,
    );
    let written: Vec<u8> = checks.iter().map(|(id, _)| *id).collect();
    assert_eq!(
        written,
        [41, 42],
        "the one under way when the cancel came ends, no more"
    );
    assert!(
        checks.iter().all(|(_, c)| matches!(c, Ok(c) if c.ok())),
        "{checks:?}"
    );
    let servo = bench.servo(31);
    assert_eq!(
        (servo.param(41), servo.param(42), servo.param(43)),
        (Some(70), Some(12_000), Some(2000)),
        "the third is as it was"
    );
}
