//! The command line explains itself (issue 29, items 5-12): a command the device does not
//! answer says so and checks first that the device is there; errors name commands by name;
//! a profile can be looked at from the command line, and an unknown name gets the nearest ones.

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

#[test]
fn profiles_show_lists_commands_fields_and_data_points() {
    let ran = crate::support::cli::run(&["profiles", "show", "window-cleaner"]);
    assert_eq!(ran.code, 0, "{ran:?}");
    let line = |needle: &str| {
        ran.out
            .lines()
            .find(|l| l.contains(needle))
            .unwrap_or_else(|| panic!("no line with {needle}: {}", ran.out))
            .to_string()
    };
    let get = line("MSP_GET_PWMVALUE");
    assert!(get.trim_start().starts_with("130"), "{get}");
    assert!(
        get.contains("Get") && get.contains("its Set: MSP_SET_PWMVALUE"),
        "{get}"
    );
    let field = line("pwmValue");
    assert!(
        field.contains("U8") && field.contains("%"),
        "type and unit: {field}"
    );

    let ran = crate::support::cli::run(&["profiles", "show", "tuya-vacuum", "--json"]);
    assert_eq!(ran.code, 0, "{ran:?}");
    let doc = ran.json();
    let dps = doc["data_points"].as_array().unwrap();
    assert!(!dps.is_empty(), "{doc}");
    let power = dps.iter().find(|d| d["dpid"] == 1).unwrap();
    assert_eq!(power["type"], "Bool", "{power}");
    assert!(doc["commands"].as_array().unwrap().len() > 3, "{doc}");

    let ran = crate::support::cli::run(&["profiles", "show", "servo", "--json"]);
    let doc = ran.json();
    let params = doc["params"].as_array().unwrap();
    assert!(
        params.iter().any(|p| p["field"]["ident"] == "voltage"),
        "{doc}"
    );

    let ran = crate::support::cli::run(&["profiles", "show", "no-such"]);
    assert_eq!(ran.code, 2, "{ran:?}");
    assert!(ran.err.contains("no profile 'no-such'"), "{ran:?}");
}

#[test]
fn an_unknown_command_suggests_the_nearest_names_and_points_to_profiles_show() {
    let ran = crate::support::cli::run(&[
        "msp",
        "--port",
        "/nonexistent/botbench-tty",
        "get",
        "MSP_GET_PWMVALU",
    ]);
    assert_eq!(ran.code, 2, "{ran:?}");
    assert!(
        ran.err
            .contains("has no command 'MSP_GET_PWMVALU'; did you mean MSP_GET_PWMVALUE?"),
        "{ran:?}"
    );
    assert!(
        ran.err
            .contains("`botbench profiles show window-cleaner` lists its commands"),
        "{ran:?}"
    );
    // A part of a name: every command holding it.
    let ran = crate::support::cli::run(&["frame", "encode", "msp", "pwmvalue"]);
    assert_eq!(ran.code, 2, "{ran:?}");
    assert!(
        ran.err
            .contains("did you mean MSP_GET_PWMVALUE or MSP_SET_PWMVALUE?"),
        "{ran:?}"
    );
    // Nothing near: no guess.
    let ran = crate::support::cli::run(&["frame", "encode", "msp", "XYZZY_QUUX_FROB"]);
    assert!(!ran.err.contains("did you mean"), "{ran:?}");
}

#[test]
fn msp_follows_the_device_it_meets_without_a_profile() {
    let sim = Sim::start(&["solar-cleanbot"]);
    // A solar name, and no --profile: the default window cleaner's names do not hold it, the
    // device says it is 0x04, the solar profile takes it.
    let ran = sim.cli("msp", &["get", "CMD_BATTERY_STATE"]);
    assert_eq!(ran.code, 0, "{ran:?}");
    assert!(
        ran.err.contains(
            "botbench: the device identifies as hardware 0x04: using profile solar-cleanbot"
        ),
        "{ran:?}"
    );
    assert!(ran.out.contains("BATTERY_OK"), "{ran:?}");
    let ran = sim.cli("msp", &["version"]);
    assert_eq!(ran.code, 0, "{ran:?}");
    assert!(ran.err.contains("using profile solar-cleanbot"), "{ran:?}");

    // The window cleaner is the default's own device: nothing said.
    let wc = Sim::start(&["window-cleaner"]);
    let ran = wc.cli("msp", &["get", "MSP_GET_PWMVALUE"]);
    assert_eq!(ran.code, 0, "{ran:?}");
    assert!(!ran.err.contains("using profile"), "{ran:?}");

    // A name no MSP profile has is refused before the port is opened.
    let ran = crate::support::cli::run(&[
        "msp",
        "--port",
        "/nonexistent/botbench-tty",
        "get",
        "CMD_BATTERY_STATEX",
    ]);
    assert_eq!(ran.code, 2, "{ran:?}");
    assert!(!ran.err.contains("/nonexistent"), "{ran:?}");

    // A board no profile claims: said with the profiles and their codes.
    let odd = Sim::start(&["window-cleaner", "--hardware-code", "0x09"]);
    let ran = odd.cli("msp", &["version"]);
    assert_eq!(ran.code, 1, "{ran:?}");
    assert!(
        ran.err
            .contains("the device identifies as hardware 0x09, which no profile claims"),
        "{ran:?}"
    );
    assert!(
        ran.err.contains("window-cleaner 0x03") && ran.err.contains("solar-cleanbot 0x04"),
        "{ran:?}"
    );
}

