//! Presets as documents: validation against the profiles, round trips, save, diff and apply
//! against the simulated window cleaner, and refusals of bad presets.

use super::*;
use botbench::ops::{Device, Run};

#[test]
fn the_factory_preset_validates_and_holds_the_profile_defaults() {
    let p = profile("window-cleaner");
    let loaded = Preset::load(Path::new(FACTORY), &p).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(loaded.preset.version, 1);
    assert_eq!(loaded.preset.profile, "window-cleaner");
    let idents: Vec<&str> = loaded.writes.iter().map(|w| w.command.as_str()).collect();
    assert_eq!(
        idents,
        [
            "MSP_SET_PWMVALUE",
            "MSP_SET_USE_FAN_LEVEL_DYNAMIC_COMP",
            "MSP_SET_USE_FAN_OUTPUT_PID",
            "MSP_SET_MOTOR_VALUE",
            "MSP_SET_BOUNDLESS",
            "MSP_SET_SPRAY_VALUE",
            "MSP_SET_GYRO_THRESHOLD",
        ]
    );
    // Every value is its field's default in the profile.
    for w in &loaded.writes {
        let set = p.command(&w.command).unwrap();
        assert_eq!(w.inputs.len(), set.request.len(), "{}", w.command);
        for f in &set.request {
            assert_eq!(
                raw(&w.inputs, &f.ident),
                f.default,
                "{} {}",
                w.command,
                f.ident
            );
        }
    }
    // The published ones (PROTOCOL_NOTES).
    let all: Vec<(String, Input)> = loaded
        .writes
        .iter()
        .flat_map(|w| w.inputs.clone())
        .collect();
    for (field, want) in [
        ("pwmValue", 85),
        ("pwmvalueMin", 77),
        ("pwmvalueMax", 100),
        ("defaultTarget", 275),
        ("maxTarget", 300),
        ("minTarget", 250),
        ("minPwmValue", 75),
        ("fanThrdAddE", 40),
        ("hangCnt", 3),
        ("waterPumpDuration", 150),
        ("gyroDiffThreshold", 140),
        ("gyroThreshold", 100),
        ("gyroUpDiffThreshold", 100),
        ("gyroUpThreshold", 45),
    ] {
        assert_eq!(raw(&all, field), Some(want), "{field}");
    }
    // And it is what `Preset::defaults` makes of the profile.
    let made = Preset::defaults(&p, "");
    assert_eq!(made.values, loaded.preset.values);
}

/// Raw values to try for an integer field: all of a small range, else its edges and a sample.
fn samples(f: &Field) -> Vec<i64> {
    let (lo, hi) = match f.range.or(f.ty.int_bounds()) {
        Some(r) if f.range.is_some() || f.labels.is_empty() => r,
        _ => return f.labels.iter().map(|l| l.value).collect(),
    };
    if hi - lo <= 70_000 {
        return (lo..=hi).collect();
    }
    let mut rng = fastrand::Rng::with_seed(5);
    let mut v = vec![lo, lo + 1, hi - 1, hi, (lo + hi) / 2, 0.clamp(lo, hi)];
    v.extend((0..2000).map(|_| rng.i64(lo..=hi)));
    v.extend(f.default);
    v
}

fn round_trips(what: &str, f: &Field) -> usize {
    let values: Vec<Value> = match f.ty {
        FieldType::Str(Len::Fixed(n)) => vec![Value::Text("a".repeat(n))],
        FieldType::Str(Len::Rest) => vec![Value::Text("text 1".into()), Value::Text(String::new())],
        FieldType::Bytes(Len::Fixed(n)) => vec![Value::Bytes(vec![0xa5; n])],
        FieldType::Bytes(Len::Rest) => vec![Value::Bytes(vec![1, 2, 0xff])],
        ty if ty.int_bounds().is_some() => samples(f).into_iter().map(Value::Int).collect(),
        _ => return 0,
    };
    for v in &values {
        let text = preset::display_value(f, v);
        if f.bits.is_empty() {
            assert_eq!(
                text,
                f.format(v),
                "{what} {}: stored as Field::format",
                f.ident
            );
        }
        assert_eq!(
            f.parse(&text).as_ref(),
            Ok(v),
            "{what} {}: {v:?} shows as '{text}'",
            f.ident
        );
    }
    values.len()
}

