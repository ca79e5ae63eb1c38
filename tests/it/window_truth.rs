//! Issue 14, "show only what is true": the real app through egui_kittest against the simulated
//! window cleaner on a pty. Cursor readout, broken lines, the packet monitor's view, port open
//! vs device answering, a unit's values and verdicts forgotten, the safe state and what is
//! running, tunable presets, per-profile port settings, pause.

use botbench::i18n::Lang;
use botbench::sim::SimOptions;
use botbench::sim::window_cleaner::WindowCleaner;
use botbench::ui::monitor::MonitorPanel;
use botbench::ui::presets::PresetsPanel;
use botbench::ui::telemetry::TelemetryPanel;
use botbench::ui::tuning::TuningPanel;
use botbench::ui::{App, PanelId};
use eframe::egui;
use egui_kittest::kittest::Queryable;

use crate::support::gui::{self, H, app, app_mut, settings, step_until};
use crate::support::{Port, serve, serve_with, served_window_cleaner as bench};

/// The app on the window cleaner at `path`, with 100 ms for the device to start answering:
/// generous for a loaded test machine.
fn harness(port: &impl Port, panel: PanelId) -> H {
    gui::on_window_cleaner(port, panel, Some(100))
}

/// The Tuning panel on `b`, its Fan PWM maximum set to 97 (a value no other field holds, to type
/// over), once every tuning value is read and no job runs.
fn tuning_read(b: &crate::support::Served<WindowCleaner>) -> H {
    b.sim.lock().unwrap().set_param("pwmvalueMax", 97).unwrap();
    let mut h = harness(b, PanelId::TUNING);
    step_until(&mut h, "the device read", |a| {
        (130..=136).all(|id| a.station().device.readings.contains_key(&id))
            && a.station().job_progress().is_none()
    });
    h.run_steps(2);
    h
}

fn show(h: &mut H, panel: PanelId) {
    app_mut(h).settings.panel = panel;
    h.run_steps(3);
}

#[test]
fn the_packet_monitor_opened_late_shows_the_newest_and_holds_where_the_technician_scrolled() {
    let b = bench();
    let mut h = harness(&b, PanelId::TUNING);
    // A small log, so that it is full (and drops its oldest) within the test.
    app_mut(&mut h).station_mut().packets.capacity = 400;
    step_until(&mut h, "traffic", |a| {
        a.station().packets.entries.len() >= 400
    });
    show(&mut h, PanelId::MONITOR);
    let newest =
        |a: &App| a.station().packets.first_seq() + a.station().packets.entries.len() as u64;
    {
        let a = app(&h);
        assert!(a.panel::<MonitorPanel>().follow, "it follows by default");
        let top = a.panel::<MonitorPanel>().top.expect("rows shown");
        assert!(
            top + 60 >= newest(a),
            "the newest is in view: top {top}, newest {}",
            newest(a)
        );
    }
    // The technician scrolls up: the view leaves the newest and stays on the same frames while
    // new ones come and old ones are dropped.
    let rows: Vec<egui::Rect> = h
        .get_all_by_label_contains("MSP_")
        .map(|n| n.rect())
        .collect();
    let area = rows[rows.len() / 2].center();
    h.hover_at(area);
    for _ in 0..6 {
        h.event(egui::Event::MouseWheel {
            unit: egui::MouseWheelUnit::Line,
            delta: egui::vec2(0.0, 5.0),
            phase: egui::TouchPhase::Move,
            source: egui::MouseWheelSource::Unknown,
            modifiers: egui::Modifiers::NONE,
        });
        h.step();
    }
    // Until the wheel's smooth scrolling has come to rest: the view stays on the same frame, or
    // on the oldest one kept (on a loaded machine the log may drop the frames under the view
    // faster than the scrolling settles; the view then moves only with the oldest).
    let (mut last, mut still) = (app(&h).panel::<MonitorPanel>().top, 0);
    let deadline = std::time::Instant::now() + crate::support::PATIENCE;
    while still < 10 {
        assert!(
            std::time::Instant::now() < deadline,
            "the wheel's scrolling never came to rest"
        );
        h.step();
        std::thread::sleep(std::time::Duration::from_millis(20));
        let top = app(&h).panel::<MonitorPanel>().top;
        let oldest = Some(app(&h).station().packets.first_seq());
        still = if top == last || top == oldest {
            still + 1
        } else {
            0
        };
        last = top;
    }
    let held = app(&h).panel::<MonitorPanel>().top.unwrap();
    assert!(!app(&h).panel::<MonitorPanel>().follow);
    let until = newest(app(&h)) + 200;
    step_until(&mut h, "more traffic", |a| newest(a) >= until);
    h.run_steps(2);
    let a = app(&h);
    // On a loaded machine more frames may come than the log keeps: a held frame that was
    // dropped leaves the view on the oldest one kept.
    assert_eq!(
        a.panel::<MonitorPanel>().top,
        Some(held.max(a.station().packets.first_seq())),
        "the view stays on the frames it was on"
    );
    let (below, secs) = a
        .panel::<MonitorPanel>()
        .behind
        .expect("says how far behind");
    assert!(below >= 200 && secs > 0.0, "{below} {secs}");
    assert!(
        h.query_by_label_contains("newer frame(s) below the view")
            .is_some()
    );
    // "Newest" follows again.
    h.get_by_label("Newest").click();
    h.run_steps(3);
    let a = app(&h);
    assert!(a.panel::<MonitorPanel>().follow);
    assert!(a.panel::<MonitorPanel>().top.unwrap() + 60 >= newest(a));
}

