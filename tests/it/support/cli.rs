//! The command line as a user runs it: the `botbench` binary in a child process, with no user
//! profiles, and `botbench sim` serving a device on a pseudo-terminal.

use std::io::{BufRead, BufReader, Lines, Write};
use std::path::PathBuf;
use std::process::{ChildStderr, Command, Stdio};

/// The answer margin the tests give a device across processes, as `--margin-ms`. The simulator
/// runs in another process, which nothing keeps in lockstep with the command: on a loaded
/// 2-core machine its thread wakes late, by up to 50 ms measured under the whole suite and two
/// busy processes, twice an exchange (the request, then the answer when it is due); an answer
/// is lost only if every attempt of an exchange is that late. An absent device costs the
/// margin: provisioning a fresh servo pings all 254 ids once.
pub const MARGIN_MS: &str = "100";

/// Where the children look for user profiles: a folder that does not exist, so that the
/// profiles of whoever runs the tests do not change them.
fn no_user_profiles() -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("no-user-profiles")
}

/// `botbench` with `args`, ready to run.
pub fn botbench<I, S>(args: I) -> Command
where
    I: IntoIterator<Item = S>,
    S: AsRef<std::ffi::OsStr>,
{
    let mut c = Command::new(env!("CARGO_BIN_EXE_botbench"));
    c.args(args);
    as_user(c)
}

/// `c` with no user profiles and nothing on standard input.
fn as_user(mut c: Command) -> Command {
    // Runs are recorded in the tests' own file and spool, never in the user's (a test that
    // looks at its records names its own with --records or these variables).
    let tmp = PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    c.env(botbench::profile::registry::DIR_ENV, no_user_profiles())
        .env("BOTBENCH_RECORDS", tmp.join("cli-records.sqlite"))
        .env("BOTBENCH_SPOOL", tmp.join("cli-spool.sqlite"))
        .stdin(Stdio::null());
    c
}

/// `botbench sim` with `args`, under real-time scheduling where this process may
/// ([`botbench::sim::process::sim_command`]: the simulator stands in for a device with a
/// processor of its own; the command under test keeps ordinary scheduling). Elsewhere it runs as
/// any process, and a heavily loaded machine can then make a test of the field's timing fail.
fn sim_command(args: &[&str]) -> Command {
    let bin = std::path::Path::new(env!("CARGO_BIN_EXE_botbench"));
    as_user(botbench::sim::process::sim_command(bin, args))
}

/// How a run ended: its exit code and what it printed.
#[derive(Debug)]
pub struct Ran {
    /// The exit code (-1 when killed by a signal).
    pub code: i32,
    /// Standard output.
    pub out: String,
    /// Standard error.
    pub err: String,
}

impl Ran {
    fn of(o: std::process::Output) -> Self {
        Self {
            code: o.status.code().unwrap_or(-1),
            out: String::from_utf8_lossy(&o.stdout).into_owned(),
            err: String::from_utf8_lossy(&o.stderr).into_owned(),
        }
    }

    /// The first line of standard output, a JSON document.
    pub fn json(&self) -> serde_json::Value {
        serde_json::from_str(self.out.lines().next().expect("a line")).expect("JSON")
    }

    /// Standard output as one JSON document a line.
    pub fn json_lines(&self) -> Vec<serde_json::Value> {
        self.out
            .lines()
            .map(|l| serde_json::from_str(l).expect("one JSON document a line"))
            .collect()
    }
}

/// How long [`run_watched`] lets a command run before the test fails instead of hanging: far
/// beyond what a loaded machine needs, since a command that ends returns at once.
pub const WATCHDOG: std::time::Duration = std::time::Duration::from_secs(120);

impl Ran {
    /// Both outputs and the exit code, for assertion messages.
    pub fn text(&self) -> String {
        format!(
            "exit {}\n--- stdout\n{}--- stderr\n{}",
            self.code, self.out, self.err
        )
    }

    /// The lines of standard output that are JSON documents (others are skipped).
    pub fn json_docs(&self) -> Vec<serde_json::Value> {
        self.out
            .lines()
            .filter(|l| l.trim_start().starts_with('{'))
            .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
            .collect()
    }
}

/// Runs `botbench` with `args` to its end, for a command that might hang (a vanished port, a
/// silent device): the test fails once it has run for [`WATCHDOG`]. The watchdog never decides
/// a verdict.
pub fn run_watched(args: &[&str]) -> Ran {
    let mut child = botbench(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("runs botbench");
    let deadline = std::time::Instant::now() + WATCHDOG;
    loop {
        if child.try_wait().expect("waits on botbench").is_some() {
            return Ran::of(child.wait_with_output().expect("botbench's output"));
        }
        if std::time::Instant::now() >= deadline {
            let _ = child.kill();
            let ran = Ran::of(child.wait_with_output().expect("botbench's output"));
            panic!(
                "botbench {args:?} did not end within {WATCHDOG:?}: {}",
                ran.text()
            );
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
}

/// Runs `botbench` with `args` to its end.
pub fn run(args: &[&str]) -> Ran {
    output(&mut botbench(args))
}

/// Runs `command` to its end.
pub fn output(command: &mut Command) -> Ran {
    Ran::of(command.output().expect("runs botbench"))
}

/// A `botbench sim` process serving a device on a pty, with its stdin to type controls into;
/// killed on drop.
pub struct SimProcess {
    process: botbench::sim::process::SimProcess,
    /// The pty path it printed first.
    pub path: String,
    stderr: Lines<BufReader<ChildStderr>>,
}

impl SimProcess {
    /// Starts `botbench sim` with `args` (the kind first) and reads the pty path it prints.
    pub fn start(args: &[&str]) -> Self {
        let mut command = sim_command(args);
        command.stdin(Stdio::piped()).stderr(Stdio::piped());
        let mut process =
            botbench::sim::process::SimProcess::start(command).expect("starts the simulator");
        let path = process.path.clone();
        let stderr = BufReader::new(process.child().stderr.take().expect("piped stderr")).lines();
        Self {
            process,
            path,
            stderr,
        }
    }

    /// Runs `botbench GROUP --port PATH --margin-ms MARGIN_MS ARGS...` against this simulator
    /// (watched: [`run_watched`]), for a test whose verdict is not about the margin.
    pub fn cli(&self, group: &str, args: &[&str]) -> Ran {
        let mut all = vec![group, "--port", &self.path, "--margin-ms", MARGIN_MS];
        all.extend_from_slice(args);
        run_watched(&all)
    }

    /// Waits, within [`WATCHDOG`], for the simulator to end on its own (its port vanished).
    pub fn wait_exit(&mut self) -> std::process::ExitStatus {
        let deadline = std::time::Instant::now() + WATCHDOG;
        loop {
            if let Some(s) = self
                .process
                .child()
                .try_wait()
                .expect("waits on the simulator")
            {
                return s;
            }
            assert!(
                std::time::Instant::now() < deadline,
                "the simulator did not end"
            );
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
    }

    /// Types a control line (`fault battery-low`, `corners 15`) and waits until the simulator
    /// confirms it.
    pub fn type_line(&mut self, control: &str) {
        let stdin = self.process.child().stdin.as_mut().expect("piped stdin");
        writeln!(stdin, "{control}").expect("the simulator reads");
        stdin.flush().expect("the simulator reads");
        let want = format!("ok: {control}");
        for line in self.stderr.by_ref() {
            if line.expect("the simulator's stderr").contains(&want) {
                return;
            }
        }
        panic!("the simulator did not confirm {control}");
    }
}
