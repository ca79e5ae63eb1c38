//! `botbench profile import tuya SCHEMA.json` (issue 26, item 7): the platform's data-point
//! schema becomes a checked profile; a malformed or contradictory schema is refused with the
//! path of the problem; the difference from a profile of the same name is shown; the vacuum's
//! own profile, exported as a schema, imports back to an equivalent profile.

use botbench::profile::Registry;
use botbench::profile::tuya_schema::{self, summary};

use crate::support::cli::{botbench, output};
use crate::support::temp_dir;

/// The field notes' example schema (§8), DP 101 included.
const NOTES_SCHEMA: &str = r#"[
  {"id": 1,  "code": "power",        "name": "Power",          "mode": "rw", "type": "obj",
   "property": {"type": "bool"}},
  {"id": 3,  "code": "mode",         "name": "Work mode",      "mode": "rw", "type": "obj",
   "property": {"type": "enum", "range": ["standby","random","smart","wall_follow","mop","spiral",
                "left_spiral","right_spiral","right_bow","left_bow","partial_bow","chargego"]}},
  {"id": 6,  "code": "battery",      "name": "Battery",        "mode": "ro", "type": "obj",
   "property": {"type": "value", "min": 0, "max": 100, "step": 1, "scale": 0, "unit": "%"}},
  {"id": 15, "code": "clean_record", "name": "Clean record",   "mode": "ro", "type": "obj",
   "property": {"type": "string", "maxlen": 255}},
  {"id": 16, "code": "clean_area",   "name": "Cleaned area",   "mode": "ro", "type": "obj",
   "property": {"type": "value", "min": 0, "max": 9999, "step": 1, "scale": 1, "unit": "m²"}},
  {"id": 18, "code": "fault",        "name": "Fault",          "mode": "ro", "type": "obj", "scope": "fault",
   "property": {"type": "bitmap", "maxlen": 7, "label": ["edge_sweep_fault","middle_sweep_fault",
                "left_wheel_fault","right_wheel_fault","garbage_box_fault","land_check_fault","collision_fault"]}},
  {"id": 19, "code": "map_config",   "name": "Map parameters", "mode": "ro", "type": "raw",
   "property": {"type": "raw", "maxlen": 128}},
  {"id": 101,"code": "beep_once",    "name": "Beep once",      "mode": "wr", "type": "obj",
   "property": {"type": "bool"}}
]"#;

#[test]
fn the_vacuum_profile_exported_as_a_schema_imports_back_equivalent() {
    let reg = Registry::builtin().unwrap();
    let vacuum = reg.get("tuya-vacuum").unwrap();
    let schema = tuya_schema::schema_of(&vacuum).to_string();
    let back = tuya_schema::import(&schema, "tuya-vacuum", &vacuum).expect("imports");
    assert_eq!(back.data_points.len(), 19);
    for (a, b) in vacuum.data_points.iter().zip(&back.data_points) {
        // Ids, access, wire type, code, range, scale, unit, step, labels, bits, maxima.
        assert_eq!(summary(a), summary(b));
        assert_eq!(a.field.name.en, b.field.name.en, "dp {}", a.id);
    }
    assert!(tuya_schema::diff(&vacuum, &back).is_empty());
    // The commands of the base protocol are the vacuum's.
    assert_eq!(back.commands.len(), vacuum.commands.len());
}

#[test]
fn profile_import_writes_a_checked_profile_and_shows_the_difference() {
    let dir = temp_dir();
    let schema = dir.path().join("rh-vacuum.json");
    std::fs::write(&schema, NOTES_SCHEMA).unwrap();
    let profiles = dir.path().join("profiles");
    let import = |args: &[&str]| {
        let mut all = vec!["profile", "import", "tuya", schema.to_str().unwrap()];
        all.extend_from_slice(args);
        output(botbench(&all).env("BOTBENCH_PROFILE_DIR", &profiles))
    };
    let o = import(&[]);
    assert_eq!(o.code, 0, "{}", o.text());
    assert!(
        o.out.contains("rh-vacuum: a new profile, 8 data point(s)"),
        "{}",
        o.text()
    );
    let written = profiles.join("rh-vacuum.ron");
    let p = botbench::profile::registry::load_file(&written).expect("a profile that loads");
    let area = p.data_points.iter().find(|d| d.id == 16).unwrap();
    assert_eq!(summary(area), "16 clean_area ro value 0 to 9999 ×0.1 m²");
    let beep = p.data_points.iter().find(|d| d.id == 101).unwrap();
    assert_eq!(beep.access, botbench::profile::Access::WriteOnly);
    // Listed as a user's profile, usable by name.
    let listed = output(botbench(["profiles"]).env("BOTBENCH_PROFILE_DIR", &profiles));
    assert!(listed.out.contains("rh-vacuum"), "{}", listed.text());
    // The same name imported as the vacuum: the difference from the built-in one is shown.
    let o = import(&["--name", "tuya-vacuum", "--json"]);
    assert_eq!(o.code, 0, "{}", o.text());
    let doc = &o.json_docs()[0];
    let diff: Vec<&str> = doc["diff"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l.as_str().unwrap())
        .collect();
    assert!(diff.contains(&"+ 101 beep_once wr bool"), "{diff:?}");
    assert!(
        diff.iter().any(|l| l.starts_with("- 2 clean_switch")),
        "{diff:?}"
    );
    // A changed schema over an existing file: the difference, and no overwrite without --replace.
    std::fs::write(
        &schema,
        NOTES_SCHEMA.replace("\"max\": 100", "\"max\": 120"),
    )
    .unwrap();
    let o = import(&[]);
    assert_eq!(o.code, 2, "{}", o.text());
    assert!(
        o.out
            .contains("~ 6 battery ro value 0 to 100 % → 6 battery ro value 0 to 120 %"),
        "{}",
        o.text()
    );
    assert!(o.err.contains("--replace"), "{}", o.text());
    assert_eq!(import(&["--replace"]).code, 0);
}

#[test]
fn a_malformed_or_contradictory_schema_is_refused_with_where() {
    let dir = temp_dir();
    let schema = dir.path().join("bad.json");
    let bad = NOTES_SCHEMA.replace("\"min\": 0, \"max\": 9999", "\"min\": 10, \"max\": 5");
    std::fs::write(&schema, bad).unwrap();
    let o = output(
        botbench(["profile", "import", "tuya", schema.to_str().unwrap()])
            .env("BOTBENCH_PROFILE_DIR", dir.path().join("profiles")),
    );
    assert_eq!(o.code, 2, "{}", o.text());
    assert!(
        o.err.contains("[4].property.max: max 5 is below min 10"),
        "{}",
        o.text()
    );
    assert!(!dir.path().join("profiles").exists(), "nothing written");
}
