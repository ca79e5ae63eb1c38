//! The production self-test against the simulated window cleaner on a pseudo-terminal.

use botbench::i18n::Lang;
use botbench::link::{Link, LinkOptions};
use botbench::ops::Cancel;
use botbench::ops::selftest::{self, Plan, Report};
use botbench::ops::{Device, Run};
use botbench::profile::{Input, Profile};
use botbench::sim::window_cleaner::{Fault, Motor, WindowCleaner};
use std::sync::{Arc, Mutex};

use crate::support::cli::{self, Sim};
use crate::support::{
    SELFTEST_PLAN, Served, identified, open_link, selftest_plan, serve, temp_dir, wait_until,
};

fn profile() -> Arc<Profile> {
    crate::support::profile("window-cleaner")
}

/// The example plan with test timings; its corner step waits as long as the operator needs.
fn example_plan(p: &Profile) -> Plan {
    Plan::parse("example", &selftest_plan(60_000), p).unwrap()
}

/// The example plan with test timings and the corner step cut to 300 ms: for a run whose corner
/// step must fail, which is only found when the step runs out.
fn plan_to_fail_corners(p: &Profile) -> Plan {
    Plan::parse("example", &selftest_plan(300), p).unwrap()
}

/// The robot on its pty and a link to it (which closes first).
struct Bench {
    link: Link,
    robot: Served<WindowCleaner>,
    sim: Arc<Mutex<WindowCleaner>>,
    profile: Arc<Profile>,
}

fn bench(faults: &[Fault]) -> Bench {
    let profile = profile();
    let mut wc = crate::support::window_cleaner();
    for f in faults {
        wc.inject(*f);
    }
    let robot = serve(wc);
    let options = LinkOptions {
        reconnect: false,
        ..LinkOptions::default()
    };
    let link = open_link(&robot, 115_200, profile.clone(), options);
    // The session learns the device code from CMD_VERSION first.
    identified(&link);
    Bench {
        link,
        sim: robot.sim.clone(),
        robot,
        profile,
    }
}

/// An operator who covers the corners when asked (and keeps them covered): the step has read
/// them all released before it asks.
fn covering_operator(sim: Arc<Mutex<WindowCleaner>>) -> impl FnMut(&str) -> bool {
    move |prompt: &str| {
        assert!(prompt.contains("corner"), "{prompt}");
        sim.lock().unwrap().set_corners(0b1111);
        true
    }
}

fn run(b: &Bench, plan: &Plan, operator: &mut dyn selftest::Operator, cancel: &Cancel) -> Report {
    selftest::run(
        Device::new(&b.link.client(), &b.profile),
        plan,
        operator,
        &mut Run::quiet(cancel),
    )
}

fn failed(r: &Report) -> Vec<&str> {
    r.failed().map(|s| s.name.as_str()).collect()
}

#[test]
fn a_healthy_robot_passes_every_step() {
    let b = bench(&[]);
    let plan = example_plan(&b.profile);
    let mut op = covering_operator(b.sim.clone());
    let mut steps_seen = Vec::new();
    let report = selftest::run_each(
        Device::new(&b.link.client(), &b.profile),
        &plan,
        &mut op,
        &mut Run::quiet(&Cancel::new()),
        &mut |r| steps_seen.push(r.name.clone()),
    );
    assert!(report.pass, "{report:#?}");
    assert_eq!(report.aborted, None);
    assert_eq!(report.results.len(), plan.steps.len());
    assert_eq!(steps_seen.len(), plan.steps.len());
    let device = report.device.as_deref().unwrap();
    assert!(device.starts_with("hw 0x03 fw "), "{device}");
    let info = report.device_info.as_ref().unwrap();
    assert!(info.build_date.is_some(), "{info:?}");
    let wheels = &report.results[4].detail;
    assert!(
        wheels.contains("adcLeftWheel") && wheels.contains("min 200"),
        "{wheels}"
    );
    // Motor and fan are off at the end.
    let sim = b.sim.lock().unwrap();
    assert_eq!(sim.motor(), Motor::Stop);
    assert_eq!(sim.fan_pwm(), 0);
}

