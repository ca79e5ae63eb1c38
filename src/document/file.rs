//! Files botbench reads and writes for a person: read within a size limit suited to each kind
//! ([`Limit`]), only when they are regular files, and written atomically through temporary files
//! of botbench's own that a killed save cannot leave piling up.
//!
//! Every file a person names (presets, plans, profiles, firmware images) is read by
//! [`read_bytes`] or [`read_text`]; every file botbench writes for a person goes through
//! [`write_atomic`], and a destination can be checked before the work that produces its
//! content ([`check_destination`]).

use super::{DocumentError, ErrorKind};
use std::io::{Read, Write};
use std::path::Path;

/// What a file is for, and the most bytes botbench reads of it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limit {
    /// What the file is, as errors name it: `preset`, `firmware image`.
    pub what: &'static str,
    /// The largest size accepted, in bytes.
    pub max: u64,
}

impl Limit {
    /// A preset of a device's tunable parameters (the factory preset is 3.5 KiB).
    pub const PRESET: Limit = Limit::new("preset", 1 << 20);
    /// A servo parameter preset (32 parameters, about 2 KiB).
    pub const SERVO_PRESET: Limit = Limit::new("servo parameter preset", 256 << 10);
    /// A self-test plan (the line-3 plan is 3.7 KiB).
    pub const SELFTEST_PLAN: Limit = Limit::new("self-test plan", 1 << 20);
    /// A servo provisioning plan (1.8 KiB).
    pub const PROVISION_PLAN: Limit = Limit::new("provisioning plan", 256 << 10);
    /// A device profile (the largest built-in, the servo's, is 36 KiB).
    pub const PROFILE: Limit = Limit::new("profile", 2 << 20);
    /// An MCU firmware image, before the device's own limit (the Tuya profile's) is applied.
    pub const FIRMWARE: Limit = Limit::new("firmware image", 16 << 20);

    /// A limit of `max` bytes for files of kind `what`.
    pub const fn new(what: &'static str, max: u64) -> Self {
        Self { what, max }
    }
}

/// A size as a person reads it: `512 bytes`, `1 MiB`, `1.5 MiB`.
pub fn size_text(bytes: u64) -> String {
    const UNITS: [(&str, u64); 3] = [("GiB", 1 << 30), ("MiB", 1 << 20), ("KiB", 1 << 10)];
    for (unit, n) in UNITS {
        if bytes >= n {
            let v = bytes as f64 / n as f64;
            return if v.fract() == 0.0 {
                format!("{v:.0} {unit}")
            } else {
                format!("{v:.1} {unit}")
            };
        }
    }
    format!("{bytes} bytes")
}

