//! One UI frame (logic + layout, headless through egui_kittest) on the telemetry panel with
//! 4 series × 10 min at 100 Hz, and the memory of an hour of 100 Hz telemetry.
//! Prints one JSON document a line. Run: `cargo bench -- ui_frame`.

use botbench::link::PortOpener;
use botbench::series::{DEFAULT_CAPACITY, SeriesSet};
use botbench::ui::{App, PanelId, Settings, Target};
use eframe::egui;
use egui_kittest::Harness;
use std::time::{Duration, Instant};

fn percentile(sorted: &[Duration], p: f64) -> f64 {
    let i = ((sorted.len() as f64 - 1.0) * p).round() as usize;
    sorted[i].as_secs_f64() * 1e3
}

/// Measures and prints; `quick` (under `cargo test`) draws 5 frames and simulates 72 s.
pub fn run(quick: bool) {
    let frames = if quick { 5 } else { 300 };

    let saved = Settings {
        // No device: the frame cost is drawing, not the link.
        target: Target::Port("/nonexistent/botbench-bench".into()),
        panel: PanelId::TELEMETRY,
        window_secs: 600.0,
        ..Settings::default()
    };
    let mut h = Harness::builder()
        .with_size(egui::vec2(1280.0, 800.0))
        .build_ui_state(
            move |ui, app: &mut Option<App>| {
                let app = app.get_or_insert_with(|| {
                    App::new(ui.ctx(), saved.clone(), PortOpener::system()).expect("app")
                });
                app.logic(ui.ctx());
                app.ui(ui);
            },
            None,
        );
    {
        let app = h.state_mut().as_mut().expect("app");
        let now = app.station().device.t0.elapsed().as_secs_f64();
        let n = DEFAULT_CAPACITY; // 10 min at 100 Hz
        let mut attitude = SeriesSet::new(DEFAULT_CAPACITY);
        let mut battery = SeriesSet::new(DEFAULT_CAPACITY);
        for i in 0..n {
            let t = now - 600.0 + i as f64 * 0.01;
            let _ = attitude.push("eulerX", t, (t * 1.3).sin() * 150.0);
            let _ = attitude.push("eulerY", t, (t * 0.7).cos() * 80.0);
            let _ = attitude.push("eulerZ", t, t * 0.5 % 360.0);
            let _ = battery.push("batteryVoltage", t, 14.8 - t * 1e-4);
        }
        app.station_mut()
            .device
            .plots
            .insert("attitude".into(), attitude);
        app.station_mut()
            .device
            .plots
            .insert("battery".into(), battery);
    }
    h.run_steps(3);
    let mut times = Vec::with_capacity(frames);
    for _ in 0..frames {
        let t = Instant::now();
        h.step();
        times.push(t.elapsed());
    }
    times.sort();
    println!(
        "{{\"name\":\"ui frame, telemetry panel, 4 series x 10 min at 100 Hz\",\"frames\":{frames},\"p50_ms\":{:.3},\"p95_ms\":{:.3},\"max_ms\":{:.3},\"target_p95_ms\":4.0}}",
        percentile(&times, 0.5),
        percentile(&times, 0.95),
        percentile(&times, 1.0)
    );

    // An hour of 100 Hz telemetry into the same bounded buffers: memory after 10 minutes and
    // after an hour.
    let mut set = SeriesSet::new(DEFAULT_CAPACITY);
    let names = ["eulerX", "eulerY", "eulerZ", "batteryVoltage"];
    let bytes = |s: &SeriesSet| s.iter().map(|(_, x)| x.allocated() * 16).sum::<usize>();
    let hours = if quick { 0.02 } else { 1.0 };
    let total = (hours * 3600.0 * 100.0) as usize;
    let mut at_10min = 0;
    for i in 0..total {
        let t = i as f64 * 0.01;
        for n in names {
            let _ = set.push(n, t, t.sin());
        }
        if i + 1 == 60_000 {
            at_10min = bytes(&set);
        }
    }
    println!(
        "{{\"name\":\"telemetry memory, 4 series at 100 Hz\",\"simulated_hours\":{hours},\"bytes_after_10_min\":{at_10min},\"bytes_at_end\":{},\"flat\":{}}}",
        bytes(&set),
        quick || at_10min == bytes(&set)
    );
}
