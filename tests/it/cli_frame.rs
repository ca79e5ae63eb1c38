//! The frame tool as a user runs it: output, JSON keys and exit codes.

use crate::support::cli::run as botbench;
use crate::support::temp_dir;

#[test]
fn decodes_the_seed_rotate_example_with_named_fields() {
    let o = botbench(&[
        "frame",
        "decode",
        "servo",
        "0x12 0x4c 0x08 0x07 0x02 0x84 0x03 0xf4 0x01 0x00 0x00 0xeb",
    ]);
    assert_eq!(o.code, 0, "{}", o.err);
    let out = o.out;
    assert!(out.contains("ROTATE"), "{out}");
    assert!(out.contains("angle = 90.0 °"), "{out}");
    assert!(out.contains("interval = 500 ms"), "{out}");
}

#[test]
fn json_output_has_stable_keys_and_reports_checksum_errors() {
    // A valid PING reply, then the same frame with a wrong checksum, then junk.
    let o = botbench(&[
        "frame",
        "decode",
        "servo",
        "05 1c 01 01 03 26",
        "05 1c 01 01 03 27",
        "00 11",
        "--json",
    ]);
    assert_eq!(o.code, 1, "frame errors exit 1");
    let docs = o.json_lines();
    assert_eq!(docs.len(), 3, "{docs:?}");
    assert_eq!(docs[0]["ok"], true);
    assert_eq!(docs[0]["name"], "PING");
    assert_eq!(docs[0]["direction"], "device_to_host");
    assert_eq!(docs[0]["fields"][0]["field"], "servo_id");
    assert_eq!(docs[0]["fields"][0]["value"], 3);
    assert_eq!(docs[1]["ok"], false);
    assert_eq!(docs[1]["error"], "checksum");
    assert_eq!(docs[1]["expected"], 0x26);
    assert_eq!(docs[1]["actual"], 0x27);
    assert_eq!(docs[1]["offset"], 6);
    assert_eq!(docs[2]["error"], "junk");
    assert_eq!(docs[2]["len"], 2);
}

#[test]
fn hex_may_be_spaced_prefixed_or_packed() {
    for form in [
        "55 aa 00 00 00 00 ff",
        "0x55,0xAA,0x00,0x00,0x00,0x00,0xff",
        "55aa00000000ff",
    ] {
        let o = botbench(&["frame", "decode", "tuya", form, "--json"]);
        assert_eq!(o.code, 0, "{form}: {}", o.err);
        assert_eq!(o.json_lines()[0]["command"], 0, "{form}");
    }
}

#[test]
fn an_unknown_command_id_is_decoded_raw_with_its_id() {
    // MSP reply to command 250, which no profile knows.
    let crc = 250u8 ^ 2 ^ 0xAB ^ 0xCD;
    let hex = format!("ff ff fa 02 ab cd {crc:02x}");
    let o = botbench(&["frame", "decode", "msp", &hex, "--json"]);
    assert_eq!(o.code, 0, "{}", o.err);
    let doc = &o.json_lines()[0];
    assert_eq!(doc["command"], 250);
    assert_eq!(doc["name"], serde_json::Value::Null);
    assert_eq!(doc["payload"], "ab cd");
}

#[test]
fn encode_builds_the_seed_frames_from_names_and_display_values() {
    let o = botbench(&[
        "frame",
        "encode",
        "servo",
        "rotate",
        "servo_id=2",
        "angle=90",
        "interval=500",
        "power=0",
    ]);
    assert_eq!(o.code, 0, "{}", o.err);
    assert_eq!(o.out.trim(), "12 4c 08 07 02 84 03 f4 01 00 00 eb");

    let o = botbench(&["frame", "encode", "tuya", "0", "--json"]);
    assert_eq!(o.json_lines()[0]["hex"], "55 aa 00 00 00 00 ff");

    // MSP SET with the profile's device code and the crc over device..data.
    let o = botbench(&["frame", "encode", "msp", "MSP_SET_PWMVALUE", "pwmValue=85"]);
    let crc = 3u8 ^ 220 ^ 1 ^ 85;
    assert_eq!(o.out.trim(), format!("ff ff 03 dc 01 55 {crc:02x}"));
}

