//! The window cleaner's production self-test: a RON test plan run step by step, operator
//! prompts, a results table and a log record.

use super::Action;
use super::runtime::Runtime;
use crate::i18n::Lang;
use eframe::egui;

/// The panel's state.
#[derive(Default)]
pub struct SelfTestPanel {}

/// What this panel's jobs report.
#[derive(Debug, Clone)]
pub enum Output {}

impl SelfTestPanel {
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