/// What a path that is not a regular file is, for a message: `a named pipe`, `a folder`.
pub fn kind_of(t: std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_char_device() {
            return "a character device (a terminal, a serial port, /dev/zero...)";
        }
        if t.is_block_device() {
            return "a block device";
        }
        if t.is_fifo() {
            return "a named pipe";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if t.is_dir() { "a folder" } else { "not a file" }
}

fn refuse(path: &Path, message: String) -> DocumentError {
    DocumentError::one(&path.display().to_string(), ErrorKind::Io, (0, 0), message)
}

/// Reads the file at `path`, at most `limit.max` bytes. Refused, before a byte is read: what is
/// not a regular file (a folder, a device such as `/dev/zero`, a pipe), a file over the limit.
/// A file that grows past the limit while it is read is refused too.
pub fn read_bytes(path: &Path, limit: Limit) -> Result<Vec<u8>, DocumentError> {
    // The type is checked before opening: opening a named pipe would wait for a writer.
    let meta = std::fs::metadata(path).map_err(|e| DocumentError::io(path, "read", &e))?;
    if !meta.is_file() {
        return Err(refuse(
            path,
            format!("not a {} file: {}", limit.what, kind_of(meta.file_type())),
        ));
    }
    let too_big = |size: Option<u64>| {
        let size = size.map_or(format!("over {}", size_text(limit.max)), size_text);
        refuse(
            path,
            format!(
                "the file is {size}; a {} is at most {}",
                limit.what,
                size_text(limit.max)
            ),
        )
    };
    if meta.len() > limit.max {
        return Err(too_big(Some(meta.len())));
    }
    let file = std::fs::File::open(path).map_err(|e| DocumentError::io(path, "read", &e))?;
    let mut bytes = Vec::with_capacity(usize::try_from(meta.len()).unwrap_or(0));
    file.take(limit.max + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| DocumentError::io(path, "read", &e))?;
    if bytes.len() as u64 > limit.max {
        // It grew while it was read.
        return Err(too_big(None));
    }
    Ok(bytes)
}

/// Reads the text file at `path` as [`read_bytes`] does; text that is not UTF-8 is refused with
/// the line and column of the first bad byte (the bytes are not quoted).
pub fn read_text(path: &Path, limit: Limit) -> Result<String, DocumentError> {
    let bytes = read_bytes(path, limit)?;
    String::from_utf8(bytes).map_err(|e| {
        let bytes = e.as_bytes();
        let at = e.utf8_error().valid_up_to();
        let good = std::str::from_utf8(&bytes[..at]).unwrap_or_default();
        let (line, col) = super::line_col(good, good.len());
        DocumentError::one(
            &path.display().to_string(),
            ErrorKind::Syntax,
            (line, col),
            format!(
                "not UTF-8 text: byte {:#04x} at offset {at} (is this a {}?)",
                bytes[at], limit.what
            ),
        )
    })
}

/// The suffix of botbench's temporary files, which only [`write_atomic`] creates.
const TMP_SUFFIX: &str = ".botbench-tmp";

/// The folder a file at `path` is written in.
fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// Checks, without writing it, that a file can be saved at `path`: its folder exists and takes
/// a new file, and `path` is a regular file or nothing. Used before work whose result would be
/// lost (reading a whole device), so that a bad destination is refused first.
pub fn check_destination(path: &Path) -> Result<(), DocumentError> {
    check_target(path)?;
    // The one sure test of a folder that takes a new file: make one (removed on drop).
    TempInFolder::create(path).map(drop)
}

/// Checks that a log at `path` can be appended to, creating it empty if it is missing: its
/// folder exists, and `path` is a regular file or nothing (a named pipe would hold the append
/// until a reader came). Used before the work whose record it keeps.
pub fn check_append(path: &Path) -> Result<(), DocumentError> {
    check_target(path)?;
    std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .map(drop)
        .map_err(|e| DocumentError::io(path, "append to it", &e))
}

/// The checks of [`check_destination`] that need no file made.
fn check_target(path: &Path) -> Result<(), DocumentError> {
    let text = path.to_string_lossy();
    let named = path.file_name().is_some_and(|n| n != "." && n != "..");
    if !named || text.ends_with('/') || text.ends_with(std::path::MAIN_SEPARATOR) {
        return Err(refuse(path, "names a folder, not a file".to_string()));
    }
    if let Ok(m) = std::fs::metadata(path)
        && !m.is_file()
    {
        return Err(refuse(
            path,
            format!("cannot be replaced: it is {}", kind_of(m.file_type())),
        ));
    }
    let dir = folder_of(path);
    match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => Ok(()),
        Ok(_) => Err(refuse(path, format!("{} is not a folder", dir.display()))),
        Err(e) => Err(refuse(
            path,
            format!("cannot write in the folder {}: {e}", dir.display()),
        )),
    }
}

/// A temporary file of botbench's own, beside its target, locked while it is written.
struct TempInFolder(tempfile::NamedTempFile);

