//! Real serial ports (and pseudo-terminals) through the serialport crate.

use super::Opener;
use super::transport::{LinkError, Transport};
use crate::system::{Holder, list_ports, other_readers};
use serialport::SerialPort;
use std::io::{ErrorKind, Read, Write};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// A serial port or pseudo-terminal.
pub struct SerialTransport {
    port: Box<dyn SerialPort>,
    path: String,
    baud: u32,
    /// The adapter's latency timer, read when the port was opened.
    latency_timer: Option<Duration>,
    /// Reads the OS said bytes were ready for, that found none: another reader of the same port
    /// took them (see [`Transport::taken`]).
    taken: u64,
    /// The other programs that had the port open when it was last looked at, and when.
    holders: (Vec<Holder>, Option<Instant>),
    /// The USB serial number of the adapter, read when the port was opened: a port that
    /// vanishes is looked for under another name by it.
    usb_serial: Option<String>,
    /// The port's descriptor, to give up its exclusive use on close (Unix).
    #[cfg(unix)]
    fd: std::os::fd::RawFd,
}

impl Drop for SerialTransport {
    /// Gives up the exclusive use (TIOCNXCL and the `flock`) before the port closes. serialport's
    /// close does not, and both stay while any copy of the descriptor is open: a child process
    /// forked at that moment (by any thread of this program: a verdict's sound player, a test's
    /// `botbench` run) holds a copy until its exec closes it, and the next open of the same port
    /// (a reconnect, `msp` opening again with the profile the device called for) failed with
    /// "busy" (seen under load: capture_record, cli_explains).
    fn drop(&mut self) {
        #[cfg(unix)]
        release_exclusive(self.fd);
    }
}

impl std::fmt::Debug for SerialTransport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SerialTransport")
            .field("path", &self.path)
            .field("baud", &self.baud)
            .finish()
    }
}

impl SerialTransport {
    /// Opens `path` at `baud`, 8N1, exclusively.
    pub fn open(path: &str, baud: u32) -> Result<Self, LinkError> {
        let open_err = |reason: String| LinkError::Open {
            path: path.to_string(),
            reason,
        };
        let meta = std::fs::metadata(path).map_err(|e| match e.kind() {
            std::io::ErrorKind::NotFound => {
                open_err(crate::system::missing_port(path, &e.to_string()))
            }
            _ => open_err(e.to_string()),
        })?;
        #[cfg(unix)]
        {
            use std::os::unix::fs::FileTypeExt;
            if !meta.file_type().is_char_device() {
                return Err(open_err(
                    "not a serial port (not a character device)".into(),
                ));
            }
        }
        #[cfg(not(unix))]
        let _ = meta;
        let port = serialport::new(path, baud)
            .timeout(Duration::from_millis(10))
            .open_native()
            .map_err(|e| open_err(crate::system::open_failure(path, &e)))?;
        non_blocking(&port).map_err(|e| open_err(format!("non-blocking reads: {e}")))?;
        #[cfg(unix)]
        let fd = std::os::fd::AsRawFd::as_raw_fd(&port);
        let mut t = Self {
            port: Box::new(port),
            path: path.to_string(),
            baud,
            latency_timer: crate::system::adapter::adapter_of(path).latency_timer(),
            taken: 0,
            holders: (Vec::new(), None),
            usb_serial: Self::usb_serial_of(path),
            #[cfg(unix)]
            fd,
        };
        let others = t.holders_now();
        if !others.is_empty() {
            log::warn!(
                "{path} is also open in {}: it may take the device's answers",
                Holder::list(&others)
            );
        }
        Ok(t)
    }

    /// The other programs that have the port open, looked up at most every
    /// [`HOLDERS_EVERY`] (a scan of `/proc` costs milliseconds).
    fn holders_now(&mut self) -> Vec<Holder> {
        let fresh = self
            .holders
            .1
            .is_some_and(|at| at.elapsed() < HOLDERS_EVERY);
        if !fresh {
            self.holders = (other_readers(&self.path), Some(Instant::now()));
        }
        self.holders.0.clone()
    }

    /// The USB serial number of the adapter at `path`, where the OS gives one.
    pub fn usb_serial_of(path: &str) -> Option<String> {
        list_ports()
            .into_iter()
            .find(|p| p.path == path)
            .and_then(|p| p.serial_number)
    }

    /// The path of the port whose USB serial number is `sn`.
    pub fn path_of_usb_serial(sn: &str) -> Option<String> {
        list_ports()
            .into_iter()
            .find(|p| p.serial_number.as_deref() == Some(sn))
            .map(|p| p.path)
    }

