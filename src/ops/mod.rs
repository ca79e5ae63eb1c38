//! Operations that take several exchanges (verified writes, scans, provisioning, firmware
//! upload). They run on the calling thread over a [`crate::link::Client`], report progress and
//! stop when cancelled, so the command line runs them directly and the GUI on a job thread.

pub mod msp;
pub mod provision;
pub mod selftest;
pub mod servo;
pub mod servo_monitor;
pub mod servo_preset;
pub mod tuya;

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
    /// What is happening now.
    pub message: String,
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
