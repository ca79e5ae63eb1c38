//! Choosing a file: every choice is a text box that takes a typed path, with a Browse… button
//! beside it for the system's file dialog. Many line PCs have no xdg desktop portal and no
//! zenity, and there rfd's dialog returns at once with nothing: botbench looks for them when it
//! starts, and a Browse that cannot open a dialog says so instead of doing nothing.

use super::Action;
use super::station::Notice;
use crate::i18n::Lang;
use eframe::egui;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Whether the system can show a file dialog.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Dialogs {
    /// A dialog can open (an xdg desktop portal or zenity is there, or not Linux).
    Available,
    /// None can: why, for the status line.
    Missing(String),
}

impl Dialogs {
    /// Looks for what rfd's xdg-portal backend needs on Linux: a session bus with a desktop
    /// portal, or the `zenity` program (its fallback).
    pub fn detect() -> Dialogs {
        if !cfg!(target_os = "linux") {
            return Dialogs::Available;
        }
        let path = std::env::var_os("PATH").unwrap_or_default();
        let bus = std::env::var_os("DBUS_SESSION_BUS_ADDRESS").is_some();
        Self::from_system(&path, bus, &|p| p.exists())
    }

    /// [`Self::detect`] from `PATH`, whether a session bus is named, and a file-existence test.
    pub fn from_system(path: &std::ffi::OsStr, bus: bool, exists: &dyn Fn(&Path) -> bool) -> Self {
        let zenity = std::env::split_paths(path).any(|d| exists(&d.join("zenity")));
        let portal = bus && PORTALS.iter().any(|p| exists(Path::new(p)));
        if zenity || portal {
            Dialogs::Available
        } else {
            Dialogs::Missing(
                "no file dialog on this system (neither an xdg desktop portal nor zenity): type \
                 the path in the box"
                    .into(),
            )
        }
    }
}

/// Where distributions install the desktop portal service.
const PORTALS: [&str; 3] = [
    "/usr/libexec/xdg-desktop-portal",
    "/usr/lib/xdg-desktop-portal",
    "/usr/lib/xdg-desktop-portal/xdg-desktop-portal",
];

/// What the dialog should ask for.
#[derive(Debug, Clone, Copy)]
pub enum Pick<'a> {
    /// An existing file, of these extensions (empty: any).
    Open(&'a [&'a str]),
    /// A file to write, proposed under this name.
    Save(&'a str),
}

/// What happened to a file row this frame.
#[derive(Debug, Clone, PartialEq)]
pub enum FileEvent {
    /// Nothing.
    None,
    /// The dialog gave a path (now in the box).
    Chosen(PathBuf),
    /// The dialog could not open, or closed at once with nothing: why.
    NoDialog(String),
}

impl FileEvent {
    /// Whether the panel goes on with the path in the box: one was chosen in the dialog, or
    /// `pressed` (the panel's own button beside the row was clicked: a typed path). A dialog
    /// that could not open is said in the status line, pushed onto `actions`.
    pub fn go(self, pressed: bool, actions: &mut Vec<Action>) -> bool {
        match self {
            FileEvent::NoDialog(why) => {
                actions.push(Action::Notify(Notice::error(no_dialog(why))));
                pressed
            }
            FileEvent::Chosen(_) => true,
            FileEvent::None => pressed,
        }
    }
}

/// The status line's message when a file dialog could not open: `why` in English (what
/// [`FileEvent::NoDialog`] carries), the advice in Chinese.
pub(crate) fn no_dialog(why: String) -> crate::i18n::Text {
    crate::i18n::Text::new(
        why,
        "文件对话框无法打开(没有可用的 xdg 桌面门户或 zenity):请在框中输入路径",
    )
}

/// A dialog that returns nothing sooner than this did not show (a person takes longer).
const TOO_QUICK: Duration = Duration::from_millis(150);

/// What a file row shows: its label, the hint in the empty box, what Browse… picks, and
/// whether both are enabled.
#[derive(Debug, Clone, Copy)]
pub struct Row<'a> {
    /// The label before the box.
    pub label: &'a str,
    /// Shown in the empty box.
    pub hint: &'a str,
    /// What Browse… asks for.
    pub pick: Pick<'a>,
    /// Off greys the box and Browse… out.
    pub enabled: bool,
}

