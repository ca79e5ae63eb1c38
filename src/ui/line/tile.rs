//! One slot's tile: fixture, port, unit, step with a progress bar, the verdict as a banner
//! readable from two metres (PASS green, FAIL red with the failing step and reason), the
//! question waiting with its answer buttons or field, Start and STOP, the slot's history.

use super::TileState;
use crate::i18n::Lang;
use crate::ops::station::{Answer, Command};
use eframe::egui::{self, Color32, RichText};

/// What the operator asked of a slot.
pub enum Action {
    /// STOP this slot.
    Stop,
    /// Start, or an answer.
    Send(Command),
    /// Open this slot in the engineer view (unlocked only).
    Engineer,
}

const PASS_GREEN: Color32 = Color32::from_rgb(20, 150, 40);
const FAIL_RED: Color32 = Color32::from_rgb(200, 30, 30);
/// The port/state line's and the slot history's text size, points: read from two metres, as
/// the unit and step lines (20 and 18); egui's body text (14) is not.
pub const READABLE: f32 = 20.0;

/// Draws `t`; returns what the operator asked, with the slot's name.
/// With `engineer` (unlocked), the slot's configuration too.
pub fn show(
    ui: &mut egui::Ui,
    t: &mut TileState,
    lang: Lang,
    engineer: bool,
) -> Vec<(String, Action)> {
    let zh = lang == Lang::Zh;
    let mut out = Vec::new();
    egui::Frame::group(ui.style()).show(ui, |ui| {
        ui.set_min_width(ui.available_width());
        ui.horizontal(|ui| {
            let title = format!(
                "{} {}  {}",
                if zh { "工位" } else { "Slot" },
                t.slot,
                if zh { &t.fixture_zh } else { &t.fixture }
            );
            ui.label(RichText::new(title).size(24.0).strong());
        });
        port_line(ui, t, zh);
        if engineer {
            ui.label(RichText::new(&t.details).monospace());
            // Only an idle slot with its port is lent: a unit running is never interrupted.
            let idle =
                t.waiting.is_some() && t.stopped.is_none() && matches!(t.port, Some((true, _)));
            let open = egui::Button::new(if zh {
                "在工程师视图中打开"
            } else {
                "Open in engineer view"
            });
            if ui.add_enabled(idle, open).clicked() {
                out.push((t.slot.clone(), Action::Engineer));
            }
        }
        let unit = t.serial.clone().unwrap_or_else(|| "—".into());
        ui.label(
            RichText::new(format!("{} {unit}", if zh { "序列号" } else { "Unit" })).size(20.0),
        );
        step_line(ui, t, zh);
        banner(ui, t, zh);
        if let Some(kept) = &t.kept_elsewhere {
            // The verdict stands; where its record went is said beside it.
            let head = if zh {
                "记录未写入存储,已另存:"
            } else {
                "Record not in its store:"
            };
            ui.label(
                RichText::new(format!("{head} {kept}"))
                    .size(16.0)
                    .color(FAIL_RED),
            );
        }
        if let Some(n) = t.earlier_runs.filter(|n| *n > 0) {
            ui.label(
                RichText::new(if zh {
                    format!("此产品已测试 {n} 次")
                } else {
                    format!("already tested {n} times before")
                })
                .size(18.0),
            );
        }
        question(ui, t, lang, &mut out);
        ui.horizontal(|ui| {
            let idle = t.waiting.is_some() && t.stopped.is_none();
            let start =
                egui::Button::new(RichText::new(if zh { "开始" } else { "Start" }).size(20.0));
            if ui.add_enabled(idle, start).clicked() {
                out.push((t.slot.clone(), Action::Send(Command::Start)));
            }
            let stop = egui::Button::new(
                RichText::new(if zh { "停止" } else { "STOP" })
                    .size(20.0)
                    .strong()
                    .color(Color32::WHITE),
            )
            .fill(FAIL_RED);
            if ui.add(stop).clicked() {
                out.push((t.slot.clone(), Action::Stop));
            }
        });
        history(ui, t, zh);
    });
    out
}

