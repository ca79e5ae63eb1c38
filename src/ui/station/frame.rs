//! A station's work each frame, apart from drawing: its link's events, its job's output, a new
//! unit on the fixture, STOP and its panels' ticks; and the actions that concern the station
//! alone (a job, the link, the packet log, a capture, STOP, the status line).

use super::{Notice, Station};
use crate::i18n::Text;
use crate::link::LinkCommand;
use crate::profile::PanelKind;
use crate::ui::Action;
use crate::ui::panel::{Forget, Panels};

impl Station {
    /// One frame's work: the link's events (within [`super::EVENT_BUDGET`]), the job's output,
    /// the port list, a new unit (forgotten, identified and read again), STOP's answers and the
    /// panels' ticks. Returns whether link events are still waiting, and what STOP and the
    /// panels asked for (for this station: [`Self::apply`], then the app).
    pub fn frame(&mut self) -> (bool, Vec<Action>) {
        let more = self.drain_link_events();
        let mut actions = self.deliver_job_output();
        self.link.refresh_ports();
        let mut stop = std::mem::take(&mut self.stop);
        actions.extend(stop.tick(self));
        self.stop = stop;
        actions.extend(self.with_panels(|p, st| p.tick(st)));
        actions.extend(self.new_unit());
        (more, actions)
    }

    /// A device that answers again after silence may be another unit on the same port (a
    /// robot swapped on the fixture): what the last one showed is forgotten, and it is
    /// identified and read again. A link that came back starts a new unit too. The verdicts
    /// stay until the identification says another unit is there ([`super::Verdicts`]).
    fn new_unit(&mut self) -> Vec<Action> {
        let fresh = std::mem::take(&mut self.link.just_connected);
        let back = std::mem::take(&mut self.link.device_back);
        if back {
            self.device.forget_values();
            self.send(LinkCommand::Identify);
            self.notify(Notice::info(Text::new(
                "the device answers again: identified and read again (it may be another unit)",
                "设备重新应答:已重新识别并读取(可能是另一台设备)",
            )));
        } else if fresh {
            self.device.epoch += 1;
        }
        if fresh || back {
            self.with_panels(|p, st| p.forget(st, Forget::Unit))
        } else {
            Vec::new()
        }
    }

    /// Runs `f` with this station's panels and the station they show: the panels are taken out
    /// of the station while `f` runs (the station's `panels` is then empty), and put back.
    pub fn with_panels<R>(&mut self, f: impl FnOnce(&mut Panels, &Station) -> R) -> R {
        let mut panels = std::mem::replace(&mut self.panels, Panels::none());
        let r = f(&mut panels, self);
        self.panels = panels;
        r
    }

    /// The panels the profile names that the device has: those whose CMD_VERSION capability
    /// bit it reports clear are left out (none before the device has answered CMD_VERSION).
    pub fn panel_kinds(&self) -> Vec<PanelKind> {
        let info = match &self.device.info {
            Some(Ok(info)) => Some(info),
            _ => None,
        };
        self.device
            .profile
            .panels
            .iter()
            .filter(|r| {
                r.flag
                    .is_none_or(|bit| info.is_none_or(|i| i.supports(bit)))
            })
            .map(|r| r.panel)
            .collect()
    }

    /// Whether the device has the panel the profile calls `kind` (see [`Self::panel_kinds`]).
    pub fn has_panel(&self, kind: PanelKind) -> bool {
        self.panel_kinds().contains(&kind)
    }

    /// STOP, now (or as soon as the link is back): the profile's stop commands, straight to the
    /// worker's queue.
    pub fn stop_now(&mut self) {
        let mut stop = std::mem::take(&mut self.stop);
        let requests = stop.stop(self);
        self.stop = stop;
        for a in requests {
            self.apply(a);
        }
    }

    /// Telemetry polling as `poll_hz` says (`None`: as fast as the wire allows), or none while
    /// polling is paused.
    pub fn restart_polls(&self, poll_hz: Option<f64>) {
        let polls = if self.link.polling_paused {
            Vec::new()
        } else {
            crate::ops::telemetry::polls(&self.device.profile, poll_hz)
        };
        self.send(LinkCommand::SetPolls(polls));
    }

    /// Carries out `action` if it concerns this station alone; returns it otherwise (for the
    /// app: a connection, the settings, the panel shown).
    pub fn apply(&mut self, action: Action) -> Option<Action> {
        match action {
            Action::Disconnect => {
                self.disconnect();
                self.notify(Notice::info(Text::new("disconnected", "已断开")));
            }
            Action::StartJob(job) => self.start_job(job),
            Action::CancelJob => self.cancel_job(),
            Action::DismissVerdicts => self.verdicts.dismiss(),
            Action::PausePacketLog(paused) => self.packets.paused = paused,
            Action::ClearPacketLog => self.packets.clear(),
            Action::StartCapture(path) => self.start_capture(&path),
            Action::StopCapture => self.stop_capture(),
            Action::OpenCapture(path) => self.open_capture(&path),
            Action::CloseCapture => self.close_capture(),
            Action::Notify(n) => self.notify(n),
            Action::DemoMcuRequest(r) => {
                if let Some(mcu) = self.link.demo_tuya() {
                    mcu.lock().unwrap_or_else(|e| e.into_inner()).request(r);
                }
            }
            Action::Link(cmd) => self.send(cmd),
            Action::Stop => self.stop_now(),
            other => return Some(other),
        }
        None
    }
}
