//! What the solar panel sends: controls (each range-checked before anything leaves), STOP, and
//! the dead-man. Everything goes straight to the worker queue (`Action::Link`) with a reply id,
//! so that it works while a job runs, and its answer is shown when it comes.

use super::super::Action;
use super::super::runtime::Runtime;
use crate::link::{LinkCommand, ReplyTo, Request};
use crate::profile::{Input, Value};
use crate::protocol::Direction;
use std::collections::HashMap;
use std::time::{Duration, Instant};

/// CMD_SET_SPEED: STOP is speed 0.
pub const CMD_SET_SPEED: u8 = 100;
/// CMD_SET_HEARTBEAT: set when the dead-man is armed.
pub const CMD_SET_HEARTBEAT: u8 = 98;
/// The dead-man intervals offered, seconds.
pub const DEADMAN_SECS: std::ops::RangeInclusive<u32> = 1..=10;

/// The last outcome of a command sent from the panel.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// Sent; no answer yet.
    Waiting(String),
    /// The device acknowledged it.
    Acked(String),
    /// It was refused before sending, or the exchange failed.
    Failed(String),
}

/// Why the robot was last stopped by the app on its own.
#[derive(Debug, Clone, PartialEq)]
pub enum Trip {
    /// The operator stopped confirming.
    NotConfirmed,
    /// The link went down while the dead-man was armed (or a STOP could not be delivered): STOP
    /// waits for the link.
    LinkLost,
    /// STOP was sent after the link came back.
    SentAfterReconnect,
}

/// The sending side of the panel.
#[derive(Debug)]
pub struct Control {
    /// Requests in flight: reply id → command id.
    sent: HashMap<u64, u8>,
    /// The last outcome per command id.
    pub outcomes: HashMap<u8, (Outcome, Instant)>,
    /// The id of the last STOP sent.
    stop_id: Option<u64>,
    /// STOP must be sent as soon as the link is back.
    pub stop_pending: bool,
    /// The dead-man is armed.
    pub deadman: bool,
    /// Its interval, seconds.
    pub deadman_secs: u32,
    /// The operator's last confirmation.
    pub confirmed_at: Option<Instant>,
    /// What the app did on its own last, and when.
    pub trip: Option<(Trip, Instant)>,
    was_connected: bool,
    last_sent: Option<u64>,
}

impl Default for Control {
    fn default() -> Self {
        Self {
            sent: HashMap::new(),
            outcomes: HashMap::new(),
            stop_id: None,
            stop_pending: false,
            deadman: false,
            deadman_secs: 2,
            confirmed_at: None,
            trip: None,
            was_connected: false,
            last_sent: None,
        }
    }
}

impl Control {
    /// Encodes `inputs` for command `id` (checking every value against the profile) and
    /// returns the action that sends it; a refusal is recorded as the command's outcome.
    /// One attempt only: a retry after a late answer would apply a relative command (rotate)
    /// twice. A failure is shown, and the operator decides.
    pub fn send(&mut self, rt: &Runtime, id: u8, inputs: &[(String, Input)]) -> Option<Action> {
        self.send_with(rt, id, inputs, 1)
    }

    fn send_with(
        &mut self,
        rt: &Runtime,
        id: u8,
        inputs: &[(String, Input)],
        attempts: u8,
    ) -> Option<Action> {
        let Some(cmd) = rt.profile.command_by_id(id) else {
            return None;
        };
        let text = inputs
            .iter()
            .map(|(k, v)| match v {
                Input::Text(t) => format!("{k}={t}"),
                Input::Raw(Value::Int(i)) => format!("{k}={i}"),
                Input::Raw(r) => format!("{k}={r:?}"),
            })
            .collect::<Vec<_>>()
            .join(", ");
        let payload = match rt.profile.encode(cmd, Direction::HostToDevice, inputs) {
            Ok(p) => p,
            Err(e) => {
                self.outcomes
                    .insert(id, (Outcome::Failed(e.to_string()), Instant::now()));
                return None;
            }
        };
        if !rt.connected() {
            self.outcomes.insert(
                id,
                (
                    Outcome::Failed("not sent: the link is down".into()),
                    Instant::now(),
                ),
            );
            return None;
        }
        let reply_id = rt.request_id();
        self.sent.insert(reply_id, id);
        self.last_sent = Some(reply_id);
        self.outcomes
            .insert(id, (Outcome::Waiting(text), Instant::now()));
        Some(Action::Link(LinkCommand::Request {
            request: Request::for_command(&rt.profile, cmd, payload).attempts(attempts),
            reply_to: ReplyTo::Event(reply_id),
        }))
    }

