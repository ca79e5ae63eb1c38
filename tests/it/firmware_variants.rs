//! Issue 13, item 5: firmware variants (a Set of its own layout, a field the firmware leaves
//! out) and payloads that do not fit the profile's layout, shown as such with their raw bytes on
//! every path that reads a reply; and the MSP write paths (tuning, presets) refusing a broken
//! relation before anything is sent. Through the codec, the command line and the window-cleaner
//! simulator answering as other firmware, on a pty.

use botbench::link::{Link, LinkEvent, LinkOptions, serial};
use botbench::ops::{OpError, exchange as msp_ops};
use botbench::preset::Preset;
use botbench::profile::registry::{BUILTIN, parse};
use botbench::profile::{FieldError, Input, Profile, Registry};
use botbench::protocol::Direction;
use botbench::sim::msp_device::MspCore;
use botbench::sim::window_cleaner::{DEVICE_CODE, WindowCleaner};
use botbench::sim::{Faults, PtyServer, SharedDevice};
use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Output, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

fn botbench(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_botbench"))
        .args(args)
        .env("BOTBENCH_PROFILE_DIR", "/nonexistent")
        .output()
        .expect("runs")
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn json(o: &Output) -> serde_json::Value {
    serde_json::from_str(stdout(o).lines().next().expect("a line")).expect("JSON")
}

fn profile(name: &str) -> Arc<Profile> {
    Registry::builtin().unwrap().get(name).unwrap()
}

/// The 1-based line of the `nth` occurrence of `needle`.
fn line_of(src: &str, needle: &str, nth: usize) -> usize {
    let pos = src.match_indices(needle).nth(nth).expect("needle").0;
    botbench::document::line_col(src, pos).0
}

fn inputs(pairs: &[(&str, &str)]) -> Vec<(String, Input)> {
    pairs
        .iter()
        .map(|(k, v)| (k.to_string(), Input::from(*v)))
        .collect()
}

#[test]
fn a_short_set_is_shown_with_the_fields_read_before_the_fault_and_exits_1() {
    let frame = "ff ff 03 e1 04 96 00 0a 02 78";
    let o = botbench(&["frame", "decode", "msp", frame]);
    assert_eq!(o.status.code(), Some(1), "{}", stdout(&o));
    let out = stdout(&o);
    for want in [
        "waterPump = 150",
        "waterPumpStartAngle = 2 °",
        "payload of 4 byte(s), the layout takes 5 byte(s)",
        "payload = 96 00 0a 02",
    ] {
        assert!(out.contains(want), "{want}:\n{out}");
    }
    let doc = json(&botbench(&["frame", "decode", "msp", frame, "--json"]));
    assert_eq!(doc["ok"], false);
    assert_eq!(doc["error"], "layout");
    assert_eq!(doc["fields"].as_array().unwrap().len(), 3);
    assert_eq!(
        (
            doc["payload_len"].as_u64(),
            doc["expected_len"]["min"].as_u64()
        ),
        (Some(4), Some(5))
    );
    // The same bytes are the earlier configurator's SET 225: its variant reads them cleanly.
    let o = botbench(&[
        "frame",
        "decode",
        "msp",
        frame,
        "--profile",
        "window-cleaner-configurator",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stdout(&o));
    assert!(
        stdout(&o).contains("waterPumpDuration = 150 ms"),
        "{}",
        stdout(&o)
    );
    assert!(
        stdout(&o).contains("waterPumpMoveCnt = 2"),
        "{}",
        stdout(&o)
    );
}

#[test]
fn a_long_reply_is_shown_with_its_extra_bytes_and_exits_1() {
    // MSP_GET_PWMVALUE answered with 85 and one byte more.
    let o = botbench(&[
        "frame",
        "decode",
        "msp",
        "--msp-dir",
        "reply",
        "ff ff 82 02 55 07 d2",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stdout(&o));
    assert!(stdout(&o).contains("pwmValue = 85 %"), "{}", stdout(&o));
    assert!(
        stdout(&o).contains("1 byte(s) past the layout's last field: 07"),
        "{}",
        stdout(&o)
    );
}

#[test]
fn the_configurator_variant_leaves_out_set_224s_second_byte_when_it_is_0() {
    let p = profile("window-cleaner-configurator");
    let set = p.command("MSP_SET_BOUNDLESS").unwrap();
    let zero = p
        .encode(
            set,
            Direction::HostToDevice,
            &inputs(&[
                ("fanThrdAddE", "40"),
                ("fanUpThrdAdd", "0"),
                ("hangCnt", "3"),
            ]),
        )
        .unwrap();
    assert_eq!(zero, [40, 3]);
    let d = p.decode(set, Direction::HostToDevice, &zero).unwrap();
    assert_eq!(d.int("fanUpThrdAdd"), Some(0));
    assert_eq!(d.int("hangCnt"), Some(3));
    let seven = p
        .encode(
            set,
            Direction::HostToDevice,
            &inputs(&[
                ("fanThrdAddE", "40"),
                ("fanUpThrdAdd", "7"),
                ("hangCnt", "3"),
            ]),
        )
        .unwrap();
    assert_eq!(seven, [40, 7, 3]);
    // SET 225 has no waterPump: naming it is an error, not a silent drop.
    let spray = p.command("MSP_SET_SPRAY_VALUE").unwrap();
    let err = p
        .encode(
            spray,
            Direction::HostToDevice,
            &inputs(&[("waterPump", "1"), ("waterPumpDuration", "150")]),
        )
        .unwrap_err();
    assert!(matches!(err, FieldError::UnknownField { .. }), "{err}");
}

#[test]
fn a_variant_set_of_its_own_layout_must_be_readable_back_through_its_get() {
    let src = BUILTIN
        .iter()
        .find(|(n, _)| *n == "window-cleaner-configurator")
        .unwrap()
        .1;
    let edited = src.replacen(
        "ident: \"waterPumpMoveCnt\"",
        "ident: \"waterPumpMoveCount\"",
        1,
    );
    let err = parse("window-cleaner-configurator.ron", &edited, None).unwrap_err();
    assert!(err.message.contains("not a field of its Get"), "{err}");
    assert_eq!(err.line, line_of(&edited, "waterPumpMoveCount", 0), "{err}");
    assert_eq!(err.file, "window-cleaner-configurator.ron");
}

/// A window cleaner answering as firmware described by `firmware`, on a pty.
fn window_cleaner(firmware: Arc<Profile>) -> (PtyServer, Arc<Mutex<WindowCleaner>>) {
    let core = MspCore::new(firmware, DEVICE_CODE, 115_200);
    let wc = Arc::new(Mutex::new(WindowCleaner::with_core(core, 0)));
    let shared: SharedDevice = wc.clone();
    (PtyServer::start(shared, Faults::default()).unwrap(), wc)
}

/// Opens the pty and waits until the session has learned the device code.
fn connect(path: &str, p: &Arc<Profile>) -> Link {
    let link = Link::open(
        serial::opener(path, 115_200),
        p.clone(),
        // Generous for a loaded test machine.
        LinkOptions {
            margin: Some(Duration::from_millis(300)),
            ..LinkOptions::default()
        },
        None,
    )
    .expect("opens the pty");
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        match link
            .events()
            .recv_timeout(deadline.saturating_duration_since(Instant::now()))
        {
            Ok(LinkEvent::Identified(r)) => {
                r.expect("CMD_VERSION answered");
                return link;
            }
            Ok(_) => {}
            Err(_) => panic!("not identified"),
        }
    }
}

/// Firmware whose GET 135 answers without waterPump and whose GET 130 answers one byte more.
const DRIFT: &str = r#"(
    id: "window-cleaner-drift",
    base: "window-cleaner",
    name: (en: "Drifted firmware", zh: "固件变化"),
    commands: [
        (
            id: 135, ident: "MSP_GET_SPRAY_VALUE", name: (en: "Get spray", zh: "获取喷水"),
            kind: Get, pair: Some(225), group: Some("spray"),
            reply: [
                (ident: "waterPumpDuration", name: (en: "d", zh: "d"), type: U16, default: Some(150)),
                (ident: "waterPumpStartAngle", name: (en: "a", zh: "a"), type: U8, default: Some(30)),
                (ident: "waterPumpMoveCnt", name: (en: "c", zh: "c"), type: U8, default: Some(3)),
            ],
        ),
        (
            id: 130, ident: "MSP_GET_PWMVALUE", name: (en: "Get fan PWM", zh: "获取风机占比"),
            kind: Get, pair: Some(220), group: Some("fan"),
            reply: [
                (ident: "pwmValue", name: (en: "p", zh: "p"), type: U8, default: Some(85)),
                (ident: "pwmExtra", name: (en: "x", zh: "x"), type: U8, default: Some(7)),
            ],
        ),
    ],
)"#;

#[test]
fn replies_that_drift_from_the_layout_reach_the_tuning_path_as_misfits_with_their_bytes() {
    let firmware = Arc::new(parse("drift.ron", DRIFT, None).unwrap());
    let (server, _wc) = window_cleaner(firmware);
    let p = profile("window-cleaner");
    let link = connect(server.path(), &p);
    let client = link.client();
    for (get, raw, fault) in [
        ("MSP_GET_SPRAY_VALUE", "96 00 1e 03", "payload ends early"),
        ("MSP_GET_PWMVALUE", "55 07", "past the layout's last field"),
    ] {
        let cmd = p.command(get).unwrap();
        let err = msp_ops::read(&client, &p, cmd, &[]).unwrap_err();
        let OpError::Answer { error, .. } = &err else {
            panic!("{get}: {err}");
        };
        let FieldError::Misfit(m) = error.as_ref() else {
            panic!("{get}: {error}");
        };
        assert_eq!(botbench::protocol::hex::format(&m.payload), raw, "{get}");
        let text = err.to_string();
        assert!(
            text.contains(fault) && text.contains(&format!("raw [{raw}]")),
            "{text}"
        );
    }
}

/// A simulator started as a technician would, stopped when dropped.
struct Sim(Child, String);

impl Sim {
    fn start(args: &[&str]) -> Self {
        let mut child = Command::new(env!("CARGO_BIN_EXE_botbench"))
            .arg("sim")
            .args(args)
            .env("BOTBENCH_PROFILE_DIR", "/nonexistent")
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("botbench sim starts");
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap())
            .read_line(&mut line)
            .unwrap();
        assert!(line.starts_with("/dev/"), "'{line}'");
        Self(child, line.trim().to_string())
    }
}

