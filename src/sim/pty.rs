//! A simulated device served on a pseudo-terminal: a client opens [`PtyServer::path`] as it
//! would open a USB serial adapter.

use super::lockstep::{self, HostAction, Lockstep};
use super::runner::{Faults, SharedDevice, VanishHandle, Wire, sleep_until};
use crate::link::{LinkError, Opener, PortOpener};
use serialport::{SerialPort, TTYPort};
use std::io::{ErrorKind, Read, Write};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// The longest the server thread blocks in one read: stop and vanish requests are seen this fast.
const POLL: Duration = Duration::from_millis(5);
/// How long a reply may wait for room in the pty before it is dropped (nobody reading).
const WRITE_TIMEOUT: Duration = Duration::from_millis(50);
/// In lockstep, how soon the server tries again to write the device's bytes the pty had no
/// room for.
const BACKLOG_RETRY: Duration = Duration::from_millis(1);
/// In lockstep, the most device bytes the server keeps for a pty that takes none: past it, the
/// copy across the pty is given up (the host reads the bytes from the lockstep's record anyway).
const BACKLOG_LIMIT: usize = 1 << 20;

#[derive(Default)]
struct Flags {
    stop: AtomicBool,
    vanish: VanishHandle,
    exited: AtomicBool,
    /// Lockstep: the server loop has ended (its drain thread ends too).
    served: AtomicBool,
    /// Lockstep: the drain thread's read failed (the port vanished): the loop ends.
    drain_failed: AtomicBool,
    /// Tests: the drain thread takes this before each read, so that a test holding it stands
    /// the drain still, as a kernel worker run late does ([`serve_lockstep`]).
    #[cfg(test)]
    drain_gate: std::sync::Mutex<()>,
    /// Tests: while a test holds this, the server loop writes nothing to the pty (its bytes wait
    /// in its backlog), as a kernel worker run late hands nothing over ([`serve_lockstep`]).
    #[cfg(test)]
    copy_gate: std::sync::Mutex<()>,
}

/// A device on a pseudo-terminal, served by a named thread until stopped or dropped.
pub struct PtyServer {
    path: String,
    device: SharedDevice,
    flags: Arc<Flags>,
    thread: Option<JoinHandle<()>>,
    /// Held open so that the path stays valid between clients.
    _slave: TTYPort,
    /// Served in lockstep with a host in this process.
    lockstep: Option<Arc<Lockstep>>,
}

impl std::fmt::Debug for PtyServer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PtyServer")
            .field("path", &self.path)
            .field("running", &self.is_running())
            .finish_non_exhaustive()
    }
}

impl PtyServer {
    /// Opens a pseudo-terminal and starts serving `device` on it with `faults`. The device's
    /// baud rate is whatever the client sets on the port.
    pub fn start(device: SharedDevice, faults: Faults) -> Result<PtyServer, LinkError> {
        Self::spawn(device, faults, None)
    }

    /// As [`PtyServer::start`], served in lockstep with a host in this process that opens the
    /// path with this server's [`Self::opener`] or [`Self::port_opener`] (see
    /// [`super::lockstep`]): for tests, whose verdicts must not depend on how fast threads are
    /// scheduled. A client that opens the path otherwise (another process) gets no answer.
    pub fn start_lockstep(device: SharedDevice, faults: Faults) -> Result<PtyServer, LinkError> {
        Self::spawn(device, faults, Some(Lockstep::new()))
    }

