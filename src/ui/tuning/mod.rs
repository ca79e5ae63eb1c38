//! The tuning panel, generated from the profile: every Get/Set pair in its group, each field with
//! the device's value, the edited value, unit and range. Edits are checked as typed; "Write
//! changes" shows the diff, writes only the changed commands (each with its full payload) and
//! reads them back.

mod table;

use super::Action;
use super::confirm;
use super::jobs;
use super::station::Station;
use crate::i18n::Lang;
use crate::ops::tuning::SetWrite;
use crate::profile::{Command, CommandKind, Field, FieldError, Value};
use crate::ui::zh::Zh;
use eframe::egui;
use std::collections::HashMap;

/// One pending change, for the confirmation table.
#[derive(Debug, Clone, PartialEq)]
pub struct Change {
    /// The Set command's ident.
    pub command: String,
    /// The field's ident.
    pub field: String,
    /// The Set command's name, as the window shows it.
    pub command_name: crate::i18n::Text,
    /// The field's name, as the window shows it.
    pub field_name: crate::i18n::Text,
    /// The device's value, as shown.
    pub device: String,
    /// The new value, as shown.
    pub new: String,
}

/// The writes of a "Write changes": each Set command with its full payload.
pub type Writes = Vec<SetWrite>;

/// Why the edits cannot be written.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PendingError {
    /// An edit the field refuses.
    #[error(transparent)]
    Value(#[from] FieldError),
    /// Edits of Get command `get` that break one of the profile's relations (minimum ≤
    /// default ≤ maximum): `error` is a [`FieldError::Relation`] naming both fields.
    #[error("{error}")]
    Relation {
        /// The Get command whose fields break it.
        get: u8,
        /// The relation broken, both sides named with their values.
        error: FieldError,
    },
    /// A typed value that is not a number where one is needed.
    #[error("{field}: not a number")]
    NotANumber {
        /// The field's ident.
        field: String,
    },
    /// A parameter of the servo's user block that has not been read: the block is written
    /// whole.
    #[error("{field} has not been read: read all first, so that the whole block can be written")]
    BlockNotRead {
        /// The parameter's ident.
        field: String,
    },
    /// A field of an edited command that has not been read: a Set sends every field.
    #[error(
        "{command}: {field} has not been read; read it first so that the whole command can be written"
    )]
    NotRead {
        /// The Set command's ident.
        command: String,
        /// The field's ident.
        field: String,
    },
}

/// The panel's own state: what the technician typed.
#[derive(Default)]
pub struct TuningPanel {
    /// Edited text by (Get command id, field ident).
    pub edits: HashMap<(u8, String), String>,
    /// The changes awaiting confirmation, and the writes they make.
    confirm: Option<(Vec<Change>, Writes)>,
    /// A group to bring to the top of the table on the next frame (by its id).
    pub scroll_to: Option<String>,
    /// The relation the edits break now, if one: its Get command, its two fields' idents and
    /// what it says (in the window's language), for the two fields' boxes.
    broken: Option<(u8, [String; 2], String)>,
}

/// The ids of the profile's groups as the table shows them, in order ("" for the commands of
/// no group).
pub fn group_ids(rt: &Station) -> Vec<String> {
    table::groups(rt, Lang::En)
        .into_iter()
        .map(|g| g.id)
        .collect()
}

impl TuningPanel {
    /// What an edit parses to, if there is an edit.
    fn edited(&self, get: u8, field: &Field) -> Option<Result<Value, FieldError>> {
        let text = self.edits.get(&(get, field.ident.clone()))?;
        Some(field.parse(text))
    }

    /// Drops edits that now equal the device's value (after a verified write, or typed back).
    fn prune(&mut self, rt: &Station) {
        let profile = &rt.device.profile;
        self.edits.retain(|(get, ident), text| {
            let Some(field) = profile
                .command_by_id(*get)
                .and_then(|c| c.reply.iter().find(|f| &f.ident == ident))
            else {
                return false;
            };
            match (field.parse(text), rt.device.value(*get, ident)) {
                (Ok(v), Some(d)) => &v != d,
                _ => true,
            }
        });
    }

