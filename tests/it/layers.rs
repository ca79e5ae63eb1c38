//! The layers of the house point down only (issue 24): every path into another top-level module
//! of `src/` (`use crate::X`, a group `use crate::{X::.., Y}`, a `crate::X::` path in code or in
//! a doc link, or `super::` climbing out of a top-level module) names a module below its own in
//! [`ORDER`]. The README's "Architecture" section says why the floors are in this order.

use std::path::{Path, PathBuf};

/// The top-level modules of `src/`, bottom first: a module may use only those before it.
pub const ORDER: &[&str] = &[
    "protocol", "i18n", "system", "series", "document", "profile", "packet", "preset", "link",
    "ops", "sim", "capture", "bench", "ui", "cli",
];

/// A path into another top-level module that does not point down.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Upward {
    /// 1-based line of the path.
    line: usize,
    /// The module it names.
    target: String,
}

/// The top-level module and the module path within the crate of a file under `src/`
/// (`link/worker/exchange.rs` is `["link", "worker", "exchange"]`); `None` for the crate root
/// (`lib.rs`, `main.rs`).
fn module_path(relative: &Path) -> Option<Vec<String>> {
    let mut parts: Vec<String> = relative
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    let file = parts.pop()?;
    let stem = file.strip_suffix(".rs")?;
    if parts.is_empty() && matches!(stem, "lib" | "main") {
        return None;
    }
    if stem != "mod" {
        parts.push(stem.to_string());
    }
    Some(parts)
}

/// The top-level modules named after `crate::` in `text` at `at` (one, or each item of a group
/// `crate::{a::b, c}`), with where each begins.
fn named_after_crate(text: &str, at: usize) -> Vec<(usize, String)> {
    if !text[at..].starts_with('{') {
        return vec![(at, ident_at(text, at))];
    }
    // The group's items: split at the commas outside nested braces, up to its closing brace.
    let mut items = Vec::new();
    let (mut depth, mut item) = (0usize, at + 1);
    for (i, c) in text[at + 1..].char_indices() {
        let i = at + 1 + i;
        match c {
            '{' => depth += 1,
            '}' if depth > 0 => depth -= 1,
            '}' | ',' if depth == 0 => {
                items.push(item..i);
                item = i + 1;
                if c == '}' {
                    break;
                }
            }
            _ => {}
        }
    }
    items
        .into_iter()
        .filter_map(|r| {
            let lead = text[r.clone()].len() - text[r.clone()].trim_start().len();
            let start = r.start + lead;
            (start < r.end).then(|| (start, ident_at(text, start)))
        })
        .collect()
}

/// The identifier starting at byte `at` of `text`.
fn ident_at(text: &str, at: usize) -> String {
    text[at..]
        .chars()
        .take_while(|c| c.is_alphanumeric() || *c == '_')
        .collect()
}

/// The paths in `text` (the source of the module at `module`) that name a top-level module not
/// below `module[0]` in `order`; a module of `src/` missing from `order` counts as above all.
fn upward(module: &[String], text: &str, order: &[&str]) -> Vec<Upward> {
    let own = module[0].as_str();
    let floor = |m: &str| order.iter().position(|o| *o == m);
    let Some(own_floor) = floor(own) else {
        return vec![Upward {
            line: 1,
            target: format!("{own} (not in the order)"),
        }];
    };
    let mut found = Vec::new();
    let mut consider = |pos: usize, target: String| {
        if target.is_empty() || target == own || target == "self" || target == "super" {
            return;
        }
        let known = order.contains(&target.as_str());
        if known && floor(&target) <= Some(own_floor) {
            return;
        }
        // `crate::VERSION` and the like: items of the crate root, not modules.
        if !known && !target.chars().next().is_some_and(char::is_lowercase) {
            return;
        }
        let line = text[..pos].matches('\n').count() + 1;
        found.push(Upward { line, target });
    };
    for (at, _) in text.match_indices("crate::") {
        let boundary = text[..at]
            .chars()
            .next_back()
            .is_none_or(|c| !(c.is_alphanumeric() || c == '_'));
        if boundary {
            for (pos, name) in named_after_crate(text, at + "crate::".len()) {
                consider(pos, name);
            }
        }
    }
    // `super::` as many times as the file's module is deep reaches the crate root (an inline
    // `mod tests` needs one more: a name there that is no top-level module is its parent's).
    let mut rest = 0;
    while let Some(found_at) = text[rest..].find("super::") {
        let at = rest + found_at;
        let mut after = at;
        while text[after..].starts_with("super::") {
            after += "super::".len();
        }
        rest = after;
        let climbs = (after - at) / "super::".len();
        let boundary = text[..at]
            .chars()
            .next_back()
            .is_none_or(|c| !(c.is_alphanumeric() || c == '_'));
        if boundary && climbs >= module.len() {
            for (pos, name) in named_after_crate(text, after) {
                if order.contains(&name.as_str()) {
                    consider(pos, name);
                }
            }
        }
    }
    found
}

