//! The servo vendor's SDK as the byte reference (tests/sdk/README.md): every frame the SDK
//! wrote or read in `tests/sdk/vectors.jsonl` decodes in botbench with the servo profile, fits its
//! layout exactly, carries no two values of one name, and encodes back to the same bytes from its
//! decoded values. The SDK's temperature conversion and defaults agree with the profile's.

use botbench::packet::{MspDirection, decode_all};
use botbench::profile::{Input, Profile, Protocol, Registry, Value};
use botbench::protocol::{Direction, hex, servo};
use serde_json::Value as Json;
use std::collections::{BTreeSet, HashSet};

fn vectors() -> Vec<Json> {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/sdk/vectors.jsonl"
    ))
    .expect("tests/sdk/vectors.jsonl");
    text.lines()
        .map(|l| serde_json::from_str(l).expect("one JSON document a line"))
        .collect()
}

fn servo_profile() -> std::sync::Arc<Profile> {
    Registry::builtin().unwrap().get("servo").unwrap()
}

/// Every `{cmd, hex}` frame in a document (requests, replies, set-up calls, unread frames).
fn frames(doc: &Json, out: &mut Vec<(u8, Vec<u8>)>) {
    match doc {
        Json::Object(map) => {
            if let (Some(cmd), Some(Json::String(h))) = (map.get("cmd"), map.get("hex")) {
                let cmd = cmd.as_u64().expect("cmd is a number") as u8;
                out.push((cmd, hex::parse(h).expect("hex")));
            }
            for (k, v) in map {
                // `rx` holds bytes as they arrived (echoes, bursts), not frames.
                if k != "rx" {
                    frames(v, out);
                }
            }
        }
        Json::Array(items) => items.iter().for_each(|v| frames(v, out)),
        _ => {}
    }
}

/// Decodes one whole frame, checks it fits and that its names are unique, and encodes it back.
fn round_trip(p: &Profile, name: &str, bytes: &[u8]) -> (u8, Direction) {
    let items = decode_all(Protocol::Servo, MspDirection::Auto, bytes);
    let [item] = items.as_slice() else {
        panic!("{name}: {} frames in {}", items.len(), hex::format(bytes));
    };
    let packet = item
        .result
        .as_ref()
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(packet.wire, bytes, "{name}");
    let cmd = packet
        .command_in(p)
        .unwrap_or_else(|| panic!("{name}: command {} is not in the profile", packet.command));
    let d = p
        .decode(cmd, packet.direction, &packet.payload)
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    let mut seen = HashSet::new();
    for v in &d.values {
        assert!(
            seen.insert(v.ident.to_ascii_lowercase()),
            "{name}: two values named {} in {}",
            v.ident,
            packet.summary(p)
        );
    }
    let inputs: Vec<(String, Input)> = d
        .values
        .iter()
        .map(|v| (v.ident.clone(), Input::Raw(v.value.clone())))
        .collect();
    let payload = p
        .encode(cmd, packet.direction, &inputs)
        .unwrap_or_else(|e| panic!("{name}: {} does not encode back: {e}", cmd.ident));
    let frame = servo::Frame {
        direction: packet.direction,
        command: packet.command,
        content: payload,
    };
    assert_eq!(
        hex::format(&frame.encode().unwrap()),
        hex::format(bytes),
        "{name}: {}",
        cmd.ident
    );
    (packet.command, packet.direction)
}

#[test]
fn every_sdk_frame_decodes_fits_and_encodes_back_byte_identical() {
    let p = servo_profile();
    let docs = vectors();
    assert_eq!(docs[0]["kind"], "meta");
    assert_eq!(docs[0]["version"], "1.3.12");
    let mut requests = BTreeSet::new();
    let mut replies = BTreeSet::new();
    let mut count = 0;
    for doc in docs.iter().filter(|d| d["kind"] == "op") {
        let name = doc["name"].as_str().unwrap();
        let mut found = Vec::new();
        frames(doc, &mut found);
        for (cmd, bytes) in found {
            let (command, dir) = round_trip(&p, name, &bytes);
            assert_eq!(command, cmd, "{name}");
            match dir {
                Direction::HostToDevice => requests.insert(command),
                Direction::DeviceToHost => replies.insert(command),
            };
            count += 1;
        }
    }
    // Every command the SDK sends, the five issue 13 added among them.
    let sdk: BTreeSet<u8> = [
        1, 2, 3, 4, 5, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 22, 23, 24, 25,
    ]
    .into();
    assert_eq!(requests, sdk);
    assert_eq!(replies, [1, 2, 3, 4, 5, 10, 16, 22].into());
    assert!(count > 400, "{count} frames");
}

