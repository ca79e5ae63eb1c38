//! A failed step's reason on a 中文 station tile (issue 27): each kind of reason the demo
//! station and the shipped plans can produce, carried typed from the slot's runner, reads in
//! Chinese on the FAIL banner, with its values (numbers, units, field idents, wire names) as
//! they are and no English words left; the slot history and a retry question too.

use botbench::i18n::Lang;
use botbench::link::{CommandName, ExchangeError};
use botbench::ops::OpError;
use botbench::ops::records::Measurement;
use botbench::ops::station::{self, Reason, What};
use botbench::ui::line::LineStation;
use eframe::egui;
use egui_kittest::Harness;
use egui_kittest::kittest::{NodeT, Queryable};

/// The demo bundle's window in 中文 with no slot running: its events come from the test.
fn chinese_window() -> (
    Harness<'static, LineStation>,
    crossbeam_channel::Sender<station::Event>,
) {
    let bundle = crate::support::demo_bundle();
    let (tx, rx) = crossbeam_channel::unbounded();
    let mut st = LineStation::new(&bundle, Vec::new(), rx);
    st.sounder = Box::new(botbench::ui::line::sound::Silent);
    st.lang = Lang::Zh;
    let h = crate::support::gui::line_station_harness(st, egui::vec2(1280.0, 800.0));
    (h, tx)
}

fn event(what: What) -> station::Event {
    station::Event {
        slot: "1".into(),
        what,
    }
}

fn fail(reason: Reason) -> station::Event {
    event(What::Verdict {
        pass: false,
        serial: Some("WC000123".into()),
        failed_step: Some("Self-test (window-cleaner-selftest)".into()),
        failed_step_zh: Some("自检".into()),
        reason: Some(reason),
        earlier_runs: None,
        record: "r".into(),
        kept: "record saved".into(),
        stored: true,
    })
}

/// Each kind of reason, with the words of its values that may stay in ASCII (idents, units,
/// wire names).
fn every_reason() -> Vec<(Reason, &'static [&'static str])> {
    let spray = spray_current_too_low();
    let first: Vec<(Reason, &'static [&'static str])> = vec![
        (Reason::HardwareNotAllowed { hw: 4 }, &[]),
        (
            Reason::FirmwareNotAllowed {
                firmware: "1.4.1".into(),
            },
            &[],
        ),
        (Reason::NoAnswer, &[]),
        (
            Reason::NoAnswerTo {
                command: "CMD_BATTERY".into(),
            },
            &[],
        ),
        (Reason::LinkLost, &[]),
        (
            Reason::LinkLostBecause {
                why: "/dev/ttyUSB0".into(),
            },
            &["dev", "ttyUSB0"],
        ),
        (
            Reason::LinkLostDuring {
                step: "Write result".into(),
                step_zh: "写入结果".into(),
            },
            &[],
        ),
        (Reason::Cancelled, &[]),
        (Reason::OperatorAborted, &[]),
        (Reason::NotAnsweredInTime, &[]),
        (Reason::OperatorSaidNo, &[]),
        (Reason::NotYesNo, &[]),
        (Reason::NoSerialScanned, &[]),
        (Reason::SerialMismatch, &[]),
        (Reason::NotAValue, &[]),
        (Reason::NotANumber, &[]),
        (
            Reason::OutOfLimits {
                values: vec![spray],
            },
            &["sprayCurrent", "A"],
        ),
        (
            Reason::UnexpectedValue {
                fields: vec!["workMode".into()],
            },
            &["workMode"],
        ),
        (
            Reason::NotToggled {
                field: "cornerLeft".into(),
            },
            &["cornerLeft"],
        ),
    ];
    first.into_iter().chain(more_reasons()).collect()
}

/// The rest of [`every_reason`]: the servo's, the Tuya MCU's, the writes', provisioning's
/// and the operations' errors.
fn more_reasons() -> Vec<(Reason, &'static [&'static str])> {
    let provision = |step: &str, why: &str| Reason::Provision {
        step: step.into(),
        why: why.into(),
    };
    let check = |id: &str, name: &str| Reason::Conformance {
        id: id.into(),
        name: name.into(),
    };
    let timeout = ExchangeError::Timeout {
        command: CommandName {
            id: 1,
            ident: Some("CMD_VERSION".into()),
        },
        attempts: 3,
        waited_ms: 300,
        host_late: None,
    };
    vec![
        (Reason::NoServo, &[]),
        (Reason::NotRun, &[]),
        (Reason::ProductInfoUnreadable, &[]),
        (Reason::DataPointsMissing, &[]),
        (Reason::NoResultCommand, &[]),
        (Reason::ReadBackDiffers { fields: vec![] }, &[]),
        (
            Reason::ReadBackDiffers {
                fields: vec!["maxSpeed".into()],
            },
            &["maxSpeed"],
        ),
        (
            check("heartbeat", "heartbeat (0x00) answered 00/01 within 3 s"),
            &[],
        ),
        (check("answer_time", "every answer within 5 s"), &[]),
        (
            check(
                "status_range",
                "each reported value within its data point's limits",
            ),
            &[],
        ),
        (
            check(
                "ota",
                "firmware update proven (0x0a/0x0b, then 0x01 names the version)",
            ),
            &[],
        ),
        (
            provision("detect", "no fresh servo (id 0) answers at any baud rate"),
            &[],
        ),
        (
            provision(
                "set baud",
                "servo 1 did not answer at 115200 baud (no answer to PING (1) after 3 attempt(s) of 50 ms)",
            ),
            &[],
        ),
        (
            provision("verify", "2 value(s) do not read back as written"),
            &[],
        ),
        (
            provision("assign id", "no free id left in the plan's ids"),
            &[],
        ),
        // Milliseconds, as units are said in 中文 too.
        (Reason::Error(OpError::Exchange(timeout)), &["ms"]),
        (
            Reason::Error(OpError::ImageTooLarge {
                size: 70000,
                max: 65536,
            }),
            &[],
        ),
        (Reason::Error(OpError::EmptyImage), &[]),
    ]
}