    fn spawn(
        device: SharedDevice,
        faults: Faults,
        lockstep: Option<Arc<Lockstep>>,
    ) -> Result<PtyServer, LinkError> {
        let open_err = |reason: String| LinkError::Open {
            path: "pseudo-terminal".into(),
            reason,
        };
        faults.check().map_err(open_err)?;
        let (master, slave) = TTYPort::pair().map_err(|e| open_err(e.to_string()))?;
        for side in [&master, &slave] {
            use std::os::fd::AsRawFd;
            crate::link::serial::close_on_exec(side.as_raw_fd())
                .map_err(|e| open_err(format!("close-on-exec: {e}")))?;
        }
        let path = slave
            .name()
            .ok_or_else(|| open_err("the pseudo-terminal has no path".into()))?;
        let baud = master.baud_rate().unwrap_or(9600);
        let flags = Arc::new(Flags::default());
        let mut wire = Wire::new(device.clone(), baud, faults);
        if lockstep.is_none() {
            wire.host_times_uncertain();
        }
        let thread_flags = flags.clone();
        let thread_lockstep = match &lockstep {
            None => None,
            Some(l) => Some((l.clone(), HostSide::of(&slave, &path).map_err(open_err)?)),
        };
        let thread = std::thread::Builder::new()
            .name("sim-pty".into())
            .spawn(move || {
                match thread_lockstep {
                    None => serve(master, wire, &thread_flags),
                    Some((l, host_side)) => {
                        serve_lockstep(master, host_side, wire, &thread_flags, &l);
                    }
                }
                thread_flags.exited.store(true, Ordering::SeqCst);
            })
            .map_err(|e| open_err(format!("cannot start the server thread: {e}")))?;
        Ok(PtyServer {
            path,
            device,
            flags,
            thread: Some(thread),
            _slave: slave,
            lockstep,
        })
    }

    /// The path a client opens, e.g. `/dev/pts/7`.
    pub fn path(&self) -> &str {
        &self.path
    }

    /// The opener of this server's pty at `baud`: in lockstep with the simulator when it serves
    /// in lockstep, else the system's serial port opener.
    pub fn opener(&self, baud: u32) -> Opener {
        match &self.lockstep {
            Some(l) => lockstep::opener(l.clone(), self.path.clone(), baud),
            None => crate::link::serial::opener(&self.path, baud),
        }
    }

    /// `ports`, except that this server's path is opened by [`Self::opener`]: what a test hands
    /// to the window or the command line, as a user's machine hands its serial ports.
    pub fn serve_in(&self, ports: PortOpener) -> PortOpener {
        match &self.lockstep {
            Some(l) => {
                let (lockstep, path) = (l.clone(), self.path.clone());
                ports.with_port(self.path.clone(), move |baud| {
                    lockstep::opener(lockstep.clone(), path.clone(), baud)
                })
            }
            None => ports,
        }
    }

    /// The system's ports, with this server's path opened by [`Self::opener`]
    /// ([`Self::serve_in`]).
    pub fn port_opener(&self) -> PortOpener {
        self.serve_in(PortOpener::system())
    }

    /// The simulated device, to read or change its state.
    pub fn device(&self) -> SharedDevice {
        self.device.clone()
    }

    /// Whether the server thread is still serving.
    pub fn is_running(&self) -> bool {
        !self.flags.exited.load(Ordering::SeqCst)
    }

    /// Makes the port vanish, as an unplugged adapter: the pty's master side is closed, and the
    /// client's reads fail (`BrokenPipe`). Returns once it is closed.
    pub fn vanish(&mut self) {
        self.flags.vanish.vanish();
        self.join();
    }

    /// A handle that makes the port vanish from another thread (within a few milliseconds).
    pub fn vanish_handle(&self) -> VanishHandle {
        self.flags.vanish.clone()
    }

    /// Stops serving and waits for the thread to end.
    pub fn stop(&mut self) {
        self.flags.stop.store(true, Ordering::SeqCst);
        self.join();
    }

