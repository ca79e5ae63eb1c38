//! The serial ports the OS lists (each with the USB adapter behind it, [`super::adapter`]), and
//! why a port cannot be opened, in words that say the fix: the group to join, the program
//! holding it (a `/proc/*/fd` scan).

use serialport::SerialPortType;

/// A port as the OS lists it.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct PortInfo {
    /// The path to open.
    pub path: String,
    /// `usb`, `pci`, `bluetooth` or `unknown`.
    pub kind: &'static str,
    /// USB vendor id.
    pub vid: Option<u16>,
    /// USB product id.
    pub pid: Option<u16>,
    /// USB serial number, where the OS gives one.
    pub serial_number: Option<String>,
    /// USB manufacturer.
    pub manufacturer: Option<String>,
    /// USB product name.
    pub product: Option<String>,
    /// The adapter's driver and latency timer, as the system tells ([`super::adapter`]).
    pub adapter: super::adapter::Adapter,
}

impl PortInfo {
    /// One line for a picker: `/dev/ttyUSB0  USB 1a86:7523 CH340 (sn 1234)`.
    pub fn label(&self) -> String {
        let mut s = self.path.clone();
        if let (Some(v), Some(p)) = (self.vid, self.pid) {
            s.push_str(&format!("  USB {v:04x}:{p:04x}"));
        }
        if let Some(prod) = &self.product {
            s.push_str(&format!(" {prod}"));
        }
        if let Some(sn) = &self.serial_number {
            s.push_str(&format!(" (sn {sn})"));
        }
        let adapter = self.adapter.summary();
        if !adapter.is_empty() {
            s.push_str(&format!("  [{adapter}]"));
        }
        s
    }
}

/// The serial ports the OS knows of (on Linux, without libudev, this reads sysfs; pseudo-terminals
/// are not listed but can be opened by path).
pub fn list_ports() -> Vec<PortInfo> {
    let Ok(ports) = serialport::available_ports() else {
        return Vec::new();
    };
    ports
        .into_iter()
        .map(|p| {
            let mut info = PortInfo {
                adapter: super::adapter::adapter_of(&p.port_name),
                path: p.port_name,
                kind: "unknown",
                vid: None,
                pid: None,
                serial_number: None,
                manufacturer: None,
                product: None,
            };
            match p.port_type {
                SerialPortType::UsbPort(u) => {
                    info.kind = "usb";
                    info.vid = Some(u.vid);
                    info.pid = Some(u.pid);
                    info.serial_number = u.serial_number;
                    info.manufacturer = u.manufacturer;
                    info.product = u.product;
                }
                SerialPortType::PciPort => info.kind = "pci",
                SerialPortType::BluetoothPort => info.kind = "bluetooth",
                SerialPortType::Unknown => {}
            }
            info
        })
        .collect()
}

/// Why `path` could not be opened, in words that say the fix: for lack of permission, the group
/// that owns the device and how to join it; for a busy port, which program holds it where this
/// user can see it (brltty and ModemManager by name, with their own fix). `error` is what the
/// serialport crate said.
pub fn open_failure(path: &str, error: &serialport::Error) -> String {
    use serialport::ErrorKind as K;
    let text = error.to_string();
    if !std::path::Path::new(path).exists() {
        return missing_port(path, &text);
    }
    match error.kind {
        K::Io(std::io::ErrorKind::PermissionDenied) => permission_denied(path),
        // serialport reports EBUSY (another opener set TIOCEXCL) and a held flock as NoDevice.
        K::NoDevice if text.contains("busy") || text.contains("lock") => busy(path),
        K::NoDevice => format!("no such device ({text})"),
        _ if text.contains("Not a typewriter") => {
            "not a serial port (not a terminal device)".to_string()
        }
        _ => text,
    }
}

/// Why a port whose path does not exist cannot open (`text`: what the OS said): not plugged
/// in or under another name, with the USB serial ports listed now.
pub fn missing_port(path: &str, text: &str) -> String {
    not_there(path, text, &list_ports())
}

/// [`missing_port`] with the USB serial ports listed now (`ports`), where the adapter may be
/// under another name.
fn not_there(path: &str, text: &str, ports: &[PortInfo]) -> String {
    let usb: Vec<&str> = ports
        .iter()
        .filter(|p| p.kind == "usb" && p.path != path)
        .map(|p| p.path.as_str())
        .collect();
    let listed = if usb.is_empty() {
        "no USB serial port is listed now: plug the adapter in".to_string()
    } else {
        format!("the USB serial ports listed now: {}", usb.join(", "))
    };
    format!(
        "{text}: no such port (not plugged in, or plugged in under another name); {listed} \
         (`botbench ports` lists every port)"
    )
}

