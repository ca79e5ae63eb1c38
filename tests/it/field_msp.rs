//! MSP boards as they behave in the field (issue 11, PROTOCOL_NOTES §4), through pseudo-terminals:
//! unsolicited frames between a request and its reply, values outside their range, answers that
//! come late, and a device that does not identify itself.

use botbench::link::{Link, LinkEvent, LinkOptions, Request};
use botbench::profile::Registry;
use botbench::sim::window_cleaner::WindowCleaner;
use botbench::sim::{Faults, PtyServer, SharedDevice, SimOptions};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crate::support::cli::Sim;

/// A window cleaner that pushes `ff fe 82 01 ee 6d` (command 130, 238 %) before each reply.
fn pushing() -> Sim {
    Sim::start(&["window-cleaner", "--async-before-reply", "ee"])
}

#[test]
fn a_request_is_answered_by_its_reply_never_by_an_unsolicited_frame() {
    let sim = pushing();
    let p = sim.path.as_str();
    let get = sim.run(&["msp", "--port", p, "get", "MSP_GET_PWMVALUE"]);
    assert_eq!(get.code, 0, "{}", get.text());
    let value = get
        .out
        .lines()
        .find(|l| l.starts_with("pwmValue"))
        .unwrap_or_default();
    assert!(value.ends_with(" 85 %"), "{}", get.text());
    // The unsolicited frame is shown as what it is, with its value flagged.
    let pushed = get
        .out
        .lines()
        .find(|l| l.contains("unsolicited") && l.contains("MSP_GET_PWMVALUE"))
        .unwrap_or_else(|| panic!("no unsolicited line: {}", get.text()));
    assert!(
        pushed.contains("238 % !! out of range 0 to 100 %"),
        "{pushed}"
    );

    let json = sim.run(&["msp", "--port", p, "--json", "get", "MSP_GET_PWMVALUE"]);
    let doc = &json.json_docs()[0];
    assert_eq!(doc["fields"][0]["value"], 85, "{}", json.text());
    assert_eq!(doc["ok"], true);
    let frames = doc["unsolicited"].as_array().expect("unsolicited frames");
    let pwm = frames
        .iter()
        .find(|f| f["command"] == "MSP_GET_PWMVALUE")
        .expect("the pushed frame");
    assert_eq!(pwm["kind"], "unsolicited");
    assert_eq!(pwm["bytes"], "ff fe 82 01 ee 6d");
    assert_eq!(pwm["fields"][0]["value"], 238);
    assert_eq!(pwm["fields"][0]["out_of_range"], true);

    let set = sim.run(&[
        "msp",
        "--port",
        p,
        "--json",
        "set",
        "MSP_SET_PWMVALUE",
        "pwmValue=85",
    ]);
    assert_eq!(set.code, 0, "{}", set.text());
    let doc = &set.json_docs()[0];
    assert_eq!(doc["verified"], true, "{}", set.text());
    assert_eq!(doc["fields"][0]["read"], 85);
    assert!(doc["unsolicited"].is_array(), "{}", set.text());

    let watch = sim.run(&[
        "msp",
        "--port",
        p,
        "--json",
        "watch",
        "MSP_GET_PWMVALUE",
        "--count",
        "4",
    ]);
    assert_eq!(watch.code, 0, "{}", watch.text());
    let docs = watch.json_docs();
    let answers: Vec<_> = docs.iter().filter(|d| d.get("summary").is_some()).collect();
    assert_eq!(answers.len(), 4, "{}", watch.text());
    for a in answers {
        assert_eq!(
            a["summary"],
            "MSP_GET_PWMVALUE pwmValue=85 %",
            "{}",
            watch.text()
        );
    }
    assert!(
        docs.iter()
            .any(|d| d["unsolicited"]["command"] == "MSP_GET_PWMVALUE"
                && d["unsolicited"]["fields"][0]["out_of_range"] == true),
        "{}",
        watch.text()
    );
}

/// A firmware whose fan PWM holds 238: the built-in profile allows 0-100.
fn out_of_range_firmware() -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("botbench-field-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let src = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/assets/profiles/window-cleaner.ron"
    ))
    .unwrap();
    let from = r#"type: U8, unit: "%", range: Some((0, 100)), default: Some(85)),"#;
    assert!(src.contains(from), "the profile's pwmValue line moved");
    let file = dir.join("window-cleaner.ron");
    std::fs::write(
        &file,
        src.replacen(
            from,
            r#"type: U8, unit: "%", range: Some((0, 255)), default: Some(238)),"#,
            1,
        ),
    )
    .unwrap();
    file
}

#[test]
fn a_value_outside_its_range_is_flagged_wherever_it_is_printed() {
    let firmware = out_of_range_firmware();
    let sim = Sim::start(&["window-cleaner", "--profile", firmware.to_str().unwrap()]);
    let p = sim.path.as_str();
    let get = sim.run(&["msp", "--port", p, "get", "MSP_GET_PWMVALUE"]);
    assert_eq!(get.code, 1, "{}", get.text());
    assert!(
        get.out
            .contains("pwmValue                 238 % !! out of range 0 to 100 %"),
        "{}",
        get.text()
    );
    let json = sim.run(&["msp", "--port", p, "--json", "get", "MSP_GET_PWMVALUE"]);
    assert_eq!(json.code, 1, "{}", json.text());
    let doc = &json.json_docs()[0];
    assert_eq!(doc["ok"], false);
    assert_eq!(doc["fields"][0]["value"], 238);
    assert_eq!(doc["fields"][0]["out_of_range"], true);
    assert!(
        doc["fields"][0]["display"]
            .as_str()
            .unwrap_or_default()
            .contains("!! out of range"),
        "{}",
        json.text()
    );
    let watch = sim.run(&[
        "msp",
        "--port",
        p,
        "watch",
        "MSP_GET_PWMVALUE",
        "--count",
        "2",
    ]);
    assert!(
        watch
            .out
            .lines()
            .filter(|l| l.contains("238 % !! out of range"))
            .count()
            == 2,
        "{}",
        watch.text()
    );
}

