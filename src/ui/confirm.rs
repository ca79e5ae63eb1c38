//! The parts every confirmation dialog shares (write changes, apply a preset, send a command
//! that moves the robot, reset a servo, update the MCU): its answers, STOP beside them for a
//! robot whose profile names one, and what a dialog closed without an answer means. STOP acts
//! at once whatever is open: the dialog's own STOP, and a click on the navigation's STOP while
//! a dialog is open (which the dialog's backdrop would otherwise take as "close"), both send it.

use crate::i18n::Lang;
use crate::profile::{Command, Input};
use crate::ui::station::Station;
use eframe::egui;

/// What a dialog's operator decided this frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Decision {
    /// The dialog's yes (Write, Confirm, Update...).
    Yes,
    /// Its no, or the dialog closed without an answer (Escape, a click outside it).
    No,
    /// STOP: the dialog closes and [`crate::ui::Action::Stop`] goes out.
    Stop,
}

/// The row of a dialog's answers, `yes` and `no` (in the window's language), and STOP when
/// `rt`'s profile names one: the one pressed this frame.
pub fn buttons(
    ui: &mut egui::Ui,
    lang: Lang,
    yes: &str,
    no: &str,
    rt: &Station,
) -> Option<Decision> {
    ui.horizontal(|ui| answer(ui, lang, yes, no, rt)).inner
}

/// The answers added to the row `ui` already is (a dialog that puts more beside them).
pub fn answer(
    ui: &mut egui::Ui,
    lang: Lang,
    yes: &str,
    no: &str,
    rt: &Station,
) -> Option<Decision> {
    let mut decision = None;
    if ui.button(yes).clicked() {
        decision = Some(Decision::Yes);
    }
    if ui.button(no).clicked() {
        decision = Some(Decision::No);
    }
    if !rt.device.profile.stop.is_empty() {
        ui.separator();
        if !crate::ui::stop::dialog_button(ui, lang, rt).is_empty() {
            decision = Some(Decision::Stop);
        }
    }
    decision
}

/// A dialog's decision this frame: the answer pressed; STOP when the click that closes it
/// fell on the navigation's STOP ([`crate::ui::stop::button`] drawn this frame); no when it
/// was closed otherwise (Escape, a click elsewhere outside it).
pub fn decided<T>(modal: &egui::ModalResponse<T>, pressed: Option<Decision>) -> Option<Decision> {
    if pressed.is_some() {
        return pressed;
    }
    let backdrop = &modal.backdrop_response;
    if backdrop.clicked()
        && let Some(at) = backdrop.interact_pointer_pos()
        && crate::ui::stop::drawn_at(&backdrop.ctx).is_some_and(|r| r.contains(at))
    {
        return Some(Decision::Stop);
    }
    modal.should_close().then_some(Decision::No)
}

/// What a command about to be sent carries, as a dialog says it in `lang`: each field by its
/// name, a named value by its name, a number with its unit (`Motor: Forward`, `电机: 前进`,
/// `Fan PWM: 60 %`); a field `cmd` does not have by its ident, as given.
pub fn inputs_said(cmd: Option<&Command>, inputs: &[(String, Input)], lang: Lang) -> String {
    inputs
        .iter()
        .map(|(k, v)| {
            let field = cmd.and_then(|c| c.request.iter().find(|f| &f.ident == k));
            let Some(f) = field else {
                return match v {
                    Input::Text(t) => format!("{k}={t}"),
                    Input::Raw(r) => format!("{k}={r:?}"),
                };
            };
            let value = match v {
                Input::Text(t) => {
                    let t = t.trim();
                    let label = f.labels.iter().find(|l| {
                        l.ident.eq_ignore_ascii_case(t) || l.name.en.eq_ignore_ascii_case(t)
                    });
                    match label {
                        Some(l) => l.name.get(lang).to_string(),
                        None => format!("{t}{}", f.unit_suffix()),
                    }
                }
                Input::Raw(r) => crate::ui::inputs::short_text(f, r, lang),
            };
            format!("{}{}{value}", f.name.get(lang), lang.tr(": ", ":"))
        })
        .collect::<Vec<_>>()
        .join(lang.tr(", ", ","))
}
