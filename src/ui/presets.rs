//! Presets: save the device's parameters to a RON file, open one and compare it with the device
//! in a diff table, apply it with read-back verification and a progress bar.

use super::confirm::Decision;
use super::jobs::{self, Job, JobError, JobOutput};
use super::settings::FileKind;
use super::station::{Reading, Station};
use super::{Action, files};
use crate::document::DocumentError;
use crate::i18n::Lang;
use crate::i18n::Text;
use crate::ops;
use crate::ops::{Device, Run};
use crate::preset::{CommandValues, DiffRow, Loaded, Preset, preset_commands};
use crate::profile::Profile;
use crate::ui::zh::Zh;
use eframe::egui;
use std::path::PathBuf;
use std::sync::Arc;

/// The panel's state: the file, and the preset opened from it.
#[derive(Default)]
pub struct PresetsPanel {
    /// The preset file's path.
    pub path: String,
    /// A note saved with the preset.
    pub note: String,
    /// The preset opened (checked against the profile).
    pub loaded: Option<Loaded>,
    /// Why the last open failed, with line and column.
    pub error: Option<DocumentError>,
    /// Apply was clicked: the preset waits for the technician's yes.
    pub confirm_apply: bool,
}

/// Reads the device's parameters and saves them as a preset at `path`, with `note`
/// ([`ops::preset::capture`]).
fn save_job(profile: &Arc<Profile>, path: PathBuf, note: String) -> Job {
    let profile = profile.clone();
    Job::new(
        Text::new("save preset", "保存预设"),
        move |client, cancel, sink| {
            let mut preset = ops::preset::capture(
                Device::new(client, &profile),
                &mut Run::new(cancel, |p| sink.progress(p)),
            )?;
            preset.note = note;
            preset.save_annotated(&path, &profile)?;
            Ok(Text::new(
                format!("saved to {}", path.display()),
                format!("已保存到 {}", path.display()),
            ))
        },
    )
}

/// Writes a (checked) preset, each command read back ([`ops::preset::apply_each`]); each
/// command's checks go to the device model.
fn apply_job(rt: &Station, preset: Preset, file: &str) -> Job {
    let profile = rt.device.profile.clone();
    let mut records = rt.records.clone();
    let path = std::path::Path::new(file.trim());
    let given = crate::ops::records::runs::Given {
        plan_sha256: crate::ops::records::record::file_sha256(path),
        plan_name: Some(crate::ops::records::runs::plan_name(path)),
        ..Default::default()
    };
    Job::new(
        Text::new("apply preset", "应用预设"),
        move |client, cancel, sink| {
            let mut total = 0;
            let mut bad = 0;
            // Run, then record (before the verdict is shown).
            let recorded = crate::ops::records::runs::preset_apply(
                Device::new(client, &profile),
                &preset,
                &given,
                &mut Run::new(cancel, |p| sink.progress(p)),
                &mut |command, checks| {
                    total += checks.len();
                    bad += checks.iter().filter(|c| !c.ok()).count();
                    if let Some(cmd) = profile.command(command) {
                        sink.send(JobOutput::Wrote(cmd.id, Ok(checks.to_vec())));
                    }
                },
                &mut records,
            );
            recorded.outcome?;
            if bad == 0 {
                Ok(crate::ui::records::with_note(
                    Text::new(
                        format!("{total} field(s) written and verified"),
                        format!("{total} 个字段已写入并校验"),
                    ),
                    &recorded.kept,
                ))
            } else {
                Err(JobError::Incomplete {
                    failed: bad,
                    total,
                    what: crate::ui::records::with_note(
                        Text::new(
                            "field(s) do not hold the preset's value",
                            "个字段未保持预设值",
                        ),
                        &recorded.kept,
                    ),
                })
            }
        },
    )
}

/// The device's values of the preset commands, from the readings replies brought.
fn device_values(rt: &Station) -> Vec<CommandValues> {
    preset_commands(&rt.device.profile)
        .into_iter()
        .filter_map(|(set, get)| {
            let Some(Reading::Values(values, _)) = rt.device.readings.get(&get.id) else {
                return None;
            };
            Some(ops::preset::command_values(set, values))
        })
        .collect()
}

