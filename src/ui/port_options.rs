//! The connection bar's **Port options** menu: the DTR and RTS lines set right after the port
//! opens, the boot wait before the first request (a board that reboots when the port opens),
//! and the answer margin at any value the command line accepts. Kept per profile
//! ([`PortSettings`]), sent with Connect.

use super::settings::PortSettings;
use crate::i18n::{Key, Lang};
use crate::link::{BOOT_WAIT_MS, LineLevel, MARGIN_MS, ms_within};
use eframe::egui;
use egui::containers::menu::{MenuButton, MenuConfig};

/// The menu's number fields as typed (`None`: showing the saved value), and why each is
/// refused when it is: a value outside the range is never taken.
#[derive(Debug, Clone, Default)]
pub struct Typed {
    boot_wait: Option<(String, Option<String>)>,
    margin: Option<(String, Option<String>)>,
}

/// The menu button and, when open, its fields (edited in `options`).
pub fn menu(ui: &mut egui::Ui, lang: Lang, options: &mut PortSettings, typed: &mut Typed) {
    let config = MenuConfig::new().close_behavior(egui::PopupCloseBehavior::CloseOnClickOutside);
    MenuButton::new(Key::PortOptions.get(lang))
        .config(config)
        .ui(ui, |ui| {
            ui.label(Key::PortOptionsHint.get(lang));
            egui::Grid::new("port-options")
                .num_columns(2)
                .show(ui, |ui| {
                    line_row(ui, lang, Key::Dtr, &mut options.dtr);
                    line_row(ui, lang, Key::Rts, &mut options.rts);
                    boot_wait_row(ui, lang, options, &mut typed.boot_wait);
                    margin_row(ui, lang, options, &mut typed.margin);
                });
        });
}

/// One line's level: keep, on or off.
fn line_row(ui: &mut egui::Ui, lang: Lang, line: Key, level: &mut LineLevel) {
    ui.label(line.get(lang));
    ui.horizontal(|ui| {
        for l in LineLevel::ALL {
            let text = match l {
                LineLevel::Keep => Key::LineKeep,
                LineLevel::On => Key::LineOn,
                LineLevel::Off => Key::LineOff,
            };
            ui.selectable_value(level, l, text.get(lang));
        }
    });
    ui.end_row();
}

/// The boot wait, ms, within [`BOOT_WAIT_MS`].
fn boot_wait_row(
    ui: &mut egui::Ui,
    lang: Lang,
    options: &mut PortSettings,
    typed: &mut Option<(String, Option<String>)>,
) {
    let label = ui.label(Key::BootWait.get(lang));
    let saved = options.boot_wait_ms.to_string();
    if let Some(ms) = number_field(ui, label.id, "boot-wait", &saved, typed, |t| {
        ms_within(t, &BOOT_WAIT_MS)
    }) {
        options.boot_wait_ms = ms;
    }
    ui.end_row();
}

/// The answer margin, ms, within [`MARGIN_MS`] (empty: auto).
fn margin_row(
    ui: &mut egui::Ui,
    lang: Lang,
    options: &mut PortSettings,
    typed: &mut Option<(String, Option<String>)>,
) {
    let label = ui.label(Key::MarginMs.get(lang));
    let saved = options.margin_ms.map(|m| m.to_string()).unwrap_or_default();
    let parse = |t: &str| match t.trim() {
        "" => Ok(None),
        t => ms_within(t, &MARGIN_MS).map(Some),
    };
    if let Some(ms) = number_field(ui, label.id, "margin", &saved, typed, parse) {
        options.margin_ms = ms;
    }
    ui.end_row();
}

/// A text field of milliseconds showing `saved` until edited; returns the value once what is
/// typed parses, and shows why not beside it otherwise.
fn number_field<T>(
    ui: &mut egui::Ui,
    label: egui::Id,
    id: &str,
    saved: &str,
    typed: &mut Option<(String, Option<String>)>,
    parse: impl Fn(&str) -> Result<T, String>,
) -> Option<T> {
    let (text, error) = typed.get_or_insert_with(|| (saved.to_string(), None));
    let mut taken = None;
    ui.horizontal(|ui| {
        let edit = egui::TextEdit::singleline(text)
            .id_salt(id)
            .desired_width(80.0);
        let response = ui.add(edit).labelled_by(label);
        ui.label("ms");
        if response.changed() {
            match parse(text) {
                Ok(v) => {
                    *error = None;
                    taken = Some(v);
                }
                Err(why) => *error = Some(why),
            }
        }
        if let Some(why) = error {
            ui.colored_label(ui.visuals().error_fg_color, why.as_str());
        }
    });
    taken
}