#[test]
fn a_run_starts_from_the_safe_state_whatever_was_left_running() {
    // Fan, motor and spray left on from the actions panel: the fan and wheel steps measure a
    // rise from rest, so the run must first bring the robot to rest.
    let b = bench(&[]);
    let client = b.link.client();
    for (cmd, field, value) in [
        ("MSP_SET_FAN", "pwm", "60"),
        ("MSP_SET_MOTOR", "motor", "forward"),
        ("MSP_SET_SPRAY", "spray", "on"),
    ] {
        let c = b.profile.command(cmd).unwrap();
        let inputs = [(field.to_string(), Input::Text(value.into()))];
        botbench::ops::exchange::send(Device::new(&client, &b.profile), c, &inputs).unwrap();
    }
    {
        let sim = b.sim.lock().unwrap();
        assert_eq!(sim.fan_pwm(), 60);
        assert!(sim.spraying());
    }
    let plan = example_plan(&b.profile);
    let mut op = covering_operator(b.sim.clone());
    let report = run(&b, &plan, &mut op, &Cancel::new());
    assert!(report.pass, "{:?} {:#?}", failed(&report), report.results);
    assert_eq!(
        report.safe_state,
        [
            "MSP_SET_MOTOR motor=stop: acknowledged",
            "MSP_SET_FAN pwm=0: acknowledged",
            "MSP_SET_SPRAY spray=off: acknowledged"
        ]
    );
    let sim = b.sim.lock().unwrap();
    assert_eq!(
        (sim.fan_pwm(), sim.motor(), sim.spraying()),
        (0, Motor::Stop, false)
    );
}

#[test]
fn each_fault_fails_exactly_its_own_step() {
    let table: [(Fault, &[&str]); 6] = [
        (Fault::GyroNoisy, &["Gyro at rest"]),
        (Fault::BatteryLow, &["Battery voltage"]),
        (
            Fault::WheelCurrentStuck,
            &["Wheel current, forward", "Wheel current, reverse"],
        ),
        (Fault::FanCurrentStuck, &["Fan current"]),
        (Fault::CornerStuck, &["Corner switches"]),
        (Fault::WaterBoxMissing, &["Water box"]),
    ];
    assert_eq!(table.len(), Fault::ALL.len());
    // Each robot on its own port, all at once.
    let runs: Vec<_> = table
        .into_iter()
        .map(|(fault, expected)| {
            std::thread::spawn(move || {
                let b = bench(&[fault]);
                let plan = if fault == Fault::CornerStuck {
                    plan_to_fail_corners(&b.profile)
                } else {
                    example_plan(&b.profile)
                };
                let mut op = covering_operator(b.sim.clone());
                let report = run(&b, &plan, &mut op, &Cancel::new());
                let motor = b.sim.lock().unwrap().motor();
                let fan = b.sim.lock().unwrap().fan_pwm();
                (fault, expected, report, motor, fan)
            })
        })
        .collect();
    for t in runs {
        let (fault, expected, report, motor, fan) =
            crate::support::joined(t, "a faulty robot's self-test");
        assert!(!report.pass, "{fault:?}: {report:#?}");
        assert_eq!(report.aborted, None, "{fault:?}");
        assert_eq!(report.results.len(), 9, "{fault:?}: every step ran");
        assert_eq!(failed(&report), expected, "{fault:?}: {report:#?}");
        // The motor is stopped and the fan off after a failed Rises step too.
        assert_eq!(motor, Motor::Stop, "{fault:?}");
        assert_eq!(fan, 0, "{fault:?}");
    }
}

