//! The USB serial adapter behind a port, as far as the system tells: its driver and, for an
//! FTDI chip, its latency timer (how long it holds received bytes before handing them over: 16 ms
//! by default; the servo vendors tell users to set it to 1 ms). The link folds the latency timer
//! into its automatic margin; the connection bar and `botbench ports` show it and offer to set
//! it where the system lets us.
//!
//! Everything system-specific is in [`platform`]: on Linux the `latency_timer` attribute of the
//! port's USB serial device in sysfs (`/sys/class/tty/<name>/device/latency_timer`, writable by
//! root or a udev rule); elsewhere the answer says what could not be read. The system root is a
//! parameter, so that the reading is tested against a fake tree.

use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// What the system tells of the adapter behind a port.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct Adapter {
    /// The kernel driver (`ftdi_sio`, `ch341-uart`, `cp210x`), where known.
    pub driver: Option<String>,
    /// The latency timer, in ms, where the adapter has one and it could be read.
    pub latency_timer_ms: Option<u32>,
    /// Whether this user may set the latency timer.
    pub latency_timer_writable: bool,
    /// What could not be read, and why (a pseudo-terminal, another system, a driver without a
    /// latency timer, a permission).
    pub note: Option<String>,
}

impl Adapter {
    /// The latency timer, where known.
    pub fn latency_timer(&self) -> Option<Duration> {
        self.latency_timer_ms
            .map(|ms| Duration::from_millis(u64::from(ms)))
    }

    /// One phrase for a port list or the connection bar: `ftdi_sio, latency timer 16 ms
    /// (settable)`, or what could not be read.
    pub fn summary(&self) -> String {
        let mut parts = Vec::new();
        if let Some(d) = &self.driver {
            parts.push(format!("driver {d}"));
        }
        if let Some(ms) = self.latency_timer_ms {
            parts.push(format!(
                "latency timer {ms} ms{}",
                if self.latency_timer_writable {
                    " (settable)"
                } else {
                    ""
                }
            ));
        }
        if let Some(n) = &self.note {
            parts.push(n.clone());
        }
        parts.join(", ")
    }
}

/// Where the system's device tree is (`/sys` on Linux); tests use a fake one.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SysRoot(pub PathBuf);

impl SysRoot {
    /// The running system's.
    pub fn system() -> Self {
        Self(PathBuf::from("/sys"))
    }
}

/// The adapter behind `port` (a path such as `/dev/ttyUSB0` or a `/dev/serial/by-id` link).
pub fn adapter_of(port: &str) -> Adapter {
    platform::read(&SysRoot::system(), Path::new(port))
}

/// Sets the latency timer of the adapter behind `port` to `ms` (1-255), and reads it back.
/// Errors: the system has no latency timer for it, refuses the write (permission), or reads back
/// another value.
pub fn set_latency_timer(port: &str, ms: u32) -> Result<u32, String> {
    platform::set(&SysRoot::system(), Path::new(port), ms)
}

/// The system-specific part.
pub mod platform {
    use super::{Adapter, SysRoot};
    use std::path::Path;

    /// The largest latency timer an FTDI chip takes, ms.
    pub const MAX_LATENCY_TIMER_MS: u32 = 255;

    /// The device name of a port: the file name it resolves to (`ttyUSB0`).
    #[cfg(target_os = "linux")]
    fn tty_name(port: &Path) -> Option<String> {
        let resolved = std::fs::canonicalize(port).unwrap_or_else(|_| port.to_path_buf());
        resolved
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
    }

