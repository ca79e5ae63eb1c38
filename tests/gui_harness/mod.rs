//! What the GUI tests share: the real app in an egui_kittest harness, connected to a simulator
//! served on a pseudo-terminal, stepped in real time until a condition holds.
#![allow(dead_code)] // each test binary uses its own part

use botbench::i18n::Lang;
use botbench::sim::{Device, Faults, PtyServer, SharedDevice};
use botbench::ui::{App, PanelId, Settings, Target};
use eframe::egui;
use egui_kittest::Harness;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The app in a harness.
pub type H = Harness<'static, Option<App>>;

/// How long a step_until may wait: generous, since a loaded CI machine is slow, and a condition
/// that holds returns at once.
const PATIENCE: Duration = Duration::from_secs(40);

/// A simulated device on a pseudo-terminal, and a handle to look inside it.
pub struct Served<D> {
    pub server: PtyServer,
    pub sim: Arc<Mutex<D>>,
}

impl<D> Served<D> {
    /// The path the app opens.
    pub fn path(&self) -> &str {
        self.server.path()
    }
}

/// Serves `device` with `faults`.
pub fn serve_with<D: Device + 'static>(device: D, faults: Faults) -> Served<D> {
    let sim = Arc::new(Mutex::new(device));
    let shared: SharedDevice = sim.clone();
    Served {
        server: PtyServer::start(shared, faults).expect("a pseudo-terminal"),
        sim,
    }
}

/// Serves `device` with no faults.
pub fn serve<D: Device + 'static>(device: D) -> Served<D> {
    serve_with(device, Faults::default())
}

/// Settings that open `path` at 115200 baud with `profile` on `panel`.
pub fn settings(path: &str, profile: &str, panel: PanelId, lang: Lang) -> Settings {
    let mut saved = Settings {
        target: Target::Port(path.to_string()),
        profile: profile.into(),
        panel,
        lang,
        ..Settings::default()
    };
    saved.port_mut().baud = Some(115_200);
    saved
}

/// The app with `saved` settings, in a 1400×1000 window: each step runs its logic and draws it.
pub fn harness(saved: Settings) -> H {
    harness_with(saved, |_| {})
}

/// As [`harness`], with `prepare` run on the app once it has started.
pub fn harness_with(saved: Settings, prepare: impl Fn(&mut App) + 'static) -> H {
    harness_sized(saved, egui::vec2(1400.0, 1000.0), prepare)
}

/// As [`harness_with`], in a window of `size` points.
pub fn harness_sized(saved: Settings, size: egui::Vec2, prepare: impl Fn(&mut App) + 'static) -> H {
    Harness::builder().with_size(size).build_ui_state(
        move |ui, app: &mut Option<App>| {
            let app = app.get_or_insert_with(|| {
                let mut app = App::new(ui.ctx(), saved.clone()).expect("app starts");
                prepare(&mut app);
                app
            });
            app.logic(ui.ctx());
            app.ui(ui);
        },
        None,
    )
}

/// The app.
pub fn app(h: &H) -> &App {
    h.state().as_ref().expect("app")
}

/// The app, to change.
pub fn app_mut(h: &mut H) -> &mut App {
    h.state_mut().as_mut().expect("app")
}

/// Steps the UI in real time until `done` holds; on timeout, panics naming `what`, with the
/// link state and the status line.
pub fn step_until(h: &mut H, what: &str, done: impl Fn(&App) -> bool) {
    step_until_or(h, what, done, |_| String::new());
}

/// As [`step_until`], and on timeout also says what `diagnose` says of the app.
pub fn step_until_or(
    h: &mut H,
    what: &str,
    done: impl Fn(&App) -> bool,
    diagnose: impl Fn(&App) -> String,
) {
    let deadline = Instant::now() + PATIENCE;
    loop {
        h.step();
        if h.state().as_ref().is_some_and(&done) {
            return;
        }
        if Instant::now() >= deadline {
            let a = app(h);
            panic!(
                "timed out waiting for {what}: link {:?}, status {:?}; {}",
                a.state.link.state,
                a.state.notice.as_ref().map(|s| &s.text),
                diagnose(a)
            );
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}