#[test]
fn failed_steps_say_what_was_measured() {
    let b = bench(&[Fault::BatteryLow, Fault::CornerStuck]);
    let plan = plan_to_fail_corners(&b.profile);
    let mut op = covering_operator(b.sim.clone());
    let report = run(&b, &plan, &mut op, &Cancel::new());
    let battery = report
        .results
        .iter()
        .find(|r| r.name == "Battery voltage")
        .unwrap();
    assert!(!battery.pass);
    assert!(
        battery.detail.contains("10.8 V") && battery.detail.contains("11.5 V to 16.8 V"),
        "{}",
        battery.detail
    );
    let corners = report
        .results
        .iter()
        .find(|r| r.name == "Corner switches")
        .unwrap();
    assert!(
        corners.detail.contains("never set: corner1"),
        "{}",
        corners.detail
    );
}

#[test]
fn an_operator_who_does_nothing_fails_the_corner_step_and_one_who_aborts_ends_the_run() {
    let b = bench(&[]);
    let plan = plan_to_fail_corners(&b.profile);
    let mut idle = |_: &str| true;
    let report = run(&b, &plan, &mut idle, &Cancel::new());
    assert!(!report.pass);
    assert_eq!(failed(&report), ["Corner switches"], "{report:#?}");

    let mut no = |_: &str| false;
    let report = run(&b, &plan, &mut no, &Cancel::new());
    assert!(!report.pass);
    let last = report.results.last().unwrap();
    assert_eq!(last.name, "Corner switches");
    assert!(!last.pass);
    assert!(last.detail.contains("operator aborted"), "{}", last.detail);
    let aborted = report.aborted.as_deref().unwrap();
    assert!(aborted.contains("'Corner switches'"), "{aborted}");
    assert!(aborted.contains("1 step(s) not run"), "{aborted}");
}

#[test]
fn a_link_lost_at_the_operator_prompt_ends_the_run_as_fail_naming_the_step() {
    let b = bench(&[]);
    let plan = example_plan(&b.profile);
    let vanish = b.robot.server.vanish_handle();
    let mut op = move |_: &str| {
        vanish.vanish();
        true
    };
    let report = run(&b, &plan, &mut op, &Cancel::new());
    assert!(!report.pass, "{report:#?}");
    let last = report.results.last().unwrap();
    assert_eq!(last.name, "Corner switches");
    assert!(!last.pass);
    let aborted = report.aborted.as_deref().unwrap();
    assert!(aborted.starts_with("step 'Corner switches':"), "{aborted}");
    // Every step before it passed, none after it ran.
    assert_eq!(report.results.len(), 8);
    assert!(report.results[..7].iter().all(|r| r.pass));
}

/// A plan with one Rises step whose settle time is long enough to act while the motor runs.
fn long_rise(p: &Profile) -> Plan {
    let text = r#"(
        version: 1,
        profile: "window-cleaner",
        steps: [
            Rises(
                name: "Wheels",
                action: ("MSP_SET_MOTOR", {"motor": "forward"}),
                command: "MSP_ANALOG",
                field: "adcLeftWheel",
                min_rise: 200,
                settle_ms: 3000,
                then: ("MSP_SET_MOTOR", {"motor": "stop"}),
            ),
        ],
    )"#;
    Plan::parse("long", text, p).unwrap()
}

/// Waits until the simulated motor runs.
fn when_motor_runs(sim: &Arc<Mutex<WindowCleaner>>) {
    wait_until("the motor to run", || {
        sim.lock().unwrap().motor() != Motor::Stop
    });
}

#[test]
fn a_cancelled_rises_step_still_stops_the_motor() {
    let b = bench(&[]);
    let plan = long_rise(&b.profile);
    let cancel = Cancel::new();
    let (sim, c) = (b.sim.clone(), cancel.clone());
    let t = std::thread::spawn(move || {
        when_motor_runs(&sim);
        c.cancel();
    });
    let report = run(&b, &plan, &mut |_: &str| true, &cancel);
    crate::support::joined(t, "the motor to run");
    assert!(!report.pass);
    let r = &report.results[0];
    assert!(r.detail.starts_with("cancelled"), "{}", r.detail);
    assert!(
        r.detail.contains("MSP_SET_MOTOR motor=stop: sent"),
        "{}",
        r.detail
    );
    assert_eq!(b.sim.lock().unwrap().motor(), Motor::Stop);
}