#[test]
fn without_a_display_the_window_says_so_and_exits_2() {
    for args in [&[][..], &["gui", "--demo", "solar-cleanbot"][..]] {
        let mut c = crate::support::cli::botbench(args);
        c.env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .env_remove("WAYLAND_SOCKET");
        let ran = crate::support::cli::output(&mut c);
        assert_eq!(ran.code, 2, "{args:?}: {ran:?}");
        assert!(
            ran.err.starts_with(
                "botbench: no display: the window needs X11 or Wayland; the command line works \
                 without one (botbench --help)"
            ),
            "{args:?}: {ran:?}"
        );
        assert!(
            !ran.err.contains(".cargo"),
            "no dependency's source path: {ran:?}"
        );
    }
}

#[test]
fn a_capture_is_not_written_over_unless_forced() {
    let dir = crate::support::temp_dir();
    let file = dir.path().join("session.pcapng");
    let file = file.to_str().unwrap();
    let sim = Sim::start(&["window-cleaner"]);
    let ran = sim.cli("msp", &["--capture", file, "version"]);
    assert_eq!(ran.code, 0, "{ran:?}");
    let first = std::fs::read(file).unwrap();
    let ran = sim.cli("msp", &["--capture", file, "ping"]);
    assert_eq!(ran.code, 2, "{ran:?}");
    assert!(
        ran.err.contains("the file exists; --force writes over it"),
        "{ran:?}"
    );
    assert_eq!(
        std::fs::read(file).unwrap(),
        first,
        "the earlier capture is kept"
    );
    let ran = sim.cli("msp", &["--capture", file, "--force", "ping"]);
    assert_eq!(ran.code, 0, "{ran:?}");
    assert_ne!(
        std::fs::read(file).unwrap(),
        first,
        "written over when forced"
    );
}

#[test]
fn the_self_test_says_its_safe_state_before_the_first_step() {
    let sim = Sim::start(&["window-cleaner"]);
    let ran = sim.cli(
        "msp",
        &["selftest", "presets/window-cleaner-selftest.ron", "--yes"],
    );
    let lines: Vec<&str> = ran.out.lines().collect();
    let safe = lines
        .iter()
        .position(|l| l.starts_with("safe state before the first step: "))
        .unwrap_or_else(|| panic!("no safe state line: {ran:?}"));
    let first_step = lines
        .iter()
        .position(|l| l.starts_with("PASS ") || l.starts_with("FAIL "))
        .unwrap_or_else(|| panic!("no step line: {ran:?}"));
    assert!(safe < first_step, "{ran:?}");
}

#[test]
fn tuya_status_columns_stay_aligned_for_long_names() {
    let sim = Sim::start(&[
        "tuya-vacuum",
        "--report-unknown-dp",
        "99:value:50",
        "--report-unknown-dp",
        "101:bool:1",
    ]);
    let ran = sim.cli("tuya", &["status"]);
    assert_eq!(ran.code, 0, "{ran:?}");
    let column = |needle: &str, value: &str| {
        let line = ran.out.lines().find(|l| l.contains(needle)).unwrap();
        line.find(value).unwrap_or_else(|| panic!("{line}"))
    };
    assert_eq!(
        column("dp 99 (not", "value 50"),
        column("dp 101 (not", "bool 1"),
        "{}",
        ran.out
    );
    let lines: Vec<&str> = ran
        .out
        .lines()
        .take_while(|l| !l.starts_with("not in"))
        .collect();
    let starts: std::collections::BTreeSet<usize> = lines
        .iter()
        .filter(|l| l.contains(") "))
        .filter_map(|l| {
            l.find(") ")
                .map(|i| i + 2 + l[i + 2..].len() - l[i + 2..].trim_start().len())
        })
        .collect();
    assert_eq!(starts.len(), 1, "one column of values: {}", ran.out);
}