/// A labelled file row: the path box (typed paths work whatever the system) and Browse…, as
/// `row` says, editing `path`.
pub fn row(
    ui: &mut egui::Ui,
    lang: Lang,
    row: Row<'_>,
    path: &mut String,
    dialogs: &Dialogs,
) -> FileEvent {
    let Row {
        label,
        hint,
        pick,
        enabled,
    } = row;
    // The label stays on the row of its box (a toolbar moves the two together).
    crate::ui::layout::group(ui, label, |ui| {
        let l = ui.label(label);
        ui.add_enabled(
            enabled,
            egui::TextEdit::singleline(path)
                .hint_text(hint)
                .desired_width(300.0),
        )
        .labelled_by(l.id);
    });
    let browse = ui.add_enabled(enabled, egui::Button::new(lang.tr("Browse…", "浏览…")));
    let browse = match dialogs {
        Dialogs::Available => browse,
        Dialogs::Missing(why) => browse.on_hover_text(why),
    };
    if !browse.clicked() {
        return FileEvent::None;
    }
    if let Dialogs::Missing(why) = dialogs {
        return FileEvent::NoDialog(why.clone());
    }
    let mut dialog = rfd::FileDialog::new();
    let typed = PathBuf::from(path.trim());
    // Where the typed path points, else, for a plan or preset to open, the shipped examples
    // (`/usr/share/botbench/presets` when installed: not where a file is written).
    let document = matches!(pick, Pick::Open(exts) if exts.contains(&"ron"));
    if let Some(dir) = typed
        .parent()
        .filter(|d| d.is_dir() && !d.as_os_str().is_empty())
    {
        dialog = dialog.set_directory(dir);
    } else if let Some(dir) = crate::system::presets_dir().filter(|_| document) {
        dialog = dialog.set_directory(dir);
    }
    let started = Instant::now();
    let chosen = match pick {
        Pick::Open(exts) => {
            if !exts.is_empty() {
                dialog = dialog.add_filter(exts.join(", "), exts);
            }
            dialog.pick_file()
        }
        Pick::Save(name) => dialog.set_file_name(name).save_file(),
    };
    match chosen {
        Some(p) => {
            *path = p.display().to_string();
            FileEvent::Chosen(p)
        }
        None if started.elapsed() < TOO_QUICK => FileEvent::NoDialog(
            "the file dialog did not open (no working xdg desktop portal or zenity): type the \
             path in the box"
                .into(),
        ),
        None => FileEvent::None,
    }
}

/// The plans and presets botbench ships (`presets/` in the source), built into the binary so
/// that they are there wherever it runs: (file name, contents).
pub const SHIPPED: [(&str, &str); 3] = [
    (
        "window-cleaner-selftest.ron",
        include_str!("../../presets/window-cleaner-selftest.ron"),
    ),
    (
        "window-cleaner-factory.ron",
        include_str!("../../presets/window-cleaner-factory.ron"),
    ),
    (
        "servo-provision-plan.ron",
        include_str!("../../presets/servo-provision-plan.ron"),
    ),
];

/// The folder the shipped files are put in for the technician to open and edit:
/// `$XDG_DATA_HOME/botbench/presets`, else `~/.local/share/botbench/presets`, else the system's
/// temporary folder's `botbench-presets`.
pub fn shipped_dir() -> PathBuf {
    let data = std::env::var_os("XDG_DATA_HOME")
        .filter(|d| !d.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".local/share")));
    match data {
        Some(d) => d.join("botbench").join("presets"),
        None => std::env::temp_dir().join("botbench-presets"),
    }
}

/// The path of shipped file `name` in `dir`, written there from the built-in copy when it is not
/// there yet (a technician's edits to it are kept). Errors: `name` is not shipped, or the folder
/// cannot be made or the file written.
pub fn shipped_in(dir: &Path, name: &str) -> std::io::Result<PathBuf> {
    let Some((_, text)) = SHIPPED.iter().find(|(n, _)| *n == name) else {
        return Err(std::io::Error::new(
            std::io::ErrorKind::NotFound,
            format!("{name} is not a shipped file"),
        ));
    };
    let path = dir.join(name);
    if !path.exists() {
        std::fs::create_dir_all(dir)?;
        crate::document::write_atomic(&path, text.as_bytes())
            .map_err(|e| std::io::Error::other(e.to_string()))?;
    }
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::ffi::OsStr;

    #[test]
    fn a_shipped_file_is_found_outside_the_source_and_a_technicians_edit_is_kept() {
        let dir = tempfile::tempdir().unwrap();
        let plan = shipped_in(dir.path(), "window-cleaner-selftest.ron").unwrap();
        assert_eq!(std::fs::read_to_string(&plan).unwrap(), SHIPPED[0].1);
        std::fs::write(&plan, "edited").unwrap();
        let again = shipped_in(dir.path(), "window-cleaner-selftest.ron").unwrap();
        assert_eq!(std::fs::read_to_string(again).unwrap(), "edited");
        assert!(shipped_in(dir.path(), "nothing.ron").is_err());
    }

    #[test]
    fn a_dialog_needs_a_portal_on_a_session_bus_or_zenity() {
        let none = |_: &Path| false;
        assert!(matches!(
            Dialogs::from_system(OsStr::new("/usr/bin:/bin"), true, &none),
            Dialogs::Missing(m) if m.contains("type the path")
        ));
        let zenity = |p: &Path| p == Path::new("/usr/bin/zenity");
        assert_eq!(
            Dialogs::from_system(OsStr::new("/bin:/usr/bin"), false, &zenity),
            Dialogs::Available
        );
        let portal = |p: &Path| p == Path::new("/usr/libexec/xdg-desktop-portal");
        assert_eq!(
            Dialogs::from_system(OsStr::new(""), true, &portal),
            Dialogs::Available
        );
        assert!(matches!(
            Dialogs::from_system(OsStr::new(""), false, &portal),
            Dialogs::Missing(_)
        ));
    }
}
