//! The ID & baud rate tab: give the selected servo a new id (refusing 255 and ids that answer;
//! a fresh id-0 servo must be alone on the bus; verified at the new id), or a new baud rate
//! (the port follows it and verifies; if it is lost, every rate is searched and the tab says
//! where it is).

use super::scan::ScanState;
use super::selection_or_hint;
use super::{Output, Servo, error_label, ok_label, send};
use crate::i18n::Lang;
use crate::i18n::Text;
use crate::ops::Device;
use crate::ops::OpError;
use crate::ops::servo::{self as ops, Presence};
use crate::ui::Action;
use crate::ui::jobs::Job;
use crate::ui::station::Station;
use eframe::egui;

/// The tab's state.
#[derive(Default)]
pub struct SetupState {
    /// The new id, as typed.
    pub new_id: String,
    /// The baud option chosen, one of the profile's baud table (0: none yet).
    pub option: u8,
    /// The last result: ok, and what happened.
    pub message: Option<(bool, String)>,
    /// The language last drawn in (for messages made between frames).
    pub lang: Lang,
}

/// Why the typed id cannot be given to the selected servo.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum IdRefusal {
    /// Not an id.
    NotAnId(String),
    /// 255, the broadcast address.
    Broadcast,
    /// The id the servo has.
    Same(u8),
    /// An id that answers on the bus (by the scan).
    InUse(u8),
}

impl IdRefusal {
    /// Why, in `lang`.
    pub fn text(&self, lang: Lang) -> String {
        match self {
            IdRefusal::NotAnId(text) => format!(
                "'{text}' {}",
                lang.tr("is not an id: give 1 to 254", "不是有效ID: 请输入1到254")
            ),
            IdRefusal::Broadcast => lang
                .tr(
                    "id 255 is the broadcast address and cannot be assigned",
                    "ID 255是广播地址, 不能分配",
                )
                .into(),
            IdRefusal::Same(id) => format!(
                "{} {id}",
                lang.tr("the servo already has id", "舵机已经是ID")
            ),
            IdRefusal::InUse(id) => format!(
                "{} {id} {}",
                lang.tr("id", "ID"),
                lang.tr(
                    "already answers on the bus (see the scan)",
                    "已在总线上应答(见扫描结果)"
                )
            ),
        }
    }
}

impl SetupState {
    /// The new id typed, checked against what is known; `Err` says why it cannot be given.
    pub fn check_id(&self, servo: Servo, scan: &ScanState) -> Result<u8, IdRefusal> {
        let text = self.new_id.trim();
        let id: u8 = text
            .parse()
            .map_err(|_| IdRefusal::NotAnId(text.to_string()))?;
        if id == crate::protocol::servo::BROADCAST_ID {
            return Err(IdRefusal::Broadcast);
        }
        if id == servo.id {
            return Err(IdRefusal::Same(id));
        }
        if scan
            .rows
            .iter()
            .any(|r| r.id == id && r.presence != Presence::Absent)
        {
            return Err(IdRefusal::InUse(id));
        }
        Ok(id)
    }

    pub(super) fn on_id(&mut self, servo: Servo, new: u8, result: Result<(), OpError>) {
        let lang = self.lang;
        self.message = Some(match result {
            Ok(()) => {
                self.new_id.clear();
                (
                    true,
                    format!(
                        "{} {} {} {new}: {}",
                        lang.tr("servo", "舵机"),
                        servo.id,
                        lang.tr("is now id", "现在的ID为"),
                        lang.tr("verified at the new id", "已在新ID校验")
                    ),
                )
            }
            Err(e) => (
                false,
                format!("{}: {e}", lang.tr("id not changed", "ID未修改")),
            ),
        });
    }

    pub(super) fn on_baud(
        &mut self,
        servo: Servo,
        result: Result<u32, OpError>,
        found: Option<u32>,
    ) {
        let lang = self.lang;
        let who = format!("{} {}", lang.tr("servo", "舵机"), servo.id);
        self.message = Some(match (result, found) {
            (Ok(b), _) => (
                true,
                format!(
                    "{who} {} {b} baud: {}",
                    lang.tr("now talks at", "现在的波特率为"),
                    lang.tr("verified; the port follows it", "已校验; 端口已随之切换")
                ),
            ),
            (Err(e), Some(b)) => (
                false,
                format!(
                    "{} ({e}). {who} {} {b} baud; {}",
                    lang.tr("not verified", "未通过校验"),
                    lang.tr("was found at", "在此波特率下找到:"),
                    lang.tr("the port is there now", "端口已切换到该波特率")
                ),
            ),
            (Err(e), None) => (
                false,
                format!(
                    "{who} {}: {e}. {}",
                    lang.tr("lost", "丢失"),
                    lang.tr(
                        "It answers at no baud rate: check power and wiring, then scan all 8 rates",
                        "在所有波特率下均无应答: 请检查电源和接线, 然后扫描全部8种波特率"
                    )
                ),
            ),
        });
    }