    /// The writes the edits call for, or why they cannot be made.
    pub fn pending(&self, rt: &Station) -> Result<(Vec<Change>, Writes), PendingError> {
        let mut changes = Vec::new();
        let mut writes = Vec::new();
        let profile = &rt.device.profile;
        for (get, set) in profile
            .commands
            .iter()
            .filter(|c| c.kind == CommandKind::Get)
            .filter_map(|g| Some((g, profile.command_by_id(g.pair?)?)))
        {
            let touched = get
                .reply
                .iter()
                .any(|f| self.edits.contains_key(&(get.id, f.ident.clone())));
            if !touched {
                continue;
            }
            // The Set's own fields, each from the Get's field of the same ident: a Set may
            // leave out fields its Get reads (a variant's SET 225 has no waterPump).
            let mut inputs = Vec::new();
            for f in set
                .request
                .iter()
                .filter_map(|sf| get.reply.iter().find(|f| f.ident == sf.ident))
            {
                let device = rt.device.value(get.id, &f.ident);
                let value = match self.edited(get.id, f) {
                    Some(Ok(v)) => {
                        if device != Some(&v) {
                            changes.push(Change {
                                command: set.ident.clone(),
                                field: f.ident.clone(),
                                command_name: set.name.clone(),
                                field_name: f.name.clone(),
                                device: device.map_or("—".into(), |d| f.format(d)),
                                new: f.format(&v),
                            });
                        }
                        v
                    }
                    Some(Err(e)) => return Err(e.into()),
                    None => match device {
                        Some(d) => d.clone(),
                        None => {
                            return Err(PendingError::NotRead {
                                command: set.ident.clone(),
                                field: f.ident.clone(),
                            });
                        }
                    },
                };
                inputs.push((f.ident.clone(), crate::profile::Input::Raw(value)));
            }
            // The profile's relations, checked as typed: the write would be refused whole.
            if let Err(error @ FieldError::Relation(_)) =
                profile.encode(set, crate::protocol::Direction::HostToDevice, &inputs)
            {
                return Err(PendingError::Relation { get: get.id, error });
            }
            writes.push((set.id, inputs));
        }
        Ok((changes, writes))
    }

