//! What the solar panel sends: controls (each range-checked before anything leaves) and the
//! dead-man. Each request is built by [`crate::ops::exchange::request`] and goes straight to
//! the worker queue (`Action::Link`) with a reply id, so that it works while a job runs, and its
//! answer is shown when it comes. STOP is the window's ([`crate::ui::stop`]): the dead-man asks
//! for it with [`Action::Stop`].

use super::super::Action;
use super::super::station::Station;
use crate::link::{LinkCommand, ReplyTo};
use crate::ops::exchange;
use crate::profile::{CommandRole, Input, Value};
use std::collections::HashMap;
use std::time::{Duration, Instant};

pub use super::super::stop::{Outcome, SendError};

/// The dead-man intervals offered, seconds.
pub const DEADMAN_SECS: std::ops::RangeInclusive<u32> = 1..=10;

/// Why the robot was last stopped by the app on its own.
#[derive(Debug, Clone, PartialEq)]
pub enum Trip {
    /// The operator stopped confirming.
    NotConfirmed,
    /// The link went down while the dead-man was armed: STOP waits for the link.
    LinkLost,
}

/// The sending side of the panel.
#[derive(Debug)]
pub struct Control {
    /// Requests in flight: reply id → command id.
    sent: HashMap<u64, u8>,
    /// The last outcome per command id.
    pub outcomes: HashMap<u8, (Outcome, Instant)>,
    /// The dead-man is armed.
    pub deadman: bool,
    /// Its interval, seconds.
    pub deadman_secs: u32,
    /// The operator's last confirmation.
    pub confirmed_at: Option<Instant>,
    /// What the app did on its own last, and when.
    pub trip: Option<(Trip, Instant)>,
    was_connected: bool,
}

impl Default for Control {
    fn default() -> Self {
        Self {
            sent: HashMap::new(),
            outcomes: HashMap::new(),
            deadman: false,
            deadman_secs: 2,
            confirmed_at: None,
            trip: None,
            was_connected: false,
        }
    }
}

impl Control {
    /// Encodes `inputs` for command `id` (checking every value against the profile) and
    /// returns the action that sends it; a refusal is recorded as the command's outcome.
    /// One attempt only: a retry after a late answer would apply a relative command (rotate)
    /// twice. A failure is shown, and the operator decides.
    pub fn send(&mut self, rt: &Station, id: u8, inputs: &[(String, Input)]) -> Option<Action> {
        let profile = &rt.device.profile;
        let cmd = profile.command_by_id(id)?;
        let text = inputs
            .iter()
            .map(|(k, v)| match v {
                Input::Text(t) => format!("{k}={t}"),
                Input::Raw(Value::Int(i)) => format!("{k}={i}"),
                Input::Raw(r) => format!("{k}={r:?}"),
            })
            .collect::<Vec<_>>()
            .join(", ");
        let request = match exchange::request(profile, cmd, inputs, 1) {
            Ok(r) => r,
            Err(e) => {
                self.outcomes
                    .insert(id, (Outcome::Failed(e.into()), Instant::now()));
                return None;
            }
        };
        if !rt.connected() {
            self.outcomes
                .insert(id, (Outcome::Failed(SendError::LinkDown), Instant::now()));
            return None;
        }
        let reply_id = rt.link.reply_id();
        self.sent.insert(reply_id, id);
        self.outcomes
            .insert(id, (Outcome::Waiting(text), Instant::now()));
        Some(Action::Link(LinkCommand::Request {
            request,
            reply_to: ReplyTo::Event(reply_id),
        }))
    }

    /// The operator confirms they are watching (dead-man).
    pub fn confirm(&mut self) {
        self.confirmed_at = Some(Instant::now());
    }

    /// Arms or disarms the dead-man; arming sets the robot's heartbeat interval to the same
    /// period, so that the robot's own watchdog (where its firmware has one) agrees: the first
    /// request field of the profile's command with role [`CommandRole::Heartbeat`] (none sent
    /// when the profile has no such command).
    pub fn arm(&mut self, rt: &Station, on: bool) -> Option<Action> {
        self.deadman = on;
        if !on {
            return None;
        }
        self.confirm();
        self.trip = None;
        let secs = i64::from(self.deadman_secs);
        let heartbeat = rt
            .device
            .profile
            .command_with_role(CommandRole::Heartbeat)?;
        let field = heartbeat.request.first()?.ident.clone();
        self.send(rt, heartbeat.id, &[(field, Input::Raw(Value::Int(secs)))])
    }

    /// Time left before the dead-man stops the robot.
    pub fn deadman_left(&self) -> Option<Duration> {
        if !self.deadman {
            return None;
        }
        let period = Duration::from_secs(u64::from(self.deadman_secs));
        Some(
            self.confirmed_at
                .map_or(Duration::ZERO, |t| period.saturating_sub(t.elapsed())),
        )
    }

