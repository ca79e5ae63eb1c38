//! The Tuya session: botbench plays the Wi-Fi module (PROTOCOL_NOTES §3). A state machine runs
//! the start-up handshake (heartbeat, product info, working mode, Wi-Fi state, query status),
//! then a heartbeat that notices an MCU restart and starts the handshake again; frames the MCU
//! sends on its own are answered ([`mcu_requests`]) or passed on as reports. The MCU's frames
//! are taken whatever their version byte, and told from the module's own echoed frames by what
//! was sent ([`echo`]).

mod echo;
mod mcu_requests;
mod product_info;
mod reports;

pub use mcu_requests::{
    Effect, McuAnswer, TuyaModuleOptions, Unknown, answer_mcu_request, local_time, utc_time,
};
pub use product_info::{ProductInfo, parse_product_info};
pub use reports::{command_ids, reported_ids, reports_reply};

use super::Unasked;
use crate::link::LinkEvent;
use crate::link::request::{ExchangeError, Reply, ReplySpec, Request};
use crate::packet::{Header, Packet};
use crate::profile::Profile;
use crate::protocol::Direction;
use crate::protocol::tuya::{self, VERSION_MCU, cmd};
use serde::Serialize;
use std::time::{Duration, Instant, SystemTime};

/// How soon a handshake that failed at a step starts again.
const HANDSHAKE_RETRY: Duration = Duration::from_secs(1);
/// How soon the heartbeat is sent again after the MCU missed one.
const HEARTBEAT_RETRY: Duration = Duration::from_secs(3);

/// A step of the module's start-up handshake.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum HandshakeStep {
    /// 0x00 until the MCU answers.
    Heartbeat,
    /// 0x01: PID, MCU version, configuration mode.
    ProductInfo,
    /// 0x02: who drives the Wi-Fi LED.
    WorkMode,
    /// 0x03: the Wi-Fi state, when the MCU drives the LED.
    WifiState,
    /// 0x08: every data point, as a burst of 0x07 reports.
    QueryStatus,
}

impl HandshakeStep {
    /// All steps, in order.
    pub const ALL: [HandshakeStep; 5] = [
        HandshakeStep::Heartbeat,
        HandshakeStep::ProductInfo,
        HandshakeStep::WorkMode,
        HandshakeStep::WifiState,
        HandshakeStep::QueryStatus,
    ];

    /// The command word it sends.
    pub fn command(self) -> u8 {
        match self {
            HandshakeStep::Heartbeat => cmd::HEARTBEAT,
            HandshakeStep::ProductInfo => cmd::PRODUCT_INFO,
            HandshakeStep::WorkMode => cmd::WORK_MODE,
            HandshakeStep::WifiState => cmd::WIFI_STATE,
            HandshakeStep::QueryStatus => cmd::QUERY_STATUS,
        }
    }
}

/// What a handshake step found, as data: the command line says it in English (`Display`),
/// the window in either language.
#[derive(Debug, Clone, PartialEq)]
pub enum StepResult {
    /// 0x00 answered.
    Heartbeat {
        /// The MCU answered 0: its first heartbeat since it started (1 afterwards).
        first_since_start: bool,
        /// The version byte of the answer's frame (see [`TuyaEvent::FrameVersion`]).
        frame_version: Option<u8>,
    },
    /// 0x01 answered: the product info, read as JSON or, when it is not, kept raw with why
    /// ([`ProductInfo::error`]); the handshake goes on either way.
    ProductInfo(ProductInfo),
    /// 0x02 answered: `None` when the MCU drives the Wi-Fi LED, else the module's GPIO numbers
    /// (LED, reset).
    WorkMode {
        /// The module's GPIOs (LED, reset), when it drives the LED itself.
        gpio: Option<(u8, u8)>,
    },
    /// 0x03 not sent: the module drives the LED, so the MCU needs no Wi-Fi state.
    WifiStateNotNeeded,
    /// 0x03 answered: the Wi-Fi state (0-6) reported to the MCU.
    WifiStateReported {
        /// The state reported.
        state: u8,
    },
    /// 0x08 answered: of the profile's `total` data points, `missing` (ids, in the profile's
    /// order) were not reported.
    Status {
        /// The profile's data points.
        total: usize,
        /// Those not reported.
        missing: Vec<u8>,
    },
    /// The step's exchange failed (no answer, a garbled one, the port lost).
    Failed(ExchangeError),
}

