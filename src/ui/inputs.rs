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

/// The allowed values of `field` as the window shows them in `lang`: the profile's range, its
/// named values by name, or both; "— (not given)" where the profile gives neither (the type's
/// own limits, 0 – 65535 °C, say nothing a technician can use).
pub fn allowed_in(field: &Field, lang: Lang) -> String {
    let names: Vec<&str> = field
        .labels
        .iter()
        .map(|l| lang.tr(&l.name.en, &l.name.zh))
        .collect();
    match (field.range.is_some(), names.is_empty()) {
        (false, true) => lang.tr("— (not given)", "—(未规定)").to_string(),
        // A long list of names is more than a cell holds (a Chinese character is as wide as
        // two Latin ones): the choice box lists them.
        (false, false) if names.len() > 2 || text_columns(&names.join(" / ")) > 32 => match lang {
            Lang::En => format!("{} options", names.len()),
            Lang::Zh => format!("{} 个选项", names.len()),
        },
        (false, false) => names.join(" / "),
        (true, true) => range_text(field),
        (true, false) => format!("{} ({})", names.join(" / "), range_text(field)),
    }
}

/// How many columns `text` takes, a Chinese character two.
fn text_columns(text: &str) -> usize {
    text.chars()
        .map(|c| if crate::ui::layout::is_cjk(c) { 2 } else { 1 })
        .sum()
}

/// A text box for a value of `field`, its hint the profile's range (none where the profile
/// gives none) and as wide as that hint, so that the hint is never cut; red while what is typed
/// is refused; the allowed values on hover. At least `min_width` points wide.
pub fn value_box(
    ui: &mut egui::Ui,
    text: &mut String,
    field: &Field,
    lang: Lang,
    min_width: f32,
) -> egui::Response {
    let hint = if field.range.is_some() {
        range_text(field)
    } else {
        String::new()
    };
    let width = crate::ui::layout::box_width_for(ui, &hint);
    let bad = !text.is_empty() && field.parse(text).is_err();
    let mut edit = egui::TextEdit::singleline(text)
        .desired_width(width.max(min_width))
        .hint_text(hint);
    if bad {
        edit = edit.text_color(egui::Color32::from_rgb(210, 40, 40));
    }
    // Its own width even where a row has less room left (the last box of a long row in a
    // grid's column): a squeezed box would hide what is typed in it.
    let size = egui::vec2(width.max(min_width), ui.spacing().interact_size.y);
    ui.add_sized(size, edit)
        .on_hover_text(allowed_in(field, lang))
}

/// A ComboBox of a labelled field's values, each by its name in `lang` and its ident; sets
/// `text` to the chosen label's ident, as [`Field::parse`] reads it. A value with no label (a
/// device's 2 where the profile names 0 and 1) shows as it is. True when a label was chosen.
/// Servo parameters and tuning use it for every field with labels.
pub fn label_choice(
    ui: &mut egui::Ui,
    lang: Lang,
    f: &Field,
    salt: impl egui::AsIdSalt,
    text: &mut String,
    name: egui::Id,
) -> bool {
    let shown = f
        .labels
        .iter()
        .find(|l| l.ident == text.trim())
        .map_or_else(
            || {
                if text.is_empty() {
                    "—".to_string()
                } else {
                    text.clone()
                }
            },
            |l| lang.tr(&l.name.en, &l.name.zh).to_string(),
        );
    let mut chosen = false;
    egui::ComboBox::from_id_salt(salt)
        .selected_text(shown)
        .width(110.0)
        .show_ui(ui, |ui| {
            for l in &f.labels {
                let label = format!("{} ({})", lang.tr(&l.name.en, &l.name.zh), l.ident);
                if ui.selectable_label(*text == l.ident, label).clicked() {
                    *text = l.ident.clone();
                    chosen = true;
                }
            }
        })
        .response
        .labelled_by(name);
    chosen
}