    fn lost(&self, e: &std::io::Error) -> LinkError {
        self.gone(&e.to_string())
    }

    /// The port is lost (`what` happened): its path, what happened and, where one is seen, the
    /// likely cause ([`crate::system::vanished`]).
    fn gone(&self, what: &str) -> LinkError {
        let mut why = format!("{}: {what}", self.path);
        if let Some(cause) = crate::system::vanished(&self.path, self.usb_serial.as_deref()) {
            why.push_str(&format!(" — {cause}"));
        }
        LinkError::Disconnected(why)
    }
}

impl Transport for SerialTransport {
    /// Writes every byte; a port that takes none for [`WRITE_STALL`] is lost (the port is
    /// non-blocking: a full output buffer is waited on, never blocked in). What the port takes
    /// at once is written without a poll ([`write_now`]); only a full buffer is polled for.
    fn write(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        let mut rest = bytes;
        let mut stalled_since: Option<Instant> = None;
        while !rest.is_empty() {
            #[cfg(unix)]
            match write_now(self.fd, rest) {
                Ok(n) if n > 0 => {
                    rest = &rest[n..];
                    stalled_since = None;
                    continue;
                }
                Ok(_) => {}
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::Interrupted) => {}
                Err(e) => return Err(self.lost(&e)),
            }
            if self.port.timeout() != WRITE_STALL {
                self.port
                    .set_timeout(WRITE_STALL)
                    .map_err(|e| LinkError::Setting(e.to_string()))?;
            }
            match self.port.write(rest) {
                Ok(0) => return Err(self.gone("write")),
                Ok(n) => {
                    rest = &rest[n..];
                    stalled_since = None;
                }
                Err(e)
                    if matches!(
                        e.kind(),
                        ErrorKind::TimedOut | ErrorKind::WouldBlock | ErrorKind::Interrupted
                    ) =>
                {
                    let since = *stalled_since.get_or_insert_with(Instant::now);
                    if since.elapsed() >= WRITE_STALL {
                        return Err(LinkError::Disconnected(format!(
                            "{}: the port took no byte; waited {} ms",
                            self.path,
                            WRITE_STALL.as_millis()
                        )));
                    }
                }
                Err(e) => return Err(self.lost(&e)),
            }
        }
        self.port.flush().map_err(|e| self.lost(&e))
    }

    /// Waits for bytes until `deadline` at most (the OS's poll), then reads them without
    /// blocking: when another reader of the port took them in between, the read finds none,
    /// counts it ([`Transport::taken`]) and waits on, never past `deadline`.
    fn read(&mut self, buf: &mut [u8], deadline: Instant) -> Result<usize, LinkError> {
        loop {
            // Zero is a poll: what has already arrived, without waiting.
            let wait = deadline.saturating_duration_since(Instant::now());
            if self.port.timeout() != wait {
                self.port
                    .set_timeout(wait)
                    .map_err(|e| LinkError::Setting(e.to_string()))?;
            }
            match self.port.read(buf) {
                Ok(0) => return Err(self.gone("end of file")),
                Ok(n) => return Ok(n),
                Err(e) if e.kind() == ErrorKind::TimedOut => return Ok(0),
                // The port said bytes were there, and they were gone: someone else read them.
                Err(e) if e.kind() == ErrorKind::WouldBlock => {
                    self.taken += 1;
                    if wait.is_zero() {
                        return Ok(0);
                    }
                }
                Err(e) if e.kind() == ErrorKind::Interrupted => {
                    if wait.is_zero() {
                        return Ok(0);
                    }
                }
                Err(e) => return Err(self.lost(&e)),
            }
        }
    }

    fn set_baud(&mut self, baud: u32) -> Result<(), LinkError> {
        self.port
            .set_baud_rate(baud)
            .map_err(|e| LinkError::Setting(format!("baud {baud}: {e}")))?;
        self.baud = baud;
        Ok(())
    }

    fn baud(&self) -> u32 {
        self.baud
    }

    fn clear_input(&mut self) -> Result<(), LinkError> {
        self.port
            .clear(serialport::ClearBuffer::Input)
            .map_err(|e| self.gone(&e.to_string()))
    }

    fn describe(&self) -> String {
        self.path.clone()
    }

    fn latency_timer(&self) -> Option<Duration> {
        self.latency_timer
    }

    fn taken(&self) -> u64 {
        self.taken
    }

    fn others_reading(&mut self) -> Vec<Holder> {
        self.holders_now()
    }

    /// DTR, then RTS. A pseudo-terminal has no modem lines: there the request is taken as done
    /// (a simulator served on one plays the board).
    fn set_lines(&mut self, dtr: Option<bool>, rts: Option<bool>) -> Result<(), LinkError> {
        let pty = self.path.starts_with("/dev/pts/");
        if let Some(on) = dtr
            && let Err(e) = self.port.write_data_terminal_ready(on)
            && !pty
        {
            return Err(super::lines::line_error("DTR", on, e));
        }
        if let Some(on) = rts
            && let Err(e) = self.port.write_request_to_send(on)
            && !pty
        {
            return Err(super::lines::line_error("RTS", on, e));
        }
        Ok(())
    }

    fn check(&mut self) -> Result<(), LinkError> {
        if std::path::Path::new(&self.path).exists() {
            Ok(())
        } else {
            Err(self.gone("the port is gone"))
        }
    }
}

