//! The real app, driven through egui_kittest against the MSP simulators on ptys: capability flags,
//! the solar cleanbot's controls, STOP and dead-man, and the window cleaner's self-test.

use botbench::i18n::Lang;
use botbench::sim::SimOptions;
use botbench::sim::solar_cleanbot::SolarCleanbot;
use botbench::sim::window_cleaner::{Fault, WindowCleaner};
use botbench::ui::device::DevicePanel;
use botbench::ui::selftest::SelfTestPanel;
use botbench::ui::solar::SolarPanel;
use botbench::ui::{App, PanelId, SolarTrip};
use egui_kittest::kittest::Queryable;

use crate::support::gui::{H, app, app_mut, has_label, settings, type_into};
use crate::support::{Port, SELFTEST_PLAN, Served, selftest_plan, serve, temp_dir};

type Bench<D> = Served<D>;

fn window_cleaner(flags: Option<u8>, faults: &[Fault]) -> Bench<WindowCleaner> {
    let mut wc = crate::support::window_cleaner();
    wc.set_flags(flags);
    for f in faults {
        wc.inject(*f);
    }
    serve(wc)
}

fn solar() -> Bench<SolarCleanbot> {
    serve(SolarCleanbot::new(&SimOptions::default()).unwrap())
}

/// The app on `profile` at `path`, with the protocol's own answer margin.
fn harness(port: &impl Port, profile: &str, panel: PanelId, lang: Lang) -> H {
    crate::support::gui::harness(settings(port.path(), profile, panel, lang), port.ports())
}

/// Steps the UI in real time until `done` holds; on timeout says what the panels hold.
fn step_until(h: &mut H, what: &str, done: impl Fn(&App) -> bool) {
    crate::support::gui::step_until_or(h, what, done, |a| {
        format!(
            "info {:?}, solar inputs {:?}, outcomes {:?}, self-test running {} results {:?} \
             error {:?}",
            a.station().device.info,
            a.panel::<SolarPanel>().inputs,
            a.panel::<SolarPanel>().control.outcomes,
            a.panel::<SelfTestPanel>().running,
            a.panel::<SelfTestPanel>().results,
            a.panel::<SelfTestPanel>().error
        )
    });
}

fn identified(a: &App) -> bool {
    a.station().connected() && matches!(a.station().device.info, Some(Ok(_)))
}

fn nav_has(h: &H, name: &str) -> bool {
    h.query_all_by_label(name).next().is_some()
}

#[test]
fn a_clear_capability_bit_hides_its_panels_and_the_app_leaves_them() {
    // Bit 0 (config page) clear: the parameter pages are hidden.
    let b = window_cleaner(Some(0b1110), &[]);
    let mut h = harness(&b, "window-cleaner", PanelId::TUNING, Lang::En);
    step_until(&mut h, "the device identified", identified);
    h.run_steps(2);
    let a = app(&h);
    assert!(!a.panels().contains(&PanelId::TUNING), "{:?}", a.panels());
    assert!(!a.panels().contains(&PanelId::PRESETS), "{:?}", a.panels());
    assert!(a.panels().contains(&PanelId::SELF_TEST));
    assert_ne!(
        a.settings.panel,
        PanelId::TUNING,
        "the app left the hidden panel"
    );
    assert!(!nav_has(&h, "Tuning") && !nav_has(&h, "Presets"));
    assert!(nav_has(&h, "Self-test"));
    // The device panel says why.
    app_mut(&mut h).settings.panel = PanelId::DEVICE;
    h.run_steps(2);
    assert!(h.query_by_label_contains("Hidden (not supported").is_some());
    assert!(h.query_all_by_label("not supported").next().is_some());

    // The same robot with the bit set shows them.
    let b = window_cleaner(Some(0b1111), &[]);
    let mut h = harness(&b, "window-cleaner", PanelId::TUNING, Lang::En);
    step_until(&mut h, "the device identified", identified);
    h.run_steps(2);
    assert!(app(&h).panels().contains(&PanelId::TUNING));
    assert_eq!(app(&h).settings.panel, PanelId::TUNING);
    assert!(nav_has(&h, "Tuning"));
}

