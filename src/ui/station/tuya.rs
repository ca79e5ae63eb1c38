//! The Tuya part of the device model: what the module session (the link's) has said, kept as it
//! arrives (bounded), so that nothing is lost while another panel is shown: the handshake's
//! steps, heartbeats, each data point's last report, the report log, and the MCU's own requests
//! with the module's answers.

use crate::link::session::tuya::{HandshakeStep, ProductInfo, TuyaEvent};
use crate::ops::tuya::{ReportedDp, read_reports};
use crate::packet::{Header, Packet};
use crate::profile::{Profile, Value};
use crate::protocol::Direction;
use crate::protocol::tuya::cmd;
use crate::ui::zh::Zh;
use chrono::{DateTime, Local};
use std::collections::{BTreeMap, VecDeque};
use std::time::Instant;

/// Lines the report log keeps.
pub const LOG_CAPACITY: usize = 500;
/// MCU requests kept.
pub const REQUESTS_CAPACITY: usize = 200;

/// How a handshake step ended.
#[derive(Debug, Clone, PartialEq)]
pub struct StepResult {
    /// It worked.
    pub ok: bool,
    /// What came back, or why it failed, in both languages (the link's
    /// [`crate::link::StepResult`] said).
    pub detail: crate::i18n::Text,
    /// When it ended, as the link saw it (each step its own time, however late the window
    /// took the news).
    pub at: DateTime<Local>,
    /// From its request to its end (`None`: it sent nothing).
    pub took: Option<std::time::Duration>,
}

/// A data point's last report that fits the profile.
#[derive(Debug, Clone, PartialEq)]
pub struct DpState {
    /// The raw value reported.
    pub value: Value,
    /// When (for comparisons).
    pub at: Instant,
    /// When (for people).
    pub clock: DateTime<Local>,
    /// Status queries sent before it came ([`TuyaModel::queries`]): a report that came after
    /// a query sent after a command is that command's read-back.
    pub query: u64,
}

/// One line of the report log.
#[derive(Debug, Clone, PartialEq)]
pub struct LogLine {
    /// Its number, counting from the connection.
    pub seq: u64,
    /// When.
    pub clock: DateTime<Local>,
    /// The data point as reported and read against the profile (with its raw bytes and the
    /// mismatch when it does not fit).
    pub item: ReportedDp,
}

/// An MCU request the module answered.
#[derive(Debug, Clone, PartialEq)]
pub struct RequestLine {
    /// When the module took it, as the link saw it (each request its own time).
    pub clock: DateTime<Local>,
    /// The command word.
    pub command: u8,
    /// What it asked.
    pub name: String,
    /// The module's answer (its data).
    pub answer: Vec<u8>,
}

/// What the Tuya link has reported since the connection.
#[derive(Debug, Clone, Default)]
pub struct TuyaModel {
    /// Counts connections: a new one starts a new session.
    pub generation: u64,
    /// The current (or last) handshake attempt, step by step, in [`HandshakeStep::ALL`] order.
    pub steps: [Option<StepResult>; 5],
    /// Handshake attempts started.
    pub attempts: u32,
    /// Where the last failed attempt stopped, until a handshake completes.
    pub stopped: Option<(HandshakeStep, StepResult)>,
    /// When the handshake last completed.
    pub done_at: Option<DateTime<Local>>,
    /// The version byte of the MCU's frames, from its last heartbeat answer in a handshake.
    pub frame_version: Option<u8>,
    /// The product info of the last handshake.
    pub product: Option<ProductInfo>,
    /// The current attempt received product info (a failed product-info step then means JSON
    /// that is shown raw, and the handshake goes on; without it, no answer).
    pub product_in_attempt: bool,
    /// The working mode: `None` the MCU drives the LED, or the module's GPIOs.
    pub work_mode: Option<Option<(u8, u8)>>,
    /// MCU restarts seen by the heartbeat, and the last one.
    pub restarts: (u32, Option<DateTime<Local>>),
    /// When the MCU last failed to answer a heartbeat.
    pub heartbeat_lost: Option<DateTime<Local>>,
    /// The last heartbeat answer: when, and its byte (0 first after a restart, 1 later).
    pub last_heartbeat: Option<(DateTime<Local>, Option<u8>)>,
    /// The last Wi-Fi state sent to the MCU (0x03), and when.
    pub wifi_sent: Option<(u8, DateTime<Local>)>,
    /// When the MCU last acknowledged a Wi-Fi state.
    pub wifi_acked: Option<DateTime<Local>>,
    /// When a status query (0x08) was last sent.
    pub last_query: Option<DateTime<Local>>,
    /// Each data point's last report that fits the profile, by id.
    pub dps: BTreeMap<u8, DpState>,
    /// Data points whose last report did not fit the profile (another type or length), by
    /// id, with when and the queries sent before it (as [`DpState::query`]): shown raw with
    /// the mismatch.
    pub misfits: BTreeMap<u8, (ReportedDp, DateTime<Local>, u64)>,
    /// Data points the profile does not have, read by their own type and length (issue 26:
    /// decoded, not dropped), by id, with when they were last reported.
    pub unknown_dps: BTreeMap<u8, (ReportedDp, DateTime<Local>)>,
    /// Status queries (0x08) sent on this connection.
    pub queries: u64,
    /// The report log, oldest first.
    pub log: VecDeque<LogLine>,
    /// Report lines so far (the next line's number).
    pub log_seq: u64,
    /// The MCU's requests answered, oldest first.
    pub requests: VecDeque<RequestLine>,
    /// Reset-Wi-Fi requests (0x04, 0x05) acknowledged, and the last one.
    pub resets: (u32, Option<RequestLine>),
    /// Frames the MCU sent that the module does not know (logged and ignored), oldest first:
    /// when, the command word, what it was taken for, its data.
    pub unknown_commands: VecDeque<(DateTime<Local>, u8, String, Vec<u8>)>,
    /// When the MCU asked for no heartbeats (0x25), until the next handshake.
    pub heartbeat_stopped: Option<DateTime<Local>>,
}

