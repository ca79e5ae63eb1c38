//! Every command of every built-in profile: random in-range values round-trip through the field
//! codec, and out-of-range values are refused with the field, the value and the range named.

use botbench::profile::model::{Access, Field, FieldType, Len};
use botbench::profile::{FieldError, Input, Profile, Registry, Value};
use botbench::protocol::Direction;
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};

fn registry() -> Registry {
    Registry::builtin().expect("built-in profiles load")
}

/// A strategy for a value the field accepts.
fn valid_value(f: &Field) -> BoxedStrategy<Value> {
    match f.ty {
        FieldType::Str(len) => {
            let n = match len {
                Len::Fixed(n) => n..=n,
                Len::Rest => 0..=20,
            };
            proptest::collection::vec(proptest::char::range('0', 'z'), n)
                .prop_map(|c| Value::Text(c.into_iter().collect()))
                .boxed()
        }
        FieldType::Bytes(len) => {
            let n = match len {
                Len::Fixed(n) => n..=n,
                Len::Rest => 0..=20,
            };
            proptest::collection::vec(any::<u8>(), n)
                .prop_map(Value::Bytes)
                .boxed()
        }
        // A bitmap: only the bits the field defines (others are a misfit a report is flagged for).
        _ if !f.bits.is_empty() => {
            let mask: i64 = f.bits.iter().map(|b| 1i64 << b.bit).sum();
            (0..=mask).prop_map(move |v| Value::Int(v & mask)).boxed()
        }
        _ => match f.allowed() {
            botbench::profile::value::Allowed::Range(lo, hi) => {
                (lo..=hi).prop_map(Value::Int).boxed()
            }
            botbench::profile::value::Allowed::Labels(_) => {
                let values: Vec<i64> = f.labels.iter().map(|l| l.value).collect();
                proptest::sample::select(values)
                    .prop_map(Value::Int)
                    .boxed()
            }
        },
    }
}

/// A parameter id (field `i` of `fields`) and, when `has_value`, its value: any parameter the
/// frame may name (only writable ones sent to the device, unless it is the frame's last field).
fn param_inputs(
    p: &Profile,
    fields: &[Field],
    i: usize,
    to_device: bool,
    has_value: bool,
) -> BoxedStrategy<Vec<(String, Value)>> {
    let params: Vec<_> = p
        .params
        .iter()
        .filter(|x| !to_device || x.access == Access::ReadWrite || fields.len() == i + 1)
        .cloned()
        .collect();
    let id_ident = fields[i].ident.clone();
    proptest::sample::select(params)
        .prop_flat_map(move |prm| {
            let id = (id_ident.clone(), Value::Int(prm.id as i64));
            let ident = prm.field.ident.clone();
            valid_value(&prm.field).prop_map(move |v| {
                let mut out = vec![id.clone()];
                if has_value {
                    out.push((ident.clone(), v));
                }
                out
            })
        })
        .boxed()
}

/// A synchronous command (its sub-command field `f`): a sub-command and 0-3 records of its
/// request, each value named `ident[i]`; the record length and count follow from them.
fn sync_inputs(p: &Profile, f: &Field) -> BoxedStrategy<Vec<(String, Value)>> {
    let ident = f.ident.clone();
    let subs: Vec<BoxedStrategy<Vec<(String, Value)>>> = f
        .labels
        .iter()
        .filter_map(|l| p.command_by_id(l.value as u8))
        .map(|sub| {
            let width: usize = sub.request.iter().filter_map(|x| x.ty.width()).sum();
            let (id, ident) = (sub.id, ident.clone());
            proptest::collection::vec(frame_inputs(p, &sub.request, true), 0..=3)
                .prop_map(move |records| {
                    let mut out = vec![
                        (ident.clone(), Value::Int(id.into())),
                        ("record_len".to_string(), Value::Int(width as i64)),
                        ("count".to_string(), Value::Int(records.len() as i64)),
                    ];
                    for (i, r) in records.into_iter().enumerate() {
                        out.extend(r.into_iter().map(|(k, v)| (format!("{k}[{i}]"), v)));
                    }
                    out
                })
                .boxed()
        })
        .collect();
    proptest::strategy::Union::new(subs).boxed()
}

