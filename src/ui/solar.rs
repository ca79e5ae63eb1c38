//! The solar cleanbot: live readouts and plots, range-checked controls, an always-visible STOP
//! and an optional dead-man.

use super::Action;
use super::runtime::Runtime;
use crate::i18n::Lang;
use eframe::egui;

/// The panel's state.
#[derive(Default)]
pub struct SolarPanel {}

/// What this panel's jobs report.
#[derive(Debug, Clone)]
pub enum Output {}

impl SolarPanel {
    /// Draws the panel.
    pub fn show(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &Runtime) -> Vec<Action> {
        let _ = rt;
        ui.label(lang.tr("Not built yet.", "尚未实现。"));
        Vec::new()
    }

    /// Takes what one of its jobs reported.
    pub fn on_output(&mut self, out: Output) {
        match out {}
    }
}
