//! The bundled CJK font covers every Chinese character botbench shows, and egui draws them.
//!
//! When a profile or a UI string gains a character outside the subset, `every_chinese_character_
//! has_a_glyph` fails naming it: run `bash assets/fonts/make-subset.sh` and commit the new font.

use botbench::i18n::{CJK_FONT, CJK_FONT_NAME, Key, Lang, install_cjk_font, tr};
use eframe::egui::{self, Color32, FontFamily, FontId};
use skrifa::{FontRef, MetadataProvider};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const REGENERATE: &str = "run `bash assets/fonts/make-subset.sh` (see assets/fonts/README.md) \
                          and commit the regenerated font";

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn is_cjk(c: char) -> bool {
    matches!(c as u32, 0x3000..=0x9FFF | 0xFF00..=0xFFEF)
}

/// Files under `dir` (recursively) whose name ends with `ext`, sorted.
fn files(dir: &Path, ext: &str) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let entries = std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display()));
        for entry in entries {
            let path = entry.expect("directory entry").path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|x| x == ext) {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

/// The files whose Chinese must render: the sources, the profiles and the shipped presets and
/// plans (a plan's `zh` names show in the window).
fn scanned_files() -> Vec<PathBuf> {
    let mut all = files(&root().join("src"), "rs");
    all.extend(files(&root().join("assets/profiles"), "ron"));
    all.extend(files(&root().join("presets"), "ron"));
    assert!(all.len() > 10, "scanned too few files: {all:?}");
    all
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The contents of the double-quoted strings of a RON file (comments skipped).
fn ron_strings(text: &str) -> String {
    let mut out = String::new();
    let mut chars = text.chars().peekable();
    let mut in_string = false;
    while let Some(c) = chars.next() {
        if in_string {
            match c {
                '\\' => {
                    chars.next();
                }
                '"' => in_string = false,
                _ => out.push(c),
            }
        } else if c == '"' {
            in_string = true;
        } else if c == '/' && chars.peek() == Some(&'/') {
            for c in chars.by_ref() {
                if c == '\n' {
                    break;
                }
            }
        }
    }
    out
}

fn font() -> FontRef<'static> {
    FontRef::new(CJK_FONT).expect("the bundled font parses")
}

#[test]
fn every_chinese_character_has_a_glyph() {
    let charmap = font().charmap();
    let mut missing: BTreeMap<char, BTreeSet<String>> = BTreeMap::new();
    let mut seen = 0usize;
    for path in scanned_files() {
        let rel = path
            .strip_prefix(root())
            .unwrap_or(&path)
            .display()
            .to_string();
        for c in read(&path).chars().filter(|&c| is_cjk(c)) {
            seen += 1;
            if charmap.map(c).is_none() {
                missing.entry(c).or_default().insert(rel.clone());
            }
        }
    }
    assert!(
        seen > 1000,
        "expected plenty of Chinese in src and profiles, saw {seen}"
    );
    assert!(
        missing.is_empty(),
        "characters without a glyph in the bundled font: {}\n{REGENERATE}",
        missing
            .iter()
            .map(|(c, files)| format!("{c} U+{:04X} ({})", *c as u32, {
                let v: Vec<&str> = files.iter().map(String::as_str).collect();
                v.join(", ")
            }))
            .collect::<Vec<_>>()
            .join("; ")
    );
}

#[test]
fn the_subset_holds_gb2312_level_1() {
    // A few of the 3755 level-1 hanzi that no botbench string uses (yet), first and last.
    let charmap = font().charmap();
    for c in "啊阿埃座做蔼矮艾碍爱隘鞍氨安俺".chars() {
        assert!(
            charmap.map(c).is_some(),
            "{c} missing: the GB2312 level-1 set is incomplete"
        );
    }
    let mapped = charmap.mappings().count();
    assert!((3755..6000).contains(&mapped), "{mapped} codepoints");
}

#[test]
fn codepoints_list_matches_the_font() {
    let list = read(&root().join("assets/fonts/codepoints.txt"));
    let listed: BTreeSet<u32> = list
        .lines()
        .filter(|l| !l.starts_with('#') && !l.is_empty())
        .map(|l| {
            let hex = l
                .strip_prefix("U+")
                .unwrap_or_else(|| panic!("bad line {l:?}"));
            u32::from_str_radix(hex, 16).unwrap_or_else(|e| panic!("bad line {l:?}: {e}"))
        })
        .collect();
    let mapped: BTreeSet<u32> = font().charmap().mappings().map(|(cp, _)| cp).collect();
    assert_eq!(listed, mapped, "codepoints.txt is stale: {REGENERATE}");
}

#[test]
fn font_stays_small_and_licensed() {
    assert!(CJK_FONT.len() < 5 * 1024 * 1024, "{} bytes", CJK_FONT.len());
    let licence = read(&root().join("assets/fonts/LICENSE-OFL.txt"));
    assert!(licence.contains("SIL OPEN FONT LICENSE Version 1.1"));
    assert!(licence.contains("Adobe"));
}

/// A context whose first pass has run, so that its fonts exist.
fn context(with_cjk: bool) -> egui::Context {
    let ctx = egui::Context::default();
    if with_cjk {
        install_cjk_font(&ctx);
    }
    let mut output = ctx.run_ui(egui::RawInput::default(), |_| {});
    output.textures_delta.clear(); // no renderer here to upload the atlas to
    ctx
}

#[test]
fn egui_has_every_ui_and_profile_glyph_after_install() {
    let mut texts: Vec<String> = Key::ALL
        .iter()
        .flat_map(|&k| [tr(Lang::En, k), tr(Lang::Zh, k)])
        .map(str::to_owned)
        .collect();
    texts.extend(Lang::ALL.iter().map(|l| l.native_name().to_owned()));
    for path in files(&root().join("assets/profiles"), "ron") {
        texts.push(ron_strings(&read(&path)));
    }
    let all: BTreeSet<char> = texts.iter().flat_map(|t| t.chars()).collect();

    let plain = context(false);
    let cjk = context(true);
    for family in [FontFamily::Proportional, FontFamily::Monospace] {
        let id = FontId::new(14.0, family.clone());
        assert!(
            !plain.fonts_mut(|f| f.has_glyph(&id, '舵')),
            "egui's default fonts already have CJK: the test proves nothing"
        );
        let missing: String = cjk.fonts_mut(|f| {
            all.iter()
                .copied()
                .filter(|&c| !c.is_control() && !f.has_glyph(&id, c))
                .collect()
        });
        assert!(missing.is_empty(), "{family:?} cannot draw {missing:?}");
        let families = cjk.fonts(|f| f.definitions().families[&family].clone());
        assert_eq!(families.last().map(String::as_str), Some(CJK_FONT_NAME));
    }
}

#[test]
fn egui_rasterizes_the_cjk_outlines() {
    // The subset has CFF outlines: check egui really draws them into its atlas.
    let ctx = context(true);
    let inked =
        |f: &mut egui::epaint::FontsView<'_>| f.image().pixels.iter().filter(|p| p.a() > 0).count();
    let before = ctx.fonts_mut(inked);
    let galley = ctx.fonts_mut(|f| {
        f.layout_no_wrap(
            tr(Lang::Zh, Key::ServoBench).to_owned(),
            FontId::proportional(20.0),
            Color32::WHITE,
        )
    });
    let after = ctx.fonts_mut(inked);
    assert!(galley.size().x > 40.0, "galley {:?}", galley.size());
    assert!(after > before + 50, "atlas ink {before} -> {after}");
}