/// Some of the profile's data points (only writable ones sent to the device), each a value.
fn data_point_inputs(p: &Profile, to_device: bool) -> BoxedStrategy<Vec<(String, Value)>> {
    let dps: Vec<_> = p
        .data_points
        .iter()
        .filter(|d| !to_device || d.access == Access::ReadWrite)
        .cloned()
        .collect();
    let n = dps.len();
    proptest::sample::subsequence(dps, 1..=n)
        .prop_flat_map(|chosen| {
            chosen
                .into_iter()
                .map(|d| {
                    let ident = d.field.ident.clone();
                    valid_value(&d.field).prop_map(move |v| (ident.clone(), v))
                })
                .collect::<Vec<_>>()
        })
        .boxed()
}

/// Named inputs for every field of a frame, chosen at random, and the values expected back.
fn frame_inputs(
    p: &Profile,
    fields: &[Field],
    to_device: bool,
) -> BoxedStrategy<Vec<(String, Value)>> {
    let mut parts: Vec<BoxedStrategy<Vec<(String, Value)>>> = Vec::new();
    let mut i = 0;
    while i < fields.len() {
        let f = &fields[i];
        match f.ty {
            FieldType::ParamId => {
                let has_value = fields
                    .get(i + 1)
                    .is_some_and(|n| n.ty == FieldType::ParamValue);
                parts.push(param_inputs(p, fields, i, to_device, has_value));
                if has_value {
                    i += 1;
                }
            }
            FieldType::CommandId => {
                parts.push(sync_inputs(p, f));
                // The record length, count and records are made there.
                i += 3;
            }
            FieldType::ParamBlock => {
                for prm in p.block_params() {
                    let ident = prm.field.ident.clone();
                    parts.push(
                        valid_value(&prm.field)
                            .prop_map(move |v| vec![(ident.clone(), v)])
                            .boxed(),
                    );
                }
            }
            FieldType::DataPoints => parts.push(data_point_inputs(p, to_device)),
            _ => {
                let ident = f.ident.clone();
                parts.push(
                    valid_value(f)
                        .prop_map(move |v| vec![(ident.clone(), v)])
                        .boxed(),
                );
            }
        }
        i += 1;
    }
    parts
        .prop_map(|v| v.into_iter().flatten().collect::<Vec<_>>())
        .boxed()
}

#[test]
fn every_command_round_trips_random_in_range_values() {
    let reg = registry();
    let mut frames = 0;
    for (p, _) in reg.iter() {
        for cmd in &p.commands {
            for dir in [Direction::HostToDevice, Direction::DeviceToHost] {
                let fields = p.fields(cmd, dir);
                if fields.is_empty() {
                    continue;
                }
                frames += 1;
                let to_device = dir == Direction::HostToDevice;
                let strategy = frame_inputs(p, fields, to_device);
                let mut runner = TestRunner::new(Config {
                    cases: 24,
                    failure_persistence: None,
                    ..Config::default()
                });
                runner
                    .run(&strategy, |inputs| {
                        let named: Vec<(String, Input)> = inputs
                            .iter()
                            .map(|(k, v)| (k.clone(), Input::Raw(v.clone())))
                            .collect();
                        let bytes = match p.encode(cmd, dir, &named) {
                            Ok(b) => b,
                            // Values drawn one by one can break a relation (a minimum above its
                            // maximum): such a write is refused, as it must be.
                            Err(FieldError::Relation(_)) => {
                                return Err(TestCaseError::reject("breaks a relation"));
                            }
                            Err(e) => {
                                return Err(TestCaseError::fail(format!(
                                    "{}/{}: {e}",
                                    p.id, cmd.ident
                                )));
                            }
                        };
                        let decoded = p.decode(cmd, dir, &bytes).map_err(|e| {
                            TestCaseError::fail(format!("{}/{}: {e}", p.id, cmd.ident))
                        })?;
                        let got: Vec<(String, Value)> = decoded
                            .values
                            .iter()
                            .map(|v| (v.ident.to_ascii_lowercase(), v.value.clone()))
                            .collect();
                        let want: Vec<(String, Value)> = inputs
                            .iter()
                            .map(|(k, v)| (k.to_ascii_lowercase(), v.clone()))
                            .collect();
                        prop_assert_eq!(got, want, "{} {}", p.id, cmd.ident);
                        prop_assert!(decoded.trailing.is_empty());
                        Ok(())
                    })
                    .unwrap_or_else(|e| panic!("{} {} {dir:?}: {e}", p.id, cmd.ident));
            }
        }
    }
    assert!(frames > 60, "only {frames} frame layouts were exercised");
}

