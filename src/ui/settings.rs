//! What is kept between runs (eframe storage): the last connection, each profile's port
//! settings, the panel shown, the language, the telemetry view and the files last used.
//! Changed only by the app, as panels ask ([`super::Action`]).

use super::panel::PanelId;
use super::station::Target;
use crate::i18n::Lang;
use crate::link::{LineLevel, PortSetup};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::time::Duration;

/// What a port needs for one kind of device, kept per profile: a 300 ms margin chosen for a
/// slow window cleaner must not slow a servo scan, nor Tuya's 9600 baud the next servo bench,
/// nor a board that reboots on open make every other device wait. Settings saved before a
/// field existed load with its default.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PortSettings {
    /// The baud rate (`None`: the profile's usual rate).
    pub baud: Option<u32>,
    /// How long the device may take to start answering, ms, within [`crate::link::MARGIN_MS`]
    /// (`None`: the protocol's own).
    pub margin_ms: Option<u64>,
    /// The DTR line right after the port opens.
    pub dtr: LineLevel,
    /// The RTS line right after the port opens.
    pub rts: LineLevel,
    /// How long to send nothing after the port opens, ms, within
    /// [`crate::link::BOOT_WAIT_MS`] (0: not at all).
    pub boot_wait_ms: u64,
}

impl PortSettings {
    /// The margin to open the port with (`None`: the protocol's own), kept within
    /// [`crate::link::MARGIN_MS`] (a hand-edited settings file may hold anything).
    pub fn margin(&self) -> Option<Duration> {
        let r = crate::link::MARGIN_MS;
        self.margin_ms
            .map(|ms| Duration::from_millis(ms.clamp(*r.start(), *r.end())))
    }

    /// What is done right after each open: the lines and the boot wait (kept within
    /// [`crate::link::BOOT_WAIT_MS`]).
    pub fn setup(&self) -> PortSetup {
        let r = crate::link::BOOT_WAIT_MS;
        PortSetup {
            dtr: self.dtr,
            rts: self.rts,
            boot_wait: Duration::from_millis(self.boot_wait_ms.clamp(*r.start(), *r.end())),
        }
    }
}

/// The saved settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Settings {
    /// The last target.
    pub target: Target,
    /// The last profile.
    pub profile: String,
    /// Port settings by profile id.
    pub ports: BTreeMap<String, PortSettings>,
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
    /// The files last used, by purpose ([`FileKind`]).
    pub files: BTreeMap<FileKind, String>,
    /// The operator's choice of a station's sound on each verdict (`None`: the bundle's).
    pub station_sound: Option<bool>,
}

/// What a remembered file is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub enum FileKind {
    /// A parameter preset (presets panel).
    Preset,
    /// A self-test plan.
    SelfTestPlan,
    /// The self-test's JSON-lines log.
    SelfTestLog,
    /// The telemetry CSV export.
    TelemetryCsv,
    /// The packet monitor's saved text.
    Packets,
    /// A servo parameter preset.
    ServoPreset,
    /// A servo provisioning plan.
    ProvisionPlan,
    /// The provisioning CSV log.
    ProvisionLog,
    /// A Tuya MCU firmware image (OTA).
    Firmware,
    /// A capture file (pcapng) recorded or opened in the packet monitor.
    Capture,
    /// Where production records go: a SQLite file or a `postgres://` URL (the Yield view).
    Records,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            target: Target::Demo("window-cleaner".into()),
            profile: "window-cleaner".into(),
            ports: BTreeMap::new(),
            panel: PanelId::TUNING,
            lang: Lang::En,
            poll_hz: Some(50.0),
            window_secs: 60.0,
            nav_open: true,
            files: BTreeMap::new(),
            station_sound: None,
        }
    }
}

impl Settings {
    /// The settings the ordinary window (`botbench gui`) saved last: eframe's storage file of
    /// the app `botbench` (on Linux `$XDG_DATA_HOME/botbench/app.ron`, else
    /// `~/.local/share/botbench/app.ron`), the settings under eframe's app key. `None` for a
    /// window never run, or a file that cannot be read or parsed. What the station window's
    /// engineer view starts from, and the port the command line remembers.
    pub fn saved_by_window() -> Option<Self> {
        let file = eframe::storage_dir("botbench")?.join("app.ron");
        let text = std::fs::read_to_string(file).ok()?;
        let kv: std::collections::HashMap<String, String> = ron::from_str(&text).ok()?;
        ron::from_str(kv.get(eframe::APP_KEY)?).ok()
    }

    /// The port settings saved for `profile` (none saved: the profile's rate, auto margin).
    pub fn port_of(&self, profile: &str) -> PortSettings {
        self.ports.get(profile).cloned().unwrap_or_default()
    }

    /// The current profile's port settings, to change.
    pub fn port_mut(&mut self) -> &mut PortSettings {
        self.ports.entry(self.profile.clone()).or_default()
    }

    /// The file last used for `kind`, if any.
    pub fn file(&self, kind: FileKind) -> Option<&str> {
        self.files.get(&kind).map(String::as_str)
    }
}