#[test]
fn the_bus_wide_and_synchronous_commands_say_what_their_first_byte_is() {
    let p = servo_profile();
    let decode = |h: &str| {
        let bytes = hex::parse(h).unwrap();
        let f = match &decode_all(Protocol::Servo, MspDirection::Auto, &bytes)[0].result {
            Ok(packet) => packet.clone(),
            Err(e) => panic!("{e}"),
        };
        let d = f.decode(&p).unwrap().unwrap();
        let named: Vec<(String, Value)> =
            d.values.into_iter().map(|v| (v.ident, v.value)).collect();
        (f.servo_target().unwrap(), named)
    };
    // BEGIN_ASYNC: no content, every servo.
    let (target, named) = decode("12 4c 12 00 70");
    assert_eq!(target, servo::Target::Bus);
    assert!(named.is_empty());
    // END_ASYNC: a cancel flag, not a servo id.
    let (target, named) = decode("12 4c 13 01 01 73");
    assert_eq!(target, servo::Target::Bus);
    assert_eq!(named, [("cancel".to_string(), Value::Int(1))]);
    // SYNC_COMMAND with MONITOR for servos 1, 2, 3 (tests/sdk/README.md).
    let (target, named) = decode("12 4c 19 06 16 01 03 01 02 03 9d");
    assert_eq!(
        target,
        servo::Target::Sync {
            sub_command: 22,
            ids: vec![1, 2, 3]
        }
    );
    let idents: Vec<&str> = named.iter().map(|(k, _)| k.as_str()).collect();
    assert_eq!(
        idents,
        [
            "sub_command",
            "record_len",
            "count",
            "servo_id[0]",
            "servo_id[1]",
            "servo_id[2]"
        ]
    );
}

#[test]
fn the_profile_converts_temperatures_as_the_sdk_does() {
    let p = servo_profile();
    let mut compared = 0;
    for doc in vectors().iter().filter(|d| {
        let n = d["name"].as_str().unwrap_or("");
        n.starts_with("query_temperature/raw_") || n.starts_with("query_servo_monitor/temp_raw_")
    }) {
        let name = doc["name"].as_str().unwrap();
        let reply = hex::parse(doc["replies"][0]["hex"].as_str().unwrap()).unwrap();
        let packet = match &decode_all(Protocol::Servo, MspDirection::Auto, &reply)[0].result {
            Ok(packet) => packet.clone(),
            Err(e) => panic!("{e}"),
        };
        let d = packet.decode(&p).unwrap().unwrap();
        let t = d
            .values
            .iter()
            .find(|v| v.field.convert.is_some())
            .unwrap_or_else(|| panic!("{name}: no converted temperature"));
        let sdk = match &doc["returned"] {
            Json::Number(n) => n.as_f64(),
            Json::Object(o) => o.get("temp").and_then(Json::as_f64),
            _ => None,
        };
        match (t.converted(), sdk, doc["error"].is_null()) {
            // The SDK's MONITOR reads an undefined conversion (raw 0, above 4096) as 0.
            (None, Some(s), true) => assert_eq!(s, 0.0, "{name}"),
            // The SDK raises (ZeroDivisionError, math domain) where the conversion is undefined.
            (None, _, false) => {}
            (Some(ours), Some(s), true) => {
                assert!(
                    (ours - s).abs() < 1e-6,
                    "{name}: {ours} against the SDK's {s}"
                );
                assert!(t.display().contains(&format!("(raw {})", int(&t.value))));
            }
            other => panic!("{name}: {other:?}"),
        }
        compared += 1;
    }
    assert!(compared >= 18, "{compared} temperatures compared");
}

fn int(v: &Value) -> i64 {
    match v {
        Value::Int(i) => *i,
        other => panic!("{other:?}"),
    }
}

#[test]
fn omitted_fields_take_the_sdks_defaults() {
    // `set_servo_angle(is_mturn=True, interval=1000)`: t_acc = t_dec = 20, power 0.
    let p = servo_profile();
    let cmd = p.command("ROTATE_MTURN_BY_INTERVAL").unwrap();
    let inputs = [
        ("servo_id".to_string(), Input::from("1")),
        ("angle".to_string(), Input::from("3600")),
        ("interval".to_string(), Input::from("1000")),
    ];
    let payload = p.encode(cmd, Direction::HostToDevice, &inputs).unwrap();
    let frame = servo::Frame::request(cmd.id, payload).encode().unwrap();
    let sdk = vectors()
        .into_iter()
        .find(|d| d["name"] == "set_servo_angle/mturn_by_interval_defaults")
        .unwrap();
    assert_eq!(
        hex::format(&frame),
        hex::format(&hex::parse(sdk["requests"][0]["hex"].as_str().unwrap()).unwrap())
    );
}
