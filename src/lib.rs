//! botbench: tune, provision and test serial-connected robots at the bench and on the line.
//!
//! One crate, a library and the `botbench` binary (window and command line). Four kinds of device
//! share one serial port: the MSP window-cleaning robot and solar-panel cleaning robot, UART bus
//! servos, and a Tuya robot-vacuum MCU, for which botbench plays the Wi-Fi module.
//!
//! The house, bottom up (a module uses only those above it in this list; `tests/it/layers.rs`
//! keeps it so, and the README's "Architecture" section says why this order):
//!
//! - [`protocol`]: pure codecs, one streaming decoder engine; no I/O, no panics on any input.
//! - [`i18n`]: the two languages (`Lang`, `Key`, `Text`) and the bundled CJK font.
//! - [`system`]: what differs between operating systems (port listing, the USB adapter's
//!   latency timer, why a port cannot be opened, where the shipped examples are), behind `cfg`.
//! - [`series`]: bounded telemetry ring buffers, decimation, CSV.
//! - [`document`]: RON documents a person writes (presets, plans): reading, located errors,
//!   atomic saves.
//! - [`profile`]: every device fact as data (RON profiles under `assets/profiles/`), the one
//!   field codec, validation and roles that code asks for.
//! - [`packet`]: a frame of any protocol as a person reads it; [`preset`]: the preset document.
//! - [`link`]: the worker thread that owns the port, its deadlines, polling and the protocol
//!   sessions (MSP identify, Tuya handshake); [`link::Client`] for blocking callers;
//!   [`link::PortOpener`], how a port named by its path is opened.
//! - [`ops`]: every operation of several exchanges (tuning, scans, provisioning, self-test, OTA),
//!   run by the command line directly and by the window on a job thread.
//! - [`sim`]: device simulators on a simulated wire or a pseudo-terminal, including the field's
//!   misbehaviour; [`capture`]: recording a session to pcapng, and replaying it.
//! - [`bench`]: end-to-end figures; [`ui`]: the eframe window; [`cli`]: the command line.
//!
//! The window never touches the port: panels return actions, the app turns them into link
//! commands and jobs, and the worker answers with events over bounded channels.

/// The build: `0.1.0 (1a2b3c4d5)`, the crate's version and the git commit it was built from
/// (`unknown` outside git; see `build.rs`). `botbench --version` prints it.
pub const VERSION: &str = concat!(
    env!("CARGO_PKG_VERSION"),
    " (",
    env!("BOTBENCH_COMMIT"),
    ")"
);

pub mod bench;
pub mod capture;
pub mod cli;
pub mod document;
pub mod i18n;
pub mod link;
pub mod ops;
pub mod packet;
pub mod preset;
pub mod profile;
pub mod protocol;
pub mod series;
pub mod sim;
pub mod system;
pub mod ui;
