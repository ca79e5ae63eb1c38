//! Issue 25, item 10, "the truth in small places": the real app through egui_kittest against
//! the simulated window cleaner on a pty. The Device panel's last answer is the device's last
//! answer on the link; a silent device gets the command line's checklist; the packet monitor
//! lists each unanswered attempt as a row of its own. (The top bar's baud after a servo's baud
//! change: `gui_servo_setup`; the Tuya console's times: `gui_tuya`.)

use botbench::i18n::Lang;
use botbench::sim::Faults;
use botbench::ui::PanelId;
use botbench::ui::device::DevicePanel;
use botbench::ui::monitor::MonitorPanel;
use egui_kittest::kittest::Queryable;

use crate::support::gui::{self, H, app, app_mut, idle, step_until};
use crate::support::{PATIENCE, Port, serve_with, temp_dir, window_cleaner};

/// The app on the window cleaner at `port` showing `panel`, with 100 ms for the device to start
/// answering: generous for a loaded test machine.
fn harness(port: &impl Port, panel: PanelId) -> H {
    gui::on_window_cleaner(port, panel, Some(100))
}

/// The text of the first label that contains `part`, if one is shown (a label's text is its
/// AccessKit value; a widget's, its label).
fn label_with(h: &H, part: &str) -> Option<String> {
    h.query_all_by_label_contains(part).next().and_then(|n| {
        let node = egui_kittest::kittest::NodeT::accesskit_node(&n);
        node.label().or_else(|| node.value())
    })
}