impl StepResult {
    /// Whether the step worked: it did not fail, a product info was valid JSON, and the status
    /// query heard every data point (the handshake goes on either way).
    pub fn ok(&self) -> bool {
        match self {
            StepResult::Failed(_) => false,
            StepResult::ProductInfo(info) => info.error.is_none(),
            StepResult::Status { missing, .. } => missing.is_empty(),
            _ => true,
        }
    }
}

impl std::fmt::Display for StepResult {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StepResult::Heartbeat {
                first_since_start,
                frame_version,
            } => {
                let answer = if *first_since_start {
                    "answered 0: first since the MCU started"
                } else {
                    "answered 1"
                };
                match frame_version {
                    Some(v) => write!(f, "{answer}; {}", version_text(*v)),
                    None => f.write_str(answer),
                }
            }
            StepResult::ProductInfo(info) => match &info.error {
                None => {
                    let pid = info.pid.as_deref().unwrap_or("?");
                    let version = info.version.as_deref().unwrap_or("?");
                    let mode = info.mode.map_or("?".to_string(), |m| m.to_string());
                    write!(f, "PID {pid}, MCU {version}, mode {mode}")
                }
                Some(e) => write!(f, "not valid JSON ({e}); shown raw: {}", info.raw),
            },
            StepResult::WorkMode { gpio: None } => f.write_str("the MCU drives the Wi-Fi LED"),
            StepResult::WorkMode {
                gpio: Some((led, reset)),
            } => write!(
                f,
                "the module drives the LED (GPIO {led}, reset GPIO {reset})"
            ),
            StepResult::WifiStateNotNeeded => f.write_str("not needed: the module drives the LED"),
            StepResult::WifiStateReported { state } => write!(f, "reported state {state}"),
            StepResult::Status { total, missing } if missing.is_empty() => {
                write!(f, "all {total} data points reported")
            }
            StepResult::Status { total, missing } => {
                let ids: Vec<String> = missing.iter().map(u8::to_string).collect();
                write!(
                    f,
                    "{} of {total} data points reported; not reported: {}",
                    total - missing.len(),
                    ids.join(", ")
                )
            }
            StepResult::Failed(e) => e.fmt(f),
        }
    }
}