    /// Draws the panel.
    fn draw(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &Station) -> Vec<Action> {
        let mut actions = Vec::new();
        self.prune(rt);
        let pending = self.pending(rt);
        self.broken = match &pending {
            Err(e @ PendingError::Relation { get, error: FieldError::Relation(b) }) => Some((
                *get,
                [b.low.clone(), b.high.clone()],
                pending_text(e, rt, lang),
            )),
            _ => None,
        };
        let busy = rt.job_progress().is_some();
        ui.horizontal(|ui| {
            let gets: Vec<u8> = rt
                .device
                .profile
                .commands
                .iter()
                .filter(|c| c.kind == CommandKind::Get && c.pair.is_some())
                .map(|c| c.id)
                .collect();
            if ui
                .add_enabled(
                    rt.connected() && !busy,
                    egui::Button::new(lang.tr("Read all", "全部读取")),
                )
                .clicked()
            {
                actions.push(Action::StartJob(jobs::read(&rt.device.profile, gets)));
            }
            let n_changes = pending.as_ref().map_or(0, |(c, _)| c.len());
            let can_write =
                rt.connected() && !busy && matches!(&pending, Ok((c, _)) if !c.is_empty());
            let write = ui.add_enabled(
                can_write,
                egui::Button::new(format!(
                    "{} ({n_changes})",
                    lang.tr("Write changes", "写入修改")
                )),
            );
            if write.clicked()
                && let Ok(p) = &pending
            {
                self.confirm = Some(p.clone());
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
            if let Err(e) = &pending {
                ui.colored_label(egui::Color32::RED, pending_text(e, rt, lang));
            }
        });
        unidentified_warning(ui, lang, rt);
        ui.separator();
        egui::ScrollArea::vertical()
            .auto_shrink(false)
            .show(ui, |ui| {
                let names = table::name_width(ui, lang, rt);
                for group in table::groups(rt, lang) {
                    let shown =
                        egui::CollapsingHeader::new(egui::RichText::new(&group.name).strong())
                            .id_salt(("group", &group.id))
                            .default_open(true)
                            .show(ui, |ui| self.group_grid(ui, lang, rt, &group, names));
                    if self.scroll_to.as_ref() == Some(&group.id) {
                        self.scroll_to = None;
                        shown.header_response.scroll_to_me_animation(
                            Some(egui::Align::TOP),
                            egui::style::ScrollAnimation::none(),
                        );
                    }
                }
            });
        if let Some(action) = self.confirm_dialog(ui, lang, rt) {
            actions.push(action);
        }
        actions
    }

    fn confirm_dialog(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &Station) -> Option<Action> {
        let (changes, writes) = self.confirm.as_ref()?;
        let mut decision = None;
        let modal = egui::Modal::new(egui::Id::unique("confirm-write")).show(ui.ctx(), |ui| {
            ui.heading(lang.tr("Write these changes?", "写入以下修改?"));
            crate::ui::layout::table(ui, egui::Grid::new("diff"), &[
                            lang.tr("Command", "命令"),
                            lang.tr("Field", "字段"),
                            lang.tr("Device", "设备值"),
                            lang.tr("New", "新值"),
                        ], |ui| {
                    for c in changes {
                        ui.label(lang.tr(&c.command_name.en, &c.command_name.zh))
                            .on_hover_text(&c.command);
                        ui.label(lang.tr(&c.field_name.en, &c.field_name.zh))
                            .on_hover_text(&c.field);
                        ui.label(&c.device);
                        ui.strong(&c.new);
                        ui.end_row();
                    }
                });
            ui.label(format!(
                "{} {} {}",
                writes.len(),
                lang.tr(
                    "command(s) will be written, then read back.",
                    "条命令将被写入并回读校验。"
                ),
                ""
            ));
            decision = confirm::buttons(
                ui,
                lang,
                lang.tr("Write", "写入"),
                lang.tr("Cancel", "取消"),
                rt,
            );
        });
        match confirm::decided(&modal, decision)? {
            confirm::Decision::Yes => {
                let (_, writes) = self.confirm.take()?;
                Some(Action::StartJob(jobs::write(&rt.device.profile, writes)))
            }
            confirm::Decision::No => {
                self.confirm = None;
                None
            }
            confirm::Decision::Stop => {
                self.confirm = None;
                Some(Action::Stop)
            }
        }
    }
}

/// The Set command paired with Get `get`.
fn profile_set(rt: &Station, get: u8) -> Option<&Command> {
    let p = &rt.device.profile;
    p.command_by_id(p.command_by_id(get)?.pair?)
}

/// An error about field `f` (`pwmvalueMax: 120 is out of range…`) with the field's name in
/// `lang` in place of its wire name.
fn named(text: &str, f: &Field, lang: Lang) -> String {
    match text.strip_prefix(&format!("{}:", f.ident)) {
        Some(rest) => format!("{}:{rest}", lang.tr(&f.name.en, &f.name.zh)),
        None => text.to_string(),
    }
}

/// A pending error as the window says it: fields and commands by their names, not wire names.
fn pending_text(e: &PendingError, rt: &Station, lang: Lang) -> String {
    let p = &rt.device.profile;
    let fields = || {
        p.commands
            .iter()
            .flat_map(|c| c.reply.iter().chain(&c.request))
    };
    match e {
        PendingError::NotRead { command, field } => {
            let cmd = p.commands.iter().find(|c| &c.ident == command);
            let f = fields().find(|f| &f.ident == field);
            let cmd = cmd.map_or(command.as_str(), |c| lang.tr(&c.name.en, &c.name.zh));
            let f = f.map_or(field.as_str(), |f| lang.tr(&f.name.en, &f.name.zh));
            match lang {
                Lang::En => format!(
                    "{cmd}: {f} has not been read; read it first so that the whole command can be written"
                ),
                Lang::Zh => format!("{cmd}:{f} 尚未读取;请先读取,以便写入完整的命令"),
            }
        }
        other => {
            let text = other.in_lang(lang);
            fields()
                .find(|f| text.starts_with(&format!("{}:", f.ident)))
                .map_or(text.clone(), |f| named(&text, f, lang))
        }
    }
}

/// MSP: when the device did not identify itself, writes go to the profile's device code: said
/// above the values, in the UI's language.
pub(super) fn unidentified_warning(ui: &mut egui::Ui, lang: Lang, rt: &Station) {
    let profile = &rt.device.profile;
    let Some(Err(e)) = &rt.device.info else {
        return;
    };
    if profile.protocol != crate::profile::Protocol::Msp {
        return;
    }
    let text = match lang {
        Lang::En => crate::ops::device::unidentified(profile, e),
        Lang::Zh => format!(
            "设备未能识别自身({e}); 请求将发往配置文件中的设备码 {:#04x}, 可能不是本设备的",
            profile.device_code.map_or(
                crate::protocol::msp::DEVICE_CORE,
                crate::profile::DeviceCode::initial
            )
        ),
    };
    ui.colored_label(egui::Color32::from_rgb(220, 150, 0), format!("⚠ {text}"));
}

impl crate::ui::PanelId {
    /// The window cleaner's parameters, read, edited and written with read-back.
    pub const TUNING: crate::ui::PanelId = crate::ui::PanelId::new("Tuning");
}

impl crate::ui::Panel for TuningPanel {
    fn id(&self) -> crate::ui::PanelId {
        crate::ui::PanelId::TUNING
    }

