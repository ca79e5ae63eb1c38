//! The desktop window (eframe/egui): one file (or folder) per panel, and one line in the list
//! ([`panels`], see [`panel`]). Panels draw from the station they show ([`Station`]: one
//! connected device's link status, device model, packet log, job, verdicts, status line) and
//! the saved [`Settings`], both read-only, and return [`Action`]s; the app applies them once per
//! frame. Panels never build a link request: they ask [`crate::ops`] for one, or start a
//! [`Job`] that runs an operation. The UI never touches the port.

pub mod app;
pub mod backdrop;
mod confirm;
mod connection;
pub mod demo_hint;
pub mod files;
pub mod fonts;
pub(crate) mod inputs;
pub mod jobs;
pub mod layout;
pub mod line;
pub mod panel;
pub mod plot;
mod port_options;
pub mod records;
pub mod repaint;
pub mod settings;
pub mod station;
mod status_bar;
pub mod stop;
pub mod tour;
pub mod views;
pub mod zh;

/// The list of panels: `panels! { module::Type, … }` declares each panel's module (a file or
/// folder of `ui/`) and makes [`panels`], a fresh panel of each, in this order: the
/// navigation's (a device's own panels are ordered by its profile; those every device has come
/// after them, in this order).
macro_rules! panels {
    ($($module:ident :: $panel:ident),+ $(,)?) => {
        $(pub mod $module;)+

        /// A fresh panel of each kind, in the list's order.
        pub fn panels() -> Vec<Box<dyn panel::Panel>> {
            vec![$(Box::new($module::$panel::default())),+]
        }
    };
}

// Adding a panel: its file (implementing `panel::Panel`) and one line here.
panels! {
    device::DevicePanel,
    tuning::TuningPanel,
    telemetry::TelemetryPanel,
    presets::PresetsPanel,
    actions::ActionsPanel,
    solar::SolarPanel,
    selftest::SelfTestPanel,
    servo_bench::ServoBenchPanel,
    tuya_console::TuyaConsolePanel,
    monitor::MonitorPanel,
    yield_view::YieldPanel,
}

pub use app::{App, AppState};
pub use jobs::Job;
pub use panel::{Panel, PanelId};
pub use settings::Settings;
pub use solar::{Outcome as SolarOutcome, Trip as SolarTrip};
pub use station::{Notice, Station, Target};
pub use telemetry::MIN_PLOT_HEIGHT;
pub use tuya_console::FirmwareFileError;
pub use views::View;

use crate::i18n::Lang;

