//! Issue 13, item 5: firmware variants (a Set of its own layout, a field the firmware leaves
//! out) and payloads that do not fit the profile's layout, shown as such with their raw bytes on
//! every path that reads a reply; and the MSP write paths (tuning, presets) refusing a broken
//! relation before anything is sent. Through the codec, the command line and the window-cleaner
//! simulator answering as other firmware, on a pty.

use botbench::ops::Device;
use botbench::ops::{OpError, exchange as msp_ops};
use botbench::preset::Preset;
use botbench::profile::registry::parse;
use botbench::profile::{FieldError, Profile};
use botbench::protocol::Direction;
use botbench::sim::msp_device::MspCore;
use botbench::sim::window_cleaner::{DEVICE_CODE, WindowCleaner};
use std::sync::Arc;

use crate::support::cli::{Sim, run as botbench};
use crate::support::{Served, builtin_src, connect, inputs, line_of, profile, serve, temp_dir};

#[test]
fn a_short_set_is_shown_with_the_fields_read_before_the_fault_and_exits_1() {
    let frame = "ff ff 03 e1 04 96 00 0a 02 78";
    let o = botbench(&["frame", "decode", "msp", frame]);
    assert_eq!(o.code, 1, "{}", o.out);
    let out = o.out;
    for want in [
        "waterPump = 150",
        "waterPumpStartAngle = 2 °",
        "payload of 4 byte(s), the layout takes 5 byte(s)",
        "payload = 96 00 0a 02",
    ] {
        assert!(out.contains(want), "{want}:\n{out}");
    }
    let doc = botbench(&["frame", "decode", "msp", frame, "--json"]).json();
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
    assert_eq!(o.code, 0, "{}", o.out);
    assert!(o.out.contains("waterPumpDuration = 150 ms"), "{}", o.out);
    assert!(o.out.contains("waterPumpMoveCnt = 2"), "{}", o.out);
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
    assert_eq!(o.code, 1, "{}", o.out);
    assert!(o.out.contains("pwmValue = 85 %"), "{}", o.out);
    assert!(
        o.out.contains("1 byte(s) past the layout's last field: 07"),
        "{}",
        o.out
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
    let src = builtin_src("window-cleaner-configurator");
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
fn window_cleaner(firmware: Arc<Profile>) -> Served<WindowCleaner> {
    let core = MspCore::new(firmware, DEVICE_CODE, 115_200);
    serve(WindowCleaner::with_core(core, 0))
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
    let wc = window_cleaner(firmware);
    let p = profile("window-cleaner");
    let link = connect(&wc, &p);
    let client = link.client();
    for (get, raw, fault) in [
        ("MSP_GET_SPRAY_VALUE", "96 00 1e 03", "payload ends early"),
        ("MSP_GET_PWMVALUE", "55 07", "past the layout's last field"),
    ] {
        let cmd = p.command(get).unwrap();
        let err = msp_ops::read(Device::new(&client, &p), cmd, &[]).unwrap_err();
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

#[test]
fn msp_get_shows_a_short_answer_as_such_with_its_raw_bytes() {
    let dir = temp_dir();
    let file = dir.path().join("window-cleaner-drift.ron");
    std::fs::write(&file, DRIFT).unwrap();
    let sim = Sim::start(&["window-cleaner", "--profile", file.to_str().unwrap()]);
    let o = sim.cli("msp", &["get", "MSP_GET_SPRAY_VALUE"]);
    assert_eq!(o.code, 1, "{}{}", o.out, o.err);
    let out = o.out;
    assert!(
        out.contains("4-byte answer where the layout takes 5 byte(s)"),
        "{out}"
    );
    assert!(out.contains("payload = 96 00 1e 03"), "{out}");
    let o = sim.cli("msp", &["get", "MSP_GET_SPRAY_VALUE", "--json"]);
    let doc = o.json();
    assert_eq!(doc["ok"], false);
    assert_eq!(doc["payload"], "96 00 1e 03");
    // A clean answer still exits 0.
    let o = sim.cli("msp", &["get", "MSP_GET_MOTOR_VALUE"]);
    assert_eq!(o.code, 0, "{}{}", o.out, o.err);
    drop(sim);
}

#[test]
fn the_configurator_variant_writes_and_reads_back_against_its_firmware() {
    let p = profile("window-cleaner-configurator");
    let wc = window_cleaner(p.clone());
    let link = connect(&wc, &p);
    let client = link.client();
    let spray = p.command("MSP_SET_SPRAY_VALUE").unwrap();
    let checks = msp_ops::write_verified(
        Device::new(&client, &p),
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
        Device::new(&client, &p),
        boundless,
        &inputs(&[
            ("fanThrdAddE", "41"),
            ("fanUpThrdAdd", "0"),
            ("hangCnt", "5"),
        ]),
    )
    .unwrap();
    assert!(checks.iter().all(|c| c.ok()), "{checks:?}");
    let wc = wc.sim();
    assert_eq!(wc.param("waterPumpDuration"), Some(200));
    assert_eq!(wc.param("fanUpThrdAdd"), Some(0));
    assert_eq!(wc.param("hangCnt"), Some(5));
}

// ------------------------------------------------------------ relations on the MSP write paths

#[test]
fn tuning_and_presets_refuse_a_broken_relation_before_anything_is_sent() {
    let p = profile("window-cleaner");
    let wc = window_cleaner(p.clone());
    let link = connect(&wc, &p);
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
    let err = msp_ops::write_verified(Device::new(&client, &p), set, &bad).unwrap_err();
    assert!(err.is_input(), "{err}");
    assert!(err.to_string().contains("minTarget"), "{err}");
    assert_eq!(wc.sim().param("minTarget"), Some(250), "nothing written");
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
