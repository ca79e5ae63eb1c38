//! The window at the sizes the line PCs have (issue 14): at 1024 px and 1280 px the top bar, the
//! solar plots, the self-test's columns and the Tuya console's bit fields stay whole and in the
//! window.

use botbench::i18n::Lang;
use botbench::sim::SimOptions;
use botbench::ui::PanelId;
use botbench::ui::selftest::SelfTestPanel;
use botbench::ui::solar::SolarPanel;
use eframe::egui;
use egui_kittest::kittest::Queryable;

use crate::support::gui::{H, app, app_mut, settings, step_until};
use crate::support::{Port, serve, served_window_cleaner as bench};

fn sized(port: &impl Port, size: egui::Vec2, lang: Lang) -> H {
    let mut saved = settings(port.path(), "window-cleaner", PanelId::TUNING, lang);
    saved.port_mut().margin_ms = Some(100);
    crate::support::gui::harness_sized(saved, port.ports(), size, |_| {})
}

#[test]
fn the_top_bar_keeps_its_badge_whole_and_its_switch_in_place() {
    let b = bench();
    for (width, lang, answering, switch) in [
        (1200.0, Lang::En, "● device answering", "中文"),
        (1024.0, Lang::En, "● device answering", "中文"),
        (1024.0, Lang::Zh, "● 设备应答中", "English"),
    ] {
        let mut h = sized(&b, egui::vec2(width, 600.0), lang);
        h.run_steps(2);
        let before = h.get_by_label(switch).rect();
        step_until(&mut h, "answers", |a| {
            a.station().link.answering() == botbench::ui::station::Answering::Yes
        });
        h.run_steps(2);
        let badge = h.get_by_label(answering).rect();
        let line = h.get_by_label(switch).rect().height();
        assert!(
            badge.height() <= line + 1.0,
            "{width} {lang:?}: the badge is on one line ({badge:?})"
        );
        assert_eq!(
            h.get_by_label(switch).rect(),
            before,
            "{width} {lang:?}: the language switch stays put"
        );
        assert!(before.right() <= width);
        h.get_by_label(switch).click();
        h.run_steps(3);
        let other = if lang == Lang::En {
            "English"
        } else {
            "中文"
        };
        assert_eq!(
            h.get_by_label(other).rect().right(),
            before.right(),
            "{width}: switching language moves the switch not"
        );
    }
}

#[test]
fn the_solar_plots_take_the_whole_width() {
    let b =
        serve(botbench::sim::solar_cleanbot::SolarCleanbot::new(&SimOptions::default()).unwrap());
    let mut saved = settings(b.path(), "solar-cleanbot", PanelId::SOLAR, Lang::En);
    saved.port_mut().margin_ms = Some(100);
    let mut h =
        crate::support::gui::harness_sized(saved, b.ports(), egui::vec2(1280.0, 800.0), |_| {});
    step_until(&mut h, "the plots drawn", |a| {
        a.panel::<SolarPanel>().plot_width > 0.0
    });
    assert!(
        app(&h).panel::<SolarPanel>().plot_width > 1280.0 * 0.8,
        "{}",
        app(&h).panel::<SolarPanel>().plot_width
    );
}

#[test]
fn at_1024_px_the_self_tests_measured_and_result_columns_stay_in_the_window() {
    let b = bench();
    let mut saved = settings(b.path(), "window-cleaner", PanelId::SELF_TEST, Lang::En);
    saved.port_mut().margin_ms = Some(100);
    let mut h =
        crate::support::gui::harness_sized(saved, b.ports(), egui::vec2(1024.0, 600.0), |_| {});
    h.run_steps(3);
    h.get_by_label("Open plan").click();
    h.run_steps(2);
    let Some(plan) = app(&h).panel::<SelfTestPanel>().plan.clone() else {
        panic!(
            "the shipped plan opens: {:?}",
            app(&h).panel::<SelfTestPanel>().error
        )
    };
    // Every step measured, with a detail as long as a failing range check writes.
    app_mut(&mut h).panel_mut::<SelfTestPanel>().results = plan
        .steps
        .iter()
        .map(|s| botbench::ops::selftest::StepResult {
            name: s.name.clone(),
            kind: "Range".into(),
            pass: false,
            detail: "batteryVoltage 10.2 V below 11.5 V; current 0.00 A within 0.00 A to 2.50 A"
                .into(),
            measurements: Vec::new(),
            started_ms: 0,
            duration_ms: 0,
            interrupted: None,
        })
        .collect();
    h.run_steps(3);
    for header in ["Measured", "Result"] {
        let r = h.get_by_label(header).rect();
        assert!(r.right() <= 1024.0, "{header} at {r:?}");
    }
    let fails: Vec<egui::Rect> = h.query_all_by_label("FAIL").map(|n| n.rect()).collect();
    assert!(fails.len() >= plan.steps.len());
    assert!(fails.iter().all(|r| r.right() <= 1024.0), "{fails:?}");
}

