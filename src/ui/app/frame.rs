//! One frame of the app: every station's work (its link's events, its job's output, a new unit,
//! STOP and its panels' ticks), the actions that came of it applied to the station they came
//! from, the title and how soon to redraw; then the window drawn: the connection bar, the status
//! line, the navigation, and the panel shown, whose actions are applied to the station shown.

use super::{App, TITLE};
use crate::ui::panel::Cx;
use crate::ui::{backdrop, demo_hint, repaint, status_bar};
use eframe::egui;

impl App {
    /// Work that is not drawing: each station's frame ([`crate::ui::Station::frame`]), its
    /// actions applied to it, the panel shown kept to one the device has, the title, the next
    /// redraw, and the screenshot tour's step.
    pub fn logic(&mut self, ctx: &egui::Context) {
        for i in 0..self.state.stations().len() {
            let Some(station) = self.state.station_at_mut(i) else {
                continue;
            };
            let (more, actions) = station.frame();
            if more {
                ctx.request_repaint();
            }
            for a in actions {
                self.apply_to(i, a);
            }
        }
        // The app leaves a panel the device turns out not to support.
        let shown = self.panels();
        if !shown.contains(&self.settings.panel)
            && let Some(&first) = shown.first()
        {
            self.settings.panel = first;
        }
        self.set_title(ctx);
        if let Some(after) = self.repaint_after() {
            ctx.request_repaint_after(after);
        }
        if let Some(mut tour) = self.tour.take() {
            tour.step(ctx, self);
            self.tour = Some(tour);
        }
        if let Some(line) = &mut self.line {
            line.logic(ctx);
        }
    }

    /// The title, set only on a change: a viewport command every frame would keep the window
    /// repainting.
    fn set_title(&mut self, ctx: &egui::Context) {
        let station = self.station();
        let title = match station.link.target() {
            Some(t) => format!(
                "{TITLE} — {} — {}",
                t.label(),
                station.device.profile.name.en
            ),
            None => format!("{TITLE} — not connected"),
        };
        if self.title != title {
            ctx.send_viewport_cmd(egui::ViewportCommand::Title(title.clone()));
            self.title = title;
        }
    }

    /// How soon the window redraws on its own: at [`repaint::LIVE`] while the panel shown shows
    /// live data (a plot of polled telemetry, the packet monitor while frames are logged) or a
    /// job runs; `None` otherwise (idle, paused or disconnected: the window sleeps until input
    /// or a worker event).
    pub fn repaint_after(&self) -> Option<std::time::Duration> {
        let station = self.station();
        let live = station
            .panels
            .find(self.settings.panel)
            .is_some_and(|p| p.live(station));
        (live || station.job_progress().is_some()).then_some(repaint::LIVE)
    }

    /// Draws the window and applies what the panels asked for; with a station open, the
    /// station (and the way back to the panels) instead.
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        if self.line.is_some() {
            self.line_ui(ui);
            return;
        }
        let lang = self.settings.lang;
        let mut actions = Vec::new();
        let (settings, station) = (&self.settings, self.state.station());
        egui::Panel::top("connection")
            .frame(backdrop::bar(ui.style()))
            .show(ui, |ui| {
                actions.extend(self.connection.show(ui, settings, station));
                demo_hint::show(ui, lang, station);
            });
        egui::Panel::bottom("status")
            .frame(backdrop::bar(ui.style()))
            .show(ui, |ui| {
                actions.extend(status_bar::show(ui, lang, station));
            });
        actions.extend(super::nav::show(ui, settings, station));
        // Each panel's widgets have ids of their own: a scroll area of one panel keeps its own
        // place, not the place of the panel shown before it.
        let panel = settings.panel;
        let station = self.state.station_mut();
        egui::CentralPanel::default()
            .frame(backdrop::central(ui.style()))
            .show(ui, |ui| {
                ui.push_id(panel.as_str(), |ui| {
                    actions.extend(station.with_panels(|panels, station| {
                        let cx = Cx {
                            lang,
                            settings,
                            station,
                        };
                        panels.show(panel, ui, &cx)
                    }));
                })
            });
        for a in actions {
            self.apply(a);
        }
        if let Some(tour) = &mut self.tour {
            tour.after_ui(ui.ctx());
        }
    }
}

impl App {
    /// The station opened with File > Open station, under a bar with Close station (enabled
    /// while no slot runs a unit).
    fn line_ui(&mut self, ui: &mut egui::Ui) {
        let Some(line) = &mut self.line else {
            return;
        };
        let zh = line.lang == crate::i18n::Lang::Zh;
        let mut close = false;
        egui::Panel::top("station-close")
            .frame(backdrop::bar(ui.style()))
            .show(ui, |ui| {
                ui.horizontal(|ui| {
                    let idle = !line.running();
                    let button =
                        egui::Button::new(if zh { "关闭工位" } else { "Close station" });
                    close = ui
                        .add_enabled(idle, button)
                        .on_disabled_hover_text(if zh {
                            "有工位正在测试:先停止它们"
                        } else {
                            "a slot is running a unit: STOP it first"
                        })
                        .clicked();
                });
            });
        line.ui(ui);
        if close {
            self.apply(crate::ui::Action::CloseStation);
        }
    }
}
