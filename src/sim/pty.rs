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
        let thread_lockstep = lockstep.clone();
        let thread = std::thread::Builder::new()
            .name("sim-pty".into())
            .spawn(move || {
                match &thread_lockstep {
                    None => serve(master, wire, &thread_flags),
                    Some(l) => serve_lockstep(master, wire, &thread_flags, l),
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
/// ([`write_unpolled`]).
fn serve_lockstep(master: TTYPort, wire: Wire, flags: &Arc<Flags>, lockstep: &Arc<Lockstep>) {
    // However the loop ends (a panicking device too), the host stops waiting for it, and only
    // once the pty's master side is closed (the loop and the drain own it): a host told that
    // nothing more comes while the port still looked open would take a vanished port for a
    // silent device.
    let stopped = lockstep.serving();
    let drain = start_drain(&master, flags, lockstep);
    serve_lockstep_loop(master, wire, flags, lockstep);
    flags.served.store(true, Ordering::SeqCst);
    if let Some(drain) = drain {
        let _ = drain.join();
    }
    drop(stopped);
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
                s.wrote(n, first, wire.last_seen().unwrap_or(now));
                due.extend_from_slice(&out[..n]);
            }
            s.next_due = wire.next_due();
            (now, now < real, s.generation())
        };
        if !due.is_empty() {
            let Some(written) = write_unpolled(fd, &due) else {
                return;
            };
            if written < due.len() {
                lockstep.lock().dropped(due.len() - written);
            }
        }
        // Held back by the host, the device waits for it to act or begin a call; else until
        // its next event. Either way the host's signal wakes it, and a stop is seen within POLL.
        let wait = if held_back {
            POLL
        } else {
            let next = wire.next_event().min(now + POLL);
            next.saturating_duration_since(Instant::now())
        };
        lockstep.wait_for_host(generation, wait);
    }
}

/// Writes `bytes` to the pty's master side (non-blocking) without polling it first (see
/// [`serve_lockstep`]): what finds no room is retried for up to [`WRITE_TIMEOUT`]. Returns how
/// many bytes were written, `None` when the pty failed (the port vanished).
fn write_unpolled(master: std::os::fd::BorrowedFd<'_>, bytes: &[u8]) -> Option<usize> {
    let deadline = Instant::now() + WRITE_TIMEOUT;
    let mut rest = bytes;
    while !rest.is_empty() {
        match nix::unistd::write(master, rest) {
            Ok(0) => break,
            Ok(n) => rest = &rest[n..],
            Err(nix::errno::Errno::EINTR) => {}
            Err(nix::errno::Errno::EAGAIN) if Instant::now() < deadline => {
                std::thread::sleep(Duration::from_millis(1));
            }
            Err(nix::errno::Errno::EAGAIN) => break,
            Err(_) => return None,
        }
    }
    Some(bytes.len() - rest.len())
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
                let before = s.crossing.changed().is_some();
                s.crossing.pty_delivered(&drained[..n]);
                if let (false, Some(changed)) = (before, s.crossing.changed()) {
                    eprintln!("lockstep: {changed}");
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::tuya_mcu::{TuyaConfig, TuyaMcu};
    use std::sync::Mutex;

    /// The device answers while what the host wrote is not drained from the pty: on a loaded
    /// machine the kernel hands bytes in flight over late, and reading the master waits for it
    /// (seen: 9 s). Here the drain is stood still; the server loop, which drained the pty
    /// itself between two turns, stood still with it and the host had no answer (10 s past
    /// its deadline, the lockstep's limit).
    #[test]
    fn the_device_answers_while_the_hosts_bytes_are_not_drained_from_the_pty() {
        let mcu = TuyaMcu::new(TuyaConfig {
            baud: Some(115_200),
            ..TuyaConfig::default()
        });
        let server =
            PtyServer::start_lockstep(Arc::new(Mutex::new(mcu)), Faults::default()).expect("pty");
        let drain_held = server.flags.drain_gate.lock().expect("the gate");
        let mut port = (server.opener(115_200))().expect("opens");
        port.write(&[0x55, 0xAA, 0x00, 0x00, 0x00, 0x00, 0xFF])
            .expect("writes the heartbeat");
        let by = Instant::now() + Duration::from_secs(1);
        let (mut got, mut buf) = (Vec::new(), [0u8; 256]);
        loop {
            let n = port.read(&mut buf, by).expect("reads");
            if n == 0 {
                break;
            }
            got.extend_from_slice(&buf[..n]);
        }
        drop(drain_held);
        let answer = [0x55, 0xAA, 0x03, 0x00, 0x00, 0x01];
        assert!(
            got.windows(answer.len()).any(|w| w == answer),
            "no heartbeat answer with the drain stood still: {got:02x?}"
        );
    }
}