fn port_line(ui: &mut egui::Ui, t: &TileState, zh: bool) {
    let text = match (&t.port, &t.stopped) {
        (_, Some(why)) if zh => format!("已停止:{}", stopped_zh(why)),
        (_, Some(why)) => format!("stopped: {why}"),
        (Some((true, path)), _) => format!("{} {path}", if zh { "端口" } else { "port" }),
        (Some((false, why)), _) => {
            if zh {
                format!("端口缺失:{}", port_missing_zh(why))
            } else {
                format!("PORT MISSING: {why}")
            }
        }
        (None, _) => (if zh {
            "正在打开端口…"
        } else {
            "opening the port…"
        })
        .to_string(),
    };
    let missing = matches!(t.port, Some((false, _)));
    let color = if missing {
        FAIL_RED
    } else {
        ui.visuals().text_color()
    };
    ui.label(RichText::new(text).size(READABLE).color(color));
}

/// Why a slot stopped, in 中文: the runner's words (`stopped`, `one unit run (--once)`)
/// translated; anything else as it is.
fn stopped_zh(why: &str) -> String {
    match why {
        "stopped" => "已按停止".into(),
        "one unit run (--once)" => "已测完一个产品(--once)".into(),
        other => other.to_string(),
    }
}

/// Why a slot's port is missing, in 中文: the port finder's words (`no adapter at P:
/// unplugged?`, `no adapter with serial number SN: unplugged?`) translated; anything else as
/// it is.
fn port_missing_zh(why: &str) -> String {
    if let Some(path) = why
        .strip_prefix("no adapter at ")
        .and_then(|r| r.strip_suffix(": unplugged?"))
    {
        format!("{path} 处没有适配器:已拔出?")
    } else if let Some(sn) = why
        .strip_prefix("no adapter with serial number ")
        .and_then(|r| r.strip_suffix(": unplugged?"))
    {
        format!("没有序列号为 {sn} 的适配器:已拔出?")
    } else {
        why.to_string()
    }
}

fn step_line(ui: &mut egui::Ui, t: &TileState, zh: bool) {
    match (&t.step, t.waiting) {
        (Some((i, of, name)), _) if t.verdict.is_none() => {
            let name = if zh { &name.zh } else { &name.en };
            let step = format!("{} {i}/{of}: {name}", if zh { "步骤" } else { "Step" });
            ui.label(RichText::new(step).size(18.0));
            ui.add(egui::ProgressBar::new(*i as f32 / (*of).max(1) as f32).show_percentage());
        }
        (_, Some(how)) => {
            let how = match (how, zh) {
                ("scan", false) => "waiting: scan the unit's serial",
                ("scan", true) => "等待:扫描序列号",
                ("auto", false) => "waiting for a unit on the fixture",
                ("auto", true) => "等待产品放上治具",
                (_, false) => "waiting: press Start",
                (_, true) => "等待:按开始",
            };
            ui.label(RichText::new(how).size(18.0));
        }
        _ => {}
    }
}