    /// STOP: speed 0, now. When the link is down it is sent as soon as the link is back.
    pub fn stop(&mut self, rt: &Runtime) -> Option<Action> {
        if !rt.connected() {
            self.stop_pending = true;
            self.trip = Some((Trip::LinkLost, Instant::now()));
            return None;
        }
        // Speed 0 is the same however often it arrives: retried.
        let a = self.send_with(
            rt,
            CMD_SET_SPEED,
            &[("speed".into(), Input::Raw(Value::Int(0)))],
            3,
        );
        if a.is_some() {
            self.stop_id = self.last_sent;
        }
        a
    }

    /// The operator confirms they are watching (dead-man).
    pub fn confirm(&mut self) {
        self.confirmed_at = Some(Instant::now());
    }

    /// Arms or disarms the dead-man; arming sets the robot's heartbeat interval to the same
    /// period, so that the robot's own watchdog (where its firmware has one) agrees.
    pub fn arm(&mut self, rt: &Runtime, on: bool) -> Option<Action> {
        self.deadman = on;
        if !on {
            return None;
        }
        self.confirm();
        self.trip = None;
        let secs = i64::from(self.deadman_secs);
        self.send(
            rt,
            CMD_SET_HEARTBEAT,
            &[("heartbeat".into(), Input::Raw(Value::Int(secs)))],
        )
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

    /// Called every frame, whichever panel is shown: takes answers, sends STOP when the
    /// dead-man runs out, and sends a pending STOP once the link is back.
    pub fn tick(&mut self, rt: &Runtime) -> Vec<Action> {
        let mut actions = Vec::new();
        let answered: Vec<u64> = self
            .sent
            .keys()
            .filter(|id| rt.replies.contains_key(id))
            .copied()
            .collect();
        for reply_id in answered {
            let Some(cmd) = self.sent.remove(&reply_id) else {
                continue;
            };
            let outcome = match rt.replies.get(&reply_id) {
                Some(Ok(_)) => {
                    let what = match self.outcomes.get(&cmd) {
                        Some((Outcome::Waiting(t), _)) => t.clone(),
                        _ => String::new(),
                    };
                    Outcome::Acked(what)
                }
                Some(Err(e)) => {
                    if Some(reply_id) == self.stop_id {
                        // A STOP that did not arrive is sent again when the link is back.
                        self.stop_pending = true;
                    }
                    Outcome::Failed(e.clone())
                }
                None => continue,
            };
            self.outcomes.insert(cmd, (outcome, Instant::now()));
        }
        let connected = rt.connected();
        if self.deadman && self.was_connected && !connected {
            self.stop_pending = true;
            self.trip = Some((Trip::LinkLost, Instant::now()));
        }
        self.was_connected = connected;
        if self.stop_pending && connected {
            self.stop_pending = false;
            actions.extend(self.stop(rt));
            self.trip = Some((Trip::SentAfterReconnect, Instant::now()));
        }
        if connected && self.deadman_left() == Some(Duration::ZERO) {
            actions.extend(self.stop(rt));
            self.deadman = false;
            self.trip = Some((Trip::NotConfirmed, Instant::now()));
        }
        if self.deadman || self.stop_pending || !self.sent.is_empty() {
            rt.ctx.request_repaint_after(Duration::from_millis(100));
        }
        actions
    }
}
