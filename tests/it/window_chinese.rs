//! Issue 25, item 11: in 中文 no English is left on screen. Every view of the four demo devices,
//! a self-test run (its step names, what each step read and measured, its verdict), the Tuya
//! console's misfits and report log: every text the window draws is searched for English words
//! ([`english_words`]); names the wire, the units and the products carry are not English
//! ([`NAMES`]).

use botbench::i18n::Lang;
use botbench::sim::tuya_mcu::{RawValue, TuyaConfig, TuyaMcu, WireForm};
use botbench::sim::{Faults, SimKind};
use botbench::ui::PanelId;
use botbench::ui::selftest::SelfTestPanel;
use eframe::egui;
use egui_kittest::kittest::Queryable;
use std::collections::{BTreeMap, BTreeSet};

use crate::support::gui::{H, app, app_mut, harness, settings, step_until};
use crate::support::{serve, serve_with, temp_dir};
use crate::window_layout::{demo, prepare, texts};

/// Latin-letter words that are names, not English: units, products, protocols, and the
/// acronyms a technician reads as they are in both languages. Compared without case.
#[rustfmt::skip]
const NAMES: &[&str] = &[
    // Units.
    "rpm", "deg", "bps", "kbps", "mah", "kpa", "fps", "min",
    // Products and formats.
    "botbench", "tuya", "fashionstar", "noto", "smartconfig", "wifi", "json", "csv", "ron",
    "sqlite", "pcapng", "cpk", "utf", "ttc", "otf",
    // Acronyms.
    "mcu", "pid", "adc", "pwm", "gpio", "ota", "rssi", "crc", "msp", "api", "imu", "led", "usb",
    "dtr", "rts", "sdk", "hex", "dps", "fpy", "mac",
    // A verdict as the line reads it in both languages.
    "pass", "fail",
    // The language switch names the other language in its own words.
    "english",
    // A command of the servo protocol (the others have a `_` in them).
    "ping",
    // Ports.
    "dev", "pts", "tty", "ttyusb", "ttyacm", "com",
];

/// The English words in `text`: words of three or more Latin letters, lower-case or capitalised
/// or in capitals (`expected`, `Battery`, `WRONG`), that are not [`NAMES`]. Names of the wire
/// and of files are not words: a word with a digit or `_` in it or a capital inside it
/// (`MSP_SET_FAN`, `batteryVoltage`, `0x1c`), and anything joined to a path, a file's extension
/// or an `=` (`/dev/pts/3`, `telemetry.csv`, `MSP_SET_FAN.pwm`, `pwm=0`).
pub(crate) fn english_words(text: &str) -> Vec<String> {
    let mut found = Vec::new();
    for chunk in text.split(|c: char| c.is_whitespace() || !c.is_ascii()) {
        let named = chunk.contains(['/', '\\', '=', '@'])
            || chunk
                .as_bytes()
                .windows(2)
                .any(|w| w[0] == b'.' && w[1].is_ascii_alphabetic());
        if named {
            continue;
        }
        for word in chunk.split(|c: char| !c.is_ascii_alphanumeric() && c != '_') {
            let letters = word.len() >= 3 && word.chars().all(|c| c.is_ascii_alphabetic());
            let rest = word.get(1..).unwrap_or("");
            let one_case = rest.chars().all(|c| c.is_ascii_lowercase())
                || word.chars().all(|c| c.is_ascii_uppercase());
            let name = NAMES.iter().any(|n| n.eq_ignore_ascii_case(word));
            if letters && one_case && !name {
                found.push(word.to_string());
            }
        }
    }
    found
}