#[test]
fn at_1024_px_a_bit_field_takes_its_rows_height_and_draws_over_no_other_row() {
    use egui_kittest::kittest::By;
    let b = serve(botbench::sim::tuya_mcu::TuyaMcu::new(
        botbench::sim::tuya_mcu::TuyaConfig {
            baud: Some(115_200),
            ..Default::default()
        },
    ));
    let mut saved = settings(b.path(), "tuya-vacuum", PanelId::TUYA_CONSOLE, Lang::En);
    saved.port_mut().baud = Some(115_200);
    let mut h =
        crate::support::gui::harness_sized(saved, b.ports(), egui::vec2(1024.0, 600.0), |_| {});
    crate::gui_tuya::handshake(&mut h);
    crate::gui_tuya::tab(&mut h, "Data points");
    step_until(&mut h, "DP 18 reported", |a| {
        crate::gui_tuya::reported(a, 18).is_some()
    });
    h.run_steps(3);
    let label = |h: &H, text: &str| {
        h.get(By::new().role(egui::accesskit::Role::Label).value(text))
            .rect()
    };
    let next_row = label(&h, "19 Map parameters").top();
    let profile = app(&h).station().device.profile.clone();
    let fault = profile.data_points.iter().find(|d| d.id == 18).unwrap();
    assert!(!fault.field.bits.is_empty());
    for bit in &fault.field.bits {
        let r = label(&h, &bit.name.en);
        assert!(
            r.bottom() <= next_row,
            "{} at {r:?}, DP 19 at {next_row}",
            bit.name.en
        );
    }
}

/// A text drawn in the last frame: its text, where, its rows, the glyphs it shows (less than
/// its text, ending in "…", where it was cut), and the rectangle it was clipped to.
struct Drawn {
    text: String,
    rect: egui::Rect,
    rows: usize,
    shown: String,
    clip: egui::Rect,
}

fn drawn_texts(h: &H) -> Vec<Drawn> {
    fn visit(clip: egui::Rect, shape: &egui::Shape, out: &mut Vec<Drawn>) {
        match shape {
            egui::Shape::Text(t) => out.push(Drawn {
                text: t.galley.text().to_string(),
                rect: t.galley.rect.translate(t.pos.to_vec2()),
                rows: t.galley.rows.len(),
                shown: t
                    .galley
                    .rows
                    .iter()
                    .flat_map(|r| r.row.glyphs.iter().map(|g| g.chr))
                    .collect(),
                clip,
            }),
            egui::Shape::Vec(v) => v.iter().for_each(|s| visit(clip, s, out)),
            _ => {}
        }
    }
    let mut out = Vec::new();
    for c in &h.output().shapes {
        visit(c.clip_rect, &c.shape, &mut out);
    }
    out
}

/// What is wrong with `d` as a text that must be whole in a window of `size`: cut, clipped,
/// past the window, or over two rows.
fn not_whole(d: &Drawn, size: egui::Vec2) -> Option<String> {
    let window = egui::Rect::from_min_size(egui::Pos2::ZERO, size).expand(0.5);
    let shown: String = d.shown.chars().filter(|c| !c.is_whitespace()).collect();
    let text: String = d.text.chars().filter(|c| !c.is_whitespace()).collect();
    if d.rows != 1 {
        Some(format!("{:?} on {} rows", d.text, d.rows))
    } else if shown != text {
        Some(format!("{:?} cut to {:?}", d.text, d.shown))
    } else if !window.contains_rect(d.rect) {
        Some(format!("{:?} at {:?}, past the window", d.text, d.rect))
    } else if !d.clip.expand(0.5).contains_rect(d.rect) {
        Some(format!(
            "{:?} at {:?} clipped to {:?}",
            d.text, d.rect, d.clip
        ))
    } else {
        None
    }
}

#[test]
fn at_scale_2_on_a_1280x800_screen_stop_and_the_status_line_stay_whole() {
    // 1280×800 pixels at 2 pixels a point: a window of 640×400 points (the harness takes the
    // screen's size in pixels once its scale is set).
    let size = egui::vec2(640.0, 400.0);
    let screen = egui::vec2(1280.0, 800.0);
    let b = bench();
    for lang in Lang::ALL {
        let mut saved = settings(b.path(), "window-cleaner", PanelId::TUNING, lang);
        saved.port_mut().margin_ms = Some(100);
        let mut h = crate::support::gui::harness_sized(saved, b.ports(), screen, |_| {});
        h.set_pixels_per_point(2.0);
        h.run_steps(2);
        let area = h.ctx.content_rect().size();
        assert_eq!(area, size, "the window in points");
        // The read made on connecting has ended too: its notice ("Read: 9 read") would change
        // the status line after the frame drew it (seen on a loaded machine).
        step_until(&mut h, "the device identified and its tuning read", |a| {
            a.station().link.answering() == botbench::ui::station::Answering::Yes
                && matches!(a.station().device.info, Some(Ok(_)))
                && a.station().notice.is_some()
                && crate::support::gui::tuning_values(a, None).is_some()
                && crate::support::gui::idle(a)
        });
        h.run_steps(3);
        // A frame can draw the status line before it takes an event that changes it (a job's
        // end: "Read: 9 read"; a round trip's new figure), and the bottom panel takes its new
        // height a frame after its row wrapped (the message then outside it, not drawn): seen
        // three times on a loaded machine. Step until a frame draws everything whole, bounded
        // by PATIENCE: a line that is never whole still fails.
        let deadline = std::time::Instant::now() + crate::support::PATIENCE;
        let mut bad = not_whole_at_scale_2(&h, lang, size);
        while !bad.is_empty() && std::time::Instant::now() < deadline {
            h.step();
            bad = not_whole_at_scale_2(&h, lang, size);
        }
        assert!(
            bad.is_empty(),
            "{lang:?} at 640×400 points, scale 2: {bad:#?}"
        );
    }
}

