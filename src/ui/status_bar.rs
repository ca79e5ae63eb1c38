//! The status line: what the link is, the last message, and the running job's progress.

use super::Action;
use super::runtime::Runtime;
use crate::i18n::Lang;
use eframe::egui;

/// Draws the status line.
pub fn show(ui: &mut egui::Ui, lang: Lang, rt: &Runtime) -> Vec<Action> {
    let mut actions = Vec::new();
    ui.horizontal(|ui| {
        match &rt.conn {
            Some(c) => {
                ui.label(c.target.label());
                if let Some(Ok(info)) = &rt.info {
                    ui.separator();
                    ui.label(format!(
                        "hw {:#04x} fw {} api {}",
                        info.hw, info.firmware, info.api
                    ));
                }
            }
            None => {
                ui.label(lang.tr("not connected", "未连接"));
            }
        }
        if let Some((title, fraction, msg)) = rt.job_progress() {
            ui.separator();
            ui.label(title);
            ui.add(
                egui::ProgressBar::new(fraction)
                    .desired_width(160.0)
                    .show_percentage(),
            );
            ui.weak(msg);
            if ui.button(lang.tr("Cancel", "取消")).clicked() {
                actions.push(Action::CancelJob);
            }
        }
        if let Some(s) = &rt.status {
            ui.separator();
            let color = if s.error {
                egui::Color32::RED
            } else {
                ui.visuals().text_color()
            };
            ui.colored_label(color, &s.text);
        }
    });
    actions
}
