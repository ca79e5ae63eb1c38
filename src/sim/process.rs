//! `botbench sim` in a process of its own, as a person runs it beside the command under test: the
//! simulator stands in for a device that has a processor of its own, so it runs under real-time
//! scheduling where this process may (the tests and `botbench bench --field` start it this way).

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::OnceLock;

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
    /// prints first. Errors (the process killed) when it cannot start or prints no `/dev/` path.
    pub fn start(mut command: Command) -> Result<Self, String> {
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
        let mut line = String::new();
        BufReader::new(stdout)
            .read_line(&mut line)
            .map_err(|e| format!("cannot read the simulator's pty path: {e}"))?;
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

impl Drop for SimProcess {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
