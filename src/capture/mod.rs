//! Capture and replay (issue 16): a port session recorded to a pcapng file ([`Capture`]), read
//! back ([`read_path`]), decoded with its profile ([`decode`]), and served again as a simulated
//! device ([`ReplayDevice`]). The file format is described in [`format`].

pub mod decode;
pub mod format;
pub mod record;
pub mod replay;

pub use decode::{CapturedFrame, frames};
pub use format::{CaptureFile, CaptureInfo, Chunk, read, read_path, write_chunks};
pub use record::{Capture, CaptureSummary, QUEUE_CHUNKS, Tap};
pub use replay::{ReplayDevice, ReplayStats};

/// What went wrong with a capture file.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CaptureError {
    /// The file could not be created or opened.
    #[error("cannot open capture {path}: {reason}")]
    Open {
        /// The file's path.
        path: String,
        /// What the OS said.
        reason: String,
    },
    /// Writing failed (the disk full, the file gone): recording stopped there.
    #[error("cannot write the capture: {0}")]
    Write(String),
    /// The file is not a capture botbench can read.
    #[error("not a botbench capture: {0}")]
    Format(String),
}

impl CaptureError {
    pub(crate) fn write(e: impl std::fmt::Display) -> Self {
        Self::Write(e.to_string())
    }

    /// The same error, naming the file.
    pub(crate) fn in_file(self, path: &std::path::Path) -> Self {
        match self {
            Self::Format(m) => Self::Format(format!("{}: {m}", path.display())),
            other => other,
        }
    }
}
