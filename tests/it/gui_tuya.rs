//! The Tuya console in the real app, driven through egui_kittest against the simulated vacuum
//! MCU on a pty: botbench plays the Wi-Fi module.

use botbench::i18n::Lang;
use botbench::profile::Value;
use botbench::profile::registry::parse;
use botbench::protocol::tuya::dp::DpValue;
use botbench::sim::Faults;
use botbench::sim::tuya_mcu::{OtaState, TuyaConfig, TuyaMcu, crc32};
use botbench::ui::tuya_console::TuyaConsolePanel;
use botbench::ui::{App, FirmwareFileError, PanelId};
use eframe::egui;
use egui::accesskit::Role;
use egui_kittest::kittest::Queryable;
use std::sync::Arc;
use std::time::Duration;

const BAUD: u32 = 115_200;
const VACUUM: &str = include_str!("../../assets/profiles/tuya-vacuum.ron");

use crate::support::gui::{H, app, app_mut, has_label, settings, step_until, type_into};
use crate::support::{Port, Served, image, serve_with, temp_dir, wait_until};

type Bench = Served<TuyaMcu>;

fn config() -> TuyaConfig {
    TuyaConfig {
        baud: Some(BAUD),
        ..TuyaConfig::default()
    }
}

fn bench_with(mcu: TuyaMcu, faults: Faults) -> Bench {
    serve_with(mcu, faults)
}

fn bench() -> Bench {
    bench_with(TuyaMcu::new(config()), Faults::default())
}

/// The vacuum profile with its value, string, bitmap and raw data points made writable, saved as
/// a file the app opens, and the MCU that goes with it.
fn writable_profile(dir: &std::path::Path) -> (String, Bench) {
    let mut src = VACUUM.replace("id: \"tuya-vacuum\"", "id: \"tuya-vacuum-rw\"");
    for id in [15, 16, 18, 19] {
        src = src.replace(
            &format!("(id: {id}, access: ReadOnly"),
            &format!("(id: {id}, access: ReadWrite"),
        );
    }
    let path = dir.join("tuya-vacuum-rw.ron");
    std::fs::write(&path, &src).unwrap();
    let profile = parse("tuya-vacuum-rw.ron", &src, Some("tuya-vacuum-rw")).unwrap();
    let mcu = TuyaMcu::with_profile(Arc::new(profile), config());
    (
        path.display().to_string(),
        bench_with(mcu, Faults::default()),
    )
}

pub(crate) fn harness(port: &impl Port, profile: &str) -> H {
    let mut saved = settings(port.path(), profile, PanelId::TUYA_CONSOLE, Lang::En);
    saved.port_mut().baud = Some(BAUD);
    crate::support::gui::harness(saved, port.ports())
}

pub(crate) fn handshake(h: &mut H) {
    step_until(h, "the handshake", |a| {
        a.station().device.tuya.done_at.is_some()
    });
    h.run_steps(2);
}

pub(crate) fn tab(h: &mut H, name: &str) {
    h.get_by(|n| n.role() == Role::Button && n.label().as_deref() == Some(name))
        .click();
    h.run_steps(2);
}

pub(crate) fn reported(a: &App, id: u8) -> Option<Value> {
    a.station()
        .device
        .tuya
        .dps
        .get(&id)
        .map(|s| s.value.clone())
}

#[test]
fn the_handshake_completes_and_the_panel_shows_the_product_info() {
    let b = bench();
    let mut h = harness(&b, "tuya-vacuum");
    handshake(&mut h);
    assert!(h.query_by_label("lgldgnmt4ifc.jzex").is_some(), "the PID");
    assert!(h.query_by_label("1.0.0").is_some(), "the MCU version");
    assert!(
        h.query_by_label("0 (default)").is_some(),
        "the configuration mode"
    );
    assert_eq!(
        h.query_all_by_label("✓ ok").count(),
        5,
        "every step is shown done"
    );
    assert!(has_label(&h, "Handshake complete at"));
    assert!(has_label(&h, "Last heartbeat:"));
    // The Wi-Fi state selector reports the chosen state to the MCU.
    h.get_by(|n| {
        n.role() == Role::ComboBox
            && n.label().as_deref() == Some("Wi-Fi state reported to the MCU")
    })
    .click();
    h.run_steps(2);
    h.get_by_label("2: Configured, not connected to router")
        .click();
    step_until(&mut h, "the MCU to hold Wi-Fi state 2", |_| {
        b.sim().wifi_state() == Some(2)
    });
    step_until(&mut h, "the ack", |a| {
        a.station().device.tuya.wifi_acked.is_some_and(|t| {
            a.station()
                .device
                .tuya
                .wifi_sent
                .as_ref()
                .is_some_and(|(s, sent)| *s == 2 && t >= *sent)
        })
    });
    h.run_steps(2);
    assert!(has_label(&h, "acknowledged at"));
}

