//! What is kept between runs (eframe storage): the last connection, the panel shown, the
//! language and the telemetry view. Changed only by the app, as panels ask ([`super::Action`]).

use super::app::PanelId;
use super::state::Target;
use crate::i18n::Lang;
use serde::{Deserialize, Serialize};

/// The saved settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Settings {
    /// The last target.
    pub target: Target,
    /// The last baud rate.
    pub baud: u32,
    /// The last profile.
    pub profile: String,
    /// The panel shown.
    pub panel: PanelId,
    /// The UI language.
    pub lang: Lang,
    /// Telemetry: polls a second (`None`: as fast as the wire allows).
    pub poll_hz: Option<f64>,
    /// Telemetry: the plotted time window, seconds.
    pub window_secs: f64,
    /// The navigation is shown.
    pub nav_open: bool,
    /// How long the device may take to start answering, ms (`None`: the protocol's own).
    pub margin_ms: Option<u64>,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            target: Target::Demo("window-cleaner".into()),
            baud: 115_200,
            profile: "window-cleaner".into(),
            panel: PanelId::Tuning,
            lang: Lang::En,
            poll_hz: Some(50.0),
            window_secs: 60.0,
            nav_open: true,
            margin_ms: None,
        }
    }
}
