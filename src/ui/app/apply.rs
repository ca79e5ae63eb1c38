//! Applying the actions the panels, STOP and the connection bar return: what concerns one
//! station alone it does itself ([`Station::apply`]); the rest is the app's: a connection (and
//! the settings it leaves), the USB adapter's latency timer, polling, the plot window, the panel
//! shown, the language and the files last used.

use super::{App, port_for};
use crate::i18n::Text;
use crate::ui::panel::PanelId;
use crate::ui::settings::PortSettings;
use crate::ui::station::{ConnectError, Notice, Station, Target};
use crate::ui::zh::Zh;
use crate::ui::{Action, connection};

impl App {
    /// Carries out one action, for the station shown.
    pub fn apply(&mut self, action: Action) {
        self.apply_to(self.state.shown(), action);
    }

    /// Carries out `action`, asked for by panel `panel` of the station shown: a job it starts
    /// reports to that panel (as when the panel returns it from drawing).
    pub fn apply_from(&mut self, panel: PanelId, action: Action) {
        let action = match action {
            Action::StartJob(job) => Action::StartJob(job.owned_by(panel)),
            a => a,
        };
        self.apply(action);
    }

    /// Carries out one action that station `i` (in [`super::AppState::stations`]) asked for.
    pub fn apply_to(&mut self, i: usize, action: Action) {
        let Some(station) = self.state.station_at_mut(i) else {
            return;
        };
        let Some(action) = station.apply(action) else {
            return;
        };
        match action {
            Action::Connect {
                target,
                profile,
                port,
            } => self.connect(i, target, profile, port),
            Action::SetLatencyTimer { port, ms } => self.set_latency_timer(i, &port, ms),
            Action::SetPollRate(hz) => {
                self.settings.poll_hz = hz;
                self.restart_polls(i);
            }
            Action::PausePolling(paused) => {
                if let Some(station) = self.state.station_at_mut(i) {
                    if paused != station.link.polling_paused {
                        // Nothing is measured while paused: the plots break there.
                        station.device.mark_gap();
                    }
                    station.link.polling_paused = paused;
                    station.link.paused_at = paused.then(std::time::Instant::now);
                }
                self.restart_polls(i);
            }
            Action::SetPlotWindow(secs) => self.settings.window_secs = secs,
            Action::ShowPanel(panel) => self.settings.panel = panel,
            Action::SetLanguage(lang) => self.settings.lang = lang,
            Action::RememberFile(kind, path) => {
                self.settings.files.insert(kind, path);
            }
            Action::OpenStation(path) => self.open_station(path),
            // Dropped: every slot stops, its port is closed.
            Action::CloseStation if self.line.as_ref().is_some_and(|l| !l.running()) => {
                self.line = None;
            }
            // The station's own (see `Station::apply`).
            _ => {}
        }
    }

    /// Adds a station to the window (the one shown stays shown), connected to `target` at
    /// `baud` with the profile `profile_id`; a port named by its path is opened with `ports`.
    /// It shares the window's profiles, records and file dialogs, and nothing else: its link,
    /// job, panels, STOP and verdicts are its own. Returns its index in
    /// [`super::AppState::stations`]. Errors: the profile does not load, or the link cannot
    /// start ([`ConnectError`]).
    pub fn add_station(
        &mut self,
        target: Target,
        baud: u32,
        profile_id: &str,
        ports: crate::link::PortOpener,
    ) -> Result<usize, ConnectError> {
        let first = self.state.station();
        let mut station = Station::new(&first.ctx, self.state.registry.clone(), profile_id)?;
        station.records = first.records.clone();
        station.dialogs = first.dialogs.clone();
        station.link.port_opener = ports;
        station.panels.restore(&self.settings);
        let actions = station.connect(target, baud, profile_id)?;
        let i = self.state.add(station);
        self.restart_polls(i);
        for a in actions {
            self.apply_to(i, a);
        }
        Ok(i)
    }

    /// Connects to the built-in demo device `kind` at its own rate with its profile, as the
    /// port picker does (the connection bar shows it).
    pub fn connect_demo(&mut self, kind: crate::sim::SimKind) {
        self.apply(Action::Connect {
            target: Target::Demo(kind.name().to_string()),
            profile: kind.profile_id().to_string(),
            port: PortSettings {
                baud: Some(kind.default_baud()),
                ..PortSettings::default()
            },
        });
        let port = port_for(&self.settings, &self.state.registry, &self.settings.profile);
        let baud = port.baud.unwrap_or(kind.default_baud());
        self.connection = connection::ConnectionBar::new(&self.settings, baud);
    }

