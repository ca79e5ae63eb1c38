//! The solar cleanbot: live readouts and plots (polled by the worker), range-checked controls,
//! a STOP that is always visible, and an optional dead-man.
//!
//! Readouts and controls come from the profile: every telemetry command (97-134) is shown with
//! its fields, and every action with a payload gets a row of inputs, each checked as typed.

mod control;

pub use control::{Control, Outcome, Trip};

use super::inputs::{command_inputs, readout_text, value_box};
use super::station::{Reading, Station};
use super::confirm::Decision;
use super::stop;
use super::{Action, plot};
use crate::i18n::Lang;
use crate::profile::{Command, CommandKind, Field, FieldType, Input, Value};
use crate::ui::zh::Zh;
use eframe::egui;
use egui_plot::Plot;
use std::collections::HashMap;

/// The plots' time window, seconds.
const WINDOW_SECS: f64 = 30.0;

/// The panel's state.
#[derive(Default)]
pub struct SolarPanel {
    /// What it sends, STOP and the dead-man.
    pub control: Control,
    /// Typed text by (command id, field ident).
    pub inputs: HashMap<(u8, String), String>,
    /// A command that moves the robot, waiting for the operator's yes.
    confirm: Option<(u8, Vec<(String, Input)>)>,
    scratch: plot::Scratch,
    /// The plots' width when last drawn, points: the whole panel's.
    pub plot_width: f32,
}

const RED: egui::Color32 = egui::Color32::from_rgb(200, 30, 30);
const GREEN: egui::Color32 = egui::Color32::from_rgb(0, 140, 60);

impl SolarPanel {
    /// Draws the panel, with the station's STOP at the top.
    fn draw(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &Station) -> Vec<Action> {
        let mut actions = Vec::new();
        crate::ui::layout::toolbar(ui, |ui| {
            actions.extend(stop::button(ui, lang, rt));
            rt.stop.status(ui, lang);
            self.trip_status(ui, lang, rt);
        });
        self.deadman(ui, lang, rt, &mut actions);
        ui.separator();
        egui::ScrollArea::vertical()
            .auto_shrink(false)
            .show(ui, |ui| {
                ui.columns(2, |cols| {
                    self.controls(&mut cols[0], lang, rt, &mut actions);
                    self.readouts(&mut cols[1], lang, rt);
                });
                ui.separator();
                // The plots across the whole width, their key above them.
                self.plots(ui, lang, rt);
            });
        self.confirm_modal(ui, lang, rt, &mut actions);
        actions
    }

    fn trip_status(&self, ui: &mut egui::Ui, lang: Lang, rt: &Station) {
        if let Some((Trip::NotConfirmed, at)) = &self.control.trip {
            ui.colored_label(
                RED,
                format!(
                    "{} ({:.0} s)",
                    lang.tr(
                        "Dead-man: the operator stopped confirming; STOP sent",
                        "失能保护:操作员未持续确认,已发送停止",
                    ),
                    at.elapsed().as_secs_f64()
                ),
            );
        }
        if !rt.connected() && rt.link.connection.is_some() {
            ui.colored_label(RED, lang.tr("link down", "链路中断"));
        }
    }

    fn deadman(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &Station, actions: &mut Vec<Action>) {
        crate::ui::layout::toolbar(ui, |ui| {
            let mut on = self.control.deadman;
            if ui
                .checkbox(&mut on, lang.tr("Dead-man", "失能保护"))
                .changed()
            {
                actions.extend(self.control.arm(rt, on));
            }
            let label = ui.label(lang.tr("confirm every", "确认间隔"));
            ui.add_enabled(
                !self.control.deadman,
                egui::DragValue::new(&mut self.control.deadman_secs)
                    .range(control::DEADMAN_SECS)
                    .suffix(" s"),
            )
            .labelled_by(label.id);
            if self.control.deadman {
                let hold = ui.add(
                    egui::Button::new(
                        lang.tr("Hold to confirm (or press Space)", "按住确认(或按空格键)"),
                    )
                    .sense(egui::Sense::click_and_drag()),
                );
                let typing = ui.ctx().memory(|m| m.focused().is_some());
                let space = !typing && ui.input(|i| i.key_pressed(egui::Key::Space));
                if hold.is_pointer_button_down_on() || hold.clicked() || space {
                    self.control.confirm();
                }
                if let Some(left) = self.control.deadman_left() {
                    let f = left.as_secs_f32() / self.control.deadman_secs.max(1) as f32;
                    ui.add(
                        egui::ProgressBar::new(f)
                            .desired_width(120.0)
                            .text(format!("{:.1} s", left.as_secs_f32())),
                    );
                }
            }
        });
        ui.weak(lang.tr(
            "While the dead-man is armed, botbench sends STOP if nobody confirms within the interval, \
             and sets the robot's heartbeat interval to the same period. If the link is down botbench \
             cannot reach the robot: only the robot's own heartbeat timeout can stop it then (the \
             protocol does not say what the firmware does when heartbeats stop). botbench sends STOP \
             as soon as the link is back.",
            "失能保护开启时,若在间隔内无人确认,botbench 发送停止,并将机器人心跳间隔设为相同时长。\
             链路中断时 botbench 无法联系机器人:此时只有机器人自身的心跳超时能让它停下(协议未说明心跳中断时固件的行为)。\
             链路恢复后 botbench 立即发送停止。",
        ));
    }

