//! Layout rules every panel shares, so that a label never breaks inside a word and every panel
//! can be read at 1024×600.
//!
//! egui wraps a label where the room ends; in Chinese, where any two characters may be parted,
//! that splits words such as 设备配置 over two lines. So a row of controls ([`toolbar`]) moves a
//! label that does not fit whole to the next row, a label that must stay on its line
//! ([`one_line`]) is cut with "…" and shows its whole text on hover, and a column meant for
//! names is as wide as its longest name measured in the window's own font ([`text_width`]).

use eframe::egui;

/// A row of controls that wraps between widgets, never inside one: a label or button that does
/// not fit the rest of the row moves, whole, to the next row. Prose that should wrap inside
/// the row is added as `egui::Label::new(..).wrap()`.
pub fn toolbar<R>(
    ui: &mut egui::Ui,
    add: impl FnOnce(&mut egui::Ui) -> R,
) -> egui::InnerResponse<R> {
    ui.horizontal_wrapped(|ui| {
        keep_words_whole(ui);
        add(ui)
    })
}

/// Widgets kept together on one row of a [`toolbar`] (a label and the box it names): the
/// group starts a new row when it does not fit the rest of this one. Its width is the one it
/// had on the last frame (egui places a widget before it is drawn), so a group finds its row
/// on the second frame it is shown. `id_salt` tells the toolbar's groups apart.
pub fn group<R>(ui: &mut egui::Ui, id_salt: &str, add: impl FnOnce(&mut egui::Ui) -> R) -> R {
    let id = ui.scope_id().with(("toolbar group", id_salt));
    let width: f32 = ui.data(|d| d.get_temp(id)).unwrap_or(0.0);
    let at_start = ui.cursor().min.x <= ui.max_rect().min.x + 0.5;
    if !at_start && width > ui.available_size_before_wrap().x + 0.5 {
        ui.end_row();
    }
    let shown = ui.horizontal(add);
    let drawn = shown.response.rect.width();
    if (drawn - width).abs() > 0.5 {
        ui.data_mut(|d| d.insert_temp(id, drawn));
        ui.ctx()
            .request_discard("a toolbar group changed its width");
    }
    shown.inner
}

/// A table of three columns (names, a middle that wraps, a button) sized so that the last
/// column stays in the window: the names' column as wide as its widest name, the buttons' as
/// its widest button, the middle gets the rest and wraps within it.
pub struct ColumnsLeft {
    /// The width, points, the middle column wraps within.
    pub middle: f32,
}

impl ColumnsLeft {
    /// Measures `names` and `buttons` (their texts) in the window's font against the room
    /// `ui` has now.
    pub fn new<'a>(
        ui: &egui::Ui,
        names: impl IntoIterator<Item = &'a str>,
        buttons: impl IntoIterator<Item = String>,
    ) -> Self {
        let font = body_font(ui);
        let names = text_width(ui, &font, names);
        let buttons: Vec<String> = buttons.into_iter().collect();
        let button = text_width(ui, &font, buttons.iter().map(String::as_str))
            + 2.0 * ui.spacing().button_padding.x;
        let gaps = 4.0 * ui.spacing().item_spacing.x + ui.spacing().scroll.bar_width;
        Self {
            middle: (ui.available_width() - names - button - gaps).max(160.0),
        }
    }

    /// The middle cell: `add` in a row that wraps within [`ColumnsLeft::middle`].
    pub fn wrapped<R>(&self, ui: &mut egui::Ui, add: impl FnOnce(&mut egui::Ui) -> R) -> R {
        ui.vertical(|ui| {
            ui.set_width(self.middle);
            toolbar(ui, add).inner
        })
        .inner
    }
}

/// A table's heading row: each heading in strong text, then the row ends. Every table of the
/// window starts so.
pub fn header_row(ui: &mut egui::Ui, headers: &[&str]) {
    for h in headers {
        ui.strong(*h);
    }
    ui.end_row();
}

/// The width, points, a text box needs to show `hint` whole: the hint in the body font, and
/// the box's frame (its padding, stroke and a little air on each side).
pub fn box_width_for(ui: &egui::Ui, hint: &str) -> f32 {
    let frame = 2.0 * (ui.spacing().button_padding.x + 2.0) + 8.0;
    text_width(ui, &body_font(ui), [hint]) + frame
}

/// Makes the labels and buttons added to `ui` from now on keep their text on one line (in a
/// wrapping row, a widget that does not fit moves to the next row).
pub fn keep_words_whole(ui: &mut egui::Ui) {
    ui.style_mut().wrap_mode = Some(egui::TextWrapMode::Extend);
}

/// A label kept on one line: where the room is short it is cut with "…", and the whole text
/// shows on hover.
pub fn one_line(ui: &mut egui::Ui, text: impl Into<egui::WidgetText>) -> egui::Response {
    let text: egui::WidgetText = text.into();
    let full = text.text().to_string();
    let response = ui.add(egui::Label::new(text).truncate());
    if response
        .intrinsic_size()
        .is_some_and(|s| s.x > response.rect.width() + 0.5)
    {
        response.on_hover_text(full)
    } else {
        response
    }
}