#[test]
fn a_malformed_product_info_is_shown_raw_and_the_handshake_goes_on() {
    let raw = b"{\"p\":\"abc\",\"v\":";
    let b = bench_with(
        TuyaMcu::new(TuyaConfig {
            product_info_raw: Some(raw.to_vec()),
            ..config()
        }),
        Faults::default(),
    );
    let mut h = harness(&b, "tuya-vacuum");
    handshake(&mut h);
    assert!(
        h.query_by_label("{\"p\":\"abc\",\"v\":").is_some(),
        "shown raw"
    );
    assert!(has_label(&h, "not valid JSON"));
    assert!(has_label(&h, "shown raw"));
}

#[test]
fn a_silent_mcu_shows_where_the_handshake_stopped_and_no_value() {
    let silent = Faults {
        silent: true,
        ..Faults::default()
    };
    let b = bench_with(TuyaMcu::new(config()), silent);
    let mut h = harness(&b, "tuya-vacuum");
    step_until(&mut h, "two failed attempts", |a| {
        a.station().device.tuya.stopped.is_some() && a.station().device.tuya.attempts >= 2
    });
    h.run_steps(2);
    assert!(has_label(&h, "Handshake stopped at Heartbeat (0x00)"));
    assert!(has_label(&h, "The handshake is tried again every second"));
    tab(&mut h, "Data points");
    assert_eq!(
        h.query_all_by_label("not reported yet").count(),
        19,
        "no data point shows a value the MCU did not report"
    );
}

#[test]
fn an_mcu_restart_is_shown_and_the_handshake_runs_again() {
    let b = bench();
    let mut h = harness(&b, "tuya-vacuum");
    h.step();
    // A short heartbeat, sent to the worker on the next frame.
    let a = app_mut(&mut h);
    a.panel_mut::<TuyaConsolePanel>().opts.heartbeat = Duration::from_millis(300);
    a.panel_mut::<TuyaConsolePanel>().synced = None;
    handshake(&mut h);
    b.sim().restart();
    step_until(&mut h, "the restart and a new handshake", |a| {
        a.station().device.tuya.restarts.0 == 1
            && a.station().device.tuya.done_at.is_some()
            && a.station().device.tuya.attempts >= 2
    });
    h.run_steps(2);
    assert!(has_label(
        &h,
        "the heartbeat answered 0, so the handshake ran again"
    ));
}

#[test]
fn a_bool_and_an_enum_set_from_the_panel_reach_the_mcu_and_their_reports_update_it() {
    let b = bench();
    let mut h = harness(&b, "tuya-vacuum");
    handshake(&mut h);
    tab(&mut h, "Data points");
    assert_eq!(reported(app(&h), 13), Some(Value::Int(0)));
    h.get_by(|n| n.role() == Role::CheckBox && n.label().as_deref() == Some("13 Find robot"))
        .click();
    step_until(&mut h, "find_robot reported on", |a| {
        reported(a, 13) == Some(Value::Int(1))
            && format!("{:?}", a.panel::<TuyaConsolePanel>().dps.marks.get(&13))
                == "Some(Confirmed)"
    });
    assert_eq!(b.sim().dp(13), Some(&DpValue::Bool(true)));
    h.get_by(|n| n.role() == Role::ComboBox && n.label().as_deref() == Some("3 Work mode"))
        .click();
    h.run_steps(2);
    h.get_by_label("Spot clean").click();
    step_until(&mut h, "the mode reported", |a| {
        reported(a, 3) == Some(Value::Int(5))
            && a.panel::<TuyaConsolePanel>().dps.pending.is_empty()
    });
    assert_eq!(b.sim().dp(3), Some(&DpValue::Enum(5)));
    h.run_steps(2);
    // The side effect the MCU reported (status: spot cleaning) is shown too, and logged.
    assert!(h.query_by_label("Spot cleaning").is_some());
    assert!(has_label(&h, "3 Work mode = Spot clean"));
    assert!(has_label(&h, "✓ reported back"));
    // Query status (0x08): every data point is reported again.
    let before = app(&h).station().device.tuya.log_seq;
    h.get_by_label("Query status").click();
    step_until(&mut h, "19 reports", |a| {
        a.station().device.tuya.log_seq >= before + 19
    });
    assert!(app(&h).station().device.tuya.last_query.is_some());
}