/// What is not whole in the frame `h` drew last, at scale 2 in a window of `size` points:
/// STOP, and each part of the status line (the port, the notice, the counters). Empty: all
/// whole.
fn not_whole_at_scale_2(h: &H, lang: Lang, size: egui::Vec2) -> Vec<String> {
    let mut bad = Vec::new();
    let texts = drawn_texts(h);
    // STOP: the button whole in the window, its word whole on it.
    let stop_word = lang.tr("STOP", "停止");
    let stop = h.get_by_label(stop_word).rect();
    if !egui::Rect::from_min_size(egui::Pos2::ZERO, size)
        .expand(0.5)
        .contains_rect(stop)
    {
        bad.push(format!("STOP at {stop:?}, past the window"));
    }
    match texts.iter().find(|d| d.text == stop_word) {
        Some(d) => bad.extend(not_whole(d, size)),
        None => bad.push("STOP's word is not drawn".into()),
    }
    // The status line: each of its parts drawn, whole.
    let a = app(h);
    let mut parts = vec![
        a.station().link.target().unwrap().label_in(lang),
        a.station()
            .notice
            .as_ref()
            .unwrap()
            .text_in(lang)
            .to_string(),
    ];
    for counter in [
        lang.tr("no answer", "无应答"),
        lang.tr("frame errors", "帧错误"),
    ] {
        let found = texts.iter().find(|d| d.text.starts_with(counter));
        parts.push(found.map_or(counter.to_string(), |d| d.text.clone()));
    }
    for part in parts {
        match texts.iter().find(|d| d.text == part) {
            Some(d) => bad.extend(not_whole(d, size)),
            None => bad.push(format!("{part:?} is not drawn")),
        }
    }
    bad
}

/// A long reason in the provisioning history (a pulled adapter's, as the link words it) once
/// made its column as wide as itself: the reason ran out of the window, and the column after
/// it, the values the servo does not hold, with it.
#[test]
fn at_1024_px_the_provisioning_history_keeps_its_columns_in_view_and_wraps_a_long_reason() {
    use botbench::ops::servo::provision::{Outcome, Record};
    use botbench::sim::servo_bus::SimServo;
    use botbench::ui::servo_bench::ServoBenchPanel;
    let b = crate::support::servo_bench::bench(vec![SimServo::fresh(4101)]);
    let saved = settings(b.path(), "servo", PanelId::SERVO_BENCH, Lang::En);
    let mut h =
        crate::support::gui::harness_sized(saved, b.ports(), egui::vec2(1024.0, 600.0), |_| {});
    step_until(&mut h, "the link", |a| a.station().connected());
    h.get_by_label("Production").click();
    h.step();
    let lost = "port lost: port disconnected: /dev/ttyUSB0: Input/output error (os error 5) — \
                /dev/ttyUSB0 is gone: unplugged (no USB serial port is listed now); plug it in again";
    let record = |result: Outcome, mismatches: Vec<String>| Record {
        time: "2026-12-07T09:21:47+00:00".into(),
        serial: Some(1001),
        id: Some(1),
        baud: None,
        result,
        mismatches,
        recorded: Vec::new(),
        timeline: Vec::new(),
        writes: Vec::new(),
    };
    let production = &mut app_mut(&mut h).panel_mut::<ServoBenchPanel>().production;
    production.history = vec![
        record(
            Outcome::Fail {
                step: "verify".into(),
                reason: "2 value(s) not as written".into(),
            },
            vec![
                "max_temperature: wrote 70, servo holds 80".into(),
                "min_voltage: wrote 6000, servo holds 4500".into(),
            ],
        ),
        record(
            Outcome::LinkLost {
                step: "set baud".into(),
                reason: lost.into(),
            },
            Vec::new(),
        ),
    ];
    production.dismissed = true;
    h.run_steps(3);
    for text in [
        "Result",
        "Details",
        lost,
        "2 value(s) not as written · not as written: max_temperature: wrote 70, servo holds 80; \
         min_voltage: wrote 6000, servo holds 4500",
    ] {
        let r = h.get_by_label(text).rect();
        assert!(r.right() <= 1024.0, "{text:?} at {r:?}");
    }
}
