//! The command line as a user runs it, two ways:
//!
//! - against a simulated device, in this process ([`Sim`]: what `botbench sim ARGS` serves,
//!   served on a pty in lockstep with the link of `cli::run_args_captured`): a device that a
//!   loaded machine cannot starve, as a real one has a processor of its own, so no verdict
//!   depends on how soon another process is scheduled;
//! - without a device, or where only a process will do (an installed binary, another user, an
//!   environment variable, a program that is not botbench driving `botbench sim`): the `botbench`
//!   binary in a child process with no user profiles ([`run`], [`run_watched`]), and
//!   [`SimProcess`] for `botbench sim` in a process of its own.
//!
//! Every run is watched: a run that does not end within [`WATCHDOG`] fails its test.

use std::io::{BufRead, BufReader, Write};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The answer margin the tests give a device across processes, as `--margin-ms`. The simulator
/// runs in another process, which nothing keeps in lockstep with the command: on a loaded
/// 2-core machine its thread wakes late, by up to 50 ms measured under the whole suite and two
/// busy processes, twice an exchange (the request, then the answer when it is due); an answer
/// is lost only if every attempt of an exchange is that late. An absent device costs the
/// margin: provisioning a fresh servo pings all 254 ids once.
pub const MARGIN_MS: &str = "100";

/// The answer margin, as `--margin-ms`, of a test whose command line must run in a process of
/// its own because the process is what it tests (an environment variable of the whole process):
/// its device is a `botbench sim` process under real-time scheduling where this process may,
/// but the command itself keeps ordinary scheduling and a loaded machine can hold its thread
/// up for tens of milliseconds between a request and its answer's deadline. One second is far
/// beyond that, and costs nothing when the device answers (only an absent one waits it out).
pub const PROCESS_MARGIN_MS: &str = "1000";

