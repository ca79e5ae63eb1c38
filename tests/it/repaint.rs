//! The window's repaint policy (issue 14, cost): a plot of streaming telemetry redraws at the
//! live rate however fast the data comes, never at once on every sample; a window with nothing
//! live asks for no frame at all. (What that costs is measured by `.ci/window_cpu.sh`, not here.)

use botbench::i18n::Lang;
use botbench::ui::repaint::LIVE;
use botbench::ui::{Action, App, PanelId};
use eframe::egui;
use std::time::Duration;

use crate::support::gui::{H, app, app_mut, harness, settings, step_until};
use crate::support::{serve, window_cleaner};

/// How soon the last frame asked for the next one (`Duration::MAX`: never).
fn requested_delay(h: &H) -> Duration {
    h.output()
        .viewport_output
        .get(&egui::ViewportId::ROOT)
        .map_or(Duration::MAX, |v| v.repaint_delay)
}

/// Steps until a frame's requested delay satisfies `done` (which may also assert on it).
fn step_until_asked(h: &mut H, what: &str, done: impl Fn(Duration) -> bool) {
    for _ in 0..1000 {
        h.step();
        if done(requested_delay(h)) {
            return;
        }
    }
    panic!(
        "no frame in 1000: {what} (last asked {:?})",
        requested_delay(h)
    );
}

fn streaming(a: &App) -> bool {
    a.station().connected()
        && a.station()
            .device
            .plots
            .get("attitude")
            .and_then(|s| s.get("eulerX"))
            .is_some_and(|s| s.len() > 20)
}

#[test]
fn a_streaming_plot_redraws_at_the_live_rate_not_on_every_sample() {
    // No faster than the eye needs: at most 15 frames a second.
    assert!(LIVE >= Duration::from_millis(66), "live rate {LIVE:?}");
    let b = serve(window_cleaner());
    let mut saved = settings(b.path(), "window-cleaner", PanelId::TELEMETRY, Lang::En);
    saved.poll_hz = Some(50.0);
    let mut h = harness(saved, b.ports());
    step_until(&mut h, "telemetry points", streaming);
    assert_eq!(app(&h).repaint_after(), Some(LIVE));
    // The frame itself asks for exactly that (a frame that also drains a backlog of worker
    // events may ask for the next at once; one that is up to date asks for LIVE).
    step_until_asked(
        &mut h,
        "a frame asking for the next after the live period",
        |d| {
            assert!(
                d == Duration::ZERO || d == LIVE,
                "a streaming frame asked for the next after {d:?}, not {LIVE:?}"
            );
            d == LIVE
        },
    );

    // Paused, the plot does not move: nothing redraws on its own.
    app_mut(&mut h).apply(Action::PausePolling(true));
    assert_eq!(app(&h).repaint_after(), None, "paused");
    app_mut(&mut h).apply(Action::PausePolling(false));
    // Another panel while telemetry is polled behind it: only the worker's background wake.
    app_mut(&mut h).apply(Action::ShowPanel(PanelId::TUNING));
    assert_eq!(app(&h).repaint_after(), None, "tuning panel");
    // The packet monitor is live while frames are logged, and not once its log is paused.
    app_mut(&mut h).apply(Action::ShowPanel(PanelId::MONITOR));
    assert_eq!(app(&h).repaint_after(), Some(LIVE), "monitor");
    app_mut(&mut h).apply(Action::PausePacketLog(true));
    assert_eq!(app(&h).repaint_after(), None, "monitor paused");
}

#[test]
fn a_disconnected_window_asks_for_no_frame() {
    let b = serve(window_cleaner());
    let saved = settings(b.path(), "window-cleaner", PanelId::TELEMETRY, Lang::En);
    let mut h = harness(saved, b.ports());
    step_until(&mut h, "telemetry points", streaming);
    app_mut(&mut h).apply(Action::Disconnect);
    assert_eq!(app(&h).repaint_after(), None);
    // Frames still come while egui settles the new layout and the closed link's last wake
    // arrives; then none is asked for, and none again.
    step_until_asked(&mut h, "a frame that asks for no next one", |d| {
        d == Duration::MAX
    });
    for _ in 0..5 {
        h.step();
        assert_eq!(
            requested_delay(&h),
            Duration::MAX,
            "an idle, disconnected window asked for a frame"
        );
    }
}