impl PresetsPanel {
    /// Opens the preset at `path`, checking it against the profile.
    pub fn open(&mut self, rt: &Station) {
        match Preset::load(&PathBuf::from(self.path.trim()), &rt.device.profile) {
            Ok(l) => {
                self.loaded = Some(l);
                self.error = None;
            }
            Err(e) => {
                self.loaded = None;
                self.error = Some(e);
            }
        }
    }

    /// Draws the panel.
    fn draw(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &Station) -> Vec<Action> {
        let mut actions = Vec::new();
        let profile = &rt.device.profile;
        let busy = rt.job_progress().is_some();
        let ready = rt.connected() && !busy;
        actions.extend(self.file_rows(ui, lang, rt, ready));
        if let Some(e) = &self.error {
            ui.colored_label(egui::Color32::RED, e.in_lang(lang));
        }
        ui.separator();
        let Some(loaded) = &self.loaded else {
            ui.weak(lang.tr(
                "Open a preset to compare it with the device and apply it.",
                "打开一个预设,与设备比较并写入。",
            ));
            return actions;
        };
        let p = &loaded.preset;
        // The preset's profile by its name in the window's language, when it is the one in use.
        let profile_name = if p.profile == profile.id {
            profile.name.get(lang).to_string()
        } else {
            p.profile.clone()
        };
        ui.label(format!(
            "{}: {}  {}: {}  {}: {}",
            lang.tr("profile", "配置"),
            profile_name,
            lang.tr("created", "创建于"),
            p.created,
            lang.tr("device", "设备"),
            p.device.as_deref().unwrap_or("-")
        ));
        if !p.note.is_empty() {
            ui.label(&p.note);
        }
        let device = device_values(rt);
        let rows = p.diff(profile, &device);
        let differing = rows.iter().filter(|r| r.differs).count();
        ui.horizontal(|ui| {
            let gets: Vec<u8> = preset_commands(profile).iter().map(|(_, g)| g.id).collect();
            if ui
                .add_enabled(
                    ready,
                    egui::Button::new(lang.tr("Compare with device", "与设备比较")),
                )
                .clicked()
            {
                actions.push(Action::StartJob(jobs::read(profile, gets)));
            }
            let apply = ui.add_enabled(
                ready,
                egui::Button::new(format!("{} ({differing})", lang.tr("Apply", "写入预设"))),
            );
            if apply.clicked() {
                self.confirm_apply = true;
            }
        });
        egui::ScrollArea::vertical()
            .auto_shrink(false)
            .show(ui, |ui| {
                diff_table(ui, lang, profile, &rows);
            });
        if self.confirm_apply {
            let preset = p.clone();
            match confirm(ui, lang, differing, rt) {
                Some(Decision::Yes) => {
                    self.confirm_apply = false;
                    actions.push(Action::StartJob(apply_job(rt, preset, &self.path)));
                }
                Some(Decision::No) => self.confirm_apply = false,
                Some(Decision::Stop) => {
                    self.confirm_apply = false;
                    actions.push(Action::Stop);
                }
                None => {}
            }
        }
        actions
    }

    /// The file row (a preset to open), and the note, Save device to file and Factory defaults.
    fn file_rows(
        &mut self,
        ui: &mut egui::Ui,
        lang: Lang,
        rt: &Station,
        ready: bool,
    ) -> Vec<Action> {
        let mut actions = Vec::new();
        let profile = &rt.device.profile;
        crate::ui::layout::toolbar(ui, |ui| {
            let event = files::row(
                ui,
                lang,
                files::Row {
                    label: lang.tr("File", "文件"),
                    hint: "window-cleaner.ron",
                    pick: files::Pick::Open(&["ron"]),
                    enabled: true,
                },
                &mut self.path,
                &rt.dialogs,
            );
            let open = ui.button(lang.tr("Open", "打开")).clicked();
            if event.go(open, &mut actions) {
                actions.extend(self.open_and_remember(rt));
            }
        });
        crate::ui::layout::toolbar(ui, |ui| {
            let label = ui.label(lang.tr("Note", "备注"));
            ui.add(egui::TextEdit::singleline(&mut self.note).desired_width(240.0))
                .labelled_by(label.id);
            let can_save = ready && !self.path.trim().is_empty();
            if ui
                .add_enabled(
                    can_save,
                    egui::Button::new(lang.tr("Save device to file", "保存设备参数到文件")),
                )
                .clicked()
            {
                actions.push(Action::RememberFile(
                    FileKind::Preset,
                    self.path.trim().to_string(),
                ));
                actions.push(Action::StartJob(save_job(
                    profile,
                    PathBuf::from(self.path.trim()),
                    self.note.clone(),
                )));
            }
            if ui
                .button(lang.tr("Factory defaults", "出厂默认值"))
                .clicked()
            {
                let preset = Preset::defaults(profile, "factory defaults from the profile");
                match preset.validate(profile) {
                    Ok(writes) => {
                        self.loaded = Some(Loaded { preset, writes });
                        self.error = None;
                        // The defaults come from the profile, not from the file named.
                        self.path.clear();
                    }
                    Err(e) => self.error = Some(e),
                }
            }
        });
        actions
    }

