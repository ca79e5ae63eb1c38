//! A simulated device served on a pseudo-terminal: a client opens [`PtyServer::path`] as it
//! would open a USB serial adapter.

use super::runner::{Faults, SharedDevice, VanishHandle, Wire, sleep_until};
use crate::link::LinkError;
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
}

/// A device on a pseudo-terminal, served by a named thread until stopped or dropped.
pub struct PtyServer {
    path: String,
    device: SharedDevice,
    flags: Arc<Flags>,
    thread: Option<JoinHandle<()>>,
    /// Held open so that the path stays valid between clients.
    _slave: TTYPort,
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
        let open_err = |reason: String| LinkError::Open {
            path: "pseudo-terminal".into(),
            reason,
        };
        faults.check().map_err(open_err)?;
        let (master, slave) = TTYPort::pair().map_err(|e| open_err(e.to_string()))?;
        let path = slave
            .name()
            .ok_or_else(|| open_err("the pseudo-terminal has no path".into()))?;
        let baud = master.baud_rate().unwrap_or(9600);
        let flags = Arc::new(Flags::default());
        let wire = Wire::new(device.clone(), baud, faults);
        let thread_flags = flags.clone();
        let thread = std::thread::Builder::new()
            .name("sim-pty".into())
            .spawn(move || {
                serve(master, wire, &thread_flags);
                thread_flags.exited.store(true, Ordering::SeqCst);
            })
            .map_err(|e| open_err(format!("cannot start the server thread: {e}")))?;
        Ok(PtyServer {
            path,
            device,
            flags,
            thread: Some(thread),
            _slave: slave,
        })
    }

    /// The path a client opens, e.g. `/dev/pts/7`.
    pub fn path(&self) -> &str {
        &self.path
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
            if !write_frame(&mut master, &out[..n]) {
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

/// Writes bytes that have arrived; `false` when the port is gone. A frame nobody makes room for is dropped.
fn write_frame(master: &mut TTYPort, frame: &[u8]) -> bool {
    if master.set_timeout(WRITE_TIMEOUT).is_err() {
        return false;
    }
    let mut rest = frame;
    while !rest.is_empty() {
        match master.write(rest) {
            Ok(0) => return true,
            Ok(n) => rest = &rest[n..],
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(e) if e.kind() == ErrorKind::TimedOut => return true,
            Err(_) => return false,
        }
    }
    true
}
