//! The records from the command line (issue 28): a self-test recorded with the unit's serial,
//! the unit's history said before its next run, the records listed, shown, exported and
//! reported (HTML with inline SVG), and bad records locations refused before anything runs, or,
//! for a line server away, the verdict shown and the record kept in the spool.

use crate::support::cli::{Sim, run};

/// A short plan: the battery voltage and the water box.
const PLAN: &str = r#"(
    version: 1,
    profile: "window-cleaner",
    name: "Records test",
    steps: [
        Range(name: "Battery voltage", command: "MSP_ADAPTER", field: "batteryVoltage",
              min: "11.5", max: "16.8", samples: 3, interval_ms: 1),
        Reads(name: "Water box", command: "MSP_WATER_BOX", expect: {"status": "1"}),
    ],
)"#;

#[test]
fn a_self_test_is_recorded_with_its_serial_and_read_back_listed_shown_exported_and_reported() {
    let dir = crate::support::temp_dir();
    let plan = dir.path().join("plan.ron");
    std::fs::write(&plan, PLAN).unwrap();
    let db = dir.path().join("line.sqlite");
    let (plan, db) = (plan.to_str().unwrap(), db.to_str().unwrap());
    let sim = Sim::start(&["window-cleaner"]);
    let args = [
        "selftest",
        plan,
        "--yes",
        "--records",
        db,
        "--serial",
        "WC-0042",
        "--station",
        "st9",
        "--operator",
        "ana",
        "--slot",
        "2",
    ];
    let first = sim.cli("msp", &args);
    assert_eq!(first.code, 0, "{}", first.text());
    assert!(
        first.out.contains("serial WC-0042: not tested before"),
        "{}",
        first.text()
    );
    assert!(first.err.contains("record saved to"), "{}", first.text());
    let second = sim.cli("msp", &args);
    assert_eq!(second.code, 0, "{}", second.text());
    assert!(
        second
            .out
            .contains("serial WC-0042: already tested 1 time, last: PASS on ")
            && second.out.contains(" at st9"),
        "{}",
        second.text()
    );
    // The history comes before the run's first step.
    let said = second.out.find("already tested").unwrap();
    assert!(
        said < second.out.find("Battery voltage").unwrap(),
        "{}",
        second.out
    );

    read_back(db, &dir.path().join("report.html"));
}

/// The two runs of WC-0042 in `db` listed, shown, exported and reported (HTML to `html`).
fn read_back(db: &str, html: &std::path::Path) {
    let list = run(&["records", "--records", db, "list"]);
    assert_eq!(list.code, 0, "{}", list.text());
    assert_eq!(list.out.lines().count(), 2, "{}", list.out);
    assert!(list.out.contains("PASS") && list.out.contains("WC-0042") && list.out.contains("st9"));

    let show = run(&["records", "--records", db, "show", "WC-0042", "--json"]);
    let docs = show.json_lines();
    assert_eq!(docs.len(), 2, "{}", show.text());
    let r = &docs[0];
    assert_eq!(r["verdict"], "PASS");
    assert_eq!(r["unit"]["serial"], "WC-0042");
    assert_eq!(r["unit"]["serial_source"], "typed");
    assert_eq!(r["unit"]["hardware"], "0x03");
    assert_eq!(r["context"]["operator"], "ana");
    assert_eq!(r["context"]["slot"], "2");
    assert_eq!(r["plan"], "Records test");
    assert_eq!(r["plan_sha256"].as_str().unwrap().len(), 64);
    assert_eq!(r["software"], env!("CARGO_PKG_VERSION"));
    let m = &r["steps"][0]["measurements"][0];
    assert_eq!(
        (m["name"].as_str(), m["unit"].as_str()),
        (Some("batteryVoltage"), Some("V"))
    );
    assert_eq!(
        (m["low"].as_f64(), m["high"].as_f64()),
        (Some(11.5), Some(16.8))
    );
    assert!(m["value"].as_f64().unwrap() > 11.5);

    let csv = run(&["records", "--records", db, "export", "--format", "csv"]);
    assert_eq!(csv.code, 0, "{}", csv.text());
    let lines: Vec<&str> = csv.out.lines().collect();
    assert!(
        lines[0].starts_with("uuid,kind,started,station"),
        "{}",
        lines[0]
    );
    // Per run: the battery voltage's measurement and the water box (no measurement).
    assert_eq!(lines.len(), 1 + 2 * 2, "{}", csv.out);
    let jsonl = run(&[
        "records",
        "--records",
        db,
        "export",
        "--format",
        "jsonl",
        "--station",
        "st9",
    ]);
    assert_eq!(jsonl.json_lines().len(), 2);
    let none = run(&[
        "records",
        "--records",
        db,
        "export",
        "--format",
        "jsonl",
        "--station",
        "other",
    ]);
    assert_eq!(none.out, "");

    let rep = run(&["report", "--records", db, "--html", html.to_str().unwrap()]);
    assert_eq!(rep.code, 0, "{}", rep.text());
    assert!(
        rep.out
            .contains("1 units, 2 runs: first-pass yield 100.0 %"),
        "{}",
        rep.out
    );
    let page = std::fs::read_to_string(html).unwrap();
    assert!(
        page.contains("<svg") && page.contains("batteryVoltage"),
        "no plot"
    );
    // Nothing runs and nothing is fetched: no script, no link or source to elsewhere (the SVG
    // namespace is a name, not a fetch).
    for fetch in ["<script", "src=", "href=", "@import", "url("] {
        assert!(!page.contains(fetch), "the page has {fetch}");
    }
    let json = run(&["report", "--records", db, "--json"]).json();
    assert_eq!(json["overall"]["units"], 1);
    assert_eq!(json["overall"]["runs"], 2);
}