#[test]
fn the_device_panel_pings_and_shows_version_build_and_flags() {
    let b = window_cleaner(Some(0b1111), &[]);
    let mut h = harness(&b, "window-cleaner", PanelId::DEVICE, Lang::En);
    // The panel reads version and power state on its own once the link is free.
    step_until(&mut h, "the power state", |a| {
        a.panel::<DevicePanel>().power.is_some() && a.station().job_progress().is_none()
    });
    assert!(matches!(app(&h).panel::<DevicePanel>().power, Some(Ok(_))));
    h.get_by_label("Ping").click();
    step_until(&mut h, "the ping", |a| {
        a.panel::<DevicePanel>().ping.is_some()
    });
    assert!(matches!(app(&h).panel::<DevicePanel>().ping, Some(Ok(_))));
    step_until(&mut h, "the ping job to end", |a| {
        a.station().job_progress().is_none()
    });
    b.sim().set_flags(Some(0b0101));
    h.get_by_label("Read version and power state").click();
    step_until(&mut h, "the new flags", |a| {
        matches!(&a.panel::<DevicePanel>().version, Some(Ok(v)) if v.flags == Some(0b0101))
            && matches!(&a.station().device.info, Some(Ok(v)) if v.flags == Some(0b0101))
    });
    h.run_steps(2);
    assert_eq!(
        app(&h)
            .panel::<DevicePanel>()
            .version
            .as_ref()
            .map(|v| v.as_ref().map(|v| v.flags)),
        Some(Ok(Some(0b0101)))
    );
    assert!(
        h.query_by_label("2024-05-17 14:03:52").is_some(),
        "build date and time"
    );
    assert!(h.query_by_label("1.4.2").is_some(), "firmware");
    assert!(h.query_by_label("Config page supported").is_some());
    assert_eq!(h.query_all_by_label("supported").count(), 2);
    assert_eq!(h.query_all_by_label("not supported").count(), 2);
}

fn solar_ready(b: &Bench<SolarCleanbot>) -> H {
    let mut h = harness(b, "solar-cleanbot", PanelId::SOLAR, Lang::En);
    step_until(&mut h, "the device identified", identified);
    h.run_steps(2);
    h
}

fn drive(h: &mut H, b: &Bench<SolarCleanbot>, speed: i16) {
    type_into(h, "Speed value", &speed.to_string());
    h.get_by_label("Set speed").click();
    h.run_steps(2);
    // Moving asks first.
    h.get_by_label("Confirm").click();
    step_until(h, "the robot to take the speed", |_| {
        b.sim().commanded_speed() == speed
    });
}

#[test]
fn speed_rotate_and_stop_from_the_solar_panel_drive_the_simulated_robot() {
    let b = solar();
    let mut h = solar_ready(&b);
    assert!(app(&h).panels().contains(&PanelId::SOLAR));
    assert!(!app(&h).panels().contains(&PanelId::SELF_TEST));
    drive(&mut h, &b, 300);
    step_until(&mut h, "the robot to move", |_| b.sim().speed() > 100.0);
    step_until(&mut h, "the readouts", |a| {
        a.station()
            .device
            .plots
            .get("motor_speed")
            .and_then(|s| s.get("averageSpeed"))
            .is_some_and(|s| s.len() > 5)
    });
    type_into(&mut h, "Rotate value", "90");
    h.get_by_label("Rotate").click();
    h.run_steps(2);
    h.get_by_label("Confirm").click();
    step_until(&mut h, "the robot to turn", |_| b.sim().yaw() > 20.0);
    // STOP, while a job runs.
    app_mut(&mut h).settings.panel = PanelId::DEVICE;
    h.run_steps(2);
    h.get_by_label("Read version and power state").click();
    h.run_steps(1);
    h.get_by_label("STOP").click();
    step_until(&mut h, "STOP", |_| b.sim().commanded_speed() == 0);
    app_mut(&mut h).settings.panel = PanelId::SOLAR;
    step_until(&mut h, "the STOP acknowledged", |a| {
        matches!(
            a.station().stop.state(),
            botbench::ui::stop::StopState::Acked(_)
        )
    });
}

