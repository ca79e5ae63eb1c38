//! What the integration tests share: simulators served on pseudo-terminals, links to them, waits
//! on conditions, temporary folders, the command line run as a user runs it ([`cli`]), the app in
//! an egui_kittest harness ([`gui`]) and the servo bench ([`servo`]).
//!
//! Tests run on parallel threads of one process: nothing here sets process-wide state, and every
//! wait is on a condition, with [`PATIENCE`] only as the point where a test gives up.
#![allow(dead_code)] // not every helper is used by every module

pub mod cli;
pub mod gui;
pub mod held_up;
pub mod servo;
pub mod servo_bench;

use botbench::link::{Link, LinkEvent, LinkOptions, Opener, PortOpener};
use botbench::profile::{Profile, Registry};
use botbench::sim::window_cleaner::WindowCleaner;
use botbench::sim::{Device, Faults, PtyServer, SharedDevice, SimOptions};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// How long a wait on a condition may take before the test fails: far beyond what a loaded
/// machine needs, since a condition that holds ends the wait at once. A bound against a hang,
/// never a speed check. Measured: on this 2-core machine at load 11-28 (the suite's eight
/// threads, or two CPU-bound loops beside it), an exchange in lockstep takes tens of
/// milliseconds (the host's and the simulator's threads each wait to be scheduled), so one servo
/// provisioning, whose id check pings all 254 ids, took over 40 s, and a station test's second
/// unit missed a 60 s bound (`station_headless::an_auto_slot_starts_when_the_simulator_presents_
/// the_next_unit_after_a_silence`, 5 of 6 copies run at once beside two CPU loops).
pub const PATIENCE: Duration = Duration::from_secs(180);

/// A built-in profile.
pub fn profile(name: &str) -> Arc<Profile> {
    Registry::builtin()
        .expect("the built-in profiles load")
        .get(name)
        .unwrap_or_else(|e| panic!("{e}"))
}

/// The text of a built-in profile.
pub fn builtin_src(name: &str) -> &'static str {
    botbench::profile::registry::BUILTIN
        .iter()
        .find(|(n, _)| *n == name)
        .unwrap_or_else(|| panic!("no built-in profile {name}"))
        .1
}

/// The 1-based line and column of the `nth` occurrence of `needle` in `src`.
pub fn line_col_of(src: &str, needle: &str, nth: usize) -> (usize, usize) {
    let pos = src.match_indices(needle).nth(nth).expect("needle").0;
    botbench::document::line_col(src, pos)
}

/// The 1-based line of the `nth` occurrence of `needle` in `src`.
pub fn line_of(src: &str, needle: &str, nth: usize) -> usize {
    line_col_of(src, needle, nth).0
}

/// Field values as a person types them: (field name, text) pairs.
pub fn inputs(pairs: &[(&str, &str)]) -> Vec<(String, botbench::profile::Input)> {
    pairs
        .iter()
        .map(|(k, v)| (k.to_string(), botbench::profile::Input::from(*v)))
        .collect()
}

/// The MSP and Tuya checksum worked out independently of the crate: the byte sum mod 256.
pub fn sum_mod_256(bytes: &[u8]) -> u8 {
    (bytes.iter().map(|&b| u32::from(b)).sum::<u32>() % 256) as u8
}

/// `n` milliseconds.
pub fn ms(n: u64) -> Duration {
    Duration::from_millis(n)
}

/// A fresh temporary folder, removed when dropped.
pub fn temp_dir() -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix("botbench-test-")
        .tempdir()
        .expect("a temporary folder")
}

/// The window cleaner as it leaves the factory.
pub fn window_cleaner() -> WindowCleaner {
    WindowCleaner::new(&SimOptions::default()).expect("the window cleaner builds")
}

/// The faults of a lossy line: 1 % of frames dropped and 1 % corrupted, drawn from `seed`.
pub fn lossy(seed: u64) -> Faults {
    Faults {
        drop: 0.01,
        corrupt: 0.01,
        seed,
        ..Faults::default()
    }
}

/// The window cleaner as it leaves the factory, served in lockstep ([`serve`]).
pub fn served_window_cleaner() -> Served<WindowCleaner> {
    serve(window_cleaner())
}

/// A simulated device served on a pseudo-terminal, and a handle to look inside it.
pub struct Served<D> {
    /// The server; `vanish` it to unplug the port.
    pub server: PtyServer,
    /// The device, to inspect and change.
    pub sim: Arc<Mutex<D>>,
}

/// A simulated device on a pseudo-terminal, as a test hands it to a link, the window or the
/// command line: its path, and the opener that reaches it (in lockstep when it is served so).
pub trait Port {
    /// The pty's path.
    fn path(&self) -> &str;
    /// The opener of the pty at `baud`.
    fn opener(&self, baud: u32) -> Opener;
    /// The system's ports, with this pty opened by [`Port::opener`]: what the window and the
    /// command line are handed.
    fn ports(&self) -> PortOpener;
}

impl Port for PtyServer {
    fn path(&self) -> &str {
        PtyServer::path(self)
    }

    fn opener(&self, baud: u32) -> Opener {
        PtyServer::opener(self, baud)
    }

    fn ports(&self) -> PortOpener {
        self.port_opener()
    }
}

impl<D> Port for Served<D> {
    fn path(&self) -> &str {
        self.server.path()
    }

    fn opener(&self, baud: u32) -> Opener {
        self.server.opener(baud)
    }

    fn ports(&self) -> PortOpener {
        self.server.port_opener()
    }
}

impl<D> Served<D> {
    /// The path a client opens.
    pub fn path(&self) -> &str {
        self.server.path()
    }

