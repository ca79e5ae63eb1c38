//! Bad input at the command line's edges (issue 17): every value, name, option and file is
//! checked before the port is opened, refused with exit 2 and a message that names the real
//! problem and quotes at most a line or so of what was given.
//!
//! The port given is one that cannot be opened: a command that opened it before looking at its
//! input fails on the port instead of naming the bad input, so each case proves the order too.

use crate::support::cli::run;
use std::path::Path;

/// A port path that does not exist: opening it fails.
const NO_PORT: &str = "/nonexistent/botbench-edges-tty";

/// Stands for `--port NO_PORT` in a command line (the port options go before or after the
/// subcommand's name).
const P: &str = "@port";

/// `args` with [`P`] replaced by `--port NO_PORT`.
fn with_port<'a>(args: &[&'a str]) -> Vec<&'a str> {
    assert!(args.contains(&P), "{args:?} names no port");
    args.iter()
        .flat_map(|a| {
            if *a == P {
                vec!["--port", NO_PORT]
            } else {
                vec![*a]
            }
        })
        .collect()
}

/// Runs `args` (with `--port NO_PORT` for [`P`]) and asserts exit 2, a message holding every
/// one of `says`, and no word about the port (it was never opened).
fn refused_before_the_port(args: &[&str], says: &[&str]) -> String {
    let all = with_port(args);
    let ran = run(&all);
    let (code, out, err) = (ran.code, ran.out, ran.err);
    assert_eq!(
        code, 2,
        "{all:?}: exit {code}\nstdout: {out}\nstderr: {err}"
    );
    assert!(
        !err.contains(NO_PORT),
        "{all:?}: the port was opened before the input was checked: {err}"
    );
    for s in says {
        assert!(err.contains(s), "{all:?}: {err:?} does not say {s:?}");
    }
    assert!(out.is_empty(), "{all:?}: printed {out}");
    err
}

/// Runs `args` (with `--port NO_PORT` for [`P`]) and asserts that it got as far as the port:
/// its input was taken.
fn reaches_the_port(args: &[&str]) {
    let all = with_port(args);
    let ran = run(&all);
    let (code, err) = (ran.code, ran.err);
    assert_eq!(code, 2, "{all:?}: {err}");
    assert!(
        err.contains(NO_PORT),
        "{all:?}: refused before the port: {err}"
    );
}

#[test]
fn values_are_checked_before_the_port_is_opened() {
    // Item 1: servo write and tuya dp looked at the value after opening (Tuya after its
    // handshake).
    refused_before_the_port(
        &["servo", P, "write", "1", "assigned_id", "300"],
        &["assigned_id", "0 to 254"],
    );
    refused_before_the_port(
        &["servo", P, "write", "1", "no_such_param", "1"],
        &["no_such_param"],
    );
    refused_before_the_port(
        &["servo", P, "write", "1", "voltage", "5000"],
        &["read-only"],
    );
    refused_before_the_port(&["tuya", P, "dp", "power=maybe"], &["power", "on, off"]);
    refused_before_the_port(
        &["tuya", P, "dp", "nonsense=1"],
        &["no data point 'nonsense'"],
    );
    refused_before_the_port(&["tuya", P, "dp", "=1"], &["no NAME before the '='"]);
    refused_before_the_port(&["servo", P, "angle", "1", "999"], &["angle"]);
    refused_before_the_port(&["msp", P, "get", "NO_SUCH_COMMAND"], &["no command"]);
    // The same input, well formed, gets as far as the port.
    reaches_the_port(&["servo", P, "write", "1", "assigned_id", "3"]);
    reaches_the_port(&["tuya", P, "dp", "power=on"]);
}

#[test]
fn a_command_of_the_wrong_kind_is_refused_and_nothing_is_sent() {
    // Item 4: `msp watch MSP_SET_PWMVALUE` sent the Set with an empty payload.
    refused_before_the_port(
        &["msp", P, "watch", "MSP_SET_PWMVALUE"],
        &[
            "MSP_SET_PWMVALUE is a Set command",
            "Get or Telemetry",
            "its Get is MSP_GET_PWMVALUE",
        ],
    );
    refused_before_the_port(
        &["msp", P, "get", "MSP_SET_PWMVALUE"],
        &["is a Set command", "its Get is MSP_GET_PWMVALUE"],
    );
    refused_before_the_port(
        &["msp", P, "set", "MSP_GET_PWMVALUE", "pwmValue=1"],
        &["is a Get command", "its Set is MSP_SET_PWMVALUE"],
    );
    reaches_the_port(&["msp", P, "watch", "MSP_GET_PWMVALUE"]);
}