/// A grid cell `width` points wide whose label wraps inside it, its row as high as its lines
/// (a cell allocated with no height is centred on the row's old height and runs over the rows
/// below). A one-line label sits where the row's other, centred, cells have their text.
pub fn wrapped_cell(ui: &mut egui::Ui, width: f32, label: egui::Label) -> egui::Response {
    ui.vertical(|ui| {
        ui.set_width(width);
        let text_h = ui.text_style_height(&egui::TextStyle::Body);
        ui.add_space(((ui.spacing().interact_size.y - text_h) / 2.0).max(0.0));
        ui.add(label.wrap())
    })
    .inner
}

/// A table cell `width` points wide holding `text` that wraps only between its words (at its
/// spaces), never inside one: for texts made of names (`陀螺仪加速度原始值: 陀螺仪X, 陀螺仪Y`),
/// which egui would otherwise part anywhere in Chinese. A word wider than the cell stays whole.
/// `style` dresses each word (weak, monospace).
pub fn words_cell(
    ui: &mut egui::Ui,
    width: f32,
    text: &str,
    style: impl Fn(egui::RichText) -> egui::RichText,
) -> egui::Response {
    let shown = ui
        .vertical(|ui| {
            ui.set_width(width);
            let text_h = ui.text_style_height(&egui::TextStyle::Body);
            ui.add_space(((ui.spacing().interact_size.y - text_h) / 2.0).max(0.0));
            ui.horizontal_wrapped(|ui| {
                keep_words_whole(ui);
                let space = text_width(ui, &body_font(ui), [" "]);
                ui.spacing_mut().item_spacing = egui::vec2(space, 0.0);
                for word in text.split(' ').filter(|w| !w.is_empty()) {
                    ui.label(style(egui::RichText::new(word)));
                }
            })
            .response
        })
        .inner;
    // Read as the one text it is (a screen reader, the tests), not word by word.
    shown.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Label, true, text));
    shown
}

/// The width, points, of the widest of `texts` on one line in `font` (the body font: the
/// labels' own), as this window's fonts draw it (the bundled CJK font for Chinese).
pub fn text_width<'a>(
    ui: &egui::Ui,
    font: &egui::FontId,
    texts: impl IntoIterator<Item = &'a str>,
) -> f32 {
    ui.fonts_mut(|f| {
        texts
            .into_iter()
            .map(|t| {
                f.layout_no_wrap(t.to_string(), font.clone(), egui::Color32::WHITE)
                    .size()
                    .x
            })
            .fold(0.0, f32::max)
    })
}

/// The body font of `ui`'s style.
pub fn body_font(ui: &egui::Ui) -> egui::FontId {
    egui::TextStyle::Body.resolve(ui.style())
}

/// The most characters a Chinese text may have and still be a label (a name, a header, a
/// status word) rather than a sentence, which may wrap anywhere.
pub const LABEL_CHARS: usize = 12;

/// The texts drawn in `shapes` that a line break parts inside a word: an English word split
/// (a letter or digit on both sides of the break), or a Chinese label (at most
/// [`LABEL_CHARS`] characters, no sentence punctuation inside) parted anywhere. Breaks the text
/// asks for (`\n`) are not counted. The screenshot tour and the layout tests run it on what a
/// frame drew.
pub fn split_words(shapes: &[egui::epaint::ClippedShape]) -> Vec<String> {
    let mut found = Vec::new();
    for clipped in shapes {
        visit_texts(&clipped.shape, &mut |galley| {
            if breaks_a_word(galley) {
                found.push(galley.text().to_string());
            }
        });
    }
    found
}

fn visit_texts(shape: &egui::Shape, f: &mut impl FnMut(&egui::Galley)) {
    visit_placed(shape, &mut |t| f(&t.galley));
}

fn visit_placed(shape: &egui::Shape, f: &mut impl FnMut(&egui::epaint::TextShape)) {
    match shape {
        egui::Shape::Text(t) => f(t),
        egui::Shape::Vec(v) => v.iter().for_each(|s| visit_placed(s, f)),
        _ => {}
    }
}

/// Pairs of texts drawn in `shapes` over each other: the parts of their rows that can be seen
/// (inside their clip) overlap by more than a point each way. Texts on different layers (a
/// popup over a panel) are the caller's to keep apart: pass one layer's shapes.
pub fn overlapping_texts(shapes: &[egui::epaint::ClippedShape]) -> Vec<(String, String)> {
    // (where, its text, which text shape)
    let mut seen: Vec<(egui::Rect, String, usize)> = Vec::new();
    let mut n = 0;
    for clipped in shapes {
        visit_placed(&clipped.shape, &mut |t| {
            n += 1;
            let text = t.galley.text();
            // A turned text (a plot's y axis label) has boxes this check does not turn.
            if text.trim().is_empty() || t.angle != 0.0 {
                return;
            }
            // Row by row: a label continuing a wrapped row starts where the row's text does.
            for row in t.galley.rows.iter().filter(|r| !r.row.glyphs.is_empty()) {
                let rect = row.rect_without_leading_space().translate(t.pos.to_vec2());
                let visible = rect.intersect(clipped.clip_rect);
                if visible.is_positive() {
                    seen.push((visible, text.to_string(), n));
                }
            }
        });
    }
    let mut found = Vec::new();
    for (i, (a, ta, na)) in seen.iter().enumerate() {
        for (b, tb, nb) in &seen[i + 1..] {
            let both = a.intersect(*b);
            if na != nb && both.width() > 1.0 && both.height() > 1.0 {
                found.push((ta.clone(), tb.clone()));
            }
        }
    }
    found
}

