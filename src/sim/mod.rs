//! Device simulators: the window cleaner, the solar cleanbot, a bus of servos and the Tuya vacuum
//! MCU. They keep state across commands and answer as the profiles say, with realistic timing and
//! optional faults. They serve the tests, the GUI's built-in demo device, and `botbench sim`.

use std::time::{Duration, Instant};

mod crossing;
pub mod fixture;
mod kind;
pub mod line;
pub mod lockstep;
pub mod msp_device;
pub mod process;
pub mod pty;
pub mod runner;
pub mod solar_cleanbot;
pub mod window_cleaner;

pub use fixture::SimFixture;
pub use kind::{SimKind, SimOptions, build, tuya_mcu};
pub use line::{Line, Split};
pub use pty::PtyServer;
pub use runner::{Faults, SharedDevice, SimTransport, VanishHandle};

/// A frame a device sends: `after` its cause has fully arrived (device latency), or, from
/// [`Device::tick`], after now.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Outgoing {
    /// Delay before the first byte leaves the device.
    pub after: Duration,
    /// The bytes.
    pub bytes: Vec<u8>,
    /// The baud rate they are sent at, when it differs from the request's (a servo that has just
    /// switched baud). A host listening at another rate receives garbage.
    pub baud: Option<u32>,
}

impl Outgoing {
    /// A frame sent `after` a delay, at the request's baud rate.
    pub fn new(after: Duration, bytes: Vec<u8>) -> Self {
        Self {
            after,
            bytes,
            baud: None,
        }
    }
}

/// A simulated device: bytes in, frames out. Wire timing and faults are the runner's business.
pub trait Device: Send {
    /// Bytes from the host have fully arrived at `now`, sent at `baud`. Returns what to send back.
    fn receive(&mut self, bytes: &[u8], baud: u32, now: Instant) -> Vec<Outgoing>;
    /// Called every few milliseconds: frames the device sends on its own.
    fn tick(&mut self, _now: Instant) -> Vec<Outgoing> {
        Vec::new()
    }
}

pub mod servo_bus;
pub mod tuya_mcu;
