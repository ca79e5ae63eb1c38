//! Loading profiles: malformed and inconsistent files fail with file, line, column and reason;
//! a user's file overrides the built-in of the same name.

use botbench::profile::registry::parse;
use botbench::profile::{Registry, Source};

use crate::support::{builtin_src as builtin, line_col_of};

/// The built-in window-cleaner profile with `from` replaced by `to` (once, checked).
fn edited(from: &str, to: &str) -> String {
    let src = builtin("window-cleaner");
    assert!(
        src.contains(from),
        "test setup: '{from}' not in the profile"
    );
    src.replacen(from, to, 1)
}

#[test]
fn every_builtin_profile_loads() {
    let reg = Registry::builtin().expect("built-ins are consistent");
    assert_eq!(
        reg.names(),
        [
            "window-cleaner",
            "window-cleaner-configurator",
            "solar-cleanbot",
            "servo",
            "tuya-vacuum"
        ]
    );
}

#[test]
fn a_syntax_error_names_file_line_and_column() {
    let src = edited("commands: [", "commands: [ oops");
    let err = parse("wc.ron", &src, None).unwrap_err();
    assert_eq!(err.file, "wc.ron");
    let (line, _) = line_col_of(&src, "oops", 0);
    assert_eq!(err.line, line, "{err}");
    assert!(
        err.to_string().starts_with(&format!("wc.ron:{line}:")),
        "{err}"
    );
}

#[test]
fn an_unknown_key_is_refused_with_its_position() {
    let src = edited("kind: Get,", "kind: Get, colour: 3,");
    let err = parse("wc.ron", &src, None).unwrap_err();
    let (line, _) = line_col_of(&src, "colour", 0);
    assert_eq!(err.line, line, "{err}");
    assert!(err.message.contains("colour"), "{err}");
}

#[test]
fn a_duplicate_command_id_points_at_the_second_one() {
    // Give MSP_GET_USE_FAN_LEVEL_DYNAMIC_COMP (131) the id 130.
    let src = edited("id: 131,", "id: 130,");
    let err = parse("wc.ron", &src, None).unwrap_err();
    assert!(err.message.contains("duplicate command id 130"), "{err}");
    let (line, col) = line_col_of(&src, "130,", 1);
    assert_eq!((err.line, err.col), (line, col), "{err}");
}

#[test]
fn a_set_without_its_get_is_refused() {
    // A Set whose Get is gone: neither names the other any more.
    let src = edited("pair: Some(220)", "pair: None").replacen("pair: Some(130)", "pair: None", 1);
    let err = parse("wc.ron", &src, None).unwrap_err();
    assert!(err.message.contains("Set without its Get"), "{err}");
    let (line, _) = line_col_of(&src, "pair: None", 1);
    assert_eq!(err.line, line, "{err}");
}

#[test]
fn a_range_wider_than_the_type_is_refused() {
    let src = edited("range: Some((0, 100))", "range: Some((0, 300))");
    let err = parse("wc.ron", &src, None).unwrap_err();
    assert!(err.message.contains("wider than its type"), "{err}");
    let (line, _) = line_col_of(&src, "Some((0, 300))", 0);
    assert_eq!(err.line, line, "{err}");
}

#[test]
fn a_default_outside_the_range_is_refused() {
    let src = edited("default: Some(85)", "default: Some(185)");
    let err = parse("wc.ron", &src, None).unwrap_err();
    assert!(err.message.contains("default"), "{err}");
    assert!(err.message.contains("185"), "{err}");
}

#[test]
fn a_file_whose_id_differs_from_its_name_is_refused() {
    let err = parse("x.ron", builtin("servo"), Some("servo-v2")).unwrap_err();
    assert!(err.message.contains("must match its file name"), "{err}");
}