/// Whether `c` is a Chinese character or full-width sign.
pub fn is_cjk(c: char) -> bool {
    matches!(c as u32, 0x2E80..=0x9FFF | 0xF900..=0xFAFF | 0xFF00..=0xFFEF)
}

/// Punctuation that makes a Chinese text a sentence when it stands inside it.
fn is_sentence_mark(c: char) -> bool {
    ",.;:!?，。；：！？、".contains(c)
}

fn breaks_a_word(galley: &egui::Galley) -> bool {
    let text = galley.text();
    let inner = text.trim_end_matches(is_sentence_mark);
    let label = text.chars().filter(|&c| is_cjk(c)).count() <= LABEL_CHARS
        && !inner.chars().any(is_sentence_mark);
    galley.rows.windows(2).any(|pair| {
        if pair[0].ends_with_newline {
            return false;
        }
        let (Some(a), Some(b)) = (pair[0].row.glyphs.last(), pair[1].row.glyphs.first()) else {
            return false;
        };
        let (a, b) = (a.chr, b.chr);
        let english = a.is_ascii_alphanumeric() && b.is_ascii_alphanumeric();
        let chinese = label && is_cjk(a) && is_cjk(b);
        english || chinese
    })
}

/// A table: `grid` (its id and any widths the caller sets), striped, with one column per header
/// and the headers as its first row, then the rows `body` adds. Returns what `body` returns.
pub fn table<R>(
    ui: &mut egui::Ui,
    grid: egui::Grid,
    headers: &[&str],
    body: impl FnOnce(&mut egui::Ui) -> R,
) -> egui::InnerResponse<R> {
    grid.striped(true)
        .num_columns(headers.len())
        .show(ui, |ui| {
            header_row(ui, headers);
            body(ui)
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What a frame drew with `add` in a 1024×600 window.
    fn drawn(add: impl Fn(&mut egui::Ui)) -> Vec<egui::epaint::ClippedShape> {
        let ctx = egui::Context::default();
        crate::i18n::install_cjk_font(&ctx);
        let input = egui::RawInput {
            screen_rect: Some(egui::Rect::from_min_size(
                egui::Pos2::ZERO,
                egui::vec2(1024.0, 600.0),
            )),
            ..Default::default()
        };
        let mut shapes = Vec::new();
        // The second frame: fonts are ready and widths settled.
        for _ in 0..2 {
            let out = ctx.run_ui(input.clone(), |ui| add(ui));
            shapes = out.shapes.clone();
            out.drop_without_applying_deltas();
        }
        shapes
    }

    #[test]
    fn a_words_cell_wraps_between_names_only() {
        let text = "陀螺仪加速度原始值: 陀螺仪X, 陀螺仪Y, 陀螺仪Z";
        let mut rows = Vec::new();
        let shapes = drawn(|ui| {
            words_cell(ui, 120.0, text, |t| t);
        });
        for clipped in &shapes {
            visit_placed(&clipped.shape, &mut |t| {
                rows.push((t.galley.text().to_string(), t.galley.rows.len(), t.pos.y));
            });
        }
        // Each name drawn whole on one row, the text on more than one row.
        let words: Vec<&str> = rows.iter().map(|(w, ..)| w.as_str()).collect();
        assert_eq!(words, text.split(' ').collect::<Vec<_>>());
        assert!(rows.iter().all(|(_, n, _)| *n == 1), "{rows:?}");
        let lines: std::collections::BTreeSet<i64> = rows.iter().map(|(.., y)| *y as i64).collect();
        assert!(lines.len() > 1, "wraps in 120 points: {rows:?}");
        // A plain wrapped label of the same text in the same width parts a name.
        let plain = drawn(|ui| {
            wrapped_cell(ui, 120.0, egui::Label::new(text));
        });
        let mut parted = false;
        for clipped in &plain {
            visit_placed(&clipped.shape, &mut |t| {
                parted |= t.galley.rows.windows(2).any(|p| {
                    let a = p[0].row.glyphs.last().map(|g| g.chr);
                    let b = p[1].row.glyphs.first().map(|g| g.chr);
                    a.is_some_and(is_cjk) && b.is_some_and(is_cjk)
                });
            });
        }
        assert!(parted, "the case words_cell exists for");
    }
}
