//! Every operation that takes several exchanges (verified writes, scans, provisioning, presets,
//! self-tests, firmware upload) is written here once, whoever starts it. Operations run on the
//! calling thread over a [`crate::link::Client`], report progress and stop when cancelled, so the
//! command line runs them directly and the GUI on a job thread. Requests the GUI sends without
//! waiting (controls, STOP, data points) are built here too, checked against the profile.
//!
//! - [`exchange`]: the protocol-neutral pieces (send, read as [`FieldValues`], verified write,
//!   a checked request); [`error`]: [`OpError`].
//! - [`device`] (MSP ping, identity, power state), [`tuning`] (batches of reads and verified
//!   writes), [`telemetry`] (what is polled), [`preset`] (capture, read, apply).
//! - [`stop`]: the profile's STOP (motors, fan, spray off), for the window's STOP button and
//!   the self-test's safe state.
//! - [`servo`] (scan, parameters, id / baud / reset, motion, production provisioning, parameter
//!   presets), [`selftest`] (the window cleaner's production test), [`tuya`] (data points,
//!   status query, OTA).

pub mod device;
pub mod error;
pub mod exchange;
pub mod preset;
pub mod selftest;
pub mod servo;
pub mod stop;
pub mod telemetry;
pub mod tuning;
pub mod tuya;

pub use error::OpError;
pub use exchange::{Check, FieldValues};

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// A cancel flag shared with whoever may cancel.
#[derive(Debug, Clone, Default)]
pub struct Cancel(Arc<AtomicBool>);

impl Cancel {
    /// A flag not yet raised.
    pub fn new() -> Self {
        Self::default()
    }

    /// Raises the flag.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether it was raised.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

/// Progress of a long operation: done out of total, and what it is doing.
#[derive(Debug, Clone, PartialEq)]
pub struct Progress {
    /// Steps done.
    pub done: u64,
    /// Steps in all.
    pub total: u64,
    /// What is happening now, in both languages (the command line prints the English).
    pub message: crate::i18n::Text,
}

impl Progress {
    /// The fraction done, 0 to 1.
    pub fn fraction(&self) -> f32 {
        if self.total == 0 {
            0.0
        } else {
            (self.done as f64 / self.total as f64).min(1.0) as f32
        }
    }
}