#[test]
fn a_link_lost_while_the_motor_runs_ends_the_run_naming_the_step_and_fails_no_part() {
    let b = bench(&[]);
    let plan = long_rise(&b.profile);
    let (sim, vanish) = (b.sim.clone(), b.robot.server.vanish_handle());
    let t = std::thread::spawn(move || {
        when_motor_runs(&sim);
        vanish.vanish();
    });
    let report = run(&b, &plan, &mut |_: &str| true, &Cancel::new());
    crate::support::joined(t, "the motor to run");
    assert!(!report.pass, "{report:#?}");
    let r = &report.results[0];
    assert_eq!(r.name, "Wheels");
    assert!(!r.pass);
    // The stop could not reach the robot, and the report says so.
    assert!(r.detail.contains("motor=stop FAILED"), "{}", r.detail);
    assert!(report.aborted.as_deref().unwrap().contains("'Wheels'"));
    // The port went: the run was interrupted in Wheels, which the unit did not fail.
    assert_eq!(
        r.interrupted,
        Some(selftest::Interruption::LinkLost),
        "{r:#?}"
    );
    assert!(failed(&report).is_empty(), "{report:#?}");
}

#[test]
fn the_report_is_logged_as_one_json_line_per_run() {
    let b = bench(&[Fault::WaterBoxMissing]);
    let text = r#"(version: 1, profile: "window-cleaner", name: "short", steps: [
        Range(name: "Battery", command: "MSP_ADAPTER", field: "batteryVoltage", min: 11.5, max: 16.8, samples: 3),
        Reads(name: "Water box", command: "MSP_WATER_BOX", expect: {"status": "1"}),
    ])"#;
    let plan = Plan::parse("short", text, &b.profile).unwrap();
    let report = run(&b, &plan, &mut |_: &str| true, &Cancel::new());
    assert_eq!(failed(&report), ["Water box"]);
    let dir = temp_dir();
    let log = dir.path().join("selftest.jsonl");
    selftest::append_log(&log, &report).unwrap();
    selftest::append_log(&log, &report).unwrap();
    let text = std::fs::read_to_string(&log).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 2);
    for line in lines {
        let v: serde_json::Value = serde_json::from_str(line).unwrap();
        assert_eq!(v["pass"], false);
        assert_eq!(v["device_info"]["hw"], 3);
        assert!(v["device_info"]["build_date"].is_string(), "{v}");
        assert!(v["device_info"]["firmware"].is_string(), "{v}");
        assert_eq!(v["results"][0]["name"], "Battery");
        assert_eq!(v["results"][0]["pass"], true);
        assert_eq!(v["results"][1]["pass"], false);
        assert!(v["started"].is_string());
    }
}

// ---- Plans that are refused ----

fn refused(text: &str) -> String {
    Plan::parse("plan.ron", text, &profile())
        .unwrap_err()
        .to_string()
}

