//! STOP, for every robot whose profile names one (the window cleaner: motor, fan, spray off;
//! the solar cleanbot: speed 0): always on screen, and straight to the worker's queue
//! (`Action::Link`, ahead of a running job's next request), with the requests
//! [`crate::ops::stop`] builds from the profile. A STOP pressed while the link is down, or lost
//! with it, is sent as soon as the link is back. Beside it, what the robot may be doing because
//! this window told it to ([`super::station::RunningSet`]).

use super::Action;
use super::station::Station;
use crate::i18n::Lang;
use crate::link::{ExchangeError, LinkCommand, ReplyTo};
use crate::ops::OpError;
use eframe::egui;
use std::collections::HashMap;
use std::time::{Duration, Instant};

const RED: egui::Color32 = egui::Color32::from_rgb(200, 30, 30);
const GREEN: egui::Color32 = egui::Color32::from_rgb(0, 140, 60);
const AMBER: egui::Color32 = egui::Color32::from_rgb(200, 120, 0);
/// The STOP button's least width, points.
pub const BUTTON_WIDTH: f32 = 90.0;
/// The STOP button's least height, points.
pub const BUTTON_HEIGHT: f32 = 32.0;

/// The last outcome of a command sent from a panel.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// Sent; no answer yet.
    Waiting(String),
    /// The device acknowledged it.
    Acked(String),
    /// It was refused before sending, or the exchange failed.
    Failed(SendError),
}