#[test]
fn a_users_file_overrides_the_builtin_and_a_broken_one_is_an_error() {
    let tmp = crate::support::temp_dir();
    let dir = tmp.path().to_path_buf();
    let mut reg = Registry::builtin().unwrap();
    // A firmware variant: the fan PWM limited to 90 %.
    let variant = edited("range: Some((0, 100))", "range: Some((0, 90))");
    std::fs::write(dir.join("window-cleaner.ron"), &variant).unwrap();
    reg.add_dir(&dir).unwrap();
    let wc = reg.get("window-cleaner").unwrap();
    let set = wc.command("MSP_SET_PWMVALUE").unwrap();
    assert!(set.request[0].parse("95").is_err());
    assert!(set.request[0].parse("90").is_ok());
    let (_, source) = reg.iter().find(|(p, _)| p.id == "window-cleaner").unwrap();
    assert_eq!(source, &Source::File(dir.join("window-cleaner.ron")));

    std::fs::write(dir.join("servo.ron"), "Profile(id: \"servo\",").unwrap();
    let err = reg.add_dir(&dir).unwrap_err();
    assert!(err.file.ends_with("servo.ron"), "{err}");
}

#[test]
fn a_panel_rule_with_a_bad_flag_or_an_unknown_panel_is_refused_with_its_line() {
    let src = edited(
        "(panel: Tuning, flag: Some(0))",
        "(panel: Tuning, flag: Some(8))",
    );
    let err = parse("wc.ron", &src, None).unwrap_err();
    let (line, _) = line_col_of(&src, "flag: Some(8)", 0);
    assert_eq!(err.line, line, "{err}");
    assert!(err.message.contains("bits 0 to 7"), "{err}");

    let src = edited("(panel: SelfTest)", "(panel: Dashboard)");
    let err = parse("wc.ron", &src, None).unwrap_err();
    let (line, _) = line_col_of(&src, "Dashboard", 0);
    assert_eq!(err.line, line, "{err}");

    let src = edited("(panel: SelfTest)", "(panel: Tuning)");
    let err = parse("wc.ron", &src, None).unwrap_err();
    assert!(err.message.contains("listed twice"), "{err}");
}

#[test]
fn a_plot_line_is_a_measurement_and_an_enum_is_shown_by_its_names() {
    // Every plot of every built-in profile: lines are measurements, states are not.
    let reg = Registry::builtin().expect("built-ins are consistent");
    for name in reg.names() {
        let p = reg.get(&name).unwrap();
        for plot in &p.plots {
            let cmd = p.command(&plot.command).expect("the plot's command");
            let field = |ident: &String| cmd.reply.iter().find(|f| &f.ident == ident).unwrap();
            for ident in &plot.fields {
                assert!(
                    field(ident).is_measurement(),
                    "{name}: plot {} draws {ident} as a line",
                    plot.id
                );
            }
            for ident in &plot.states {
                assert!(field(ident).is_state(), "{name}: {}: {ident}", plot.id);
            }
        }
    }
    // The solar cleanbot's battery state goes beside its voltage.
    let solar = reg.get("solar-cleanbot").unwrap();
    let battery = solar.plots.iter().find(|p| p.id == "battery").unwrap();
    assert_eq!(
        (battery.fields.as_slice(), battery.states.as_slice()),
        (&["voltage".to_string()][..], &["state".to_string()][..])
    );

    // An enum drawn as a line is refused where it is named, saying where it goes instead.
    let src = builtin("solar-cleanbot");
    let line = r#"fields: ["voltage"], states: ["state"]"#;
    assert!(src.contains(line), "test setup");
    let bad = src.replacen(line, r#"fields: ["voltage", "state"]"#, 1);
    let err = parse("solar-cleanbot.ron", &bad, None).unwrap_err();
    assert!(err.message.contains("'state' is an enum"), "{err}");
    assert!(err.message.contains("states"), "{err}");
    assert_eq!(err.line, line_col_of(&bad, r#""state"]"#, 0).0, "{err}");
    // …and so is a measurement listed as a state.
    let bad = src.replacen(line, r#"fields: ["voltage"], states: ["voltage"]"#, 1);
    let err = parse("solar-cleanbot.ron", &bad, None).unwrap_err();
    assert!(
        err.message.contains("a measurement goes under fields"),
        "{err}"
    );
}