fn step_index(step: HandshakeStep) -> usize {
    HandshakeStep::ALL
        .iter()
        .position(|s| *s == step)
        .unwrap_or(0)
}

impl TuyaModel {
    /// A new session for the connection after `self`'s.
    pub fn next(&self) -> Self {
        Self {
            generation: self.generation + 1,
            ..Self::default()
        }
    }

    /// Whether `step` failed only because its product info is not JSON: it is shown raw and the
    /// handshake goes on.
    pub fn shown_raw(&self, step: HandshakeStep) -> bool {
        step == HandshakeStep::ProductInfo && self.product_in_attempt
    }

    /// Takes a Tuya event from the worker.
    pub fn on_event(&mut self, ev: TuyaEvent) {
        let now = Local::now();
        match ev {
            TuyaEvent::Step {
                step,
                result,
                at,
                took,
            } => {
                let ok = result.ok();
                if step == HandshakeStep::Heartbeat {
                    // Every attempt starts with a heartbeat: a new attempt.
                    self.steps = Default::default();
                    self.attempts += 1;
                    self.done_at = None;
                    self.product_in_attempt = false;
                    self.heartbeat_stopped = None;
                }
                let result = StepResult {
                    ok,
                    detail: result.said(),
                    at: DateTime::from(at),
                    took,
                };
                // A product info that is not JSON is shown raw and the handshake goes on.
                if !ok && !self.shown_raw(step) {
                    self.stopped = Some((step, result.clone()));
                }
                self.steps[step_index(step)] = Some(result);
            }
            TuyaEvent::FrameVersion { version } => self.frame_version = Some(version),
            TuyaEvent::ProductInfo(p) => {
                self.product = Some(p);
                self.product_in_attempt = true;
            }
            TuyaEvent::WorkMode { gpio } => self.work_mode = Some(gpio),
            TuyaEvent::HandshakeDone => {
                // When its last step ended, as the link saw it.
                let last = self.steps[step_index(HandshakeStep::QueryStatus)].as_ref();
                self.done_at = Some(last.map_or(now, |r| r.at));
                self.stopped = None;
            }
            TuyaEvent::McuRestarted => {
                self.restarts.0 += 1;
                self.restarts.1 = Some(now);
            }
            TuyaEvent::HeartbeatLost => self.heartbeat_lost = Some(now),
            TuyaEvent::Heartbeat { answer } => self.last_heartbeat = Some((now, answer)),
            TuyaEvent::WifiStateSent { state } => self.wifi_sent = Some((state, now)),
            TuyaEvent::WifiStateAcked => self.wifi_acked = Some(now),
            TuyaEvent::StatusQueried => {
                self.last_query = Some(now);
                self.queries += 1;
            }
            TuyaEvent::McuUnknown {
                at,
                command,
                what,
                data,
            } => {
                if self.unknown_commands.len() >= REQUESTS_CAPACITY {
                    self.unknown_commands.pop_front();
                }
                let at = DateTime::from(at);
                self.unknown_commands.push_back((at, command, what, data));
            }
            TuyaEvent::HeartbeatStopped => self.heartbeat_stopped = Some(now),
            TuyaEvent::McuRequest {
                at,
                command,
                name,
                answer,
                ..
            } => {
                let line = RequestLine {
                    clock: DateTime::from(at),
                    command,
                    name,
                    answer,
                };
                if matches!(command, cmd::RESET_WIFI | cmd::RESET_WIFI_MODE) {
                    self.resets.0 += 1;
                    self.resets.1 = Some(line.clone());
                }
                if self.requests.len() >= REQUESTS_CAPACITY {
                    self.requests.pop_front();
                }
                self.requests.push_back(line);
            }
        }
    }