#[test]
fn every_field_of_every_paired_command_round_trips_through_its_display_text() {
    let reg = Registry::builtin().unwrap();
    let mut tried = 0;
    for (p, _) in reg.iter() {
        for cmd in p.commands.iter().filter(|c| c.pair.is_some()) {
            for f in cmd.request.iter().chain(&cmd.reply) {
                let what = format!("{} {}", p.id, cmd.ident);
                match f.ty {
                    // These expand into the profile's parameters.
                    FieldType::ParamValue | FieldType::ParamBlock => {
                        for param in &p.params {
                            tried += round_trips(&what, &param.field);
                        }
                    }
                    _ => tried += round_trips(&what, f),
                }
            }
        }
    }
    assert!(tried > 10_000, "{tried} values tried");
}

#[test]
fn save_change_diff_apply_brings_the_device_back_to_the_preset() {
    let p = profile("window-cleaner");
    let wc = window_cleaner();
    let link = connect(&wc, &p);
    let client = link.client();
    let cancel = Cancel::new();
    let dir = temp_dir();
    let file = dir.path().join("line3.ron");

    // Save what the device holds.
    let mut seen: Vec<Progress> = Vec::new();
    let captured = ops::preset::capture(
        Device::new(&client, &p),
        &mut Run::new(&cancel, |pr| seen.push(pr)),
    )
    .unwrap();
    assert_eq!(captured.device.as_deref(), Some("hw 0x03 fw 1.4.2"));
    assert_eq!(captured.values.len(), preset::preset_commands(&p).len());
    // The tunable commands only: the auto-test result (147/148) is the unit's own.
    assert_eq!(seen.last().map(|s| (s.done, s.total)), Some((8, 8)));
    assert!(
        captured
            .values
            .iter()
            .all(|v| v.command != "MSP_SET_AUTO_TEST_RESULT"),
        "{captured:?}"
    );
    captured.save_annotated(&file, &p).unwrap();
    let leftovers: Vec<_> = std::fs::read_dir(dir.path()).unwrap().flatten().collect();
    assert_eq!(leftovers.len(), 1, "no temporary file is left behind");
    let text = std::fs::read_to_string(&file).unwrap();
    assert!(text.starts_with("// botbench preset"), "{text}");
    assert!(text.contains(r#""defaultTarget": "2.75","#), "{text}");
    let saved = Preset::load(&file, &p).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(saved.preset, captured);
    assert_eq!(saved.writes.len(), 8);

    // Someone changes two values on the device.
    {
        let mut sim = wc.sim();
        sim.set_param("pwmValue", 60).unwrap();
        sim.set_param("defaultTarget", 290).unwrap();
    }
    let device =
        ops::preset::read_device(Device::new(&client, &p), &mut Run::quiet(&cancel)).unwrap();
    let rows = saved.preset.diff(&p, &device);
    assert_eq!(rows.len(), 25);
    let differing: Vec<(&str, &str, &str, Option<&str>)> = rows
        .iter()
        .filter(|r| r.differs)
        .map(|r| {
            (
                r.command.as_str(),
                r.field.as_str(),
                r.preset.as_str(),
                r.device.as_deref(),
            )
        })
        .collect();
    assert_eq!(
        differing,
        [
            ("MSP_SET_PWMVALUE", "pwmValue", "85", Some("60")),
            (
                "MSP_SET_USE_FAN_OUTPUT_PID",
                "defaultTarget",
                "2.75",
                Some("2.90")
            ),
        ]
    );

    // Apply: every field is written and read back.
    let mut steps = Vec::new();
    let mut run = Run::new(&cancel, |pr: Progress| steps.push(pr.done));
    let checks = ops::preset::apply(Device::new(&client, &p), &saved.preset, &mut run).unwrap();
    drop(run);
    assert_eq!(steps, (0..=8).collect::<Vec<u64>>());
    assert_eq!(checks.len(), 25);
    assert!(checks.iter().all(|c| c.ok()), "{checks:?}");
    {
        let sim = wc.sim();
        assert_eq!(sim.param("pwmValue"), Some(85));
        assert_eq!(sim.param("defaultTarget"), Some(275));
    }
    let after =
        ops::preset::read_device(Device::new(&client, &p), &mut Run::quiet(&cancel)).unwrap();
    assert!(saved.preset.diff(&p, &after).iter().all(|r| !r.differs));
}

#[test]
fn the_factory_preset_applies_to_a_tuned_device() {
    let p = profile("window-cleaner");
    let wc = window_cleaner();
    {
        let mut sim = wc.sim();
        sim.set_param("gyroUpThreshold", 60).unwrap();
        sim.set_param("waterPump", 0).unwrap();
        sim.set_param("maxTarget", 320).unwrap();
    }
    let link = connect(&wc, &p);
    let factory = Preset::load(Path::new(FACTORY), &p).unwrap().preset;
    let checks = ops::preset::apply(
        Device::new(&link.client(), &p),
        &factory,
        &mut Run::quiet(&Cancel::new()),
    )
    .unwrap();
    assert_eq!(checks.len(), 22);
    assert!(checks.iter().all(|c| c.ok()), "{checks:?}");
    let sim = wc.sim();
    assert_eq!(sim.param("gyroUpThreshold"), Some(45));
    assert_eq!(sim.param("waterPump"), Some(1));
    assert_eq!(sim.param("maxTarget"), Some(300));
}

#[test]
fn a_cancel_stops_between_commands_and_says_what_was_and_was_not_written() {
    let p = profile("window-cleaner");
    let wc = window_cleaner();
    wc.sim().set_param("gyroThreshold", 99).unwrap();
    let link = connect(&wc, &p);
    let factory = Preset::load(Path::new(FACTORY), &p).unwrap().preset;
    let cancel = Cancel::new();
    let c2 = cancel.clone();
    let mut run = Run::new(&cancel, |pr: Progress| {
        if pr.done == 1 {
            c2.cancel();
        }
    });
    // Issue 25, 4a: a cancelled apply is no success, and says where it stopped.
    let e = ops::preset::apply(Device::new(&link.client(), &p), &factory, &mut run).unwrap_err();
    let botbench::ops::OpError::CancelledAfter {
        done,
        total,
        done_items,
        not_done,
        ..
    } = &e
    else {
        panic!("not a cancel after some: {e:?}");
    };
    // Only MSP_SET_PWMVALUE was written.
    assert_eq!((*done, *total), (1, 7), "{e}");
    assert_eq!(done_items, &["MSP_SET_PWMVALUE"], "{e}");
    assert_eq!(not_done.len(), 6, "{e}");
    assert!(
        e.to_string().starts_with("cancelled after 1 of 7 commands"),
        "{e}"
    );
    assert_eq!(wc.sim().param("gyroThreshold"), Some(99));
}

#[test]
fn a_malformed_preset_is_refused_with_line_and_column() {
    let p = profile("window-cleaner");
    // A missing comma: the error is at the next field's key.
    let text = factory_text().replacen(r#""pwmvalueMax": "100","#, r#""pwmvalueMax": "100""#, 1);
    let line = text
        .lines()
        .position(|l| l.contains(r#""pwmvalueMin""#))
        .unwrap()
        + 1;
    let e = parse_err(&text, &p);
    assert_eq!(e.kind, ErrorKind::Syntax, "{e}");
    assert_eq!(e.problems[0].line, line, "{e}");
    assert!(e.problems[0].col > 1, "{e}");
    assert!(
        e.to_string().starts_with(&format!("test.ron:{line}:")),
        "{e}"
    );

    // Not RON at all.
    let e = parse_err("version: 1\nprofile = window-cleaner", &p);
    assert_eq!(e.kind, ErrorKind::Syntax, "{e}");
    assert!(e.problems[0].line >= 1, "{e}");

    // A field the format does not have.
    let text = factory_text().replacen("    note:", "    nite:", 1);
    let e = parse_err(&text, &p);
    assert_eq!(e.kind, ErrorKind::Syntax, "{e}");
    assert!(e.to_string().contains("nite"), "{e}");

    // A command given twice.
    let text = factory_text().replacen(
        "        // Set fan PWM\n",
        "        \"MSP_SET_PWMVALUE\": { \"pwmValue\": \"10\" },\n",
        1,
    );
    let e = parse_err(&text, &p);
    assert!(e.to_string().contains("given twice"), "{e}");
}

#[test]
fn a_preset_for_another_profile_is_refused_with_the_reason() {
    let p = profile("window-cleaner");
    let text = factory_text().replacen(
        r#"profile: "window-cleaner""#,
        r#"profile: "solar-cleanbot""#,
        1,
    );
    let e = parse_err(&text, &p);
    assert_eq!(e.kind, ErrorKind::Profile);
    assert_eq!(
        e.message(),
        "this preset is for solar-cleanbot; the connected device uses window-cleaner"
    );
    let line = text.lines().position(|l| l.contains("profile:")).unwrap() + 1;
    assert_eq!(e.problems[0].line, line);
}

#[test]
fn a_missing_or_newer_version_is_refused() {
    let p = profile("window-cleaner");
    let e = parse_err(&factory_text().replacen("    version: 1,\n", "", 1), &p);
    assert_eq!(e.kind, ErrorKind::Version, "{e}");
    assert!(e.message().contains("no `version`"), "{e}");

    let e = parse_err(
        &factory_text().replacen("version: 1,", "version: 2,", 1),
        &p,
    );
    assert_eq!(e.kind, ErrorKind::Version, "{e}");
    assert!(e.message().contains("newer"), "{e}");

    // A newer file with fields this version does not know still says "newer".
    let text = factory_text().replacen("version: 1,", "version: 3,\n    checksum: \"x\",", 1);
    let e = parse_err(&text, &p);
    assert_eq!(e.kind, ErrorKind::Version, "{e}");
}

#[test]
fn an_out_of_range_value_is_refused_before_anything_is_written() {
    let p = profile("window-cleaner");
    let wc = window_cleaner();
    {
        let mut sim = wc.sim();
        sim.set_param("pwmValue", 50).unwrap();
        sim.set_param("gyroThreshold", 99).unwrap();
    }
    let text = factory_text().replacen(r#""pwmValue": "85""#, r#""pwmValue": "101""#, 1);
    let e = parse_err(&text, &p);
    assert_eq!(e.kind, ErrorKind::Value);
    let line = text.lines().position(|l| l.contains(r#""101""#)).unwrap() + 1;
    assert_eq!(e.problems.len(), 1, "{e}");
    assert_eq!(e.problems[0].line, line, "{e}");
    let m = e.message();
    for part in ["MSP_SET_PWMVALUE", "pwmValue", "101", "0 to 100"] {
        assert!(m.contains(part), "'{part}' in {m}");
    }

    // Applying it anyway (unchecked) writes nothing, not even the valid commands.
    let unchecked = Preset::parse_unchecked("test.ron", &text).unwrap();
    let link = connect(&wc, &p);
    let err = ops::preset::apply(
        Device::new(&link.client(), &p),
        &unchecked,
        &mut Run::quiet(&Cancel::new()),
    )
    .unwrap_err();
    assert!(
        matches!(err, OpError::Document(ref e) if e.to_string().contains("out of range")),
        "{err}"
    );
    let sim = wc.sim();
    assert_eq!(sim.param("pwmValue"), Some(50));
    assert_eq!(sim.param("gyroThreshold"), Some(99));
}

#[test]
fn a_value_between_steps_is_refused() {
    let p = profile("window-cleaner");
    let text = factory_text().replacen(
        r#""defaultTarget": "2.75""#,
        r#""defaultTarget": "2.755""#,
        1,
    );
    let e = parse_err(&text, &p);
    assert_eq!(e.kind, ErrorKind::Value);
    let m = e.message();
    for part in [
        "MSP_SET_USE_FAN_OUTPUT_PID",
        "defaultTarget",
        "2.755",
        "0.01",
    ] {
        assert!(m.contains(part), "'{part}' in {m}");
    }
    // "2.80" and "2.8" are the same value; an unquoted number is read as its text.
    let text = factory_text().replacen(r#""defaultTarget": "2.75""#, r#""defaultTarget": 2.8"#, 1);
    let loaded = Preset::parse("t.ron", &text, &p).unwrap_or_else(|e| panic!("{e}"));
    let pid = &loaded.writes[2];
    assert_eq!(raw(&pid.inputs, "defaultTarget"), Some(280));
}

#[test]
fn unknown_commands_and_fields_and_missing_fields_are_each_reported() {
    let p = profile("window-cleaner");
    let text = factory_text()
        .replacen(r#""MSP_SET_PWMVALUE""#, r#""MSP_SET_PWMVALUES""#, 1)
        .replacen(r#""hangCnt""#, r#""hangCount""#, 1)
        .replacen("            \"gyroThreshold\": \"100\",", "", 1)
        .replacen(r#""MSP_SET_MOTOR_VALUE""#, r#""MSP_GET_MOTOR_VALUE""#, 1);
    let e = parse_err(&text, &p);
    assert_eq!(e.kind, ErrorKind::Value);
    let all = e.to_string();
    assert_eq!(e.problems.len(), 5, "{all}");
    assert!(
        all.contains("window-cleaner has no command 'MSP_SET_PWMVALUES'"),
        "{all}"
    );
    assert!(
        all.contains("MSP_GET_MOTOR_VALUE is not a Set command"),
        "{all}"
    );
    assert!(all.contains("name its Set, MSP_SET_MOTOR_VALUE"), "{all}");
    assert!(
        all.contains("MSP_SET_BOUNDLESS has no field 'hangCount'"),
        "{all}"
    );
    // Renaming hangCnt also leaves it missing.
    assert!(all.contains("MSP_SET_BOUNDLESS: missing hangCnt"), "{all}");
    assert!(
        all.contains("MSP_SET_GYRO_THRESHOLD: missing gyroThreshold"),
        "{all}"
    );
    assert!(e.problems.iter().all(|pr| pr.line > 0), "{all}");
}

#[test]
fn to_ron_reads_back_as_the_same_preset() {
    let p = profile("window-cleaner");
    let mut pr = Preset::defaults(&p, "quote \" and\nnewline");
    pr.device = Some("hw 0x03 fw 1.4.2".into());
    for text in [pr.to_ron(None), pr.to_ron(Some(&p))] {
        let back = Preset::parse("t.ron", &text, &p).unwrap_or_else(|e| panic!("{e}\n{text}"));
        assert_eq!(back.preset, pr);
    }
    let dir = temp_dir();
    let file = dir.path().join("plain.ron");
    pr.save(&file).unwrap();
    pr.save(&file).unwrap(); // replaces
    assert_eq!(Preset::load(&file, &p).unwrap().preset, pr);
    let e = pr.save(&dir.path().join("no/such/dir/x.ron")).unwrap_err();
    assert_eq!(e.kind, ErrorKind::Io);
}