/// Every `.rs` file under `dir`, sorted.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).expect("reads src/") {
            let path = entry.expect("a directory entry").path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}

/// The upward paths of every file under `src`, as `file:line: ...` lines.
fn violations(src: &Path, order: &[&str]) -> Vec<String> {
    let mut out = Vec::new();
    for file in rust_files(src) {
        let relative = file.strip_prefix(src).expect("under src/");
        let Some(module) = module_path(relative) else {
            continue;
        };
        let text = std::fs::read_to_string(&file).expect("reads a source file");
        for u in upward(&module, &text, order) {
            out.push(format!(
                "src/{}:{}: {} uses {}, which is not below it",
                relative.display(),
                u.line,
                module[0],
                u.target
            ));
        }
    }
    out
}

#[test]
fn every_module_of_src_uses_only_the_modules_below_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let found = violations(&src, ORDER);
    assert!(
        found.is_empty(),
        "paths pointing up the order {}:\n{}",
        ORDER.join(" < "),
        found.join("\n")
    );
    // Every top-level module is in the order, and nothing in the order is gone.
    let mut tops: Vec<String> = rust_files(&src)
        .iter()
        .filter_map(|f| module_path(f.strip_prefix(&src).ok()?))
        .map(|m| m[0].clone())
        .collect();
    tops.sort();
    tops.dedup();
    let mut ordered: Vec<String> = ORDER.iter().map(|s| s.to_string()).collect();
    ordered.sort();
    assert_eq!(tops, ordered, "the order names every top-level module once");
}

fn path(p: &str) -> Vec<String> {
    p.split('/').map(str::to_string).collect()
}

fn targets(module: &str, text: &str) -> Vec<(usize, String)> {
    upward(&path(module), text, ORDER)
        .into_iter()
        .map(|u| (u.line, u.target))
        .collect()
}

#[test]
fn a_planted_upward_import_is_found_with_its_line() {
    // Each way of naming an upper module, planted in the link.
    let planted = "\
use crate::profile::Profile;
use crate::ui::App;
fn f() { crate::ops::device::ping(); }
use crate::{packet::Packet, sim::Faults};
use crate::{
    protocol::msp,
    cli::{self, CliError},
};
/// See [`crate::bench::run`].
fn g() { super::super::ui::tour(); }
";
    assert_eq!(
        targets("link/worker", planted),
        [
            (2, "ui".to_string()),
            (3, "ops".to_string()),
            (4, "sim".to_string()),
            (7, "cli".to_string()),
            (9, "bench".to_string()),
            (10, "ui".to_string()),
        ]
    );
    // `super::super::` from link/worker/exchange.rs stays inside link.
    assert!(targets("link/worker/exchange", "use super::super::ui::x;").is_empty());
    assert_eq!(
        targets("link/worker/exchange", "use super::super::super::ui::x;"),
        [(1, "ui".to_string())]
    );
}

#[test]
fn downward_and_own_paths_and_root_items_pass() {
    let text = "\
use crate::profile::{Profile, Text};
use crate::link::{self, Link};
use crate::{i18n::Lang, protocol};
const V: &str = crate::VERSION;
fn h() { my_crate::ui::x(); }
";
    assert!(
        targets("ops/tuning", text).is_empty(),
        "{:?}",
        targets("ops/tuning", text)
    );
    // The same text one floor lower: the link may not use ops, but here nothing names ops.
    assert_eq!(
        targets("profile", "use crate::ops::Check;"),
        [(1, "ops".to_string())]
    );
}

#[test]
fn a_module_missing_from_the_order_is_reported() {
    assert_eq!(
        targets("records/store", "use crate::profile::Profile;"),
        [(1, "records (not in the order)".to_string())]
    );
}

#[test]
fn module_paths_follow_the_files() {
    assert_eq!(module_path(Path::new("lib.rs")), None);
    assert_eq!(module_path(Path::new("packet.rs")), Some(path("packet")));
    assert_eq!(module_path(Path::new("link/mod.rs")), Some(path("link")));
    assert_eq!(
        module_path(Path::new("link/worker/exchange.rs")),
        Some(path("link/worker/exchange"))
    );
}