#[test]
fn the_english_word_check_finds_words_and_passes_names() {
    assert_eq!(
        english_words("电池电压 12.6 V (allowed 11.5 V to 16.8 V)"),
        ["allowed"]
    );
    assert_eq!(english_words("adcFan 35 → 36 NO RISE"), ["RISE"]);
    assert_eq!(english_words("Reads status"), ["Reads", "status"]);
    assert!(english_words("MSP_SET_FAN pwm=0:已发送").is_empty());
    assert!(english_words("batteryVoltage 12.6 V,/dev/pts/3,telemetry.csv").is_empty());
    assert!(english_words("PASS 合格 MCU 0x1c Tuya WiFi Cpk 1.33 JSON").is_empty());
    assert!(english_words("hw 0x03 fw 1.4.2 ms Hz").is_empty());
}

/// The English words each text drawn now holds: `text → words`.
fn english_drawn(h: &H, seen: &mut BTreeMap<String, BTreeSet<String>>, view: &str) {
    // A preset's note is the file's own words, shown as written.
    let note = app(h)
        .panel::<botbench::ui::presets::PresetsPanel>()
        .loaded
        .as_ref()
        .map(|l| l.preset.note.clone());
    for (text, ..) in texts(h) {
        if Some(&text) == note.as_ref() {
            continue;
        }
        let words = english_words(&text);
        if !words.is_empty() {
            seen.entry(format!("{view}: {text:?}"))
                .or_default()
                .extend(words);
        }
    }
}