#[test]
fn out_of_range_control_values_are_refused_and_nothing_is_sent() {
    let b = solar();
    let mut h = solar_ready(&b);
    let before = b.sim().heartbeat();
    type_into(&mut h, "Speed value", "5000");
    assert!(
        h.query_all_by_label_contains("out of range")
            .next()
            .is_some(),
        "the refusal is shown as typed"
    );
    h.get_by_label("Set speed").click();
    h.run_steps(3);
    assert!(h.query_by_label("Confirm").is_none(), "nothing to confirm");
    type_into(&mut h, "Heartbeat interval", "0");
    h.get_by_label("Set heartbeat").click();
    type_into(&mut h, "Frame rate", "abc");
    h.get_by_label("Set vision frame rate").click();
    h.run_steps(5);
    assert!(
        app(&h).panel::<SolarPanel>().control.outcomes.is_empty(),
        "nothing was sent"
    );
    // A value in range goes through and is acknowledged; the link keeps order, so anything the
    // refused ones had sent would have reached the robot before it.
    type_into(&mut h, "Frame rate", "15");
    h.get_by_label("Set vision frame rate").click();
    step_until(&mut h, "the frame rate", |a| {
        b.sim().frame_rate() == 15 && !a.panel::<SolarPanel>().control.outcomes.is_empty()
    });
    let sim = b.sim();
    assert_eq!(sim.commanded_speed(), 0);
    assert_eq!(sim.heartbeat(), before);
    drop(sim);
    assert_eq!(
        app(&h).panel::<SolarPanel>().control.outcomes.len(),
        1,
        "only the frame rate was sent: {:?}",
        app(&h).panel::<SolarPanel>().control.outcomes
    );
}

#[test]
fn the_dead_man_stops_the_robot_when_the_operator_stops_confirming() {
    let b = solar();
    let mut h = solar_ready(&b);
    drive(&mut h, &b, 200);
    app_mut(&mut h)
        .panel_mut::<SolarPanel>()
        .control
        .deadman_secs = 1;
    h.get_by_label("Dead-man").click();
    // Arming sets the robot's heartbeat to the same period.
    step_until(&mut h, "the heartbeat set", |_| b.sim().heartbeat() == 1);
    h.get_by_label("Hold to confirm (or press Space)").click();
    // Nobody confirms any more.
    step_until(&mut h, "the dead-man STOP", |_| {
        b.sim().commanded_speed() == 0
    });
    assert!(matches!(
        app(&h).panel::<SolarPanel>().control.trip,
        Some((SolarTrip::NotConfirmed, _))
    ));
    assert!(
        !app(&h).panel::<SolarPanel>().control.deadman,
        "it disarms once tripped"
    );
    h.run_steps(2);
    assert!(h.query_by_label_contains("stopped confirming").is_some());
}

/// The example plan with test timings, written into `dir`. Its corner step waits as long as
/// the operator needs: only a lost link ends it early here.
fn plan_file(dir: &tempfile::TempDir) -> std::path::PathBuf {
    let path = dir.path().join("plan.ron");
    std::fs::write(&path, selftest_plan(60_000)).unwrap();
    path
}

/// Clicks Run once nothing else runs, and waits for the job to start.
fn start_selftest(h: &mut H) {
    step_until(h, "no job running", |a| {
        a.station().job_progress().is_none()
    });
    h.get_by_label("Run self-test").click();
    step_until(h, "the self-test job", |a| {
        a.panel::<SelfTestPanel>().running && a.station().job.as_ref().is_some_and(|j| !j.is_done())
    });
}

/// Opens the plan, runs it, and covers the corners when the prompt asks (answering through the
/// modal). Returns the log's path, in `dir`.
fn run_selftest(
    h: &mut H,
    b: &Bench<WindowCleaner>,
    dir: &tempfile::TempDir,
) -> std::path::PathBuf {
    let plan = plan_file(dir);
    let log = dir.path().join("selftest.jsonl");
    step_until(h, "the device identified", |a| {
        identified(a) && a.station().job_progress().is_none()
    });
    {
        let a = app_mut(h);
        a.panel_mut::<SelfTestPanel>().path = plan.display().to_string();
        a.panel_mut::<SelfTestPanel>().log_path = log.display().to_string();
    }
    h.step();
    h.get_by_label("Open plan").click();
    h.run_steps(2);
    assert!(
        app(h).panel::<SelfTestPanel>().plan.is_some(),
        "{:?}",
        app(h).panel::<SelfTestPanel>().error
    );
    start_selftest(h);
    step_until(h, "the operator prompt", |a| {
        a.panel::<SelfTestPanel>().prompt.is_some()
    });
    h.run_steps(2);
    assert!(h.query_by_label_contains("corner switches").is_some());
    // The step has read the corners all released before it asked: the operator covers them.
    b.sim().set_corners(0b1111);
    h.get_by_label("Done").click();
    step_until(h, "the report", |a| a.station().verdicts.selftest.is_some());
    h.run_steps(2);
    log
}