fn sent_dp_commands(a: &App) -> usize {
    a.station()
        .packets
        .entries
        .iter()
        .filter_map(|l| l.frame())
        .filter(|e| {
            e.direction == botbench::protocol::Direction::HostToDevice
                && e.frame.as_ref().is_ok_and(|p| p.command == 0x06)
        })
        .count()
}

#[test]
fn a_value_out_of_range_is_refused_before_sending_and_typed_data_points_are_set() {
    let tmp = temp_dir();
    let dir = tmp.path();
    let (profile, b) = writable_profile(dir);
    let mut h = harness(&b, &profile);
    handshake(&mut h);
    tab(&mut h, "Data points");
    assert_eq!(reported(app(&h), 16), Some(Value::Int(350)));
    type_into(&mut h, "16 Clean area", "1200");
    assert!(has_label(
        &h,
        "1200.0 is out of range; allowed 0.0 to 999.9 m²"
    ));
    assert!(h.query_by_label("Send").is_none(), "nothing to send");
    h.key_press(egui::Key::Enter);
    h.run_steps(5);
    assert_eq!(sent_dp_commands(app(&h)), 0, "no 0x06 went out");
    // A valid value of each typed kind goes out and comes back. The link keeps order: had the
    // refused value been sent, the MCU would have taken it before the first of these.
    app_mut(&mut h)
        .panel_mut::<TuyaConsolePanel>()
        .dps
        .edits
        .clear();
    h.run_steps(2);
    let cases: [(&str, &str, u8, Value, DpValue); 4] = [
        (
            "16 Clean area",
            "12.5",
            16,
            Value::Int(125),
            DpValue::Value(125),
        ),
        (
            "15 Clean record",
            "20261122083000",
            15,
            Value::Text("20261122083000".into()),
            DpValue::String("20261122083000".into()),
        ),
        (
            "18 Fault",
            "left_wheel_fault|collision_fault",
            18,
            Value::Int(0x44),
            DpValue::Bitmap {
                bits: 0x44,
                width: 1,
            },
        ),
        (
            "19 Map parameters",
            "01 20 30",
            19,
            Value::Bytes(vec![1, 0x20, 0x30]),
            DpValue::Raw(vec![1, 0x20, 0x30]),
        ),
    ];
    for (label, text, id, value, dp) in cases {
        type_into(&mut h, label, text);
        h.get_by_label("Send").click();
        step_until(&mut h, label, |a| {
            reported(a, id) == Some(value.clone())
                && a.panel::<TuyaConsolePanel>().dps.pending.is_empty()
        });
        assert_eq!(b.sim().dp(id), Some(&dp), "{label}");
        if id == 16 {
            assert_eq!(sent_dp_commands(app(&h)), 1, "only the valid area went out");
        }
        assert_eq!(
            format!(
                "{:?}",
                app(&h).panel::<TuyaConsolePanel>().dps.marks.get(&id)
            ),
            "Some(Confirmed)",
            "{label}"
        );
    }
    h.run_steps(2);
    // The fault bits the MCU reported are lit by name.
    assert!(h.query_by_label("Left wheel fault").is_some());
    assert!(h.query_by_label("Bumper fault").is_some());
}

