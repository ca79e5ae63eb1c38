//! The tuning table: one grid per group of the profile, every group's columns in the same
//! places, the names' column as wide as the longest name.

use super::{TuningPanel, named, profile_set};
use crate::i18n::Lang;
use crate::profile::{Command, CommandKind, Field, FieldError, Value};
use crate::ui::inputs::range_text;
use crate::ui::station::{Mark, Reading, Station};
use crate::ui::zh::Zh;
use eframe::egui;

/// A panel group: its id ("" for the commands without one), its name, its Get/Set pairs.
pub(super) struct Group<'p> {
    pub(super) id: String,
    pub(super) name: String,
    pub(super) pairs: Vec<(&'p Command, &'p Command)>,
}

/// The Get/Set pairs of the profile, grouped.
pub(super) fn groups(rt: &Station, lang: Lang) -> Vec<Group<'_>> {
    let p = &rt.device.profile;
    let pairs: Vec<(&Command, &Command)> = p
        .commands
        .iter()
        .filter(|c| c.kind == CommandKind::Get)
        .filter_map(|g| Some((g, p.command_by_id(g.pair?)?)))
        .collect();
    let mut out: Vec<Group<'_>> = p
        .groups
        .iter()
        .map(|g| {
            let members = pairs
                .iter()
                .filter(|(get, _)| get.group.as_deref() == Some(&g.id))
                .copied()
                .collect();
            Group {
                id: g.id.clone(),
                name: lang.tr(&g.name.en, &g.name.zh).to_string(),
                pairs: members,
            }
        })
        .collect();
    let other: Vec<_> = pairs
        .iter()
        .filter(|(get, _)| get.group.is_none())
        .copied()
        .collect();
    if !other.is_empty() {
        out.push(Group {
            id: String::new(),
            name: lang.tr("Other", "其他").to_string(),
            pairs: other,
        });
    }
    out.retain(|g| !g.pairs.is_empty());
    out
}

impl TuningPanel {
    /// One grid per group, so that its columns line up: a header row per command, then its
    /// fields.
    pub(super) fn group_grid(
        &mut self,
        ui: &mut egui::Ui,
        lang: Lang,
        rt: &Station,
        group: &Group<'_>,
        names: f32,
    ) {
        // Every group's table has the same six columns across the whole width, whatever its
        // contents: a long text wraps or is cut in its cell instead of moving the columns. The
        // names' column is as wide as the profile's longest name (up to 40 % of the width), so
        // that a name never wraps where it fits; the other five share the rest.
        let gap = ui.spacing().item_spacing.x;
        let width = ui.available_width() - 5.0 * gap;
        let name_col = names.clamp(width / 6.0, width * 0.4).max(60.0);
        let col = ((width - name_col) / 5.0).max(60.0);
        let name_cell = |ui: &mut egui::Ui, text: egui::RichText| {
            crate::ui::layout::wrapped_cell(ui, name_col, egui::Label::new(text))
        };
        egui::Grid::new(("fields", &group.id))
            .num_columns(6)
            .striped(true)
            .min_col_width(col)
            .max_col_width(col)
            .show(ui, |ui| {
                name_cell(ui, egui::RichText::new(lang.tr("Field", "字段")).weak());
                ui.weak(lang.tr("Device", "设备值"));
                ui.weak(lang.tr("Edited", "修改值"));
                ui.weak(lang.tr("Unit", "单位"));
                ui.weak(lang.tr("Range", "范围"));
                ui.weak("");
                ui.end_row();
                for (get, set) in &group.pairs {
                    name_cell(
                        ui,
                        egui::RichText::new(lang.tr(&get.name.en, &get.name.zh)).italics(),
                    )
                    .on_hover_text(format!(
                        "{} {} / {} {}",
                        get.ident, get.id, set.ident, set.id
                    ));
                    let refused = rt.device.refused.get(&get.id);
                    match rt.device.readings.get(&get.id) {
                        _ if refused.is_some() => {
                            let e = refused.map(|e| lang.tr(&e.to_string(), &e.zh()).to_string());
                            let text = format!(
                                "{}: {}",
                                lang.tr("write refused, nothing sent", "写入被拒绝,未发送"),
                                e.unwrap_or_default()
                            );
                            let label = egui::RichText::new(&text).color(egui::Color32::RED);
                            ui.add(egui::Label::new(label).truncate())
                                .on_hover_text(text);
                        }
                        Some(Reading::Failed(e)) => {
                            let text = format!("{}: {e}", lang.tr("read failed", "读取失败"));
                            let label = egui::RichText::new(&text).color(egui::Color32::RED);
                            ui.add(egui::Label::new(label).truncate())
                                .on_hover_text(text);
                        }
                        _ => {
                            ui.weak(format!("{} / {}", get.id, set.id));
                        }
                    }
                    ui.end_row();
                    for f in &get.reply {
                        let name = name_cell(ui, egui::RichText::new(field_name(f, lang)))
                            .on_hover_text(&f.ident);
                        self.field_row(ui, lang, rt, get.id, f, name.id);
                        ui.end_row();
                    }
                }
            });
    }

