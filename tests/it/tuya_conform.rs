//! `botbench tuya conform` (issue 26, item 8): the simulated MCU, which follows the SDK,
//! conforms; each of its field misbehaviours (items 1-6) fails the check that matches it, with
//! the bytes that show it; the run is recorded through the records layer.

use botbench::link::LinkOptions;
use botbench::ops::tuya::Expect;
use botbench::ops::tuya::conform::{self, Conformance, Grade};
use botbench::ops::{Device, Run};
use botbench::protocol::tuya::dp::DpValue;
use botbench::sim::tuya_mcu::{OtaFault, RawValue, TuyaConfig, TuyaMcu, parse_misreport};
use std::collections::BTreeMap;
use std::time::Duration;

use crate::support::cli::{Sim, run};
use crate::support::{open_link, profile, serve};

const BAUD: u32 = 115_200;

/// A 4 KiB image naming version 1.2.3.
fn image() -> Vec<u8> {
    let mut image = vec![0xA5u8; 4096];
    image[64..70].copy_from_slice(b"1.2.3\0");
    image
}

/// Grades a simulated MCU configured with `cfg`, in this process (no module session: the
/// checks drive it), with the update when `ota`.
fn grade(cfg: TuyaConfig, ota: bool) -> Conformance {
    let cfg_fails_the_update = cfg.ota_fault.is_some();
    let mcu = serve(TuyaMcu::new(TuyaConfig {
        baud: Some(BAUD),
        ota_restart: Duration::from_millis(300),
        ..cfg
    }));
    let p = profile("tuya-vacuum");
    let link = open_link(
        &mcu,
        BAUD,
        p.clone(),
        LinkOptions {
            start_session: false,
            ..LinkOptions::default()
        },
    );
    // The update's limit is the wall clock's, which a loaded machine stretches (the MCU here
    // is back 300 ms after the last packet in its own time, in lockstep): an update that must
    // pass gets 60 s; one that must fail keeps 5 s, which it fails by whatever the load.
    let limit = if cfg_fails_the_update {
        Duration::from_secs(5)
    } else {
        Duration::from_secs(60)
    };
    let options = conform::Options {
        ota: ota.then(|| {
            (
                image(),
                Expect {
                    version: "1.2.3".into(),
                    limit,
                },
            )
        }),
        ota_max: p.ota_max_bytes(),
    };
    let c = link.client();
    conform::conform(
        Device::new(&c, &p),
        &options,
        &mut Run::new(&Default::default(), |_| {}),
        &mut |_| {},
    )
    .expect("graded")
}

fn check<'c>(c: &'c Conformance, id: &str) -> &'c conform::Check {
    c.checks
        .iter()
        .find(|k| k.id == id)
        .unwrap_or_else(|| panic!("no check {id}: {c:#?}"))
}

#[test]
fn the_simulated_mcu_conforms_and_its_update_is_proven() {
    let c = grade(TuyaConfig::default(), true);
    for k in &c.checks {
        assert_eq!(k.grade, Grade::Pass, "{k:#?}");
    }
    assert!(c.pass());
    assert_eq!(c.version.as_deref(), Some("1.0.0"));
    assert!(check(&c, "ota").detail.contains("version 1.0.0 → 1.2.3"));
    // Without --ota the update is skipped, not failed.
    let c = grade(TuyaConfig::default(), false);
    assert_eq!(check(&c, "ota").grade, Grade::Skip);
    assert!(c.pass(), "{c:#?}");
}

/// Grades a simulated MCU with one field misbehaviour (`what`, configured by `cfg`): the check
/// `id` fails, it is `mandatory` or not, and the whole passes only when it is not. One test per
/// misbehaviour, so that the suite runs them side by side (each grades a whole MCU).
fn fails_its_own_check(what: &str, cfg: TuyaConfig, id: &str, mandatory: bool) {
    let c = grade(cfg, false);
    let k = check(&c, id);
    assert_eq!(k.grade, Grade::Fail, "{what}: {k:#?}");
    assert_eq!(k.mandatory, mandatory, "{what}");
    assert_eq!(c.pass(), !mandatory, "{what}: {:#?}", c.failed());
}

#[test]
fn a_battery_reported_at_150_percent_fails_status_range() {
    let cfg = TuyaConfig {
        report_out_of_range: BTreeMap::from([(6, RawValue::Int(150))]),
        ..TuyaConfig::default()
    };
    fails_its_own_check("battery 150 %", cfg, "status_range", true);
}

#[test]
fn the_mode_reported_as_a_value_fails_status_types() {
    let cfg = TuyaConfig {
        misreport: BTreeMap::from([parse_misreport("3:value:4").unwrap()]),
        ..TuyaConfig::default()
    };
    fails_its_own_check("mode reported as a value", cfg, "status_types", true);
}

#[test]
fn a_data_point_the_profile_lacks_fails_status_unknown_not_mandatory() {
    let cfg = TuyaConfig {
        report_unknown_dp: vec![(101, DpValue::Value(50))],
        ..TuyaConfig::default()
    };
    fails_its_own_check("DP 101 the profile lacks", cfg, "status_unknown", false);
}

#[test]
fn reports_100_to_150_ms_apart_fail_status_burst_not_mandatory() {
    let cfg = TuyaConfig {
        report_gap: Some((Duration::from_millis(100), Duration::from_millis(150))),
        ..TuyaConfig::default()
    };
    fails_its_own_check("reports 100-150 ms apart", cfg, "status_burst", false);
}

