//! Issue 13, items 2, 3, 4 and 6: one name per decoded field, defaults where a frame is built,
//! converted temperatures with their raw value, and relations between fields (checked at load,
//! and before a servo parameter is written). Firmware variants and misfits are in
//! firmware_variants.rs.

use botbench::ops::Device;
use botbench::ops::servo as servo_ops;
use botbench::profile::registry::parse;
use botbench::profile::{Input, Value};
use botbench::protocol::Direction;
use botbench::sim::servo_bus::SimServo;

use crate::support::cli::run as botbench;
use crate::support::servo::Bench;
use crate::support::{builtin_src, inputs, line_of, profile};

// ------------------------------------------------------------ 2. one name per decoded field

#[test]
fn a_write_of_the_id_parameter_names_the_new_id_apart_from_the_servo_id() {
    let o = botbench(&[
        "frame",
        "decode",
        "servo",
        "12 4c 04 03 00 22 05 8c",
        "--json",
    ]);
    assert_eq!(o.code, 0, "{}", o.err);
    let doc = o.json();
    let names: Vec<&str> = doc["fields"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["field"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["servo_id", "data_id", "assigned_id"]);
    assert_eq!(doc["fields"][0]["value"], 0);
    assert_eq!(doc["fields"][2]["value"], 5);
}

#[test]
fn a_profile_whose_decoded_frame_would_carry_two_values_of_one_name_is_refused() {
    // Parameter 34 named as the frames' own first field.
    let src = builtin_src("servo");
    let from = "ident: \"assigned_id\"";
    let edited = src.replacen(from, "ident: \"servo_id\"", 1);
    let err = parse("servo.ron", &edited, None).unwrap_err();
    assert!(err.message.contains("two values named 'servo_id'"), "{err}");
    assert_eq!(
        err.line,
        line_of(
            &edited,
            "ident: \"servo_id\", name: (en: \"Servo ID (assigned)\"",
            0
        ),
        "{err}"
    );
    // A Tuya data point named as a field of the frame that carries it.
    let tuya = builtin_src("tuya-vacuum");
    let dp_cmd = profile("tuya-vacuum");
    let list = dp_cmd
        .commands
        .iter()
        .flat_map(|c| c.request.iter().chain(&c.reply))
        .find(|f| f.ty == botbench::profile::FieldType::DataPoints)
        .map(|f| f.ident.clone())
        .unwrap();
    let first_dp = &dp_cmd.data_points[0].field.ident;
    let edited = tuya.replacen(
        &format!("ident: \"{first_dp}\""),
        &format!("ident: \"{list}\""),
        1,
    );
    let err = parse("tuya-vacuum.ron", &edited, None).unwrap_err();
    assert!(err.message.contains("two values named"), "{err}");
}

// ------------------------------------------------------------ 3. defaults

#[test]
fn an_omitted_field_with_a_default_takes_it() {
    let o = botbench(&["frame", "encode", "servo", "SET_ORIGIN", "servo_id=0"]);
    assert_eq!(o.code, 0, "{}", o.err);
    assert_eq!(o.out.trim(), "12 4c 17 02 00 00 77");
    // The SDK's t_acc = t_dec = 20 ms and power 0: its bytes for `set_servo_angle(1, 90.5,
    // interval=500)` (tests/sdk/vectors.jsonl, set_servo_angle/by_interval).
    let o = botbench(&[
        "frame",
        "encode",
        "servo",
        "ROTATE_BY_INTERVAL",
        "servo_id=1",
        "angle=90.5",
        "interval=500",
    ]);
    assert_eq!(o.code, 0, "{}", o.err);
    assert_eq!(
        o.out.trim(),
        "12 4c 0b 0b 01 89 03 f4 01 14 00 14 00 00 00 1e"
    );
    // A field without a default is still required.
    let o = botbench(&[
        "frame",
        "encode",
        "servo",
        "ROTATE_BY_INTERVAL",
        "servo_id=1",
    ]);
    assert_eq!(o.code, 2);
    assert!(o.err.contains("'angle' is missing"), "{}", o.err);
}

// ------------------------------------------------------------ 4. temperature

#[test]
fn a_thermistor_reading_shows_in_celsius_with_its_raw_value_beside() {
    // READ_DATA parameter 4 answered with 32: 241.3 °C by the SDK's conversion.
    let reply = "05 1c 03 04 01 04 20 00 4d";
    let o = botbench(&["frame", "decode", "servo", reply]);
    assert_eq!(o.code, 0, "{}", o.err);
    assert!(
        o.out.contains("temprature = 241.3 °C (raw 32)"),
        "{}",
        o.out
    );
    let doc = botbench(&["frame", "decode", "servo", reply, "--json"]).json();
    let t = &doc["fields"][2];
    assert_eq!(t["field"], "temprature");
    assert_eq!(t["value"], 32);
    assert!(
        (t["converted"].as_f64().unwrap() - 241.31).abs() < 0.01,
        "{t}"
    );
    assert_eq!(t["unit"], "°C");
    // No temperature stands for raw 0: shown as such, never as a number.
    let monitor = "05 1c 16 10 01 e8 1c 78 00 78 03 00 00 01 39 30 00 00 03 00 ac";
    let doc = botbench(&["frame", "decode", "servo", monitor, "--json"]).json();
    let t = &doc["fields"][4];
    assert_eq!(
        (t["value"].as_i64(), t["converted"].is_null()),
        (Some(0), true)
    );
    assert_eq!(t["display"], "n/a (raw 0)");
}

// ------------------------------------------------------------ 6. relations

#[test]
fn a_minimum_above_its_maximum_is_refused_naming_both_fields() {
    let p = profile("window-cleaner");
    let set = p.command("MSP_SET_USE_FAN_OUTPUT_PID").unwrap();
    let values = [
        ("fanPwmvalueAtIdle", "60"),
        ("fanPwmvalueMin", "70"),
        ("fanPwmvalueMax", "100"),
        ("defaultTarget", "3.20"),
        ("maxTarget", "3.00"),
        ("minTarget", "3.50"),
    ];
    let err = p
        .encode(set, Direction::HostToDevice, &inputs(&values))
        .unwrap_err();
    assert_eq!(
        err.to_string(),
        "Minimum pressure target (minTarget) 3.50 must be ≤ Default pressure target (defaultTarget) 3.20"
    );
    // The command line refuses it before building a frame.
    let mut args = vec!["frame", "encode", "msp", "MSP_SET_USE_FAN_OUTPUT_PID"];
    let kv: Vec<String> = values.iter().map(|(k, v)| format!("{k}={v}")).collect();
    args.extend(kv.iter().map(String::as_str));
    let o = botbench(&args);
    assert_eq!(o.code, 2);
    assert!(o.err.contains("(minTarget) 3.50 must be ≤"), "{}", o.err);
    // Fan PWM minimum ≤ maximum.
    let comp = p.command("MSP_SET_USE_FAN_LEVEL_DYNAMIC_COMP").unwrap();
    let err = p
        .encode(
            comp,
            Direction::HostToDevice,
            &inputs(&[("pwmvalueMax", "60"), ("pwmvalueMin", "77")]),
        )
        .unwrap_err();
    assert!(
        err.to_string()
            .contains("(pwmvalueMin) 77 % must be ≤ Fan PWM maximum (pwmvalueMax) 60 %"),
        "{err}"
    );
}

#[test]
fn a_servo_angle_limit_is_checked_against_the_other_one_the_servo_holds() {
    let bench = Bench::new(vec![
        SimServo::fresh(1)
            .with_id(1)
            .with_param(51, 300)
            .with_param(52, -300),
    ]);
    let client = bench.client();
    let p = &bench.profile;
    let low = p.find_param("angle_limit_low").unwrap();
    let err =
        servo_ops::write_param(Device::new(&client, p), 1, low, Input::from("45")).unwrap_err();
    assert_eq!(
        err.to_string(),
        "Angle lower limit (angle_limit_low) 45.0 ° must be ≤ Angle upper limit (angle_limit_high) 30.0 °"
    );
    assert_eq!(bench.bus().servos()[0].param(52), Some(-300));
    let check =
        servo_ops::write_param(Device::new(&client, p), 1, low, Input::from("-45")).unwrap();
    assert!(check.ok());
    assert_eq!(check.read, Value::Int(-450));
}

#[test]
fn a_malformed_relation_is_refused_at_load_with_its_line_and_column() {
    let src = builtin_src("window-cleaner");
    let anchor = "(low: \"MSP_GET_USE_FAN_OUTPUT_PID.minTarget\", high: \"MSP_GET_USE_FAN_OUTPUT_PID.defaultTarget\")";
    assert!(src.contains(anchor), "test setup");
    for (bad, says) in [
        (
            "(low: \"MSP_GET_USE_FAN_OUTPUT_PID.minTargt\", high: \"MSP_GET_USE_FAN_OUTPUT_PID.defaultTarget\")",
            "MSP_GET_USE_FAN_OUTPUT_PID has no field 'minTargt'",
        ),
        (
            "(low: \"MSP_GET_USE_FAN_OUTPUT_PID.minTarget\", high: \"MSP_GET_PWMVALUE.pwmValue\")",
            "not fields of one command",
        ),
        (
            "(low: \"MSP_GET_USE_FAN_OUTPUT_PID.minTarget\", high: \"pwmValue\")",
            "no parameter 'pwmValue'",
        ),
        (
            "(low: \"MSP_GET_USE_FAN_OUTPUT_PID.maxTarget\", high: \"MSP_GET_USE_FAN_OUTPUT_PID.minTarget\")",
            "the defaults break it",
        ),
    ] {
        let edited = src.replacen(anchor, bad, 1);
        let err = parse("window-cleaner.ron", &edited, None).unwrap_err();
        assert!(err.message.contains(says), "{says}: {err}");
        assert_eq!(err.line, line_of(&edited, bad, 0), "{err}");
        assert!(err.col > 1, "{err}");
    }
}

#[test]
fn a_relation_summing_fields_is_checked_at_load_and_refused_across_commands() {
    let src = builtin_src("servo");
    let anchor = "(low: \"ROTATE_MTURN_BY_INTERVAL.t_acc + ROTATE_MTURN_BY_INTERVAL.t_dec\", high: \"ROTATE_MTURN_BY_INTERVAL.interval\")";
    assert!(src.contains(anchor), "test setup");
    assert!(parse("servo.ron", src, None).is_ok());
    for (bad, says) in [
        (
            "(low: \"ROTATE_MTURN_BY_INTERVAL.t_acc + ROTATE_MTURN_BY_VELOCITY.t_dec\", high: \"ROTATE_MTURN_BY_INTERVAL.interval\")",
            "not fields of one command",
        ),
        (
            "(low: \"ROTATE_MTURN_BY_INTERVAL.t_acc + ROTATE_MTURN_BY_INTERVAL.t_decc\", high: \"ROTATE_MTURN_BY_INTERVAL.interval\")",
            "has no field 't_decc'",
        ),
        (
            "(low: \"angle_limit_low + over_volt_low\", high: \"angle_limit_high\")",
            "not fields of one command",
        ),
    ] {
        let edited = src.replacen(anchor, bad, 1);
        let err = parse("servo.ron", &edited, None).unwrap_err();
        assert!(err.message.contains(says), "{says}: {err}");
        assert_eq!(err.line, line_of(&edited, bad, 0), "{err}");
    }
}
