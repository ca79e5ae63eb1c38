//! The parts every confirmation dialog shares (write changes, apply a preset, send a command
//! that moves the robot, reset a servo, update the MCU): its yes/no buttons, and what a dialog
//! closed without an answer means.

use eframe::egui;

/// The row of a dialog's two answers, `yes` and `no` (in the window's language): `Some(true)`
/// or `Some(false)` when one was pressed this frame, else `None`.
pub fn buttons(ui: &mut egui::Ui, yes: &str, no: &str) -> Option<bool> {
    ui.horizontal(|ui| answer(ui, yes, no)).inner
}

/// The two answers added to the row `ui` already is (a dialog that puts more beside them).
pub fn answer(ui: &mut egui::Ui, yes: &str, no: &str) -> Option<bool> {
    let mut decision = None;
    if ui.button(yes).clicked() {
        decision = Some(true);
    }
    if ui.button(no).clicked() {
        decision = Some(false);
    }
    decision
}

/// A dialog's decision this frame: the answer pressed, or no when the dialog was closed without
/// one (Escape, a click outside it).
pub fn decided<T>(modal: &egui::ModalResponse<T>, pressed: Option<bool>) -> Option<bool> {
    match pressed {
        None if modal.should_close() => Some(false),
        pressed => pressed,
    }
}