fn telemetry(port: &impl Port, lang: Lang) -> H {
    let mut saved = settings(port.path(), "window-cleaner", PanelId::TELEMETRY, lang);
    saved.port_mut().margin_ms = Some(100);
    // A window far longer than the test: its left part is before any data.
    saved.window_secs = 600.0;
    crate::support::gui::harness(saved, port.ports())
}

/// Samples in the first plot's series.
fn samples(a: &App) -> usize {
    let id = &a.station().device.profile.plots[0].id;
    a.station()
        .device
        .plots
        .get(id)
        .and_then(|s| s.iter().next().map(|(_, series)| series.iter().count()))
        .unwrap_or(0)
}

#[test]
fn the_cursor_readout_is_a_sample_under_the_pointer_or_nothing_and_moves_nothing() {
    let b = bench();
    let mut h = telemetry(&b, Lang::En);
    step_until(&mut h, "samples", |a| {
        samples(a) >= 5 && a.panel::<TelemetryPanel>().shown.len() >= 2
    });
    let before = app(&h).panel::<TelemetryPanel>().shown[1].rect;
    let plot = app(&h).panel::<TelemetryPanel>().shown[0].rect;
    // Over the newest data: the readout is a sample's own time, with values.
    h.hover_at(egui::pos2(plot.right() - 4.0, plot.center().y));
    h.run_steps(3);
    {
        let a = app(&h);
        let r = a.panel::<TelemetryPanel>().shown[0]
            .readout
            .clone()
            .expect("a readout");
        let id = &a.station().device.profile.plots[0].id;
        let set = a.station().device.plots.get(id).unwrap();
        let (field, series) = set.iter().next().unwrap();
        assert!(
            series.iter().any(|s| s.t == r.t),
            "the readout's time {} is a sample of {field}",
            r.t
        );
        assert!(!r.values.is_empty());
        assert_eq!(
            a.panel::<TelemetryPanel>().shown[1].rect,
            before,
            "the readout moves nothing"
        );
        for s in &a.panel::<TelemetryPanel>().shown {
            assert!(!s.legend.names.iter().any(|n| n.contains("cursor")));
        }
    }
    // Before any data: nothing.
    h.hover_at(egui::pos2(plot.left() + 10.0, plot.center().y));
    h.run_steps(3);
    assert_eq!(
        app(&h).panel::<TelemetryPanel>().shown[0].readout,
        None,
        "no sample there"
    );
    // Off the plots (over the top bar): nothing anywhere.
    h.hover_at(egui::pos2(plot.right() - 4.0, 5.0));
    h.run_steps(3);
    assert!(
        app(&h)
            .panel::<TelemetryPanel>()
            .shown
            .iter()
            .all(|s| s.readout.is_none())
    );
}

#[test]
fn a_pause_keeps_the_paused_data_in_view_and_breaks_the_line() {
    let b = bench();
    let mut h = telemetry(&b, Lang::En);
    step_until(&mut h, "samples", |a| {
        samples(a) >= 5 && !a.panel::<TelemetryPanel>().shown.is_empty()
    });
    let window = h.get_all_by_label("Window").next().unwrap().rect();
    h.get_by_label("Pause").click();
    h.run_steps(3);
    assert_eq!(
        h.get_all_by_label("Window").next().unwrap().rect(),
        window,
        "Pause/Resume moves nothing"
    );
    let end = app(&h).panel::<TelemetryPanel>().shown[0].x.1;
    let t0 = app(&h).station().device.t0;
    step_until(&mut h, "time to pass", |a| {
        a.station().device.t0.elapsed().as_secs_f64() > end + 0.5 && t0 == a.station().device.t0
    });
    h.run_steps(2);
    assert!(app(&h).panel::<TelemetryPanel>().follow);
    assert_eq!(
        app(&h).panel::<TelemetryPanel>().shown[0].x.1,
        end,
        "the view stays where polling paused"
    );
    let n = samples(app(&h));
    h.get_by_label("Resume").click();
    step_until(&mut h, "new samples", |a| samples(a) >= n + 3);
    let a = app(&h);
    let id = &a.station().device.profile.plots[0].id;
    let set = a.station().device.plots.get(id).unwrap();
    let (field, _) = set.iter().next().unwrap();
    let (mut pts, mut starts) = (Vec::new(), Vec::new());
    set.decimate_segments(
        field,
        0.0,
        a.station().plot_end(),
        1000,
        &mut pts,
        &mut starts,
    );
    assert!(
        starts.len() >= 2,
        "the line is broken where polling paused: {starts:?}"
    );
}

#[test]
fn a_silent_device_is_a_port_open_not_a_device_answering() {
    let b = serve_with(
        WindowCleaner::new(&SimOptions::default()).unwrap(),
        botbench::sim::Faults {
            silent: true,
            ..Default::default()
        },
    );
    let mut h = harness(&b, PanelId::TUNING);
    step_until(&mut h, "the port", |a| a.station().connected());
    step_until(&mut h, "unanswered requests", |a| {
        matches!(
            a.station().link.answering(),
            botbench::ui::station::Answering::No(_)
        )
    });
    h.run_steps(2);
    assert!(h.query_by_label_contains("device silent").is_some());
    assert!(h.query_by_label_contains("device answering").is_none());
}

