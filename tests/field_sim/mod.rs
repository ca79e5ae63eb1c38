//! `botbench sim` and the command line as separate processes, for the field tests: a simulator
//! that misbehaves as real adapters, buses and firmware do, and a command run against it that
//! must end (a watchdog fails the test instead of hanging; it never decides a verdict).
#![allow(dead_code)] // each test binary uses its own part

use std::io::{BufRead, Read};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

/// How long a command may run before the test fails instead of hanging: generous, since a
/// loaded machine is slow, and a command that ends returns at once.
pub const WATCHDOG: Duration = Duration::from_secs(120);

/// The binary under test.
pub fn exe() -> &'static str {
    env!("CARGO_BIN_EXE_botbench")
}

/// A simulator process serving a pseudo-terminal.
pub struct Sim {
    child: Child,
    /// The pty's path.
    pub path: String,
}

impl Sim {
    /// Starts `botbench sim ARGS...` and reads the pty's path from its first line.
    pub fn start(args: &[&str]) -> Sim {
        let mut child = Command::new(exe())
            .arg("sim")
            .args(args)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("the simulator starts");
        let mut path = String::new();
        std::io::BufReader::new(child.stdout.take().expect("stdout"))
            .read_line(&mut path)
            .expect("the simulator prints its path");
        assert!(
            path.starts_with("/dev/"),
            "no pty path from sim {args:?}: {path:?}"
        );
        Sim {
            child,
            path: path.trim().to_string(),
        }
    }

    /// Waits for the simulator to end on its own (a vanished port), within the watchdog.
    pub fn wait(&mut self) -> ExitStatus {
        let deadline = Instant::now() + WATCHDOG;
        loop {
            if let Some(s) = self.child.try_wait().expect("wait") {
                return s;
            }
            assert!(Instant::now() < deadline, "the simulator did not end");
            std::thread::sleep(Duration::from_millis(10));
        }
    }
}

impl Drop for Sim {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// What a command did.
#[derive(Debug)]
pub struct Run {
    /// Its exit code (`None`: killed by a signal).
    pub code: Option<i32>,
    /// Its standard output.
    pub stdout: String,
    /// Its standard error.
    pub stderr: String,
}

impl Run {
    /// Both outputs, for assertion messages.
    pub fn text(&self) -> String {
        format!(
            "exit {:?}\n--- stdout\n{}--- stderr\n{}",
            self.code, self.stdout, self.stderr
        )
    }

    /// The standard output's lines parsed as JSON documents.
    pub fn json(&self) -> Vec<serde_json::Value> {
        self.stdout
            .lines()
            .filter(|l| l.trim_start().starts_with('{'))
            .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
            .collect()
    }
}

/// Runs `botbench ARGS...` to its end; fails the test if it has not ended within the watchdog.
pub fn botbench(args: &[&str]) -> Run {
    let mut child = Command::new(exe())
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("botbench starts");
    let mut out = child.stdout.take().expect("stdout");
    let mut err = child.stderr.take().expect("stderr");
    let t_out = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = out.read_to_string(&mut s);
        s
    });
    let t_err = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = err.read_to_string(&mut s);
        s
    });
    let deadline = Instant::now() + WATCHDOG;
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait") {
            break s;
        }
        if Instant::now() >= deadline {
            let _ = child.kill();
            let _ = child.wait();
            panic!(
                "botbench {args:?} did not end within {WATCHDOG:?}; stdout so far: {}",
                t_out.join().unwrap_or_default()
            );
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    Run {
        code: status.code(),
        stdout: t_out.join().unwrap_or_default(),
        stderr: t_err.join().unwrap_or_default(),
    }
}