/// Why a command sent from a panel did not get through.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SendError {
    /// Refused before sending: a value the profile refuses, an unknown command.
    #[error(transparent)]
    Refused(#[from] OpError),
    /// Not sent: the link is down.
    #[error("not sent: the link is down")]
    LinkDown,
    /// Sent, and the exchange failed.
    #[error(transparent)]
    Exchange(#[from] ExchangeError),
}

/// Where the last STOP stands.
#[derive(Debug, Clone, PartialEq)]
pub enum StopState {
    /// No STOP sent on this connection.
    None,
    /// Waiting for the link to come back.
    Pending,
    /// Sent; some answers outstanding.
    Waiting,
    /// Every command of this STOP acknowledged: when the last answer came.
    Acked(Instant),
    /// A command failed: which, and why.
    Failed(String),
}

/// The STOP's state: what was sent, what answered, what waits for the link.
#[derive(Debug, Default)]
pub struct StopControl {
    /// Requests in flight: reply id → command ident.
    sent: HashMap<u64, String>,
    /// The last STOP: each command's ident and outcome, in the profile's order.
    pub last: Vec<(String, Outcome)>,
    /// When the last STOP was sent.
    pub sent_at: Option<Instant>,
    /// STOP must be sent as soon as the link is back.
    pub pending: bool,
    /// When a pending STOP was sent after the link came back.
    pub after_reconnect: Option<Instant>,
    /// When the last STOP's last answer came (on the monotonic clock, and as the wall clock's
    /// HH:MM:SS for the operator), once every command of it was acknowledged.
    acked: Option<(Instant, String)>,
}

impl StopControl {
    /// STOP, now: every command of the profile's STOP, each retried (a stop is the same
    /// however often it arrives). While the link is down it waits for the link.
    pub fn stop(&mut self, rt: &Station) -> Vec<Action> {
        if !rt.connected() {
            self.pending = true;
            return Vec::new();
        }
        let requests = match crate::ops::stop::requests(&rt.device.profile) {
            Ok(r) => r,
            Err(e) => {
                self.last = vec![("STOP".into(), Outcome::Failed(e.into()))];
                return Vec::new();
            }
        };
        self.sent.clear();
        self.last.clear();
        self.acked = None;
        self.sent_at = Some(Instant::now());
        requests
            .into_iter()
            .map(|(ident, request)| {
                let id = rt.link.reply_id();
                self.sent.insert(id, ident.clone());
                self.last.push((ident.clone(), Outcome::Waiting(ident)));
                Action::Link(LinkCommand::Request {
                    request,
                    reply_to: ReplyTo::Event(id),
                })
            })
            .collect()
    }

    /// Called every frame: takes the answers, and sends a pending STOP once the link is back.
    /// A STOP lost with the link is sent again when it is back; one the robot did not answer
    /// on a working link is shown, and the operator presses again.
    pub fn tick(&mut self, rt: &Station) -> Vec<Action> {
        for (ident, reply) in rt.device.take_answered(&mut self.sent) {
            let outcome = match reply {
                Ok(_) => Outcome::Acked(ident.clone()),
                Err(e) => {
                    if !rt.connected() {
                        self.pending = true;
                    }
                    Outcome::Failed(e.clone().into())
                }
            };
            if let Some(slot) = self.last.iter_mut().find(|(i, _)| *i == ident) {
                slot.1 = outcome;
            }
            if self.acked.is_none()
                && self
                    .last
                    .iter()
                    .all(|(_, o)| matches!(o, Outcome::Acked(_)))
            {
                let wall = chrono::Local::now().format("%H:%M:%S").to_string();
                self.acked = Some((Instant::now(), wall));
            }
        }
        let mut actions = Vec::new();
        if self.pending && rt.connected() {
            self.pending = false;
            actions = self.stop(rt);
            self.after_reconnect = Some(Instant::now());
        }
        if self.pending || !self.sent.is_empty() {
            rt.ctx.request_repaint_after(Duration::from_millis(100));
        }
        actions
    }

    /// Where the last STOP stands.
    pub fn state(&self) -> StopState {
        if self.pending {
            return StopState::Pending;
        }
        if let Some((ident, Outcome::Failed(e))) = self
            .last
            .iter()
            .find(|(_, o)| matches!(o, Outcome::Failed(_)))
        {
            return StopState::Failed(format!("{ident}: {e}"));
        }
        if self.last.is_empty() {
            return StopState::None;
        }
        if self
            .last
            .iter()
            .all(|(_, o)| matches!(o, Outcome::Acked(_)))
        {
            return StopState::Acked(self.acked.as_ref().map_or_else(Instant::now, |a| a.0));
        }
        StopState::Waiting
    }

    /// One line saying where the last STOP stands (nothing before the first).
    pub fn status(&self, ui: &mut egui::Ui, lang: Lang) {
        match self.state() {
            StopState::None => {}
            StopState::Pending => {
                ui.colored_label(
                    RED,
                    lang.tr(
                        "Link down: STOP will be sent as soon as the link is back.",
                        "链路中断:链路恢复后将立即发送停止。",
                    ),
                );
            }
            StopState::Waiting => {
                ui.label(lang.tr("STOP sent, waiting for the answer…", "已发送停止,等待应答…"));
            }
            StopState::Acked(at) => {
                // When this STOP was acknowledged: the wall clock, and how long after it was
                // sent (an earlier STOP's time would tell the operator the robot stopped before
                // this press).
                let wall = self.acked.as_ref().map_or("", |a| a.1.as_str());
                let took = self.sent_at.map_or(0.0, |s| {
                    at.saturating_duration_since(s).as_secs_f64() * 1000.0
                });
                let text = match lang {
                    Lang::En => {
                        format!("STOP acknowledged at {wall}, {took:.0} ms after it was sent")
                    }
                    Lang::Zh => format!("停止已于 {wall} 确认(发送后 {took:.0} ms)"),
                };
                ui.colored_label(GREEN, text);
            }
            StopState::Failed(e) => {
                ui.colored_label(RED, format!("{}: {e}", lang.tr("STOP failed", "停止失败")));
            }
        }
        if let Some(at) = self.after_reconnect {
            ui.colored_label(
                RED,
                format!(
                    "{} ({:.0} s)",
                    lang.tr("The link came back: STOP sent", "链路已恢复:已发送停止"),
                    at.elapsed().as_secs_f64()
                ),
            );
        }
    }
}

/// Where the STOP buttons' last place is kept in the context's memory.
fn drawn_id() -> egui::Id {
    egui::Id::unique("botbench-stop-button-rect")
}

/// Where a STOP button was drawn this frame (the last drawn), if one was: a confirmation
/// dialog's backdrop, which takes every click outside the dialog, passes a click there on as
/// STOP ([`crate::ui::confirm::decided`]).
pub fn drawn_at(ctx: &egui::Context) -> Option<egui::Rect> {
    let frame = ctx.cumulative_pass_nr();
    ctx.data(|d| d.get_temp::<(u64, egui::Rect)>(drawn_id()))
        .and_then(|(at, rect)| (at == frame).then_some(rect))
}

/// The STOP button: big, red, one click ([`Action::Stop`]); its hover says what it sends. The
/// STOP always on screen (the navigation's, the solar panel's); where it is drawn is kept, so
/// that a click on it while a dialog is open is STOP ([`drawn_at`]).
pub fn button(ui: &mut egui::Ui, lang: Lang, rt: &Station) -> Vec<Action> {
    let response = draw(ui, lang, rt);
    let frame = ui.ctx().cumulative_pass_nr();
    ui.ctx()
        .data_mut(|d| d.insert_temp(drawn_id(), (frame, response.rect)));
    clicked(&response)
}

/// A confirmation dialog's STOP: as [`button`], inside the dialog.
pub fn dialog_button(ui: &mut egui::Ui, lang: Lang, rt: &Station) -> Vec<Action> {
    clicked(&draw(ui, lang, rt))
}

fn clicked(response: &egui::Response) -> Vec<Action> {
    if response.clicked() {
        vec![Action::Stop]
    } else {
        Vec::new()
    }
}

/// Draws a STOP button; its hover says what it sends.
fn draw(ui: &mut egui::Ui, lang: Lang, rt: &Station) -> egui::Response {
    let b = egui::Button::new(
        egui::RichText::new(lang.tr("STOP", "停止"))
            .strong()
            .color(egui::Color32::WHITE),
    )
    .fill(RED)
    .min_size(egui::vec2(BUTTON_WIDTH, BUTTON_HEIGHT));
    let what = rt
        .device
        .profile
        .stop_commands()
        .iter()
        .map(|(c, inputs)| {
            let values: Vec<String> = inputs
                .iter()
                .map(|(k, v)| match v {
                    crate::profile::Input::Text(t) => format!("{k}={t}"),
                    crate::profile::Input::Raw(r) => format!("{k}={r:?}"),
                })
                .collect();
            format!("{} {}", lang.tr(&c.name.en, &c.name.zh), values.join(" "))
        })
        .collect::<Vec<_>>()
        .join(", ");
    ui.add(b)
        .on_hover_text(format!("{}: {what}", lang.tr("Now", "立即")))
}

/// What the robot may be doing because this window told it to: "Running: Fan 60 %", one line
/// each; nothing when all is at rest.
pub fn running(ui: &mut egui::Ui, lang: Lang, rt: &Station) {
    let profile = &rt.device.profile;
    if rt.device.running.is_empty() {
        return;
    }
    ui.colored_label(
        AMBER,
        egui::RichText::new(lang.tr("Running:", "运行中:")).strong(),
    );
    for r in rt.device.running.iter() {
        let Some(cmd) = profile.command_by_id(r.command) else {
            continue;
        };
        let values: Vec<String> = r
            .values
            .iter()
            .filter_map(|(k, v)| {
                let f = cmd.request.iter().find(|f| &f.ident == k)?;
                Some(crate::ui::inputs::short_text(f, v, lang))
            })
            .collect();
        let mut text = format!(
            "{} {}",
            lang.tr(&cmd.name.en, &cmd.name.zh),
            values.join(" ")
        );
        if !r.acknowledged {
            text.push_str(lang.tr(" (not acknowledged)", "(未确认)"));
        }
        if r.before_loss {
            text.push_str(lang.tr(" (before the link was lost)", "(链路中断前)"));
        }
        ui.colored_label(AMBER, text)
            .on_hover_text(format!("{} ({})", cmd.ident, cmd.id));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::LinkState;

    /// The id of the profile's command with role Drive (the solar cleanbot's speed).
    fn drive(rt: &Station) -> u8 {
        let role = crate::profile::CommandRole::Drive;
        rt.device.profile.command_with_role(role).expect("drive").id
    }

    fn runtime(profile: &str) -> Station {
        let mut rt = Station::new(
            &eframe::egui::Context::default(),
            std::sync::Arc::new(crate::profile::Registry::load().unwrap()),
            profile,
        )
        .unwrap();
        rt.link.state = Some(LinkState::Connected {
            port: "test".into(),
            baud: 115_200,
        });
        rt
    }

    /// The command and payload of a request action, and its reply id.
    fn sent(a: &Action) -> (u8, Vec<u8>, u64) {
        match a {
            Action::Link(LinkCommand::Request {
                request,
                reply_to: ReplyTo::Event(id),
            }) => (request.command, request.payload.clone(), *id),
            other => panic!("not a request answered as an event: {other:?}"),
        }
    }

    #[test]
    fn the_window_cleaners_stop_is_its_profiles_list() {
        let rt = runtime("window-cleaner");
        let mut c = StopControl::default();
        let a: Vec<(u8, Vec<u8>)> = c
            .stop(&rt)
            .iter()
            .map(|a| {
                let (cmd, payload, _) = sent(a);
                (cmd, payload)
            })
            .collect();
        assert_eq!(a, [(214, vec![0]), (211, vec![0]), (209, vec![0])]);
        assert_eq!(c.state(), StopState::Waiting);
    }

    #[test]
    fn a_stop_while_the_link_is_down_is_sent_when_it_is_back() {
        let mut rt = runtime("solar-cleanbot");
        let mut c = StopControl::default();
        rt.link.state = Some(LinkState::Reconnecting { attempt: 1 });
        assert!(c.stop(&rt).is_empty());
        assert_eq!(c.state(), StopState::Pending);
        assert!(c.tick(&rt).is_empty(), "nothing can be sent");
        rt.link.state = Some(LinkState::Connected {
            port: "test".into(),
            baud: 115_200,
        });
        let actions = c.tick(&rt);
        assert_eq!(actions.len(), 1, "{actions:?}");
        let (cmd, payload, id) = sent(&actions[0]);
        assert_eq!((cmd, payload), (drive(&rt), vec![0, 0]));
        assert!(c.after_reconnect.is_some());
        let ack =
            crate::packet::Packet::msp_reply(crate::protocol::msp::Reply::new(drive(&rt), vec![]));
        rt.device.replies.insert(
            id,
            Ok(crate::link::Reply {
                packets: vec![ack],
                rtt: Duration::from_millis(2),
                attempts: 1,
            }),
        );
        c.tick(&rt);
        assert!(matches!(c.state(), StopState::Acked(_)));
    }

    #[test]
    fn a_stop_lost_with_the_link_is_sent_again_and_one_unanswered_is_shown() {
        let mut rt = runtime("solar-cleanbot");
        let drive = drive(&rt);
        let mut c = StopControl::default();
        let (_, _, id) = sent(&c.stop(&rt)[0]);
        rt.device.replies.insert(
            id,
            Err(ExchangeError::Timeout {
                command: drive.into(),
                attempts: 3,
                waited_ms: 50,
                host_late: None,
            }),
        );
        assert!(c.tick(&rt).is_empty());
        assert!(matches!(c.state(), StopState::Failed(e) if e.contains("CMD_SET_SPEED")));
        let (_, _, id) = sent(&c.stop(&rt)[0]);
        rt.device
            .replies
            .insert(id, Err(ExchangeError::Disconnected("unplugged".into())));
        rt.link.state = None;
        assert!(c.tick(&rt).is_empty());
        assert_eq!(c.state(), StopState::Pending);
        rt.link.state = Some(LinkState::Connected {
            port: "test".into(),
            baud: 115_200,
        });
        assert_eq!(sent(&c.tick(&rt)[0]).1, vec![0, 0]);
    }
}