#[test]
fn the_mcus_requests_are_answered_and_shown_with_a_chosen_time() {
    let b = bench();
    let mut h = harness(&b, "tuya-vacuum");
    handshake(&mut h);
    tab(&mut h, "MCU requests");
    app_mut(&mut h)
        .panel_mut::<TuyaConsolePanel>()
        .requests
        .time_text = "2026-11-22 08:30:15".into();
    h.get_by(|n| n.role() == Role::RadioButton && n.label().as_deref() == Some("chosen time"))
        .click();
    h.run_steps(3);
    assert!(
        app(&h)
            .panel::<TuyaConsolePanel>()
            .opts
            .fixed_time
            .is_some()
    );
    h.run_steps(2);
    {
        let mut m = b.sim();
        m.request_local_time();
        m.reset_wifi();
        m.request_wifi_test();
        m.request_mac();
    }
    step_until(&mut h, "four requests answered", |a| {
        a.station().device.tuya.requests.len() == 4
    });
    h.run_steps(2);
    assert!(has_label(&h, "time 2026-11-22 08:30:15, Sunday"));
    assert!(has_label(&h, "The MCU asked to reset the Wi-Fi, times: 1"));
    assert!(has_label(&h, "passed, signal 80 %"));
    assert!(h.query_by_label("02:b0:7b:00:00:01").is_some());
    // The last answers may still be on the wire.
    wait_until("the MCU to hold four answers", || {
        b.sim().answers().len() >= 4
    });
    let answers = b.sim().answers().to_vec();
    assert!(
        answers.contains(&(0x1c, vec![1, 26, 11, 22, 8, 30, 15, 7])),
        "{answers:?}"
    );
}

/// An MCU after the handshake, and `img` in a file (in the folder returned) chosen on the
/// firmware tab; Start update clicked, so the confirmation shows.
fn update_asked(img: &[u8]) -> (tempfile::TempDir, Bench, H) {
    let tmp = temp_dir();
    let file = tmp.path().join("firmware.bin");
    std::fs::write(&file, img).unwrap();
    let b = bench();
    let mut h = harness(&b, "tuya-vacuum");
    handshake(&mut h);
    tab(&mut h, "Firmware update");
    type_into(&mut h, "Firmware file", &file.display().to_string());
    // The image names no version: the simulator comes back with its own raised (1.0.1).
    type_into(&mut h, "Version after the update", "1.0.1");
    h.get_by_label("Start update").click();
    h.run_steps(2);
    (tmp, b, h)
}

#[test]
fn an_update_from_the_panel_completes_and_the_mcu_holds_the_image() {
    let img = image(3000);
    let (dir, b, mut h) = update_asked(&img);
    assert!(h.query_by_label("Update the MCU firmware?").is_some());
    let typed = dir.path().join("firmware.bin").display().to_string();
    assert_eq!(
        app(&h)
            .settings
            .file(botbench::ui::settings::FileKind::Firmware),
        Some(typed.as_str()),
        "the typed image's path is remembered"
    );
    h.get_by_label("Update").click();
    step_until(&mut h, "the update to end", |a| {
        a.panel::<TuyaConsolePanel>().ota.result.is_some()
    });
    let result = app(&h)
        .panel::<TuyaConsolePanel>()
        .ota
        .result
        .clone()
        .unwrap();
    let report = result.expect("the update succeeds");
    assert_eq!(
        (report.size, report.packet_size, report.packets),
        (3000, 256, 12)
    );
    assert_eq!(
        *b.sim().ota_state(),
        OtaState::Complete {
            size: 3000,
            crc32: crc32(&img)
        }
    );
    assert_eq!(
        (
            report.before_version.as_deref(),
            report.after_version.as_deref()
        ),
        (Some("1.0.0"), Some("1.0.1"))
    );
    h.run_steps(2);
    assert!(has_label(&h, "Update complete"));
    assert!(has_label(&h, "MCU version 1.0.0 → 1.0.1"));
}