    /// Draws the tab; returns what the technician asked for.
    pub(super) fn show(
        &mut self,
        ui: &mut egui::Ui,
        lang: Lang,
        rt: &Station,
        busy: bool,
        selected: Option<Servo>,
        scan: &ScanState,
    ) -> Vec<Action> {
        self.lang = lang;
        let mut actions = Vec::new();
        let Some(servo) = selection_or_hint(ui, lang, selected) else {
            return actions;
        };
        let can = rt.connected() && !busy;
        ui.heading(lang.tr("Servo ID", "舵机ID"));
        let fresh = crate::ops::servo::factory_location(&rt.device.profile).id;
        if servo.id == fresh {
            ui.label(format!(
                "{} {fresh}{}",
                lang.tr("A fresh servo (id", "出厂舵机(ID"),
                lang.tr(
                    ") gets an id only when it is the only servo on the bus: the bus is checked first.",
                    ")仅在总线上只有它一个舵机时才能分配ID: 将先检查总线。"
                )
            ));
        }
        let check = self.check_id(servo, scan);
        ui.horizontal(|ui| {
            let l = ui.label(lang.tr("New id", "新ID"));
            // The ids the profile's ServoId parameter allows, as the box's hint.
            let hint = rt
                .device
                .profile
                .servo_id_param()
                .filter(|p| p.field.range.is_some())
                .map(|p| crate::ui::inputs::range_text(&p.field))
                .unwrap_or_default();
            let width = crate::ui::layout::box_width_for(ui, &hint).max(50.0);
            ui.add(
                egui::TextEdit::singleline(&mut self.new_id)
                    .hint_text(hint)
                    .desired_width(width),
            )
            .labelled_by(l.id);
            let set = ui.add_enabled(
                can && check.is_ok(),
                egui::Button::new(lang.tr("Set ID", "设置ID")),
            );
            if set.clicked()
                && let Ok(new) = check
            {
                self.message = None;
                actions.push(id_job(rt, servo, new));
            }
            if let Err(e) = &check
                && !self.new_id.trim().is_empty()
            {
                error_label(ui, e.text(lang));
            }
        });
        ui.add_space(8.0);
        actions.extend(self.baud_section(ui, lang, rt, servo, can));
        ui.weak(lang.tr(
            "The servo switches at once; the port follows it and verifies. If it does not answer there, all 8 rates are searched.",
            "舵机立即切换; 端口随之切换并校验。若新波特率下无应答, 将搜索全部8种波特率。",
        ));
        ui.add_space(8.0);
        match &self.message {
            Some((true, m)) => ok_label(ui, m),
            Some((false, m)) => error_label(ui, m),
            None => {}
        }
        actions
    }

    /// The baud rate: one of the profile's options (its label's name where that says more), and
    /// Set baud rate.
    fn baud_section(
        &mut self,
        ui: &mut egui::Ui,
        lang: Lang,
        rt: &Station,
        servo: Servo,
        can: bool,
    ) -> Vec<Action> {
        let mut actions = Vec::new();
        ui.heading(lang.tr("Baud rate", "波特率"));
        ui.horizontal(|ui| {
            let l = ui.label(lang.tr("New baud rate", "新波特率"));
            let profile = &rt.device.profile;
            let text = profile.baud_of_option(self.option).map_or_else(
                || lang.tr("choose…", "请选择…").to_string(),
                |b| format!("{} ({b})", self.option),
            );
            egui::ComboBox::from_id_salt("servo-new-baud")
                .selected_text(text)
                .show_ui(ui, |ui| {
                    // Each option with its rate, or its label's name where that says more
                    // (e.g. newer servos only).
                    let Ok((param, rates)) = ops::baud_param(profile) else {
                        return;
                    };
                    for (&opt, b) in rates {
                        let name = param
                            .field
                            .labels
                            .iter()
                            .find(|l| l.value == i64::from(opt))
                            .map(|l| l.name.get(lang));
                        let label = match name {
                            Some(name) if name != b.to_string() => format!("{opt} ({name})"),
                            _ => format!("{opt} ({b})"),
                        };
                        ui.selectable_value(&mut self.option, opt, label);
                    }
                })
                .response
                .labelled_by(l.id);
            let target = profile.baud_of_option(self.option);
            let set = ui.add_enabled(
                can && target.is_some_and(|b| b != servo.baud),
                egui::Button::new(lang.tr("Set baud rate", "设置波特率")),
            );
            if set.clicked() {
                self.message = None;
                actions.push(baud_job(rt, servo, self.option));
            }
        });
        actions
    }
}

fn id_job(rt: &Station, servo: Servo, new: u8) -> Action {
    let profile = rt.device.profile.clone();
    Action::StartJob(Job::new(
        Text::new("set id", "设置 ID"),
        move |client, cancel, sink| {
            ops::switch(client, servo.baud)?;
            let result = ops::set_id(Device::new(client, &profile), servo.id, new, cancel);
            send(
                sink,
                Output::IdSet {
                    servo,
                    new,
                    result: result.clone(),
                },
            );
            result?;
            Ok(Text::new(
                format!("servo {} is now id {new} (verified)", servo.id),
                format!("舵机 {} 现为 ID {new}(已校验)", servo.id),
            ))
        },
    ))
}

fn baud_job(rt: &Station, servo: Servo, option: u8) -> Action {
    let profile = rt.device.profile.clone();
    Action::StartJob(Job::new(
        Text::new("set baud rate", "设置波特率"),
        move |client, _, sink| {
            ops::switch(client, servo.baud)?;
            let result = ops::set_baud(Device::new(client, &profile), servo.id, option);
            // Where the servo is when the change was not verified: the operation says where it
            // found the servo after the change (and left the port there); after another failure it
            // is looked for at every rate.
            let found = match &result {
                Ok(_) => None,
                Err(OpError::NotAtNewRate { found, .. }) => *found,
                Err(_) => ops::locate(Device::new(client, &profile), servo.id)
                    .ok()
                    .flatten(),
            };
            if result.is_err() && found.is_none() {
                let _ = ops::switch(client, servo.baud);
            }
            send(
                sink,
                Output::BaudSet {
                    servo,
                    result: result.clone(),
                    found,
                },
            );
            let b = result?;
            Ok(Text::new(
                format!("servo {} now at {b} baud (verified)", servo.id),
                format!("舵机 {} 现为 {b} 波特(已校验)", servo.id),
            ))
        },
    ))
}