#[test]
fn bad_records_locations_are_refused_before_anything_runs() {
    let dir = crate::support::temp_dir();
    let plan = dir.path().join("plan.ron");
    std::fs::write(&plan, PLAN).unwrap();
    let plan = plan.to_str().unwrap();
    let notes = dir.path().join("notes.txt");
    std::fs::write(&notes, "not a database\n".repeat(100)).unwrap();
    let bad = run(&[
        "msp",
        "--port",
        "/dev/null",
        "selftest",
        plan,
        "--records",
        "postgres://ana:pw@host:port/db",
    ]);
    assert_eq!(bad.code, 2, "{}", bad.text());
    assert!(
        bad.err.contains("not a PostgreSQL URL") && !bad.err.contains("pw@"),
        "{}",
        bad.err
    );
    let sim = Sim::start(&["window-cleaner"]);
    let notdb = sim.cli(
        "msp",
        &["selftest", plan, "--records", notes.to_str().unwrap()],
    );
    assert_eq!(notdb.code, 2, "{}", notdb.text());
    assert!(
        notdb.err.contains("notes.txt is not a SQLite database"),
        "{}",
        notdb.err
    );
    assert!(
        !notdb.out.contains("Battery voltage"),
        "it ran: {}",
        notdb.out
    );
    let none = run(&[
        "records",
        "--records",
        dir.path().join("none.sqlite").to_str().unwrap(),
        "list",
    ]);
    assert_eq!(none.code, 2, "{}", none.text());
    assert!(
        none.err.contains("no records file there yet"),
        "{}",
        none.err
    );
}

#[test]
fn a_line_server_away_still_shows_the_verdict_and_keeps_the_record_in_the_spool() {
    let dir = crate::support::temp_dir();
    let plan = dir.path().join("plan.ron");
    std::fs::write(&plan, PLAN).unwrap();
    let spool = dir.path().join("spool.sqlite");
    // The spool is named by --spool (BOTBENCH_SPOOL would be the whole process's): the command
    // runs in this process, its simulator in lockstep with it.
    let sim = Sim::start(&["window-cleaner"]);
    // Port 1 on this machine: nothing listens there.
    let ran = sim.cli(
        "msp",
        &[
            "selftest",
            plan.to_str().unwrap(),
            "--records",
            "postgres://botbench@127.0.0.1:1/line",
            "--spool",
            spool.to_str().unwrap(),
            "--serial",
            "WC-7",
        ],
    );
    assert_eq!(ran.code, 0, "{}", ran.text());
    assert!(
        ran.out.contains("PASS: all 2 steps passed"),
        "{}",
        ran.text()
    );
    assert!(ran.err.contains("cannot be reached"), "{}", ran.err);
    assert!(
        ran.err.contains("record kept in the spool") && ran.err.contains("(1 waiting"),
        "{}",
        ran.err
    );
    let list = crate::support::cli::run_in_process(
        &["records", "--records", spool.to_str().unwrap(), "list"],
        &botbench::link::PortOpener::system(),
    );
    assert!(list.out.contains("WC-7"), "{}", list.text());
}
