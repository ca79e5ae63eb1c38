#!/usr/bin/env bash
# make-subset.sh — regenerates assets/fonts/NotoSansCJKsc-Regular-subset.otf, the CJK font that
# botbench embeds (src/i18n/mod.rs, `include_bytes!`) so that its Chinese labels render.
#
# The generated font is committed: building botbench never runs this script. Run it again when
# the UI strings grow, that is when `cargo test --test i18n` (or the unit tests in src/i18n/mod.rs)
# report a Chinese character that has no glyph in the bundled font.
#
# Needs (Debian + PyPI):
#     apt-get update && apt-get install -y fonts-noto-cjk
#     pip install fonttools
#
# Usage (from anywhere):  bash assets/fonts/make-subset.sh
#
# What goes in the subset:
#   * every non-ASCII character found in src/**/*.rs and assets/**/*.ron (scanned afresh),
#   * the GB2312 level-1 hanzi (3755 common characters: GB2312 bytes 0xB0A1-0xD7F9, decoded),
#   * printable ASCII, Latin-1 punctuation and symbols (U+00A0-00FF), general punctuation
#     (U+2000-206F), CJK symbols and punctuation (U+3000-303F), halfwidth and fullwidth forms
#     (U+FF00-FFEF).
# From the Simplified Chinese face (number 2) of Debian's NotoSansCJK-Regular.ttc, with all
# name records kept (copyright, licence) and the hinting kept. The output is an OpenType/CFF
# `.otf`. It is idempotent: the same inputs give the same bytes (SOURCE_DATE_EPOCH is pinned to
# the source font's own modification date, so fontTools writes no "now" timestamp).
#
# It also writes codepoints.txt beside the font: one `U+XXXX` per line, every codepoint the
# subset maps, for people and tools that want to check coverage without parsing the font.
set -euo pipefail

HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/../.." && pwd)"
SRC_FONT="${SRC_FONT:-/usr/share/fonts/opentype/noto/NotoSansCJK-Regular.ttc}"
FACE="${FACE:-2}" # 0 JP, 1 KR, 2 SC, 3 TC, 4 HK in the Debian .ttc
OUT="$HERE/NotoSansCJKsc-Regular-subset.otf"

if [[ ! -f "$SRC_FONT" ]]; then
    echo "missing $SRC_FONT: apt-get install -y fonts-noto-cjk" >&2
    exit 1
fi
if ! command -v pyftsubset >/dev/null; then
    echo "missing pyftsubset: pip install fonttools" >&2
    exit 1
fi

WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT

# Check the face is the Simplified Chinese one, collect the characters, pin the timestamp.
python3 - "$SRC_FONT" "$FACE" "$ROOT" "$WORK" <<'PY'
import pathlib, sys
from fontTools.ttLib import TTFont

src_font, face, root, work = sys.argv[1], int(sys.argv[2]), pathlib.Path(sys.argv[3]), pathlib.Path(sys.argv[4])
font = TTFont(src_font, fontNumber=face, lazy=True)
name = font["name"].getDebugName(4)
if name != "Noto Sans CJK SC":
    sys.exit(f"face {face} of {src_font} is {name!r}, not 'Noto Sans CJK SC'")

chars = set()
files = sorted(root.glob("src/**/*.rs")) + sorted(root.glob("assets/**/*.ron"))
for path in files:
    chars.update(ch for ch in path.read_text(encoding="utf-8") if ord(ch) > 0x7E)

level1 = set()
for hi in range(0xB0, 0xD8):
    for lo in range(0xA1, 0xFF):
        if hi == 0xD7 and lo > 0xF9:
            break  # 0xD7FA-0xD7FE are unassigned
        level1.add(bytes([hi, lo]).decode("gb2312"))
assert len(level1) == 3755, len(level1)
chars |= level1
# These must all be in the subset; the ranges below may hold codepoints the font lacks.
(work / "required.txt").write_text("".join(sorted(chars)), encoding="utf-8")

ranges = [(0x20, 0x7E), (0xA0, 0xFF), (0x2000, 0x206F), (0x3000, 0x303F), (0xFF00, 0xFFEF)]
for lo, hi in ranges:
    chars.update(chr(c) for c in range(lo, hi + 1))

(work / "chars.txt").write_text("".join(sorted(chars)), encoding="utf-8")
# head.modified counts seconds from 1904-01-01; SOURCE_DATE_EPOCH counts from 1970-01-01.
(work / "epoch").write_text(str(font["head"].modified - 2082844800))
print(f"{len(files)} files scanned, {len(chars)} characters requested")
PY

SOURCE_DATE_EPOCH="$(cat "$WORK/epoch")" pyftsubset "$SRC_FONT" \
    --font-number="$FACE" \
    --text-file="$WORK/chars.txt" \
    --name-IDs='*' \
    --name-languages='*' \
    --notdef-outline \
    --output-file="$OUT"

# Verify: every CJK character of the scanned files must be in the subset; list what it maps.
python3 - "$OUT" "$WORK/required.txt" "$HERE/codepoints.txt" <<'PY'
import sys
from fontTools.ttLib import TTFont

out, required_file, list_file = sys.argv[1:4]
cmap = TTFont(out)["cmap"].getBestCmap()
wanted = open(required_file, encoding="utf-8").read()
missing = [c for c in wanted if ord(c) not in cmap]
cjk = [c for c in missing if 0x3000 <= ord(c) <= 0x9FFF or 0xFF00 <= ord(c) <= 0xFFEF]
other = [c for c in missing if c not in cjk]
if other:
    print(f"note: not in the source font (egui's default fonts may cover them): {''.join(other)}")
with open(list_file, "w", encoding="ascii") as f:
    f.write("# Codepoints mapped by NotoSansCJKsc-Regular-subset.otf; written by make-subset.sh.\n")
    for cp in sorted(cmap):
        f.write(f"U+{cp:04X}\n")
if cjk:
    sys.exit("source font lacks: " + " ".join(f"U+{ord(c):04X}({c})" for c in cjk))
print(f"{out}: {len(cmap)} codepoints")
PY

du -h "$OUT"