/// The verdict, big: PASS on green, FAIL on red with the failing step and why.
fn banner(ui: &mut egui::Ui, t: &TileState, zh: bool) {
    let Some((pass, step, reason)) = &t.verdict else {
        return;
    };
    let (word, fill) = match (pass, zh) {
        (true, false) => ("PASS", PASS_GREEN),
        (true, true) => ("合格 PASS", PASS_GREEN),
        (false, false) => ("FAIL", FAIL_RED),
        (false, true) => ("不合格 FAIL", FAIL_RED),
    };
    egui::Frame::new()
        .fill(fill)
        .inner_margin(12.0)
        .show(ui, |ui| {
            ui.set_min_width(ui.available_width());
            ui.vertical_centered(|ui| {
                ui.label(
                    RichText::new(word)
                        .size(56.0)
                        .strong()
                        .color(Color32::WHITE),
                );
                if let Some(step) = step {
                    let why = match reason {
                        Some(why) if zh => crate::ui::zh::Zh::zh(why),
                        Some(why) => why.to_string(),
                        None => String::new(),
                    };
                    let step = if zh { &step.zh } else { &step.en };
                    // The step, then why on a line of its own: each read whole from two
                    // metres, a question mark in the step's name not run into the reason.
                    let text = if why.is_empty() {
                        step.clone()
                    } else {
                        format!("{step}\n{why}")
                    };
                    ui.label(RichText::new(text).size(20.0).color(Color32::WHITE));
                }
            });
        });
}

/// The question waiting: Yes/No buttons, or a field for a value or a scanned code.
fn question(ui: &mut egui::Ui, t: &mut TileState, lang: Lang, out: &mut Vec<(String, Action)>) {
    let zh = lang == Lang::Zh;
    let scan_idle = t.waiting == Some("scan") && t.stopped.is_none();
    let (kind, text) = match &t.asking {
        Some((kind, en, zh_text)) => (*kind, if zh { zh_text.clone() } else { en.clone() }),
        None if scan_idle => (
            "scan",
            (if zh {
                "扫描序列号"
            } else {
                "Scan the unit's serial"
            })
            .to_string(),
        ),
        None => return,
    };
    ui.label(RichText::new(&text).size(20.0).strong());
    match kind {
        "confirm" | "retry" => {
            ui.horizontal(|ui| {
                let yes = egui::Button::new(
                    RichText::new(if zh { "是 (Y)" } else { "Yes (Y)" }).size(22.0),
                );
                if ui.add(yes).clicked() {
                    out.push((t.slot.clone(), Action::Send(Command::Answer(Answer::Yes))));
                }
                let no = egui::Button::new(
                    RichText::new(if zh { "否 (N)" } else { "No (N)" }).size(22.0),
                );
                if ui.add(no).clicked() {
                    out.push((t.slot.clone(), Action::Send(Command::Answer(Answer::No))));
                }
            });
        }
        "measure" | "scan" => {
            ui.horizontal(|ui| {
                let field = ui.add(egui::TextEdit::singleline(&mut t.typed).desired_width(200.0));
                let entered = field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
                if (ui.button("OK").clicked() || entered) && !t.typed.trim().is_empty() {
                    let answer = Answer::Text(t.typed.trim().to_string());
                    out.push((t.slot.clone(), Action::Send(Command::Answer(answer))));
                    t.typed.clear();
                }
            });
        }
        _ => {}
    }
}

fn history(ui: &mut egui::Ui, t: &TileState, zh: bool) {
    if t.history.is_empty() {
        return;
    }
    ui.horizontal_wrapped(|ui| {
        ui.label(RichText::new(if zh { "记录:" } else { "History:" }).size(READABLE));
        for (pass, unit) in &t.history {
            let (word, color) = match (*pass, zh) {
                (true, false) => ("PASS", PASS_GREEN),
                (true, true) => ("合格", PASS_GREEN),
                (false, false) => ("FAIL", FAIL_RED),
                (false, true) => ("不合格", FAIL_RED),
            };
            ui.label(
                RichText::new(format!("{unit} {word}"))
                    .size(READABLE)
                    .strong()
                    .color(color),
            );
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_runner_s_port_and_link_reasons_read_in_chinese() {
        assert_eq!(
            port_missing_zh("no adapter at /dev/serial/by-path/x: unplugged?"),
            "/dev/serial/by-path/x 处没有适配器:已拔出?"
        );
        assert_eq!(
            port_missing_zh("no adapter with serial number A1: unplugged?"),
            "没有序列号为 A1 的适配器:已拔出?"
        );
    }
}