/// Steps the UI until a label containing `part` is shown, and returns its text; fails after
/// [`PATIENCE`].
fn step_until_shown(h: &mut H, part: &str) -> String {
    let deadline = std::time::Instant::now() + PATIENCE;
    loop {
        h.step();
        if let Some(text) = label_with(h, part) {
            return text;
        }
        assert!(
            std::time::Instant::now() < deadline,
            "timed out waiting for a label with '{part}'"
        );
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
}

/// The Device panel's "last answer" moves on while telemetry polls answer, with no job of the
/// panel's own running (it was set when one of the panel's jobs ended, and stood still).
#[test]
fn the_device_panels_last_answer_moves_on_with_the_polls_answers() {
    let b = serve_with(window_cleaner(), Faults::default());
    let mut h = harness(&b, PanelId::DEVICE);
    // The panel reads the version and power state once: wait for that job to end.
    step_until(&mut h, "the panel's own read done", |a| {
        idle(a) && a.panel::<DevicePanel>().power.is_some()
    });
    let first = step_until_shown(&mut h, "last answer");
    // `last answer HH:MM:SS.mmm (N s ago)`: the time of the answer, not the seconds since.
    let clock = |t: &str| t.split_whitespace().nth(2).map(str::to_string);
    let deadline = std::time::Instant::now() + PATIENCE;
    loop {
        h.step();
        let now = label_with(&h, "last answer").expect("the last answer stays shown");
        if clock(&now) != clock(&first) {
            break;
        }
        assert!(
            std::time::Instant::now() < deadline,
            "the last answer stood at '{first}' while the device answered polls"
        );
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    assert!(idle(app(&h)), "no job ran meanwhile");
}

/// A device that does not answer gets, in the Device panel, the checklist the command line
/// gives (power, wiring, baud, profile, and a board that reboots on open when no boot wait is
/// set), naming the window's fields, in English and in Chinese.
#[test]
fn a_silent_device_gets_the_command_lines_checklist_in_both_languages() {
    let silent = Faults {
        silent: true,
        ..Faults::default()
    };
    let b = serve_with(window_cleaner(), silent);
    let mut h = harness(&b, PanelId::DEVICE);
    let said = step_until_shown(&mut h, "nothing answered: is the device powered");
    for part in [
        "its TX wired to the adapter's RX (and RX to TX, GND to GND)",
        "at this baud rate (the bar's Baud)",
        "Or is it a board that reboots when the port opens",
        "Port options › Boot wait 2000 ms",
    ] {
        assert!(said.contains(part), "'{part}' in: {said}");
    }
    assert!(label_with(&h, "The device does not answer").is_some());
    app_mut(&mut h).settings.lang = Lang::Zh;
    let zh = step_until_shown(&mut h, "无应答:设备是否通电");
    assert!(zh.contains("端口选项 › 开机等待 2000 ms"), "{zh}");
    assert!(!zh.contains("nothing answered"), "{zh}");
}

/// The packet monitor lists each attempt no frame answered as a row of its own (a simulator
/// dropping a third of its frames), filtered by its request's command as the other rows are,
/// in both languages and in the saved log.
#[test]
fn the_packet_monitor_lists_unanswered_attempts_as_rows_filtered_and_saved() {
    let lossy = Faults {
        drop: 0.3,
        seed: 11,
        ..Faults::default()
    };
    let b = serve_with(window_cleaner(), lossy);
    let mut h = harness(&b, PanelId::MONITOR);
    let row = step_until_shown(&mut h, "no answer to ");
    assert!(
        row.contains(" ms, attempt ") && row.contains(" of "),
        "{row}"
    );
    h.get_by_label("Pause").click();
    h.run_steps(2);
    // The command it names, as the filter takes it.
    let rest = row.split("no answer to ").nth(1).expect("the row's words");
    let name = rest.split_whitespace().next().expect("a command name");
    app_mut(&mut h).panel_mut::<MonitorPanel>().filter = name.to_string();
    h.run_steps(2);
    assert!(
        label_with(&h, &format!("no answer to {name}")).is_some(),
        "the filter keeps {name}'s unanswered rows"
    );
    app_mut(&mut h).panel_mut::<MonitorPanel>().filter = "0xfe".to_string();
    h.run_steps(2);
    assert!(
        label_with(&h, "no answer to").is_none(),
        "no row of another command"
    );
    app_mut(&mut h).panel_mut::<MonitorPanel>().filter = name.to_string();
    h.run_steps(2);

    let dir = temp_dir();
    let path = dir.path().join("packets.txt");
    app_mut(&mut h).panel_mut::<MonitorPanel>().save_path = path.display().to_string();
    h.get_by_label("Save").click();
    h.run_steps(2);
    let saved = std::fs::read_to_string(&path).expect("the log saved");
    assert!(saved.starts_with("# botbench packet log"), "{saved}");
    assert!(
        saved.contains(&format!("no answer to {name}")),
        "the saved log holds the unanswered rows:\n{saved}"
    );

    app_mut(&mut h).settings.lang = Lang::Zh;
    h.run_steps(2);
    assert!(
        label_with(&h, "无应答,已等待").is_some(),
        "the row in Chinese"
    );
}

/// A device silent while this computer is held up past every answer's deadline (issue 25, item
/// 4e): the Device panel's checklist leads with the loaded computer and asks about the wiring
/// only for a device that still does not answer with the computer idle, in both languages
/// (before: the wiring checklist alone, as for a device unplugged).
#[test]
fn a_silent_device_on_a_held_up_computer_is_said_loaded_first() {
    let silent = Faults {
        silent: true,
        ..Faults::default()
    };
    let b = serve_with(window_cleaner(), silent);
    let mut h = harness(&crate::support::held_up::HeldUpPort(&b), PanelId::DEVICE);
    let said = step_until_shown(&mut h, "if it still does not answer with the computer idle");
    let late = said.find("this computer was held up ");
    let wiring =
        said.find("if it still does not answer with the computer idle: is the device powered");
    assert!(
        late.is_some() && wiring.is_some() && late < wiring,
        "the loaded computer leads: {said}"
    );
    app_mut(&mut h).settings.lang = Lang::Zh;
    let zh = step_until_shown(&mut h, "若电脑空闲时仍无应答");
    assert!(!zh.contains("held up"), "{zh}");
}
