//! Servo parameter presets in the parameters tab: the file (typed, or chosen with Browse…, and
//! remembered), loading a preset into the edits (checked against the profile; a bad file is refused with its line and column, nothing of
//! it is taken), saving what the servo holds.

use super::params::{ParamsState, editable};
use crate::i18n::Lang;
use crate::ops::servo::preset::ParamPreset;
use crate::profile::{Profile, Value};
use crate::ui::settings::FileKind;
use crate::ui::station::Station;
use crate::ui::{Action, files};
use eframe::egui;

impl ParamsState {
    /// The preset file row (typed path, Browse…), Load preset, the note and Save preset; a
    /// preset loaded or saved is remembered.
    pub(super) fn preset_row(
        &mut self,
        ui: &mut egui::Ui,
        lang: Lang,
        rt: &Station,
    ) -> Vec<Action> {
        let mut actions = Vec::new();
        let profile = &rt.device.profile;
        crate::ui::layout::toolbar(ui, |ui| {
            let event = files::row(
                ui,
                lang,
                files::Row {
                    label: lang.tr("Parameter preset", "参数预设"),
                    hint: "servo-params.ron",
                    pick: files::Pick::Open(&["ron"]),
                    enabled: true,
                },
                &mut self.preset_path,
                &rt.dialogs,
            );
            let named = !self.preset_path.trim().is_empty();
            let load = ui
                .add_enabled(named, egui::Button::new(lang.tr("Load preset", "载入预设")))
                .clicked();
            if event.go(load, &mut actions) && self.load_preset(profile) {
                actions.push(self.remember());
            }
            crate::ui::layout::group(ui, "note", |ui| {
                let l = ui.label(lang.tr("Note", "备注"));
                ui.add(egui::TextEdit::singleline(&mut self.note).desired_width(140.0))
                    .labelled_by(l.id);
            });
            if ui
                .add_enabled(named, egui::Button::new(lang.tr("Save preset", "保存预设")))
                .clicked()
                && self.save_preset(profile)
            {
                actions.push(self.remember());
            }
        });
        actions
    }

    fn remember(&self) -> Action {
        Action::RememberFile(FileKind::ServoPreset, self.preset_path.trim().to_string())
    }

    /// Loads the preset at the path into the edits (nothing is written until "Write changes");
    /// whether it loaded.
    pub fn load_preset(&mut self, profile: &Profile) -> bool {
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
        self.message.as_ref().is_some_and(|(ok, _)| *ok)
    }

    /// Saves what the servo holds (as read) to the preset path; whether it was saved.
    pub fn save_preset(&mut self, profile: &Profile) -> bool {
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
            return false;
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
            return false;
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
        self.message.as_ref().is_some_and(|(ok, _)| *ok)
    }
}
