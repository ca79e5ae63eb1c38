//! The parameters tab: the selected servo's read-only (1-8) and user (32-53) parameters from the
//! profile, with unit, range and labels. Edits are checked as typed; changed values are written
//! and read back one by one, or the whole user block in one exchange. "Reset user data" asks
//! first. Servo parameter presets are saved from and loaded into the table.

use super::params_jobs::{block_job, read_all_job, read_block_job, reset_job, write_job};
use super::selection_or_hint;
use super::{Servo, error_label, ok_label};
use crate::i18n::Lang;
use crate::ops::OpError;
use crate::ops::servo as ops;
use crate::profile::{Access, Param, Profile, Value};
use crate::ui::Action;
use crate::ui::confirm::Decision;
use crate::ui::layout::header_row;
use crate::ui::station::Station;
use crate::ui::tuning::PendingError;
use crate::ui::zh::Zh;
use eframe::egui;
use std::collections::BTreeMap;

/// What a parameter shows after a write.
#[derive(Debug, Clone, PartialEq)]
pub enum ParamMark {
    /// The servo holds what was written.
    Verified,
    /// The servo holds this raw value instead.
    Mismatch(i64),
    /// The write failed.
    Failed(OpError),
}

/// The parameters tab's state (for the selected servo).
#[derive(Default)]
pub struct ParamsState {
    /// Raw values read from the servo by `data_id`, or why the read failed.
    pub values: BTreeMap<u8, Result<i64, OpError>>,
    /// Edited text by `data_id`.
    pub edits: BTreeMap<u8, String>,
    /// Marks left by the last write.
    pub marks: BTreeMap<u8, ParamMark>,
    /// The preset file.
    pub preset_path: String,
    /// The preset's note.
    pub note: String,
    /// The last preset, reset or write message: ok, and its text.
    pub message: Option<(bool, String)>,
    /// "Reset user data" awaits confirmation.
    pub confirm_reset: bool,
    /// The language last drawn in (for messages made between frames).
    pub lang: Lang,
    /// The servo whose parameters were read when the tab first showed it.
    pub read_on_show: Option<Servo>,
}

/// Whether the table edits this parameter (the id and the baud rate have their own tab).
pub(super) fn editable(p: &Param) -> bool {
    p.access == Access::ReadWrite && !ops::follows_servo(p)
}

impl ParamsState {
    pub(super) fn device(&self, id: u8) -> Option<i64> {
        self.values.get(&id).and_then(|v| v.as_ref().ok()).copied()
    }

    /// Drops edits that equal what the servo holds.
    fn prune(&mut self, profile: &Profile) {
        let values = &self.values;
        self.edits.retain(|id, text| {
            let Some(p) = profile.param(*id) else {
                return false;
            };
            let device = values.get(id).and_then(|v| v.as_ref().ok()).copied();
            !matches!((p.field.parse(text), device), (Ok(Value::Int(v)), Some(d)) if v == d)
        });
    }

    /// The values to write (raw, by `data_id`), or the first reason they cannot be written.
    pub fn pending(&self, profile: &Profile) -> Result<Vec<(u8, i64)>, PendingError> {
        let mut out = Vec::new();
        for (id, text) in &self.edits {
            let Some(p) = profile.param(*id) else {
                continue;
            };
            match p.field.parse(text) {
                Ok(Value::Int(v)) => {
                    if self.device(*id) != Some(v) {
                        out.push((*id, v));
                    }
                }
                Ok(_) => {
                    return Err(PendingError::NotANumber {
                        field: p.field.ident.clone(),
                    });
                }
                Err(e) => return Err(e.into()),
            }
        }
        Ok(out)
    }

    /// The whole user block as it would be written: the servo's values with the edits applied.
    fn block(&self, profile: &Profile) -> Result<Vec<(u8, i64)>, PendingError> {
        let pending = self.pending(profile)?;
        profile
            .block_params()
            .map(|p| {
                if let Some((_, v)) = pending.iter().find(|(id, _)| *id == p.id) {
                    return Ok((p.id, *v));
                }
                self.device(p.id)
                    .map(|v| (p.id, v))
                    .ok_or_else(|| PendingError::BlockNotRead {
                        field: p.field.ident.clone(),
                    })
            })
            .collect()
    }

