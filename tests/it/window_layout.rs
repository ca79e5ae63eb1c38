//! The window at 1024×600 (and 800×500, its least), as a technician reads it: in every view of
//! the four demo devices no label parts a word over two lines (in Chinese, where any two
//! characters may be parted, nor in English), no text is drawn over another, and no label sits
//! on another row than the box it names; the navigation and the status line stay one line
//! each; no control lies past the window's edge; the telemetry plots keep their height and
//! scroll into view; range hints are whole; a panel keeps its own scroll place.

use botbench::i18n::Lang;
use botbench::link::PortOpener;
use botbench::sim::SimKind;
use botbench::ui::layout::{one_line, overlapping_texts, split_words};
use botbench::ui::presets::PresetsPanel;
use botbench::ui::selftest::SelfTestPanel;
use botbench::ui::servo_bench::ServoBenchPanel;
use botbench::ui::station::Answering;
use botbench::ui::telemetry::TelemetryPanel;
use botbench::ui::{App, PanelId, Settings, Target};
use eframe::egui;
use egui_kittest::Harness;
use egui_kittest::kittest::{By, NodeT, Queryable};

use crate::support::gui::{H, app, app_mut, harness_sized, step_until};

const SMALL: egui::Vec2 = egui::vec2(1024.0, 600.0);
/// The window's least size (`ui::run`'s `min_inner_size`).
const LEAST: egui::Vec2 = egui::vec2(800.0, 500.0);

/// Every text the last frame drew: its text, where, and how many rows it took.
pub(crate) fn texts(h: &H) -> Vec<(String, egui::Rect, usize)> {
    fn visit(shape: &egui::Shape, out: &mut Vec<(String, egui::Rect, usize)>) {
        match shape {
            egui::Shape::Text(t) => out.push((
                t.galley.text().to_string(),
                t.galley.rect.translate(t.pos.to_vec2()),
                t.galley.rows.len(),
            )),
            egui::Shape::Vec(v) => v.iter().for_each(|s| visit(s, out)),
            _ => {}
        }
    }
    let mut out = Vec::new();
    for c in &h.output().shapes {
        visit(&c.shape, &mut out);
    }
    out
}

/// What the glyphs of the text `text` show in the last frame (less than `text`, ending in
/// "…", where it was cut), if it was drawn.
fn shown_of(h: &H, text: &str) -> Option<String> {
    h.output().shapes.iter().find_map(|c| match &c.shape {
        egui::Shape::Text(t) if t.galley.text() == text => Some(
            t.galley
                .rows
                .iter()
                .flat_map(|r| r.row.glyphs.iter().map(|g| g.chr))
                .collect(),
        ),
        _ => None,
    })
}

/// Labels drawn on another row than the widget they name (a label at the end of one row, its
/// box at the start of the next): `label → widget` for each.
fn parted_labels(h: &H) -> Vec<String> {
    let mut parted = Vec::new();
    for node in h.root().children_recursive() {
        let widget = node.accesskit_node();
        for label in widget.labelled_by() {
            let (Some(w), Some(l)) = (widget.bounding_box(), label.bounding_box()) else {
                continue;
            };
            if w.y1 <= l.y0 || l.y1 <= w.y0 {
                parted.push(format!(
                    "{:?} → {:?}",
                    label.label().or_else(|| label.value()).unwrap_or_default(),
                    widget.role()
                ));
            }
        }
    }
    parted
}

#[test]
fn the_check_finds_a_label_split_over_two_lines_and_a_one_line_label_passes() {
    let mut h = Harness::builder()
        .with_size(egui::vec2(200.0, 200.0))
        .build_ui(|ui| {
            botbench::i18n::install_cjk_font(ui.ctx());
            ui.set_max_width(50.0);
            ui.label("光伏清扫机器人");
            ui.label("Configuration");
        });
    h.run_steps(2);
    let split = split_words(&h.output().shapes);
    assert_eq!(split, ["光伏清扫机器人", "Configuration"], "{split:?}");

    let mut h = Harness::builder()
        .with_size(egui::vec2(200.0, 200.0))
        .build_ui(|ui| {
            botbench::i18n::install_cjk_font(ui.ctx());
            ui.set_max_width(50.0);
            one_line(ui, "光伏清扫机器人");
            // A sentence may wrap between any two characters.
            ui.label("失能保护开启时,若在间隔内无人确认,发送停止。");
        });
    h.run_steps(2);
    assert!(split_words(&h.output().shapes).is_empty());
}

