//! Characters the bundled CJK font lacks, and a system CJK font that has them. The bundled
//! subset ([`super::CJK_FONT`]) holds every character of botbench's own texts and profiles and
//! the 3,755 common hanzi; a firmware variant's profile may name something in a rarer one (U+9502,
//! lithium). Such a label is drawn with a CJK font of the system when one is installed, and
//! warned about otherwise (egui would draw a box).

use skrifa::MetadataProvider;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Where the usual CJK fonts live, with the face to use in a collection (`.ttc`): Debian's
/// `fonts-noto-cjk` (face 2: Simplified Chinese), `fonts-wqy-microhei`, `fonts-wqy-zenhei`,
/// `fonts-droid-fallback`, `fonts-arphic-uming`; Windows' Microsoft YaHei; macOS' PingFang.
pub const SYSTEM_CJK_FONTS: &[(&str, u32)] = &[
    ("/usr/share/fonts/opentype/noto/NotoSansCJK-Regular.ttc", 2),
    ("/usr/share/fonts/truetype/wqy/wqy-microhei.ttc", 0),
    ("/usr/share/fonts/truetype/wqy/wqy-zenhei.ttc", 0),
    (
        "/usr/share/fonts/truetype/droid/DroidSansFallbackFull.ttf",
        0,
    ),
    ("/usr/share/fonts/truetype/arphic/uming.ttc", 0),
    ("C:\\Windows\\Fonts\\msyh.ttc", 0),
    ("/System/Library/Fonts/PingFang.ttc", 0),
];

/// The most bytes a system font file is read to (the largest CJK collections are ~20 MB).
const FONT_FILE_MAX: u64 = 64 * 1024 * 1024;

/// Whether `c` is in a block that only a CJK font draws (CJK radicals to ideographs, Hangul,
/// compatibility ideographs and forms, fullwidth forms, the supplementary ideographs).
pub fn is_cjk(c: char) -> bool {
    matches!(c as u32,
        0x2E80..=0x9FFF | 0xAC00..=0xD7AF | 0xF900..=0xFAFF | 0xFE30..=0xFE4F
        | 0xFF00..=0xFFEF | 0x20000..=0x3134F)
}

/// The bundled font's codepoints.
fn bundled() -> &'static std::collections::HashSet<u32> {
    static SET: OnceLock<std::collections::HashSet<u32>> = OnceLock::new();
    SET.get_or_init(|| {
        skrifa::FontRef::new(super::CJK_FONT)
            .map(|f| f.charmap().mappings().map(|(c, _)| c).collect())
            .unwrap_or_default()
    })
}

/// The CJK characters of `text` the bundled font has no glyph for, in order, each once.
pub fn bundled_lacks(text: &str) -> Vec<char> {
    let have = bundled();
    let mut out: Vec<char> = Vec::new();
    for c in text
        .chars()
        .filter(|&c| is_cjk(c) && !have.contains(&(c as u32)))
    {
        if !out.contains(&c) {
            out.push(c);
        }
    }
    out
}

/// A font file of the system, read whole, and the face of it to use.
#[derive(Clone)]
pub struct SystemFont {
    /// Its path.
    pub path: PathBuf,
    /// The face in a collection (0 for a single font).
    pub index: u32,
    /// The file's bytes.
    pub bytes: Vec<u8>,
}

impl std::fmt::Debug for SystemFont {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "SystemFont({}, face {})",
            self.path.display(),
            self.index
        )
    }
}

/// The first of `candidates` (path, face) that exists, reads (at most 64 MB), parses and
/// has a glyph for every one of `needed`; `None` when none does.
pub fn system_font_covering(candidates: &[(&str, u32)], needed: &[char]) -> Option<SystemFont> {
    candidates.iter().find_map(|&(path, index)| {
        let path = Path::new(path);
        let size = std::fs::metadata(path).ok()?.len();
        if size > FONT_FILE_MAX {
            return None;
        }
        let bytes = std::fs::read(path).ok()?;
        let font = skrifa::FontRef::from_index(&bytes, index).ok()?;
        let charmap = font.charmap();
        if !needed.iter().all(|&c| charmap.map(c).is_some()) {
            return None;
        }
        Some(SystemFont {
            path: path.to_path_buf(),
            index,
            bytes,
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bundled_font_lacks_a_rare_hanzi_and_has_the_common_ones() {
        assert_eq!(
            bundled_lacks("\u{9502}电池 电池 STOP 停止"),
            vec!['\u{9502}']
        );
        assert!(bundled_lacks("风机最大占比, 停止 ä é").is_empty());
    }

    #[test]
    fn a_system_font_is_taken_only_when_it_has_every_character_needed() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("font.otf");
        std::fs::write(&path, super::super::CJK_FONT).unwrap();
        let path = path.to_str().unwrap();
        let missing = dir.path().join("none.ttc");
        let candidates = [(missing.to_str().unwrap(), 0), (path, 0)];
        let found = system_font_covering(&candidates, &['安', '停']).expect("the second one");
        assert_eq!(found.path, Path::new(path));
        assert!(
            system_font_covering(&candidates, &['\u{9502}']).is_none(),
            "a font without the character is no help"
        );
    }
}
