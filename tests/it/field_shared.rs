//! Another program reads the same port (issue 25, item 1): a second botbench, a terminal
//! program, ModemManager. The OS hands each byte to one reader, and wakes them all: the link's
//! read found nothing where the port had said bytes were ready, and blocked there for ever.
//! Here the other reader is `cat` on the pty, started before botbench, as a terminal program
//! left open is (root opens a port another process marked exclusive anyway, so the tests run
//! the case exclusivity cannot prevent). botbench must end (the watchdog of `run_watched`
//! fails the test instead of hanging), say that bytes are being taken by someone else and by
//! whom, and never report an empty or partial scan as a success.

use crate::support::PATIENCE;
use crate::support::cli::{Ran, Sim, SimProcess};
use std::process::{Child, Command, Stdio};
use std::time::Instant;

/// `cat PATH`, reading the port and throwing its bytes away; killed on drop.
struct Thief(Child);

impl Thief {
    /// Starts `cat` on `path` and waits until the OS lists it as a reader of the port.
    fn on(path: &str) -> Self {
        let child = Command::new("cat")
            .arg(path)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("runs cat");
        let thief = Self(child);
        let deadline = Instant::now() + PATIENCE;
        while !botbench::system::other_readers(path)
            .iter()
            .any(|h| h.pid == thief.0.id())
        {
            assert!(Instant::now() < deadline, "cat never opened {path}");
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        thief
    }
}

impl Drop for Thief {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Whether `run` says that the port's bytes are being taken, naming `cat`.
fn says_taken(run: &Ran) -> bool {
    let said = format!("{}{}", run.out, run.err);
    said.contains("bytes are being taken by someone else") && said.contains("cat (pid")
}

#[test]
fn a_watch_with_another_reader_on_the_port_ends_and_says_who_takes_the_bytes() {
    let sim = SimProcess::start(&["window-cleaner"]);
    let _thief = Thief::on(&sim.path);
    let run = sim.cli("msp", &["watch", "MSP_GET_PWMVALUE", "--count", "40"]);
    assert!(says_taken(&run), "{}", run.text());
    assert!(
        !run.out.contains("is the device powered") && !run.err.contains("is the device powered"),
        "the wiring is not blamed: {}",
        run.text()
    );
}

#[test]
fn a_version_with_another_reader_on_the_port_ends_and_answers_or_says_who_takes_the_bytes() {
    let sim = SimProcess::start(&["window-cleaner"]);
    let _thief = Thief::on(&sim.path);
    let run = sim.cli("msp", &["version"]);
    if run.code == 0 {
        // Only an identification that got its answers may succeed.
        assert!(run.out.contains("1.4.2"), "{}", run.text());
    } else {
        assert!(says_taken(&run), "{}", run.text());
        assert!(
            !run.err.contains("is the device powered"),
            "the wiring is not blamed: {}",
            run.text()
        );
    }
}

#[test]
fn a_scan_with_another_reader_on_the_port_never_exits_0_having_missed_a_servo() {
    let sim = SimProcess::start(&["servo-bus", "--servos", "1,2,5"]);
    let _thief = Thief::on(&sim.path);
    let run = sim.cli("servo", &["--json", "scan", "--ids", "0-10"]);
    let found = |run: &Ran| {
        run.json_docs()
            .first()
            .and_then(|d| d["servos"].as_array().map(Vec::len))
    };
    if run.code == 0 {
        // Only a scan that got every answer may succeed.
        assert_eq!(found(&run), Some(3), "{}", run.text());
    } else {
        assert!(says_taken(&run), "{}", run.text());
    }
}

#[test]
fn a_scan_that_finds_nothing_exits_1_unless_an_empty_bus_is_allowed() {
    let sim = Sim::start(&["servo-bus", "--servos", "7"]);
    let empty = sim.cli("servo", &["scan", "--ids", "0-3"]);
    assert_eq!(empty.code, 1, "{}", empty.text());
    assert!(
        empty.err.contains("no servo answered") && empty.err.contains("is the device powered"),
        "{}",
        empty.text()
    );
    let allowed = sim.cli("servo", &["scan", "--ids", "0-3", "--allow-empty"]);
    assert_eq!(allowed.code, 0, "{}", allowed.text());
}

#[test]
fn the_windows_stop_with_another_reader_on_the_port_is_answered_or_says_who_takes_the_bytes() {
    use crate::support::gui::{app, harness, settings, step_until};
    use botbench::ui::PanelId;
    use botbench::ui::stop::StopState;
    use egui_kittest::kittest::Queryable;
    // The device served by another program, as `botbench sim` serves it: the window opens the
    // port as any, and `cat` can take its bytes.
    let sim = SimProcess::start(&["window-cleaner"]);
    let _thief = Thief::on(&sim.path);
    let saved = settings(
        &sim.path,
        "window-cleaner",
        PanelId::DEVICE,
        botbench::i18n::Lang::En,
    );
    let mut h = harness(saved, botbench::link::PortOpener::system());
    step_until(&mut h, "the port open", |a| a.station().connected());
    h.get_by_label("STOP").click();
    // The link thread never blocks in a read: STOP is answered, or fails saying why.
    step_until(&mut h, "STOP answered or failed", |a| {
        matches!(
            a.station().stop.state(),
            StopState::Acked(_) | StopState::Failed(_)
        )
    });
    if let StopState::Failed(e) = app(&h).station().stop.state() {
        assert!(
            e.contains("bytes are being taken by someone else") && e.contains("cat (pid"),
            "{e}"
        );
    }
}
