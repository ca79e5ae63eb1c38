//! The packet monitor: every frame sent and received, with time, direction, hex and decoded
//! meaning (command name, fields, errors). Filter by command, pause, copy, save as text.

use super::Action;
use super::state::{AppState, Notice};
use crate::i18n::Lang;
use crate::link::LogEntry;
use crate::profile::Profile;
use crate::protocol::{Direction, hex};
use eframe::egui;

/// The monitor's view state.
#[derive(Default)]
pub struct MonitorPanel {
    /// Show only frames whose command name or number contains this.
    pub filter: String,
    /// Show errors only.
    pub errors_only: bool,
}

/// One log line: `12:00:01.234 >> ff ff 03 82 00 81  MSP_GET_PWMVALUE`.
pub fn line(profile: &Profile, e: &LogEntry) -> String {
    let time = chrono::DateTime::<chrono::Local>::from(e.at).format("%H:%M:%S%.3f");
    match &e.frame {
        Ok(p) => format!(
            "{time} {} {:<40} {}{}",
            e.direction.arrow(),
            hex::format(&p.wire),
            p.summary(profile),
            e.note
                .as_ref()
                .map_or(String::new(), |n| format!("  [{n}]"))
        ),
        Err(err) => format!(
            "{time} {} {:<40} !! {err}",
            e.direction.arrow(),
            hex::format(err.bytes())
        ),
    }
}

impl MonitorPanel {
    fn matches(&self, profile: &Profile, e: &LogEntry) -> bool {
        if self.errors_only && e.frame.is_ok() {
            return false;
        }
        let f = self.filter.trim();
        if f.is_empty() {
            return true;
        }
        match &e.frame {
            Ok(p) => {
                let name = profile
                    .command_by_id(p.command)
                    .map_or("", |c| c.ident.as_str());
                p.command.to_string() == f
                    || name.to_ascii_lowercase().contains(&f.to_ascii_lowercase())
            }
            Err(_) => false,
        }
    }

    /// Draws the panel.
    pub fn show(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &AppState) -> Vec<Action> {
        let mut actions = Vec::new();
        let profile = rt.device.profile.clone();
        let log = &rt.packets;
        ui.horizontal_wrapped(|ui| {
            let label = ui.label(lang.tr("Filter", "筛选"));
            ui.add(
                egui::TextEdit::singleline(&mut self.filter)
                    .hint_text(lang.tr("command name or number", "命令名或编号"))
                    .desired_width(180.0),
            )
            .labelled_by(label.id);
            ui.checkbox(&mut self.errors_only, lang.tr("errors only", "仅错误"));
            let pause = if log.paused {
                lang.tr("Resume", "继续")
            } else {
                lang.tr("Pause", "暂停")
            };
            if ui.button(pause).clicked() {
                actions.push(Action::PausePacketLog(!log.paused));
            }
            if ui.button(lang.tr("Clear", "清空")).clicked() {
                actions.push(Action::ClearPacketLog);
            }
            let copy = ui.button(lang.tr("Copy", "复制")).clicked();
            let save_clicked = ui.button(lang.tr("Save…", "保存…")).clicked();
            if copy || save_clicked {
                let shown: Vec<String> = log
                    .entries
                    .iter()
                    .filter(|e| self.matches(&profile, e))
                    .map(|e| line(&profile, e))
                    .collect();
                if copy {
                    ui.ctx().copy_text(shown.join("\n"));
                    actions.push(Action::Notify(Notice::info(format!(
                        "{} line(s) copied",
                        shown.len()
                    ))));
                } else {
                    actions.push(save(&shown));
                }
            }
            let shown = log
                .entries
                .iter()
                .filter(|e| self.matches(&profile, e))
                .count();
            ui.weak(format!(
                "{} {} / {}{}",
                shown,
                lang.tr("shown", "条显示"),
                log.entries.len(),
                if log.dropped > 0 {
                    format!(
                        ", {} {}",
                        log.dropped,
                        lang.tr("not kept while paused", "暂停期间未记录")
                    )
                } else {
                    String::new()
                }
            ));
        });
        ui.separator();
        let rows: Vec<&LogEntry> = log
            .entries
            .iter()
            .filter(|e| self.matches(&profile, e))
            .collect();
        let row_h = ui.text_style_height(&egui::TextStyle::Monospace) + 2.0;
        egui::ScrollArea::both()
            .auto_shrink(false)
            .stick_to_bottom(!log.paused)
            .show_rows(ui, row_h, rows.len(), |ui, range| {
                for e in &rows[range] {
                    let text = line(&profile, e);
                    let unsolicited = matches!(&e.frame, Ok(p) if matches!(p.header, crate::packet::Header::MspReply { kind: crate::protocol::msp::ReplyKind::Async }));
                    let color = match (&e.frame, e.direction) {
                        (Err(_), _) => egui::Color32::RED,
                        (Ok(_), Direction::HostToDevice) => ui.visuals().text_color(),
                        // Frames that answer nothing they were sent for: unsolicited, late.
                        (Ok(_), Direction::DeviceToHost) if unsolicited || e.note.is_some() => {
                            egui::Color32::from_rgb(220, 150, 0)
                        }
                        (Ok(_), Direction::DeviceToHost) => egui::Color32::from_rgb(40, 140, 200),
                    };
                    ui.add(
                        egui::Label::new(egui::RichText::new(text).monospace().color(color))
                            .wrap_mode(egui::TextWrapMode::Extend),
                    );
                }
            });
        actions
    }
}

fn save(lines: &[String]) -> Action {
    let Some(path) = rfd::FileDialog::new()
        .set_file_name("packets.txt")
        .save_file()
    else {
        return Action::Notify(Notice::info(
            "save cancelled (no file chosen, or no file dialog on this system)",
        ));
    };
    match crate::document::write_atomic(&path, (lines.join("\n") + "\n").as_bytes()) {
        Ok(()) => Action::Notify(Notice::info(format!(
            "{} line(s) saved to {}",
            lines.len(),
            path.display()
        ))),
        Err(e) => Action::Notify(Notice::error(e.to_string())),
    }
}