impl TempInFolder {
    /// Removes the temporary files a killed save left in `path`'s folder, then makes a new one,
    /// named `.<file name>.<random>.botbench-tmp` and locked for as long as it exists.
    fn create(path: &Path) -> Result<Self, DocumentError> {
        let dir = folder_of(path);
        remove_stale(dir);
        let prefix = format!(
            ".{}.",
            path.file_name()
                .map_or("file".into(), |n| n.to_string_lossy())
        );
        // A cleaner in another process may take a file made here for stale between its
        // creation and its lock, and remove it; then make another.
        for _ in 0..8 {
            let mut builder = tempfile::Builder::new();
            builder.prefix(&prefix).suffix(TMP_SUFFIX);
            // The mode a file the user makes gets (0666 less the umask: 0644 as a rule), not
            // a temporary file's 0600: a preset saved on a line PC is read by other users.
            #[cfg(unix)]
            {
                use std::os::unix::fs::PermissionsExt;
                builder.permissions(std::fs::Permissions::from_mode(0o666));
            }
            let tmp = builder.tempfile_in(dir).map_err(|e| {
                DocumentError::io(path, "create a temporary file in its folder", &e)
            })?;
            tmp.as_file()
                .lock()
                .map_err(|e| DocumentError::io(path, "lock its temporary file", &e))?;
            if still_named(&tmp) {
                return Ok(Self(tmp));
            }
        }
        Err(refuse(
            path,
            "cannot keep a temporary file in its folder: another program removes them".into(),
        ))
    }
}

/// Whether the temporary file's name still leads to it (no cleaner removed it).
fn still_named(tmp: &tempfile::NamedTempFile) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (std::fs::metadata(tmp.path()), tmp.as_file().metadata()) {
            (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        tmp.path().exists()
    }
}