    /// Called every frame, whichever panel is shown: takes answers, and asks for STOP when the
    /// dead-man runs out or the link goes down while it is armed (STOP then waits for the
    /// link).
    pub fn tick(&mut self, rt: &Station) -> Vec<Action> {
        let mut actions = Vec::new();
        for (cmd, reply) in rt.device.take_answered(&mut self.sent) {
            let outcome = match reply {
                Ok(_) => {
                    let what = match self.outcomes.get(&cmd) {
                        Some((Outcome::Waiting(t), _)) => t.clone(),
                        _ => String::new(),
                    };
                    Outcome::Acked(what)
                }
                Err(e) => Outcome::Failed(e.clone().into()),
            };
            self.outcomes.insert(cmd, (outcome, Instant::now()));
        }
        let connected = rt.connected();
        if self.deadman && self.was_connected && !connected {
            actions.push(Action::Stop);
            self.trip = Some((Trip::LinkLost, Instant::now()));
        }
        self.was_connected = connected;
        if connected && self.deadman_left() == Some(Duration::ZERO) {
            actions.push(Action::Stop);
            self.deadman = false;
            self.trip = Some((Trip::NotConfirmed, Instant::now()));
        }
        if self.deadman || !self.sent.is_empty() {
            rt.ctx.request_repaint_after(Duration::from_millis(100));
        }
        actions
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::LinkState;

    fn runtime() -> Station {
        let mut rt = Station::new(
            &eframe::egui::Context::default(),
            std::sync::Arc::new(crate::profile::Registry::load().unwrap()),
            "solar-cleanbot",
        )
        .unwrap();
        rt.link.state = Some(LinkState::Connected {
            port: "test".into(),
            baud: 115_200,
        });
        rt
    }

    /// The command and payload of a request action.
    fn sent(a: &Action) -> (u8, Vec<u8>) {
        match a {
            Action::Link(LinkCommand::Request { request, .. }) => {
                (request.command, request.payload.clone())
            }
            other => panic!("not a request: {other:?}"),
        }
    }

    /// The id and first request field of the command with `role`.
    fn with_role(rt: &Station, role: CommandRole) -> (u8, String) {
        let c = rt.device.profile.command_with_role(role).expect("role");
        (c.id, c.request[0].ident.clone())
    }

    #[test]
    fn out_of_range_values_are_refused_before_sending() {
        let rt = runtime();
        let (drive, speed) = with_role(&rt, CommandRole::Drive);
        let mut c = Control::default();
        let a = c.send(&rt, drive, &[(speed.clone(), Input::Text("1001".into()))]);
        assert!(a.is_none());
        assert!(matches!(
            c.outcomes.get(&drive),
            Some((Outcome::Failed(e), _)) if e.to_string().contains("out of range")
        ));
        let a = c.send(&rt, drive, &[(speed, Input::Text("-250".into()))]);
        assert_eq!(sent(&a.unwrap()), (drive, (-250i16).to_le_bytes().to_vec()));
    }

    #[test]
    fn the_dead_man_sets_the_command_with_role_heartbeat_wherever_the_profile_puts_it() {
        let mut rt = runtime();
        let (heartbeat, _) = with_role(&rt, CommandRole::Heartbeat);
        let mut c = Control::default();
        let arm = c.arm(&rt, true).expect("the heartbeat is set");
        assert_eq!(sent(&arm), (heartbeat, 2i16.to_le_bytes().to_vec()));

        // A firmware whose heartbeat is another command (here CMD_SET_ROTATE): an edited
        // profile moves the role, and arming follows it.
        let src = crate::profile::registry::BUILTIN
            .iter()
            .find(|(n, _)| *n == "solar-cleanbot")
            .expect("built-in")
            .1;
        let (from, to) = ("kind: Action, role: Some(Heartbeat),", "kind: Action,");
        let rotate = "ident: \"CMD_SET_ROTATE\", name: (en: \"Rotate\", zh: \"设置旋转角度值\"),\n            kind: Action, confirm: true,";
        assert!(src.contains(from) && src.contains(rotate), "test setup");
        let moved = src.replacen(from, to, 1).replacen(
            rotate,
            &format!("{rotate} role: Some(Heartbeat),"),
            1,
        );
        let edited = crate::profile::registry::parse("solar-cleanbot.ron", &moved, None)
            .expect("the edited profile loads");
        let rotate_id = edited.command("CMD_SET_ROTATE").expect("rotate").id;
        assert_ne!(rotate_id, heartbeat);
        rt.device.profile = std::sync::Arc::new(edited);
        let mut c = Control::default();
        let arm = c.arm(&rt, true).expect("the moved heartbeat is set");
        assert_eq!(sent(&arm), (rotate_id, 2i16.to_le_bytes().to_vec()));
    }

    #[test]
    fn the_dead_man_asks_for_stop_when_the_link_goes_down() {
        let mut rt = runtime();
        let mut c = Control::default();
        let (heartbeat, _) = with_role(&rt, CommandRole::Heartbeat);
        let arm = c.arm(&rt, true).expect("the heartbeat is set");
        assert_eq!(sent(&arm), (heartbeat, 2i16.to_le_bytes().to_vec()));
        assert!(c.tick(&rt).is_empty(), "confirmed just now");
        rt.link.state = Some(LinkState::Lost {
            reason: "unplugged".into(),
        });
        let actions = c.tick(&rt);
        assert!(matches!(actions[..], [Action::Stop]), "{actions:?}");
        assert!(matches!(c.trip, Some((Trip::LinkLost, _))));
    }
}
