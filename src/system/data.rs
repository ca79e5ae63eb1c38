//! Where the shipped example files (presets, plans, profiles) are: `BOTBENCH_DATA_DIR`,
//! `../share/botbench` from the executable, a checkout above it, `/usr/share/botbench`.

use std::path::{Path, PathBuf};

/// The environment variable naming the folder of the example files, over every other choice.
pub const DATA_DIR_ENV: &str = "BOTBENCH_DATA_DIR";

/// Where the Debian package puts the example files.
#[cfg(unix)]
pub const INSTALLED_DATA_DIR: &str = "/usr/share/botbench";

/// The folder of the shipped example files (`presets/`: presets and plans; `profiles/`: the
/// built-in profiles, to copy and edit): `$BOTBENCH_DATA_DIR` if set; else, from the
/// executable's folder, `../share/botbench` (installed: `/usr/bin` → `/usr/share/botbench`),
/// the folder itself when it holds `presets/` (an unpacked archive), or the source checkout
/// above it (a development build in `target/release`); else [`INSTALLED_DATA_DIR`].
pub fn data_dir() -> Option<PathBuf> {
    let exe = std::env::current_exe().ok();
    data_dir_from(
        std::env::var_os(DATA_DIR_ENV).map(PathBuf::from),
        exe.as_deref(),
    )
}

/// [`data_dir`] with its inputs given.
fn data_dir_from(env: Option<PathBuf>, exe: Option<&Path>) -> Option<PathBuf> {
    if let Some(dir) = env.filter(|d| !d.as_os_str().is_empty()) {
        return Some(dir);
    }
    if let Some(bin) = exe.and_then(Path::parent) {
        let share = bin.join("../share/botbench");
        if share.join("presets").is_dir() {
            return Some(share.canonicalize().unwrap_or(share));
        }
        if bin.join("presets").is_dir() {
            return Some(bin.to_path_buf());
        }
        if let Some(checkout) = bin
            .ancestors()
            .find(|d| d.join("Cargo.toml").is_file() && d.join("presets").is_dir())
        {
            return Some(checkout.to_path_buf());
        }
    }
    #[cfg(unix)]
    {
        Some(PathBuf::from(INSTALLED_DATA_DIR))
    }
    #[cfg(not(unix))]
    {
        None
    }
}

/// `path` as given when it exists or is absolute; a relative path that is not here but is in
/// the shipped examples ([`data_dir`]) is taken from there, so that
/// `presets/window-cleaner-selftest.ron` opens on an installed machine in any folder.
pub fn shipped_or_given(path: &Path) -> PathBuf {
    shipped_or_given_in(data_dir().as_deref(), path)
}

/// [`shipped_or_given`] with the data folder given.
fn shipped_or_given_in(data: Option<&Path>, path: &Path) -> PathBuf {
    if path.is_absolute() || path.exists() {
        return path.to_path_buf();
    }
    data.map(|d| d.join(path))
        .filter(|p| p.is_file())
        .unwrap_or_else(|| path.to_path_buf())
}

/// The folder of the shipped presets and plans, for a file dialog to start in (where it exists).
pub fn presets_dir() -> Option<PathBuf> {
    data_dir().map(|d| d.join("presets")).filter(|d| d.is_dir())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_data_dir_follows_the_environment_then_the_executable() {
        let root = tempfile::tempdir().unwrap();
        let r = root.path();
        // Installed: PREFIX/bin/botbench and PREFIX/share/botbench/presets.
        std::fs::create_dir_all(r.join("usr/bin")).unwrap();
        std::fs::create_dir_all(r.join("usr/share/botbench/presets")).unwrap();
        let exe = r.join("usr/bin/botbench");
        let share = r.join("usr/share/botbench").canonicalize().unwrap();
        assert_eq!(data_dir_from(None, Some(&exe)), Some(share));
        // The environment wins.
        let env = r.join("elsewhere");
        assert_eq!(data_dir_from(Some(env.clone()), Some(&exe)), Some(env));
        // An unpacked archive: presets/ beside the executable.
        std::fs::create_dir_all(r.join("portable/presets")).unwrap();
        let portable = r.join("portable/botbench");
        assert_eq!(
            data_dir_from(None, Some(&portable)),
            Some(r.join("portable"))
        );
        // A development build: the checkout above target/release.
        std::fs::create_dir_all(r.join("src/target/release")).unwrap();
        std::fs::create_dir_all(r.join("src/presets")).unwrap();
        std::fs::write(r.join("src/Cargo.toml"), "").unwrap();
        let dev = r.join("src/target/release/botbench");
        assert_eq!(data_dir_from(None, Some(&dev)), Some(r.join("src")));
        // Nothing found: the package's folder.
        let lost = r.join("lost/botbench");
        #[cfg(unix)]
        assert_eq!(
            data_dir_from(None, Some(&lost)),
            Some(PathBuf::from(INSTALLED_DATA_DIR))
        );
    }

    #[test]
    fn a_relative_path_not_found_here_comes_from_the_examples() {
        let data = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(data.path().join("presets")).unwrap();
        let shipped = data.path().join("presets/plan.ron");
        std::fs::write(&shipped, "()").unwrap();
        let d = Some(data.path());
        assert_eq!(
            shipped_or_given_in(d, Path::new("presets/plan.ron")),
            shipped
        );
        // Found here (relative to the working folder): kept.
        assert_eq!(
            shipped_or_given_in(d, Path::new("Cargo.toml")),
            PathBuf::from("Cargo.toml")
        );
        // Found nowhere: kept, for the error to name it as given.
        let missing = Path::new("presets/missing.ron");
        assert_eq!(shipped_or_given_in(d, missing), missing.to_path_buf());
        assert_eq!(shipped_or_given_in(None, missing), missing.to_path_buf());
        // Absolute: kept.
        let abs = data.path().join("plan.ron");
        assert_eq!(shipped_or_given_in(d, &abs), abs);
    }
}