/// The app on the built-in demo `kind` at `size` in `lang`, stepped until the device answers
/// and is identified (so that the navigation lists its panels).
pub(crate) fn demo(kind: SimKind, lang: Lang, size: egui::Vec2) -> H {
    let mut saved = Settings {
        target: Target::Demo(kind.name().to_string()),
        profile: kind.profile_id().to_string(),
        panel: PanelId::MONITOR,
        lang,
        ..Settings::default()
    };
    saved.port_mut().baud = Some(kind.default_baud());
    let mut h = harness_sized(saved, PortOpener::system(), size, |_| {});
    step_until(&mut h, "the device to answer", move |a| ready(kind, a));
    h
}

fn ready(kind: SimKind, a: &App) -> bool {
    match kind {
        SimKind::ServoBus => a.station().connected(),
        SimKind::TuyaVacuum => a.station().device.tuya.done_at.is_some(),
        _ => a.station().link.answering() == Answering::Yes && a.station().device.info.is_some(),
    }
}

/// The app on `kind` as a technician has it before the views are walked: the window
/// cleaner's self-test plan and a preset open; the servo bus scanned and a servo's parameters
/// read (its ranges the profile's, named values by their names).
pub(crate) fn prepare(h: &mut H, kind: SimKind) {
    if kind == SimKind::WindowCleaner {
        // The self-test's plan and a preset open, as a technician has them.
        let a = app_mut(h);
        a.with_panel(|p: &mut SelfTestPanel, st| p.open(st));
        let dir = botbench::ui::files::shipped_dir();
        let preset = botbench::ui::files::shipped_in(&dir, "window-cleaner-factory.ron");
        a.with_panel(|p: &mut PresetsPanel, st| {
            p.path = preset.unwrap().display().to_string();
            p.open(st);
        });
        assert!(
            a.panel::<SelfTestPanel>().plan.is_some() && a.panel::<PresetsPanel>().loaded.is_some()
        );
    }
    if kind == SimKind::ServoBus {
        // The bus scanned and the servo's parameters read, as a technician has them.
        app_mut(h).settings.panel = PanelId::SERVO_BENCH;
        h.run_steps(2);
        h.get_by_label("扫描").click();
        step_until(h, "the scan", |a| {
            a.panel::<ServoBenchPanel>().selected.is_some() && a.station().job_progress().is_none()
        });
        let params = app(h)
            .views()
            .into_iter()
            .find(|v| v.name.ends_with("Params"));
        app_mut(h).show_view(&params.expect("a Params tab"));
        step_until(h, "the parameters read", |a| {
            !a.panel::<ServoBenchPanel>().params.values.is_empty()
                && a.station().job_progress().is_none()
        });
        h.run_steps(2);
        // Ranges are the profile's, named values by their names: no type limit, no ident.
        for (text, ..) in texts(h) {
            for wire in ["65535", "4294967295", "limit_power", "interruptible"] {
                assert!(!text.contains(wire), "{text:?} shows {wire}");
            }
        }
    }
}