#[test]
fn bench_says_times_in_ms_and_speed_as_a_share_of_the_wire_limit() {
    let ran = crate::support::cli::run(&["bench", "--only", "tuya-handshake"]);
    assert_eq!(ran.code, 0, "{ran:?}");
    for line in ran.out.lines() {
        assert!(line.contains(" ms  wire "), "{line}");
        assert!(line.contains(" of the wire limit "), "{line}");
        assert!(!line.contains(" s ") && !line.contains("ratio"), "{line}");
    }
    assert!(ran.out.lines().count() >= 2, "{ran:?}");
}

#[test]
fn completions_manpage_and_a_default_port_from_botbench_port() {
    for shell in ["bash", "zsh", "fish", "powershell"] {
        let ran = crate::support::cli::run(&["completions", shell]);
        assert_eq!(ran.code, 0, "{shell}: {ran:?}");
        assert!(ran.out.contains("botbench"), "{shell}: {ran:?}");
        assert!(
            ran.out.contains("profiles"),
            "{shell}: subcommands: {ran:?}"
        );
    }
    let ran = crate::support::cli::run(&["manpage"]);
    assert_eq!(ran.code, 0, "{ran:?}");
    assert!(
        ran.out.starts_with(".ie") || ran.out.contains(".TH botbench"),
        "{ran:?}"
    );
    let ran = crate::support::cli::run(&["--help"]);
    assert!(ran.out.contains("BOTBENCH_PORT"), "said in --help: {ran:?}");

    // The port from the environment (a child process: the variable is its own).
    // Both are processes of their own, which a loaded machine can hold up: the margin is
    // PROCESS_MARGIN_MS (the port's source is under test here, not the device's timing).
    let sim = crate::support::cli::SimProcess::start(&["window-cleaner"]);
    let margin = crate::support::cli::PROCESS_MARGIN_MS;
    let mut c = crate::support::cli::botbench(["msp", "ping", "--margin-ms", margin]);
    c.env("BOTBENCH_PORT", &sim.path);
    let ran = crate::support::cli::output(&mut c);
    assert_eq!(ran.code, 0, "{ran:?}");
    assert!(ran.out.contains("answered in"), "{ran:?}");
    let ran = crate::support::cli::run(&["msp", "ping"]);
    assert_eq!(ran.code, 2, "{ran:?}");
    assert!(ran.err.contains("or set BOTBENCH_PORT"), "{ran:?}");

    // Without either, the window's last port, when it was a port (a child process with its
    // own data folder, holding what the window saves).
    let data = tempfile::tempdir().expect("a temporary folder");
    let remember = |target: botbench::ui::Target| {
        let settings = botbench::ui::Settings {
            target,
            ..Default::default()
        };
        let saved = ron::to_string(&settings).expect("settings as RON");
        let kv = std::collections::HashMap::from([(eframe::APP_KEY.to_string(), saved)]);
        std::fs::create_dir_all(data.path().join("botbench")).expect("the data folder");
        std::fs::write(
            data.path().join("botbench/app.ron"),
            ron::to_string(&kv).expect("storage as RON"),
        )
        .expect("app.ron written");
    };
    let ping = || {
        let mut c = crate::support::cli::botbench(["msp", "ping", "--margin-ms", margin]);
        c.env_remove("BOTBENCH_PORT")
            .env("XDG_DATA_HOME", data.path());
        crate::support::cli::output(&mut c)
    };
    remember(botbench::ui::Target::Port(sim.path.clone()));
    let ran = ping();
    assert_eq!(ran.code, 0, "{ran:?}");
    assert!(ran.out.contains("answered in"), "{ran:?}");
    assert!(ran.err.contains("the window's last port"), "said: {ran:?}");
    // The built-in simulator is not a port: the command line asks for one.
    remember(botbench::ui::Target::Demo("window-cleaner".into()));
    let ran = ping();
    assert_eq!(ran.code, 2, "{ran:?}");
    assert!(ran.err.contains("no port given"), "{ran:?}");
}

/// A watch that lost some of its polls (a lossy line) says how many at its end, beside each
/// failure said as it came; it fails only when nothing answered.
#[test]
fn a_watch_that_lost_some_polls_says_how_many_at_its_end() {
    let sim = Sim::start(&["window-cleaner", "--drop", "0.3", "--seed", "7"]);
    let ran = sim.cli(
        "msp",
        &[
            "--margin-ms",
            "5",
            "watch",
            "MSP_GET_PWMVALUE",
            "--count",
            "16",
        ],
    );
    assert_eq!(ran.code, 0, "some polls answered: {ran:?}");
    let failed = ran.out.lines().filter(|l| l.contains(" !")).count();
    assert!(failed > 0 && failed < 16, "{ran:?}");
    let last = ran.err.lines().last().unwrap_or_default();
    assert_eq!(
        last,
        format!("botbench: {failed} of 16 polls had no answer"),
        "{ran:?}"
    );
}
