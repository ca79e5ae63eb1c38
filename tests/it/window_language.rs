//! In 中文 the window says what happens in Chinese: every status-line message and every job's
//! title and progress, through a technician's usual work on the demo devices (connect, ping,
//! read the version, read every parameter, export, copy, scan a servo bus, disconnect) and a
//! device that never answers.

use botbench::i18n::Lang;
use botbench::link::PortOpener;
use botbench::sim::{Faults, SimKind};
use botbench::ui::{App, PanelId, Settings, Target};
use egui_kittest::kittest::Queryable;
use std::cell::RefCell;

use crate::support::gui::{H, app_mut, harness_with, settings, step_until};
use crate::support::{serve_with, window_cleaner};

/// The first run of three or more English words in `text` (what an untranslated sentence
/// leaves in Chinese), if any. Names, units and numbers (`MCU`, `ms`, `0x03`, `/dev/pts/3`)
/// stand alone and are not a sentence.
fn english_sentence(text: &str) -> Option<String> {
    let letter = |c: char| c.is_ascii_alphabetic() || c == '\'' || c == '-';
    let (mut run, mut longest): (Vec<&str>, Vec<&str>) = (Vec::new(), Vec::new());
    let mut rest = text;
    while !rest.is_empty() {
        // The next word, and what stands between it and the one before.
        let start = rest.find(letter).unwrap_or(rest.len());
        let (between, from) = rest.split_at(start);
        let end = from.find(|c: char| !letter(c)).unwrap_or(from.len());
        let (word, after) = from.split_at(end);
        if between != " " {
            run.clear();
        }
        if word.len() >= 2 && word.starts_with(|c: char| c.is_ascii_alphabetic()) {
            run.push(word);
        } else {
            run.clear();
        }
        if run.len() > longest.len() {
            longest = run.clone();
        }
        rest = after;
    }
    (longest.len() >= 3).then(|| longest.join(" "))
}

#[test]
fn the_english_sentence_check_finds_a_sentence_and_passes_names_and_units() {
    assert_eq!(
        english_sentence("版本:version and power state read"),
        Some("version and power state read".into())
    );
    assert_eq!(
        english_sentence("已连接 simulated solar cleanbot,波特率 115200"),
        Some("simulated solar cleanbot".into())
    );
    assert_eq!(english_sentence("已连接 /dev/pts/3,波特率 115200"), None);
    assert_eq!(english_sentence("通讯检测:1.2 ms 内应答"), None);
    assert_eq!(english_sentence("MCU 已重启"), None);
}

/// Takes what `a` shows in Chinese now (its status line, its job's title and progress) into
/// `seen`, once each.
fn take(seen: &mut Vec<String>, a: &App) {
    let mut now = Vec::new();
    if let Some(n) = &a.station().notice {
        now.push(n.text_in(Lang::Zh).to_string());
    }
    if let Some((title, _, msg)) = a.station().job_progress() {
        now.push(title.zh.clone());
        now.push(msg.zh.clone());
    }
    for s in now {
        if !s.is_empty() && !seen.contains(&s) {
            seen.push(s);
        }
    }
}

/// What the window said in Chinese while stepping: status lines, job titles and progress.
#[derive(Default)]
struct Said(Vec<String>);

impl Said {
    /// Steps until `done`, taking what is said on every frame.
    fn step_until(&mut self, h: &mut H, what: &str, done: impl Fn(&App) -> bool) {
        let seen = RefCell::new(std::mem::take(&mut self.0));
        step_until(h, what, |a| {
            take(&mut seen.borrow_mut(), a);
            done(a)
        });
        self.0 = seen.into_inner();
    }

    fn english(&self) -> Vec<String> {
        self.0
            .iter()
            .filter_map(|s| english_sentence(s).map(|e| format!("{s:?} ({e:?})")))
            .collect()
    }
}

fn notice_has(a: &App, zh: &str) -> bool {
    a.station()
        .notice
        .as_ref()
        .is_some_and(|n| n.zh.contains(zh))
}

fn demo(kind: SimKind, panel: PanelId) -> H {
    let mut saved = Settings {
        target: Target::Demo(kind.name().to_string()),
        profile: kind.profile_id().to_string(),
        panel,
        lang: Lang::Zh,
        ..Settings::default()
    };
    saved.port_mut().baud = Some(kind.default_baud());
    harness_with(saved, PortOpener::system(), |_| {})
}