#[test]
fn an_empty_or_missing_firmware_file_is_refused_with_a_clear_message() {
    let tmp = temp_dir();
    let dir = tmp.path();
    let empty = dir.join("empty.bin");
    std::fs::write(&empty, b"").unwrap();
    let b = bench();
    let mut h = harness(&b, "tuya-vacuum");
    handshake(&mut h);
    tab(&mut h, "Firmware update");
    // No file named: nothing to start.
    app_mut(&mut h)
        .panel_mut::<TuyaConsolePanel>()
        .ota
        .path
        .clear();
    h.step();
    assert!(
        egui_kittest::kittest::NodeT::accesskit_node(&h.get_by_label("Start update")).is_disabled()
    );
    for (path, why) in [
        (empty.display().to_string(), "the firmware file is empty"),
        (
            dir.join("missing.bin").display().to_string(),
            "No such file",
        ),
    ] {
        app_mut(&mut h).panel_mut::<TuyaConsolePanel>().ota.path = path.clone();
        h.step();
        h.get_by_label("Start update").click();
        h.run_steps(2);
        let err = app(&h)
            .panel::<TuyaConsolePanel>()
            .ota
            .error
            .clone()
            .expect("refused");
        let err = err.to_string();
        assert!(err.contains(&path) && err.contains(why), "{err}");
        assert!(has_label(&h, why));
        assert!(h.query_by_label("Update the MCU firmware?").is_none());
        assert!(app(&h).station().job.is_none(), "no update started");
    }
    assert_eq!(*b.sim().ota_state(), OtaState::Idle);
}

/// A 64 KiB update asked for, confirmed, and under way (its first KiB acked).
fn update_under_way() -> (tempfile::TempDir, Bench, H) {
    let (dir, b, mut h) = update_asked(&image(65_536));
    h.get_by_label("Update").click();
    step_until(&mut h, "some progress", |a| {
        a.panel::<TuyaConsolePanel>()
            .ota
            .progress
            .as_ref()
            .is_some_and(|p| p.done >= 1024)
    });
    (dir, b, h)
}

/// Waits for the update to end, and returns why it failed.
fn update_error(h: &mut H) -> botbench::ui::jobs::JobError {
    step_until(h, "the update to end", |a| {
        a.panel::<TuyaConsolePanel>().ota.result.is_some()
    });
    app(h)
        .panel::<TuyaConsolePanel>()
        .ota
        .result
        .clone()
        .expect("ended")
        .expect_err("failed")
}

#[test]
fn an_update_can_be_cancelled_and_says_where_it_stopped() {
    let (_dir, b, mut h) = update_under_way();
    h.run_steps(1);
    assert!(has_label(&h, "B/s"), "the rate is shown");
    assert!(has_label(&h, "left"), "the time left is shown");
    assert!(has_label(&h, "packets of 256 bytes (asked by the MCU)"));
    h.get_by_label("Cancel update").click();
    let err = update_error(&mut h);
    assert!(err.to_string().contains("cancelled after offset"), "{err}");
    assert!(!matches!(b.sim().ota_state(), OtaState::Complete { .. }));
}

/// A port lost part of the way through an update is no verdict on the MCU: said as a link
/// lost during the update, with where it got to, until the operator dismisses it (issue 25,
/// item 6).
#[test]
fn a_port_lost_during_an_update_is_said_as_a_lost_link_until_dismissed() {
    let (_dir, b, mut h) = update_under_way();
    b.server.vanish_handle().vanish();
    let err = update_error(&mut h);
    h.run_steps(2);
    assert!(
        err.to_string()
            .starts_with("link lost during the update, after offset"),
        "{err}"
    );
    assert!(has_label(&h, "No verdict"), "not an update that failed");
    assert!(!has_label(&h, "Update failed"));
    h.get_by_label("Dismiss").click();
    h.run_steps(2);
    assert!(app(&h).panel::<TuyaConsolePanel>().ota.result.is_none());
    assert!(!has_label(&h, "No verdict"), "dismissed");
}

