//! Values typed into a command's fields, checked as typed against the profile (range, labels,
//! step), and the allowed values as a person reads them.

use crate::i18n::Lang;
use crate::profile::value::Allowed;
use crate::profile::{Command, Field, FieldError, Input, Value};
use eframe::egui;
use std::collections::HashMap;

/// Why what was typed cannot be sent.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum InputError {
    /// Nothing typed for a field.
    #[error("{field}: give a value ({allowed})")]
    Missing {
        /// The field's ident.
        field: String,
        /// What it takes, as [`range_text`] says.
        allowed: String,
    },
    /// A value the field refuses.
    #[error(transparent)]
    Value(#[from] FieldError),
}

/// The inputs of `cmd` from the text typed for each field (by (command id, field ident)), each
/// checked; the error names the first field that cannot be sent.
pub fn command_inputs(
    cmd: &Command,
    typed: &HashMap<(u8, String), String>,
) -> Result<Vec<(String, Input)>, InputError> {
    cmd.request
        .iter()
        .map(|f| {
            let text = typed
                .get(&(cmd.id, f.ident.clone()))
                .map_or("", String::as_str);
            if text.trim().is_empty() {
                return Err(InputError::Missing {
                    field: f.ident.clone(),
                    allowed: range_text(f),
                });
            }
            f.parse(text)?;
            Ok((f.ident.clone(), Input::Text(text.to_string())))
        })
        .collect()
}

/// The allowed values, as shown: `0 – 100 %` or the labels.
pub fn range_text(field: &Field) -> String {
    match field.allowed() {
        Allowed::Range(lo, hi) => {
            format!(
                "{} – {}{}",
                field.format_number(lo),
                field.format_number(hi),
                field.unit_suffix()
            )
        }
        Allowed::Labels(f) => f
            .labels
            .iter()
            .map(|l| l.ident.as_str())
            .collect::<Vec<_>>()
            .join(" / "),
    }
}

/// A button whose text changes (Pause / Resume, 暂停 / 继续) at a width that does not: the
/// widgets after it stay where they are.
pub fn steady_button(text: &str) -> eframe::egui::Button<'_> {
    eframe::egui::Button::new(text).min_size(eframe::egui::vec2(80.0, 0.0))
}

/// A value a device sent, as a readout shows it (monospace, as [`Field::format`] writes it); a
/// value outside the field's range in red with its mark, never as a clean value.
pub fn device_value(ui: &mut egui::Ui, field: &Field, value: &Value) -> egui::Response {
    let text = field.format(value);
    match field.range_mark(value) {
        Some(mark) => ui
            .colored_label(
                egui::Color32::from_rgb(210, 40, 40),
                egui::RichText::new(format!("{text} {mark}")).monospace(),
            )
            .on_hover_text(format!("{}: {}", field.ident, range_text(field))),
        None => ui.monospace(text),
    }
}

/// A value a device sent as a person reads it, names in the window's language: an enum by its
/// label's name and code (`Warning (1)`), a bit field by its raw value and the names of its set
/// bits (`0x05 [Brush, Fan]`), anything else as [`Field::display`] gives it (with its unit and,
/// outside its range, its mark).
pub fn readout_text(f: &Field, v: &Value, lang: Lang) -> String {
    if let Value::Int(raw) = v {
        if let Some(l) = f.label(*raw) {
            return format!("{} ({raw})", lang.tr(&l.name.en, &l.name.zh));
        }
        if !f.bits.is_empty() {
            let set: Vec<&str> = f
                .bits
                .iter()
                .filter(|b| b.bit < 64 && raw >> b.bit & 1 == 1)
                .map(|b| lang.tr(&b.name.en, &b.name.zh))
                .collect();
            return format!("{raw:#04x} [{}]", set.join(", "));
        }
    }
    f.display(v)
}