/// The likely cause, in words that say what to do, of a port at `path` that went away while
/// open: renamed after a replug (the adapter whose USB serial number was `usb_serial` is listed
/// at another path now), taken by brltty (the braille daemon runs, or holds the port), or
/// unplugged (with the USB serial ports listed now, where another name may be the same
/// adapter back). `None` while `path` is still there and no brltty holds it.
pub fn vanished(path: &str, usb_serial: Option<&str>) -> Option<String> {
    if std::path::Path::new(path).exists() {
        return vanish_cause(path, Some(&holders(path)), &[], usb_serial, None);
    }
    let brltty = process_named("brltty");
    vanish_cause(path, None, &list_ports(), usb_serial, brltty)
}

/// [`vanished`] from what was seen: `holders` of the port while it is still there (`None`: it
/// is gone), the `ports` listed now, and the pid of a running brltty.
fn vanish_cause(
    path: &str,
    holders: Option<&[Holder]>,
    ports: &[PortInfo],
    usb_serial: Option<&str>,
    brltty_pid: Option<u32>,
) -> Option<String> {
    let brltty = |pid: u32| {
        format!(
            "taken by brltty (pid {pid}), the braille display daemon, which claims CH340/CH341 \
             adapters on Ubuntu; without a braille display, remove it: sudo apt remove brltty"
        )
    };
    if let Some(holders) = holders {
        return holders
            .iter()
            .find(|h| h.name == "brltty")
            .map(|h| brltty(h.pid));
    }
    if let Some(sn) = usb_serial
        && let Some(now) = ports
            .iter()
            .find(|p| p.serial_number.as_deref() == Some(sn) && p.path != path)
    {
        return Some(format!(
            "renamed after a replug: the same adapter (USB serial {sn}) is now {}; connect to \
             that port",
            now.path
        ));
    }
    if let Some(pid) = brltty_pid {
        return Some(brltty(pid));
    }
    let usb: Vec<&str> = ports
        .iter()
        .filter(|p| p.kind == "usb")
        .map(|p| p.path.as_str())
        .collect();
    Some(if usb.is_empty() {
        format!("{path} is gone: unplugged (no USB serial port is listed now); plug it in again")
    } else {
        format!(
            "{path} is gone: unplugged, or plugged in again under another name (listed now: {})",
            usb.join(", ")
        )
    })
}

#[cfg(test)]
mod not_there_tests {
    use super::*;

    #[test]
    fn a_port_that_is_not_there_says_so_and_lists_the_usb_ports_there_are() {
        let os = "No such file or directory (os error 2)";
        let none = not_there("/dev/ttyUSB0", os, &[]);
        assert!(none.starts_with(os), "{none}");
        assert!(
            none.contains("no such port (not plugged in, or plugged in under another name)")
                && none.contains("no USB serial port is listed now: plug the adapter in"),
            "{none}"
        );
        let usb = PortInfo {
            path: "/dev/ttyUSB1".into(),
            kind: "usb",
            vid: None,
            pid: None,
            serial_number: None,
            manufacturer: None,
            product: None,
            adapter: Default::default(),
        };
        let other = not_there("/dev/ttyUSB0", os, &[usb]);
        assert!(
            other.contains("the USB serial ports listed now: /dev/ttyUSB1"),
            "{other}"
        );
    }
}

/// Every kind of cause [`vanished`] gives for a lost `path`, for the tests of the texts made of
/// them (the window's Chinese): renamed, taken by brltty while there, taken by a running
/// brltty, unplugged with other ports listed, unplugged with none.
#[cfg(test)]
pub(crate) fn every_vanish_cause(path: &str) -> Vec<String> {
    let usb = |p: &str, sn: &str| PortInfo {
        path: p.into(),
        kind: "usb",
        vid: None,
        pid: None,
        serial_number: Some(sn.into()),
        manufacturer: None,
        product: None,
        adapter: super::adapter::Adapter::default(),
    };
    let now = [usb("/dev/ttyUSB1", "A1"), usb("/dev/ttyUSB2", "C3")];
    let held = [Holder {
        pid: 4,
        name: "brltty".into(),
    }];
    [
        vanish_cause(path, None, &now, Some("A1"), None),
        vanish_cause(path, Some(&held), &[], None, None),
        vanish_cause(path, None, &now, None, Some(9)),
        vanish_cause(path, None, &now, Some("B2"), None),
        vanish_cause(path, None, &[], None, None),
    ]
    .into_iter()
    .flatten()
    .collect()
}