/// What the Tuya part of the link reports.
#[derive(Debug, Clone, PartialEq)]
pub enum TuyaEvent {
    /// A handshake step finished, well or not ([`StepResult::ok`]).
    Step {
        /// Which.
        step: HandshakeStep,
        /// What it found, or why it failed.
        result: StepResult,
        /// When it finished (its answer came, or it gave up), on the wall clock.
        at: SystemTime,
        /// From its request's send to its end; `None` for a step that sent nothing (the Wi-Fi
        /// state the MCU does not need).
        took: Option<Duration>,
    },
    /// The version byte of the MCU's frames (its heartbeat answer's): 0x03 by the protocol
    /// document, 0x01 from MCU SDKs before v2.5, 0x00 from some firmware.
    FrameVersion {
        /// The version byte.
        version: u8,
    },
    /// Product info as read.
    ProductInfo(ProductInfo),
    /// The working mode: the MCU drives the LED, or the module's GPIO numbers.
    WorkMode {
        /// GPIO numbers (LED, reset) when the module drives the LED itself.
        gpio: Option<(u8, u8)>,
    },
    /// Every step done; heartbeats follow.
    HandshakeDone,
    /// The heartbeat answer was 0: the MCU restarted, and the handshake runs again.
    McuRestarted,
    /// The MCU stopped answering heartbeats.
    HeartbeatLost,
    /// The MCU answered a heartbeat (0x00): its byte, 0 the first since it started, 1 later.
    Heartbeat {
        /// The answer's byte, if it had one.
        answer: Option<u8>,
    },
    /// The module reported a Wi-Fi state (0x03, 0-6) to the MCU.
    WifiStateSent {
        /// The state reported.
        state: u8,
    },
    /// The MCU acknowledged a Wi-Fi state (its 0x03 answer).
    WifiStateAcked,
    /// The module asked for every data point's status (0x08).
    StatusQueried,
    /// The MCU asked something and the module answered (or, for an acknowledgement of the
    /// module's own push, took it).
    McuRequest {
        /// When the module took it, on the wall clock.
        at: SystemTime,
        /// The MCU's command word.
        command: u8,
        /// What it asked.
        name: String,
        /// The request's data.
        request: Vec<u8>,
        /// The answer's command word (the request's, 0x23 for a 0x22); `None` when the frame
        /// needs no answer.
        reply: Option<u8>,
        /// The answer's data.
        answer: Vec<u8>,
    },
    /// The MCU sent a command (or an extended-service sub-command) the module does not know:
    /// logged with its bytes and ignored, as a real module does.
    McuUnknown {
        /// When the module took it, on the wall clock.
        at: SystemTime,
        /// The command word.
        command: u8,
        /// What the module made of it: `command 0x99`, `extended service sub-command 0x36`.
        what: String,
        /// The frame's data.
        data: Vec<u8>,
    },
    /// The MCU asked the module to stop its heartbeat (0x25): the module acknowledged and sends
    /// none from now until the next handshake; an MCU restart is then not seen by it.
    HeartbeatStopped,
}

/// The Tuya session of one link: the module's side of the handshake and heartbeat.
#[derive(Debug)]
pub(crate) struct TuyaSession {
    /// What the module answers the MCU; changed at any time, even during an exchange.
    options: TuyaModuleOptions,
    /// Run the handshake on every new connection ([`crate::link::LinkOptions::start_session`]).
    handshake_on_connect: bool,
    phase: Phase,
    /// What was sent and is awaited.
    asked: Option<Ask>,
    /// The profile's data points: the status query's answer is complete when each reported.
    data_points: Vec<u8>,
    /// The status query's answer: the reports of every data point.
    status_reply: ReplySpec,
    /// The module's own frames read back on a line that echoes.
    echo: echo::EchoFilter,
    /// The MCU asked for no heartbeats (0x25): none is sent until the next handshake.
    heartbeat_stopped: bool,
}

/// Where the module stands with the MCU.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// Nothing scheduled (no handshake asked on this connection, or the port was lost).
    Idle,
    /// The handshake starts at this time (at once on connect, a second after a failed step).
    HandshakeAt(Instant),
    /// In the handshake: this step is sent next, at once.
    Handshake(HandshakeStep),
    /// The handshake is done; the next heartbeat is due at this time.
    Heartbeat(Instant),
}

/// A request sent and awaited.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Ask {
    /// A handshake step (for 0x03, with the Wi-Fi state reported), sent at this time.
    Step(HandshakeStep, u8, Instant),
    /// The heartbeat after the handshake.
    Heartbeat,
}

impl TuyaSession {
    /// A session answering the MCU with `options`; the handshake starts at `now` when
    /// `handshake_on_connect`.
    pub(crate) fn new(
        profile: &Profile,
        options: TuyaModuleOptions,
        handshake_on_connect: bool,
        now: Instant,
    ) -> Self {
        // A write-only data point is never reported.
        let data_points: Vec<u8> = profile
            .data_points
            .iter()
            .filter(|d| d.access.reported())
            .map(|d| d.id)
            .collect();
        let mut session = Self {
            options,
            handshake_on_connect,
            phase: Phase::Idle,
            asked: None,
            status_reply: reports_reply(profile, &data_points),
            data_points,
            echo: echo::EchoFilter::default(),
            heartbeat_stopped: false,
        };
        session.connected(now);
        session
    }