#[test]
fn the_self_test_passes_on_a_healthy_robot_and_logs_the_device() {
    let b = window_cleaner(Some(0x0F), &[]);
    let mut h = harness(&b, "window-cleaner", PanelId::SELF_TEST, Lang::En);
    let dir = temp_dir();
    let log = run_selftest(&mut h, &b, &dir);
    let report = app(&h).station().verdicts.selftest.clone().unwrap();
    assert!(report.pass, "{report:#?}");
    assert_eq!(
        h.query_all_by_label("PASS").count(),
        report.results.len() + 1,
        "every row and the banner"
    );
    assert!(h.query_all_by_label("FAIL").next().is_none());
    assert!(
        h.query_by_label("11.5 V to 16.8 V").is_some(),
        "bounds with units"
    );
    let text = std::fs::read_to_string(&log).unwrap();
    assert_eq!(text.lines().count(), 1);
    assert!(
        text.contains("\"pass\":true") && text.contains("2024-05-17 14:03:52"),
        "{text}"
    );
}

#[test]
fn the_self_test_fails_naming_the_faulty_check() {
    let b = window_cleaner(Some(0x0F), &[Fault::FanCurrentStuck]);
    let mut h = harness(&b, "window-cleaner", PanelId::SELF_TEST, Lang::En);
    let dir = temp_dir();
    run_selftest(&mut h, &b, &dir);
    let report = app(&h).station().verdicts.selftest.clone().unwrap();
    assert!(!report.pass);
    let failed: Vec<&str> = report.failed().map(|r| r.name.as_str()).collect();
    assert_eq!(failed, ["Fan current"], "{report:#?}");
    assert_eq!(
        h.query_all_by_label("FAIL").count(),
        2,
        "the row and the banner"
    );
    assert!(h.query_by_label("Failed: Fan current").is_some());
    assert_eq!(b.sim().fan_pwm(), 0, "the fan is off after");
}

#[test]
fn a_malformed_plan_is_refused_with_its_line() {
    let b = window_cleaner(Some(0x0F), &[]);
    let mut h = harness(&b, "window-cleaner", PanelId::SELF_TEST, Lang::En);
    step_until(&mut h, "the link", |a| a.station().connected());
    let dir = temp_dir();
    let path = dir.path().join("bad-plan.ron");
    std::fs::write(
        &path,
        "(\n  version: 1,\n  profile: \"window-cleaner\",\n  name: \"bad\",\n  steps: [\n    Reads(name: \"Water\", command: \"MSP_NO_SUCH_COMMAND\"),\n  ],\n)\n",
    )
    .unwrap();
    app_mut(&mut h).panel_mut::<SelfTestPanel>().path = path.display().to_string();
    h.step();
    h.get_by_label("Open plan").click();
    h.run_steps(2);
    let err = app(&h)
        .panel::<SelfTestPanel>()
        .error
        .clone()
        .expect("refused")
        .to_string();
    assert!(
        err.contains(":6:") && err.contains("MSP_NO_SUCH_COMMAND"),
        "{err}"
    );
    assert!(app(&h).panel::<SelfTestPanel>().plan.is_none());
    assert!(
        h.query_by_label("Run self-test").is_none(),
        "nothing to run"
    );
    assert!(h.query_by_label_contains("The plan was refused").is_some());
}