#[test]
fn an_unidentified_device_is_said_and_strict_refuses_to_write() {
    // Every CMD_VERSION reply fails its checksum.
    let sim = Sim::start(&["window-cleaner", "--garble-command", "2"]);
    let p = sim.path.as_str();
    let strict = sim.run(&[
        "msp",
        "--port",
        p,
        "--strict",
        "set",
        "MSP_SET_PWMVALUE",
        "pwmValue=40",
    ]);
    assert_eq!(strict.code, 1, "{}", strict.text());
    assert!(
        strict.err.contains("did not identify itself") && strict.err.contains("--strict"),
        "{}",
        strict.text()
    );
    // Nothing was written: the device still holds its default.
    let get = sim.run(&["msp", "--port", p, "--json", "get", "MSP_GET_PWMVALUE"]);
    assert_eq!(
        get.json_docs()[0]["fields"][0]["value"],
        85,
        "{}",
        get.text()
    );
    assert!(
        get.err.contains("device code 0x03"),
        "the warning names the code used: {}",
        get.text()
    );
    let warnings = get.json_docs()[0]["warnings"].clone();
    assert!(
        warnings[0]
            .as_str()
            .is_some_and(|w| w.contains("did not identify itself")),
        "a script reading --json sees it too: {}",
        get.text()
    );
    let set = sim.run(&["msp", "--port", p, "set", "MSP_SET_PWMVALUE", "pwmValue=40"]);
    assert_eq!(set.code, 0, "{}", set.text());
    assert!(
        set.err
            .contains("warning: the device did not identify itself")
            && set.err.contains("bad checksum"),
        "{}",
        set.text()
    );
    assert!(set.out.contains("verified"), "{}", set.text());
}

/// A window cleaner on a pty whose answers start `latency` after each request, and a link to it.
fn slow_window_cleaner(
    latency: Duration,
    margin: Option<Duration>,
) -> (PtyServer, Link, Arc<Mutex<WindowCleaner>>) {
    let opts = SimOptions {
        latency: Some(latency),
        ..SimOptions::default()
    };
    let wc = Arc::new(Mutex::new(WindowCleaner::new(&opts).unwrap()));
    let shared: SharedDevice = wc.clone();
    let server = PtyServer::start_lockstep(shared, Faults::default()).unwrap();
    let profile = Registry::builtin().unwrap().get("window-cleaner").unwrap();
    let options = LinkOptions {
        margin,
        reconnect: false,
        ..LinkOptions::default()
    };
    let link = Link::open(server.opener(115_200), profile, options, None).unwrap();
    (server, link, wc)
}

fn pwm(link: &Link) -> i64 {
    let reply = link
        .client()
        .request(Request::new(130, Vec::new()))
        .expect("the fan PWM is read");
    i64::from(reply.payload().expect("a payload")[0])
}

#[test]
fn a_late_answer_is_never_taken_for_the_next_request_of_the_same_command() {
    // Answers start 60 ms after each request; the link waits 20 ms an attempt: every attempt
    // but the one answered leaves an answer owed, arriving while the next request is asked.
    let (_server, link, wc) =
        slow_window_cleaner(Duration::from_millis(60), Some(Duration::from_millis(20)));
    link.client()
        .device_info()
        .expect("identified, however late");
    assert_eq!(pwm(&link), 85);
    // The device changes meanwhile (as after a write from elsewhere); the next read must see
    // it, not a late answer to the attempts before.
    wc.lock().unwrap().set_param("pwmValue", 40).unwrap();
    assert_eq!(pwm(&link), 40);
    wc.lock().unwrap().set_param("pwmValue", 55).unwrap();
    assert_eq!(pwm(&link), 55);
}

#[test]
fn late_answers_widen_the_automatic_margin() {
    // 35 ms: beyond MSP's own 20 ms margin.
    let (_server, link, _wc) = slow_window_cleaner(Duration::from_millis(35), None);
    let info = link.client().device_info();
    assert!(
        info.is_ok(),
        "CMD_VERSION is answered late, and taken: {info:?}"
    );
    assert_eq!(pwm(&link), 85);
    let deadline = Instant::now() + crate::support::cli::WATCHDOG;
    loop {
        if let Ok(LinkEvent::Stats(s)) = link.events().recv_timeout(Duration::from_millis(100))
            && let Some(margin) = s.margin
            && margin > Duration::from_millis(35)
        {
            // Measured to when the answer arrived: the 35 ms, less the microseconds between
            // the host's previous port call and its request (the device hears the request from
            // then on, never later than the host reckons).
            assert!(
                s.answer_latency
                    .is_some_and(|l| l >= Duration::from_millis(34)),
                "{s:?}"
            );
            break;
        }
        assert!(Instant::now() < deadline, "the margin never widened");
    }
    assert_eq!(pwm(&link), 85);
}
