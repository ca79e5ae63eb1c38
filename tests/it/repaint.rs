//! The window's repaint policy (issue 14, cost): a plot of streaming telemetry redraws at the
//! live rate however fast the data comes, never at once on every sample; a window with nothing
//! live asks for no frame at all. (What that costs is measured by `.ci/window_cpu.sh`, not here.)

use botbench::i18n::Lang;
use botbench::ui::repaint::LIVE;
use botbench::ui::{Action, App, PanelId};
use eframe::egui;
use std::time::Duration;

use crate::support::gui::{H, app, app_mut, harness, harness_sized, settings, step_until};
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

/// The area of triangle `tri` inside `clip` (a polygon clipped edge by edge, then its area).
fn clipped_area(tri: [egui::Pos2; 3], clip: egui::Rect) -> f64 {
    let mut poly: Vec<[f64; 2]> = tri
        .iter()
        .map(|p| [f64::from(p.x), f64::from(p.y)])
        .collect();
    let (x0, y0) = (f64::from(clip.min.x), f64::from(clip.min.y));
    let (x1, y1) = (f64::from(clip.max.x), f64::from(clip.max.y));
    // Each edge of the clip: which coordinate, the bound, and whether inside is above it.
    for (axis, bound, above) in [(0, x0, true), (0, x1, false), (1, y0, true), (1, y1, false)] {
        let inside = |p: &[f64; 2]| {
            if above {
                p[axis] >= bound
            } else {
                p[axis] <= bound
            }
        };
        let mut out = Vec::with_capacity(poly.len() + 2);
        for (i, a) in poly.iter().enumerate() {
            let b = &poly[(i + 1) % poly.len()];
            if inside(a) {
                out.push(*a);
            }
            if inside(a) != inside(b) {
                let f = (bound - a[axis]) / (b[axis] - a[axis]);
                out.push([a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])]);
            }
        }
        poly = out;
        if poly.is_empty() {
            return 0.0;
        }
    }
    let twice: f64 = (0..poly.len())
        .map(|i| {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum();
    twice.abs() / 2.0
}

/// The pixels the last frame shaded, in window areas (1.0: as many as the window has): every
/// triangle egui tessellated from the frame's shapes, cut to its clip rectangle as the GPU's
/// scissor cuts it, summed. The GL clear before a frame is not in it: it fills memory without
/// shading (see `botbench::ui::backdrop`). Nor is the frame egui_kittest draws around the app
/// (a central panel's fill 8 points inside the harness, which the real window has not): the
/// frame's first shape, checked to be that.
fn shaded(h: &H) -> f64 {
    let ppp = h.ctx.pixels_per_point();
    let screen = h.ctx.content_rect();
    let mut shapes = h.output().shapes.clone();
    let first = shapes.remove(0);
    assert!(
        matches!(&first.shape, egui::Shape::Rect(r) if r.rect == screen.shrink(8.0)),
        "the frame's first shape is not egui_kittest's frame: {:?}",
        first.shape
    );
    let mut area = 0.0;
    for p in &h.ctx.tessellate(shapes, ppp) {
        let egui::epaint::Primitive::Mesh(mesh) = &p.primitive else {
            continue;
        };
        let clip = p.clip_rect.intersect(screen);
        for t in mesh.indices.chunks_exact(3) {
            let tri = [t[0], t[1], t[2]].map(|i| mesh.vertices[i as usize].pos);
            area += clipped_area(tri, clip);
        }
    }
    area / f64::from(screen.area())
}

/// Under software rendering a frame costs the pixels it shades (botbench::ui::backdrop): the
/// telemetry view streaming at 50 Hz, at the window's first size, shades fewer pixels than the
/// window has (its panels painted their fills over the clear: 1.8 window areas a frame).
#[test]
fn the_streaming_telemetry_view_shades_each_pixel_of_the_window_less_than_once_a_frame() {
    let b = serve(window_cleaner());
    let mut saved = settings(b.path(), "window-cleaner", PanelId::TELEMETRY, Lang::En);
    saved.poll_hz = Some(50.0);
    let mut h = harness_sized(saved, b.ports(), egui::vec2(1200.0, 780.0), |_| {});
    step_until(&mut h, "telemetry points", streaming);
    h.step();
    let shaded = shaded(&h);
    assert!(
        shaded < 1.0,
        "a frame of the telemetry view shaded {shaded:.2} window areas"
    );
}