/// Integer fields of every command, parameter and data point.
fn all_int_fields(p: &Profile) -> Vec<&Field> {
    let mut out: Vec<&Field> = p
        .commands
        .iter()
        .flat_map(|c| c.request.iter().chain(&c.reply))
        .collect();
    out.extend(p.params.iter().map(|x| &x.field));
    out.extend(p.data_points.iter().map(|d| &d.field));
    out.retain(|f| f.ty.int_bounds().is_some());
    out
}

#[test]
fn every_field_refuses_values_outside_its_range() {
    let reg = registry();
    let mut checked = 0;
    for (p, _) in reg.iter() {
        for f in all_int_fields(p) {
            let (tlo, thi) = f.ty.int_bounds().unwrap();
            let (lo, hi) = match f.allowed() {
                botbench::profile::value::Allowed::Range(lo, hi) => (lo, hi),
                botbench::profile::value::Allowed::Labels(_) => {
                    let vals: Vec<i64> = f.labels.iter().map(|l| l.value).collect();
                    (*vals.iter().min().unwrap(), *vals.iter().max().unwrap())
                }
            };
            for bad in [lo - 1, hi + 1, tlo - 1, thi + 1] {
                if (lo..=hi).contains(&bad) {
                    continue;
                }
                let err = f
                    .check(&Value::Int(bad))
                    .expect_err("out of range is refused");
                match &err {
                    FieldError::OutOfRange {
                        field, min, max, ..
                    } => {
                        assert_eq!(field, &f.ident);
                        assert_eq!(min, &f.format_number(lo));
                        assert_eq!(max, &f.format_number(hi));
                    }
                    FieldError::NotALabel { field, .. } => assert_eq!(field, &f.ident),
                    other => panic!("{}: unexpected {other}", f.ident),
                }
                // The same refusal for what a person types (a converted field takes `raw N`).
                let typed = if f.convert.is_some() {
                    format!("raw {bad}")
                } else {
                    f.format_number(bad)
                };
                assert!(f.parse(&typed).is_err(), "{}: '{typed}' accepted", f.ident);
                checked += 1;
            }
        }
    }
    assert!(
        checked > 200,
        "only {checked} out-of-range values were tried"
    );
}

#[test]
fn typed_values_use_display_units_labels_and_bits() {
    let reg = registry();
    let wc = reg.get("window-cleaner").unwrap();
    let pid = wc.command("MSP_SET_USE_FAN_OUTPUT_PID").unwrap();
    let target = pid
        .request
        .iter()
        .find(|f| f.ident == "defaultTarget")
        .unwrap();
    assert_eq!(target.parse("2.75").unwrap(), Value::Int(275));
    assert!(matches!(
        target.parse("2.755"),
        Err(FieldError::NotOnStep { .. })
    ));
    assert!(matches!(
        target.parse("two"),
        Err(FieldError::NotANumber { .. })
    ));
    assert_eq!(target.format(&Value::Int(275)), "2.75");

    let tuya = reg.get("tuya-vacuum").unwrap();
    let mode = &tuya.find_data_point("mode").unwrap().field;
    assert_eq!(mode.parse("SMART").unwrap(), Value::Int(2));
    assert!(matches!(
        mode.parse("fly"),
        Err(FieldError::NotALabel { .. })
    ));
    let fault = &tuya.find_data_point("fault").unwrap().field;
    assert_eq!(
        fault.parse("edge_sweep_fault|collision_fault").unwrap(),
        Value::Int(0b100_0001)
    );
    let power = &tuya.find_data_point("power").unwrap().field;
    assert_eq!(power.parse("on").unwrap(), Value::Int(1));
}

#[test]
fn writing_read_only_parameters_and_report_only_data_points_is_refused() {
    let reg = registry();
    let servo = reg.get("servo").unwrap();
    let write = servo.command("WRITE_DATA").unwrap();
    let inputs = vec![
        ("servo_id".to_string(), Input::from("1")),
        ("data_id".to_string(), Input::from("voltage")),
        ("data".to_string(), Input::from("5000")),
    ];
    let err = servo
        .encode(write, Direction::HostToDevice, &inputs)
        .unwrap_err();
    assert!(matches!(err, FieldError::ReadOnly { .. }), "{err}");

    let tuya = reg.get("tuya-vacuum").unwrap();
    let dp_cmd = tuya.command("6").unwrap();
    let err = tuya
        .encode(
            dp_cmd,
            Direction::HostToDevice,
            &[("battery".into(), Input::from("50"))],
        )
        .unwrap_err();
    assert!(matches!(err, FieldError::ReadOnly { .. }), "{err}");
    let err = tuya
        .encode(
            dp_cmd,
            Direction::HostToDevice,
            &[("nonsense".into(), Input::from("1"))],
        )
        .unwrap_err();
    assert!(matches!(err, FieldError::UnknownDataPoint { .. }), "{err}");
}