/// What is wrong with the view drawn now: texts over texts, the port box's hint cut, a control
/// past the window's right edge, a label parted from its box, a word split over two lines.
fn problems(h: &H, kind: SimKind, view: &str, size: egui::Vec2, lang: Lang) -> Vec<String> {
    let mut bad = Vec::new();
    for (a, b) in overlapping_texts(&h.output().shapes) {
        bad.push(format!(
            "{} {} {}×{} {lang:?}: {a:?} over {b:?}",
            kind.name(),
            view,
            size.x,
            size.y
        ));
    }
    // The port box's hint is whole (the box was once squeezed to "…").
    let hint = lang.tr("or a path, e.g. /dev/pts/3", "或输入路径,如 /dev/pts/3");
    if shown_of(h, hint).as_deref() != Some(hint) {
        bad.push(format!(
            "{} {} {}×{} {lang:?}: the port hint shows {:?}",
            kind.name(),
            view,
            size.x,
            size.y,
            shown_of(h, hint)
        ));
    }
    // Every control can be reached: none lies past the window's right edge (the
    // solar actions' Send buttons once did at 1024 px, behind a wide row).
    use egui::accesskit::Role;
    let controls = [
        Role::Button,
        Role::TextInput,
        Role::ComboBox,
        Role::CheckBox,
    ]
    .into_iter()
    .flat_map(|role| h.query_all(By::new().role(role)).collect::<Vec<_>>());
    for button in controls {
        let r = button.rect();
        if r.max.x > size.x + 1.0 && r.min.y < size.y {
            bad.push(format!(
                "{} {} {}×{} {lang:?}: control {:?} at x {:.0}..{:.0}, past the window",
                kind.name(),
                view,
                size.x,
                size.y,
                button.accesskit_node().label(),
                r.min.x,
                r.max.x
            ));
        }
    }
    for parted in parted_labels(h) {
        bad.push(format!(
            "{} {} {}×{} {lang:?}: {parted} on another row",
            kind.name(),
            view,
            size.x,
            size.y
        ));
    }
    for text in split_words(&h.output().shapes) {
        bad.push(format!(
            "{} {} {}×{} {lang:?}: {text:?} split",
            kind.name(),
            view,
            size.x,
            size.y
        ));
    }
    bad
}

#[test]
fn at_1024_and_800_px_every_view_keeps_words_whole_texts_apart_and_labels_by_their_boxes() {
    let mut bad = Vec::new();
    for kind in SimKind::ALL {
        let mut h = demo(kind, Lang::Zh, SMALL);
        prepare(&mut h, kind);
        for (size, lang) in [SMALL, LEAST]
            .into_iter()
            .flat_map(|s| Lang::ALL.map(|l| (s, l)))
        {
            h.set_size(size);
            app_mut(&mut h).settings.lang = lang;
            for view in app(&h).views() {
                app_mut(&mut h).show_view(&view);
                // egui lays a new panel out over two passes.
                h.run_steps(3);
                bad.extend(problems(&h, kind, &view.name, size, lang));
            }
        }
    }
    assert!(
        bad.is_empty(),
        "words split over two lines, texts over texts, labels parted from their boxes:\n{}",
        bad.join("\n")
    );
}

#[test]
fn at_1024_px_in_chinese_the_navigation_and_the_status_line_keep_one_line() {
    for kind in [SimKind::TuyaVacuum, SimKind::SolarCleanbot] {
        let mut h = demo(kind, Lang::Zh, SMALL);
        h.run_steps(2);
        let drawn = texts(&h);
        let panels = app(&h).panels();
        for panel in panels {
            let name = panel.name(Lang::Zh);
            let (_, rect, rows) = drawn
                .iter()
                .find(|(t, ..)| t == name)
                .unwrap_or_else(|| panic!("{name} is in the navigation"));
            assert_eq!(*rows, 1, "{}: {name} on one line ({rect:?})", kind.name());
        }
        // The status line: the bottom row of the window, every text on it whole and inside.
        let line = SMALL.y - 30.0;
        let status: Vec<_> = drawn.iter().filter(|(_, r, _)| r.top() > line).collect();
        assert!(status.len() >= 3, "{}: {status:?}", kind.name());
        for (text, rect, rows) in status {
            assert_eq!(*rows, 1, "{}: {text} on one line", kind.name());
            assert!(
                rect.right() <= SMALL.x + 0.5,
                "{}: {text} ends at {} past the window",
                kind.name(),
                rect.right()
            );
        }
    }
}