/// The id of a running process whose command name is `name` (`/proc/PID/comm`), if any.
fn process_named(name: &str) -> Option<u32> {
    let procs = std::fs::read_dir("/proc").ok()?;
    procs.flatten().find_map(|entry| {
        let pid = entry.file_name().to_str()?.parse::<u32>().ok()?;
        let comm = std::fs::read_to_string(entry.path().join("comm")).ok()?;
        (comm.trim() == name).then_some(pid)
    })
}

/// A process that has a device open.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Holder {
    /// Its process id.
    pub pid: u32,
    /// Its command name (`/proc/PID/comm`: at most 15 bytes).
    pub name: String,
}

impl Holder {
    /// `holders` as words: `cat (pid 4711), ModemManager (pid 812)`.
    pub fn list(holders: &[Holder]) -> String {
        holders
            .iter()
            .map(|h| format!("{} (pid {})", h.name, h.pid))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// The other processes that have `path` open, among those this user may look into (all of them
/// for root). Linux: a scan of `/proc/*/fd`; elsewhere nothing is found.
pub fn holders(path: &str) -> Vec<Holder> {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::fs::MetadataExt;
        let Ok(target) = std::fs::canonicalize(path) else {
            return Vec::new();
        };
        // The same node, not only the same name: a pseudo-terminal's name is given again once it
        // is closed, and a process may still hold the old one.
        let Ok(node) = std::fs::metadata(&target).map(|m| (m.dev(), m.ino())) else {
            return Vec::new();
        };
        let me = std::process::id();
        let Ok(procs) = std::fs::read_dir("/proc") else {
            return Vec::new();
        };
        let mut found = Vec::new();
        for entry in procs.flatten() {
            let Some(pid) = entry
                .file_name()
                .to_str()
                .and_then(|s| s.parse::<u32>().ok())
            else {
                continue;
            };
            if pid == me {
                continue;
            }
            let Ok(fds) = std::fs::read_dir(entry.path().join("fd")) else {
                continue;
            };
            let holds = fds.flatten().any(|fd| {
                std::fs::read_link(fd.path()).is_ok_and(|l| l == target)
                    && std::fs::metadata(fd.path()).is_ok_and(|m| (m.dev(), m.ino()) == node)
            });
            if holds {
                let name = std::fs::read_to_string(entry.path().join("comm"))
                    .map(|s| s.trim().to_string())
                    .unwrap_or_else(|_| "?".into());
                found.push(Holder { pid, name });
            }
        }
        found.sort_by_key(|h| h.pid);
        found
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = path;
        Vec::new()
    }
}

/// The other processes that may read `path`'s bytes: [`holders`], except, for a pseudo-terminal,
/// the program that serves its other side (it holds the pty's master, whose
/// `/proc/PID/fdinfo` names the pty by `tty-index`; a simulator also keeps the pty's own side
/// open, and in lockstep reads it only to check the bytes that crossed) and the children that inherited it from that program.
pub fn other_readers(path: &str) -> Vec<Holder> {
    let found = holders(path);
    if found.is_empty() {
        return found;
    }
    let index = std::fs::canonicalize(path).ok().and_then(|p| {
        p.strip_prefix("/dev/pts")
            .ok()
            .and_then(|n| n.to_str()?.parse::<u32>().ok())
    });
    match index {
        // A child of the serving program holds the pty only as inherited from it (it opened
        // both sides without close-on-exec): not a reader either.
        Some(index) => found
            .into_iter()
            .filter(|h| {
                !serves_pty(h.pid, index) && !parent_of(h.pid).is_some_and(|p| serves_pty(p, index))
            })
            .collect(),
        None => found,
    }
}

/// The parent of process `pid` (`/proc/PID/stat`, the field after the command's closing
/// parenthesis and state).
fn parent_of(pid: u32) -> Option<u32> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let after = &stat[stat.rfind(')')? + 1..];
    after.split_whitespace().nth(1)?.parse().ok()
}

/// Whether process `pid` holds the master side of pseudo-terminal `index` (`/dev/pts/INDEX`).
fn serves_pty(pid: u32, index: u32) -> bool {
    let Ok(fds) = std::fs::read_dir(format!("/proc/{pid}/fd")) else {
        return false;
    };
    let want = format!("tty-index:\t{index}");
    fds.flatten().any(|fd| {
        let is_master = std::fs::read_link(fd.path())
            .is_ok_and(|l| l.ends_with("ptmx") || l == std::path::Path::new("/dev/pts/ptmx"));
        is_master
            && std::fs::read_to_string(format!(
                "/proc/{pid}/fdinfo/{}",
                fd.file_name().to_string_lossy()
            ))
            .is_ok_and(|info| info.lines().any(|l| l.trim_end() == want))
    })
}

