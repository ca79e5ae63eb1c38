//! botbench on a line PC (issue 18): the build it names, the shipped examples found from an
//! installed layout, and the messages for a port this user may not open or another program holds,
//! through pseudo-terminals and the real binary.

use serialport::SerialPort;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::support::cli::{Ran, botbench, output, watched};
use crate::support::{temp_dir, wait_until};

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_botbench")
}

fn stderr(out: &Ran) -> String {
    out.err.clone()
}

#[test]
fn version_names_the_version_and_the_commit() {
    let out = output(&mut botbench(["--version"]));
    assert_eq!(out.code, 0, "{}", out.text());
    let line = out.out;
    let want = format!("botbench {} (", env!("CARGO_PKG_VERSION"));
    assert!(line.starts_with(&want), "{line}");
    let commit = line.trim().strip_prefix(&want).unwrap().strip_suffix(')');
    let commit = commit.unwrap_or_else(|| panic!("{line}"));
    // Built in a git checkout (as here and in CI): the commit of HEAD.
    let head = Command::new("git")
        .args(["rev-parse", "--short=9", "HEAD"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output();
    match head {
        Ok(h) if h.status.success() => {
            assert_eq!(commit, String::from_utf8(h.stdout).unwrap().trim())
        }
        _ => assert_eq!(commit, "unknown"),
    }
}

/// `PREFIX/bin/botbench` (a hard link to, or a copy of, this build) and
/// `PREFIX/share/botbench/presets`, as the Debian package lays them out under /usr.
fn installed_layout(prefix: &Path) -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    std::fs::create_dir_all(prefix.join("bin")).unwrap();
    let presets = prefix.join("share/botbench/presets");
    std::fs::create_dir_all(&presets).unwrap();
    for e in std::fs::read_dir(root.join("presets")).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), presets.join(e.file_name())).unwrap();
    }
    let exe = prefix.join("bin/botbench");
    if std::fs::hard_link(bin(), &exe).is_err() {
        std::fs::copy(bin(), &exe).unwrap();
    }
    exe
}

#[test]
fn an_installed_binary_reads_the_shipped_plans_from_any_folder() {
    let tmp = temp_dir();
    let exe = installed_layout(&tmp.path().join("usr"));
    let elsewhere = tmp.path().join("home");
    std::fs::create_dir_all(&elsewhere).unwrap();
    let run = |plan: &str| {
        watched(
            Command::new(&exe)
                .args([
                    "msp",
                    "--port",
                    "/dev/botbench-no-such-port",
                    "selftest",
                    plan,
                ])
                .current_dir(&elsewhere)
                .env_remove("BOTBENCH_DATA_DIR")
                .stdin(std::process::Stdio::null()),
            "the installed botbench",
        )
    };
    // The plan is read and checked (from PREFIX/share/botbench), then the port is opened.
    let out = run("presets/window-cleaner-selftest.ron");
    let err = stderr(&out);
    assert!(err.contains("/dev/botbench-no-such-port"), "{err}");
    assert!(!err.contains("selftest.ron"), "{err}");
    // A plan that is neither here nor shipped is refused by the name given.
    let out = run("presets/no-such-plan.ron");
    assert_eq!(out.code, 2, "{}", out.text());
    let err = stderr(&out);
    assert!(err.contains("presets/no-such-plan.ron"), "{err}");
    assert!(!err.contains("/dev/botbench-no-such-port"), "{err}");
}

/// A pseudo-terminal's device path, and the master that keeps it alive.
fn pty() -> (serialport::TTYPort, String) {
    let (master, slave) = serialport::TTYPort::pair().unwrap();
    let path = slave.name().unwrap();
    drop(slave);
    (master, path)
}

fn is_root() -> bool {
    std::fs::read_to_string("/proc/self/status")
        .unwrap_or_default()
        .lines()
        .find_map(|l| l.strip_prefix("Uid:"))
        .and_then(|v| v.split_whitespace().nth(1).map(|u| u == "0"))
        .unwrap_or(false)
}