    /// The system's ports, with this device's pty served in lockstep ([`Port::ports`]).
    pub fn ports(&self) -> PortOpener {
        self.server.port_opener()
    }

    /// The device, locked.
    pub fn sim(&self) -> MutexGuard<'_, D> {
        self.sim.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// Serves `device` with `faults`, in lockstep with the links this process opens on it (see
/// `botbench::sim::lockstep`): what the device hears and answers does not depend on how fast the
/// test's threads are scheduled.
pub fn serve_with<D: Device + 'static>(device: D, faults: Faults) -> Served<D> {
    served_by(PtyServer::start_lockstep, device, faults)
}

/// Serves `device` with no faults, in lockstep (see [`serve_with`]).
pub fn serve<D: Device + 'static>(device: D) -> Served<D> {
    serve_with(device, Faults::default())
}

/// Serves `device` on a plain pseudo-terminal, for a client in another process or one that opens
/// the port itself.
pub fn serve_plain<D: Device + 'static>(device: D, faults: Faults) -> Served<D> {
    served_by(PtyServer::start, device, faults)
}

fn served_by<D: Device + 'static>(
    start: fn(SharedDevice, Faults) -> Result<PtyServer, botbench::link::LinkError>,
    device: D,
    faults: Faults,
) -> Served<D> {
    let sim = Arc::new(Mutex::new(device));
    Served {
        server: start(sim.clone(), faults).expect("a pseudo-terminal"),
        sim,
    }
}

/// A firmware image of `len` random bytes, the same for the same length.
pub fn image(len: usize) -> Vec<u8> {
    let mut rng = fastrand::Rng::with_seed(len as u64);
    (0..len).map(|_| rng.u8(..)).collect()
}

/// A link to `port` at `baud` with `profile`.
pub fn open_link(port: &impl Port, baud: u32, profile: Arc<Profile>, options: LinkOptions) -> Link {
    Link::open(port.opener(baud), profile, options, None).expect("opens the port")
}

/// Waits for the first event of `link` that `pick` accepts, dropping the others; fails naming
/// `what` after [`PATIENCE`].
pub fn next_event<T>(link: &Link, what: &str, mut pick: impl FnMut(LinkEvent) -> Option<T>) -> T {
    let deadline = Instant::now() + PATIENCE;
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        match link.events().recv_timeout(left) {
            Ok(ev) => {
                if let Some(t) = pick(ev) {
                    return t;
                }
            }
            Err(e) => panic!("no {what}: {e}"),
        }
    }
}

/// A link to the MSP device at `path` at 115200 baud, once its session has learned the device
/// code.
pub fn connect(port: &impl Port, profile: &Arc<Profile>) -> Link {
    let link = open_link(port, 115_200, profile.clone(), LinkOptions::default());
    identified(&link);
    link
}

/// Waits until the link's session has identified the device (MSP: CMD_VERSION answered).
pub fn identified(link: &Link) {
    next_event(link, "identification", |ev| match ev {
        LinkEvent::Identified(r) => Some(r.expect("CMD_VERSION answered")),
        _ => None,
    });
}

/// Waits until `done` holds, looking every millisecond; fails naming `what` after [`PATIENCE`].
pub fn wait_until(what: &str, mut done: impl FnMut() -> bool) {
    let deadline = Instant::now() + PATIENCE;
    while !done() {
        assert!(Instant::now() < deadline, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// The result of the thread `handle` (`what`, for the failure), once it has ended; fails after
/// [`PATIENCE`] rather than hang, and passes its panic on.
pub fn joined<T>(handle: std::thread::JoinHandle<T>, what: &str) -> T {
    wait_until(what, || handle.is_finished());
    match handle.join() {
        Ok(t) => t,
        Err(panic) => std::panic::resume_unwind(panic),
    }
}

/// The example self-test plan (`presets/window-cleaner-selftest.ron`).
pub const SELFTEST_PLAN: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/presets/window-cleaner-selftest.ron"
);

/// The example self-test plan with test timings: reads 1 ms apart instead of 20, settle times cut
/// to what the simulated currents need to rise well past the plan's minimum (the wheels follow
/// their motor with a 0.25 s time constant, the fan with 0.4 s), and the corner step's 20 s cut
/// to `corner_timeout_ms` (a step that must fail waits it out; one that must pass ends as soon
/// as the corners are seen).
pub fn selftest_plan(corner_timeout_ms: u64) -> String {
    let text = std::fs::read_to_string(SELFTEST_PLAN).expect("the example plan");
    let timings = [
        ("samples: 10,", "samples: 10,\n            interval_ms: 1,"),
        ("samples: 5,", "samples: 5,\n            interval_ms: 1,"),
        ("settle_ms: 600,", "settle_ms: 300,"),
        ("settle_ms: 800,", "settle_ms: 400,"),
        (
            "timeout_ms: 20000,",
            &format!("timeout_ms: {corner_timeout_ms},"),
        ),
    ];
    timings.iter().fold(text, |text, (from, to)| {
        assert!(text.contains(from), "the example plan has no {from}");
        text.replace(from, to)
    })
}

/// The demo bundle (three simulated slots), loaded.
pub fn demo_bundle() -> botbench::ops::station::Bundle {
    let registry = botbench::profile::Registry::builtin().unwrap();
    let sims = botbench::sim::SimKind::names_with_profiles();
    let cx = botbench::ops::station::LoadContext {
        registry: &registry,
        simulated: &sims,
    };
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("presets/demo-station.ron");
    botbench::ops::station::load(&path, &cx).unwrap()
}