    fn join(&mut self) {
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for PtyServer {
    fn drop(&mut self) {
        self.stop();
        if let Some(l) = &self.lockstep {
            l.close();
        }
    }
}

/// The server loop. Ends (closing the master) on stop, vanish, or a port error.
fn serve(mut master: TTYPort, mut wire: Wire, flags: &Flags) {
    let mut buf = [0u8; 4096];
    loop {
        if flags.stop.load(Ordering::SeqCst) || flags.vanish.is_vanished() || wire.vanished() {
            return;
        }
        let now = Instant::now();
        follow_baud(&master, &mut wire);
        wire.pump(now);
        let mut out = [0u8; 4096];
        loop {
            let n = wire.take_due(now, &mut out);
            if n == 0 {
                break;
            }
            if write_frame(&mut master, &out[..n]).is_none() {
                return;
            }
        }
        let next = wire.next_event().min(now + POLL);
        let wait = next.saturating_duration_since(Instant::now());
        // Block in the read for most of the wait; spin the last bit for a punctual delivery.
        let block = wait.saturating_sub(Duration::from_micros(150));
        if master.set_timeout(block).is_err() {
            return;
        }
        match master.read(&mut buf) {
            Ok(0) => {}
            Ok(n) => {
                // The client sets its baud before it writes: read it after the bytes.
                follow_baud(&master, &mut wire);
                wire.host_wrote(&buf[..n], Instant::now());
            }
            Err(e) if matches!(e.kind(), ErrorKind::TimedOut | ErrorKind::Interrupted) => {}
            Err(e) if e.kind() == ErrorKind::WouldBlock => {}
            Err(_) => return,
        }
        if next > Instant::now() && next - Instant::now() < Duration::from_micros(200) {
            sleep_until(next);
        }
    }
}

/// Takes the baud rate the client has set on the port.
fn follow_baud(master: &TTYPort, wire: &mut Wire) {
    if let Ok(baud) = master.baud_rate()
        && baud != wire.baud()
        && baud > 0
    {
        wire.set_baud(baud, Instant::now());
    }
}

/// Writes bytes that have arrived; how many were written, `None` when the port is gone. What
/// nobody makes room for is dropped.
fn write_frame(master: &mut TTYPort, frame: &[u8]) -> Option<usize> {
    if master.set_timeout(WRITE_TIMEOUT).is_err() {
        return None;
    }
    let mut rest = frame;
    while !rest.is_empty() {
        match master.write(rest) {
            Ok(0) => break,
            Ok(n) => rest = &rest[n..],
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(e) if e.kind() == ErrorKind::TimedOut => break,
            Err(_) => return None,
        }
    }
    Some(frame.len() - rest.len())
}

/// The server loop in lockstep with the host (see [`super::lockstep`]): the host's writes and
/// baud switches are taken at the instants the host stamped them, in order; the device's time
/// never passes the stamp of an action not yet taken.
///
/// The loop never polls or reads the pty's master side: on Linux both wait for the kernel's
/// worker to hand over bytes in flight (`n_tty_poll` and `n_tty_read` call
/// `tty_buffer_flush_work`), and on a machine loaded with CPU-bound work that worker was seen
/// to run 2-20 s late, every simulator of the process standing still meanwhile (strace: a
/// zero-timeout `ppoll` of the master returning after 9.1 s in four server threads at once;
/// the hosts gave up after three attempts). The host's bytes that cross the pty are drained by
/// a thread of their own ([`drain_host_bytes`]), and replies are written without a poll
/// ([`write_unpolled`]). The host, for the same reason, reads the replies from the lockstep's
/// record of them, not from the pty; the copy that crosses is drained at the host's side by a
/// thread of the server's ([`drain_device_bytes`]).
fn serve_lockstep(
    master: TTYPort,
    host_side: HostSide,
    wire: Wire,
    flags: &Arc<Flags>,
    lockstep: &Arc<Lockstep>,
) {
    // However the loop ends (a panicking device too), the host stops waiting for it, and only
    // once the pty's master side is closed (the loop and the drain own it): a host told that
    // nothing more comes while the port still looked open would take a vanished port for a
    // silent device.
    let stopped = lockstep.serving();
    let drain = start_drain(&master, flags, lockstep);
    let host_drain = start_host_drain(host_side, flags, lockstep);
    serve_lockstep_loop(master, wire, flags, lockstep);
    flags.served.store(true, Ordering::SeqCst);
    for drain in [drain, host_drain].into_iter().flatten() {
        let _ = drain.join();
    }
    drop(stopped);
}

/// The host's side of a lockstep pty, as the server reads it: the pty's own side (a duplicate
/// of the descriptor the server holds open) and, for its terminal settings, the path opened
/// again (read-only, never the controlling terminal).
struct HostSide {
    reader: TTYPort,
    settings: std::fs::File,
}

impl HostSide {
    fn of(slave: &TTYPort, path: &str) -> Result<Self, String> {
        use std::os::unix::fs::OpenOptionsExt;
        let reader = slave
            .try_clone_native()
            .map_err(|e| format!("cannot share the pty's side: {e}"))?;
        let settings = std::fs::OpenOptions::new()
            .read(true)
            .custom_flags(libc::O_NOCTTY | libc::O_NONBLOCK)
            .open(path)
            .map_err(|e| format!("cannot open {path} for its settings: {e}"))?;
        Ok(Self { reader, settings })
    }
}

/// Starts the thread that drains the device's bytes at the host's side of the pty (`None` when
/// it cannot start: the comparison is then not made).
fn start_host_drain(
    host_side: HostSide,
    flags: &Arc<Flags>,
    lockstep: &Arc<Lockstep>,
) -> Option<JoinHandle<()>> {
    let (flags, lockstep) = (flags.clone(), lockstep.clone());
    std::thread::Builder::new()
        .name("sim-pty-host-drain".into())
        .spawn(move || drain_device_bytes(host_side, &flags, &lockstep))
        .ok()
}

/// Starts the thread that drains what the host's writes brought across the pty (`None`, and the
/// loop ends at once, when the master cannot be shared or made non-blocking).
fn start_drain(
    master: &TTYPort,
    flags: &Arc<Flags>,
    lockstep: &Arc<Lockstep>,
) -> Option<JoinHandle<()>> {
    let fail = || {
        flags.drain_failed.store(true, Ordering::SeqCst);
        None
    };
    let Ok(reader) = master.try_clone_native() else {
        return fail();
    };
    // Shared by both descriptors: the loop's writes never block, the drain waits in its poll.
    if crate::link::serial::non_blocking(master).is_err() {
        return fail();
    }
    let (flags, lockstep) = (flags.clone(), lockstep.clone());
    std::thread::Builder::new()
        .name("sim-pty-drain".into())
        .spawn(move || drain_host_bytes(reader, &flags, &lockstep))
        .map_or_else(|_| fail(), Some)
}

#[allow(unsafe_code)]
fn serve_lockstep_loop(master: TTYPort, mut wire: Wire, flags: &Flags, lockstep: &Lockstep) {
    use std::os::fd::{AsRawFd, BorrowedFd};
    // SAFETY: `master` owns this descriptor and outlives every use of `fd` (this function).
    let fd = unsafe { BorrowedFd::borrow_raw(master.as_raw_fd()) };
    let mut out = [0u8; 4096];
    // The device's bytes the pty has not taken yet (no room, or a test's gate held).
    let mut backlog: Vec<u8> = Vec::new();
    loop {
        // A port that vanishes after so many bytes from the host vanishes in lockstep too.
        if flags.stop.load(Ordering::SeqCst)
            || flags.vanish.is_vanished()
            || wire.vanished()
            || flags.drain_failed.load(Ordering::SeqCst)
        {
            return;
        }
        let mut due: Vec<u8> = Vec::new();
        let mut cleared = false;
        let (now, held_back, generation) = {
            let mut s = lockstep.lock();
            let real = Instant::now();
            // Never past what the host may still stamp (see the lockstep module doc).
            let now = Lockstep::horizon(&s, real);
            while let Some((at, action)) = s.actions.pop_front() {
                match action {
                    HostAction::Wrote(bytes) => wire.host_wrote(&bytes, at),
                    HostAction::Baud(baud) => wire.set_baud(baud, at),
                    HostAction::Opened => {
                        // What the host wrote before the open reached the device before it.
                        wire.pump(at);
                        wire.opened(at);
                    }
                    HostAction::Clear => {
                        // What had reached the host by the clear is dropped, written or not.
                        wire.pump(at);
                        wire.clear_arrived(at);
                        s.cleared();
                        cleared = true;
                    }
                }
            }
            let horizon = s.actions.front().map_or(now, |(at, _)| now.min(*at));
            wire.pump(horizon);
            // One batch a frame, due when its first byte is: a simulator catching up after a
            // stall (its thread held up, or the host's) hands the host frames due apart as they
            // were due, not all when the first of them was (seen: a slow MCU's 19 reports,
            // 100-150 ms apart, all taken as a query's answer by a host held up 3 s).
            loop {
                let first = wire.next_byte_due().unwrap_or(now);
                let n = wire.take_frame_due(now, &mut out);
                if n == 0 {
                    break;
                }
                let kept = s.wrote(&out[..n], first, wire.last_seen().unwrap_or(now));
                due.extend_from_slice(&out[..kept]);
            }
            s.next_due = wire.next_due();
            (now, now < real, s.generation())
        };
        if !due.is_empty() || cleared {
            lockstep.signal_host();
        }
        backlog.extend_from_slice(&due);
        if !copy_across(fd, &mut backlog, flags, lockstep) {
            return;
        }
        // Held back by the host, the device waits for it to act or begin a call; else until
        // its next event. Either way the host's signal wakes it, and a stop is seen within POLL.
        let wait = if held_back {
            POLL
        } else if !backlog.is_empty() {
            BACKLOG_RETRY
        } else {
            let next = wire.next_event().min(now + POLL);
            next.saturating_duration_since(Instant::now())
        };
        lockstep.wait_for_host(generation, wait);
    }
}

/// Writes what it can of the device's bytes in `backlog` to the pty's master side
/// (non-blocking) without polling it first (see [`serve_lockstep`]); the rest waits for the next
/// turn. The host reads the bytes from the lockstep's record, so a pty that takes them late
/// holds nobody up; one that has not taken [`BACKLOG_LIMIT`] bytes stops the comparison
/// instead of growing. Returns `false` when the pty failed (the port vanished).
fn copy_across(
    master: std::os::fd::BorrowedFd<'_>,
    backlog: &mut Vec<u8>,
    flags: &Flags,
    lockstep: &Lockstep,
) -> bool {
    #[cfg(test)]
    let Ok(_gate) = flags.copy_gate.try_lock() else {
        return true;
    };
    #[cfg(not(test))]
    let _ = flags;
    let mut written = 0;
    while written < backlog.len() {
        match nix::unistd::write(master, &backlog[written..]) {
            Ok(0) | Err(nix::errno::Errno::EAGAIN) => break,
            Ok(n) => written += n,
            Err(nix::errno::Errno::EINTR) => {}
            Err(_) => return false,
        }
    }
    let mut s = lockstep.lock();
    s.to_host_crossing.sent(&backlog[..written]);
    backlog.drain(..written);
    if backlog.len() > BACKLOG_LIMIT {
        s.to_host_crossing.give_up();
        backlog.clear();
    }
    true
}

/// The drain thread: reads what the host's writes brought across the pty, for the comparison
/// with what it wrote ([`super::crossing`]), until the loop has ended; a failed read (the port
/// vanished) ends the loop too.
fn drain_host_bytes(mut reader: TTYPort, flags: &Flags, lockstep: &Lockstep) {
    let mut drained = [0u8; 4096];
    if reader.set_timeout(POLL).is_err() {
        flags.drain_failed.store(true, Ordering::SeqCst);
        return;
    }
    while !flags.served.load(Ordering::SeqCst) {
        #[cfg(test)]
        let _gate = flags.drain_gate.lock();
        match reader.read(&mut drained) {
            Ok(0) => {}
            Ok(n) => {
                let mut s = lockstep.lock();
                let before = s.to_device.changed().is_some();
                s.to_device.delivered(&drained[..n]);
                if let (false, Some(changed)) = (before, s.to_device.changed()) {
                    eprintln!("lockstep: {changed}");
                    drop(s);
                    lockstep.signal_host();
                }
            }
            Err(e)
                if matches!(
                    e.kind(),
                    ErrorKind::TimedOut | ErrorKind::Interrupted | ErrorKind::WouldBlock
                ) => {}
            Err(_) => {
                flags.drain_failed.store(true, Ordering::SeqCst);
                return;
            }
        }
    }
}

/// The host-side drain thread: reads the device's bytes that crossed the pty at the host's side,
/// for the comparison with what the simulator wrote ([`super::crossing`]), and watches the
/// host's terminal settings ([`not_raw`]), until the loop has ended or the pty is closed.
fn drain_device_bytes(host_side: HostSide, flags: &Flags, lockstep: &Lockstep) {
    let HostSide {
        mut reader,
        settings,
    } = host_side;
    let mut drained = [0u8; 4096];
    if reader.set_timeout(POLL).is_err() {
        return;
    }
    let mut said = false;
    while !flags.served.load(Ordering::SeqCst) {
        let read = reader.read(&mut drained);
        let mut s = lockstep.lock();
        if let Some(on) = not_raw(&settings) {
            s.to_host_crossing.not_raw(&on);
        }
        match read {
            Ok(n) => s.to_host_crossing.delivered(&drained[..n]),
            Err(e)
                if matches!(
                    e.kind(),
                    ErrorKind::TimedOut | ErrorKind::Interrupted | ErrorKind::WouldBlock
                ) => {}
            // The master is closed (the port vanished, or the loop ended): nothing more comes.
            Err(_) => return,
        }
        if let (false, Some(changed)) = (said, s.to_host_crossing.changed()) {
            eprintln!("lockstep: {changed}");
            said = true;
            drop(s);
            lockstep.signal_host();
        }
    }
}

/// The terminal settings of a pty side that make it not raw, named (e.g. `ICANON ICRNL`):
/// those that change the bytes it hands its reader, or hold them back for a line. `None` when
/// raw, or when the settings cannot be read.
fn not_raw(side: &std::fs::File) -> Option<String> {
    use nix::sys::termios::{InputFlags as I, LocalFlags as L};
    let t = nix::sys::termios::tcgetattr(side).ok()?;
    let local = [
        (L::ICANON, "ICANON"),
        (L::ECHO, "ECHO"),
        (L::ISIG, "ISIG"),
        (L::IEXTEN, "IEXTEN"),
    ];
    let input = [
        (I::ICRNL, "ICRNL"),
        (I::INLCR, "INLCR"),
        (I::IGNCR, "IGNCR"),
        (I::ISTRIP, "ISTRIP"),
        (I::IXON, "IXON"),
        (I::PARMRK, "PARMRK"),
    ];
    let on: Vec<&str> = local
        .iter()
        .filter(|(f, _)| t.local_flags.contains(*f))
        .map(|(_, name)| *name)
        .chain(
            input
                .iter()
                .filter(|(f, _)| t.input_flags.contains(*f))
                .map(|(_, name)| *name),
        )
        .collect();
    (!on.is_empty()).then(|| on.join(" "))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::tuya_mcu::{TuyaConfig, TuyaMcu};
    use std::sync::Mutex;

    /// A Tuya MCU served in lockstep at 115200 baud.
    fn tuya_server() -> PtyServer {
        let mcu = TuyaMcu::new(TuyaConfig {
            baud: Some(115_200),
            ..TuyaConfig::default()
        });
        PtyServer::start_lockstep(Arc::new(Mutex::new(mcu)), Faults::default()).expect("pty")
    }

    const HEARTBEAT: [u8; 7] = [0x55, 0xAA, 0x00, 0x00, 0x00, 0x00, 0xFF];
    const HEARTBEAT_ANSWER: [u8; 6] = [0x55, 0xAA, 0x03, 0x00, 0x00, 0x01];

    /// What `port` reads until a read by `by` finds nothing more.
    fn read_until_quiet(port: &mut dyn crate::link::Transport, by: Instant) -> Vec<u8> {
        let (mut got, mut buf) = (Vec::new(), [0u8; 256]);
        loop {
            let n = port.read(&mut buf, by).expect("reads");
            if n == 0 {
                return got;
            }
            got.extend_from_slice(&buf[..n]);
        }
    }

    /// The device answers while what the host wrote is not drained from the pty: on a loaded
    /// machine the kernel hands bytes in flight over late, and reading the master waits for it
    /// (seen: 9 s). Here the drain is stood still; the server loop, which drained the pty
    /// itself between two turns, stood still with it and the host had no answer (10 s past
    /// its deadline, the lockstep's limit).
    #[test]
    fn the_device_answers_while_the_hosts_bytes_are_not_drained_from_the_pty() {
        let server = tuya_server();
        let drain_held = server.flags.drain_gate.lock().expect("the gate");
        let mut port = (server.opener(115_200))().expect("opens");
        port.write(&HEARTBEAT).expect("writes the heartbeat");
        let got = read_until_quiet(port.as_mut(), Instant::now() + Duration::from_secs(1));
        drop(drain_held);
        assert!(
            got.windows(HEARTBEAT_ANSWER.len())
                .any(|w| w == HEARTBEAT_ANSWER),
            "no heartbeat answer with the drain stood still: {got:02x?}"
        );
    }

    /// The host has the device's answer while the pty has not handed it over: on a loaded
    /// machine the kernel's worker that moves bytes across ran up to 18 s late, and a host that
    /// read its port waited for it (seen: "read 631 of 10008 written", 18 s past the read's
    /// deadline). Here nothing is written to the pty while the gate is held; once it is let go,
    /// the copy crosses and agrees with what the host read.
    #[test]
    fn the_host_has_the_devices_answer_while_the_pty_has_not_handed_it_over() {
        let server = tuya_server();
        let copy_held = server.flags.copy_gate.lock().expect("the gate");
        let mut port = (server.opener(115_200))().expect("opens");
        port.write(&HEARTBEAT).expect("writes the heartbeat");
        let got = read_until_quiet(port.as_mut(), Instant::now() + Duration::from_secs(1));
        assert!(
            got.windows(HEARTBEAT_ANSWER.len())
                .any(|w| w == HEARTBEAT_ANSWER),
            "no heartbeat answer with the pty's copy held back: {got:02x?}"
        );
        drop(copy_held);
        let lockstep = server.lockstep.clone().expect("in lockstep");
        let deadline = Instant::now() + Duration::from_secs(30);
        while lockstep.lock().to_host_crossing.matched() < got.len() as u64 {
            assert!(Instant::now() < deadline, "the copy never crossed the pty");
            std::thread::sleep(Duration::from_millis(2));
        }
        assert_eq!(lockstep.lock().crossing_changed(), None);
    }

    /// A host's port that is not raw (here canonical mode with CR taken as a newline, as a
    /// terminal leaves it) fails the read, saying so: the host reads the device's bytes from the
    /// lockstep's record, which such a port would have changed or held back.
    #[test]
    fn a_host_port_left_in_canonical_mode_fails_its_reads_saying_so() {
        use nix::sys::termios::{InputFlags, LocalFlags, SetArg, tcgetattr, tcsetattr};
        let server = tuya_server();
        let mut port = (server.opener(115_200))().expect("opens");
        let side = std::fs::File::open(server.path()).expect("opens the pty for its settings");
        let mut t = tcgetattr(&side).expect("settings");
        t.local_flags.insert(LocalFlags::ICANON);
        t.input_flags.insert(InputFlags::ICRNL);
        tcsetattr(&side, SetArg::TCSANOW, &t).expect("cooked");
        port.write(&HEARTBEAT).expect("writes the heartbeat");
        let deadline = Instant::now() + Duration::from_secs(30);
        let mut buf = [0u8; 256];
        let said = loop {
            match port.read(&mut buf, Instant::now() + Duration::from_millis(50)) {
                Err(e) => break e.to_string(),
                Ok(_) => assert!(Instant::now() < deadline, "the reads never failed"),
            }
        };
        assert!(
            said.contains("host's port is not in raw mode (ICANON ICRNL on)"),
            "{said}"
        );
    }
}
