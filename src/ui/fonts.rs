//! The window's fonts: egui's, then the bundled CJK subset, then, when a profile names
//! something in a character the subset lacks (a rarer hanzi such as U+9502, lithium), a CJK
//! font of the system that has it; with none installed, the window warns once at load, naming
//! the profile, the characters and how to get such a font, instead of drawing boxes unsaid.

use crate::i18n::glyphs::{SystemFont, system_font_covering};
use crate::i18n::{Text, font_definitions_with, install_cjk_font};
use crate::profile::Registry;
use crate::ui::station::Notice;
use eframe::egui;

/// Installs the fonts `registry`'s texts need into `ctx`, looking for a system CJK font among
/// `candidates` (path, face; [`crate::i18n::glyphs::SYSTEM_CJK_FONTS`]) only when the bundled
/// one lacks a character. Returns the system font installed, or the warning to show when
/// characters stay without a glyph.
pub fn install(
    ctx: &egui::Context,
    registry: &Registry,
    candidates: &[(&str, u32)],
) -> Result<Option<SystemFont>, Notice> {
    let lacking = registry.lacking_glyphs();
    let mut needed: Vec<char> = lacking
        .iter()
        .flat_map(|(_, c)| c.iter().copied())
        .collect();
    needed.sort_unstable();
    needed.dedup();
    if needed.is_empty() {
        install_cjk_font(ctx);
        return Ok(None);
    }
    if let Some(font) = system_font_covering(candidates, &needed) {
        log::info!(
            "characters {} drawn with the system font {}",
            needed.iter().collect::<String>(),
            font.path.display()
        );
        ctx.set_fonts(font_definitions_with(&font));
        return Ok(Some(font));
    }
    install_cjk_font(ctx);
    let which: Vec<String> = lacking
        .iter()
        .map(|(id, c)| format!("{id}: {}", c.iter().collect::<String>()))
        .collect();
    let which = which.join("; ");
    log::warn!("no glyph for profile characters ({which}) and no system CJK font");
    Err(Notice::error(Text::new(
        format!(
            "profile text the bundled font cannot draw ({which}): install a CJK font \
             (Debian: fonts-noto-cjk) and start again"
        ),
        format!(
            "配置文件中有内置字体无法显示的字符({which}):请安装中文字体(Debian:fonts-noto-cjk)后重新启动"
        ),
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A profile labelled with a hanzi the bundled font lacks: warned about at load, naming
    /// the profile and the character, when no system font has it (issue 25, item 11).
    #[test]
    fn a_label_the_bundled_font_cannot_draw_is_warned_about_without_a_system_font() {
        let dir = tempfile::tempdir().unwrap();
        let src = include_str!("../../assets/profiles/window-cleaner.ron")
            .replace("zh: \"风机最大占比\"", "zh: \"\u{9502}电池风机最大占比\"");
        std::fs::write(dir.path().join("window-cleaner.ron"), src).unwrap();
        let registry = Registry::load_from(Some(dir.path())).unwrap();
        assert_eq!(
            registry.lacking_glyphs(),
            vec![("window-cleaner".to_string(), vec!['\u{9502}'])]
        );
        let ctx = egui::Context::default();
        let said = install(&ctx, &registry, &[]).unwrap_err();
        assert!(said.error);
        assert!(
            said.text.contains("window-cleaner: \u{9502}"),
            "{}",
            said.text
        );
        assert!(said.zh.contains("fonts-noto-cjk"), "{}", said.zh);
        // The built-ins alone need nothing of the system.
        let builtin = Registry::builtin().unwrap();
        assert!(builtin.lacking_glyphs().is_empty());
        assert!(install(&ctx, &builtin, &[]).unwrap().is_none());
    }
}