impl Drop for Sim {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

#[test]
fn msp_get_shows_a_short_answer_as_such_with_its_raw_bytes() {
    let dir = std::env::temp_dir().join(format!("botbench-drift-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("window-cleaner-drift.ron");
    std::fs::write(&file, DRIFT).unwrap();
    let sim = Sim::start(&["window-cleaner", "--profile", file.to_str().unwrap()]);
    let o = botbench(&[
        "msp",
        "--margin-ms",
        "300",
        "--port",
        &sim.1,
        "get",
        "MSP_GET_SPRAY_VALUE",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}{}", stdout(&o), stderr(&o));
    let out = stdout(&o);
    assert!(
        out.contains("4-byte answer where the layout takes 5 byte(s)"),
        "{out}"
    );
    assert!(out.contains("payload = 96 00 1e 03"), "{out}");
    let o = botbench(&[
        "msp",
        "--margin-ms",
        "300",
        "--port",
        &sim.1,
        "get",
        "MSP_GET_SPRAY_VALUE",
        "--json",
    ]);
    let doc = json(&o);
    assert_eq!(doc["ok"], false);
    assert_eq!(doc["payload"], "96 00 1e 03");
    // A clean answer still exits 0.
    let o = botbench(&[
        "msp",
        "--margin-ms",
        "300",
        "--port",
        &sim.1,
        "get",
        "MSP_GET_MOTOR_VALUE",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}{}", stdout(&o), stderr(&o));
    drop(sim);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_configurator_variant_writes_and_reads_back_against_its_firmware() {
    let p = profile("window-cleaner-configurator");
    let (server, wc) = window_cleaner(p.clone());
    let link = connect(server.path(), &p);
    let client = link.client();
    let spray = p.command("MSP_SET_SPRAY_VALUE").unwrap();
    let checks = msp_ops::write_verified(
        &client,
        &p,
        spray,
        &inputs(&[
            ("waterPumpDuration", "200"),
            ("waterPumpStartAngle", "45"),
            ("waterPumpMoveCnt", "4"),
        ]),
    )
    .unwrap();
    assert_eq!(checks.len(), 3);
    assert!(checks.iter().all(|c| c.ok()), "{checks:?}");
    let boundless = p.command("MSP_SET_BOUNDLESS").unwrap();
    let checks = msp_ops::write_verified(
        &client,
        &p,
        boundless,
        &inputs(&[
            ("fanThrdAddE", "41"),
            ("fanUpThrdAdd", "0"),
            ("hangCnt", "5"),
        ]),
    )
    .unwrap();
    assert!(checks.iter().all(|c| c.ok()), "{checks:?}");
    let wc = wc.lock().unwrap();
    assert_eq!(wc.param("waterPumpDuration"), Some(200));
    assert_eq!(wc.param("fanUpThrdAdd"), Some(0));
    assert_eq!(wc.param("hangCnt"), Some(5));
}

// ------------------------------------------------------------ relations on the MSP write paths

#[test]
fn tuning_and_presets_refuse_a_broken_relation_before_anything_is_sent() {
    let p = profile("window-cleaner");
    let (server, wc) = window_cleaner(p.clone());
    let link = connect(server.path(), &p);
    let client = link.client();
    let set = p.command("MSP_SET_USE_FAN_OUTPUT_PID").unwrap();
    let bad = inputs(&[
        ("fanPwmvalueAtIdle", "60"),
        ("fanPwmvalueMin", "70"),
        ("fanPwmvalueMax", "100"),
        ("defaultTarget", "2.75"),
        ("maxTarget", "3.00"),
        ("minTarget", "3.50"),
    ]);
    let err = msp_ops::write_verified(&client, &p, set, &bad).unwrap_err();
    assert!(err.is_input(), "{err}");
    assert!(err.to_string().contains("minTarget"), "{err}");
    assert_eq!(
        wc.lock().unwrap().param("minTarget"),
        Some(250),
        "nothing written"
    );
    // A preset holding it is refused when it is loaded, at its command's line.
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/presets/window-cleaner-factory.ron"
    ))
    .unwrap()
    .replacen("\"minTarget\": \"2.50\"", "\"minTarget\": \"3.50\"", 1);
    let err = Preset::parse("factory.ron", &text, &p).unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains("(minTarget) 3.50 must be ≤"), "{msg}");
    assert!(
        msg.contains(&format!(
            ":{}:",
            line_of(&text, "\"MSP_SET_USE_FAN_OUTPUT_PID\"", 0)
        )),
        "{msg}"
    );
}

#[test]
fn a_longer_cmd_version_identifies_the_device_and_keeps_its_extra_bytes() {
    use botbench::link::DeviceInfo;
    let p = profile("window-cleaner");
    let info = DeviceInfo::from_version(&p, &[3, 1, 4, 2, 1, 0, 7, 0x0f, 0xaa]).unwrap();
    assert_eq!((info.hw, info.flags), (3, Some(0x0f)));
    assert_eq!(info.extra.as_deref(), Some("aa"));
    let info = DeviceInfo::from_version(&p, &[3, 1, 4, 2, 1, 0, 7]).unwrap();
    assert_eq!((info.flags, info.extra), (None, None));
    let err = DeviceInfo::from_version(&p, &[3, 1, 4, 2, 1]).unwrap_err();
    assert!(err.contains("raw [03 01 04 02 01]"), "{err}");
}
