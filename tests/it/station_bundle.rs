//! The station bundle (issue 27): checked whole before anything runs. `station --check` prints
//! every named file's SHA-256 and the bundle's; each bad bundle is refused with exit 2 and its
//! file:line:column or slot named; `station new` writes the example, which checks clean.

use crate::support::cli::run_in_process;
use botbench::link::PortOpener;
use std::path::{Path, PathBuf};

/// The demo bundle's text with `edit` applied, written into `dir` beside copies of the files
/// it names.
fn bundle_in(dir: &Path, edit: impl Fn(String) -> String) -> PathBuf {
    let presets = Path::new(env!("CARGO_MANIFEST_DIR")).join("presets");
    for f in ["window-cleaner-selftest.ron", "servo-provision-plan.ron"] {
        std::fs::copy(presets.join(f), dir.join(f)).unwrap();
    }
    let text = std::fs::read_to_string(presets.join("demo-station.ron")).unwrap();
    let path = dir.join("station.ron");
    std::fs::write(&path, edit(text)).unwrap();
    path
}

fn check(path: &Path) -> crate::support::cli::Ran {
    run_in_process(
        &["station", &path.display().to_string(), "--check"],
        &PortOpener::system(),
    )
}

#[test]
fn the_demo_bundle_checks_and_its_hash_covers_every_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = bundle_in(dir.path(), |t| t);
    let ran = run_in_process(
        &["station", &path.display().to_string(), "--check", "--json"],
        &PortOpener::system(),
    );
    assert_eq!(ran.code, 0, "{}", ran.text());
    let doc = ran.json();
    let files = doc["files"].as_array().unwrap();
    assert_eq!(files.len(), 2, "{doc}");
    let plan = dir.path().join("window-cleaner-selftest.ron");
    let want = botbench::ops::records::record::file_sha256(&plan).unwrap();
    assert_eq!(files[0]["sha256"], want.as_str(), "{doc}");
    assert_eq!(doc["slots"].as_array().unwrap().len(), 3);
    let before = doc["bundle_sha256"].as_str().unwrap().to_string();
    // A named file edited (a comment only): the bundle's hash changes, its text's does not.
    let mut text = std::fs::read_to_string(&plan).unwrap();
    text.push_str("\n// edited\n");
    std::fs::write(&plan, text).unwrap();
    let again = run_in_process(
        &["station", &path.display().to_string(), "--check", "--json"],
        &PortOpener::system(),
    );
    assert_eq!(again.code, 0, "{}", again.text());
    assert_ne!(again.json()["bundle_sha256"].as_str().unwrap(), before);
    assert_eq!(again.json()["text_sha256"], doc["text_sha256"]);
}

#[test]
fn a_pinned_file_edited_after_the_bundle_was_made_is_refused_where_it_is_pinned() {
    let dir = tempfile::tempdir().unwrap();
    let good = bundle_in(dir.path(), |t| t);
    let ran = run_in_process(
        &["station", &good.display().to_string(), "--check", "--json"],
        &PortOpener::system(),
    );
    let sha = ran.json()["files"][0]["sha256"]
        .as_str()
        .unwrap()
        .to_string();
    let pin = |sha: &str| {
        let sha = sha.to_string();
        move |t: String| {
            t.replace(
                "    plans: {",
                &format!(
                    "    pins: {{ \"window-cleaner-selftest.ron\": \"{sha}\" }},\n    plans: {{"
                ),
            )
        }
    };
    let pinned = bundle_in(dir.path(), pin(&sha));
    assert_eq!(check(&pinned).code, 0, "{}", check(&pinned).text());
    let wrong = "0".repeat(64);
    let pinned = bundle_in(dir.path(), pin(&wrong));
    let ran = check(&pinned);
    assert_eq!(ran.code, 2, "{}", ran.text());
    let line = pinned_line(&pinned);
    assert!(
        ran.err.contains(&format!("station.ron:{line}:"))
            && ran.err.contains("has changed since the bundle was made")
            && ran.err.contains(&sha[..16]),
        "{}",
        ran.text()
    );
}

/// The line of `pins:` in the bundle at `path`.
fn pinned_line(path: &Path) -> usize {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .position(|l| l.trim_start().starts_with("pins: {"))
        .unwrap()
        + 1
}

/// A change of the bundle's text.
type Edit = Box<dyn Fn(String) -> String>;