#[test]
fn the_msp_panels_render_in_english_and_chinese() {
    let b = solar();
    for lang in [Lang::En, Lang::Zh] {
        let mut h = harness(&b, "solar-cleanbot", PanelId::SOLAR, lang);
        step_until(&mut h, "readings", |a| {
            a.station().device.readings.len() > 5
        });
        for panel in app(&h).panels() {
            app_mut(&mut h).settings.panel = panel;
            h.run_steps(2);
        }
        drop(h);
    }
    let b = window_cleaner(Some(0x0F), &[]);
    for lang in [Lang::En, Lang::Zh] {
        let mut h = harness(&b, "window-cleaner", PanelId::SELF_TEST, lang);
        step_until(&mut h, "the link", |a| a.station().connected());
        app_mut(&mut h).panel_mut::<SelfTestPanel>().path = SELFTEST_PLAN.into();
        h.step();
        let open = lang.tr("Open plan", "打开方案");
        h.get_by_label(open).click();
        h.run_steps(2);
        assert!(
            app(&h).panel::<SelfTestPanel>().plan.is_some(),
            "{:?} on {:?}",
            app(&h).panel::<SelfTestPanel>().error,
            app(&h).settings.panel
        );
        app_mut(&mut h).settings.panel = PanelId::DEVICE;
        h.run_steps(2);
    }
}

/// A port lost in a step is no verdict on the part it checks (issue 25, item 6): the banner says
/// `link lost during <step>`, never FAIL, and the step's row says it was interrupted.
#[test]
fn a_link_lost_at_the_operator_prompt_ends_the_self_test_with_no_verdict_naming_the_step() {
    let b = window_cleaner(Some(0x0F), &[]);
    let mut h = harness(&b, "window-cleaner", PanelId::SELF_TEST, Lang::En);
    let dir = temp_dir();
    let plan = plan_file(&dir);
    step_until(&mut h, "the device identified", |a| {
        identified(a) && a.station().job_progress().is_none()
    });
    {
        let a = app_mut(&mut h);
        a.panel_mut::<SelfTestPanel>().path = plan.display().to_string();
        a.panel_mut::<SelfTestPanel>().log_path = String::new();
    }
    h.step();
    h.get_by_label("Open plan").click();
    h.run_steps(2);
    start_selftest(&mut h);
    step_until(&mut h, "the operator prompt", |a| {
        a.panel::<SelfTestPanel>().prompt.is_some()
    });
    b.server.vanish_handle().vanish();
    h.run_steps(2);
    h.get_by_label("Done").click();
    step_until(&mut h, "the report", |a| {
        a.station().verdicts.selftest.is_some()
    });
    h.run_steps(2);
    let report = app(&h).station().verdicts.selftest.clone().unwrap();
    assert!(!report.pass);
    let aborted = report.aborted.as_deref().unwrap_or_default();
    assert!(aborted.starts_with("step 'Corner switches':"), "{aborted}");
    assert_eq!(report.failed().count(), 0, "no part failed: {report:#?}");
    assert!(h.query_by_label("NO VERDICT").is_some(), "the banner");
    assert!(
        h.query_by_label("link lost during Corner switches")
            .is_some()
    );
    assert!(
        h.query_all_by_label("FAIL").next().is_none(),
        "no part failing"
    );
    assert!(h.query_by_label("interrupted").is_some(), "the step's row");
    assert!(h.query_all_by_label("PASS").count() < report.results.len() + 1);
}