    /// Reads what the system tells of the adapter behind `port`, under `root`.
    #[cfg(target_os = "linux")]
    pub fn read(root: &SysRoot, port: &Path) -> Adapter {
        let Some(name) = tty_name(port) else {
            return Adapter {
                note: Some(format!("{}: no device name", port.display())),
                ..Adapter::default()
            };
        };
        let device = root.0.join("class/tty").join(&name).join("device");
        if !device.exists() {
            return Adapter {
                note: Some(format!(
                    "no USB serial device for {name} in sysfs (a pseudo-terminal or a built-in port): no latency timer"
                )),
                ..Adapter::default()
            };
        }
        let driver = std::fs::read_link(device.join("driver"))
            .ok()
            .and_then(|d| d.file_name().map(|n| n.to_string_lossy().into_owned()));
        let file = device.join("latency_timer");
        let mut adapter = Adapter {
            driver: driver.clone(),
            ..Adapter::default()
        };
        match std::fs::read_to_string(&file) {
            Ok(text) => match text.trim().parse::<u32>() {
                Ok(ms) => {
                    adapter.latency_timer_ms = Some(ms);
                    adapter.latency_timer_writable =
                        std::fs::OpenOptions::new().write(true).open(&file).is_ok();
                }
                Err(_) => {
                    adapter.note = Some(format!(
                        "{} holds '{}', not a number of ms",
                        file.display(),
                        text.trim()
                    ));
                }
            },
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                let usb = std::fs::canonicalize(&device)
                    .is_ok_and(|d| d.to_string_lossy().contains("/usb"));
                // The driver is already in the summary: the note says what the port is.
                adapter.note = Some(if usb {
                    "USB serial adapter without a latency timer (a small fixed delay)".to_string()
                } else {
                    "built-in serial port (not USB): no latency timer".to_string()
                });
            }
            Err(e) => {
                adapter.note = Some(format!("cannot read {}: {e}", file.display()));
            }
        }
        adapter
    }

    /// Sets the latency timer behind `port`, under `root`, and reads it back.
    #[cfg(target_os = "linux")]
    pub fn set(root: &SysRoot, port: &Path, ms: u32) -> Result<u32, String> {
        if !(1..=MAX_LATENCY_TIMER_MS).contains(&ms) {
            return Err(format!(
                "latency timer {ms} ms is out of range; allowed 1 to {MAX_LATENCY_TIMER_MS} ms"
            ));
        }
        let before = read(root, port);
        if before.latency_timer_ms.is_none() {
            return Err(format!(
                "{}: no latency timer to set ({})",
                port.display(),
                before.note.unwrap_or_default()
            ));
        }
        let name = tty_name(port).unwrap_or_default();
        let file = root
            .0
            .join("class/tty")
            .join(&name)
            .join("device/latency_timer");
        std::fs::write(&file, format!("{ms}\n")).map_err(|e| {
            let hint = if e.kind() == std::io::ErrorKind::PermissionDenied {
                " (writable by root: run `sudo botbench ports --set-latency-timer ...`, or add a udev rule)"
            } else {
                ""
            };
            format!("cannot write {}: {e}{hint}", file.display())
        })?;
        match read(root, port).latency_timer_ms {
            Some(now) if now == ms => Ok(now),
            other => Err(format!(
                "{} reads back {other:?} after writing {ms}",
                file.display()
            )),
        }
    }

    /// Other systems: nothing is read.
    #[cfg(not(target_os = "linux"))]
    pub fn read(_root: &SysRoot, _port: &Path) -> Adapter {
        Adapter {
            note: Some(format!(
                "the latency timer cannot be read on {} (only on Linux): set the margin by hand if answers come late",
                std::env::consts::OS
            )),
            ..Adapter::default()
        }
    }

    /// Other systems: nothing is set.
    #[cfg(not(target_os = "linux"))]
    pub fn set(_root: &SysRoot, port: &Path, _ms: u32) -> Result<u32, String> {
        Err(format!(
            "{}: the latency timer cannot be set from botbench on {} (use the driver's settings)",
            port.display(),
            std::env::consts::OS
        ))
    }
}

#[cfg(test)]
#[cfg(target_os = "linux")]
mod tests {
    use super::platform::{read, set};
    use super::*;