#[test]
fn messages_name_the_real_problem_and_the_allowed_values() {
    // Item 7, each as the issue found it.
    let e = refused_before_the_port(
        &[
            "msp",
            P,
            "set",
            "MSP_SET_PWMVALUE",
            "pwmValue=70",
            "pwmValue=80",
        ],
        &["'pwmValue' is given twice"],
    );
    assert!(!e.contains("has no field"), "{e}");
    let e = refused_before_the_port(
        &[
            "msp",
            P,
            "set",
            "MSP_SET_PWMVALUE",
            "pwmValue=99999999999999999999999",
        ],
        &["pwmValue", "0 to 100 %"],
    );
    assert!(!e.contains("255"), "the type's range, not the field's: {e}");
    refused_before_the_port(
        &["msp", P, "set", "MSP_SET_PWMVALUE", "pwmValue=1e400"],
        &["0 to 100 %"],
    );
    refused_before_the_port(
        &["msp", P, "set", "MSP_SET_PWMVALUE", "pwmValue="],
        &["no value given", "0 to 100 %"],
    );
    refused_before_the_port(
        &["msp", P, "set", "MSP_SET_PWMVALUE", "fan=1"],
        &["has no field 'fan'; its fields: pwmValue"],
    );
    let e = refused_before_the_port(&["tuya", P, "dp", "power=maybe"], &["'maybe'"]);
    assert!(!e.contains("not a number"), "a bool is not a number: {e}");
    refused_before_the_port(&["tuya", P, "dp", "power=on", "1=off"], &["given twice"]);
}

#[test]
fn numeric_options_out_of_range_are_refused_and_max_is_a_rate() {
    // Item 2: `--baud 0` was taken.
    for args in [
        &["msp", P, "--baud", "0", "version"][..],
        &["servo", P, "--baud", "99999999", "ping", "1"],
        &["msp", P, "--margin-ms", "0", "version"],
        &["tuya", P, "--wait", "0", "status"],
        &["msp", P, "watch", "MSP_GET_PWMVALUE", "--count", "0"],
    ] {
        let e = refused_before_the_port(args, &["out of range", "from"]);
        assert!(e.len() < 400, "{e}");
    }
    refused_before_the_port(&["servo", P, "ping", "255"], &["broadcast id", "0 to 254"]);
    // Item 3: the help of --poll-pipeline says `--rate max`; the parser takes it.
    reaches_the_port(&["msp", P, "watch", "MSP_GET_PWMVALUE", "--rate", "max"]);
    refused_before_the_port(
        &["msp", P, "watch", "MSP_GET_PWMVALUE", "--rate", "fast"],
        &["or max"],
    );
}

/// A file of `len` bytes of one junk line.
fn junk(dir: &Path, name: &str, len: usize) -> String {
    let path = dir.join(name);
    std::fs::write(&path, "Z".repeat(len)).unwrap();
    path.display().to_string()
}

#[test]
fn files_are_read_within_a_bound_and_messages_quote_a_line_at_most() {
    // Item 5: `preset apply /dev/zero` read until memory ran out; a 100 MB junk preset gave a
    // 104 MB message.
    let dir = crate::support::temp_dir();
    let big = junk(dir.path(), "big.ron", 3 << 20);
    let small = junk(dir.path(), "small.ron", 900 << 10);
    let plan = junk(dir.path(), "plan.ron", 900 << 10);
    let profile = junk(dir.path(), "junk-profile.ron", 3 << 20);
    let empty = junk(dir.path(), "empty.ron", 0);
    let cases: Vec<(Vec<&str>, &[&str])> = vec![
        (
            vec!["preset", "apply", P, "/dev/zero"],
            &["not a preset file", "character device"],
        ),
        (
            vec!["preset", "diff", P, &big],
            &["the file is 3 MiB; a preset is at most 1 MiB"],
        ),
        (vec!["preset", "apply", P, &small], &["small.ron"]),
        (vec!["preset", "apply", P, &empty], &["empty"]),
        (
            vec!["preset", "apply", P, dir.path().to_str().unwrap()],
            &["a folder"],
        ),
        (vec!["msp", P, "selftest", &plan], &["plan.ron"]),
        (
            vec!["msp", P, "selftest", "/dev/zero"],
            &["character device"],
        ),
        (
            vec!["servo", P, "provision", "/dev/zero"],
            &["character device"],
        ),
        (
            vec!["tuya", P, "ota", "/dev/zero"],
            &["not a firmware image file"],
        ),
        (
            vec!["msp", P, "--profile", &profile, "version"],
            &["a profile is at most 2 MiB"],
        ),
    ];
    for (args, says) in &cases {
        let e = refused_before_the_port(args, says);
        // The message quotes a line or so of the file, never the file.
        assert!(e.len() < 1000, "{args:?}: a message of {} bytes", e.len());
    }
}

#[test]
fn a_save_to_where_it_cannot_be_written_is_refused_before_the_device_is_read() {
    // Item 6: `preset save` to a folder read the whole device, then exited 1.
    let dir = crate::support::temp_dir();
    let folder = dir.path().display().to_string();
    let missing = dir.path().join("no/such/folder/p.ron");
    let trailing = format!("{folder}/new/");
    refused_before_the_port(&["preset", "save", P, &folder], &["folder"]);
    refused_before_the_port(
        &["preset", "save", P, missing.to_str().unwrap()],
        &["cannot write in the folder"],
    );
    refused_before_the_port(&["preset", "save", P, &trailing], &["folder"]);
    refused_before_the_port(&["preset", "save", P, "/dev/null"], &["character device"]);
    // A destination that can be written gets as far as the port, and leaves nothing behind.
    let fine = dir.path().join("p.ron");
    reaches_the_port(&["preset", "save", P, fine.to_str().unwrap()]);
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert!(left.is_empty(), "left behind: {left:?}");
}