#[test]
fn commands_are_found_by_canonical_name_in_any_case_and_by_number() {
    let reg = registry();
    let wc = reg.get("window-cleaner").unwrap();
    let by_name = wc.command("msp_get_pwmvalue").unwrap();
    assert_eq!(by_name.id, 130);
    assert_eq!(wc.command("130").unwrap().ident, by_name.ident);
    assert_eq!(wc.command("0x82").unwrap().ident, by_name.ident);
    assert!(wc.command("MSP_NOPE").is_none());
    // 130 means something else on the solar cleanbot: commands belong to a profile.
    let solar = reg.get("solar-cleanbot").unwrap();
    assert_ne!(solar.command("130").unwrap().ident, by_name.ident);
}

#[test]
fn a_set_sends_the_layout_of_its_get() {
    let reg = registry();
    let wc = reg.get("window-cleaner").unwrap();
    for get in 130..=136u8 {
        let g = wc.command_by_id(get).unwrap();
        let s = wc.command_by_id(get + 90).unwrap();
        assert_eq!(g.pair, Some(s.id));
        let a: Vec<_> = g.reply.iter().map(|f| (&f.ident, f.ty)).collect();
        let b: Vec<_> = s.request.iter().map(|f| (&f.ident, f.ty)).collect();
        assert_eq!(a, b, "{} / {}", g.ident, s.ident);
        assert!(!a.is_empty());
    }
}

/// Each refusal names the real problem and what is allowed (issue 17, item 7).
#[test]
fn a_refused_value_is_told_what_is_wrong_and_what_is_allowed() {
    let reg = registry();
    let wc = reg.get("window-cleaner").unwrap();
    let set = wc.command("MSP_SET_PWMVALUE").unwrap();
    let encode = |inputs: &[(&str, &str)]| {
        let inputs = crate::support::inputs(inputs);
        wc.encode(set, Direction::HostToDevice, &inputs)
            .unwrap_err()
            .to_string()
    };
    // Given twice: not "has no field 'pwmValue'; its fields: pwmValue".
    let e = encode(&[("pwmValue", "70"), ("pwmValue", "80")]);
    assert!(e.contains("'pwmValue' is given twice"), "{e}");
    // Beyond any integer: the field's range (0 to 100 %), not the type's (0 to 255).
    for huge in ["99999999999999999999999", "1e400", "-1e400"] {
        let e = encode(&[("pwmValue", huge)]);
        assert!(e.contains("allowed 0 to 100 %"), "{huge}: {e}");
    }
    let e = encode(&[("pwmValue", "")]);
    assert!(e.contains("no value given; allowed 0 to 100 %"), "{e}");
    let e = encode(&[("pwmValue", "lots")]);
    assert!(
        e.contains("'lots' is not a number; allowed 0 to 100 %"),
        "{e}"
    );
    // A command that takes no fields says so, rather than "its fields:" and nothing.
    let get = wc.command("MSP_GET_PWMVALUE").unwrap();
    let e = wc
        .encode(
            get,
            Direction::HostToDevice,
            &[("pwmValue".into(), Input::from("1"))],
        )
        .unwrap_err()
        .to_string();
    assert!(e.ends_with("it takes no fields"), "{e}");
    // A bool is not a number.
    let tuya = reg.get("tuya-vacuum").unwrap();
    let dp = tuya.command("6").unwrap();
    let dps = |inputs: &[(&str, &str)]| {
        let inputs = crate::support::inputs(inputs);
        tuya.encode(dp, Direction::HostToDevice, &inputs)
    };
    let e = dps(&[("power", "maybe")]).unwrap_err().to_string();
    assert!(!e.contains("not a number"), "{e}");
    assert!(e.contains("'maybe'") && e.contains("on, off"), "{e}");
    // One data point by name and by number is given twice.
    let e = dps(&[("power", "on"), ("1", "off")])
        .unwrap_err()
        .to_string();
    assert!(e.contains("'power' is given twice"), "{e}");
    assert!(dps(&[("power", "on")]).is_ok());
    // A long input is quoted to a line at most.
    let long = "9".repeat(100_000);
    let e = encode(&[("pwmValue", &long)]);
    assert!(e.len() < 200, "{} bytes", e.len());
}