    fn name(&self, lang: Lang) -> &'static str {
        lang.tr("Tuning", "参数调校")
    }

    fn kind(&self) -> Option<crate::profile::PanelKind> {
        Some(crate::profile::PanelKind::Tuning)
    }

    fn show(&mut self, ui: &mut egui::Ui, cx: &crate::ui::panel::Cx<'_>) -> Vec<Action> {
        self.draw(ui, cx.lang, cx.station)
    }

    /// Another connection: the edits go. Another unit: what it holds is read as soon as it
    /// answers (nothing is shown before).
    fn forget(&mut self, station: &Station, why: crate::ui::panel::Forget) -> Vec<Action> {
        match why {
            crate::ui::panel::Forget::Connection => {
                *self = Self::default();
                Vec::new()
            }
            crate::ui::panel::Forget::Unit => {
                if !station.has_panel(crate::profile::PanelKind::Tuning) {
                    return Vec::new();
                }
                let profile = &station.device.profile;
                let gets: Vec<u8> = profile
                    .commands
                    .iter()
                    .filter(|c| c.kind == CommandKind::Get && c.pair.is_some())
                    .map(|c| c.id)
                    .collect();
                vec![Action::StartJob(jobs::read(profile, gets))]
            }
        }
    }

    /// Its groups of parameters, by id (`other` for those in none).
    fn parts(&self, station: &Station) -> Vec<String> {
        group_ids(station)
            .into_iter()
            .map(|id| if id.is_empty() { "other".into() } else { id })
            .collect()
    }

    /// Brings group `part` to the top.
    fn show_part(&mut self, part: usize, station: &Station) {
        self.scroll_to = group_ids(station).into_iter().nth(part);
    }
}