    /// Changes what the module answers the MCU, and the heartbeat interval: a heartbeat already
    /// scheduled moves to the new interval after the last one (a shorter interval does not wait
    /// out the old one).
    pub(crate) fn set_options(&mut self, options: TuyaModuleOptions) {
        if let Phase::Heartbeat(due) = self.phase
            && let Some(last) = due.checked_sub(self.options.heartbeat)
        {
            self.phase = Phase::Heartbeat(last + options.heartbeat);
        }
        self.options = options;
    }

    /// A new connection (the first, or after a reconnect).
    pub(crate) fn connected(&mut self, now: Instant) {
        self.echo.connected();
        self.heartbeat_stopped = false;
        if self.handshake_on_connect {
            self.phase = Phase::HandshakeAt(now);
        }
    }

    /// The port went away: the heartbeat stops until a handshake. A handshake under way fails
    /// at its step and is tried again.
    pub(crate) fn lost(&mut self) {
        if let Phase::Heartbeat(_) = self.phase {
            self.phase = Phase::Idle;
        }
    }

    /// [`crate::link::LinkCommand::Handshake`]: the handshake starts again at `now`.
    pub(crate) fn handshake_again(&mut self, now: Instant) {
        self.phase = Phase::HandshakeAt(now);
        self.heartbeat_stopped = false;
    }

    /// Whether a request is due at `now`: no heartbeat after the MCU asked for none (0x25).
    pub(crate) fn due(&self, now: Instant) -> bool {
        match self.phase {
            Phase::Idle => false,
            Phase::Heartbeat(_) if self.heartbeat_stopped => false,
            Phase::HandshakeAt(at) | Phase::Heartbeat(at) => at <= now,
            Phase::Handshake(_) => true,
        }
    }

    /// The module wrote the frame `sent`: what it reports, when it is a Wi-Fi state or a status
    /// query.
    pub(crate) fn wrote(&mut self, sent: &Packet) -> Option<TuyaEvent> {
        self.echo.wrote(&sent.wire);
        match sent.command {
            cmd::WIFI_STATE => sent
                .payload
                .first()
                .map(|&state| TuyaEvent::WifiStateSent { state }),
            cmd::QUERY_STATUS => Some(TuyaEvent::StatusQueried),
            _ => None,
        }
    }

    /// A frame read from the line, as the MCU's or, when it repeats what the module sent, as
    /// the module's own echo (direction host to device); and what it reports, when it is the
    /// MCU's answer to a heartbeat or to a Wi-Fi state.
    pub(crate) fn received(&mut self, mut p: Packet) -> (Packet, Option<TuyaEvent>) {
        if self.echo.is_echo(&p) {
            p.direction = Direction::HostToDevice;
            return (p, None);
        }
        let event = match p.command {
            cmd::HEARTBEAT => Some(TuyaEvent::Heartbeat {
                answer: p.payload.first().copied(),
            }),
            cmd::WIFI_STATE => Some(TuyaEvent::WifiStateAcked),
            _ => None,
        };
        (p, event)
    }

    /// The request due at `now`, if any; its answer is then awaited.
    pub(crate) fn next_request(&mut self, now: Instant) -> Option<Request> {
        if !self.due(now) {
            return None;
        }
        let step = match self.phase {
            Phase::Heartbeat(_) => {
                self.asked = Some(Ask::Heartbeat);
                return Some(Request::new(cmd::HEARTBEAT, Vec::new()).attempts(2));
            }
            Phase::HandshakeAt(_) => HandshakeStep::Heartbeat,
            Phase::Handshake(step) => step,
            Phase::Idle => return None,
        };
        self.phase = Phase::Handshake(step);
        let wifi_state = self.options.wifi_state;
        self.asked = Some(Ask::Step(step, wifi_state, now));
        Some(match step {
            HandshakeStep::Heartbeat => Request::new(cmd::HEARTBEAT, Vec::new()).attempts(2),
            HandshakeStep::WifiState => Request::new(cmd::WIFI_STATE, vec![wifi_state]),
            HandshakeStep::QueryStatus => {
                Request::new(cmd::QUERY_STATUS, Vec::new()).reply(self.status_reply.clone())
            }
            HandshakeStep::ProductInfo | HandshakeStep::WorkMode => {
                Request::new(step.command(), Vec::new())
            }
        })
    }