#[test]
fn at_1024_px_every_solar_plot_keeps_its_height_and_scrolls_into_view() {
    let mut h = demo(SimKind::SolarCleanbot, Lang::Zh, SMALL);
    app_mut(&mut h).settings.panel = PanelId::TELEMETRY;
    step_until(&mut h, "every plot drawn", |a| {
        a.panel::<TelemetryPanel>().shown.len() == a.station().device.profile.plots.len()
    });
    h.run_steps(2);
    let inside = |a: &App| {
        let last = a
            .panel::<TelemetryPanel>()
            .shown
            .last()
            .expect("a plot")
            .rect;
        a.panel::<TelemetryPanel>()
            .plots_view
            .expand(1.0)
            .contains_rect(last)
    };
    let a = app(&h);
    assert!(a.panel::<TelemetryPanel>().shown.len() >= 3);
    for s in &a.panel::<TelemetryPanel>().shown {
        assert!(
            s.rect.height() >= botbench::ui::MIN_PLOT_HEIGHT - 1.0,
            "{} is {} high",
            s.id,
            s.rect.height()
        );
    }
    assert!(
        !inside(a),
        "at 600 points the last plot starts below the view"
    );
    // The mouse wheel over the plots brings the last one into view.
    let over = a.panel::<TelemetryPanel>().plots_view.center();
    h.hover_at(over);
    for _ in 0..4 {
        h.event(egui::Event::MouseWheel {
            unit: egui::MouseWheelUnit::Point,
            delta: egui::vec2(0.0, -400.0),
            phase: egui::TouchPhase::Move,
            source: egui::MouseWheelSource::Unknown,
            modifiers: egui::Modifiers::NONE,
        });
        h.step();
    }
    step_until(&mut h, "the last plot in view", inside);
}

#[test]
fn a_panel_keeps_its_own_scroll_place_when_another_panel_was_scrolled() {
    let mut h = demo(SimKind::WindowCleaner, Lang::En, SMALL);
    let a = app_mut(&mut h);
    let dir = botbench::ui::files::shipped_dir();
    let preset = botbench::ui::files::shipped_in(&dir, "window-cleaner-factory.ron");
    a.with_panel(|p: &mut PresetsPanel, st| {
        p.path = preset.unwrap().display().to_string();
        p.open(st);
    });
    // The tuning table scrolled to its last group…
    let last = app(&h)
        .views()
        .into_iter()
        .rfind(|v| v.panel == PanelId::TUNING);
    app_mut(&mut h).show_view(&last.expect("a tuning group"));
    h.run_steps(3);
    let read_all = h.get_by_label("Read all").rect();
    let first = h.query_by_label("Fan PWM");
    assert!(
        first.is_none_or(|n| n.rect().bottom() < read_all.bottom()),
        "the tuning table is scrolled down"
    );
    // …and the presets' table starts at its top.
    app_mut(&mut h).settings.panel = PanelId::PRESETS;
    h.run_steps(3);
    let compare = h.get_by_label("Compare with device").rect();
    let header = h.get_by_label("Command").rect();
    assert!(
        header.top() > compare.bottom(),
        "the presets' header row is in view ({header:?} under {compare:?})"
    );
}

#[test]
fn at_1024_px_every_range_hint_of_the_solar_actions_is_drawn_whole() {
    let mut h = demo(SimKind::SolarCleanbot, Lang::En, SMALL);
    app_mut(&mut h).settings.panel = PanelId::ACTIONS;
    h.run_steps(3);
    let profile = app(&h).station().device.profile.clone();
    let mut hints = 0;
    for f in profile
        .commands
        .iter()
        .filter(|c| c.kind == botbench::profile::CommandKind::Action)
        .flat_map(|c| &c.request)
        .filter(|f| f.labels.is_empty())
    {
        let Some((lo, hi)) = f.range else { continue };
        let hint = format!(
            "{} – {}{}",
            f.format_number(lo),
            f.format_number(hi),
            f.unit_suffix()
        );
        assert_eq!(
            shown_of(&h, &hint).as_deref(),
            Some(hint.as_str()),
            "{}: the hint is drawn whole",
            f.ident
        );
        hints += 1;
    }
    assert!(hints >= 4, "{hints} ranged fields");
}