/// The ASCII words of `text` (letters, digits, `_`), less numbers, hex codes, wire names
/// (upper case and `_`, e.g. CMD_VERSION, MCU, ID) and the `allowed` values.
fn english_words(text: &str, allowed: &[&str]) -> Vec<String> {
    text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .filter(|w| w.chars().any(|c| c.is_ascii_alphabetic()))
        .filter(|w| !w.starts_with("0x") && !w.chars().next().is_some_and(|c| c.is_ascii_digit()))
        .filter(|w| {
            !w.chars()
                .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_')
        })
        .filter(|w| !["Wi", "Fi"].contains(w) && !allowed.contains(w))
        .map(str::to_string)
        .collect()
}

/// A node's text: a label's own, else its value.
fn text_of(n: &egui_kittest::Node<'_>) -> Option<String> {
    let node = n.accesskit_node();
    node.label().or_else(|| node.value())
}

/// The FAIL banner's lines: the failed step, then why.
fn banner_line(h: &Harness<'static, LineStation>) -> String {
    h.query_all_by_label_contains("自检\n")
        .next()
        .and_then(|n| text_of(&n))
        .unwrap_or_else(|| {
            let all: Vec<String> = h
                .query_all_by_label_contains("")
                .filter_map(|n| text_of(&n))
                .collect();
            format!("no banner line among {all:?}")
        })
}

#[test]
fn every_kind_of_failure_reason_reads_in_chinese_on_the_tile() {
    let (mut h, tx) = chinese_window();
    let mut left_english = Vec::new();
    for (reason, allowed) in every_reason() {
        let english = reason.to_string();
        tx.send(fail(reason)).unwrap();
        h.step();
        h.step();
        let line = banner_line(&h);
        let words = english_words(&line, allowed);
        if !words.is_empty() || line.contains(&english) {
            left_english.push(format!("{line}  ({english}: {words:?})"));
        }
    }
    assert!(
        left_english.is_empty(),
        "English left on the 中文 tile:\n{}",
        left_english.join("\n")
    );
    // A value out of its limits says what was measured and what is allowed.
    tx.send(fail(Reason::OutOfLimits {
        values: vec![spray_current_too_low()],
    }))
    .unwrap();
    h.step();
    h.step();
    let line = banner_line(&h);
    assert!(
        line.contains("sprayCurrent 测得 0.1 A") && line.contains("0.2 至 1.5 A"),
        "{line}"
    );
    // The history says each verdict in 中文.
    assert!(h.query_all_by_label_contains("WC000123 不合格").count() >= 1);
    assert_eq!(h.query_all_by_label_contains("WC000123 FAIL").count(), 0);
}

#[test]
fn a_retry_question_says_why_the_step_failed_in_chinese() {
    let (mut h, tx) = chinese_window();
    tx.send(event(What::Step {
        index: 2,
        of: 4,
        name: "Self-test (window-cleaner-selftest)".into(),
        name_zh: "自检".into(),
        attempt: 1,
    }))
    .unwrap();
    let why = Reason::NotToggled {
        field: "cornerLeft".into(),
    };
    tx.send(event(What::Ask {
        kind: "retry",
        text: format!("Self-test (window-cleaner-selftest) failed: {why}. Retry once?"),
        text_zh: format!("自检 失败:{why}。重试一次?"),
        why: Some(why),
    }))
    .unwrap();
    h.step();
    h.step();
    assert!(
        h.query_by_label("自检 失败:cornerLeft 未被触发。重试一次?")
            .is_some(),
        "{:?}",
        h.state().tiles[0].asking
    );
}

/// The self-test's spray current measured at 0.1 A against its 0.2-1.5 A limits.
fn spray_current_too_low() -> Measurement {
    Measurement {
        name: "sprayCurrent".into(),
        unit: "A".into(),
        low: Some(0.2),
        high: Some(1.5),
        value: 0.1,
        pass: false,
    }
}
