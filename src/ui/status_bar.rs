//! The status line: what the link is, its counters, the last message, and the running job's
//! progress.

use super::Action;
use super::station::Station;
use crate::i18n::Lang;
use eframe::egui;

/// Draws the status line.
pub fn show(ui: &mut egui::Ui, lang: Lang, rt: &Station) -> Vec<Action> {
    let mut actions = Vec::new();
    super::layout::toolbar(ui, |ui| {
        // Every part keeps its words whole, and a part the row has no room left for moves,
        // whole, to a second row (a narrow window, or a scale factor of 2 on a small screen);
        // the message last, on a row of its own when it would not fit the rest of this one,
        // cut only when even that is too short (whole on hover).
        // A running job first, so that its Cancel is in reach however long the rest is.
        if let Some((title, fraction, msg)) = rt.job_progress() {
            ui.label(title.get(lang));
            ui.add(
                egui::ProgressBar::new(fraction)
                    .desired_width(160.0)
                    .show_percentage(),
            );
            if ui.button(lang.tr("Cancel", "取消")).clicked() {
                actions.push(Action::CancelJob);
            }
            // What the job is doing, in at most a third of the room left: the message after it
            // keeps the rest.
            let room = egui::vec2(ui.available_width() / 3.0, ui.spacing().interact_size.y);
            ui.allocate_ui(room, |ui| {
                super::layout::one_line(ui, egui::RichText::new(msg.get(lang)).weak())
            });
            ui.separator();
        }
        match rt.link.target() {
            Some(target) => {
                ui.label(target.label_in(lang));
                if let Some(Ok(info)) = &rt.device.info {
                    ui.separator();
                    ui.label(format!(
                        "{} {:#04x} {} {} API {}",
                        lang.tr("hw", "硬件"),
                        info.hw,
                        lang.tr("fw", "固件"),
                        info.firmware,
                        info.api
                    ));
                }
                ui.separator();
                link_stats(ui, lang, rt);
                if rt.link.connection.is_some() {
                    ui.separator();
                    super::connection::timing(ui, lang, rt, &mut actions);
                }
            }
            None => {
                ui.label(lang.tr("not connected", "未连接"));
            }
        }
        if let Some(s) = &rt.notice {
            let text = s.text_in(lang);
            let width = super::layout::text_width(ui, &super::layout::body_font(ui), [text]);
            if width + 2.0 * ui.spacing().item_spacing.x > ui.available_width() {
                ui.end_row();
            } else {
                ui.separator();
            }
            let color = if s.error {
                egui::Color32::RED
            } else {
                ui.visuals().text_color()
            };
            super::layout::one_line(ui, egui::RichText::new(text).color(color));
        }
    });
    actions
}

/// The link's round trip and counters.
fn link_stats(ui: &mut egui::Ui, lang: Lang, rt: &Station) {
    if let Some(rtt) = rt.link.stats.rtt {
        let said = |ms: f64| format!("{} {ms:.1} ms", lang.tr("round trip", "往返"));
        // As wide as a round trip of 999.9 ms whatever the figure: the row does not move with
        // each answer's (at a scale factor of 2 the message after it flipped between rows,
        // and was not drawn in the frame between).
        let font = super::layout::body_font(ui);
        let widest = super::layout::text_width(ui, &font, [said(999.9).as_str()]);
        ui.scope(|ui| {
            ui.set_min_width(widest);
            ui.label(said(rtt.as_secs_f64() * 1e3));
        });
    }
    let warn = egui::Color32::from_rgb(220, 150, 0);
    let quiet = ui.visuals().weak_text_color();
    // A scan asks every id, and most never answer: on a servo bus silence is not an error.
    let silence_expected = rt.device.profile.protocol == crate::profile::Protocol::Servo;
    let details = format!(
        "{} {}, {} {}, {} {}, {} {}",
        lang.tr("retries", "重试"),
        rt.link.stats.retries,
        lang.tr("frames sent", "已发送帧"),
        rt.link.stats.sent,
        lang.tr("received", "已接收"),
        rt.link.stats.received,
        lang.tr("dropped events", "丢弃事件"),
        rt.link.stats.dropped_events
    );
    let n = rt.link.stats.timeouts;
    let color = if n > 0 && !silence_expected {
        warn
    } else {
        quiet
    };
    ui.colored_label(color, format!("{} {n}", lang.tr("no answer", "无应答")))
        .on_hover_text(details.clone());
    let n = rt.link.stats.frame_errors;
    let color = if n > 0 { warn } else { quiet };
    ui.colored_label(color, format!("{} {n}", lang.tr("frame errors", "帧错误")))
        .on_hover_text(details);
}