    /// A fake sysfs with one FTDI port (`ttyUSB0`, latency timer 16), one CH340 (`ttyUSB1`, no
    /// latency timer) and nothing for `ttyS0`.
    fn fake() -> tempfile::TempDir {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path();
        let drivers = root.join("bus/usb-serial/drivers");
        for d in ["ftdi_sio", "ch341-uart"] {
            std::fs::create_dir_all(drivers.join(d)).unwrap();
        }
        for (tty, driver, timer) in [
            ("ttyUSB0", "ftdi_sio", Some("16\n")),
            ("ttyUSB1", "ch341-uart", None),
        ] {
            let device = root.join("devices/usb1/1-1:1.0").join(tty);
            std::fs::create_dir_all(&device).unwrap();
            std::os::unix::fs::symlink(drivers.join(driver), device.join("driver")).unwrap();
            if let Some(t) = timer {
                std::fs::write(device.join("latency_timer"), t).unwrap();
            }
            let class = root.join("class/tty").join(tty);
            std::fs::create_dir_all(&class).unwrap();
            std::os::unix::fs::symlink(&device, class.join("device")).unwrap();
        }
        dir
    }

    #[test]
    fn reads_an_ftdi_latency_timer_and_says_what_others_lack() {
        let dir = fake();
        let root = SysRoot(dir.path().to_path_buf());
        let ftdi = read(&root, Path::new("/dev/ttyUSB0"));
        assert_eq!(ftdi.driver.as_deref(), Some("ftdi_sio"));
        assert_eq!(ftdi.latency_timer(), Some(Duration::from_millis(16)));
        assert!(ftdi.latency_timer_writable, "{ftdi:?}");
        assert!(ftdi.summary().contains("latency timer 16 ms"), "{ftdi:?}");
        let ch340 = read(&root, Path::new("/dev/ttyUSB1"));
        assert_eq!(ch340.driver.as_deref(), Some("ch341-uart"));
        assert_eq!(ch340.latency_timer_ms, None);
        assert!(
            ch340
                .note
                .as_deref()
                .unwrap_or("")
                .contains("USB serial adapter without a latency timer"),
            "{ch340:?}"
        );
        assert!(
            ch340.summary().starts_with("driver ch341-uart, "),
            "{}",
            ch340.summary()
        );
        let pty = read(&root, Path::new("/dev/pts/7"));
        assert_eq!(pty.latency_timer_ms, None);
        assert!(
            pty.note
                .as_deref()
                .unwrap_or("")
                .contains("pseudo-terminal"),
            "{pty:?}"
        );
    }

    #[test]
    fn sets_the_latency_timer_and_refuses_what_it_cannot() {
        let dir = fake();
        let root = SysRoot(dir.path().to_path_buf());
        assert_eq!(set(&root, Path::new("/dev/ttyUSB0"), 1), Ok(1));
        assert_eq!(
            read(&root, Path::new("/dev/ttyUSB0")).latency_timer_ms,
            Some(1)
        );
        let e = set(&root, Path::new("/dev/ttyUSB0"), 0).unwrap_err();
        assert!(e.contains("out of range"), "{e}");
        let e = set(&root, Path::new("/dev/ttyUSB1"), 1).unwrap_err();
        assert!(e.contains("no latency timer"), "{e}");
        // A file this user may not write (root's, in the field).
        let file = dir
            .path()
            .join("devices/usb1/1-1:1.0/ttyUSB0/latency_timer");
        let mut perms = std::fs::metadata(&file).unwrap().permissions();
        std::os::unix::fs::PermissionsExt::set_mode(&mut perms, 0o444);
        std::fs::set_permissions(&file, perms).unwrap();
        let ro = read(&root, Path::new("/dev/ttyUSB0"));
        // Root may write anyway; anyone else is told it is not settable.
        if std::fs::OpenOptions::new().write(true).open(&file).is_err() {
            assert!(!ro.latency_timer_writable);
            let e = set(&root, Path::new("/dev/ttyUSB0"), 1).unwrap_err();
            assert!(e.contains("cannot write"), "{e}");
        }
    }
}
