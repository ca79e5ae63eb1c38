//! The command line run in this process, handed its port opener the way the binary hands it the
//! system's serial ports (`botbench::cli::main(PortOpener::system())`): a test's simulator is
//! reached through the opener it is given, served in lockstep, so nothing here depends on how
//! fast another process is scheduled.

use crate::support::cli::{run_in_process, run_in_process_into};
use crate::support::served_window_cleaner;
use botbench::link::PortOpener;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

#[test]
fn the_command_line_opens_its_port_with_the_opener_it_is_handed() {
    let b = served_window_cleaner();
    let opened = Arc::new(AtomicUsize::new(0));
    let ports = {
        let (opened, served, path) = (opened.clone(), b.ports(), b.path().to_string());
        PortOpener::system().with_port(b.path(), move |baud| {
            opened.fetch_add(1, Ordering::SeqCst);
            served.open(&path, baud)
        })
    };
    let ran = run_in_process(&["msp", "--port", b.path(), "version"], &ports);
    assert_eq!(
        ran.code,
        0,
        "msp version against the served window cleaner: {}",
        ran.text()
    );
    assert_eq!(
        opened.load(Ordering::SeqCst),
        1,
        "opened once, through the opener handed in"
    );

    // A port the opener does not serve is the system's: this one does not exist.
    let ran = run_in_process(
        &["msp", "--port", "/nonexistent/botbench-tty", "version"],
        &ports,
    );
    assert_eq!(
        ran.code,
        2,
        "a port that cannot be opened is bad input: {}",
        ran.text()
    );
    assert_eq!(opened.load(Ordering::SeqCst), 1);
}

#[test]
fn a_run_in_this_process_reads_the_profiles_of_the_folder_it_is_given_never_the_users() {
    let b = served_window_cleaner();
    let dir = crate::support::temp_dir();
    let broken = dir.path().join("window-cleaner.ron");
    std::fs::write(&broken, "(id: \"window-cleaner\",").unwrap();
    // Given the folder: its malformed profile is an error naming the file.
    let given = botbench::cli::Captured::default().with_profiles(dir.path());
    let ran = run_in_process_into(&["profiles"], &b.ports(), given);
    assert_eq!(ran.code, 2, "{}", ran.text());
    assert!(ran.err.contains("window-cleaner.ron"), "{}", ran.text());
    // The tests' runs get an empty folder: the built-ins, whatever the user has.
    let ran = run_in_process(&["profiles"], &b.ports());
    assert_eq!(ran.code, 0, "{}", ran.text());
    assert!(ran.out.contains("window-cleaner"), "{}", ran.text());
}

/// A port nothing ever answers on, on a computer so loaded that every read that finds nothing
/// returns 30 ms after its deadline (the link's thread not scheduled in time).
struct HeldUpSilent;

impl botbench::link::Transport for HeldUpSilent {
    fn write(&mut self, _bytes: &[u8]) -> Result<(), botbench::link::LinkError> {
        Ok(())
    }
    fn read(
        &mut self,
        _buf: &mut [u8],
        deadline: std::time::Instant,
    ) -> Result<usize, botbench::link::LinkError> {
        let wake = deadline + std::time::Duration::from_millis(30);
        std::thread::sleep(wake.saturating_duration_since(std::time::Instant::now()));
        Ok(0)
    }
    fn set_baud(&mut self, _baud: u32) -> Result<(), botbench::link::LinkError> {
        Ok(())
    }
    fn baud(&self) -> u32 {
        115_200
    }
    fn clear_input(&mut self) -> Result<(), botbench::link::LinkError> {
        Ok(())
    }
    fn describe(&self) -> String {
        "a silent port on a held-up computer".into()
    }
}

/// The path the held-up silent port is served at.
const HELD_UP: &str = "/botbench-test/held-up-silent";

/// The system's ports, and [`HeldUpSilent`] at [`HELD_UP`].
fn held_up_ports() -> PortOpener {
    PortOpener::system().with_port(HELD_UP, |_baud| {
        Box::new(|| Ok(Box::new(HeldUpSilent) as Box<dyn botbench::link::Transport>))
    })
}

