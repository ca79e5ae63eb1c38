//! The device's actions (motor, fan, spray, voice, calibration, Wi-Fi test…), generated from the
//! profile's Action commands. Each field is range-checked as typed; a command that makes the
//! robot move asks for confirmation first.

use super::Action;
use super::inputs::{command_inputs, value_box};
use super::confirm::Decision;
use super::jobs;
use super::station::Station;
use crate::i18n::Lang;
use crate::profile::{Command, CommandKind, Input};
use crate::ui::zh::Zh;
use eframe::egui;
use std::collections::HashMap;

/// The panel's state: typed values, and a command awaiting confirmation.
#[derive(Default)]
pub struct ActionsPanel {
    /// Typed text by (command id, field ident).
    pub inputs: HashMap<(u8, String), String>,
    /// A command that moves the robot, waiting for the operator's yes.
    confirm: Option<(u8, Vec<(String, Input)>)>,
}

impl ActionsPanel {
    /// Draws the panel.
    fn draw(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &Station) -> Vec<Action> {
        let mut actions = Vec::new();
        let ready = rt.connected() && rt.job_progress().is_none();
        let profile = &rt.device.profile;
        let cmds: Vec<&Command> = profile
            .commands
            .iter()
            .filter(|c| c.kind == CommandKind::Action)
            .collect();
        // The fields' column wraps its label-and-box pairs within what the names' and the
        // Send buttons' columns leave, so that Send stays in the window however many fields a
        // command has (the solar cleanbot's grid-line data has five).
        let layout = crate::ui::layout::ColumnsLeft::new(
            ui,
            cmds.iter().map(|c| lang.tr(&c.name.en, &c.name.zh)),
            [
                format!("⚠ {}", lang.tr("Send…", "发送…")),
                lang.tr("Send", "发送").to_string(),
            ],
        );
        egui::ScrollArea::vertical()
            .auto_shrink(false)
            .show(ui, |ui| {
                egui::Grid::new("actions")
                    .striped(true)
                    .num_columns(3)
                    .show(ui, |ui| {
                        for cmd in cmds {
                            ui.label(lang.tr(&cmd.name.en, &cmd.name.zh))
                                .on_hover_text(format!("{} ({})", cmd.ident, cmd.id));
                            layout.wrapped(ui, |ui| fields(ui, &mut self.inputs, cmd, lang));
                            let send = self.send_button(ui, lang, rt, cmd, ready);
                            actions.extend(send);
                            ui.end_row();
                        }
                    });
            });
        actions.extend(self.confirmation(ui, lang, rt));
        actions
    }

    /// A command's Send button (Send… with a warning when the command moves the robot): off
    /// while not `ready` or while a field's value is refused, which its hover says.
    fn send_button(
        &mut self,
        ui: &mut egui::Ui,
        lang: Lang,
        rt: &Station,
        cmd: &Command,
        ready: bool,
    ) -> Option<Action> {
        let profile = &rt.device.profile;
        let inputs = command_inputs(cmd, &self.inputs);
        let stopping = inputs.as_ref().is_ok_and(|i| profile.is_stop(cmd.id, i));
        let label = if cmd.confirm && !stopping {
            format!("⚠ {}", lang.tr("Send…", "发送…"))
        } else {
            lang.tr("Send", "发送").to_string()
        };
        let resp = ui.add_enabled(ready && inputs.is_ok(), egui::Button::new(label));
        let resp = match &inputs {
            Err(e) => resp.on_disabled_hover_text(e.in_lang(lang)),
            Ok(_) => resp,
        };
        if !resp.clicked() {
            return None;
        }
        let Ok(inputs) = inputs else {
            return None;
        };
        // Stopping (motor stop, fan 0) moves nothing: no warning.
        if cmd.confirm && !stopping {
            self.confirm = Some((cmd.id, inputs));
            None
        } else {
            Some(Action::StartJob(jobs::send(profile, cmd.id, inputs)))
        }
    }

    /// The confirmation of a command that moves the robot, while one waits: what it sends, and
    /// the operator's yes or no.
    fn confirmation(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &Station) -> Option<Action> {
        let profile = &rt.device.profile;
        let (id, inputs) = self.confirm.as_ref()?;
        let cmd = profile.command_by_id(*id);
        let name = cmd.map_or(String::new(), |c| c.name.get(lang).to_string());
        let mut decision = None;
        let modal = egui::Modal::new(egui::Id::unique("confirm-action")).show(ui.ctx(), |ui| {
            ui.heading(lang.tr("The robot will move", "机器人将会动作"));
            ui.label(format!(
                "{name}{}{}",
                lang.tr(" — ", "——"),
                super::confirm::inputs_said(cmd, inputs, lang)
            ));
            ui.label(lang.tr(
                "Make sure it is safe, then confirm.",
                "请确认安全后再执行。",
            ));
            ui.label(lang.tr("STOP stays available.", "停止按钮始终可用。"));
            decision = super::confirm::buttons(
                ui,
                lang,
                lang.tr("Confirm", "确认"),
                lang.tr("Cancel", "取消"),
                rt,
            );
        });
        match super::confirm::decided(&modal, decision)? {
            Decision::Yes => {
                let (id, inputs) = self.confirm.take()?;
                Some(Action::StartJob(jobs::send(profile, id, inputs)))
            }
            Decision::No => {
                self.confirm = None;
                None
            }
            Decision::Stop => {
                self.confirm = None;
                Some(Action::Stop)
            }
        }
    }
}

/// A command's fields: each a box for its value (checked as typed), or a list of its labels.
fn fields(
    ui: &mut egui::Ui,
    inputs: &mut HashMap<(u8, String), String>,
    cmd: &Command,
    lang: Lang,
) {
    for f in &cmd.request {
        let key = (cmd.id, f.ident.clone());
        let text = inputs.entry(key).or_default();
        crate::ui::layout::group(ui, &f.ident, |ui| {
            let name = ui.label(lang.tr(&f.name.en, &f.name.zh));
            if f.labels.is_empty() {
                value_box(ui, text, f, lang, 70.0).labelled_by(name.id);
                return;
            }
            // The value chosen by its name in the window's language, as everywhere.
            crate::ui::inputs::label_choice(ui, lang, f, ("act", cmd.id, &f.ident), text, name.id);
        });
    }
}

impl crate::ui::PanelId {
    /// The device's actions (motor, fan, spray…), from its profile.
    pub const ACTIONS: crate::ui::PanelId = crate::ui::PanelId::new("Actions");
}

impl crate::ui::Panel for ActionsPanel {
    fn id(&self) -> crate::ui::PanelId {
        crate::ui::PanelId::ACTIONS
    }

    fn name(&self, lang: Lang) -> &'static str {
        lang.tr("Actions", "动作测试")
    }

    fn kind(&self) -> Option<crate::profile::PanelKind> {
        Some(crate::profile::PanelKind::Actions)
    }

    fn show(&mut self, ui: &mut egui::Ui, cx: &crate::ui::panel::Cx<'_>) -> Vec<Action> {
        self.draw(ui, cx.lang, cx.station)
    }
}