#[test]
fn a_disconnect_forgets_the_units_version_values_and_marks() {
    let b = bench();
    let mut h = harness(&b, PanelId::TUNING);
    // Whether the device answers comes with the worker's next statistics report, which may
    // arrive after the values: wait for it, not for a number of frames.
    step_until(&mut h, "the device read and its answers counted", |a| {
        a.station().device.info.is_some()
            && a.station().device.value(130, "pwmValue").is_some()
            && a.station().link.answering() == botbench::ui::station::Answering::Yes
    });
    h.run_steps(2);
    assert!(h.query_by_label_contains("device answering").is_some());
    assert!(
        h.query_by_label_contains(" fw ").is_some(),
        "the version is shown"
    );
    h.get_by_label("Disconnect").click();
    h.run_steps(3);
    let a = app(&h);
    assert!(a.station().device.info.is_none());
    assert!(a.station().device.value(130, "pwmValue").is_none());
    assert!(
        h.query_by_label_contains(" fw ").is_none(),
        "no version of a gone unit"
    );
    assert!(h.query_by_label_contains("verified").is_none());
}

#[test]
fn stop_is_on_every_window_cleaner_panel_and_goes_straight_to_the_robot() {
    let b = bench();
    let mut h = harness(&b, PanelId::TUNING);
    step_until(&mut h, "the link", |a| a.station().connected());
    for panel in [
        PanelId::TUNING,
        PanelId::TELEMETRY,
        PanelId::MONITOR,
        PanelId::PRESETS,
        PanelId::ACTIONS,
        PanelId::DEVICE,
        PanelId::SELF_TEST,
    ] {
        show(&mut h, panel);
        assert!(
            h.query_all_by_label("STOP").next().is_some(),
            "{panel:?} has STOP"
        );
    }
    show(&mut h, PanelId::TUNING);
    h.get_all_by_label("STOP").next().unwrap().click();
    let ids: Vec<u8> = {
        let p = &app(&h).station().device.profile;
        p.stop
            .iter()
            .map(|s| p.command(&s.command).expect("a STOP command").id)
            .collect()
    };
    assert!(!ids.is_empty());
    step_until(&mut h, "every STOP command answered", |a| {
        ids.iter().all(|id| {
            a.station().packets.entries.iter().any(|l| {
                l.frame().is_some_and(|e| {
                    e.direction == botbench::protocol::Direction::DeviceToHost
                        && e.frame.as_ref().is_ok_and(|p| p.command == *id)
                })
            })
        })
    });
    step_until(&mut h, "the acknowledgement", |a| {
        matches!(
            a.station().stop.state(),
            botbench::ui::stop::StopState::Acked(_)
        )
    });
    h.run_steps(2);
    assert!(h.query_by_label_contains("STOP acknowledged").is_some());
    assert!(h.query_by_label_contains("the robot will move").is_none());
}

/// Every text box's left edge.
/// Every text box's left edge in the tuning tables (below "Read all").
fn input_lefts(h: &H) -> Vec<f32> {
    let top = h.get_by_label("Read all").rect().bottom();
    h.query_all(egui_kittest::kittest::by().role(egui::accesskit::Role::TextInput))
        .filter(|n| n.rect().top() > top)
        .map(|n| n.rect().left())
        .collect()
}

#[test]
fn the_tuning_tables_line_up_across_the_width_and_say_only_what_the_profile_gives() {
    let b = bench();
    let mut h = tuning_read(&b);
    let lefts = input_lefts(&h);
    assert!(lefts.len() > 10, "{lefts:?}");
    let min = lefts.iter().copied().fold(f32::MAX, f32::min);
    let max = lefts.iter().copied().fold(f32::MIN, f32::max);
    assert!(
        max - min < 1.0,
        "the Edited column is the same in every group: {lefts:?}"
    );
    assert!(
        min > 1400.0 * 0.3,
        "the table spreads over the width (Edited column at {min})"
    );
    for limit in ["4294967", "65535", "2147483"] {
        assert!(
            h.query_by_label_contains(limit).is_none(),
            "no type limit ({limit}) shown as a range"
        );
    }
    // The write dialog names fields as the window does.
    open_write_dialog(&mut h);
    // The table indents its field names: the exact name is the dialog's.
    assert!(
        h.query_by_label("Fan PWM maximum").is_some(),
        "the dialog names the field"
    );
    assert!(h.query_by_label_contains("pwmvalueMax").is_none());
}