/// Where the children and the runs in this process look for user profiles: a folder that does
/// not exist, so that the profiles of whoever runs the tests do not change them.
pub fn no_user_profiles() -> PathBuf {
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
    /// The exit code (`None`: killed by a signal) and what the threads reading the outputs got
    /// (they end when the process and its children have closed them).
    fn from_parts(
        code: Option<i32>,
        out: std::thread::JoinHandle<Vec<u8>>,
        err: std::thread::JoinHandle<Vec<u8>>,
    ) -> Self {
        // A child that left a grandchild holding its outputs would keep them open: the test
        // fails after PATIENCE instead of hanging on the reader.
        let text = |h: std::thread::JoinHandle<Vec<u8>>| {
            let bytes = super::joined(h, "the end of a child's output (a grandchild holding it?)");
            String::from_utf8_lossy(&bytes).into_owned()
        };
        Self {
            code: code.unwrap_or(-1),
            out: text(out),
            err: text(err),
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

/// How long a run ([`run_watched`], [`run_in_process`]) may take before the test fails instead
/// of hanging: far beyond what a loaded machine needs, since a command that ends returns at
/// once. 120 s was too short: with two CPU-bound loops beside eight tests, a provisioning in
/// lockstep (some two thousand exchanges, each a hand-over between the link's thread and the
/// simulator's) ran past it, slow but right.
pub const WATCHDOG: std::time::Duration = std::time::Duration::from_secs(600);

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
    watched(&mut botbench(args), &format!("botbench {args:?}"))
}

/// Runs `command` (`what`, for the failure) to its end with its outputs piped; the test fails
/// once it has run for [`WATCHDOG`] (the process killed), rather than hang.
pub fn watched(command: &mut Command, what: &str) -> Ran {
    try_watched(command, what).unwrap_or_else(|e| panic!("cannot run {what}: {e}"))
}

/// As [`watched`], for a program that may not be installed: the error when it cannot start.
pub fn try_watched(command: &mut Command, what: &str) -> std::io::Result<Ran> {
    let mut child = command
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()?;
    // The outputs are read as they come, so that a child writing more than a pipe holds never
    // blocks on a full pipe while it is waited for.
    let out = drain(child.stdout.take());
    let err = drain(child.stderr.take());
    let deadline = std::time::Instant::now() + WATCHDOG;
    let status = loop {
        if let Some(status) = child.try_wait().expect("waits on the child") {
            break status;
        }
        if std::time::Instant::now() >= deadline {
            let _ = child.kill();
            let _ = child.wait();
            let ran = Ran::from_parts(None, out, err);
            panic!("{what} did not end within {WATCHDOG:?}: {}", ran.text());
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    };
    Ok(Ran::from_parts(status.code(), out, err))
}

/// A thread reading `pipe` to its end.
fn drain<R: std::io::Read + Send + 'static>(pipe: Option<R>) -> std::thread::JoinHandle<Vec<u8>> {
    spawn_named("child-output", move || {
        let mut bytes = Vec::new();
        if let Some(mut p) = pipe {
            let _ = p.read_to_end(&mut bytes);
        }
        bytes
    })
}

/// `f` on a thread named `name`.
fn spawn_named<T: Send + 'static>(
    name: &str,
    f: impl FnOnce() -> T + Send + 'static,
) -> std::thread::JoinHandle<T> {
    std::thread::Builder::new()
        .name(name.into())
        .spawn(f)
        .expect("starts a thread")
}

/// Runs `botbench` with `args` to its end (within [`WATCHDOG`], see [`run_watched`]).
pub fn run(args: &[&str]) -> Ran {
    run_watched(args)
}

/// Runs `command` (a [`botbench`] command) to its end, within [`WATCHDOG`].
pub fn output(command: &mut Command) -> Ran {
    watched(command, "botbench")
}

/// A `botbench sim` process serving a device on a pty, with its stdin to type controls into;
/// killed on drop.
pub struct SimProcess {
    process: botbench::sim::process::SimProcess,
    /// The pty path it printed first.
    pub path: String,
    /// Its stderr, a line at a time, read on a thread of its own so that a wait for a line is
    /// bounded.
    stderr: std::sync::mpsc::Receiver<std::io::Result<String>>,
}

impl SimProcess {
    /// Starts `botbench sim` with `args` (the kind first) and reads the pty path it prints.
    pub fn start(args: &[&str]) -> Self {
        let mut command = sim_command(args);
        command.stdin(Stdio::piped()).stderr(Stdio::piped());
        let mut process =
            botbench::sim::process::SimProcess::start(command).expect("starts the simulator");
        let path = process.path.clone();
        let lines = BufReader::new(process.child().stderr.take().expect("piped stderr")).lines();
        let (tx, stderr) = std::sync::mpsc::channel();
        spawn_named("sim-stderr", move || {
            for line in lines {
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
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
        let deadline = std::time::Instant::now() + super::PATIENCE;
        loop {
            let left = deadline.saturating_duration_since(std::time::Instant::now());
            match self.stderr.recv_timeout(left) {
                Ok(Ok(line)) if line.contains(&want) => return,
                Ok(Ok(_)) => {}
                Ok(Err(e)) => panic!("the simulator's stderr: {e}"),
                Err(e) => panic!("the simulator did not confirm {control}: {e}"),
            }
        }
    }
}

/// A simulated device as `botbench sim ARGS...` serves it, but served in this process on a pty
/// in lockstep with the link of a command line run in this process ([`Sim::run`],
/// [`Sim::cli`]): a device that a loaded machine cannot starve, as a real device has a
/// processor of its own. What the verdict is about (a late answer, a split reply, a slow host)
/// is the simulator's explicit timing, never how soon a thread is scheduled.
pub struct Sim {
    server: botbench::sim::PtyServer,
    control: Option<botbench::cli::SimControl>,
    ports: botbench::link::PortOpener,
    /// The pty's path, for `--port`.
    pub path: String,
}

impl Sim {
    /// Serves what `botbench sim ARGS...` (`args`: the kind first) would.
    pub fn start(args: &[&str]) -> Self {
        let sim = botbench::cli::simulated(args)
            .unwrap_or_else(|e| panic!("sim {args:?}: {}", e.message));
        let server =
            botbench::sim::PtyServer::start_lockstep(sim.device, sim.faults).expect("serves a pty");
        Self {
            path: server.path().to_string(),
            ports: server.port_opener(),
            control: sim.control,
            server,
        }
    }

    /// As [`Self::start`], with a count of the bytes the device has heard (to act once a run
    /// has reached it, not after a while).
    pub fn start_heard(args: &[&str]) -> (Self, Arc<AtomicUsize>) {
        let sim = botbench::cli::simulated(args)
            .unwrap_or_else(|e| panic!("sim {args:?}: {}", e.message));
        let heard = Arc::new(AtomicUsize::new(0));
        let device: botbench::sim::SharedDevice = Arc::new(std::sync::Mutex::new(Heard {
            inner: sim.device,
            heard: heard.clone(),
        }));
        let server =
            botbench::sim::PtyServer::start_lockstep(device, sim.faults).expect("serves a pty");
        let sim = Self {
            path: server.path().to_string(),
            ports: server.port_opener(),
            control: sim.control,
            server,
        };
        (sim, heard)
    }

    /// Runs `botbench ARGS...` in this process, `--port` this simulator's path reaching it in
    /// lockstep (see [`run_in_process`]).
    pub fn run(&self, args: &[&str]) -> Ran {
        run_in_process(args, &self.ports)
    }

    /// As [`Self::run`], the operator typing `input` (lines) at the command's prompts.
    pub fn run_typing(&self, args: &[&str], input: &str) -> Ran {
        run_in_process_into(args, &self.ports, botbench::cli::Captured::typing(input))
    }

    /// Runs `botbench GROUP --port PATH ARGS...` against this simulator (see [`Self::run`]).
    pub fn cli(&self, group: &str, args: &[&str]) -> Ran {
        let mut all = vec![group, "--port", &self.path];
        all.extend_from_slice(args);
        self.run(&all)
    }

    /// Does what a line typed on `botbench sim`'s stdin does (`fault battery-low`, `corners
    /// 15`).
    pub fn type_line(&mut self, control: &str) {
        let c = self
            .control
            .as_ref()
            .expect("a simulator that takes commands");
        c.type_line(control)
            .unwrap_or_else(|e| panic!("{control}: {e}"));
    }

    /// Waits, within [`WATCHDOG`], until the simulator stops serving (its port vanished, as
    /// asked).
    pub fn wait_stopped(&self) {
        let deadline = std::time::Instant::now() + WATCHDOG;
        while self.server.is_running() {
            assert!(
                std::time::Instant::now() < deadline,
                "the simulator did not stop"
            );
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
    }

    /// Makes the port vanish now, as an unplugged adapter (its pty's master side closed).
    pub fn vanish_now(&mut self) {
        self.server.vanish();
    }

    /// `ports`, with this simulator's path reaching it in lockstep (several simulators for
    /// one run: a station's slots).
    pub fn serve_in(&self, ports: botbench::link::PortOpener) -> botbench::link::PortOpener {
        self.server.serve_in(ports)
    }

    /// The port opener that reaches this simulator (for a run that is watched as it goes).
    pub fn ports(&self) -> &botbench::link::PortOpener {
        &self.ports
    }
}

/// Runs `botbench ARGS...` in this process (`cli::run_args_captured`), ports opened with
/// `ports`, on a thread of its own; the test fails once it has run for [`WATCHDOG`] rather than
/// hang. A run that records (see [`records_in_tests`]) records in the tests' own file.
pub fn run_in_process(args: &[&str], ports: &botbench::link::PortOpener) -> Ran {
    run_in_process_into(args, ports, botbench::cli::Captured::default())
}

/// As [`run_in_process`], writing into `captured` (its operator's typing, if given).
pub fn run_in_process_into(
    args: &[&str],
    ports: &botbench::link::PortOpener,
    captured: botbench::cli::Captured,
) -> Ran {
    let run = start_in_process(args, ports, &captured);
    let what = format!("botbench {args:?} (in process)");
    let code = finish_in_process(run, &captured, &what);
    Ran {
        code: code.into(),
        out: captured.out(),
        err: captured.err(),
    }
}

/// `args`, with `--records` naming the tests' own file when they run a command that records a
/// run (`msp selftest`, `servo provision`, `preset apply`) and name none: a child process gets
/// it as `BOTBENCH_RECORDS` ([`as_user`]), a run in this process as an option (the variable is
/// the whole process's, and other tests run beside it).
fn records_in_tests(args: &[&str]) -> Vec<String> {
    let mut all: Vec<String> = args.iter().map(|a| a.to_string()).collect();
    let has = |w: &str| args.contains(&w);
    let records = (has("selftest") && has("msp"))
        || (has("provision") && has("servo"))
        || (has("preset") && has("apply"));
    if records && !has("--records") {
        let file = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli-records.sqlite");
        all.extend(["--records".to_string(), file.display().to_string()]);
    }
    all
}

/// Starts `botbench ARGS...` in this process on a thread of its own, writing to `captured`,
/// with no user profiles unless `captured` names a folder of them
/// ([`botbench::cli::Captured::with_profiles`]).
pub fn start_in_process(
    args: &[&str],
    ports: &botbench::link::PortOpener,
    captured: &botbench::cli::Captured,
) -> std::thread::JoinHandle<u8> {
    let mut all = vec!["botbench".to_string()];
    all.extend(records_in_tests(args));
    // The user's profiles are not the tests': an empty folder unless the test names one.
    let into = match captured.profiles() {
        Some(_) => captured.clone(),
        None => captured.clone().with_profiles(no_user_profiles()),
    };
    let ports = ports.clone();
    std::thread::Builder::new()
        .name("cli-in-process".into())
        .spawn(move || botbench::cli::run_args_captured(all, &ports, &into))
        .expect("starts the command line's thread")
}

/// The exit code of a run started with [`start_in_process`], once it has ended; fails after
/// [`WATCHDOG`] with what it wrote so far.
pub fn finish_in_process(
    run: std::thread::JoinHandle<u8>,
    captured: &botbench::cli::Captured,
    what: &str,
) -> u8 {
    let deadline = std::time::Instant::now() + WATCHDOG;
    while !run.is_finished() {
        assert!(
            std::time::Instant::now() < deadline,
            "{what} did not end within {WATCHDOG:?}\n--- stdout\n{}--- stderr\n{}",
            captured.out(),
            captured.err()
        );
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    match run.join() {
        Ok(code) => code,
        Err(panic) => std::panic::resume_unwind(panic),
    }
}

/// A device that counts the bytes it hears, then does what `inner` does.
struct Heard {
    inner: botbench::sim::SharedDevice,
    heard: Arc<AtomicUsize>,
}

impl botbench::sim::Device for Heard {
    fn receive(
        &mut self,
        bytes: &[u8],
        baud: u32,
        now: std::time::Instant,
    ) -> Vec<botbench::sim::Outgoing> {
        self.heard.fetch_add(bytes.len(), Ordering::SeqCst);
        botbench::sim::runner::lock(&self.inner).receive(bytes, baud, now)
    }

    fn tick(&mut self, now: std::time::Instant) -> Vec<botbench::sim::Outgoing> {
        botbench::sim::runner::lock(&self.inner).tick(now)
    }
}
