//! The slot runner (issue 27) driven as the window drives it: a slot whose adapter is unplugged
//! mid-unit says `link lost during <step>`, shows its port missing, waits for it, and comes back
//! under the same fixture path (a `/dev/serial/by-path`-style link re-pointed at the new
//! adapter's device), all without stalling; STOP ends it.

use crate::support::cli::{Sim, WATCHDOG};
use botbench::link::PortOpener;
use botbench::ops::records::{Recorder, RunContext, SqliteStore};
use botbench::ops::station::{self, Answer, Command, Event, LoadContext, OperatorHands, What};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// The next event that `want` accepts, failing after [`WATCHDOG`] with what came meanwhile.
fn next_event(rx: &crossbeam_channel::Receiver<Event>, want: impl Fn(&What) -> bool) -> Event {
    let deadline = std::time::Instant::now() + WATCHDOG;
    let mut seen = Vec::new();
    loop {
        let left = deadline.saturating_duration_since(std::time::Instant::now());
        match rx.recv_timeout(left) {
            Ok(ev) if want(&ev.what) => return ev,
            Ok(ev) => seen.push(ev),
            Err(e) => panic!("no such event ({e}); seen: {seen:#?}"),
        }
    }
}

/// The fixture's path: a symbolic link, as udev keeps under /dev/serial/by-path, pointing at
/// whichever pty serves the unit now; its opener reaches that simulator in lockstep.
struct FixturePath {
    link: PathBuf,
    current: Arc<Mutex<Option<(PortOpener, String)>>>,
}

impl FixturePath {
    fn new(dir: &Path) -> Self {
        Self {
            link: dir.join("pci-0000:00:14.0-usb-0:2:1.0-port0"),
            current: Arc::default(),
        }
    }

    fn plug(&self, sim: &Sim) {
        let _ = std::fs::remove_file(&self.link);
        std::os::unix::fs::symlink(&sim.path, &self.link).unwrap();
        *self.current.lock().unwrap() = Some((sim.ports().clone(), sim.path.clone()));
    }

    fn unplug(&self) {
        std::fs::remove_file(&self.link).unwrap();
        *self.current.lock().unwrap() = None;
    }

    fn opener(&self) -> PortOpener {
        let current = self.current.clone();
        PortOpener::system().with_port(self.link.display().to_string(), move |baud| {
            match current.lock().unwrap().clone() {
                Some((ports, path)) => ports.open(&path, baud),
                None => PortOpener::system().open("/nonexistent/unplugged", baud),
            }
        })
    }
}

#[test]
fn an_unplugged_slot_says_link_lost_during_its_step_and_comes_back_under_the_same_path() {
    let dir = tempfile::tempdir().unwrap();
    let fixture = FixturePath::new(dir.path());
    let mut first = Sim::start(&["window-cleaner"]);
    fixture.plug(&first);
    let bundle_path = dir.path().join("station.ron");
    std::fs::write(
        &bundle_path,
        format!(
            r#"(version: 1, id: "replug",
                plans: {{ "wc": (start: Button, steps: [
                    Identify(hardware: [3]), Confirm(question: "Did it spray?"), WriteResult]) }},
                slots: [(name: "1", fixture: "WC", port: UsbPath("{}"),
                         profile: "window-cleaner", plan: "wc")])"#,
            fixture.link.display()
        ),
    )
    .unwrap();
    let registry = botbench::profile::Registry::builtin().unwrap();
    let sims = [("window-cleaner", "window-cleaner")];
    let cx = LoadContext {
        registry: &registry,
        simulated: &sims,
    };
    let bundle = station::load(&bundle_path, &cx).unwrap();
    let store = SqliteStore::open(&dir.path().join("records.sqlite")).unwrap();
    let recorder = Recorder::with_store(Box::new(store), RunContext::default(), None);
    let context = station::StationContext::new(&bundle, None, recorder);
    let (tx, rx) = crossbeam_channel::unbounded();
    let slot = bundle.slots[0].clone();
    let handle = station::spawn(
        slot,
        context,
        fixture.opener(),
        Box::new(OperatorHands),
        tx,
        false,
    )
    .unwrap();
    next_event(&rx, |w| matches!(w, What::Port { present: true, .. }));
    next_event(&rx, |w| matches!(w, What::Waiting { .. }));
    handle.commands.send(Command::Start).unwrap();
    next_event(&rx, |w| {
        matches!(
            w,
            What::Ask {
                kind: "confirm",
                ..
            }
        )
    });
    // The adapter is pulled while the operator looks at the unit.
    fixture.unplug();
    first.vanish_now();
    handle.commands.send(Command::Answer(Answer::Yes)).unwrap();
    let verdict = next_event(&rx, |w| matches!(w, What::Verdict { .. }));
    let What::Verdict {
        pass,
        reason,
        failed_step,
        ..
    } = verdict.what
    else {
        unreachable!()
    };
    assert!(!pass);
    assert_eq!(failed_step.as_deref(), Some("Write result"));
    assert_eq!(
        reason.map(|r| r.to_string()).as_deref(),
        Some("link lost during Write result")
    );
    let missing = next_event(&rx, |w| matches!(w, What::Port { present: false, .. }));
    let What::Port { detail, .. } = missing.what else {
        unreachable!()
    };
    assert!(detail.contains("unplugged"), "{detail}");
    // The adapter comes back in the same socket: the same fixture path, another device file.
    let second = Sim::start(&["window-cleaner"]);
    assert_ne!(second.path, first.path);
    fixture.plug(&second);
    let back = next_event(&rx, |w| matches!(w, What::Port { present: true, .. }));
    let What::Port { detail, .. } = back.what else {
        unreachable!()
    };
    assert_eq!(detail, fixture.link.display().to_string());
    next_event(&rx, |w| matches!(w, What::Waiting { .. }));
    // STOP: the slot ends at once, saying so.
    handle.cancel.cancel();
    next_event(&rx, |w| matches!(w, What::Stopped { .. }));
    crate::support::joined(handle.thread, "the slot's thread");
}