#[test]
fn the_configurator_variants_own_set_layout_is_written_and_verified() {
    let profile =
        botbench::sim::msp_device::builtin_profile("window-cleaner-configurator").unwrap();
    let core = botbench::sim::msp_device::MspCore::new(profile, 3, 115_200);
    let b = serve(WindowCleaner::with_core(core, 1));
    b.sim
        .lock()
        .unwrap()
        .set_param("waterPumpDuration", 151)
        .unwrap();
    let mut saved = settings(
        b.path(),
        "window-cleaner-configurator",
        PanelId::TUNING,
        Lang::En,
    );
    saved.port_mut().margin_ms = Some(100);
    let mut h = crate::support::gui::harness(saved, b.ports());
    step_until(&mut h, "the spray settings read", |a| {
        a.station().device.value(135, "waterPumpDuration").is_some()
            && a.station().job_progress().is_none()
    });
    h.run_steps(2);
    let is_151 = |n: &egui_kittest::kittest::AccessKitNode<'_>| {
        n.role() == egui::accesskit::Role::TextInput && n.value().as_deref() == Some("151")
    };
    h.get_by(is_151).focus();
    h.step();
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::A);
    h.step();
    h.get_by(is_151).type_text("200");
    h.run_steps(2);
    let a = app(&h);
    let (_, writes) = a
        .panel::<TuningPanel>()
        .pending(a.station())
        .expect("the write is possible");
    let set = writes.iter().find(|(id, _)| *id == 225).expect("SET 225");
    let fields: Vec<&str> = set.1.iter().map(|(f, _)| f.as_str()).collect();
    assert_eq!(
        fields,
        [
            "waterPumpDuration",
            "waterPumpStartAngle",
            "waterPumpMoveCnt"
        ],
        "the Set's own fields"
    );
    step_until(&mut h, "no job running", |a| {
        a.station().job_progress().is_none()
    });
    h.get_by_label_contains("Write changes (1)").click();
    h.run_steps(3);
    h.get_by_label("Write").click();
    step_until(&mut h, "the write verified", |a| {
        a.station()
            .device
            .marks
            .get(&(135, "waterPumpDuration".to_string()))
            == Some(&botbench::ui::station::Mark::Verified)
    });
    assert_eq!(b.sim.lock().unwrap().param("waterPumpDuration"), Some(200));
}

/// The app at `size` on the window cleaner, in `lang`.
#[test]
fn in_chinese_the_status_line_and_the_plot_legends_are_chinese() {
    let b = bench();
    let mut h = telemetry(&b, Lang::Zh);
    step_until(&mut h, "samples", |a| {
        samples(a) >= 2 && !a.panel::<TelemetryPanel>().shown.is_empty()
    });
    h.run_steps(2);
    let a = app(&h);
    let profile = &a.station().device.profile;
    for s in &a.panel::<TelemetryPanel>().shown {
        let p = profile.plots.iter().find(|p| p.id == s.id).unwrap();
        for (ident, name) in p.fields.iter().zip(&s.legend.names) {
            assert!(
                !name.contains(ident.as_str()),
                "{name} is not the wire name {ident}"
            );
            assert!(name.chars().any(|c| c as u32 > 0x2e80), "{name} is Chinese");
        }
        assert!(!s.legend.y_label.is_empty());
    }
    let first = a.panel::<TelemetryPanel>().shown[0].legend.names[0].clone();
    assert!(
        h.query_by_label(&format!("— {first}")).is_some(),
        "the key shows {first}"
    );
    h.get_by_label("断开").click();
    h.run_steps(3);
    assert!(h.query_by_label("已断开").is_some(), "the status line");
}