/// The message for a busy port.
fn busy(path: &str) -> String {
    let holders = holders(path);
    if holders.is_empty() {
        return format!(
            "busy: another program has it open (not one this user can see; \
             `sudo fuser -v {path}` names it)"
        );
    }
    let mut s = String::from("busy: another program has it open:");
    for h in &holders {
        s.push_str(&format!("\n  {} (pid {})", h.name, h.pid));
        match h.name.as_str() {
            "brltty" => s.push_str(
                " — the braille display daemon, which claims CH340/CH341 adapters on Ubuntu; \
                 without a braille display, remove it: sudo apt remove brltty",
            ),
            "ModemManager" => s.push_str(
                " — it probes a new USB modem-like port for a few seconds after it appears: \
                 try again in a moment, or stop it: sudo systemctl stop ModemManager",
            ),
            _ => s.push_str(" — close it, then try again"),
        }
    }
    s
}

/// The message for a port this user may not open.
#[cfg(target_os = "linux")]
fn permission_denied(path: &str) -> String {
    use std::os::unix::fs::{MetadataExt, PermissionsExt};
    let Ok(meta) = std::fs::metadata(path) else {
        return "permission denied".into();
    };
    let groups = read_table("/etc/group");
    let group = groups
        .iter()
        .find(|g| g.get(2).and_then(|id| id.parse::<u32>().ok()) == Some(meta.gid()))
        .and_then(|g| g.first().cloned())
        .unwrap_or_else(|| meta.gid().to_string());
    let user = user_name();
    let listed = groups.iter().any(|g| {
        g.first() == Some(&group)
            && g.get(3)
                .is_some_and(|m| m.split(',').any(|u| u.trim() == user))
    });
    let access = Access {
        group,
        mode: meta.permissions().mode() & 0o7777,
        user,
        listed,
        in_session: session_gids().contains(&meta.gid()),
    };
    access.message(path)
}

/// Who may open a device, and who is asking.
#[cfg(target_os = "linux")]
#[derive(Debug, Clone)]
struct Access {
    /// The group that owns the device node.
    group: String,
    /// The node's permission bits.
    mode: u32,
    /// This process's user.
    user: String,
    /// The user is a member of `group` in /etc/group.
    listed: bool,
    /// This process runs with `group` (a login since the user was added).
    in_session: bool,
}

#[cfg(target_os = "linux")]
impl Access {
    /// Why `path` was refused, and the fix.
    fn message(&self, path: &str) -> String {
        let Access {
            group, mode, user, ..
        } = self;
        let head = format!("permission denied: {path} belongs to group '{group}' (mode {mode:o})");
        if mode & 0o060 != 0o060 {
            format!(
                "{head}, whose members may not read and write it: a udev rule giving it to group \
                 dialout with MODE=\"0660\" fixes that"
            )
        } else if self.listed && !self.in_session {
            format!(
                "{head}; user '{user}' was added to '{group}' after this login started: log out \
                 and back in (or run `newgrp {group}` in this terminal)"
            )
        } else {
            format!(
                "{head} and user '{user}' is not in it: run `sudo usermod -aG {group} {user}`, \
                 then log out and back in (a new login picks up the group)"
            )
        }
    }
}

/// The message for a port this user may not open.
#[cfg(not(target_os = "linux"))]
fn permission_denied(_path: &str) -> String {
    "permission denied (on Windows another program may hold the port)".into()
}

/// The lines of a colon-separated table (`/etc/group`, `/etc/passwd`), split.
#[cfg(target_os = "linux")]
fn read_table(path: &str) -> Vec<Vec<String>> {
    std::fs::read_to_string(path)
        .unwrap_or_default()
        .lines()
        .map(|l| l.split(':').map(str::to_string).collect())
        .collect()
}

/// A field of `/proc/self/status` (`Uid`, `Groups`…), split on whitespace.
#[cfg(target_os = "linux")]
fn self_status(key: &str) -> Vec<u32> {
    std::fs::read_to_string("/proc/self/status")
        .unwrap_or_default()
        .lines()
        .find_map(|l| l.strip_prefix(key)?.strip_prefix(':').map(str::to_string))
        .map(|v| {
            v.split_whitespace()
                .filter_map(|n| n.parse().ok())
                .collect()
        })
        .unwrap_or_default()
}

/// The groups this process runs with: its effective group and its supplementary groups.
#[cfg(target_os = "linux")]
fn session_gids() -> Vec<u32> {
    let mut gids = self_status("Groups");
    gids.extend(self_status("Gid").get(1));
    gids
}