    /// Connects station `i`; the shown station's connection is saved (target, profile, its
    /// port settings) as the one to open next time.
    fn connect(&mut self, i: usize, target: Target, profile: String, port: PortSettings) {
        let baud = port
            .baud
            .unwrap_or_else(|| super::usual_baud(&self.state.registry, &profile));
        let Some(station) = self.state.station_at_mut(i) else {
            return;
        };
        station.link.options.margin = port.margin();
        station.link.options.setup = port.setup();
        let actions = match station.connect(target.clone(), baud, &profile) {
            Ok(actions) => actions,
            Err(e) => {
                station.notify(Notice::error(
                    Text::new("cannot connect", "无法连接").then(": ", &e.said()),
                ));
                return;
            }
        };
        // The shown station's connection is the one saved (another station keeps its own).
        if i == self.state.shown() {
            self.settings.target = target;
            self.settings.profile = profile;
            // Kept for this profile only: another device keeps its own.
            *self.settings.port_mut() = PortSettings {
                baud: Some(baud),
                ..port
            };
        }
        let shown = self.panels();
        if !shown.contains(&self.settings.panel)
            && let Some(&first) = shown.first()
        {
            self.settings.panel = first;
        }
        self.restart_polls(i);
        for a in actions {
            self.apply_to(i, a);
        }
    }

    /// Sets the latency timer of the USB adapter at `port`, then reconnects station `i` if it
    /// is open on it (the link reads the latency timer when it opens the port).
    fn set_latency_timer(&mut self, i: usize, port: &str, ms: u32) {
        let result = crate::system::adapter::set_latency_timer(port, ms);
        let on_it = self
            .state
            .station_at_mut(i)
            .is_some_and(|s| s.link.target() == Some(&Target::Port(port.to_string())));
        if result.is_ok() && on_it {
            let profile = self.settings.profile.clone();
            let saved = port_for(&self.settings, &self.state.registry, &profile);
            self.connect(i, Target::Port(port.to_string()), profile, saved);
        }
        let Some(station) = self.state.station_at_mut(i) else {
            return;
        };
        match result {
            Ok(now) => {
                station.link.refresh_ports_now();
                station.notify(Notice::info(Text::new(
                    format!("{port}: latency timer set to {now} ms"),
                    format!("{port}:延迟定时器已设为 {now} ms"),
                )));
            }
            Err(e) => station.notify(Notice::error(Text::new(
                format!("{port}: latency timer not set: {e}"),
                format!("{port}:延迟定时器未设置:{e}"),
            ))),
        }
    }

    /// File > Open station: the bundle at `path` (or one picked in a file dialog) checked and
    /// started, shown in place of the panels. A bundle refused (its problem at file:line:column,
    /// a slot's missing port) starts nothing and is said in the status line; the window stays
    /// as it was. The window's link is left as it is (a slot may need its port: close it first).
    fn open_station(&mut self, path: Option<std::path::PathBuf>) {
        if self.line.is_some() {
            return;
        }
        let path = match path {
            Some(p) => p,
            None => {
                if let crate::ui::files::Dialogs::Missing(why) = &self.station().dialogs {
                    let why = why.clone();
                    self.station_mut().notify(Notice::error(Text::new(
                        format!("no file dialog: {why}"),
                        format!("无法打开文件对话框:{why}"),
                    )));
                    return;
                }
                let dialog = rfd::FileDialog::new().add_filter("station bundle (ron)", &["ron"]);
                let dialog = match crate::system::presets_dir() {
                    Some(dir) => dialog.set_directory(dir),
                    None => dialog,
                };
                match dialog.pick_file() {
                    Some(p) => p,
                    None => return,
                }
            }
        };
        let records = self
            .settings
            .file(crate::ui::settings::FileKind::Records)
            .map(str::to_string);
        let ports = self.station().link.port_opener.clone();
        match crate::ui::line::open(&path, &self.state.registry, &ports, records.as_deref()) {
            Ok(line) => {
                let mut line = line.with_sound_chosen(self.settings.station_sound);
                line.lang = self.settings.lang;
                // Its engineer view starts from this window's settings.
                line.window_settings = self.settings.clone();
                self.line = Some(Box::new(line));
            }
            Err(e) => self.station_mut().notify(Notice::error(Text::new(
                format!("station not opened: {e}"),
                format!("工位未打开:{e}"),
            ))),
        }
    }

    fn restart_polls(&mut self, i: usize) {
        let poll_hz = self.settings.poll_hz;
        if let Some(station) = self.state.station_at_mut(i) {
            Station::restart_polls(station, poll_hz);
        }
    }
}
