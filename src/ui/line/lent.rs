//! A slot lent to the engineer view: today's window (the ordinary panels, [`crate::ui::App`])
//! on that slot's device, inside the station window.
//!
//! Why lending: a slot's link belongs to its runner thread, and a port has one owner. So the
//! engineer asks for an idle slot ([`crate::ops::station::Command::Lend`]); its runner closes its
//! port and says where it was ([`crate::ops::station::What::Lent`]); the engineer view then
//! opens that port with the slot's own opener (a simulated slot's device is the same unit) and
//! profile, as an ordinary window's station would. Closing the view (Back to the station, or
//! Lock) drops that window's link first, then gives the slot back
//! ([`crate::ops::station::Command::Return`]): the runner opens its port again and waits for
//! the next unit. The other slots run on meanwhile. The view starts from the ordinary
//! window's saved settings (each profile's margin, the panel, the telemetry rate, the files
//! last used), on the slot's port, profile and rate, in the station's language. A slot running a unit is not lent: the
//! button shows only while the slot waits for a unit.

use crate::ui::App;
use eframe::egui;

/// The engineer view of one slot.
pub struct Lent {
    /// The slot's name.
    pub slot: String,
    /// The port the runner gave up; `None` until it has ([`crate::ops::station::What::Lent`]).
    pub port: Option<String>,
    /// Today's window on the slot's device, once the port is given up.
    pub app: Option<Box<App>>,
    /// Why the window could not be made (its profiles did not load).
    pub error: Option<String>,
}

impl Lent {
    /// Slot `slot` asked for.
    pub fn asked(slot: &str) -> Self {
        Self {
            slot: slot.to_string(),
            port: None,
            app: None,
            error: None,
        }
    }

    /// Once the port is given up: today's window on it, then its frame's work. The window
    /// starts from `saved`, the ordinary window's saved settings (each profile's answer margin,
    /// the panel, the telemetry rate and window, the files last used), on the slot's port
    /// (`opener` opens it) with the slot's `profile`, at that profile's usual rate (the one the
    /// slot runs at, whatever rate the ordinary window last used), shown in `lang` (the
    /// station's: one window, one language).
    pub fn logic(
        &mut self,
        ctx: &egui::Context,
        opener: &crate::link::PortOpener,
        profile: &str,
        lang: crate::i18n::Lang,
        saved: &crate::ui::Settings,
    ) {
        if let (Some(port), None, None) = (&self.port, &self.app, &self.error) {
            let mut settings = crate::ui::Settings {
                target: crate::ui::Target::Port(port.clone()),
                profile: profile.to_string(),
                lang,
                ..saved.clone()
            };
            settings.port_mut().baud = None;
            match App::new(ctx, settings, opener.clone()) {
                Ok(app) => self.app = Some(Box::new(app)),
                Err(e) => self.error = Some(e.to_string()),
            }
        }
        if let Some(app) = &mut self.app {
            app.logic(ctx);
        }
    }

    /// The view under the station's bar: today's window, or why it is not there yet.
    pub fn ui(&mut self, ui: &mut egui::Ui, zh: bool) {
        match (&mut self.app, &self.error) {
            (Some(app), _) => app.ui(ui),
            (None, Some(e)) => {
                egui::CentralPanel::default()
                    .frame(crate::ui::backdrop::central(ui.style()))
                    .show(ui, |ui| {
                        ui.colored_label(egui::Color32::from_rgb(200, 30, 30), e.as_str());
                    });
            }
            (None, None) => {
                egui::CentralPanel::default()
                    .frame(crate::ui::backdrop::central(ui.style()))
                    .show(ui, |ui| {
                        ui.label(if zh {
                            format!("等待工位 {} 释放端口…", self.slot)
                        } else {
                            format!("waiting for slot {} to give up its port…", self.slot)
                        });
                    });
            }
        }
    }
}