/// Something a panel asks the app to do.
#[derive(Debug)]
pub enum Action {
    /// Open a link (closing any other).
    Connect {
        /// To what.
        target: Target,
        /// With which profile.
        profile: String,
        /// The port's settings: baud (`None`: the profile's usual), margin, DTR, RTS and boot
        /// wait; saved for this profile when the shown station connects.
        port: settings::PortSettings,
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
    /// The operator has read the verdicts on the unit on the fixture (self-test, provisioning):
    /// they go from the screen before the next unit's run.
    DismissVerdicts,
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
    /// Record the link's bytes to this capture file (pcapng).
    StartCapture(std::path::PathBuf),
    /// Stop recording.
    StopCapture,
    /// Show this capture file in the packet monitor, instead of the live frames.
    OpenCapture(std::path::PathBuf),
    /// Back to the live frames.
    CloseCapture,
    /// A status-line message.
    Notify(Notice),
    /// Remember the file last used for this purpose.
    RememberFile(settings::FileKind, String),
    /// STOP: the profile's stop commands, straight to the worker (sent when the link is back if
    /// it is down).
    Stop,
    /// A command for the worker that needs no answer on this thread (stop all, polls, Tuya
    /// options, a request an operation built…).
    Link(crate::link::LinkCommand),
    /// Ask the built-in simulated Tuya MCU (the demo device) to send one of its own requests;
    /// nothing happens on a real port.
    DemoMcuRequest(crate::sim::tuya_mcu::McuRequest),
    /// File > Open station: the station bundle at this path (`None`: ask with a file dialog)
    /// checked and started, shown in place of the panels ([`line::open`]).
    OpenStation(Option<std::path::PathBuf>),
    /// Close the station shown (only while no slot runs a unit): back to the panels.
    CloseStation,
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

/// The settings the window opens with: the saved ones, overridden by what the command line
/// gave. A built-in demo device named without a baud rate runs at its profile's rate (the Tuya
/// vacuum at 9600, as its profile and the protocol document say), not the last port's.
pub fn launch_settings(
    mut saved: Settings,
    target: Option<Target>,
    baud: Option<u32>,
    profile: Option<String>,
    panel: Option<PanelId>,
) -> Settings {
    let mut demo_baud = None;
    if let Some(t) = target {
        if let Target::Demo(kind) = &t
            && let Ok(kind) = kind.parse::<crate::sim::SimKind>()
        {
            demo_baud = Some(kind.default_baud());
        }
        saved.target = t;
    }
    if let Some(p) = profile {
        saved.profile = p;
    }
    // The port settings are the profile's: set once the profile is known.
    if let Some(b) = baud.or(demo_baud) {
        saved.port_mut().baud = Some(b);
    }
    if let Some(p) = panel {
        saved.panel = p;
    }
    saved
}

/// The window's icon: the bundled 256×256 PNG (assets/icons/botbench-256.png, rendered from the
/// desktop entry's botbench.svg). A PNG that cannot be decoded gives egui's default icon, never
/// a failed start.
fn window_icon() -> std::sync::Arc<eframe::egui::IconData> {
    let png = include_bytes!("../../assets/icons/botbench-256.png");
    std::sync::Arc::new(eframe::icon_data::from_png_bytes(png).unwrap_or_default())
}

/// Opens the window. `target`, `baud` and `profile` override the saved settings; a port named by
/// its path is opened with `ports`. With `screenshots`, the window tours the demo devices and
/// saves screenshots there, then closes (see [`tour`]); it then neither reads nor keeps saved
/// settings.
pub fn run(
    target: Option<Target>,
    baud: Option<u32>,
    profile: Option<String>,
    panel: Option<PanelId>,
    screenshots: Option<std::path::PathBuf>,
    ports: crate::link::PortOpener,
) -> Result<(), UiError> {
    let touring = screenshots.is_some();
    crate::system::heap::keep_freed_memory(crate::system::heap::WINDOW_KEPT_BYTES);
    let options = eframe::NativeOptions {
        viewport: eframe::egui::ViewportBuilder::default()
            .with_inner_size([1200.0, 780.0])
            .with_min_inner_size([800.0, 500.0])
            .with_title(app::TITLE)
            .with_icon(window_icon()),
        // Dithering is a per-pixel cost that software rendering pays on every frame, for
        // gradients the window does not draw.
        dithering: false,
        ..Default::default()
    };
    eframe::run_native(
        "botbench",
        options,
        Box::new(move |cc| {
            let saved: Settings = cc
                .storage
                .filter(|_| !touring)
                .and_then(|s| eframe::get_value(s, eframe::APP_KEY))
                .unwrap_or_default();
            let saved = launch_settings(saved, target, baud, profile, panel);
            let mut app = App::new(&cc.egui_ctx, saved, ports)
                .map_err(|e| -> Box<dyn std::error::Error + Send + Sync> { e.into() })?;
            app.tour = screenshots.map(tour::Tour::new);
            Ok(Box::new(app))
        }),
    )
    .map_err(|e| UiError::Window(e.to_string()))
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_bundled_window_icon_decodes_to_256_by_256() {
        let icon = super::window_icon();
        assert_eq!((icon.width, icon.height), (256, 256));
        assert_eq!(icon.rgba.len(), 256 * 256 * 4);
    }
}
