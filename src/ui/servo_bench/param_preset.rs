//! Servo parameter presets in the parameters tab: the file path, loading a preset into the
//! edits (checked against the profile; a bad file is refused with its line and column, nothing of
//! it is taken), saving what the servo holds.

use super::params::{ParamsState, editable};
use crate::i18n::Lang;
use crate::ops::servo::preset::ParamPreset;
use crate::profile::{Profile, Value};
use eframe::egui;

impl ParamsState {
    pub(super) fn preset_row(&mut self, ui: &mut egui::Ui, lang: Lang, profile: &Profile) {
        crate::ui::layout::toolbar(ui, |ui| {
            crate::ui::layout::group(ui, "preset", |ui| {
                let l = ui.label(lang.tr("Parameter preset", "参数预设"));
                ui.add(egui::TextEdit::singleline(&mut self.preset_path).desired_width(260.0))
                    .labelled_by(l.id);
            });
            if ui.button(lang.tr("Open…", "打开…")).clicked()
                && let Some(p) = rfd::FileDialog::new()
                    .add_filter("RON", &["ron"])
                    .pick_file()
            {
                self.preset_path = p.display().to_string();
                self.load_preset(profile);
            }
            if ui
                .add_enabled(
                    !self.preset_path.trim().is_empty(),
                    egui::Button::new(lang.tr("Load preset", "载入预设")),
                )
                .clicked()
            {
                self.load_preset(profile);
            }
            crate::ui::layout::group(ui, "note", |ui| {
                let l = ui.label(lang.tr("Note", "备注"));
                ui.add(egui::TextEdit::singleline(&mut self.note).desired_width(140.0))
                    .labelled_by(l.id);
            });
            if ui
                .button(lang.tr("Save preset as…", "预设另存为…"))
                .clicked()
                && let Some(p) = rfd::FileDialog::new()
                    .add_filter("RON", &["ron"])
                    .set_file_name("servo-params.ron")
                    .save_file()
            {
                self.preset_path = p.display().to_string();
                self.save_preset(profile);
            }
            if ui
                .add_enabled(
                    !self.preset_path.trim().is_empty(),
                    egui::Button::new(lang.tr("Save preset", "保存预设")),
                )
                .clicked()
            {
                self.save_preset(profile);
            }
        });
    }

    /// Loads the preset at the path into the edits (nothing is written until "Write changes").
    pub fn load_preset(&mut self, profile: &Profile) {
        let path = std::path::PathBuf::from(self.preset_path.trim());
        match ParamPreset::load(&path, profile) {
            Ok(preset) => {
                let values = preset.resolve(profile).unwrap_or_default();
                for (id, raw) in &values {
                    if let Some(p) = profile.param(*id) {
                        self.edits.insert(*id, p.field.format(&Value::Int(*raw)));
                    }
                }
                self.note = preset.note;
                self.message = Some((
                    true,
                    format!(
                        "{} {} {}: {}",
                        values.len(),
                        self.lang.tr("values loaded from", "个值载入自"),
                        path.display(),
                        self.lang
                            .tr("review them, then Write changes", "请检查后点击写入修改")
                    ),
                ));
            }
            Err(e) => self.message = Some((false, e.to_string())),
        }
    }

    /// Saves what the servo holds (as read) to the preset path.
    pub fn save_preset(&mut self, profile: &Profile) {
        let missing: Vec<&str> = profile
            .params
            .iter()
            .filter(|p| editable(p) && self.device(p.id).is_none())
            .map(|p| p.field.ident.as_str())
            .collect();
        if !missing.is_empty() {
            self.message = Some((
                false,
                format!(
                    "{}: {}",
                    self.lang
                        .tr("read all first; not read", "请先全部读取; 未读取"),
                    missing.join(", ")
                ),
            ));
            return;
        }
        if !self.edits.is_empty() {
            self.message = Some((
                false,
                self.lang
                    .tr(
                        "write or revert the edits first: a preset holds what the servo holds",
                        "请先写入或撤销修改: 预设保存的是舵机中的值",
                    )
                    .into(),
            ));
            return;
        }
        let values: Vec<(u8, i64)> = self
            .values
            .iter()
            .filter_map(|(id, v)| Some((*id, *v.as_ref().ok()?)))
            .collect();
        let preset = ParamPreset::from_values(profile, &self.note, &values);
        let path = std::path::PathBuf::from(self.preset_path.trim());
        self.message = Some(match preset.save(&path, profile) {
            Ok(()) => (
                true,
                format!(
                    "{} {}",
                    self.lang.tr("saved to", "已保存到"),
                    path.display()
                ),
            ),
            Err(e) => (
                false,
                format!("{}: {e}", self.lang.tr("cannot save", "无法保存")),
            ),
        });
    }
}
