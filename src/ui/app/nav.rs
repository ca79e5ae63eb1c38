//! The navigation: the panels the shown station's device has, by name in the window's language
//! (its width fixed by the longest name in either language, so that switching the language
//! moves nothing), and below them STOP, for a robot whose profile names one, with what the
//! robot may be doing.

use super::App;
use crate::i18n::Lang;
use crate::ui::panel::{PanelId, Panels};
use crate::ui::station::Station;
use crate::ui::{Action, Settings, layout, stop};
use eframe::egui;

impl App {
    /// The panels the shown station's device has, in the navigation's order (see
    /// [`Panels::shown`]).
    pub fn panels(&self) -> Vec<PanelId> {
        let station = self.station();
        station.panels.shown(station)
    }
}

/// Draws the navigation of `station`; returns the panel clicked, or STOP.
pub(super) fn show(ui: &mut egui::Ui, settings: &Settings, station: &Station) -> Vec<Action> {
    let lang = settings.lang;
    let mut actions = Vec::new();
    let panels = &station.panels;
    egui::Panel::left("nav")
        .frame(crate::ui::backdrop::bar(ui.style()))
        .resizable(false)
        .exact_size(width(ui, panels))
        .show(ui, |ui| {
            ui.add_space(4.0);
            // The list scrolls where the window is too low for it and STOP below it (a small
            // screen, or a scale factor of 2): STOP stays whole in view.
            let line = ui.text_style_height(&egui::TextStyle::Body) + ui.spacing().item_spacing.y;
            let below = if station.device.profile.stop.is_empty() {
                0.0
            } else {
                stop::BUTTON_HEIGHT + 2.0 * line + 4.0 * ui.spacing().item_spacing.y
            };
            egui::ScrollArea::vertical()
                .id_salt("nav-list")
                .max_height((ui.available_height() - below).max(line))
                .show(ui, |ui| {
                    layout::keep_words_whole(ui);
                    for id in panels.shown(station) {
                        let Some(panel) = panels.find(id) else {
                            continue;
                        };
                        if ui
                            .selectable_label(settings.panel == id, panel.name(lang))
                            .clicked()
                        {
                            actions.push(Action::ShowPanel(id));
                        }
                    }
                });
            // STOP is on every panel of a robot whose profile names one (a panel that shows
            // its own, the solar one, at the top, leaves this one out), with what the robot
            // may be doing.
            if !station.device.profile.stop.is_empty() {
                ui.separator();
                if !panels.find(settings.panel).is_some_and(|p| p.shows_stop()) {
                    actions.extend(stop::button(ui, lang, station));
                    station.stop.status(ui, lang);
                }
                stop::running(ui, lang, station);
            }
        });
    actions
}

/// The navigation's width, points: its longest panel name in either language on one line, or
/// the STOP button, whichever is wider.
fn width(ui: &egui::Ui, panels: &Panels) -> f32 {
    let names = panels.iter().flat_map(|p| Lang::ALL.map(|l| p.name(l)));
    let text = layout::text_width(ui, &layout::body_font(ui), names);
    let button = text + 2.0 * ui.spacing().button_padding.x;
    // The panel's frame: its inner margin on both sides, and a little air.
    let margin = 2.0 * 8.0 + 4.0;
    button.max(stop::BUTTON_WIDTH) + margin
}