    /// The result of the request [`Self::next_request`] gave, at `now`. Returns whether the next
    /// handshake step follows at once; `events` gets what to report.
    pub(crate) fn on_answer(
        &mut self,
        result: Result<Reply, ExchangeError>,
        now: Instant,
        events: &mut Vec<LinkEvent>,
    ) -> bool {
        match self.asked.take() {
            Some(Ask::Step(step, wifi_state, sent)) => match result {
                Ok(reply) => {
                    let took = now.saturating_duration_since(sent);
                    self.step_done((step, took), wifi_state, &reply, now, events)
                }
                Err(e) => {
                    let took = now.saturating_duration_since(sent);
                    events.push(step_event(step, StepResult::Failed(e), Some(took)));
                    self.phase = Phase::HandshakeAt(now + HANDSHAKE_RETRY);
                    false
                }
            },
            Some(Ask::Heartbeat) => {
                match result {
                    Ok(r) if r.payload() == Some(&[0][..]) => {
                        events.push(LinkEvent::Tuya(TuyaEvent::McuRestarted));
                        self.phase = Phase::HandshakeAt(now);
                    }
                    Ok(_) => self.phase = Phase::Heartbeat(now + self.options.heartbeat),
                    // The port is gone: the handshake runs again on the next connection.
                    Err(ExchangeError::Disconnected(_)) => {}
                    Err(_) => {
                        events.push(LinkEvent::Tuya(TuyaEvent::HeartbeatLost));
                        self.phase = Phase::Heartbeat(now + HEARTBEAT_RETRY);
                    }
                }
                false
            }
            None => false,
        }
    }

    /// A handshake step answered after `took` since its request: reports it and moves to the
    /// next step (returns `true`), or ends the handshake.
    fn step_done(
        &mut self,
        (step, took): (HandshakeStep, Duration),
        wifi_state: u8,
        reply: &Reply,
        now: Instant,
        events: &mut Vec<LinkEvent>,
    ) -> bool {
        let payload = reply.payload().unwrap_or_default();
        let next = match step {
            HandshakeStep::Heartbeat => heartbeat_answered(reply, took, events),
            HandshakeStep::ProductInfo => {
                let info = parse_product_info(payload);
                events.push(LinkEvent::Tuya(TuyaEvent::ProductInfo(info.clone())));
                events.push(step_event(step, StepResult::ProductInfo(info), Some(took)));
                HandshakeStep::WorkMode
            }
            HandshakeStep::WorkMode => work_mode_answered(payload, took, events),
            HandshakeStep::WifiState => {
                let result = StepResult::WifiStateReported { state: wifi_state };
                events.push(step_event(step, result, Some(took)));
                HandshakeStep::QueryStatus
            }
            HandshakeStep::QueryStatus => {
                events.push(step_event(step, self.status_of(reply), Some(took)));
                events.push(LinkEvent::Tuya(TuyaEvent::HandshakeDone));
                self.phase = Phase::Heartbeat(now + self.options.heartbeat);
                return false;
            }
        };
        self.phase = Phase::Handshake(next);
        true
    }

    /// The status query's result: which of the profile's data points its reports left out.
    fn status_of(&self, reply: &Reply) -> StepResult {
        let reported = reported_ids(&reply.packets);
        let missing: Vec<u8> = self
            .data_points
            .iter()
            .copied()
            .filter(|id| !reported.contains(id))
            .collect();
        StepResult::Status {
            total: self.data_points.len(),
            missing,
        }
    }