/// A value a device sent, as a readout shows it (monospace, as [`Field::format`] writes it, a
/// named value by its name in `lang`); a value outside the field's range in red with its mark,
/// never as a clean value.
pub fn device_value(ui: &mut egui::Ui, field: &Field, value: &Value, lang: Lang) -> egui::Response {
    if let Value::Int(raw) = value
        && let Some(l) = field.label(*raw)
    {
        return ui
            .monospace(lang.tr(&l.name.en, &l.name.zh))
            .on_hover_text(format!("{} ({raw})", l.ident));
    }
    let text = said_in(field.format(value), lang);
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
        if let Some(text) = bits_text(f, *raw, lang) {
            return text;
        }
    }
    said_in(f.display(v), lang)
}

/// A value as a line of readings shows it (other telemetry, what STOP changed): a named value by
/// its name alone, a bit field by its set bits' names, anything else with its unit, in `lang`;
/// [`readout_text`] also gives a name's code and the range mark.
pub fn short_text(f: &Field, v: &Value, lang: Lang) -> String {
    if let Value::Int(raw) = v
        && let Some(l) = f.label(*raw)
    {
        return lang.tr(&l.name.en, &l.name.zh).to_string();
    }
    if let Value::Int(raw) = v
        && let Some(text) = bits_text(f, *raw, lang)
    {
        return text;
    }
    said_in(format!("{}{}", f.format(v), f.unit_suffix()), lang)
}

/// A bit field's value as a person reads it: the raw value and the names of its set bits in
/// `lang` (`0x05 [Brush, Fan]`), or that no bit is set; `None` for a field without bits.
pub fn bits_text(f: &Field, raw: i64, lang: Lang) -> Option<String> {
    if f.bits.is_empty() {
        return None;
    }
    let set: Vec<&str> = f
        .bits
        .iter()
        .filter(|b| b.bit < 64 && raw >> b.bit & 1 == 1)
        .map(|b| lang.tr(&b.name.en, &b.name.zh))
        .collect();
    Some(if set.is_empty() {
        format!("{raw:#04x} ({})", lang.tr("no bit set", "无置位"))
    } else {
        format!("{raw:#04x} [{}]", set.join(", "))
    })
}

/// A value's text as [`Field::format`] and [`Field::display`] write it (for files and the
/// command line, in English), said in `lang` for the window: the raw value beside a converted
/// one is `(原始值 1779)` in Chinese, an undefined conversion `无效`.
pub fn said_in(text: String, lang: Lang) -> String {
    match lang {
        Lang::En => text,
        Lang::Zh => text
            .replace(" (raw ", " (原始值 ")
            .replace("n/a (", "无效 ("),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::profile::Registry;

    #[test]
    fn readouts_are_said_in_the_windows_language() {
        let reg = Registry::builtin().unwrap();
        let servo = reg.get("servo").unwrap();
        let temperature = &servo
            .param_with_role(&crate::profile::ParamRole::Temperature)
            .unwrap()
            .field;
        let en = readout_text(temperature, &Value::Int(1779), Lang::En);
        let zh = readout_text(temperature, &Value::Int(1779), Lang::Zh);
        assert!(en.ends_with("(raw 1779)"), "{en}");
        assert!(zh.ends_with("(原始值 1779)") && !zh.contains("raw"), "{zh}");
        assert_eq!(en.replace("(raw ", "(原始值 "), zh, "the same value");

        let wc = reg.get("window-cleaner").unwrap();
        let corners = wc
            .commands
            .iter()
            .flat_map(|c| &c.reply)
            .find(|f| f.ident == "corners")
            .unwrap();
        assert_eq!(
            readout_text(corners, &Value::Int(0), Lang::En),
            "0x00 (no bit set)"
        );
        assert_eq!(
            readout_text(corners, &Value::Int(0), Lang::Zh),
            "0x00 (无置位)"
        );
        assert!(
            readout_text(corners, &Value::Int(5), Lang::En).starts_with("0x05 [Corner switch 1")
        );
    }
}