/// A plan's own words in Chinese: the shipped plan gives every step name, its name and its
/// prompt one; a translation of something the plan does not say is refused where it is.
#[test]
fn a_plan_says_its_names_and_prompts_in_chinese() {
    let p = profile();
    let plan = example_plan(&p);
    assert_eq!(plan.said("Gyro at rest", Lang::Zh), "静止时陀螺仪");
    assert_eq!(plan.said("Gyro at rest", Lang::En), "Gyro at rest");
    assert_ne!(plan.said(&plan.name, Lang::Zh), plan.name);
    for step in &plan.steps {
        assert!(
            plan.zh.contains_key(&step.name),
            "the shipped plan says '{}' in Chinese",
            step.name
        );
    }
    let prompts = plan.steps.iter().filter_map(|s| match &s.kind {
        botbench::ops::selftest::StepKind::Operator { prompt, .. } => Some(prompt),
        _ => None,
    });
    for prompt in prompts {
        assert!(plan.zh.contains_key(prompt), "the prompt '{prompt}'");
    }

    let text = r#"(
    version: 1,
    profile: "window-cleaner",
    steps: [Reads(name: "Water box", command: "MSP_WATER_BOX")],
    zh: {
        "Water box": "水箱",
        "Water tank": "水箱",
        "Water box ": " ",
    },
)"#;
    let e = Plan::parse("plan.ron", text, &p).unwrap_err();
    let all = e.to_string();
    assert!(
        all.contains("plan.ron:7:9: zh translates 'Water tank', which is not the plan's name, a step's name or a prompt"),
        "{all}"
    );
    assert!(
        all.contains("plan.ron:8:9: zh translates 'Water box '"),
        "{all}"
    );
    assert_eq!(e.problems.len(), 2, "{all}");
}

#[test]
fn malformed_plans_are_refused_with_file_line_and_column() {
    // Bad RON.
    let e = refused("(\n  version: 1,\n  profile: \"window-cleaner\"\n  steps: [],\n)");
    assert!(e.starts_with("plan.ron:4:"), "{e}");

    // An unknown command, an unknown field, a bad threshold, min above max, an unknown key.
    let text = r#"(
    version: 1,
    profile: "window-cleaner",
    steps: [
        Reads(name: "a", command: "MSP_NO_SUCH"),
        Range(name: "b", command: "MSP_ADAPTER", field: "batteryVolts", min: "11", max: "16"),
        Range(name: "c", command: "MSP_ADAPTER", field: "batteryVoltage", min: "eleven", max: "16"),
        Range(name: "d", command: "MSP_ADAPTER", field: "batteryVoltage", min: "16", max: "11"),
        Rises(name: "e", action: ("MSP_SET_MOTOR", {"motor": "sideways"}), command: "MSP_ANALOG",
              field: "adcFan", min_rise: "5", settle_ms: 10, then: ("MSP_SET_MOTOR", {"motor": "stop"})),
        Range(name: "f", command: "MSP_ADAPTER", field: "batteryVoltage", min: "0", max: "9999"),
    ],
)"#;
    let e = Plan::parse("plan.ron", text, &profile()).unwrap_err();
    let all = e.to_string();
    let lines: Vec<usize> = e.problems.iter().map(|p| p.line).collect();
    assert_eq!(lines, [5, 6, 7, 8, 9, 11], "{all}");
    assert!(
        all.contains("plan.ron:5:35: window-cleaner has no command 'MSP_NO_SUCH'"),
        "{all}"
    );
    assert!(
        all.contains("MSP_ADAPTER has no field 'batteryVolts'"),
        "{all}"
    );
    assert!(
        all.contains("its fields: adapterVoltage, batteryVoltage"),
        "{all}"
    );
    assert!(all.contains("min: 'eleven' is not a number"), "{all}");
    assert!(all.contains("min 16 is above max 11"), "{all}");
    assert!(all.contains("'sideways' is not one of"), "{all}");
    assert!(
        all.contains("max: 9999 is beyond what batteryVoltage can read"),
        "{all}"
    );

    let e = refused(
        "(version: 1, profile: \"window-cleaner\", steps: [\n  Reads(name: \"a\", command: \"MSP_WATER_BOX\", colour: \"red\"),\n])",
    );
    assert!(e.starts_with("plan.ron:2:"), "{e}");
    assert!(e.contains("colour"), "{e}");

    let e = refused(
        "(version: 1, profile: \"solar-cleanbot\", steps: [Reads(name: \"a\", command: \"MSP_WATER_BOX\")])",
    );
    assert!(e.contains("this plan is for 'solar-cleanbot'"), "{e}");
}

// ---- The command line ----