/// How long a write may find the port taking no byte before the port counts as lost.
const WRITE_STALL: Duration = Duration::from_secs(2);
/// How often the other programs holding the port are looked up again.
const HOLDERS_EVERY: Duration = Duration::from_secs(1);

/// Makes reads from `port` non-blocking (Unix: `O_NONBLOCK`): the serialport crate polls before
/// it reads, and a blocking read after the poll said bytes were ready would wait forever when
/// another reader of the same port took them. Reads still wait, in the poll, until their
/// deadline. Elsewhere (Windows: reads end at the port's timeout) nothing is needed.
///
/// One of the crate's two `unsafe` blocks (with [`close_on_exec`]): serialport gives the
/// descriptor only as a raw one.
#[cfg(unix)]
#[allow(unsafe_code)]
pub(crate) fn non_blocking(port: &serialport::TTYPort) -> std::io::Result<()> {
    use std::os::fd::AsRawFd;
    let fd = port.as_raw_fd();
    // SAFETY: `fd` is the open descriptor `port` owns for as long as this call; F_GETFL and
    // F_SETFL read and set its status flags only.
    let flags = unsafe { libc::fcntl(fd, libc::F_GETFL) };
    if flags < 0 {
        return Err(std::io::Error::last_os_error());
    }
    // SAFETY: as above.
    if unsafe { libc::fcntl(fd, libc::F_SETFL, flags | libc::O_NONBLOCK) } < 0 {
        return Err(std::io::Error::last_os_error());
    }
    Ok(())
}

/// Marks descriptor `fd` close-on-exec, so that no program this process starts inherits it.
/// serialport opens a port so, but not the two sides of a pseudo-terminal pair
/// (`TTYPort::pair`): without this, every child process started while a simulator serves (a
/// test's `botbench` run, any program a user starts from a host with a simulator) holds the
/// simulator's pty open and looks like another reader of the port.
#[cfg(unix)]
#[allow(unsafe_code)]
pub fn close_on_exec(fd: std::os::fd::RawFd) -> std::io::Result<()> {
    // SAFETY: the caller passes a descriptor it owns and keeps open for this call; F_GETFD and
    // F_SETFD read and set its descriptor flags only.
    let flags = unsafe { libc::fcntl(fd, libc::F_GETFD) };
    if flags < 0 {
        return Err(std::io::Error::last_os_error());
    }
    // SAFETY: as above.
    if unsafe { libc::fcntl(fd, libc::F_SETFD, flags | libc::FD_CLOEXEC) } < 0 {
        return Err(std::io::Error::last_os_error());
    }
    Ok(())
}

#[cfg(not(unix))]
pub(crate) fn non_blocking(_port: &serialport::COMPort) -> std::io::Result<()> {
    Ok(())
}

/// Opens `path`, and after a loss reopens it by path, or by the adapter's USB serial number when
/// the OS gave the port a new path.
pub fn opener(path: &str, baud: u32) -> Opener {
    let path = path.to_string();
    let usb_serial = SerialTransport::usb_serial_of(&path);
    Box::new(move || {
        let first = SerialTransport::open(&path, baud);
        let t = match (first, &usb_serial) {
            (Ok(t), _) => t,
            (Err(e), Some(sn)) => match SerialTransport::path_of_usb_serial(sn) {
                Some(p) => SerialTransport::open(&p, baud)?,
                None => return Err(e),
            },
            (Err(e), None) => return Err(e),
        };
        Ok(Box::new(t) as Box<dyn Transport>)
    })
}

/// Makes the [`Opener`] of a port named by its path, at a baud rate.
type OpenPort = dyn Fn(&str, u32) -> Opener + Send + Sync;