    /// A field's row after its name (labelled by `name`): device value, edit, unit, range and
    /// mark.
    fn field_row(
        &mut self,
        ui: &mut egui::Ui,
        lang: Lang,
        rt: &Station,
        get: u8,
        f: &Field,
        name: egui::Id,
    ) {
        let key = (get, f.ident.clone());
        let device = rt.device.value(get, &f.ident);
        match device {
            Some(v) => crate::ui::inputs::device_value(ui, f, v, lang),
            None => ui.weak(lang.tr("not read yet", "尚未读取")),
        };
        let writable =
            profile_set(rt, get).is_none_or(|set| set.request.iter().any(|sf| sf.ident == f.ident));
        let mut text = self
            .edits
            .get(&key)
            .cloned()
            .unwrap_or_else(|| device.map(|v| f.format(v)).unwrap_or_default());
        let parsed = self.edits.get(&key).map(|t| f.parse(t));
        // A relation broken by the edits marks both its fields, as typed.
        let broken = self
            .broken
            .as_ref()
            .filter(|(g, sides, _)| *g == get && sides.contains(&f.ident))
            .map(|(_, _, text)| text.clone());
        let invalid = matches!(parsed, Some(Err(_))) || broken.is_some();
        let changed = matches!(&parsed, Some(Ok(v)) if device != Some(v));
        let resp = if f.labels.is_empty() {
            let mut edit = egui::TextEdit::singleline(&mut text).desired_width(90.0);
            if invalid {
                edit = edit.text_color(egui::Color32::RED);
            }
            ui.add_enabled(writable, edit).labelled_by(name)
        } else {
            // A named value is chosen by its name, not typed.
            let before = text.clone();
            let resp = ui
                .add_enabled_ui(writable, |ui| {
                    crate::ui::inputs::label_choice(
                        ui,
                        lang,
                        f,
                        ("tuning", get, &f.ident),
                        &mut text,
                        name,
                    );
                })
                .response;
            if text != before {
                self.edits.insert(key.clone(), text.clone());
            }
            resp
        };
        let resp = if writable {
            resp
        } else {
            resp.on_disabled_hover_text(lang.tr(
                "read only: the Set command does not carry this field",
                "只读:设置命令不含此字段",
            ))
        };
        let resp = if invalid {
            ui.painter().rect_stroke(
                resp.rect,
                2.0,
                egui::Stroke::new(1.5, egui::Color32::RED),
                egui::StrokeKind::Outside,
            );
            match broken {
                Some(text) => resp.on_hover_text(text),
                None => resp,
            }
        } else {
            resp
        };
        if resp.changed() {
            self.edits.insert(key.clone(), text);
        }
        unit_cell(ui, lang, f);
        ui.weak(crate::ui::inputs::allowed_in(f, lang));
        mark_cell(ui, lang, f, &parsed, changed, rt.device.mark(get, &f.ident));
    }
}

/// A field's name as its table row shows it, indented under its command.
fn field_name(f: &Field, lang: Lang) -> String {
    format!("   {}", lang.tr(&f.name.en, &f.name.zh))
}

/// The width, points, of the longest command or field name the tables show in `lang`.
pub(super) fn name_width(ui: &egui::Ui, lang: Lang, rt: &Station) -> f32 {
    let mut names = Vec::new();
    for group in groups(rt, lang) {
        for (get, _) in &group.pairs {
            names.push(lang.tr(&get.name.en, &get.name.zh).to_string());
            names.extend(get.reply.iter().map(|f| field_name(f, lang)));
        }
    }
    let font = crate::ui::layout::body_font(ui);
    crate::ui::layout::text_width(ui, &font, names.iter().map(String::as_str)) + 4.0
}

/// The field's unit; where the protocol publishes none, says so.
fn unit_cell(ui: &mut egui::Ui, lang: Lang, f: &Field) {
    if f.unit.is_empty() {
        ui.weak("—").on_hover_text(lang.tr(
            "the protocol does not publish this field's unit",
            "协议未公布此字段的单位",
        ));
    } else {
        ui.label(&f.unit);
    }
}

/// A field's mark: its edit refused (why, on hover), changed, verified after a write, or read
/// back otherwise than written.
fn mark_cell(
    ui: &mut egui::Ui,
    lang: Lang,
    f: &Field,
    parsed: &Option<Result<Value, FieldError>>,
    changed: bool,
    mark: Option<&Mark>,
) {
    match (parsed, mark) {
        (Some(Err(e)), _) => {
            ui.colored_label(
                egui::Color32::RED,
                format!("× {}", lang.tr("invalid", "无效")),
            )
            .on_hover_text(format!(
                "{}\n{}: {}",
                named(&e.in_lang(lang), f, lang),
                lang.tr("allowed", "允许"),
                range_text(f)
            ));
        }
        _ if changed => {
            ui.colored_label(
                egui::Color32::from_rgb(220, 150, 0),
                format!("● {}", lang.tr("changed", "已修改")),
            );
        }
        (_, Some(Mark::Verified)) => {
            ui.colored_label(
                egui::Color32::from_rgb(40, 160, 60),
                format!("✓ {}", lang.tr("verified", "已校验")),
            );
        }
        (_, Some(Mark::Mismatch(read))) => {
            ui.colored_label(
                egui::Color32::RED,
                format!(
                    "× {} {}",
                    lang.tr("mismatch: device holds", "不一致:设备为"),
                    f.format(read)
                ),
            );
        }
        _ => {
            ui.label("");
        }
    }
}