#[test]
fn in_chinese_a_technicians_day_on_the_window_cleaner_is_said_in_chinese() {
    let mut said = Said::default();
    let mut h = demo(SimKind::WindowCleaner, PanelId::DEVICE);
    said.step_until(&mut h, "the first read", |a| {
        a.station().device.info.is_some() && a.station().job_progress().is_none()
    });
    for (button, done) in [("通讯检测", "通讯检测:"), ("读取版本与电源状态", "版本:")]
    {
        h.get_by_label(button).click();
        said.step_until(&mut h, button, |a| {
            notice_has(a, done) && a.station().job_progress().is_none()
        });
    }
    app_mut(&mut h).settings.panel = PanelId::TUNING;
    h.run_steps(2);
    h.get_by_label("全部读取").click();
    said.step_until(&mut h, "every parameter read", |a| {
        notice_has(a, "读取:") && a.station().job_progress().is_none()
    });
    app_mut(&mut h).settings.panel = PanelId::TELEMETRY;
    h.run_steps(2);
    h.get_by_label("导出 CSV").click();
    said.step_until(&mut h, "the export refused", |a| notice_has(a, "导出"));
    app_mut(&mut h).settings.panel = PanelId::MONITOR;
    h.run_steps(2);
    h.get_by_label("复制").click();
    said.step_until(&mut h, "the frames copied", |a| notice_has(a, "复制"));
    h.get_by_label("断开").click();
    said.step_until(&mut h, "disconnected", |a| notice_has(a, "已断开"));
    assert!(said.0.len() >= 8, "{:?}", said.0);
    assert!(
        said.english().is_empty(),
        "English in 中文: {:?}",
        said.english()
    );
}

#[test]
fn in_chinese_a_silent_device_and_a_servo_scan_are_said_in_chinese() {
    let mut said = Said::default();
    let silent = serve_with(
        window_cleaner(),
        Faults {
            silent: true,
            ..Faults::default()
        },
    );
    let mut saved = settings(silent.path(), "window-cleaner", PanelId::TUNING, Lang::Zh);
    saved.port_mut().margin_ms = Some(5);
    let mut h = harness_with(saved, silent.ports(), |_| {});
    // On connecting, the tuning panel's values are read: none answers.
    said.step_until(&mut h, "the first read to fail", |a| {
        a.station().notice.as_ref().is_some_and(|n| n.error) && a.station().job_progress().is_none()
    });
    assert!(
        said.english().is_empty(),
        "English in 中文: {:?}",
        said.english()
    );

    let mut h = demo(SimKind::ServoBus, PanelId::SERVO_BENCH);
    said.step_until(&mut h, "connected", |a| a.station().connected());
    h.get_by_label("扫描").click();
    said.step_until(&mut h, "the scan", |a| {
        notice_has(a, "扫描:") && a.station().job_progress().is_none()
    });
    assert!(
        said.english().is_empty(),
        "English in 中文: {:?}",
        said.english()
    );
    assert!(said.0.iter().any(|s| s.contains("找到")), "{:?}", said.0);
}

#[test]
fn in_chinese_the_other_telemetry_names_its_fields_not_their_wire_names() {
    let mut h = demo(SimKind::SolarCleanbot, PanelId::TELEMETRY);
    step_until(&mut h, "the rangefinder read", |a| {
        a.station()
            .device
            .profile
            .command("CMD_RANGEFINDER")
            .and_then(|c| a.station().device.readings.get(&c.id))
            .is_some()
    });
    h.run_steps(2);
    let app = h.state().as_ref().expect("app");
    let cmd = app
        .station()
        .device
        .profile
        .command("CMD_RANGEFINDER")
        .unwrap();
    let shown: Vec<String> = h
        .output()
        .shapes
        .iter()
        .filter_map(|c| match &c.shape {
            eframe::egui::Shape::Text(t) => Some(t.galley.text().to_string()),
            _ => None,
        })
        .filter(|t| t.contains(&cmd.reply[0].name.zh))
        .collect();
    assert!(
        !shown.is_empty(),
        "the rangefinder's values are shown by name"
    );
    for f in &cmd.reply {
        for text in &shown {
            assert!(
                !text.contains(&f.ident),
                "{text:?} holds the wire name {}",
                f.ident
            );
        }
    }
}