    fn readouts(&self, ui: &mut egui::Ui, lang: Lang, rt: &Station) {
        ui.strong(lang.tr("Readouts", "实时读数"));
        let cmds = rt.device.profile.commands.iter().filter(|c| {
            c.kind == CommandKind::Telemetry
                && !rt.device.profile.is_core(c)
                && c.request.is_empty()
                && !c.reply.is_empty()
        });
        egui::Grid::new("solar-readouts")
            .num_columns(2)
            .striped(true)
            .show(ui, |ui| {
                for cmd in cmds {
                    ui.label(lang.tr(&cmd.name.en, &cmd.name.zh))
                        .on_hover_text(format!("{} ({})", cmd.ident, cmd.id));
                    match rt.device.readings.get(&cmd.id) {
                        Some(Reading::Values(values, at)) => {
                            let stale = at.elapsed() > plot::STALE;
                            // One field a line: wrapped runs of values overlap the next row.
                            ui.vertical(|ui| {
                                for (k, v) in values {
                                    let Some(f) = cmd.reply.iter().find(|f| f.ident == k) else {
                                        continue;
                                    };
                                    let text = format!(
                                        "{}: {}",
                                        lang.tr(&f.name.en, &f.name.zh),
                                        readout_text(f, v, lang)
                                    );
                                    if stale {
                                        ui.weak(text);
                                    } else if f.out_of_range(v).is_some() {
                                        ui.colored_label(
                                            RED,
                                            egui::RichText::new(text).monospace(),
                                        );
                                    } else {
                                        ui.monospace(text);
                                    }
                                }
                                if stale {
                                    ui.colored_label(
                                        RED,
                                        format!(
                                            "{} {:.0} s",
                                            lang.tr("stale: last answer", "数据过期:上次应答"),
                                            at.elapsed().as_secs_f64()
                                        ),
                                    );
                                }
                            });
                        }
                        Some(Reading::Failed(e)) => {
                            ui.colored_label(RED, e.in_lang(lang));
                        }
                        None => {
                            ui.weak(lang.tr("no answer yet", "尚无应答"));
                        }
                    }
                    ui.end_row();
                }
            });
    }

    fn plots(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &Station) {
        let now = rt.plot_end();
        let width_px = ui.available_width().max(100.0) as usize;
        for p in &rt.device.profile.plots {
            ui.label(egui::RichText::new(lang.tr(&p.name.en, &p.name.zh)).strong());
            let legend = plot::Legend::new(rt.device.profile.command(&p.command), &p.fields, lang);
            plot::key(ui, &legend, &plot::states(rt, p, lang));
            let set = rt.device.plots.get(&p.id);
            let scratch = &mut self.scratch;
            let shown = Plot::new(("solar-plot", &p.id)).height(130.0);
            let resp = plot::axes(shown, lang, rt.device.t0_wall, &legend)
                .allow_drag(false)
                .allow_zoom(false)
                .allow_scroll(false)
                .show(ui, |pui| {
                    pui.set_plot_bounds_x(now - WINDOW_SECS..=now);
                    let x = (now - WINDOW_SECS, now);
                    let extent = set.and_then(|set| {
                        plot::lines(pui, set, &p.fields, &legend, x, width_px, scratch)
                    });
                    plot::fit_y(pui, extent, legend.integer);
                });
            self.plot_width = resp.response.rect.width();
        }
    }