#[test]
fn a_data_point_never_reported_fails_status_all() {
    let cfg = TuyaConfig {
        never_report: vec![19],
        ..TuyaConfig::default()
    };
    fails_its_own_check("DP 19 never reported", cfg, "status_all", true);
}

#[test]
fn a_frame_over_the_cap_fails_frames_clean() {
    let cfg = TuyaConfig {
        report_out_of_range: BTreeMap::from([(15, RawValue::Len(2000))]),
        ..TuyaConfig::default()
    };
    let what = "a 2000-byte clean record (a frame over the cap)";
    fails_its_own_check(what, cfg, "frames_clean", true);
}

#[test]
fn writes_of_report_only_data_points_taken_fail_read_only_refused() {
    let cfg = TuyaConfig {
        accept_read_only: true,
        ..TuyaConfig::default()
    };
    let what = "writes of report-only DPs taken";
    fails_its_own_check(what, cfg, "read_only_refused", true);
}

#[test]
fn a_bad_checksum_read_all_the_same_fails_bad_checksum() {
    let cfg = TuyaConfig {
        ignore_checksum: true,
        ..TuyaConfig::default()
    };
    fails_its_own_check(
        "a bad checksum read all the same",
        cfg,
        "bad_checksum",
        true,
    );
}

#[test]
fn an_unknown_command_answered_fails_unknown_command() {
    let cfg = TuyaConfig {
        answer_unknown: true,
        ..TuyaConfig::default()
    };
    fails_its_own_check("an unknown command answered", cfg, "unknown_command", true);
}

#[test]
fn frames_of_version_0x00_fail_frame_version_not_mandatory() {
    let cfg = TuyaConfig {
        frame_version: 0,
        ..TuyaConfig::default()
    };
    fails_its_own_check("frames of version 0x00", cfg, "frame_version", false);
}

/// Grades a simulated MCU whose update goes wrong by `fault`: the update check fails, saying
/// `said`, and so does the whole. One test per way, run side by side.
fn an_update_that_fails_fails_the_update_check(fault: OtaFault, said: &str) {
    let c = grade(
        TuyaConfig {
            ota_fault: Some(fault),
            ..TuyaConfig::default()
        },
        true,
    );
    let k = check(&c, "ota");
    assert_eq!(k.grade, Grade::Fail, "{fault:?}: {k:#?}");
    assert!(k.detail.contains(said), "{fault:?}: {}", k.detail);
    assert!(!c.pass());
}

#[test]
fn an_update_to_a_firmware_still_on_the_old_version_fails_the_update_check() {
    an_update_that_fails_fails_the_update_check(
        OtaFault::OldVersion,
        "still running version 1.0.0",
    );
}

#[test]
fn an_mcu_that_never_comes_back_from_its_update_fails_the_update_check() {
    an_update_that_fails_fails_the_update_check(OtaFault::NeverBack, "never came back");
}

#[test]
fn an_mcu_that_stops_acking_its_update_fails_the_update_check() {
    an_update_that_fails_fails_the_update_check(
        OtaFault::RefusePacket(1024),
        "stopped acking at offset 1024",
    );
}

#[test]
fn tuya_conform_prints_the_table_exits_by_the_mandatory_checks_and_records_the_run() {
    let dir = crate::support::temp_dir();
    let db = dir.path().join("line.sqlite");
    let db = db.to_str().unwrap();
    let good = Sim::start(&["tuya-vacuum", "--baud", "115200"]);
    let o = good.cli(
        "tuya",
        &[
            "--baud",
            "115200",
            "conform",
            "--records",
            db,
            "--serial",
            "VAC-7",
        ],
    );
    assert_eq!(o.code, 0, "{}", o.text());
    assert!(o.out.contains("CONFORMS:"), "{}", o.text());
    assert!(
        o.out
            .lines()
            .any(|l| l.starts_with("heartbeat") && l.contains("PASS"))
    );
    let bad = Sim::start(&["tuya-vacuum", "--baud", "115200", "--ignore-checksum"]);
    let o = bad.cli(
        "tuya",
        &[
            "--baud",
            "115200",
            "--json",
            "conform",
            "--records",
            db,
            "--serial",
            "VAC-8",
        ],
    );
    assert_eq!(o.code, 1, "{}", o.text());
    let doc = &o.json_docs()[0];
    let k = doc["checks"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["id"] == "bad_checksum")
        .unwrap();
    assert_eq!(k["grade"], "FAIL");
    // The corrupted heartbeat and the MCU's answer to it are the evidence.
    assert!(
        k["evidence"]
            .as_str()
            .unwrap()
            .starts_with("55 aa 00 00 00 00 00 →"),
        "{k}"
    );
    let show = run(&["records", "--records", db, "show", "VAC-8", "--json"]);
    let r = &show.json_lines()[0];
    assert_eq!(r["kind"], "tuya-conform", "{r}");
    assert_eq!(r["verdict"], "FAIL");
    assert_eq!(r["failed_step"], "bad_checksum");
    assert_eq!(r["unit"]["firmware"], "1.0.0");
    let show = run(&["records", "--records", db, "show", "VAC-7", "--json"]);
    assert_eq!(show.json_lines()[0]["verdict"], "PASS", "{}", show.text());
}