/// How the window and the command line open the port a user names by its path: the system's
/// serial ports ([`PortOpener::system`], through [`opener`]), except the paths a caller serves
/// itself ([`PortOpener::with_port`]: a test's simulator, served in lockstep with the link on a
/// pseudo-terminal). Handed to `ui::App::new` and `cli::main`; cheap to clone.
#[derive(Clone)]
pub struct PortOpener(Arc<OpenPort>);

impl PortOpener {
    /// The system's serial ports and pseudo-terminals, by path ([`opener`]).
    pub fn system() -> Self {
        Self(Arc::new(opener))
    }

    /// The opener of `path` at `baud` (nothing is opened until it is called).
    pub fn open(&self, path: &str, baud: u32) -> Opener {
        (self.0)(path, baud)
    }

    /// `self`, except that `path` is opened by `open` (given the baud rate): a port this process
    /// serves itself.
    pub fn with_port(
        self,
        path: impl Into<String>,
        open: impl Fn(u32) -> Opener + Send + Sync + 'static,
    ) -> Self {
        let served = path.into();
        Self(Arc::new(move |path: &str, baud: u32| {
            if path == served {
                open(baud)
            } else {
                self.open(path, baud)
            }
        }))
    }
}

impl Default for PortOpener {
    fn default() -> Self {
        Self::system()
    }
}

impl std::fmt::Debug for PortOpener {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("PortOpener")
    }
}

/// Writes what the port takes of `bytes` at once (the descriptor is non-blocking: a full
/// output buffer is `WouldBlock`); returns how many it took.
///
/// Not through serialport's write, which polls the port first: on Linux a poll of a terminal
/// with no input waiting waits for the kernel's worker to hand over bytes in flight
/// (`n_tty_poll` calls `tty_buffer_flush_work`), and on a machine loaded with CPU-bound work
/// that worker was seen to run more than 10 s late (tests on pseudo-terminals, 6 at once beside
/// two CPU-bound loops: a Tuya handshake step "not done within 10 s" in every one of them at
/// the same moment, while a thread that only slept was never more than 24 ms late). A write
/// needs to wait only when the buffer is full.
#[cfg(unix)]
#[allow(unsafe_code)]
fn write_now(fd: std::os::fd::RawFd, bytes: &[u8]) -> std::io::Result<usize> {
    // SAFETY: `fd` is the open descriptor of the port this transport owns for as long as this
    // call; `bytes` is valid for reads of its length, and write(2) only reads it.
    let n = unsafe { libc::write(fd, bytes.as_ptr().cast(), bytes.len()) };
    usize::try_from(n).map_err(|_| std::io::Error::last_os_error())
}

/// Gives up the exclusive use serialport took at open on `fd`: the terminal's exclusive mode
/// (TIOCNXCL) and the exclusive `flock`, which belongs to the open file and so lives on in every
/// copy of the descriptor. Errors (a port already gone) are of no consequence: the descriptor
/// is closed next.
#[cfg(unix)]
#[allow(unsafe_code)]
fn release_exclusive(fd: std::os::fd::RawFd) {
    // SAFETY: `fd` is the open descriptor of the port this transport owns until after this
    // call; TIOCNXCL takes no argument and changes only the terminal's exclusive flag, LOCK_UN
    // only the advisory lock of its open file.
    unsafe {
        let _ = libc::ioctl(fd, libc::TIOCNXCL);
        let _ = libc::flock(fd, libc::LOCK_UN);
    }
}

#[cfg(all(test, unix))]
mod tests {
    use super::SerialTransport;
    use serialport::SerialPort;

    /// A copy of the port's descriptor that outlives the transport (as a child forked at that
    /// moment holds one until its exec) must not make the next open of the port "busy".
    #[test]
    #[allow(unsafe_code)]
    fn a_port_closed_while_a_copy_of_its_descriptor_lives_can_be_opened_again() {
        let (_master, slave) = serialport::TTYPort::pair().expect("a pty pair");
        let path = slave.name().expect("the pty's path");
        drop(slave);
        let first = SerialTransport::open(&path, 115_200).expect("the first open");
        // SAFETY: duplicates a descriptor the transport holds open; the copy is closed below.
        let copy = unsafe { libc::dup(first.fd) };
        assert!(copy >= 0, "dup: {}", std::io::Error::last_os_error());
        drop(first);
        let again = SerialTransport::open(&path, 115_200);
        // SAFETY: closes the copy made above, once.
        unsafe { libc::close(copy) };
        assert!(again.is_ok(), "{:?}", again.err());
    }
}