    fn controls(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &Station, actions: &mut Vec<Action>) {
        ui.strong(lang.tr("Controls", "控制"));
        let profile = rt.device.profile.clone();
        let cmds = profile
            .commands
            .iter()
            .filter(|c| c.kind == CommandKind::Action && !c.request.is_empty());
        for cmd in cmds {
            crate::ui::layout::toolbar(ui, |ui| {
                for f in &cmd.request {
                    self.input(ui, lang, cmd, f);
                }
            });
            let inputs = command_inputs(cmd, &self.inputs);
            crate::ui::layout::toolbar(ui, |ui| {
                let resp = ui.add_enabled(
                    rt.connected() && inputs.is_ok(),
                    egui::Button::new(lang.tr(&cmd.name.en, &cmd.name.zh)),
                );
                let resp = match &inputs {
                    Err(e) => resp.on_disabled_hover_text(e.in_lang(lang)),
                    Ok(_) => resp.on_hover_text(format!("{} ({})", cmd.ident, cmd.id)),
                };
                if resp.clicked()
                    && let Ok(inputs) = inputs.clone()
                {
                    let moving = inputs.iter().any(|(_, v)| match v {
                        Input::Text(t) => t.trim().parse::<f64>() != Ok(0.0),
                        Input::Raw(r) => *r != Value::Int(0),
                    });
                    if cmd.confirm && moving {
                        self.confirm = Some((cmd.id, inputs));
                    } else {
                        actions.extend(self.control.send(rt, cmd.id, &inputs));
                    }
                }
                // Why it cannot be sent, as typed; then what the last send did.
                let typed = cmd.request.iter().any(|f| {
                    self.inputs
                        .get(&(cmd.id, f.ident.clone()))
                        .is_some_and(|t| !t.is_empty())
                });
                if let (Err(e), true) = (&inputs, typed) {
                    ui.colored_label(RED, format!("{} {e}", lang.tr("refused:", "拒绝:")));
                } else {
                    match self.control.outcomes.get(&cmd.id) {
                        Some((Outcome::Waiting(t), _)) => {
                            ui.label(format!(
                                "{t}: {}",
                                lang.tr("sent, waiting…", "已发送,等待应答…")
                            ));
                        }
                        Some((Outcome::Acked(t), at)) => {
                            ui.colored_label(
                                GREEN,
                                format!(
                                    "{t}: {} ({:.0} s)",
                                    lang.tr("acknowledged", "设备已确认"),
                                    at.elapsed().as_secs_f64()
                                ),
                            );
                        }
                        Some((Outcome::Failed(e), _)) => {
                            ui.colored_label(RED, e.in_lang(lang));
                        }
                        None => {}
                    }
                }
            });
            ui.add_space(4.0);
        }
    }

    /// A field's name and its box (or choice), kept together on one row.
    fn input(&mut self, ui: &mut egui::Ui, lang: Lang, cmd: &Command, f: &Field) {
        let text = self.inputs.entry((cmd.id, f.ident.clone())).or_default();
        crate::ui::layout::group(ui, &f.ident, |ui| {
            let name = ui.label(lang.tr(&f.name.en, &f.name.zh));
            if f.labels.is_empty() || f.range.is_some() {
                let width = if matches!(f.ty, FieldType::Bytes(_)) {
                    160.0
                } else {
                    70.0
                };
                value_box(ui, text, f, lang, width).labelled_by(name.id);
            } else {
                let salt = ("solar", cmd.id, &f.ident);
                crate::ui::inputs::label_choice(ui, lang, f, salt, text, name.id);
            }
        });
    }

    fn confirm_modal(
        &mut self,
        ui: &mut egui::Ui,
        lang: Lang,
        rt: &Station,
        actions: &mut Vec<Action>,
    ) {
        let Some((id, inputs)) = &self.confirm else {
            return;
        };
        let cmd = rt.device.profile.command_by_id(*id);
        let name = cmd.map_or(String::new(), |c| c.name.get(lang).to_string());
        let what = super::confirm::inputs_said(cmd, inputs, lang);
        let mut decision = None;
        let modal = egui::Modal::new(egui::Id::unique("solar-confirm")).show(ui.ctx(), |ui| {
            ui.heading(lang.tr("The robot will move", "机器人将会动作"));
            ui.label(format!("{name}{}{what}", lang.tr(" — ", "——")));
            ui.label(lang.tr(
                "Make sure it is safe, then confirm. STOP stays available.",
                "请确认安全后再执行。停止按钮始终可用。",
            ));
            decision = super::confirm::buttons(
                ui,
                lang,
                lang.tr("Confirm", "确认"),
                lang.tr("Cancel", "取消"),
                rt,
            );
        });
        match super::confirm::decided(&modal, decision) {
            Some(Decision::Yes) => {
                if let Some((id, inputs)) = self.confirm.take() {
                    actions.extend(self.control.send(rt, id, &inputs));
                }
            }
            Some(Decision::No) => self.confirm = None,
            Some(Decision::Stop) => {
                self.confirm = None;
                actions.push(Action::Stop);
            }
            None => {}
        }
    }
}

impl crate::ui::PanelId {
    /// The solar cleanbot's readouts and controls.
    pub const SOLAR: crate::ui::PanelId = crate::ui::PanelId::new("Solar");
}

impl crate::ui::Panel for SolarPanel {
    fn id(&self) -> crate::ui::PanelId {
        crate::ui::PanelId::SOLAR
    }

    fn name(&self, lang: Lang) -> &'static str {
        lang.tr("Solar cleanbot", "光伏清扫机器人")
    }

    fn kind(&self) -> Option<crate::profile::PanelKind> {
        Some(crate::profile::PanelKind::Solar)
    }

    fn show(&mut self, ui: &mut egui::Ui, cx: &crate::ui::panel::Cx<'_>) -> Vec<Action> {
        self.draw(ui, cx.lang, cx.station)
    }

    /// The dead-man, whichever panel is shown.
    fn tick(&mut self, station: &Station) -> Vec<Action> {
        self.control.tick(station)
    }

    fn live(&self, station: &Station) -> bool {
        station.connected() && !station.link.polling_paused
    }

    fn shows_stop(&self) -> bool {
        true
    }
}
