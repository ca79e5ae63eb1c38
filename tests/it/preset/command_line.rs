//! The `botbench preset` command line against files and the simulator.

use super::*;

// ---- The command line ----

/// `botbench` with `args`: exit code, stdout, stderr.
fn botbench(args: &[&str]) -> (i32, String, String) {
    let ran = cli::run(args);
    (ran.code, ran.out, ran.err)
}

#[test]
fn cli_preset_apply_refuses_a_bad_file_before_opening_the_port() {
    let dir = temp_dir();
    let bad = dir.path().join("bad.ron");
    let text = factory_text().replacen(r#""pwmValue": "85""#, r#""pwmValue": "101""#, 1);
    let line = text.lines().position(|l| l.contains(r#""101""#)).unwrap() + 1;
    std::fs::write(&bad, &text).unwrap();
    let bad = bad.to_str().unwrap();
    // The port does not exist: the error must be the file's, not the port's.
    let (code, _, err) = botbench(&[
        "preset",
        "apply",
        bad,
        "--port",
        "/dev/botbench-no-such-port",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains(&format!("bad.ron:{line}:13: MSP_SET_PWMVALUE")),
        "{err}"
    );
    assert!(err.contains("101 is out of range"), "{err}");
    assert!(!err.contains("botbench-no-such-port"), "{err}");

    // A real device is left as it was.
    let wc = serve_plain(crate::support::window_cleaner(), Faults::default());
    let (code, _, err) = botbench(&["preset", "apply", bad, "--port", wc.path()]);
    assert_eq!(code, 2, "{err}");
    assert_eq!(wc.sim().param("pwmValue"), Some(85));
    assert_eq!(wc.sim().param("gyroThreshold"), Some(100));

    // Malformed RON and a missing file are exit 2 as well.
    let broken = dir.path().join("broken.ron");
    std::fs::write(&broken, "(version: 1, profile: \"window-cleaner\"").unwrap();
    let (code, _, err) = botbench(&[
        "preset",
        "apply",
        broken.to_str().unwrap(),
        "--port",
        "/dev/null",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("broken.ron:1:"), "{err}");
    let (code, _, err) = botbench(&[
        "preset",
        "diff",
        dir.path().join("none.ron").to_str().unwrap(),
        "--port",
        "/dev/null",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("cannot read"), "{err}");
}

#[test]
fn cli_preset_save_diff_and_apply_against_the_simulator() {
    let sim = Sim::start(&["window-cleaner"]);
    let port = sim.path.as_str();
    // Against the simulator, the command line runs in this process, in lockstep with it.
    let botbench = |args: &[&str]| {
        let ran = sim.run(args);
        (ran.code, ran.out, ran.err)
    };
    let dir = temp_dir();
    let tuned = dir.path().join("tuned.ron");
    let tuned_s = tuned.to_str().unwrap();

    let (code, out, err) = botbench(&[
        "preset", "save", tuned_s, "--port", port, "--note", "line 3",
    ]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        out.contains("saved 8 commands (25 fields) from hw 0x03 fw 1.4.2"),
        "{out}"
    );
    let p = profile("window-cleaner");
    let saved = Preset::load(&tuned, &p).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(saved.preset.note, "line 3");

    // The factory preset matches a factory-fresh simulator.
    let (code, out, err) = botbench(&["preset", "diff", FACTORY, "--port", port]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        out.contains("the device holds the preset (22 fields)"),
        "{out}"
    );

    // Tune the fan and apply.
    let text = std::fs::read_to_string(&tuned).unwrap().replacen(
        r#""pwmValue": "85""#,
        r#""pwmValue": "90""#,
        1,
    );
    std::fs::write(&tuned, text).unwrap();
    let (code, out, err) = botbench(&["preset", "apply", tuned_s, "--port", port]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        out.contains("pwmValue") && out.contains("90 %  verified"),
        "{out}"
    );
    assert!(!out.contains("MISMATCH"), "{out}");
    assert_eq!(out.matches("verified").count(), 26, "{out}"); // 25 fields + the summary
    assert!(!out.contains("AUTO_TEST"), "{out}");

    // Now the factory preset differs in one field: exit 1, and JSON says which.
    let (code, out, err) = botbench(&["preset", "diff", FACTORY, "--port", port, "--json"]);
    assert_eq!(code, 1, "{out}{err}");
    let doc: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(doc["differing"], 1);
    let row = doc["rows"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["differs"] == true)
        .unwrap();
    assert_eq!(row["field"], "pwmValue");
    assert_eq!(row["device"], "90");

    // Back to the factory values.
    let (code, out, err) = botbench(&["preset", "apply", FACTORY, "--port", port, "--json"]);
    assert_eq!(code, 0, "{out}{err}");
    let doc: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(doc["verified"], true);
    assert_eq!(doc["commands"].as_array().unwrap().len(), 7);
    let (code, _, _) = botbench(&["preset", "diff", FACTORY, "--port", port]);
    assert_eq!(code, 0);

    // A preset for another profile is refused with the reason.
    let solar = dir.path().join("solar.ron");
    std::fs::write(
        &solar,
        factory_text().replacen(r#""window-cleaner""#, r#""solar-cleanbot""#, 1),
    )
    .unwrap();
    let (code, _, err) = botbench(&["preset", "apply", solar.to_str().unwrap(), "--port", port]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("this preset is for solar-cleanbot; the connected device uses window-cleaner"),
        "{err}"
    );
}

#[test]
fn a_preset_holding_a_units_own_state_is_refused_where_it_names_it() {
    // A golden unit's preset saved before the profile marked what is tunable: it carries the
    // unit's auto-test result, which must not be copied onto the next unit.
    let p = profile("window-cleaner");
    let text = factory_text().replacen(
        "    values: {\n",
        "    values: {\n        \"MSP_SET_AUTO_TEST_RESULT\": {\"result\": \"1\"},\n",
        1,
    );
    let line = text
        .lines()
        .position(|l| l.contains("\"MSP_SET_AUTO_TEST_RESULT\": {"))
        .unwrap()
        + 1;
    let err = parse_err(&text, &p).to_string();
    assert!(err.contains(&format!(":{line}:")), "{err}");
    assert!(
        err.contains("MSP_SET_AUTO_TEST_RESULT is not tunable"),
        "{err}"
    );
    // The factory defaults and a capture never name it.
    let defaults = Preset::defaults(&p, "");
    assert!(
        defaults
            .values
            .iter()
            .all(|v| !v.command.contains("AUTO_TEST"))
    );
}