    /// Read all, Read block, Write changes, Write block, Revert and Reset user data…
    fn buttons(
        &mut self,
        ui: &mut egui::Ui,
        lang: Lang,
        rt: &Station,
        servo: Servo,
        can: bool,
        pending: &Result<Vec<(u8, i64)>, PendingError>,
    ) -> Vec<Action> {
        let mut actions = Vec::new();
        let profile = rt.device.profile.clone();
        crate::ui::layout::toolbar(ui, |ui| {
            if ui
                .add_enabled(can, egui::Button::new(lang.tr("Read all", "全部读取")))
                .on_hover_text(lang.tr(
                    "Read-only parameters one by one, user parameters as one 32-byte block",
                    "只读参数逐个读取, 用户参数按32字节批量读取",
                ))
                .clicked()
            {
                actions.push(read_all_job(rt, servo));
            }
            if ui
                .add_enabled(
                    can,
                    egui::Button::new(lang.tr("Read block (batch)", "批量读取用户参数")),
                )
                .on_hover_text(lang.tr(
                    "The 22 user parameters as one 32-byte block",
                    "一次读取22个用户参数(32字节)",
                ))
                .clicked()
            {
                actions.push(read_block_job(rt, servo));
            }
            let n = pending.as_ref().map_or(0, Vec::len);
            let write = ui.add_enabled(
                can && n > 0 && pending.is_ok(),
                egui::Button::new(format!("{} ({n})", lang.tr("Write changes", "写入修改"))),
            );
            if write.clicked()
                && let Ok(values) = pending
            {
                actions.push(write_job(rt, servo, values.clone()));
            }
            let block = self.block(&profile);
            if ui
                .add_enabled(
                    can && block.is_ok(),
                    egui::Button::new(lang.tr("Write block (batch)", "批量写入用户参数")),
                )
                .on_hover_text(match &block {
                    Ok(_) => lang
                        .tr(
                            "All 22 user parameters in one exchange, then read back",
                            "一次写入全部22个用户参数并回读",
                        )
                        .to_string(),
                    Err(e) => e.in_lang(lang),
                })
                .clicked()
                && let Ok(values) = block
            {
                actions.push(block_job(rt, servo, values));
            }
            if ui
                .add_enabled(
                    !self.edits.is_empty(),
                    egui::Button::new(lang.tr("Revert", "撤销修改")),
                )
                .clicked()
            {
                self.edits.clear();
            }
            if ui
                .add_enabled(
                    can,
                    egui::Button::new(lang.tr("Reset user data…", "重置用户数据…")),
                )
                .clicked()
            {
                self.confirm_reset = true;
            }
        });
        actions
    }

    /// Draws the tab.
    pub(super) fn show(
        &mut self,
        ui: &mut egui::Ui,
        lang: Lang,
        rt: &Station,
        busy: bool,
        selected: Option<Servo>,
    ) -> Vec<Action> {
        let mut actions = Vec::new();
        let Some(servo) = selection_or_hint(ui, lang, selected) else {
            return actions;
        };
        self.lang = lang;
        let profile = rt.device.profile.clone();
        self.prune(&profile);
        let pending = self.pending(&profile);
        let can = rt.connected() && !busy;
        // What the servo holds is shown as soon as the tab shows it: nothing is shown unread.
        if can && self.values.is_empty() && self.read_on_show != Some(servo) {
            self.read_on_show = Some(servo);
            actions.push(read_all_job(rt, servo));
        }
        actions.extend(self.buttons(ui, lang, rt, servo, can, &pending));
        // The first reason the edits cannot be written, on a line that is always there: an
        // invalid keystroke never moves the table under the pointer.
        match &pending {
            Err(e) => error_label(ui, e.in_lang(lang)),
            Ok(_) => {
                ui.label("");
            }
        }
        actions.extend(self.preset_row(ui, lang, rt));
        match &self.message {
            Some((true, m)) => ok_label(ui, m),
            Some((false, m)) => error_label(ui, m),
            None => {}
        }
        ui.separator();
        egui::Grid::new("servo-params")
            .striped(true)
            .num_columns(7)
            .min_col_width(40.0)
            .show(ui, |ui| {
                header_row(
                    ui,
                    &[
                        lang.tr("ID", "ID"),
                        lang.tr("Parameter", "参数"),
                        lang.tr("Servo", "舵机值"),
                        lang.tr("New value", "新值"),
                        lang.tr("Unit", "单位"),
                        lang.tr("Range", "范围"),
                        "",
                    ],
                );
                for p in &profile.params {
                    self.row(ui, lang, p);
                    ui.end_row();
                }
            });
        if self.confirm_reset {
            actions.extend(self.reset_dialog(ui, lang, rt, servo));
        }
        actions
    }