/// A servo read that went unanswered while this computer was held up past the answer's
/// deadline says the loaded computer first, and the wiring checklist only after it, once
/// (issue 25, item 4e: a loaded host is not a missing servo).
#[test]
fn an_unanswered_read_on_a_held_up_computer_leads_with_the_loaded_computer() {
    let ran = run_in_process(
        &["servo", "--port", HELD_UP, "read", "1", "voltage"],
        &held_up_ports(),
    );
    assert_eq!(ran.code, 1, "{}", ran.text());
    let said = ran.err.lines().last().unwrap_or_default();
    assert!(
        said.contains("no answer to READ_DATA (3) after"),
        "{}",
        ran.text()
    );
    let late = said.find("; this computer was held up ");
    let wiring = said.find("TX wired");
    assert!(
        late.is_some() && wiring.is_some() && late < wiring,
        "the loaded computer leads: {said}"
    );
    assert!(
        said.contains(
            " ms past the answer's deadline (a loaded computer: the answer may have come \
             while it was): close other programs and retry; if it still does not answer with \
             the computer idle: is the device powered"
        ),
        "{said}"
    );
    assert_eq!(said.matches("held up").count(), 1, "said once: {said}");
}

/// A scan that found nothing while this computer was held up past its sweeps' deadlines says
/// the loaded computer first, before the wiring, and still exits 1.
#[test]
fn an_empty_scan_on_a_held_up_computer_leads_with_the_loaded_computer() {
    let ran = run_in_process(
        &["servo", "--port", HELD_UP, "scan", "--ids", "0-3"],
        &held_up_ports(),
    );
    assert_eq!(ran.code, 1, "{}", ran.text());
    let said = ran
        .err
        .lines()
        .find(|l| l.contains("no servo answered on"))
        .unwrap_or_default();
    let late = said.find("; this computer was held up ");
    let wiring = said.find("TX wired");
    assert!(
        late.is_some() && wiring.is_some() && late < wiring,
        "the loaded computer leads: {}",
        ran.text()
    );
}

/// `sim`'s ports, its path behind a computer held up at its first `late_reads` reads that
/// find nothing ([`crate::support::held_up`]).
fn held_up_at_first(sim: &crate::support::cli::Sim, late_reads: usize) -> PortOpener {
    crate::support::held_up::held_up(sim.ports().clone(), &sim.path, late_reads)
}

/// A scan that found servos while this computer was held up through every sweep, however often
/// it asked the silent ids again, cannot say those ids are empty: it names them (issue 25, item
/// 4e: before, "a servo may have been missed", naming none and asking none again).
#[test]
fn a_scan_held_up_through_every_sweep_names_the_ids_it_cannot_vouch_for() {
    let sim = crate::support::cli::Sim::start(&["servo-bus", "--servos", "1,5"]);
    let ports = held_up_at_first(&sim, usize::MAX);
    let ran = run_in_process(
        &["servo", "--port", &sim.path, "scan", "--ids", "0-6"],
        &ports,
    );
    assert_eq!(ran.code, 0, "{}", ran.text());
    for id in ["1", "5"] {
        assert!(
            ran.out
                .lines()
                .any(|l| l.split_whitespace().next() == Some(id)),
            "servo {id} is listed: {}",
            ran.text()
        );
    }
    let said = ran
        .err
        .lines()
        .find(|l| l.contains("stayed silent only while this computer was held up"))
        .unwrap_or_else(|| panic!("the unsure ids said: {}", ran.text()));
    assert!(
        said.contains("5 id(s) stayed silent") && said.contains("(0, 2, 3, 4, 6 at "),
        "{said}"
    );
}

/// A scan held up in its first sweep asks the ids silent then again, and never counts a servo
/// that answered among those it cannot vouch for.
#[test]
fn a_scan_held_up_only_at_first_asks_the_silent_ids_again_and_vouches_for_them() {
    let sim = crate::support::cli::Sim::start(&["servo-bus", "--servos", "1,5"]);
    let ports = held_up_at_first(&sim, 2);
    let ran = run_in_process(
        &[
            "servo", "--port", &sim.path, "--json", "scan", "--ids", "0-6",
        ],
        &ports,
    );
    assert_eq!(ran.code, 0, "{}", ran.text());
    let doc: serde_json::Value = serde_json::from_str(&ran.out).expect("a JSON document");
    assert!(
        doc["host_late_ms"].as_f64().is_some_and(|ms| ms >= 20.0),
        "the hold-up is reported: {}",
        ran.out
    );
    let unsure = doc["unsure"].as_array().expect("the unsure ids");
    assert!(
        unsure
            .iter()
            .all(|u| [0, 2, 3, 4, 6].contains(&u["id"].as_u64().unwrap_or(99))),
        "only silent ids: {}",
        ran.out
    );
    assert!(
        doc["asked_after_hold_up"].as_u64().is_some_and(|n| n >= 5),
        "the silent ids were asked again: {}",
        ran.out
    );
}