#[test]
fn a_set_given_some_fields_keeps_the_devices_values_for_the_rest() {
    // Fields left out were written with the profile's defaults, over the device's tuning.
    let sim = crate::support::cli::Sim::start(&["window-cleaner"]);
    let msp = |args: &[&str]| {
        let mut all = vec!["msp", "--port", &sim.path, "--json"];
        all.extend(args);
        sim.run(&all)
    };
    let set = "MSP_SET_USE_FAN_LEVEL_DYNAMIC_COMP";
    let ran = msp(&["set", set, "pwmvalueMax=95", "pwmvalueMin=60"]);
    assert_eq!(ran.code, 0, "{ran:?}");
    // Only the minimum given: the maximum is the device's 95, not the profile's default 100.
    let ran = msp(&["set", set, "pwmvalueMin=70"]);
    assert_eq!(ran.code, 0, "{ran:?}");
    let fields = ran.json()["fields"].clone();
    let kept: Vec<(String, bool)> = fields
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            (
                f["field"].as_str().unwrap().to_string(),
                f["kept"].as_bool().unwrap(),
            )
        })
        .collect();
    assert_eq!(
        kept,
        [
            ("pwmvalueMax".to_string(), true),
            ("pwmvalueMin".to_string(), false)
        ]
    );
    let ran = msp(&["get", "MSP_GET_USE_FAN_LEVEL_DYNAMIC_COMP"]);
    assert_eq!(ran.code, 0, "{ran:?}");
    let values: Vec<i64> = ran.json()["fields"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["value"].as_i64().unwrap())
        .collect();
    assert_eq!(values, [95, 70]);
}

/// The port options go before or after the subcommand's name, as a technician types them; a
/// command without a port says how to give one.
#[test]
fn port_options_are_taken_after_the_subcommand_and_a_missing_port_is_named() {
    for args in [
        &["servo", "scan", "--port", NO_PORT][..],
        &["msp", "get", "MSP_GET_PWMVALUE", "--port", NO_PORT],
        &["tuya", "status", "--port", NO_PORT],
        // set-baud's own BAUD beside the port's --baud.
        &[
            "servo", "set-baud", "1", "57600", "--port", NO_PORT, "--baud", "9600",
        ],
        &[
            "servo", "--baud", "9600", "set-baud", "1", "57600", "--port", NO_PORT,
        ],
    ] {
        let ran = run(args);
        assert_eq!(ran.code, 2, "{args:?}: {ran:?}");
        assert!(
            ran.err.contains(NO_PORT),
            "{args:?} reached the port: {}",
            ran.err
        );
    }
    let ran = run(&["servo", "scan"]);
    assert_eq!(ran.code, 2, "{ran:?}");
    assert!(
        ran.err.contains("no port given: add --port PORT"),
        "{}",
        ran.err
    );
    // --poll-pipeline is MSP's alone.
    let ran = run(&["servo", "--help"]);
    assert!(!ran.out.contains("--poll-pipeline"), "{}", ran.out);
    assert!(run(&["msp", "--help"]).out.contains("--poll-pipeline"));
}

/// A latency timer out of range, or a port that does not exist, is refused as input (exit 2).
#[test]
fn a_latency_timer_to_set_is_checked_as_input() {
    for (args, says) in [
        (["/dev/null", "0"], "1 to 255 ms"),
        (["/dev/null", "256"], "1 to 255 ms"),
        (["/dev/null", "fast"], "1 to 255 ms"),
        ([NO_PORT, "1"], "there is no port"),
    ] {
        let mut all = vec!["ports", "--set-latency-timer"];
        all.extend(args);
        let ran = run(&all);
        assert_eq!(ran.code, 2, "{all:?}: {ran:?}");
        assert!(ran.err.contains(says), "{all:?}: {}", ran.err);
    }
}

#[test]
fn bench_refuses_a_case_it_does_not_have_and_runs_nothing() {
    let ran = run(&["bench", "--only", "servo-sacn"]);
    assert_eq!(ran.code, 2, "{}{}", ran.out, ran.err);
    assert!(
        ran.err.contains("'servo-sacn'") && ran.err.contains("servo-provision"),
        "{}",
        ran.err
    );
    assert!(ran.out.is_empty(), "{}", ran.out);
    // The field scan's case runs with --field only.
    let ran = run(&["bench", "--only", "field"]);
    assert_eq!(ran.code, 2, "{}{}", ran.out, ran.err);
    assert!(ran.err.contains("with --field only"), "{}", ran.err);
    assert!(ran.out.is_empty(), "{}", ran.out);
}