#[test]
fn each_bad_bundle_is_refused_naming_its_place_or_slot() {
    let dir = tempfile::tempdir().unwrap();
    let cases: Vec<(&str, Edit, &str)> = vec![
        (
            "a missing file",
            Box::new(|t| {
                t.replace(
                    "SelfTest(\"window-cleaner-selftest.ron\")",
                    "SelfTest(\"gone.ron\")",
                )
            }),
            "gone.ron",
        ),
        (
            "two slots on one port",
            Box::new(|t| {
                t.replace("Simulated(\"servo-bus\")", "Path(\"/dev/null\")")
                    .replace("Simulated(\"tuya-vacuum\")", "Path(\"/dev/null\")")
            }),
            "slot 3: two slots on one port: /dev/null is slot 2's port too",
        ),
        (
            "an unknown profile",
            Box::new(|t| t.replace("profile: \"servo\"", "profile: \"servo-x\"")),
            "slot 2: no profile 'servo-x'",
        ),
        (
            "an unknown plan step",
            Box::new(|t| t.replace("TuyaStatus,", "TuyaDance,")),
            "TuyaDance",
        ),
        (
            "a step for another kind of device",
            Box::new(|t| t.replace("TuyaStatus,", "WriteResult,")),
            "slot 3: plan tuya-vacuum, step 2 (WriteResult): takes a device speaking msp",
        ),
        (
            "an unknown plan",
            Box::new(|t| t.replace("plan: \"servo\"", "plan: \"servos\"")),
            "slot 2: no plan 'servos'",
        ),
        (
            "a line level that is not one",
            Box::new(|t| t.replace("dtr: \"keep\"", "dtr: \"high\"")),
            "slot 1: dtr: 'high' is not a line level; give on, off or keep",
        ),
        (
            "a boot wait out of range",
            Box::new(|t| t.replace("boot_wait_ms: 0", "boot_wait_ms: 40000")),
            "slot 1: boot_wait_ms: 40000 is out of range; give milliseconds from 0 to 30000",
        ),
        (
            "a bad scan pattern",
            Box::new(|t| {
                t.replace(
                    "// Scan(pattern: \"WC[0-9]{6}\")",
                    "Scan(pattern: \"WC[0-9\")",
                )
            }),
            "Scan pattern",
        ),
    ];
    for (what, edit, said) in cases {
        let path = bundle_in(dir.path(), edit);
        let ran = check(&path);
        assert_eq!(ran.code, 2, "{what}: {}", ran.text());
        assert!(ran.err.contains(said), "{what}: {}", ran.text());
        // Every refusal is placed in the bundle: file:line:col.
        let placed = regex_like_place(&ran.err);
        assert!(placed, "{what} names no line and column: {}", ran.text());
        assert!(
            !ran.out.contains("bundle checked"),
            "{what}: {}",
            ran.text()
        );
    }
}

/// Whether `err` holds `station.ron:LINE:COL:`.
fn regex_like_place(err: &str) -> bool {
    err.split("station.ron:").skip(1).any(|rest| {
        let mut parts = rest.splitn(3, ':');
        let line = parts.next().unwrap_or("");
        let col = parts.next().unwrap_or("");
        line.parse::<usize>().is_ok_and(|l| l > 0) && col.parse::<usize>().is_ok_and(|c| c > 0)
    })
}

#[test]
fn a_slot_whose_port_is_missing_at_start_is_named_and_nothing_starts() {
    let dir = tempfile::tempdir().unwrap();
    let path = bundle_in(dir.path(), |t| {
        t.replace(
            "Simulated(\"window-cleaner\")",
            "UsbPath(\"/dev/serial/by-path/pci-0000:00:14.0-usb-0:9:1.0-port0\")",
        )
    });
    let ran = check(&path);
    assert_eq!(ran.code, 2, "{}", ran.text());
    assert!(
        ran.err
            .contains("slot 1: no adapter at /dev/serial/by-path/")
            && ran.err.contains("unplugged"),
        "{}",
        ran.text()
    );
    assert!(ran.out.contains("MISSING"), "{}", ran.text());
}

#[test]
fn station_new_writes_the_example_which_checks_clean_and_is_never_written_over() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("line.ron");
    let p = path.display().to_string();
    let ran = run_in_process(&["station", "new", &p], &PortOpener::system());
    assert_eq!(ran.code, 0, "{}", ran.text());
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("Simulated(\"window-cleaner\")") && text.contains("// "));
    // Its files are the shipped presets (not beside it): found there when this is an installed
    // botbench; here, copied beside it.
    let presets = Path::new(env!("CARGO_MANIFEST_DIR")).join("presets");
    for f in ["window-cleaner-selftest.ron", "servo-provision-plan.ron"] {
        std::fs::copy(presets.join(f), dir.path().join(f)).unwrap();
    }
    assert_eq!(check(&path).code, 0, "{}", check(&path).text());
    let again = run_in_process(&["station", "new", &p], &PortOpener::system());
    assert_eq!(again.code, 2, "{}", again.text());
    assert_eq!(std::fs::read_to_string(&path).unwrap(), text);
}

#[test]
fn every_shipped_station_bundle_loads() {
    let presets = Path::new(env!("CARGO_MANIFEST_DIR")).join("presets");
    let registry = botbench::profile::Registry::builtin().unwrap();
    let sims = [
        ("window-cleaner", "window-cleaner"),
        ("solar-cleanbot", "solar-cleanbot"),
        ("servo-bus", "servo"),
        ("tuya-vacuum", "tuya-vacuum"),
    ];
    let cx = botbench::ops::station::LoadContext {
        registry: &registry,
        simulated: &sims,
    };
    let mut n = 0;
    for e in std::fs::read_dir(&presets).unwrap() {
        let path = e.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if name.contains("station") {
            let b =
                botbench::ops::station::load(&path, &cx).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert!(!b.slots.is_empty());
            n += 1;
        }
    }
    assert!(n >= 4, "the demo and one bundle per device kind: {n}");
}