/// A simulated unit whose next `late` answers leave [`LateAnswers::DELAY`] after their request:
/// the field's device, line or host running late for one identity poll of the idle fixture.
struct LateAnswers {
    inner: botbench::sim::SharedDevice,
    /// Answers still to send late.
    late: Arc<std::sync::atomic::AtomicU32>,
    /// Answers sent on time since the late ones were asked for.
    on_time: Arc<std::sync::atomic::AtomicU32>,
}

impl LateAnswers {
    /// Past both attempts' windows of an identity poll (CMD_VERSION, two attempts of tens of
    /// ms), well within the station's [`station::EMPTY_SILENCE`].
    const DELAY: std::time::Duration = std::time::Duration::from_millis(700);
}

impl botbench::sim::Device for LateAnswers {
    fn receive(
        &mut self,
        bytes: &[u8],
        baud: u32,
        now: std::time::Instant,
    ) -> Vec<botbench::sim::Outgoing> {
        use std::sync::atomic::Ordering::SeqCst;
        let mut out = self.inner.lock().unwrap().receive(bytes, baud, now);
        if out.is_empty() {
            return out;
        }
        if self.late.load(SeqCst) > 0 {
            self.late.fetch_sub(1, SeqCst);
            out.iter_mut().for_each(|o| o.after += Self::DELAY);
        } else {
            self.on_time.fetch_add(1, SeqCst);
        }
        out
    }

    fn tick(&mut self, now: std::time::Instant) -> Vec<botbench::sim::Outgoing> {
        self.inner.lock().unwrap().tick(now)
    }
}

/// An Auto slot's unit whose answers to one idle poll came late (a starved device, a late host)
/// is the same unit still on the fixture, not a new one: it is not tested again. Seen at load
/// 14-19: units tested twice, the fixture taken for empty after one timed-out poll.
#[test]
fn a_unit_that_answers_one_idle_poll_late_is_not_tested_twice() {
    use std::sync::atomic::{AtomicU32, Ordering::SeqCst};
    let dir = tempfile::tempdir().unwrap();
    let sim = botbench::cli::simulated(["window-cleaner"]).unwrap();
    let late = Arc::new(AtomicU32::new(0));
    let on_time = Arc::new(AtomicU32::new(0));
    let device: botbench::sim::SharedDevice = Arc::new(Mutex::new(LateAnswers {
        inner: sim.device,
        late: late.clone(),
        on_time: on_time.clone(),
    }));
    let server = botbench::sim::PtyServer::start_lockstep(device, sim.faults).unwrap();
    let bundle_path = dir.path().join("station.ron");
    std::fs::write(
        &bundle_path,
        format!(
            r#"(version: 1, id: "late-poll",
                plans: {{ "wc": (start: Auto, steps: [Identify(hardware: [3])]) }},
                slots: [(name: "1", fixture: "WC", port: Path("{}"),
                         profile: "window-cleaner", plan: "wc")])"#,
            server.path()
        ),
    )
    .unwrap();
    let registry = botbench::profile::Registry::builtin().unwrap();
    let cx = LoadContext {
        registry: &registry,
        simulated: &[],
    };
    let bundle = station::load(&bundle_path, &cx).unwrap();
    let store = SqliteStore::open(&dir.path().join("records.sqlite")).unwrap();
    let recorder = Recorder::with_store(Box::new(store), RunContext::default(), None);
    let context = station::StationContext::new(&bundle, None, recorder);
    let (tx, rx) = crossbeam_channel::unbounded();
    let handle = station::spawn(
        bundle.slots[0].clone(),
        context,
        server.port_opener(),
        Box::new(OperatorHands),
        tx,
        false,
    )
    .unwrap();
    let verdict = next_event(&rx, |w| matches!(w, What::Verdict { .. }));
    assert!(
        matches!(verdict.what, What::Verdict { pass: true, .. }),
        "{verdict:?}"
    );
    next_event(&rx, |w| matches!(w, What::Waiting { .. }));
    // The next idle poll's two attempts are answered late; then the unit answers on time again,
    // poll after poll (CMD_VERSION and CMD_BUILD_INFO each).
    on_time.store(0, SeqCst);
    late.store(2, SeqCst);
    crate::support::wait_until(
        "two late answers and two idle polls answered after them",
        || late.load(SeqCst) == 0 && on_time.load(SeqCst) >= 4,
    );
    handle.cancel.cancel();
    let mut after = Vec::new();
    loop {
        let ev = next_event(&rx, |_| true);
        if matches!(ev.what, What::Stopped { .. }) {
            break;
        }
        after.push(ev.what);
    }
    crate::support::joined(handle.thread, "the slot's thread");
    assert!(
        !after.iter().any(|w| matches!(w, What::Unit { .. })),
        "the same unit was tested again after one late poll: {after:#?}"
    );
}