/// Runs the self-test CLI on `plan` against `sim`; when it prompts the operator, the simulator's
/// corners are pressed (as a fixture would), all released before.
fn cli_selftest(sim: &mut Sim, plan: &str, extra: &[&str]) -> cli::Ran {
    sim.type_line("corners 0");
    let mut args = vec!["msp", "--port", &sim.path, "selftest", plan, "--yes"];
    args.extend_from_slice(extra);
    let captured = botbench::cli::Captured::default();
    let run = cli::start_in_process(&args, sim.ports(), &captured);
    crate::support::wait_until("the operator prompt", || {
        captured.err().contains("OPERATOR:") || run.is_finished()
    });
    sim.type_line("corners 15");
    let code = cli::finish_in_process(run, &captured, "msp selftest");
    cli::Ran {
        code: code.into(),
        out: captured.out(),
        err: captured.err(),
    }
}

#[test]
fn cli_selftest_passes_a_healthy_robot_and_fails_a_faulty_one() {
    let dir = temp_dir();
    let log = dir.path().join("line3.jsonl");
    let log_s = log.to_str().unwrap();
    let plan = dir.path().join("plan.ron");
    std::fs::write(&plan, selftest_plan(60_000)).unwrap();
    let plan = plan.to_str().unwrap();

    let mut sim = Sim::start(&["window-cleaner"]);
    let cli::Ran { code, out, err } = cli_selftest(&mut sim, plan, &["--log", log_s]);
    assert_eq!(code, 0, "{out}\n{err}");
    assert!(
        err.contains("OPERATOR: Cover each of the four corner switches"),
        "{err}"
    );
    assert_eq!(
        out.lines().filter(|l| l.starts_with("PASS  ")).count(),
        9,
        "{out}"
    );
    assert!(out.contains("PASS  Corner switches"), "{out}");
    let last = out.lines().last().unwrap();
    assert!(
        last.starts_with("PASS: all 9 steps passed (hw 0x03"),
        "{out}"
    );
    drop(sim);

    let mut sim = Sim::start(&["window-cleaner"]);
    sim.type_line("fault battery-low");
    let cli::Ran { code, out, err } = cli_selftest(&mut sim, plan, &["--log", log_s]);
    assert_eq!(code, 1, "{out}\n{err}");
    assert!(out.contains("FAIL  Battery voltage"), "{out}");
    assert!(out.contains("10.8 V"), "{out}");
    let last = out.lines().last().unwrap();
    assert!(
        last.starts_with("FAIL: 1 of 9 steps failed: Battery voltage"),
        "{out}"
    );

    let cli::Ran { code, out, err } = cli_selftest(&mut sim, plan, &["--json"]);
    assert_eq!(code, 1, "{err}");
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(v["pass"], false);
    assert_eq!(v["results"].as_array().unwrap().len(), 9);

    let logged = std::fs::read_to_string(&log).unwrap();
    let runs: Vec<serde_json::Value> = logged
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(runs.len(), 2);
    assert_eq!(runs[0]["pass"], true);
    assert_eq!(runs[1]["pass"], false);
}

#[test]
fn cli_selftest_refuses_a_bad_plan_before_opening_the_port() {
    let dir = temp_dir();
    let bad = dir.path().join("bad.ron");
    let text = std::fs::read_to_string(SELFTEST_PLAN).unwrap().replacen(
        "\"batteryVoltage\"",
        "\"batteryVolts\"",
        1,
    );
    let line = text
        .lines()
        .position(|l| l.contains("batteryVolts"))
        .unwrap()
        + 1;
    std::fs::write(&bad, &text).unwrap();
    let mut c = cli::botbench(["msp", "--port", "/dev/botbench-no-such-port", "selftest"]);
    let cli::Ran { code, err, .. } = cli::output(c.arg(&bad));
    assert_eq!(code, 2, "{err}");
    assert!(err.contains(&format!("bad.ron:{line}:")), "{err}");
    assert!(err.contains("no field 'batteryVolts'"), "{err}");
    assert!(!err.contains("botbench-no-such-port"), "{err}");
}