fn report(seen: &BTreeMap<String, BTreeSet<String>>) -> String {
    seen.iter()
        .map(|(text, words)| {
            format!(
                "{text} ({})",
                words.iter().cloned().collect::<Vec<_>>().join(", ")
            )
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn in_chinese_every_view_of_every_demo_device_draws_no_english_word() {
    let mut seen = BTreeMap::new();
    for kind in SimKind::ALL {
        let mut h = demo(kind, Lang::Zh, egui::vec2(1280.0, 800.0));
        prepare(&mut h, kind);
        for view in app(&h).views() {
            app_mut(&mut h).show_view(&view);
            h.run_steps(3);
            english_drawn(&h, &mut seen, &format!("{} {}", kind.name(), view.name));
        }
    }
    assert!(seen.is_empty(), "English in 中文:\n{}", report(&seen));
}

#[test]
fn in_chinese_a_self_test_run_says_its_steps_reads_measurements_and_verdict_in_chinese() {
    let mut wc = crate::support::window_cleaner();
    wc.set_flags(Some(0x0F));
    wc.inject(botbench::sim::window_cleaner::Fault::FanCurrentStuck);
    let b = serve(wc);
    let mut h = harness(
        settings(b.path(), "window-cleaner", PanelId::SELF_TEST, Lang::Zh),
        b.ports(),
    );
    let dir = temp_dir();
    let plan = dir.path().join("plan.ron");
    std::fs::write(&plan, crate::support::selftest_plan(60_000)).unwrap();
    step_until(&mut h, "the device identified", |a| {
        a.station().connected()
            && matches!(a.station().device.info, Some(Ok(_)))
            && a.station().job_progress().is_none()
    });
    {
        let a = app_mut(&mut h);
        a.panel_mut::<SelfTestPanel>().path = plan.display().to_string();
        a.panel_mut::<SelfTestPanel>().log_path =
            dir.path().join("log.jsonl").display().to_string();
    }
    h.step();
    h.get_by_label("打开方案").click();
    h.run_steps(2);
    let mut seen = BTreeMap::new();
    english_drawn(&h, &mut seen, "the plan");
    h.get_by_label("运行自检").click();
    step_until(&mut h, "the operator prompt", |a| {
        a.panel::<SelfTestPanel>().prompt.is_some()
    });
    h.run_steps(2);
    english_drawn(&h, &mut seen, "the prompt");
    b.sim().set_corners(0b1111);
    h.get_by_label("完成").click();
    step_until(&mut h, "the report", |a| {
        a.station().verdicts.selftest.is_some() && !a.panel::<SelfTestPanel>().running
    });
    h.run_steps(3);
    assert!(!app(&h).station().verdicts.selftest.as_ref().unwrap().pass);
    english_drawn(&h, &mut seen, "the report");
    assert!(seen.is_empty(), "English in 中文:\n{}", report(&seen));
}

#[test]
fn in_chinese_the_tuya_consoles_misfits_and_report_log_are_chinese() {
    let b = serve_with(
        TuyaMcu::new(TuyaConfig {
            baud: Some(115_200),
            report_out_of_range: BTreeMap::from([(6, RawValue::Int(150))]),
            misreport: BTreeMap::from([(3, WireForm { ty: 2, len: 4 })]),
            ..TuyaConfig::default()
        }),
        Faults::default(),
    );
    let mut saved = settings(b.path(), "tuya-vacuum", PanelId::TUYA_CONSOLE, Lang::Zh);
    saved.port_mut().baud = Some(115_200);
    let mut h = harness(saved, b.ports());
    step_until(&mut h, "the misfits reported", |a| {
        let t = &a.station().device.tuya;
        t.done_at.is_some() && t.misfits.contains_key(&6) && t.misfits.contains_key(&3)
    });
    let mut seen = BTreeMap::new();
    for view in app(&h).views() {
        app_mut(&mut h).show_view(&view);
        h.run_steps(3);
        english_drawn(&h, &mut seen, &view.name);
    }
    assert!(seen.is_empty(), "English in 中文:\n{}", report(&seen));
}

/// Issue 25, item 11: a command that moves the robot asks first, and in 中文 its dialog says
/// what it sends by the fields' and values' Chinese names (电机:前进), not the wire's English
/// ones (motor=forward): every such command of the window cleaner's Actions panel.
#[test]
fn in_chinese_each_confirmation_says_what_it_sends_in_chinese() {
    let mut seen = BTreeMap::new();
    let mut said = Vec::new();
    let kind = SimKind::WindowCleaner;
    let mut h = demo(kind, Lang::Zh, egui::vec2(1280.0, 800.0));
    let view = app(&h)
        .views()
        .into_iter()
        .find(|v| v.panel == PanelId::ACTIONS)
        .expect("the Actions panel");
    app_mut(&mut h).show_view(&view);
    h.run_steps(3);
    // The values to send: a fan PWM typed, the motor's direction chosen.
    crate::support::gui::type_into(&mut h, "风机占比", "60");
    h.get_by_role_and_label(egui::accesskit::Role::ComboBox, "马达")
        .click();
    h.run_steps(2);
    h.get_by_label_contains("前进").click();
    h.run_steps(3);
    let asking = h.query_all_by_label("⚠ 发送…").count();
    assert!(asking >= 2, "commands that ask first: {asking}");
    for i in 0..asking {
        // A job under way (the demo's first reads) keeps Send off.
        step_until(&mut h, "no job running", crate::support::gui::idle);
        h.run_steps(2);
        h.query_all_by_label("⚠ 发送…")
            .nth(i)
            .expect("the same buttons")
            .click();
        h.run_steps(3);
        assert!(
            texts(&h).iter().any(|(t, ..)| t == "机器人将会动作"),
            "dialog {i}: {:?}",
            texts(&h).iter().map(|t| t.0.clone()).collect::<Vec<_>>()
        );
        english_drawn(&h, &mut seen, &format!("confirmation {i}"));
        said.extend(
            texts(&h)
                .into_iter()
                .map(|t| t.0)
                .filter(|t| t.starts_with("控制")),
        );
        h.get_by_label("取消").click();
        h.run_steps(3);
        assert!(
            !texts(&h).iter().any(|(t, ..)| t == "机器人将会动作"),
            "closed"
        );
    }
    assert!(seen.is_empty(), "English in 中文:\n{}", report(&seen));
    for what in ["控制风机——风机占比:60 %", "控制马达——马达:前进"] {
        assert!(said.iter().any(|t| t == what), "{what} not in {said:?}");
    }
}
