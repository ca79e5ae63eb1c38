//! Real serial ports (and pseudo-terminals) through the serialport crate.

use super::Opener;
use super::transport::{LinkError, Transport};
use crate::system::list_ports;
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
        let meta = std::fs::metadata(path).map_err(|e| open_err(e.to_string()))?;
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
            .open()
            .map_err(|e| open_err(crate::system::open_failure(path, &e)))?;
        Ok(Self {
            port,
            path: path.to_string(),
            baud,
            latency_timer: crate::system::adapter::adapter_of(path).latency_timer(),
        })
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
        LinkError::Disconnected(format!("{}: {e}", self.path))
    }
}

impl Transport for SerialTransport {
    fn write(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        self.port.write_all(bytes).map_err(|e| self.lost(&e))?;
        self.port.flush().map_err(|e| self.lost(&e))
    }

    fn read(&mut self, buf: &mut [u8], deadline: Instant) -> Result<usize, LinkError> {
        let now = Instant::now();
        // Zero is a poll: what has already arrived, without waiting.
        let wait = deadline.saturating_duration_since(now);
        if self.port.timeout() != wait {
            self.port
                .set_timeout(wait)
                .map_err(|e| LinkError::Setting(e.to_string()))?;
        }
        match self.port.read(buf) {
            Ok(0) => Err(LinkError::Disconnected(format!(
                "{}: end of file",
                self.path
            ))),
            Ok(n) => Ok(n),
            Err(e) if e.kind() == ErrorKind::TimedOut || e.kind() == ErrorKind::WouldBlock => Ok(0),
            Err(e) if e.kind() == ErrorKind::Interrupted => Ok(0),
            Err(e) => Err(self.lost(&e)),
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
            .map_err(|e| LinkError::Disconnected(format!("{}: {e}", self.path)))
    }

    fn describe(&self) -> String {
        self.path.clone()
    }

    fn latency_timer(&self) -> Option<Duration> {
        self.latency_timer
    }

    fn check(&mut self) -> Result<(), LinkError> {
        if std::path::Path::new(&self.path).exists() {
            Ok(())
        } else {
            Err(LinkError::Disconnected(format!(
                "{}: the port is gone",
                self.path
            )))
        }
    }
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