#[test]
fn factory_defaults_leave_no_file_named_and_a_typed_preset_path_is_remembered() {
    let b = bench();
    let dir = std::env::temp_dir().join(format!("botbench-wt-preset-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("golden.ron");
    let mut h = harness(&b, PanelId::PRESETS);
    step_until(&mut h, "the device read", |a| {
        a.station().device.value(130, "pwmValue").is_some() && a.station().job_progress().is_none()
    });
    app_mut(&mut h).panel_mut::<PresetsPanel>().path = path.display().to_string();
    h.step();
    h.get_by_label("Save device to file").click();
    step_until(&mut h, "the preset saved", |a| {
        path.exists() && a.station().job_progress().is_none()
    });
    assert_eq!(
        app(&h)
            .settings
            .file(botbench::ui::settings::FileKind::Preset),
        Some(path.display().to_string().as_str()),
        "the path is remembered"
    );
    h.get_by_label("Factory defaults").click();
    h.run_steps(2);
    assert!(app(&h).panel::<PresetsPanel>().loaded.is_some());
    assert_eq!(
        app(&h).panel::<PresetsPanel>().path,
        "",
        "the defaults are not the file named before"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn other_telemetry_lists_every_telemetry_command_in_a_box_of_many_rows() {
    use botbench::profile::CommandKind;
    let b = bench();
    let mut h = telemetry(&b, Lang::En);
    h.run_steps(3);
    let profile = app(&h).station().device.profile.clone();
    let others: Vec<_> = profile
        .commands
        .iter()
        .filter(|c| c.kind == CommandKind::Telemetry && !c.reply.is_empty())
        .collect();
    assert!(others.len() > 10, "{} telemetry commands", others.len());
    let heading = h.get_by_label("Other telemetry").rect();
    let window = h.ctx.content_rect();
    let visible = others
        .iter()
        .filter(|c| {
            h.query_all_by_label(&c.name.en)
                .map(|n| n.rect())
                .any(|r| r.top() >= heading.bottom() && r.bottom() <= window.bottom())
        })
        .count();
    // A box two rows high was the fault: at 1000 px it holds at least ten.
    assert!(visible >= 10, "{visible} of {} rows in view", others.len());
}

#[test]
fn a_profiles_port_settings_are_its_own() {
    let b = bench();
    let mut saved = settings(b.path(), "window-cleaner", PanelId::TELEMETRY, Lang::En);
    saved.port_mut().margin_ms = Some(300);
    let mut h = crate::support::gui::harness(saved, b.ports());
    h.run_steps(3);
    assert_eq!(app(&h).connection.port().margin_ms, Some(300));
    let choose = |h: &mut H, id: &str| {
        h.get_by_role_and_label(egui::accesskit::Role::ComboBox, "Profile")
            .click();
        h.run_steps(2);
        h.get_by_label_contains(&format!("{id} — ")).click();
        h.run_steps(2);
    };
    choose(&mut h, "servo");
    assert_eq!(
        app(&h).connection.port().margin_ms,
        None,
        "the servo takes the automatic margin, not the window cleaner's 300 ms"
    );
    choose(&mut h, "window-cleaner");
    assert_eq!(app(&h).connection.port().margin_ms, Some(300));
}

/// The STOP commands' ids of the shown station's profile.
fn stop_ids(h: &H) -> Vec<u8> {
    let p = &app(h).station().device.profile;
    p.stop
        .iter()
        .map(|s| p.command(&s.command).expect("a STOP command").id)
        .collect()
}

/// How many of the STOP commands' requests the window has sent so far (each command counts).
fn stops_sent(a: &App, ids: &[u8]) -> usize {
    a.station()
        .packets
        .entries
        .iter()
        .filter_map(|l| l.frame())
        .filter(|e| {
            e.direction == botbench::protocol::Direction::HostToDevice
                && e.frame.as_ref().is_ok_and(|p| ids.contains(&p.command))
        })
        .count()
}

/// Opens Tuning's "Write these changes?" with one edit (Fan PWM maximum 97 -> 90).
fn open_write_dialog(h: &mut H) {
    retype(h, "97", "90");
    h.get_by_label_contains("Write changes (1)").click();
    h.run_steps(3);
    assert!(h.query_by_label("Write these changes?").is_some());
}

/// STOP acts at once whatever is open (issue 25, item 5): a confirmation dialog shows STOP
/// beside its answers; a click on the navigation's STOP while the dialog is open sends STOP
/// and closes the dialog (the dialog's backdrop took that click as "close" alone); STOP's line
/// says when this STOP was acknowledged, on the wall clock.
#[test]
fn stop_acts_at_once_while_a_confirmation_dialog_is_open() {
    let b = bench();
    let mut h = tuning_read(&b);
    let ids = stop_ids(&h);
    assert!(!ids.is_empty());
    open_write_dialog(&mut h);
    let stops: Vec<egui::Rect> = h.get_all_by_label("STOP").map(|n| n.rect()).collect();
    assert_eq!(stops.len(), 2, "the dialog shows STOP beside its answers");
    // The navigation's STOP (the leftmost), clicked through the open dialog.
    let nav = h
        .get_all_by_label("STOP")
        .min_by(|a, b| a.rect().left().total_cmp(&b.rect().left()))
        .unwrap();
    nav.click();
    step_until(&mut h, "every STOP command sent", |a| {
        stops_sent(a, &ids) >= ids.len()
    });
    h.run_steps(2);
    assert!(
        h.query_by_label("Write these changes?").is_none(),
        "the dialog closed"
    );
    step_until(&mut h, "the acknowledgement", |a| {
        matches!(
            a.station().stop.state(),
            botbench::ui::stop::StopState::Acked(_)
        )
    });
    h.run_steps(2);
    let line = text_of(&h.get_by_label_contains("STOP acknowledged at"));
    let wall = chrono::Local::now().format("%H:").to_string();
    assert!(line.contains(&wall), "{line}: the wall clock's time");
    // The dialog's own STOP: another STOP, acknowledged after the first.
    let first = match app(&h).station().stop.state() {
        botbench::ui::stop::StopState::Acked(at) => at,
        other => panic!("{other:?}"),
    };
    // The edit is still there (nothing was written): the dialog again.
    h.get_by_label_contains("Write changes (1)").click();
    h.run_steps(3);
    assert!(h.query_by_label("Write these changes?").is_some());
    let dialog_stop = h
        .get_all_by_label("STOP")
        .max_by(|a, b| a.rect().left().total_cmp(&b.rect().left()))
        .unwrap();
    dialog_stop.click();
    step_until(&mut h, "the second STOP sent", |a| {
        stops_sent(a, &ids) >= 2 * ids.len()
    });
    step_until(
        &mut h,
        "the second STOP acknowledged",
        |a| matches!(a.station().stop.state(), botbench::ui::stop::StopState::Acked(at) if at > first),
    );
    h.run_steps(2);
    assert!(h.query_by_label("Write these changes?").is_none());
    assert_eq!(
        b.sim.lock().unwrap().param("pwmvalueMax"),
        Some(97),
        "nothing was written"
    );
}

/// The telemetry header shows the poll rate achieved beside the one asked for (issue 25,
/// item 7), and no rate while polling is paused.
#[test]
fn the_telemetry_header_shows_the_rate_achieved_beside_the_one_asked() {
    let b = bench();
    let mut h = telemetry(&b, Lang::En);
    step_until(&mut h, "samples over a second", |a| {
        botbench::ui::telemetry::achieved_rate(a.station()).is_some()
    });
    h.run_steps(2);
    let label = text_of(&h.get_by_label_contains("achieved "));
    let hz: f64 = label
        .trim_start_matches("achieved ")
        .trim_end_matches(" Hz")
        .parse()
        .unwrap_or_else(|e| panic!("{label}: {e}"));
    assert!(hz > 0.0, "{label}");
    h.get_by_label("Pause").click();
    h.run_steps(3);
    assert!(h.query_by_label("achieved —").is_some(), "paused: no rate");
}

/// A node's text: a label's own, else its value.
fn text_of(n: &egui_kittest::Node<'_>) -> String {
    use egui_kittest::kittest::NodeT;
    let node = n.accesskit_node();
    node.label().or_else(|| node.value()).unwrap_or_default()
}

/// Types `to` into the tuning box that shows `from` (a value no other box shows).
fn retype(h: &mut H, from: &str, to: &str) {
    h.get_by(|n| {
        n.role() == egui::accesskit::Role::TextInput && n.value().as_deref() == Some(from)
    })
    .focus();
    h.step();
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::A);
    h.step();
    h.get_by(|n| {
        n.role() == egui::accesskit::Role::TextInput && n.value().as_deref() == Some(from)
    })
    .type_text(to);
    h.run_steps(2);
}

/// Rules checked as typed (issue 25, item 9): edits that break a relation of the profile
/// (Fan PWM minimum <= Fan PWM maximum) are said as typed, naming both fields, and disable
/// Write; the edits and the device's readings stay.
#[test]
fn a_relation_broken_by_the_edits_is_said_as_typed_and_disables_write() {
    let b = bench();
    b.sim.lock().unwrap().set_param("pwmvalueMin", 23).unwrap();
    b.sim.lock().unwrap().set_param("pwmvalueMax", 61).unwrap();
    let mut h = harness(&b, PanelId::TUNING);
    step_until(&mut h, "the device read", |a| {
        (130..=136).all(|id| a.station().device.readings.contains_key(&id))
            && a.station().job_progress().is_none()
    });
    h.run_steps(2);
    retype(&mut h, "23", "70");
    h.run_steps(2);
    let said = text_of(&h.get_by_label_contains("must be ≤"));
    assert!(
        said.contains("Fan PWM minimum") && said.contains("Fan PWM maximum"),
        "{said}"
    );
    let write = h.get_by_label_contains("Write changes");
    assert!(
        egui_kittest::kittest::NodeT::accesskit_node(&write).is_disabled(),
        "Write is disabled while a relation is broken"
    );
    // Raising the maximum too mends it: Write takes both edits.
    retype(&mut h, "61", "80");
    h.run_steps(2);
    assert!(h.query_by_label_contains("must be ≤").is_none());
    assert!(h.query_by_label("Write changes (2)").is_some());
    let a = app(&h);
    let get = a
        .station()
        .device
        .profile
        .command("MSP_GET_USE_FAN_LEVEL_DYNAMIC_COMP")
        .expect("the fan level group")
        .id;
    assert_eq!(
        a.station().device.value(get, "pwmvalueMin"),
        Some(&botbench::profile::Value::Int(23)),
        "the reading stays"
    );
}

/// Every shape the last frame drew, with the rectangle it was clipped to (a plot's shapes are
/// clipped to its data area).
fn drawn(h: &H) -> Vec<(egui::Rect, egui::Shape)> {
    fn visit(clip: egui::Rect, shape: &egui::Shape, out: &mut Vec<(egui::Rect, egui::Shape)>) {
        match shape {
            egui::Shape::Vec(v) => v.iter().for_each(|s| visit(clip, s, out)),
            s => out.push((clip, s.clone())),
        }
    }
    let mut out = Vec::new();
    for c in &h.output().shapes {
        visit(c.clip_rect, &c.shape, &mut out);
    }
    out
}

/// The y tick labels drawn beside the data area `rect` of a plot: numbers, left of it, centred
/// within its height.
fn y_tick_labels(h: &H, rect: egui::Rect) -> Vec<String> {
    drawn(h)
        .into_iter()
        .filter_map(|(_, s)| match s {
            egui::Shape::Text(t) => {
                let at = t.galley.rect.translate(t.pos.to_vec2());
                let text = t.galley.text().to_string();
                let beside = at.right() <= rect.left() + 8.0
                    && at.right() >= rect.left() - 80.0
                    && at.center().y >= rect.top() - 1.0
                    && at.center().y <= rect.bottom() + 1.0;
                (beside && text.parse::<f64>().is_ok()).then_some(text)
            }
            _ => None,
        })
        .collect()
}

#[test]
fn every_plot_labels_at_least_three_y_ticks_at_1024_and_1280_px() {
    let b = bench();
    // The battery flat at 12.6 V (it drains far slower than a tenth of a volt in a test).
    b.sim().set_battery(12.6);
    for size in [egui::vec2(1024.0, 600.0), egui::vec2(1280.0, 800.0)] {
        let mut saved = gui::settings(b.path(), "window-cleaner", PanelId::TELEMETRY, Lang::En);
        saved.port_mut().margin_ms = Some(100);
        saved.window_secs = 10.0;
        let mut h = gui::harness_sized(saved, b.ports(), size, |_| {});
        step_until(&mut h, "samples in every plot", |a| {
            samples(a) >= 5 && a.panel::<TelemetryPanel>().shown.len() == 2
        });
        h.run_steps(3);
        for i in 0..2 {
            // A plot below the view (at 600 points the second one is) is scrolled into it.
            let inside = move |a: &App| {
                let t = a.panel::<TelemetryPanel>();
                t.plots_view.expand(1.0).contains_rect(t.shown[i].rect)
            };
            let over = app(&h).panel::<TelemetryPanel>().plots_view.center();
            for _ in 0..8 {
                if inside(app(&h)) {
                    break;
                }
                h.hover_at(over);
                h.event(egui::Event::MouseWheel {
                    unit: egui::MouseWheelUnit::Point,
                    delta: egui::vec2(0.0, -200.0),
                    phase: egui::TouchPhase::Move,
                    source: egui::MouseWheelSource::Unknown,
                    modifiers: egui::Modifiers::NONE,
                });
                h.run_steps(3);
            }
            h.hover_at(egui::pos2(1.0, 1.0));
            h.run_steps(2);
            let s = app(&h).panel::<TelemetryPanel>().shown[i].clone();
            assert!(inside(app(&h)), "{}: scrolled into view", s.id);
            let ticks = y_tick_labels(&h, s.rect);
            assert!(
                ticks.len() >= 3,
                "{}×{}: {} plot ({:?} over {:.0} points) labels {ticks:?}",
                size.x,
                size.y,
                s.id,
                s.y,
                s.rect.height()
            );
        }
    }
}

#[test]
fn a_trace_resumed_after_a_gap_is_lines_that_never_cross_it_and_nothing_filled() {
    let b = bench();
    // 600 s across the plot: many samples a pixel, where egui_plot merged points into bands.
    let mut h = telemetry(&b, Lang::En);
    step_until(&mut h, "samples", |a| {
        samples(a) >= 20 && !a.panel::<TelemetryPanel>().shown.is_empty()
    });
    h.get_by_label("Pause").click();
    h.run_steps(2);
    let paused = app(&h).station().device.t0.elapsed().as_secs_f64();
    step_until(&mut h, "two seconds paused", |a| {
        a.station().device.t0.elapsed().as_secs_f64() > paused + 2.0
    });
    let n = samples(app(&h));
    h.get_by_label("Resume").click();
    step_until(&mut h, "samples after the gap", |a| samples(a) >= n + 20);
    h.run_steps(3);
    assert_no_line_across_a_gap(&h, "the pause");
}

/// Item 7: an outage (the device lifted off its fixture for two seconds, every poll
/// unanswered, then answering again on the same link) is a gap in every trace, as a pause is:
/// no line joins the samples before it to those after. (A new connection starts new plots.)
#[test]
fn a_trace_resumed_after_an_outage_is_lines_that_never_cross_it() {
    let device: botbench::sim::SharedDevice =
        std::sync::Arc::new(std::sync::Mutex::new(crate::support::window_cleaner()));
    let (lift, hands) = botbench::sim::fixture::Lift::new(device);
    let b = crate::support::serve(lift);
    let mut h = telemetry(&b, Lang::En);
    step_until(&mut h, "samples", |a| {
        samples(a) >= 20 && !a.panel::<TelemetryPanel>().shown.is_empty()
    });
    hands.lift_for(std::time::Duration::from_secs(2));
    let n = samples(app(&h));
    step_until(&mut h, "samples after the outage", |a| samples(a) >= n + 20);
    h.run_steps(3);
    assert_no_line_across_a_gap(&h, "the outage");
}

/// Every trace of every plot shown is drawn as lines (no filled shape over the data), none of
/// whose segments crosses a break of its series, of which there is at least one (`gap`).
fn assert_no_line_across_a_gap(h: &H, gap: &str) {
    let a = app(h);
    let shapes = drawn(h);
    let mut lines = 0;
    for s in &a.panel::<TelemetryPanel>().shown {
        let plot = a
            .station()
            .device
            .profile
            .plots
            .iter()
            .find(|p| p.id == s.id);
        let set = a.station().device.plots.get(&s.id).unwrap();
        let breaks: Vec<f64> = set.breaks().collect();
        assert!(!breaks.is_empty(), "{}: {gap} is a gap", s.id);
        let time =
            |x: f32| s.x.0 + f64::from((x - s.rect.left()) / s.rect.width()) * (s.x.1 - s.x.0);
        let half_px = (s.x.1 - s.x.0) / f64::from(s.rect.width()) / 2.0;
        let colours: Vec<egui::Color32> = (0..plot.unwrap().fields.len())
            .map(botbench::ui::plot::color)
            .collect();
        let over_data = |clip: &egui::Rect| {
            clip.min.distance(s.rect.min) < 1.0 && clip.max.distance(s.rect.max) < 1.0
        };
        for (clip, shape) in shapes.iter().filter(|(clip, _)| over_data(clip)) {
            let trace = |p: &egui::epaint::PathShape| matches!(&p.stroke.color, egui::epaint::ColorMode::Solid(c) if colours.contains(c));
            match shape {
                egui::Shape::Band(_) | egui::Shape::Mesh(_) => {
                    panic!("{}: a filled shape over the data at {clip:?}", s.id)
                }
                egui::Shape::Path(p) if trace(p) => {
                    lines += 1;
                    for w in p.points.windows(2) {
                        let (ta, tb) = (time(w[0].x), time(w[1].x));
                        for g in &breaks {
                            assert!(
                                !(ta + half_px < *g && *g < tb - half_px),
                                "{}: a segment from {ta:.2} s to {tb:.2} s joins across the gap at {g:.2} s",
                                s.id
                            );
                        }
                    }
                }
                _ => {}
            }
        }
    }
    assert!(lines >= 4, "each trace drawn in stretches: {lines} lines");
}

/// Item 9: a write refused before anything is sent (a value out of its range, as a write
/// built outside the panel's checks would carry) leaves the group's readings and the
/// technician's edits as they were, and the status says it was refused with nothing sent,
/// never "not verified".
#[test]
fn a_write_refused_before_sending_keeps_readings_and_edits_and_says_nothing_was_sent() {
    use botbench::profile::Input;
    let b = bench();
    let mut h = tuning_read(&b);
    retype(&mut h, "97", "90");
    let profile = app(&h).station().device.profile.clone();
    let refused = botbench::ui::jobs::write(
        &profile,
        vec![(
            220,
            vec![("pwmValue".to_string(), Input::Text("700".into()))],
        )],
    );
    app_mut(&mut h).apply(botbench::ui::Action::StartJob(refused));
    step_until(&mut h, "the write's end", |a| {
        a.station().job_progress().is_none() && a.station().device.refused.contains_key(&130)
    });
    h.run_steps(3);
    let a = app(&h);
    assert!(
        (130..=136).all(|id| a.station().device.readings.contains_key(&id)),
        "the readings stay"
    );
    assert!(
        h.query_by(|n| {
            n.role() == egui::accesskit::Role::TextInput && n.value().as_deref() == Some("90")
        })
        .is_some(),
        "the edit stays"
    );
    assert!(
        h.query_all_by_label_contains("refused, nothing sent")
            .next()
            .is_some(),
        "the status says what happened"
    );
    assert!(
        h.query_all_by_label_contains("not verified")
            .next()
            .is_none(),
        "nothing said unverified"
    );
    assert_eq!(
        b.sim.lock().unwrap().param("pwmValue"),
        Some(85),
        "nothing sent"
    );
}

/// What opens a dialog.
type Opens = dyn Fn(&mut H);

/// Item 5, every dialog that asks before moving or writing: the Actions panel's "The robot will
/// move" and the Presets panel's "Apply this preset?" show STOP beside their answers, and the
/// navigation's STOP clicked through either sends STOP and closes it.
#[test]
fn the_navigations_stop_acts_through_the_actions_and_preset_dialogs_too() {
    let b = bench();
    let mut h = harness(&b, PanelId::ACTIONS);
    step_until(&mut h, "the device identified", |a| {
        a.station().device.info.is_some() && a.station().job_progress().is_none()
    });
    h.run_steps(2);
    let ids = stop_ids(&h);
    let mut sent = 0;
    // The motor's direction chosen, then its Send…
    h.get_by_role_and_label(egui::accesskit::Role::ComboBox, "Motor")
        .click();
    h.run_steps(2);
    h.get_by_label_contains("Forward").click();
    h.run_steps(2);
    let dialogs: [(&str, &Opens); 2] = [
        ("The robot will move", &|h: &mut H| {
            // The Send… on the motor's row.
            let row = h
                .get_by_role_and_label(egui::accesskit::Role::ComboBox, "Motor")
                .rect()
                .center()
                .y;
            h.get_all_by_label("⚠ Send…")
                .min_by(|a, b| {
                    (a.rect().center().y - row)
                        .abs()
                        .total_cmp(&(b.rect().center().y - row).abs())
                })
                .expect("a Send…")
                .click();
            h.run_steps(3);
        }),
        ("Apply this preset?", &|h: &mut H| {
            let a = app_mut(h);
            a.apply(botbench::ui::Action::ShowPanel(PanelId::PRESETS));
            let dir = botbench::ui::files::shipped_dir();
            let preset = botbench::ui::files::shipped_in(&dir, "window-cleaner-factory.ron");
            a.with_panel(|p: &mut PresetsPanel, st| {
                p.path = preset.expect("the shipped preset").display().to_string();
                p.open(st);
            });
            h.run_steps(3);
            h.get_by_label_contains("Apply (").click();
            h.run_steps(3);
        }),
    ];
    for (title, open) in dialogs {
        open(&mut h);
        assert!(h.query_by_label(title).is_some(), "{title} is open");
        assert_eq!(
            h.get_all_by_label("STOP").count(),
            2,
            "{title}: STOP beside its answers"
        );
        h.get_all_by_label("STOP")
            .min_by(|a, b| a.rect().left().total_cmp(&b.rect().left()))
            .expect("the navigation's STOP")
            .click();
        sent += ids.len();
        step_until(&mut h, "STOP sent", |a| stops_sent(a, &ids) >= sent);
        h.run_steps(2);
        assert!(h.query_by_label(title).is_none(), "{title} closed");
    }
}
