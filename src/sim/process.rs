//! `botbench sim` in a process of its own, as a person runs it beside the command under test: the
//! simulator stands in for a device that has a processor of its own, so it runs under real-time
//! scheduling where this process may (the tests and `botbench bench --field` start it this way).

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, ChildStdout, Command, Stdio};
use std::sync::OnceLock;
use std::time::Duration;

/// The real-time priority a simulator process runs at where it may (`chrt --fifo`, 1-99; low:
/// it only has to come before the ordinary processes of a loaded machine).
pub const SIM_PRIORITY: &str = "10";

/// Whether this process may start a program under real-time scheduling (`chrt --fifo`: root, or
/// CAP_SYS_NICE, as CI has); asked once.
pub fn may_run_realtime() -> bool {
    static MAY: OnceLock<bool> = OnceLock::new();
    *MAY.get_or_init(|| {
        Command::new("chrt")
            .args(["--fifo", SIM_PRIORITY, "true"])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success())
    })
}

/// `BIN sim ARGS...` (`bin` is a botbench executable): under `chrt --fifo` [`SIM_PRIORITY`]
/// where [`may_run_realtime`], so that the load beside it does not make it answer late as a
/// device never would (the command it serves keeps ordinary scheduling, late as a loaded host
/// is); elsewhere as any process.
pub fn sim_command(bin: &Path, args: &[&str]) -> Command {
    let mut c = if may_run_realtime() {
        let mut c = Command::new("chrt");
        c.args(["--fifo", SIM_PRIORITY]).arg(bin);
        c
    } else {
        Command::new(bin)
    };
    c.arg("sim").args(args);
    c
}

/// A `botbench sim` process serving a device on a pty: killed and reaped when dropped (an error
/// or a panic in its owner included).
#[derive(Debug)]
pub struct SimProcess {
    child: Child,
    /// The pty path it printed on its first line.
    pub path: String,
}

impl SimProcess {
    /// Starts `command` (from [`sim_command`]) with its stdout piped and reads the pty path it
    /// prints first, waiting at most [`START_LIMIT`]. Errors (the process killed) when it cannot
    /// start, prints no `/dev/` path, or prints nothing within the limit (a simulator that hangs
    /// before serving fails its caller instead of hanging it).
    pub fn start(command: Command) -> Result<Self, String> {
        Self::start_within(command, START_LIMIT)
    }

    /// As [`Self::start`], waiting at most `limit` for the pty path.
    pub fn start_within(mut command: Command, limit: Duration) -> Result<Self, String> {
        let child = command
            .stdout(Stdio::piped())
            .spawn()
            .map_err(|e| format!("cannot start the simulator: {e}"))?;
        let mut sim = SimProcess {
            child,
            path: String::new(),
        };
        let stdout = sim
            .child
            .stdout
            .take()
            .ok_or("the simulator's stdout is not piped")?;
        let line = first_line(stdout, limit)?;
        let path = line.trim();
        if !path.starts_with("/dev/") {
            return Err(format!(
                "the simulator printed {line:?} where its pty path was expected"
            ));
        }
        sim.path = path.to_string();
        Ok(sim)
    }

    /// The process, to type into its stdin or wait on it.
    pub fn child(&mut self) -> &mut Child {
        &mut self.child
    }
}

/// How long [`SimProcess::start`] waits for the simulator's pty path: far beyond what a loaded
/// machine needs to start a process (a simulator prints its path before it serves anything).
pub const START_LIMIT: Duration = Duration::from_secs(60);

/// The first line `pipe` gives within `limit`, read on a thread of its own (named
/// `sim-stdout`), so that a process that never prints is an error, not a hang. The thread ends
/// when the line comes or the pipe closes (the process is killed on error by its owner).
fn first_line(pipe: ChildStdout, limit: Duration) -> Result<String, String> {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::Builder::new()
        .name("sim-stdout".into())
        .spawn(move || {
            let mut line = String::new();
            let read = BufReader::new(pipe).read_line(&mut line).map(|_| line);
            let _ = tx.send(read);
        })
        .map_err(|e| format!("cannot read the simulator's pty path: {e}"))?;
    match rx.recv_timeout(limit) {
        Ok(read) => read.map_err(|e| format!("cannot read the simulator's pty path: {e}")),
        Err(_) => Err(format!(
            "the simulator printed no pty path within {} s",
            limit.as_secs()
        )),
    }
}

impl Drop for SimProcess {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_simulator_that_prints_no_path_is_an_error_not_a_hang() {
        let mut silent = Command::new("sleep");
        silent.arg("600");
        let e = SimProcess::start_within(silent, Duration::from_millis(200)).unwrap_err();
        assert!(e.contains("printed no pty path within"), "{e}");
        let mut wrong = Command::new("echo");
        wrong.arg("hello");
        let e = SimProcess::start(wrong).unwrap_err();
        assert!(e.contains("where its pty path was expected"), "{e}");
    }
}