#[test]
fn every_section_renders_in_english_and_chinese() {
    // A glyph missing from the bundled fonts panics while drawing: draw every section with
    // something in it, in both languages.
    let tmp = temp_dir();
    let dir = tmp.path();
    let (profile, b) = writable_profile(dir);
    let mut h = harness(&b, &profile);
    handshake(&mut h);
    {
        let mut m = b.sim();
        m.set_dp(
            18,
            DpValue::Bitmap {
                bits: 0x7f,
                width: 1,
            },
        );
        m.request_local_time();
        m.reset_wifi_mode(1);
        m.request_wifi_test();
        m.request_net_status();
        m.request_mac();
    }
    step_until(&mut h, "the requests", |a| {
        a.station().device.tuya.requests.len() == 5
    });
    tab(&mut h, "Data points");
    type_into(&mut h, "16 Clean area", "-5");
    app_mut(&mut h).panel_mut::<TuyaConsolePanel>().ota.error = Some(FirmwareFileError::Empty {
        path: "firmware.bin".into(),
    });
    for (lang, tabs) in [
        (Lang::Zh, ["握手", "数据点", "MCU请求", "固件升级"]),
        (
            Lang::En,
            [
                "Handshake",
                "Data points",
                "MCU requests",
                "Firmware update",
            ],
        ),
    ] {
        app_mut(&mut h).settings.lang = lang;
        h.run_steps(2);
        for t in tabs {
            tab(&mut h, t);
        }
    }
    assert!(has_label(&h, "firmware file is empty"));
}

/// A time as the console shows it.
fn shown(t: &chrono::DateTime<chrono::Local>) -> String {
    t.format("%H:%M:%S%.3f").to_string()
}

/// Issue 25, item 10: each handshake step has its own time (when it ended, as the link saw it)
/// and how long it took from its request, however late the window takes the news. Here the
/// window draws no frame until the MCU, answering each request 30 ms late, has been asked the
/// Wi-Fi state: the first steps' news is read in one frame (before, they all showed that
/// frame's time).
#[test]
fn each_handshake_step_shows_its_own_time_and_how_long_it_took() {
    let latency = Duration::from_millis(30);
    let b = bench_with(
        TuyaMcu::new(TuyaConfig {
            latency,
            ..config()
        }),
        Faults::default(),
    );
    let mut h = harness(&b, "tuya-vacuum");
    wait_until("the MCU to be told the Wi-Fi state", || {
        b.sim().wifi_state().is_some()
    });
    handshake(&mut h);
    let steps: Vec<_> = app(&h)
        .station()
        .device
        .tuya
        .steps
        .iter()
        .map(|s| s.clone().expect("every step done"))
        .collect();
    // Each step's answer comes at least the MCU's latency after the last one's.
    for pair in steps.windows(2) {
        let gap = (pair[1].at - pair[0].at).to_std().unwrap_or_default();
        assert!(
            gap >= latency,
            "each step its own time: {} then {}",
            shown(&pair[0].at),
            shown(&pair[1].at)
        );
    }
    for s in &steps {
        let at = shown(&s.at);
        assert!(h.query_all_by_label(&at).next().is_some(), "{at} shown");
        let took = s.took.expect("each step sent its request");
        assert!(
            took >= latency,
            "{took:?}: the MCU answers {latency:?} late"
        );
        let ms = format!("{:.0} ms", took.as_secs_f64() * 1e3);
        assert!(h.query_all_by_label(&ms).next().is_some(), "{ms} shown");
    }
    assert!(h.query_by_label("Took").is_some());
}

/// Issue 25, item 10: each MCU request has its own time, when the module took it, however late
/// the window takes the news (before, both showed the time of the frame that read them).
#[test]
fn each_mcu_request_shows_the_time_it_was_answered() {
    let b = bench();
    let mut h = harness(&b, "tuya-vacuum");
    handshake(&mut h);
    tab(&mut h, "MCU requests");
    let answered = b.sim().answers().len();
    b.sim().request_local_time();
    wait_until("the MCU to have the time", || {
        b.sim().answers().len() > answered
    });
    let between = chrono::Local::now();
    b.sim().request_mac();
    wait_until("the MCU to have the MAC", || {
        b.sim().answers().len() > answered + 1
    });
    step_until(&mut h, "two requests answered", |a| {
        a.station().device.tuya.requests.len() == 2
    });
    h.run_steps(2);
    let requests = app(&h).station().device.tuya.requests.clone();
    assert!(
        requests[0].clock <= between && between <= requests[1].clock,
        "the time asked {} before {} before the MAC asked {}",
        shown(&requests[0].clock),
        shown(&between),
        shown(&requests[1].clock)
    );
    for r in &requests {
        assert!(h.query_all_by_label(&shown(&r.clock)).next().is_some());
    }
}
