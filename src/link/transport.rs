//! The byte pipe under the link: a serial port, a pseudo-terminal, or an in-process simulator.

use std::time::{Duration, Instant};

/// Why the link failed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum LinkError {
    /// The port could not be opened (missing, not a serial port, in use, no permission).
    #[error("cannot open {path}: {reason}")]
    Open {
        /// The port's path.
        path: String,
        /// What the OS said.
        reason: String,
    },
    /// The port went away (an adapter unplugged, a pty closed).
    #[error("port disconnected: {0}")]
    Disconnected(String),
    /// The port refused a setting.
    #[error("port setting refused: {0}")]
    Setting(String),
}

/// A byte pipe with deadlines. Implementations: [`super::serial::SerialTransport`] and the
/// in-process simulator transport of `sim`.
pub trait Transport: Send {
    /// Writes all bytes.
    fn write(&mut self, bytes: &[u8]) -> Result<(), LinkError>;
    /// Reads what arrives, waiting until `deadline` at most for the first byte; `Ok(0)` when
    /// nothing arrived in time.
    fn read(&mut self, buf: &mut [u8], deadline: Instant) -> Result<usize, LinkError>;
    /// Changes the baud rate.
    fn set_baud(&mut self, baud: u32) -> Result<(), LinkError>;
    /// The current baud rate.
    fn baud(&self) -> u32;
    /// Drops bytes received and not yet read.
    fn clear_input(&mut self) -> Result<(), LinkError>;
    /// A short description for the status bar: the path, or `simulated window cleaner`.
    fn describe(&self) -> String;
    /// The USB adapter's latency timer (how long it holds received bytes before handing them
    /// over), where it is known ([`crate::system::adapter`]).
    fn latency_timer(&self) -> Option<Duration> {
        None
    }
    /// How many times, since the port was opened, the OS said bytes had arrived and they were
    /// gone when read: another reader of the same port (a second botbench, a terminal program,
    /// ModemManager) took them. Only a real port can tell; 0 elsewhere.
    fn taken(&self) -> u64 {
        0
    }
    /// The other programs that have the port open (Linux, those this user may see), looked up
    /// at most once a second: who may be taking its bytes.
    fn others_reading(&mut self) -> Vec<crate::system::Holder> {
        Vec::new()
    }
    /// Checks, while idle, that the port is still there (a USB adapter unplugged).
    fn check(&mut self) -> Result<(), LinkError> {
        Ok(())
    }
    /// When the last byte the last read returned had arrived, where the port knows it (a pty
    /// served in lockstep knows when each byte was due); `None`: when the read returned, all a
    /// real port can say. The link measures an answer's latency to this instant, so that a
    /// host thread that gets to its read late (a loaded machine) does not count its own delay
    /// as the device's, where that can be known.
    fn arrived_at(&self) -> Option<Instant> {
        None
    }
    /// When the last write's bytes started on the wire, where the port knows it (a pty served in
    /// lockstep stamps each write with the instant the device hears it from); `None`: when the
    /// write returned, all a real port can say. The link counts the answer's deadline from this
    /// instant, so that a host thread held up before or in its write does not stretch the
    /// device's time to answer, where that can be known.
    fn written_at(&self) -> Option<Instant> {
        None
    }
    /// Sets the modem lines right after the port opened: DTR and RTS asserted (`Some(true)`),
    /// cleared (`Some(false)`) or left as they are (`None`). Only a real port has them; a
    /// simulator takes it as done. Errors: the port refused ([`LinkError::Setting`]).
    fn set_lines(&mut self, dtr: Option<bool>, rts: Option<bool>) -> Result<(), LinkError> {
        let _ = (dtr, rts);
        Ok(())
    }
}

/// How long `bytes` bytes take on the wire at `baud` (8N1: 10 bits a byte).
pub fn wire_time(bytes: usize, baud: u32) -> Duration {
    let baud = u64::from(baud.max(1));
    Duration::from_nanos(bytes as u64 * 10 * 1_000_000_000 / baud)
}