/// This build run as the unprivileged user `nobody` (CI runs as root), through setpriv or
/// runuser, from a folder `nobody` may enter (`dir`: a checkout under /root is not one).
fn as_nobody(dir: &Path, args: &[&str]) -> Option<Command> {
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(dir, std::fs::Permissions::from_mode(0o755)).unwrap();
    let exe = dir.join("botbench");
    if std::fs::hard_link(bin(), &exe).is_err() {
        std::fs::copy(bin(), &exe).unwrap();
    }
    let exe = exe.to_str().unwrap();
    let has = |tool: &str| {
        Command::new(tool)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success())
    };
    if has("setpriv") {
        let mut c = Command::new("setpriv");
        c.args([
            "--reuid=nobody",
            "--regid=nogroup",
            "--clear-groups",
            "--",
            exe,
        ]);
        c.args(args);
        Some(c)
    } else if has("runuser") {
        let mut c = Command::new("runuser");
        c.args(["-u", "nobody", "--", exe]);
        c.args(args);
        Some(c)
    } else {
        None
    }
}

#[test]
fn a_port_this_user_may_not_open_says_which_group_to_join() {
    let (_master, path) = pty();
    let out = if is_root() {
        // Root opens anything: as `nobody`, a port of group dialout, mode 660, as a USB adapter's.
        let chown = Command::new("chown")
            .args(["root:dialout", &path])
            .status()
            .unwrap();
        assert!(chown.success());
        let chmod = Command::new("chmod").args(["660", &path]).status().unwrap();
        assert!(chmod.success());
        let dir = temp_dir();
        let Some(mut cmd) = as_nobody(dir.path(), &["msp", "--port", &path, "version"]) else {
            eprintln!("SKIPPED: neither setpriv nor runuser is installed to run as nobody");
            return;
        };
        cmd.env("HOME", "/tmp")
            .env(botbench::profile::registry::DIR_ENV, "/nonexistent")
            .stdin(std::process::Stdio::null());
        watched(&mut cmd, "botbench as nobody")
    } else {
        // Another user: a mode that forbids even the owner.
        let chmod = Command::new("chmod").args(["000", &path]).status().unwrap();
        assert!(chmod.success());
        output(&mut botbench(["msp", "--port", &path, "version"]))
    };
    // A port that cannot be opened is bad input to the command line: exit 2.
    assert_eq!(out.code, 2, "{}", out.text());
    let err = stderr(&out);
    assert!(err.contains(&format!("cannot open {path}")), "{err}");
    assert!(err.contains("permission denied"), "{err}");
    if is_root() {
        assert!(
            err.contains("belongs to group 'dialout' (mode 660)"),
            "{err}"
        );
        assert!(err.contains("sudo usermod -aG dialout nobody"), "{err}");
        assert!(err.contains("log out and back in"), "{err}");
    } else {
        assert!(err.contains("(mode 0)"), "{err}");
        assert!(err.contains("udev rule"), "{err}");
    }
}

#[test]
fn a_busy_port_says_so_and_names_what_holds_it() {
    let (_master, path) = pty();
    // This test holds the port exclusively (TIOCEXCL and flock, as botbench itself does)…
    let held = serialport::new(&path, 115_200).open().unwrap();
    // …and a program named brltty has it open too, as the braille daemon does to a CH340.
    let tmp = temp_dir();
    let brltty = tmp.path().join("brltty");
    // A link, not a copy: a copy's file is open for writing until closed, and a process another
    // test forks meanwhile holds it open too, so exec'ing it failed now and then with "Text file
    // busy" (ETXTBSY). The process's name is the link's (the kernel names it by the path given).
    std::os::unix::fs::symlink("/bin/sleep", &brltty).unwrap();
    let port_file = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(&path)
        .unwrap();
    let mut daemon = Command::new(&brltty)
        .arg("60")
        .stdin(port_file)
        .spawn()
        .unwrap();
    // It is brltty once it has exec'd (before, it is a copy of this test).
    let comm = format!("/proc/{}/comm", daemon.id());
    wait_until("the stand-in brltty to run", || {
        std::fs::read_to_string(&comm).is_ok_and(|c| c.trim() == "brltty")
    });
    let out = output(&mut botbench(["msp", "--port", &path, "version"]));
    let _ = daemon.kill();
    let _ = daemon.wait();
    drop(held);
    // A port that cannot be opened is bad input to the command line: exit 2.
    assert_eq!(out.code, 2, "{}", out.text());
    let err = stderr(&out);
    assert!(err.contains(&format!("cannot open {path}: busy")), "{err}");
    assert!(
        err.contains(&format!("(pid {})", std::process::id())),
        "{err}"
    );
    assert!(
        err.contains(&format!("brltty (pid {})", daemon.id())),
        "{err}"
    );
    assert!(err.contains("sudo apt remove brltty"), "{err}");
}