/// Removes botbench's temporary files in `dir` whose writer is gone: each is locked by its
/// writer while it lives, and the lock ends with the process, so a file that can be locked was
/// left by a save that was killed. Files of other programs are never touched.
fn remove_stale(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let name = name.to_string_lossy();
        let ours = name.starts_with('.') && name.ends_with(TMP_SUFFIX);
        if !ours || !entry.file_type().is_ok_and(|t| t.is_file()) {
            continue;
        }
        let Ok(file) = std::fs::File::open(entry.path()) else {
            continue;
        };
        if file.try_lock().is_ok() {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// Writes `bytes` to `path` atomically: into a temporary file of botbench's own in the same
/// folder, synced to disk, then renamed over `path`. On any failure `path` is untouched and the
/// temporary file is removed; one left by a killed save is removed by the next save in that
/// folder. A `path` that exists and is not a regular file (a folder, a device) is refused.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), DocumentError> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// [`write_atomic`], the content written by `write` (streamed, for large files).
pub fn write_atomic_with(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), DocumentError> {
    check_target(path)?;
    let TempInFolder(mut tmp) = TempInFolder::create(path)?;
    {
        let mut w = std::io::BufWriter::new(tmp.as_file_mut());
        write(&mut w)
            .and_then(|()| w.flush())
            .map_err(|e| DocumentError::io(path, "write", &e))?;
    }
    // A file saved over keeps its own permissions.
    if let Ok(meta) = std::fs::metadata(path) {
        tmp.as_file()
            .set_permissions(meta.permissions())
            .map_err(|e| DocumentError::io(path, "keep its permissions", &e))?;
    }
    tmp.as_file()
        .sync_all()
        .map_err(|e| DocumentError::io(path, "write", &e))?;
    tmp.persist(path)
        .map_err(|e| DocumentError::io(path, "replace the file", &e.error))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A saved file gets the mode a file the user makes gets (not a temporary file's 0600),
    /// and one saved over keeps its own.
    #[cfg(unix)]
    #[test]
    fn a_saved_file_is_readable_as_the_users_files_are_and_keeps_its_mode() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let plain = dir.path().join("plain.txt");
        std::fs::write(&plain, b"x").unwrap();
        let made = std::fs::metadata(&plain).unwrap().permissions().mode() & 0o777;
        let saved = dir.path().join("saved.ron");
        write_atomic(&saved, b"()").unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&saved), made, "as std::fs::write makes it");
        std::fs::set_permissions(&saved, std::fs::Permissions::from_mode(0o640)).unwrap();
        write_atomic(&saved, b"(again)").unwrap();
        assert_eq!(mode(&saved), 0o640);
    }
    use std::path::PathBuf;

    /// The names in `dir`, sorted.
    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn a_killed_saves_temporary_file_is_removed_by_the_next_save() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("target.ron");
        // What a save killed between creating its temporary file and renaming it leaves: a
        // file of botbench's own, locked by nobody.
        let stale = dir.path().join(".target.ron.a1b2c3.botbench-tmp");
        std::fs::write(&stale, "half a preset").unwrap();
        // One a live save holds (locked), and files of other programs, are kept.
        let live = dir.path().join(".other.ron.d4e5f6.botbench-tmp");
        std::fs::write(&live, "being written").unwrap();
        let holder = std::fs::File::open(&live).unwrap();
        holder.lock().unwrap();
        let foreign = ["notes.tmp", ".target.ron.1234.tmp", "x.botbench-tmp"];
        for f in foreign {
            std::fs::write(dir.path().join(f), "not ours").unwrap();
        }
        write_atomic(&target, b"whole").unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"whole");
        let mut expected: Vec<String> = foreign.iter().map(|s| s.to_string()).collect();
        expected.extend([".other.ron.d4e5f6.botbench-tmp".into(), "target.ron".into()]);
        expected.sort();
        assert_eq!(names(dir.path()), expected);
        // Once its writer is gone, the next save takes it too. A child process that another
        // test is starting holds a copy of every open descriptor (and so the lock) until it
        // execs: wait for the lock to be free, not for a time.
        drop(holder);
        let give_up = std::time::Instant::now() + std::time::Duration::from_secs(60);
        loop {
            check_destination(&target).unwrap();
            if !live.exists() || std::time::Instant::now() > give_up {
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        assert!(!live.exists());
    }

    #[test]
    fn a_failed_write_leaves_the_file_and_no_temporary_file() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("p.ron");
        std::fs::write(&target, "old").unwrap();
        let e =
            write_atomic_with(&target, |_| Err(std::io::Error::other("disk full"))).unwrap_err();
        assert!(e.to_string().contains("disk full"), "{e}");
        assert_eq!(std::fs::read(&target).unwrap(), b"old");
        assert_eq!(names(dir.path()), ["p.ron"]);
    }

    #[test]
    fn only_regular_files_within_the_limit_are_read() {
        let dir = tempfile::tempdir().unwrap();
        let limit = Limit::new("test file", 100);
        let e = read_bytes(Path::new("/dev/zero"), limit).unwrap_err();
        assert!(e.to_string().contains("character device"), "{e}");
        let e = read_bytes(dir.path(), limit).unwrap_err();
        assert!(
            e.to_string().contains("not a test file file: a folder"),
            "{e}"
        );
        let over = dir.path().join("over");
        std::fs::write(&over, [b'x'; 101]).unwrap();
        let e = read_bytes(&over, limit).unwrap_err();
        assert!(
            e.to_string()
                .contains("the file is 101 bytes; a test file is at most 100 bytes"),
            "{e}"
        );
        let at = dir.path().join("at");
        std::fs::write(&at, [b'x'; 100]).unwrap();
        assert_eq!(read_bytes(&at, limit).unwrap().len(), 100);
        std::fs::write(&at, [b'a', b'\n', 0xff, b'b']).unwrap();
        let e = read_text(&at, limit).unwrap_err();
        assert!(e.to_string().contains("not UTF-8 text: byte 0xff"), "{e}");
        assert_eq!(e.at(), (2, 1));
        #[cfg(unix)]
        {
            let fifo = dir.path().join("fifo");
            let made = std::process::Command::new("mkfifo").arg(&fifo).status();
            if made.is_ok_and(|s| s.success()) {
                // Refused without waiting for a writer.
                let e = read_bytes(&fifo, limit).unwrap_err();
                assert!(e.to_string().contains("named pipe"), "{e}");
            }
        }
        assert_eq!(size_text(3 << 20), "3 MiB");
        assert_eq!(size_text(1536), "1.5 KiB");
    }

    #[test]
    fn a_destination_is_checked_before_the_work() {
        let dir = tempfile::tempdir().unwrap();
        assert!(check_destination(&dir.path().join("new.ron")).is_ok());
        for (path, says) in [
            (dir.path().to_path_buf(), "folder"),
            (
                dir.path().join("no/such/p.ron"),
                "cannot write in the folder",
            ),
            (PathBuf::from("/dev/null"), "character device"),
        ] {
            let e = check_destination(&path).unwrap_err();
            assert!(e.to_string().contains(says), "{}: {e}", path.display());
        }
        assert!(names(dir.path()).is_empty(), "{:?}", names(dir.path()));
    }
}
