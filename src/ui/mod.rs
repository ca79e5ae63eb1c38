//! The desktop window (eframe/egui): one file (or folder) per panel. Panels draw from the
//! run-time state ([`AppState`]: link status, device model, packet log, job, status line) and
//! the saved [`Settings`], both read-only, and return [`Action`]s; the app applies them once per
//! frame. Panels never build a link request: they ask [`crate::ops`] for one, or start a
//! [`Job`] that runs an operation. The UI never touches the port.

mod actions;
pub mod app;
mod connection;
mod device;
mod inputs;
pub mod jobs;
mod monitor;
mod presets;
mod selftest;
mod servo_bench;
pub mod settings;
mod solar;
pub mod state;
mod status_bar;
mod telemetry;
mod tuning;
mod tuya_console;

pub use app::{App, PanelId};
pub use jobs::Job;
pub use settings::Settings;
pub use solar::{Outcome as SolarOutcome, Trip as SolarTrip};
pub use state::{AppState, Notice, Target};
pub use tuya_console::FirmwareFileError;

use crate::i18n::Lang;

/// Something a panel asks the app to do.
#[derive(Debug)]
pub enum Action {
    /// Open a link (closing any other).
    Connect {
        /// To what.
        target: Target,
        /// At what rate.
        baud: u32,
        /// With which profile.
        profile: String,
        /// How long the device may take to start answering, ms (`None`: the protocol's own).
        margin_ms: Option<u64>,
    },
    /// Close the link.
    Disconnect,
    /// Set the USB adapter's latency timer of a port (Linux, FTDI), then reconnect to it.
    SetLatencyTimer {
        /// The port's path.
        port: String,
        /// The new latency timer, ms.
        ms: u32,
    },
    /// Start a job (the one way to start one).
    StartJob(Job),
    /// Cancel the running job.
    CancelJob,
    /// Telemetry polls a second (`None`: as fast as the wire allows).
    SetPollRate(Option<f64>),
    /// Pause or resume telemetry polling.
    PausePolling(bool),
    /// The plotted time window, seconds.
    SetPlotWindow(f64),
    /// Show this panel.
    ShowPanel(PanelId),
    /// The UI language.
    SetLanguage(Lang),
    /// Freeze or unfreeze the packet log.
    PausePacketLog(bool),
    /// Forget the packet log.
    ClearPacketLog,
    /// A status-line message.
    Notify(Notice),
    /// A command for the worker that needs no answer on this thread (stop all, polls, Tuya
    /// options, a request an operation built…).
    Link(crate::link::LinkCommand),
}

/// Why the window could not open.
#[derive(Debug, thiserror::Error)]
pub enum UiError {
    /// The profiles cannot be loaded.
    #[error(transparent)]
    Profile(#[from] crate::profile::ProfileError),
    /// eframe could not open the window.
    #[error("{0}")]
    Window(String),
}

/// Opens the window. `target`, `baud` and `profile` override the saved settings.
pub fn run(
    target: Option<Target>,
    baud: Option<u32>,
    profile: Option<String>,
    panel: Option<PanelId>,
) -> Result<(), UiError> {
    let options = eframe::NativeOptions {
        viewport: eframe::egui::ViewportBuilder::default()
            .with_inner_size([1200.0, 780.0])
            .with_min_inner_size([800.0, 500.0])
            .with_title("botbench"),
        ..Default::default()
    };
    eframe::run_native(
        "botbench",
        options,
        Box::new(move |cc| {
            let mut saved: Settings = cc
                .storage
                .and_then(|s| eframe::get_value(s, eframe::APP_KEY))
                .unwrap_or_default();
            if let Some(t) = target {
                saved.target = t;
            }
            if let Some(b) = baud {
                saved.baud = b;
            }
            if let Some(p) = profile {
                saved.profile = p;
            }
            if let Some(p) = panel {
                saved.panel = p;
            }
            let app = App::new(&cc.egui_ctx, saved)
                .map_err(|e| -> Box<dyn std::error::Error + Send + Sync> { e.into() })?;
            Ok(Box::new(app))
        }),
    )
    .map_err(|e| UiError::Window(e.to_string()))
}