#[test]
fn encoded_frames_decode_back_to_the_same_values() {
    let o = botbench(&[
        "frame",
        "encode",
        "msp",
        "132",
        "--reply",
        "fanPwmvalueAtIdle=30",
        "fanPwmvalueMin=77",
        "fanPwmvalueMax=100",
        "defaultTarget=2.75",
        "maxTarget=3",
        "minTarget=2.5",
    ]);
    assert_eq!(o.code, 0, "{}", o.err);
    let hex = o.out;
    let o = botbench(&["frame", "decode", "msp", hex.trim(), "--json"]);
    let doc = &o.json_lines()[0];
    let fields = doc["fields"].as_array().unwrap();
    let get = |name: &str| {
        fields
            .iter()
            .find(|f| f["field"] == name)
            .map(|f| f["display"].as_str().unwrap().to_string())
    };
    assert_eq!(get("defaultTarget").as_deref(), Some("2.75"));
    assert_eq!(get("minTarget").as_deref(), Some("2.50"));
    assert_eq!(get("fanPwmvalueMin").as_deref(), Some("77 %"));
}

#[test]
fn bad_input_gets_a_clear_message_and_exit_code_2() {
    let cases: &[(&[&str], &str)] = &[
        (&["frame", "decode", "msp", "12 4g"], "not a hex digit"),
        (
            &["frame", "decode", "msp", "124"],
            "odd number of hex digits",
        ),
        (
            &["frame", "encode", "msp", "MSP_SET_PWMVALUE", "pwmValue=101"],
            "out of range; allowed 0 to 100",
        ),
        (
            &[
                "frame",
                "encode",
                "msp",
                "MSP_SET_PWMVALUE",
                "pwmValue=lots",
            ],
            "not a number",
        ),
        (
            &["frame", "encode", "msp", "MSP_SET_PWMVALUE", "fanSpeed=1"],
            "has no field 'fanSpeed'",
        ),
        (
            &["frame", "encode", "msp", "MSP_NOPE"],
            "has no command 'MSP_NOPE'",
        ),
        (
            &["frame", "encode", "servo", "set", "servo_id=1"],
            "has no command",
        ),
        (
            &["frame", "encode", "tuya", "6", "mode=fly"],
            "'fly' is not one of",
        ),
        (&["frame", "encode", "tuya", "6", "battery=50"], "read-only"),
        (
            &["frame", "encode", "msp", "--profile", "servo", "1"],
            "speaks servo, not msp",
        ),
        (
            &["frame", "decode", "msp", "ff", "--profile", "nope"],
            "no profile 'nope'",
        ),
        (&["frame", "frobnicate"], "unrecognized subcommand"),
    ];
    for (args, want) in cases {
        let o = botbench(args);
        assert_eq!(o.code, 2, "{args:?}: {}", o.err);
        assert!(o.err.contains(want), "{args:?}: {}", o.err);
    }
}

#[test]
fn a_malformed_profile_file_is_refused_with_line_and_column() {
    let dir = temp_dir();
    let path = dir.path().join("window-cleaner.ron");
    std::fs::write(
        &path,
        "Profile(\n  id: \"window-cleaner\",\n  name: oops,\n)",
    )
    .unwrap();
    let o = botbench(&[
        "frame",
        "decode",
        "msp",
        "ff",
        "--profile",
        path.to_str().unwrap(),
    ]);
    assert_eq!(o.code, 2);
    assert!(o.err.contains(":3:"), "{}", o.err);
}

#[test]
fn truncated_and_over_long_frames_are_reported() {
    let o = botbench(&[
        "frame",
        "decode",
        "tuya",
        "55 aa 03 07 ff ff 00",
        "55 aa 00 00 00",
        "--json",
    ]);
    assert_eq!(o.code, 1);
    let kinds: Vec<String> = o
        .json_lines()
        .iter()
        .map(|d| d["error"].as_str().unwrap_or("ok").to_string())
        .collect();
    assert!(kinds.contains(&"too_long".to_string()), "{kinds:?}");
    assert_eq!(
        kinds.last().map(String::as_str),
        Some("truncated"),
        "{kinds:?}"
    );
}
