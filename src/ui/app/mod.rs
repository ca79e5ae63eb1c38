//! The app shell: saved settings kept apart from run-time state (the stations), a top bar, a
//! left navigation, one panel at a time, a status line. By what it does: the frame's logic and
//! drawing (`frame.rs`), applying the actions the panels return (`apply.rs`), and the
//! navigation (`nav.rs`).

mod apply;
mod frame;
mod nav;

use super::panel::Panel;
use super::settings::{FileKind, PortSettings, Settings};
use super::station::Station;
use super::{Action, connection, files, tour};
use crate::link::PortOpener;
use crate::profile::{ProfileError, Registry};
use eframe::egui;
use std::sync::Arc;

/// The start of the window's title: `botbench 0.1.0`.
pub const TITLE: &str = concat!("botbench ", env!("CARGO_PKG_VERSION"));

/// The window's run-time state (never saved): its stations, one today, each everything the
/// window holds about one connected device, and the profiles they share.
pub struct AppState {
    /// Every profile (each station holds the same, shared).
    pub registry: Arc<Registry>,
    /// Never empty: [`Self::new`] makes the first.
    stations: Vec<Station>,
    /// The index of the station the panels show.
    shown: usize,
}

impl AppState {
    /// The state of a window with one station, `first`, shown.
    pub fn new(registry: Arc<Registry>, first: Station) -> Self {
        Self {
            registry,
            stations: vec![first],
            shown: 0,
        }
    }

    /// The station the panels show.
    pub fn station(&self) -> &Station {
        &self.stations[self.shown]
    }

    /// The station the panels show, to change.
    pub fn station_mut(&mut self) -> &mut Station {
        &mut self.stations[self.shown]
    }

    /// Every station, in the order they were added.
    pub fn stations(&self) -> &[Station] {
        &self.stations
    }

    /// Station `i`, to change.
    pub fn station_at_mut(&mut self, i: usize) -> Option<&mut Station> {
        self.stations.get_mut(i)
    }

    /// Adds `station` (the one shown stays shown); returns its index.
    pub fn add(&mut self, station: Station) -> usize {
        self.stations.push(station);
        self.stations.len() - 1
    }

    /// Shows station `i` (nothing changes when there is none).
    pub fn show(&mut self, i: usize) {
        if i < self.stations.len() {
            self.shown = i;
        }
    }

    /// The index of the station shown.
    pub fn shown(&self) -> usize {
        self.shown
    }
}

/// The application.
pub struct App {
    /// Kept between runs.
    pub settings: Settings,
    /// Not kept: the stations (link status, device model, packet log, job, verdicts, STOP, the
    /// panels' own state).
    pub state: AppState,
    /// The connection bar's fields.
    pub connection: connection::ConnectionBar,
    /// The screenshot tour, when the window was opened for one.
    pub tour: Option<tour::Tour>,
    /// The line station opened with File > Open station, shown in place of the panels.
    pub line: Option<Box<crate::ui::line::LineStation>>,
    /// The window title last set.
    title: String,
}

impl App {
    /// An app with `settings`, connected to its target; a port named by its path is opened with
    /// `ports` (the system's serial ports, [`PortOpener::system`], or a test's simulator).
    /// Errors: no profile loads ([`ProfileError`]).
    pub fn new(
        ctx: &egui::Context,
        settings: Settings,
        ports: PortOpener,
    ) -> Result<Self, ProfileError> {
        // Scroll bars shown solid wherever a panel has more than its room (egui's floating
        // ones show only under the pointer: a technician does not see that more is below).
        ctx.all_styles_mut(|s| s.spacing.scroll = egui::style::ScrollStyle::solid());
        let registry = Arc::new(Registry::load()?);
        let fonts =
            crate::ui::fonts::install(ctx, &registry, crate::i18n::glyphs::SYSTEM_CJK_FONTS);
        let mut station = Station::new(ctx, registry.clone(), &settings.profile)?;
        station.link.port_opener = ports;
        if let Err(warning) = fonts {
            station.notify(warning);
        }
        let state = AppState::new(registry, station);
        let port = port_for(&settings, &state.registry, &settings.profile);
        let mut app = Self {
            connection: connection::ConnectionBar::new(&settings, port.baud.unwrap_or(115_200)),
            settings,
            state,
            tour: None,
            line: None,
            title: String::new(),
        };
        app.restore_files();
        app.apply(Action::Connect {
            target: app.settings.target.clone(),
            profile: app.settings.profile.clone(),
            port,
        });
        Ok(app)
    }

