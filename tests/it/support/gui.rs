//! The real app in an egui_kittest harness, connected to a simulator served in lockstep on a
//! pseudo-terminal ([`super::serve`]), stepped until a condition holds.

use super::PATIENCE;
use botbench::i18n::Lang;
use botbench::ui::{App, PanelId, Settings, Target};
use eframe::egui;
use egui_kittest::Harness;
use egui_kittest::kittest::{AccessKitNode, Queryable};
use std::time::{Duration, Instant};

/// The app in a harness.
pub type H = Harness<'static, Option<App>>;

/// Settings that open `path` at 115200 baud with `profile` on `panel`, with the protocol's own
/// answer margin.
pub fn settings(path: &str, profile: &str, panel: PanelId, lang: Lang) -> Settings {
    Settings {
        target: Target::Port(path.to_string()),
        baud: 115_200,
        profile: profile.into(),
        panel,
        lang,
        ..Settings::default()
    }
}

/// The app with `saved` settings, in a 1400×1000 window: each step runs its logic and draws it.
pub fn harness(saved: Settings) -> H {
    harness_with(saved, |_| {})
}

/// As [`harness`], with `prepare` run on the app once it has started.
pub fn harness_with(saved: Settings, prepare: impl Fn(&mut App) + 'static) -> H {
    Harness::builder()
        .with_size(egui::vec2(1400.0, 1000.0))
        .build_ui_state(
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
                a.state.link.state,
                a.state.notice.as_ref().map(|s| &s.text),
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