/// This process's user name (its effective uid in /etc/passwd, else `$USER`).
#[cfg(target_os = "linux")]
fn user_name() -> String {
    let uid = self_status("Uid").get(1).copied();
    read_table("/etc/passwd")
        .into_iter()
        .find(|u| u.get(2).and_then(|id| id.parse().ok()) == uid)
        .and_then(|u| u.into_iter().next())
        .or_else(|| std::env::var("USER").ok())
        .unwrap_or_else(|| "$USER".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn usb(path: &str, sn: &str) -> PortInfo {
        PortInfo {
            path: path.into(),
            kind: "usb",
            vid: Some(0x1a86),
            pid: Some(0x7523),
            serial_number: Some(sn.into()),
            manufacturer: None,
            product: None,
            adapter: super::super::adapter::Adapter::default(),
        }
    }

    #[test]
    fn a_vanished_port_says_renamed_brltty_or_unplugged() {
        let now = [usb("/dev/ttyUSB1", "A1")];
        let c = |ports: &[PortInfo], sn: Option<&str>, brltty: Option<u32>| {
            vanish_cause("/dev/ttyUSB0", None, ports, sn, brltty).unwrap_or_default()
        };
        let renamed = c(&now, Some("A1"), Some(9));
        assert!(renamed.starts_with("renamed after a replug"), "{renamed}");
        assert!(renamed.contains("is now /dev/ttyUSB1"), "{renamed}");
        let taken = c(&now, Some("B2"), Some(9));
        assert!(taken.starts_with("taken by brltty (pid 9)"), "{taken}");
        let other = c(&now, Some("B2"), None);
        assert!(
            other.contains("/dev/ttyUSB0 is gone: unplugged, or plugged in again under another name (listed now: /dev/ttyUSB1)"),
            "{other}"
        );
        let none = c(&[], None, None);
        assert!(
            none.contains("unplugged (no USB serial port is listed now)"),
            "{none}"
        );
        let held = [Holder {
            pid: 4,
            name: "brltty".into(),
        }];
        let here = vanish_cause("/dev/ttyUSB0", Some(&held), &[], None, None);
        assert!(here.is_some_and(|m| m.starts_with("taken by brltty (pid 4)")));
        assert_eq!(
            vanish_cause("/dev/ttyUSB0", Some(&[]), &now, None, None),
            None
        );
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn a_refused_port_says_which_group_to_join_or_to_log_in_again() {
        let mut a = Access {
            group: "dialout".into(),
            mode: 0o660,
            user: "ana".into(),
            listed: false,
            in_session: false,
        };
        let m = a.message("/dev/ttyUSB0");
        assert!(
            m.starts_with("permission denied: /dev/ttyUSB0 belongs to group 'dialout' (mode 660)"),
            "{m}"
        );
        assert!(m.contains("sudo usermod -aG dialout ana"), "{m}");
        assert!(m.contains("log out and back in"), "{m}");
        // Added to the group, but this login is older.
        a.listed = true;
        let m = a.message("/dev/ttyUSB0");
        assert!(m.contains("was added to 'dialout' after this login"), "{m}");
        assert!(m.contains("newgrp dialout"), "{m}");
        assert!(!m.contains("usermod"), "{m}");
        // A node its group may not open: joining the group would not help.
        a.mode = 0o600;
        let m = a.message("/dev/ttyUSB0");
        assert!(m.contains("udev rule"), "{m}");
        assert!(!m.contains("usermod"), "{m}");
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn holders_names_the_other_processes_that_have_a_port_open() {
        use serialport::SerialPort;
        let (master, slave) = serialport::TTYPort::pair().unwrap();
        let path = slave.name().unwrap();
        drop(slave);
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(&path)
            .unwrap();
        // This process is not its own holder.
        let me = std::process::id();
        assert!(holders(&path).iter().all(|h| h.pid != me));
        let mut child = std::process::Command::new("sleep")
            .arg("60")
            .stdin(file)
            .spawn()
            .unwrap();
        // Until it has become `sleep`, the child is a copy of this test.
        let comm = format!("/proc/{}/comm", child.id());
        for _ in 0..1000 {
            if std::fs::read_to_string(&comm).is_ok_and(|c| c.trim() == "sleep") {
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
        let found = holders(&path);
        let _ = child.kill();
        let _ = child.wait();
        drop(master);
        let sleep = Holder {
            pid: child.id(),
            name: "sleep".into(),
        };
        assert!(found.contains(&sleep), "{found:?}");
    }
}