    /// The station the panels show.
    pub fn station(&self) -> &Station {
        self.state.station()
    }

    /// The station the panels show, to change.
    pub fn station_mut(&mut self) -> &mut Station {
        self.state.station_mut()
    }

    /// The shown station's panel of type `T`.
    ///
    /// # Panics
    /// When `T` is not in the list (`panels!` in `ui/mod.rs`): a test asking for a panel that
    /// does not exist.
    pub fn panel<T: Panel>(&self) -> &T {
        match self.station().panels.get::<T>() {
            Some(p) => p,
            None => panic!("no such panel: {}", std::any::type_name::<T>()),
        }
    }

    /// The shown station's panel of type `T`, to change (see [`Self::panel`]).
    pub fn panel_mut<T: Panel>(&mut self) -> &mut T {
        match self.station_mut().panels.get_mut::<T>() {
            Some(p) => p,
            None => panic!("no such panel: {}", std::any::type_name::<T>()),
        }
    }

    /// Runs `f` on the shown station's panel of type `T`, with the station it shows (the way
    /// the app itself calls a panel: see [`Station::with_panels`]).
    ///
    /// # Panics
    /// When `T` is not in the list (see [`Self::panel`]).
    pub fn with_panel<T: Panel, R>(&mut self, f: impl FnOnce(&mut T, &Station) -> R) -> R {
        self.station_mut()
            .with_panels(|panels, station| match panels.get_mut::<T>() {
                Some(p) => f(p, station),
                None => panic!("no such panel: {}", std::any::type_name::<T>()),
            })
    }

    /// The window's title: `botbench 0.1.0 — built-in simulated window-cleaner — Window-cleaning
    /// robot`, or `botbench 0.1.0 — not connected`.
    pub fn title(&self) -> &str {
        &self.title
    }

    /// The files last used, back in their boxes (each panel takes its own), and where records
    /// go.
    fn restore_files(&mut self) {
        let records = self.settings.file(FileKind::Records).map(str::to_string);
        let settings = &self.settings;
        let station = self.state.station_mut();
        station.panels.restore(settings);
        station.records.configure(records);
    }
}

/// The port settings to open `profile` with: its saved ones, the baud rate always given (its
/// saved one, else the profile's usual rate).
fn port_for(saved: &Settings, registry: &Registry, profile: &str) -> PortSettings {
    let mut port = saved.port_of(profile);
    port.baud = Some(port.baud.unwrap_or_else(|| usual_baud(registry, profile)));
    port
}

/// The usual baud rate of `profile` (115200 for a profile that does not load).
fn usual_baud(registry: &Registry, profile: &str) -> u32 {
    registry.get(profile).map_or(115_200, |p| p.baud)
}

/// A file last used for `kind`, else the shipped example `name` (found wherever the binary
/// runs, see [`files::shipped_in`]): what a panel's box starts with.
pub(crate) fn file_or_shipped(settings: &Settings, kind: FileKind, name: &str) -> Option<String> {
    settings.file(kind).map(str::to_string).or_else(|| {
        files::shipped_in(&files::shipped_dir(), name)
            .ok()
            .map(|p| p.display().to_string())
    })
}

impl eframe::App for App {
    fn clear_color(&self, visuals: &egui::Visuals) -> [f32; 4] {
        crate::ui::backdrop::clear_color(visuals)
    }

    fn logic(&mut self, ctx: &egui::Context, _frame: &mut eframe::Frame) {
        App::logic(self, ctx);
    }

    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        App::ui(self, ui);
    }

    fn raw_input_hook(&mut self, _ctx: &egui::Context, raw_input: &mut egui::RawInput) {
        // A screenshot tour shows each view as it is, not a hover text from wherever the X
        // server's pointer happens to rest over the window.
        if self.tour.is_some() {
            raw_input
                .events
                .retain(|e| !matches!(e, egui::Event::PointerMoved(_)));
            raw_input.events.push(egui::Event::PointerGone);
        }
    }

    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        // A screenshot tour's panels, sizes and languages are not the user's choice.
        if self.tour.is_none() {
            if let Some(chosen) = self.line.as_ref().and_then(|l| l.sound_chosen) {
                self.settings.station_sound = Some(chosen);
            }
            eframe::set_value(storage, eframe::APP_KEY, &self.settings);
        }
    }
}