#[test]
fn a_fan_left_on_is_shown_running_the_self_test_starts_safe_and_its_verdict_belongs_to_one_unit() {
    use botbench::profile::Input;
    use botbench::ui::{Action, jobs};
    let b = window_cleaner(Some(0x0F), &[]);
    let mut h = harness(&b, "window-cleaner", PanelId::SELF_TEST, Lang::En);
    step_until(&mut h, "the device identified", |a| {
        identified(a) && a.station().job_progress().is_none()
    });
    // The fan left on from Actions: the window says so on every panel.
    let profile = app(&h).station().device.profile.clone();
    let fan = profile.command("MSP_SET_FAN").expect("the fan command").id;
    app_mut(&mut h).apply(Action::StartJob(jobs::send(
        &profile,
        fan,
        vec![("pwm".into(), Input::Text("60".into()))],
    )));
    step_until(&mut h, "the fan running", |a| {
        !a.station().device.running.is_empty() && a.station().job_progress().is_none()
    });
    h.run_steps(2);
    assert!(h.query_by_label("Running:").is_some());
    assert!(has_label(&h, "60 %"), "the running fan with its value");
    assert!(b.sim().fan_pwm() > 0);
    // The plan starts from the safe state it sets: no false "Fan current" failure.
    let dir = temp_dir();
    run_selftest(&mut h, &b, &dir);
    let report = app(&h).station().verdicts.selftest.clone().unwrap();
    assert!(report.pass, "{report:#?}");
    assert!(!report.safe_state.is_empty());
    assert!(h.query_by_label("Running:").is_none(), "nothing runs after");
    assert!(h.query_all_by_label("PASS").next().is_some(), "the banner");
    // A disconnect says nothing of which unit is on the fixture: the verdict stays, naming
    // the unit it is about (issue 25, item 6).
    app_mut(&mut h).apply(Action::Disconnect);
    h.run_steps(3);
    assert!(app(&h).station().verdicts.selftest.is_some());
    assert!(
        h.query_all_by_label("PASS").next().is_some(),
        "the banner stays"
    );
    assert!(h.query_by_label_contains("build 37").is_some(), "its unit");
    // The same unit connected again keeps it.
    connect_again(&mut h, &b, 37);
    h.run_steps(3);
    assert!(
        h.query_all_by_label("PASS").next().is_some(),
        "the same unit"
    );
    // Another unit identifies itself (another build): the verdict was not about it.
    b.sim().core_mut().identity.build = 38;
    connect_again(&mut h, &b, 38);
    h.run_steps(3);
    assert!(app(&h).station().verdicts.selftest.is_none());
    assert!(
        h.query_all_by_label("PASS").next().is_none(),
        "no banner left"
    );
}

/// Connects the window to `b` again and waits until the device identifies itself with `build`.
fn connect_again(h: &mut H, b: &Bench<WindowCleaner>, build: u8) {
    app_mut(h).apply(botbench::ui::Action::Connect {
        target: botbench::ui::Target::Port(b.path().to_string()),
        profile: "window-cleaner".into(),
        port: Default::default(),
    });
    step_until(h, "the device identified again", |a| {
        a.station().connected()
            && matches!(&a.station().device.info, Some(Ok(i)) if i.build == build)
            && a.station().job_progress().is_none()
    });
}

/// A verdict stays until the operator dismisses it or the next run starts (issue 25, item 6).
#[test]
fn a_verdict_stays_until_dismissed_and_goes_as_the_next_run_starts() {
    let b = window_cleaner(Some(0x0F), &[]);
    let mut h = harness(&b, "window-cleaner", PanelId::SELF_TEST, Lang::En);
    let dir = temp_dir();
    run_selftest(&mut h, &b, &dir);
    assert!(h.query_all_by_label("PASS").next().is_some(), "the banner");
    h.get_by_label("Dismiss").click();
    h.run_steps(3);
    assert!(app(&h).station().verdicts.selftest.is_none());
    assert!(h.query_all_by_label("PASS").next().is_none(), "dismissed");
    // Another run's verdict; the next run clears it as it starts.
    run_selftest(&mut h, &b, &dir);
    assert!(
        h.query_all_by_label("PASS").next().is_some(),
        "the next verdict"
    );
    start_selftest(&mut h);
    h.run_steps(2);
    assert!(
        h.query_all_by_label("PASS").next().is_none(),
        "no banner while the next run runs"
    );
    app_mut(&mut h).apply(botbench::ui::Action::CancelJob);
    step_until(&mut h, "the run cancelled", |a| {
        !a.panel::<SelfTestPanel>().running
    });
}

/// The truth in small places (issue 25, item 10): the round trip shown is the connection's,
/// gone once its link is lost (the worker's last measurement came back with every report).
#[test]
fn the_round_trip_is_cleared_when_the_link_is_lost() {
    let b = window_cleaner(Some(0x0F), &[]);
    let mut h = harness(&b, "window-cleaner", PanelId::DEVICE, Lang::En);
    step_until(&mut h, "a round trip measured", |a| {
        identified(a) && a.station().link.stats.rtt.is_some()
    });
    b.server.vanish_handle().vanish();
    step_until(&mut h, "the link lost", |a| !a.station().link.connected());
    // Reports keep coming from the worker while it tries the port again.
    for _ in 0..20 {
        h.run_steps(2);
        assert_eq!(
            app(&h).station().link.stats.rtt,
            None,
            "a lost link's round trip"
        );
    }
}
