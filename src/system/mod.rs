//! What differs between operating systems, in one place, below the link: the serial ports the
//! OS lists and why a port cannot be opened (`ports.rs`), the USB adapter behind a port and its
//! latency timer ([`adapter`]: sysfs, read and set), and where the shipped example files
//! (presets, plans, profiles) are (`data.rs`), whether a window can be shown ([`display`]), and
//! how much freed memory the C heap keeps ([`heap`]).
//!
//! Verified on Linux (Debian 12) only. Elsewhere these files compile to the fallbacks under
//! `cfg(not(target_os = "linux"))`: port listing through the serialport crate (which has its own
//! Windows and macOS code), the OS's own words for an open failure, no latency timer, and the
//! example files next to the executable. A Windows or macOS build starts here.

pub mod adapter;
mod data;
pub mod display;
pub mod heap;
mod ports;

#[cfg(unix)]
pub use data::INSTALLED_DATA_DIR;
pub use data::{DATA_DIR_ENV, data_dir, presets_dir, shipped_or_given};
#[cfg(test)]
pub(crate) use ports::every_vanish_cause;
pub use ports::{
    Holder, PortInfo, holders, list_ports, missing_port, open_failure, other_readers, vanished,
};