    /// Opens the preset at the path typed or chosen, and remembers the path.
    fn open_and_remember(&mut self, rt: &Station) -> Vec<Action> {
        self.open(rt);
        if self.error.is_some() {
            return Vec::new();
        }
        vec![Action::RememberFile(
            FileKind::Preset,
            self.path.trim().to_string(),
        )]
    }
}

/// Asks before applying, as Tuning's "Write changes" does: [`Decision::Yes`] to write, STOP
/// beside the answers.
fn confirm(ui: &mut egui::Ui, lang: Lang, differing: usize, rt: &Station) -> Option<Decision> {
    let mut decision = None;
    let modal = egui::Modal::new(egui::Id::unique("confirm-apply-preset")).show(ui.ctx(), |ui| {
        ui.heading(lang.tr("Apply this preset?", "写入此预设?"));
        ui.label(format!(
            "{differing} {}",
            lang.tr(
                "field(s) differ from the device; the preset's commands will be written, then read back.",
                "项与设备不同;预设的命令将被写入并回读校验。",
            )
        ));
        decision = super::confirm::buttons(
            ui,
            lang,
            lang.tr("Write", "写入"),
            lang.tr("Cancel", "取消"),
            rt,
        );
    });
    super::confirm::decided(&modal, decision)
}

/// The preset beside the device, field by field, by the profile's names (the wire names on
/// hover); a preset value that differs is marked.
fn diff_table(ui: &mut egui::Ui, lang: Lang, profile: &Profile, rows: &[DiffRow]) {
    crate::ui::layout::table(ui, egui::Grid::new("preset-diff"), &[
                    lang.tr("Command", "命令"),
                    lang.tr("Field", "字段"),
                    lang.tr("Preset", "预设值"),
                    lang.tr("Device", "设备值"),
                ], |ui| {
            for r in rows {
                // The profile's names, the wire names on hover.
                let cmd = profile.command(&r.command);
                let field = cmd.and_then(|c| {
                    c.request
                        .iter()
                        .chain(&c.reply)
                        .find(|f| f.ident == r.field)
                });
                let named = |t: Option<&crate::i18n::Text>, wire: &str| {
                    t.map_or(wire.to_string(), |t| t.get(lang).to_string())
                };
                ui.label(named(cmd.map(|c| &c.name), &r.command))
                    .on_hover_text(&r.command);
                ui.label(named(field.map(|f| &f.name), &r.field))
                    .on_hover_text(&r.field);
                if r.differs {
                    ui.colored_label(egui::Color32::from_rgb(220, 150, 0), &r.preset);
                } else {
                    ui.label(&r.preset);
                }
                match &r.device {
                    Some(d) => ui.label(d),
                    None => ui.weak(lang.tr("not read yet", "尚未读取")),
                };
                ui.end_row();
            }
        });
}

impl crate::ui::PanelId {
    /// Presets: save, compare, apply.
    pub const PRESETS: crate::ui::PanelId = crate::ui::PanelId::new("Presets");
}

impl crate::ui::Panel for PresetsPanel {
    fn id(&self) -> crate::ui::PanelId {
        crate::ui::PanelId::PRESETS
    }

    fn name(&self, lang: Lang) -> &'static str {
        lang.tr("Presets", "预设")
    }

    fn kind(&self) -> Option<crate::profile::PanelKind> {
        Some(crate::profile::PanelKind::Presets)
    }

    fn show(&mut self, ui: &mut egui::Ui, cx: &crate::ui::panel::Cx<'_>) -> Vec<Action> {
        self.draw(ui, cx.lang, cx.station)
    }

    fn restore(&mut self, settings: &crate::ui::Settings) {
        if let Some(p) = settings.file(FileKind::Preset) {
            self.path = p.to_string();
        }
    }
}
