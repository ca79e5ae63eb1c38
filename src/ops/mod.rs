//! Every operation that takes several exchanges (verified writes, scans, provisioning, presets,
//! self-tests, firmware upload) is written here once, whoever starts it. Operations run on the
//! calling thread over a [`crate::link::Client`], report progress and stop when cancelled, so the
//! command line runs them directly and the GUI on a job thread. Requests the GUI sends without
//! waiting (controls, STOP, data points) are built here too, checked against the profile.
//!
//! Two contexts go into every operation: the [`Device`] it works on (the link's client and the
//! device's profile) and, for a long one, its [`Run`] (the cancel flag and where progress goes).
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
//! - [`station`]: the line station: its bundle, line plans and the slot runner.

pub mod device;
pub mod error;
pub mod exchange;
pub mod preset;
pub mod records;
pub mod selftest;
pub mod servo;
pub mod station;
pub mod stop;
pub mod telemetry;
pub mod tuning;
pub mod tuya;

pub use error::OpError;
pub use exchange::{Check, FieldValues};

use crate::link::Client;
use crate::profile::Profile;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// The device an operation works on: the link's blocking [`Client`] (each request waits for its
/// own answer) and the device's [`Profile`] (its commands, fields, ranges and roles). Copied
/// into an operation and each of its steps, instead of the two apart.
#[derive(Debug, Clone, Copy)]
pub struct Device<'a> {
    /// The link to the device.
    pub client: &'a Client,
    /// What the device is.
    pub profile: &'a Profile,
}

impl<'a> Device<'a> {
    /// The device behind `client`, described by `profile`.
    pub fn new(client: &'a Client, profile: &'a Profile) -> Self {
        Self { client, profile }
    }
}

/// One run of a long operation: the flag that cancels it (looked at between its steps) and
/// where it reports how far it got (`P`: a [`Progress`], or what a step of its own reports,
/// e.g. a scan's ids swept).
pub struct Run<'a, P = Progress> {
    cancel: &'a Cancel,
    progress: Box<dyn FnMut(P) + 'a>,
}

impl<'a, P> Run<'a, P> {
    /// A run cancelled by `cancel`, reporting to `progress`.
    pub fn new(cancel: &'a Cancel, progress: impl FnMut(P) + 'a) -> Self {
        Self {
            cancel,
            progress: Box::new(progress),
        }
    }

    /// A run cancelled by `cancel` whose progress nobody follows.
    pub fn quiet(cancel: &'a Cancel) -> Self {
        Self::new(cancel, |_| {})
    }

    /// Whether it was cancelled.
    pub fn is_cancelled(&self) -> bool {
        self.cancel.is_cancelled()
    }

    /// Its cancel flag, for a step that reports progress of another kind ([`Run::new`]).
    pub fn cancel_flag(&self) -> &'a Cancel {
        self.cancel
    }

    /// Reports how far it got.
    pub fn report(&mut self, progress: P) {
        (self.progress)(progress);
    }

    /// [`OpError::Cancelled`] once it was cancelled: the operation stops between two steps.
    pub fn go_on(&self) -> Result<(), OpError> {
        if self.is_cancelled() {
            Err(OpError::Cancelled)
        } else {
            Ok(())
        }
    }
}

impl<P> std::fmt::Debug for Run<'_, P> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Run")
            .field("cancelled", &self.is_cancelled())
            .finish_non_exhaustive()
    }
}

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