    /// A frame from the MCU that is not the awaited answer: one of its own requests (answered:
    /// a synchronous report 0x22 is a report too, answered 0x23), a data-point report, a
    /// command the module does not know (logged and ignored), or an answer to something else.
    pub(crate) fn unasked(&mut self, p: &Packet) -> Unasked {
        match answer_mcu_request(&self.options, p.command, &p.payload) {
            Ok(Some(answer)) => {
                if answer.effect == Some(Effect::StopHeartbeat) {
                    self.heartbeat_stopped = true;
                }
                let reply = answer
                    .reply
                    .as_ref()
                    .map(|(c, d)| tuya::Frame::from_module(*c, d.clone()));
                let (reply_command, data) = answer.reply.unwrap_or((p.command, Vec::new()));
                let mut events = vec![TuyaEvent::McuRequest {
                    at: SystemTime::now(),
                    command: p.command,
                    name: answer.name.to_string(),
                    request: p.payload.clone(),
                    reply: reply.as_ref().map(|_| reply_command),
                    answer: data,
                }];
                if answer.effect == Some(Effect::StopHeartbeat) {
                    events.push(TuyaEvent::HeartbeatStopped);
                }
                Unasked::McuRequest {
                    reply,
                    events,
                    report: p.command == cmd::DP_REPORT_SYNC,
                }
            }
            Ok(None) if p.command == cmd::DP_REPORT => Unasked::Report,
            Ok(None) => Unasked::Stale,
            Err(Unknown { what }) => {
                log::warn!(
                    "MCU {what} not known to the module: ignored [{}]",
                    crate::protocol::hex::format(&p.wire)
                );
                Unasked::Ignored(TuyaEvent::McuUnknown {
                    at: SystemTime::now(),
                    command: p.command,
                    what,
                    data: p.payload.clone(),
                })
            }
        }
    }
}

/// The MCU's frame version as a person reads it: `MCU frames carry version 0x00 (the protocol
/// document says 0x03)`.
pub fn version_text(version: u8) -> String {
    if version == VERSION_MCU {
        format!("MCU frames carry version {version:#04x}")
    } else {
        format!(
            "MCU frames carry version {version:#04x} (the protocol document says {VERSION_MCU:#04x})"
        )
    }
}

/// The heartbeat step answered after `took`: its answer (0 first since the MCU started) and the
/// version byte of the MCU's frames are reported; product info is next.
fn heartbeat_answered(reply: &Reply, took: Duration, events: &mut Vec<LinkEvent>) -> HandshakeStep {
    let frame_version = match reply.packets.first().map(|p| &p.header) {
        Some(Header::Tuya { version }) => Some(*version),
        _ => None,
    };
    if let Some(version) = frame_version {
        events.push(LinkEvent::Tuya(TuyaEvent::FrameVersion { version }));
    }
    let result = StepResult::Heartbeat {
        first_since_start: reply.payload() == Some(&[0][..]),
        frame_version,
    };
    events.push(step_event(HandshakeStep::Heartbeat, result, Some(took)));
    HandshakeStep::ProductInfo
}

/// The working mode answered after `took`: who drives the Wi-Fi LED. When the module does, the
/// MCU needs no Wi-Fi state (that step is reported as not needed, having sent nothing) and the
/// status query is next.
fn work_mode_answered(
    payload: &[u8],
    took: Duration,
    events: &mut Vec<LinkEvent>,
) -> HandshakeStep {
    let gpio = match payload {
        [led, reset, ..] => Some((*led, *reset)),
        _ => None,
    };
    events.push(LinkEvent::Tuya(TuyaEvent::WorkMode { gpio }));
    events.push(step_event(
        HandshakeStep::WorkMode,
        StepResult::WorkMode { gpio },
        Some(took),
    ));
    if gpio.is_none() {
        return HandshakeStep::WifiState;
    }
    let skipped = StepResult::WifiStateNotNeeded;
    events.push(step_event(HandshakeStep::WifiState, skipped, None));
    HandshakeStep::QueryStatus
}

/// A step's end, now, `took` after its request.
fn step_event(step: HandshakeStep, result: StepResult, took: Option<Duration>) -> LinkEvent {
    LinkEvent::Tuya(TuyaEvent::Step {
        step,
        result,
        at: SystemTime::now(),
        took,
    })
}