    fn row(&mut self, ui: &mut egui::Ui, lang: Lang, p: &Param) {
        let f = &p.field;
        ui.monospace(p.id.to_string());
        let name = ui
            .label(lang.tr(&f.name.en, &f.name.zh))
            .on_hover_text(&f.ident);
        let device = self.device(p.id);
        match self.values.get(&p.id) {
            Some(Ok(v)) => {
                crate::ui::inputs::device_value(ui, f, &Value::Int(*v), lang);
            }
            Some(Err(e)) => {
                ui.colored_label(
                    egui::Color32::from_rgb(210, 40, 40),
                    lang.tr("read failed", "读取失败"),
                )
                .on_hover_text(e.in_lang(lang));
            }
            None => {
                ui.weak(lang.tr("not read yet", "尚未读取"));
            }
        }
        let parsed = self.edits.get(&p.id).map(|t| f.parse(t));
        if p.reserved {
            ui.weak(lang.tr("reserved", "保留"));
        } else if editable(p) {
            let mut text =
                self.edits.get(&p.id).cloned().unwrap_or_else(|| {
                    device.map(|v| f.format(&Value::Int(v))).unwrap_or_default()
                });
            // An id of the parameter's own: the field keeps its focus whatever the rows above
            // it show.
            let salt = ("servo-param", p.id);
            let changed = if f.labels.is_empty() {
                let invalid = matches!(parsed, Some(Err(_)));
                let mut edit = egui::TextEdit::singleline(&mut text)
                    .id_salt(salt)
                    .desired_width(110.0);
                if invalid {
                    edit = edit.text_color(egui::Color32::from_rgb(210, 40, 40));
                }
                ui.add(edit).labelled_by(name.id).changed()
            } else {
                crate::ui::inputs::label_choice(ui, lang, f, salt, &mut text, name.id)
            };
            if changed {
                self.edits.insert(p.id, text);
            }
        } else if p.access == Access::ReadWrite {
            ui.weak(lang.tr("set in ID & baud rate", "在ID与波特率页设置"));
        } else {
            ui.weak(lang.tr("read-only", "只读"));
        }
        ui.label(&f.unit);
        ui.weak(crate::ui::inputs::allowed_in(f, lang));
        let changed = matches!(&parsed, Some(Ok(Value::Int(v))) if device != Some(*v));
        match (&parsed, self.marks.get(&p.id)) {
            (Some(Err(e)), _) => {
                ui.colored_label(
                    egui::Color32::from_rgb(210, 40, 40),
                    format!("× {}: {e}", lang.tr("invalid", "无效")),
                );
            }
            _ if changed => {
                ui.colored_label(
                    egui::Color32::from_rgb(220, 150, 0),
                    lang.tr("changed", "已修改"),
                );
            }
            (_, Some(ParamMark::Verified)) => ok_label(ui, lang.tr("verified", "已校验")),
            (_, Some(ParamMark::Mismatch(v))) => error_label(
                ui,
                format!(
                    "× {} {}",
                    lang.tr("mismatch: servo holds", "不一致: 舵机为"),
                    f.format(&Value::Int(*v))
                ),
            ),
            (_, Some(ParamMark::Failed(e))) => error_label(
                ui,
                format!("× {}: {e}", lang.tr("write failed", "写入失败")),
            ),
            _ => {
                ui.label("");
            }
        }
    }

    fn reset_dialog(
        &mut self,
        ui: &mut egui::Ui,
        lang: Lang,
        rt: &Station,
        servo: Servo,
    ) -> Vec<Action> {
        let mut actions = Vec::new();
        let home = ops::factory_location(&rt.device.profile);
        let mut decision = None;
        let modal = egui::Modal::new(egui::Id::unique("servo-reset")).show(ui.ctx(), |ui| {
            ui.heading(lang.tr("Reset user data?", "重置用户数据?"));
            ui.label(format!(
                "{} {} ({} {}). {} {} {} {} {}.",
                lang.tr("Servo", "舵机"),
                servo.id,
                servo.baud,
                lang.tr("baud", "波特"),
                lang.tr(
                    "All user parameters return to the factory defaults, including the id and the baud rate: the servo will be id",
                    "全部用户参数将恢复出厂默认值, 包括ID和波特率: 舵机将变为ID"
                ),
                home.id,
                lang.tr("at", "波特率"),
                home.baud,
                lang.tr("baud", "波特")
            ));
            ui.label(lang.tr(
                "It is refused if another servo already answers there. The parameters are read again afterwards.",
                "若已有其他舵机在该ID应答则拒绝执行。重置后将重新读取参数。",
            ));
            decision = crate::ui::confirm::buttons(
                ui,
                lang,
                lang.tr("Reset", "重置"),
                lang.tr("Keep", "不重置"),
                rt,
            );
        });
        if let Some(decision) = crate::ui::confirm::decided(&modal, decision) {
            self.confirm_reset = false;
            match decision {
                Decision::Yes => actions.push(reset_job(rt, servo)),
                Decision::No => {}
                Decision::Stop => actions.push(Action::Stop),
            }
        }
        actions
    }
}
