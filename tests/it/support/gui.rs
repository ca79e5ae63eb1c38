//! The real app in an egui_kittest harness, connected to a simulator served in lockstep on a
//! pseudo-terminal ([`super::serve`]), stepped until a condition holds.

use super::{PATIENCE, Port};
use botbench::i18n::Lang;
use botbench::link::PortOpener;
use botbench::profile::{CommandKind, Value};
use botbench::ui::station::Reading;
use botbench::ui::{App, PanelId, Settings, Target};
use eframe::egui;
use egui_kittest::Harness;
use egui_kittest::kittest::{AccessKitNode, Queryable};
use std::collections::BTreeMap;
use std::time::{Duration, Instant};

/// The app in a harness.
pub type H = Harness<'static, Option<App>>;

/// Settings that open `path` at 115200 baud with `profile` on `panel`, with the protocol's own
/// answer margin.
pub fn settings(path: &str, profile: &str, panel: PanelId, lang: Lang) -> Settings {
    let mut saved = Settings {
        target: Target::Port(path.to_string()),
        profile: profile.into(),
        panel,
        lang,
        ..Settings::default()
    };
    saved.port_mut().baud = Some(115_200);
    // Runs are recorded in the tests' own file, never in the user's.
    saved.files.insert(
        botbench::ui::settings::FileKind::Records,
        records_file().display().to_string(),
    );
    saved
}

/// The records file the window's tests record their runs in.
pub fn records_file() -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("gui-records.sqlite")
}

/// The app on the window cleaner at `port`, showing `panel`, in English, with the protocol's own
/// answer margin or `margin_ms`.
pub fn on_window_cleaner(port: &impl Port, panel: PanelId, margin_ms: Option<u64>) -> H {
    let mut saved = settings(port.path(), "window-cleaner", panel, Lang::En);
    saved.port_mut().margin_ms = margin_ms;
    harness(saved, port.ports())
}

/// The app with `saved` settings, opening ports with `ports` (a test's simulator served in
/// lockstep: [`Port::ports`]), in a 1400×1000 window: each step runs its logic and draws it.
pub fn harness(saved: Settings, ports: PortOpener) -> H {
    harness_with(saved, ports, |_| {})
}

/// As [`harness`], with `prepare` run on the app once it has started.
pub fn harness_with(saved: Settings, ports: PortOpener, prepare: impl Fn(&mut App) + 'static) -> H {
    harness_sized(saved, ports, egui::vec2(1400.0, 1000.0), prepare)
}

/// As [`harness_with`], in a window of `size` points; records go to [`records_file`] unless
/// `saved` names another.
pub fn harness_sized(
    mut saved: Settings,
    ports: PortOpener,
    size: egui::Vec2,
    prepare: impl Fn(&mut App) + 'static,
) -> H {
    // Runs are recorded, and the Yield view reads, in the tests' own file, never this PC's
    // (where a technician's or another trial's records would change what a view shows).
    saved
        .files
        .entry(botbench::ui::settings::FileKind::Records)
        .or_insert_with(|| records_file().display().to_string());
    Harness::builder().with_size(size).build_ui_state(
        move |ui, app: &mut Option<App>| {
            let app = app.get_or_insert_with(|| {
                let mut app = App::new(ui.ctx(), saved.clone(), ports.clone()).expect("app starts");
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

/// Steps the UI until `done` holds; after [`PATIENCE`], fails naming `what`, with the link
/// state and the status line.
pub fn step_until(h: &mut H, what: &str, done: impl Fn(&App) -> bool) {
    step_until_or(h, what, done, |_| String::new());
}

/// As [`step_until`], and on failure also says what `diagnose` says of the app.
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
                a.station().link.state,
                a.station().notice.as_ref().map(|s| &s.text),
                diagnose(a)
            );
        }
        // The link and job threads do the work: give them the processor.
        std::thread::sleep(Duration::from_millis(2));
    }
}

fn is_text_input(n: &AccessKitNode<'_>) -> bool {
    n.role() == egui::accesskit::Role::TextInput
}

/// Replaces the text of the text field labelled `label` with `text`, as a user does: focus,
/// select all, type.
pub fn type_into(h: &mut H, label: &str, text: &str) {
    replace_text(h, |n| n.label().as_deref() == Some(label), text);
}

/// Replaces the text of the text field that now holds `current` with `text`.
pub fn edit_value(h: &mut H, current: &str, new: &str) {
    replace_text(h, |n| n.value().as_deref() == Some(current), new);
}

fn replace_text(h: &mut H, which: impl Fn(&AccessKitNode<'_>) -> bool, text: &str) {
    h.get_by(|n| is_text_input(n) && which(n)).focus();
    h.step();
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::A);
    h.step();
    h.get_by(|n| is_text_input(n) && which(n)).type_text(text);
    h.run_steps(2);
}

/// Whether some widget's label contains `text`.
pub fn has_label(h: &H, text: &str) -> bool {
    h.query_all_by_label_contains(text).next().is_some()
}

/// Whether no job runs.
pub fn idle(a: &App) -> bool {
    a.station().job_progress().is_none()
}

/// Each tuning value (every Get with a Set pair: what *Read all* reads), by command id, once
/// every one of them has been read, at `since` or later when given.
pub fn tuning_values(
    a: &App,
    since: Option<Instant>,
) -> Option<BTreeMap<u8, BTreeMap<String, Value>>> {
    let p = &a.station().device.profile;
    p.commands
        .iter()
        .filter(|c| c.kind == CommandKind::Get && c.pair.is_some())
        .map(|c| match a.station().device.readings.get(&c.id) {
            Some(Reading::Values(v, at)) if since.is_none_or(|t| *at >= t) => Some((
                c.id,
                v.iter().map(|(k, v)| (k.to_string(), v.clone())).collect(),
            )),
            _ => None,
        })
        .collect()
}

/// Waits until the read the app makes on connecting has brought every tuning value and ended.
pub fn read_on_connecting(h: &mut H) {
    step_until(h, "every tuning value read on connecting", |a| {
        a.station().connected() && tuning_values(a, None).is_some() && idle(a)
    });
}

/// Clicks *Read all* on the tuning panel (once the read on connecting has ended: the button
/// waits for a running job) and waits until every tuning value has been read again and the job
/// has ended; returns the values.
pub fn read_all(h: &mut H) -> BTreeMap<u8, BTreeMap<String, Value>> {
    read_on_connecting(h);
    let asked = Instant::now();
    h.get_by_label("Read all").click();
    step_until(h, "every tuning value read again", |a| {
        tuning_values(a, Some(asked)).is_some() && idle(a)
    });
    tuning_values(app(h), Some(asked)).expect("every value read")
}

/// The station window (`botbench station BUNDLE`) in a kittest harness of `size` pixels, with the
/// bundled CJK font, drawn as the window draws it (its logic, then its view).
pub fn line_station_harness(
    st: botbench::ui::line::LineStation,
    size: egui::Vec2,
) -> Harness<'static, botbench::ui::line::LineStation> {
    Harness::builder().with_size(size).build_ui_state(
        |ui, st: &mut botbench::ui::line::LineStation| {
            botbench::i18n::install_cjk_font(ui.ctx());
            st.logic(ui.ctx());
            st.ui(ui);
        },
        st,
    )
}