    /// Takes a report (0x07 or 0x22), whenever it comes (a slow MCU's late one too): each data
    /// point in it, checked against the profile. One that fits is shown as its value; one of
    /// another type or length, or a value the data point does not allow, is shown raw with the
    /// mismatch, and the value shown before stays marked as older; one the profile lacks is
    /// kept apart by its own type.
    pub fn on_report(&mut self, profile: &Profile, p: &Packet) {
        if !matches!(p.header, Header::Tuya { .. }) || p.direction != Direction::DeviceToHost {
            return;
        }
        let (at, clock) = (Instant::now(), Local::now());
        for item in read_reports(profile, std::slice::from_ref(p)) {
            if !item.in_profile() {
                self.unknown_dps.insert(item.id, (item.clone(), clock));
                self.log(clock, item);
                continue;
            }
            match (&item.value, &item.misfit) {
                (Some(value), None) => {
                    self.misfits.remove(&item.id);
                    self.dps.insert(
                        item.id,
                        DpState {
                            value: value.clone(),
                            at,
                            clock,
                            query: self.queries,
                        },
                    );
                }
                _ => {
                    self.misfits
                        .insert(item.id, (item.clone(), clock, self.queries));
                }
            }
            self.log(clock, item);
        }
    }

    fn log(&mut self, clock: DateTime<Local>, item: ReportedDp) {
        if self.log.len() >= LOG_CAPACITY {
            self.log.pop_front();
        }
        self.log.push_back(LogLine {
            seq: self.log_seq,
            clock,
            item,
        });
        self.log_seq += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::session::tuya::parse_product_info;
    use crate::link::{self};

    fn step(step: HandshakeStep, ok: bool) -> TuyaEvent {
        let result = if ok {
            link::StepResult::WifiStateNotNeeded
        } else {
            link::StepResult::Failed(link::ExchangeError::Cancelled)
        };
        TuyaEvent::Step {
            step,
            result,
            at: std::time::SystemTime::now(),
            took: None,
        }
    }

    #[test]
    fn product_info_that_is_not_json_does_not_stop_the_handshake_but_no_answer_does() {
        let mut s = TuyaModel::default();
        s.on_event(step(HandshakeStep::Heartbeat, true));
        s.on_event(TuyaEvent::ProductInfo(parse_product_info(b"{\"p\":")));
        s.on_event(step(HandshakeStep::ProductInfo, false));
        assert!(s.stopped.is_none());
        assert!(s.shown_raw(HandshakeStep::ProductInfo));
        // The next attempt gets no answer at all.
        s.on_event(step(HandshakeStep::Heartbeat, true));
        s.on_event(step(HandshakeStep::ProductInfo, false));
        assert_eq!(s.attempts, 2);
        assert_eq!(
            s.stopped.as_ref().map(|(st, _)| *st),
            Some(HandshakeStep::ProductInfo)
        );
        assert!(s.steps[2].is_none(), "a new attempt clears the later steps");
        s.on_event(TuyaEvent::HandshakeDone);
        assert!(s.stopped.is_none() && s.done_at.is_some());
    }

    #[test]
    fn the_logs_are_bounded_and_a_wrong_typed_report_is_logged_not_shown() {
        let profile = crate::sim::tuya_mcu::builtin_vacuum_profile();
        let mut s = TuyaModel::default();
        let frame = |data: Vec<u8>| {
            Packet::tuya_received(crate::protocol::tuya::Frame::from_mcu(cmd::DP_REPORT, data))
        };
        // DP 6 (battery) is a value; reported as a bool it is kept raw with the mismatch.
        s.on_report(&profile, &frame(vec![6, 1, 0, 1, 1]));
        assert!(s.dps.is_empty());
        assert!(s.log[0].item.misfit.is_some());
        assert_eq!(s.misfits.get(&6).map(|m| m.0.raw.clone()), Some(vec![1]));
        s.on_report(&profile, &frame(vec![6, 2, 0, 4, 0, 0, 0, 42]));
        for _ in 0..LOG_CAPACITY {
            s.on_report(&profile, &frame(vec![1, 1, 0, 1, 1]));
        }
        assert_eq!(s.log.len(), LOG_CAPACITY);
        assert_eq!(s.dps.get(&1).map(|d| d.value.clone()), Some(Value::Int(1)));
        assert_eq!(s.dps.get(&6).map(|d| d.value.clone()), Some(Value::Int(42)));
        assert!(
            s.misfits.is_empty(),
            "a report that fits replaces the misfit"
        );
        for _ in 0..REQUESTS_CAPACITY + 5 {
            s.on_event(TuyaEvent::McuRequest {
                at: std::time::SystemTime::now(),
                command: cmd::RESET_WIFI,
                name: "reset Wi-Fi".into(),
                request: Vec::new(),
                reply: Some(cmd::RESET_WIFI),
                answer: Vec::new(),
            });
        }
        assert_eq!(s.requests.len(), REQUESTS_CAPACITY);
        assert_eq!(s.resets.0, REQUESTS_CAPACITY as u32 + 5);
    }
}
