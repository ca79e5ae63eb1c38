//! The protocol sessions the worker drives: what each protocol does on a connection beyond the
//! exchanges callers ask for. MSP identifies the device once per connection ([`msp`]); botbench
//! plays the Tuya Wi-Fi module, with its handshake, heartbeat and answers to the MCU ([`tuya`]);
//! the servo bus has no session of its own.
//!
//! A session is a state machine without I/O. The worker asks it for the request due
//! (`next_request`), runs the exchange, and hands it the result (`on_answer`), which gives back
//! the events to report. Frames that answer no request are sorted by `unasked`.

pub mod msp;
pub mod tuya;

pub use msp::{Capability, DeviceInfo, build_date, capabilities};

use crate::link::request::{ExchangeError, Match, Reply, ReplySpec, Request};
use crate::link::{LinkEvent, LinkOptions};
use crate::packet::{Header, Packet};
use crate::profile::{Profile, Protocol};
use crate::protocol::{Direction, EncodeError, msp as msp_codec, servo, tuya as tuya_codec};
use std::sync::Arc;
use std::time::Instant;
use tuya::TuyaEvent;

/// When a session's requests go out relative to the requests callers queued.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Precedence {
    /// Before them: they depend on it (MSP requests go to the device code CMD_VERSION names).
    BeforeRequests,
    /// After them, before telemetry polls (Tuya's handshake and heartbeat).
    AfterRequests,
}

/// What a frame from the device is when it is not the awaited answer.
#[derive(Debug)]
pub(crate) enum Unasked {
    /// Our own request read back (a one-wire servo adapter echoes it): ignored.
    Echo,
    /// A message the device sends on its own (an MSP async message, a Tuya data-point report):
    /// passed on as a report; it answers nothing.
    Report,
    /// A servo reply nobody waits for (it came late): passed on as a report, and an answer to
    /// something else.
    LateReply,
    /// An answer to something else (a late MSP or Tuya answer): dropped.
    Stale,
    /// The Tuya MCU's own request: the module writes `reply` (if it needs one) and reports
    /// `events`; a synchronous report (0x22) is passed on as a report too (`report`).
    McuRequest {
        /// The module's answer; `None` for an acknowledgement of the module's own push.
        reply: Option<tuya_codec::Frame>,
        /// What is reported.
        events: Vec<TuyaEvent>,
        /// The frame is a data-point report as well.
        report: bool,
    },
    /// A Tuya MCU command the module does not know: reported (`event`), logged and ignored.
    Ignored(TuyaEvent),
}

impl Unasked {
    /// Whether it answers some other request (so that a request that got only such frames
    /// failed with [`ExchangeError::Mismatch`] rather than a timeout).
    pub(crate) fn answers_other(&self) -> bool {
        matches!(self, Unasked::LateReply | Unasked::Stale)
    }
}

/// The protocol session of one link.
#[derive(Debug)]
pub(crate) enum ProtocolSession {
    /// MSP: identify once per connection.
    Msp(msp::MspSession),
    /// The servo bus: exchanges only. `id_param` is the profile's servo id parameter
    /// ([`crate::profile::ParamRole::ServoId`]), which every servo has: the fence after an
    /// unanswered ping reads it.
    Servo {
        /// Its parameter id, if the profile has one.
        id_param: Option<u8>,
    },
    /// Tuya: botbench as the Wi-Fi module.
    Tuya(tuya::TuyaSession),
}

impl ProtocolSession {
    /// The session for `profile`'s protocol, starting at `now` when
    /// [`LinkOptions::start_session`] says so.
    pub(crate) fn new(profile: Arc<Profile>, options: &LinkOptions, now: Instant) -> Self {
        match profile.protocol {
            Protocol::Msp => Self::Msp(msp::MspSession::new(profile, options.start_session)),
            Protocol::Servo => Self::Servo {
                id_param: profile.servo_id_param().map(|p| p.id),
            },
            Protocol::Tuya => Self::Tuya(tuya::TuyaSession::new(
                &profile,
                options.tuya.clone(),
                options.start_session,
                now,
            )),
        }
    }

    /// Its protocol.
    pub(crate) fn protocol(&self) -> Protocol {
        match self {
            Self::Msp(_) => Protocol::Msp,
            Self::Servo { .. } => Protocol::Servo,
            Self::Tuya(_) => Protocol::Tuya,
        }
    }

    /// The bytes of `req` and the frame they are, for the packet log. MSP requests that name no
    /// device code go to the session's; a request that waits for no answer asks the device for
    /// none. Errors: the payload is too long for the frame ([`ExchangeError::Encode`]).
    pub(crate) fn encode(&self, req: &Request) -> Result<(Vec<u8>, Packet), ExchangeError> {
        let enc = |e: EncodeError| ExchangeError::Encode(e.to_string());
        Ok(match self {
            Self::Msp(s) => {
                if let Some(refused) = s.refuses(req.command) {
                    return Err(refused);
                }
                let mut r = msp_codec::Request::new(
                    req.device.unwrap_or(s.device_code()),
                    req.command,
                    req.payload.clone(),
                );
                if req.reply == ReplySpec::None {
                    r.option = msp_codec::OPTION_SILENT;
                }
                (r.encode().map_err(enc)?, Packet::msp_request(r))
            }
            Self::Servo { .. } => {
                let f = servo::Frame::request(req.command, req.payload.clone());
                (f.encode().map_err(enc)?, Packet::servo(f))
            }
            Self::Tuya(_) => {
                let f = tuya_codec::Frame::from_module(req.command, req.payload.clone());
                (f.encode().map_err(enc)?, Packet::tuya(f))
            }
        })
    }

    /// The frame `sent` was written (a Tuya line that echoes gives it back): what the session
    /// reports of it (Tuya: a Wi-Fi state reported, a status query).
    pub(crate) fn wrote(&mut self, sent: &Packet) -> Option<LinkEvent> {
        match self {
            Self::Tuya(s) => s.wrote(sent).map(LinkEvent::Tuya),
            _ => None,
        }
    }

    /// A frame read from the line, sorted: on a Tuya line, the module's own frames echoed
    /// back are marked as sent by the host. With what the session reports of it (Tuya: a
    /// heartbeat answered, a Wi-Fi state acknowledged).
    pub(crate) fn received(&mut self, p: Packet) -> (Packet, Option<LinkEvent>) {
        match self {
            Self::Tuya(s) => {
                let (p, event) = s.received(p);
                (p, event.map(LinkEvent::Tuya))
            }
            _ => (p, None),
        }
    }

    /// Whether polls at the wire's maximum may be sent ahead of the answers still to come:
    /// MSP only, whose line is full duplex and whose device answers in order.
    pub(crate) fn pipelines_polls(&self) -> bool {
        matches!(self, Self::Msp(_))
    }

    /// Whether the device answers requests one by one, in order, so that an answer owed to an
    /// earlier request comes before a later request's (MSP, the servo bus); the Tuya MCU also
    /// speaks on its own and is not.
    pub(crate) fn in_order(&self) -> bool {
        matches!(self, Self::Msp(_) | Self::Servo { .. })
    }

    /// A request whose answer cannot be taken for `owed` (another command to the same device),
    /// to send before a request an owed answer could be taken for: when its answer comes, the
    /// owed one has come or never will. `None` where there is none (Tuya).
    pub(crate) fn fence_request(&self, owed: &Match) -> Option<Request> {
        match self {
            Self::Msp(_) if owed.command == msp_codec::CMD_PING => Some(
                Request::new(msp_codec::CMD_VERSION, Vec::new())
                    .device(msp_codec::DEVICE_CORE)
                    .attempts(2),
            ),
            Self::Msp(_) => Some(Request::new(msp_codec::CMD_PING, Vec::new()).attempts(2)),
            Self::Servo { id_param } => {
                let id = *owed.from.first()?;
                let (command, payload) = if owed.command == servo::cmd::PING {
                    (servo::cmd::READ_DATA, vec![id, (*id_param)?])
                } else {
                    (servo::cmd::PING, vec![id])
                };
                let answer = Match::servo(command, &[id]).with_prefix(payload.clone());
                Some(
                    Request::new(command, payload)
                        .reply(ReplySpec::Required(answer))
                        .attempts(2),
                )
            }
            Self::Tuya(_) => None,
        }
    }

    /// A new connection after a reconnect, at `now`.
    pub(crate) fn connected(&mut self, now: Instant) {
        match self {
            Self::Msp(s) => s.connected(),
            Self::Servo { .. } => {}
            Self::Tuya(s) => s.connected(now),
        }
    }

    /// The port went away (`reason`): whoever waits for the session is told.
    pub(crate) fn lost(&mut self, reason: &str) {
        match self {
            Self::Msp(s) => s.lost(&ExchangeError::Disconnected(reason.to_string())),
            Self::Servo { .. } => {}
            Self::Tuya(s) => s.lost(),
        }
    }

    /// The link closes: whoever waits for the session is told it was cancelled.
    pub(crate) fn closed(&mut self) {
        if let Self::Msp(s) = self {
            s.closed(&ExchangeError::Cancelled);
        }
    }

    /// [`crate::link::LinkCommand::DeviceInfo`]: MSP gives this connection's identification
    /// (when it is known, or once it is); other protocols have none
    /// ([`ExchangeError::NotInProtocol`]).
    pub(crate) fn want_device_info(&mut self, waiter: msp::InfoWaiter) {
        match self {
            Self::Msp(s) => s.want_device_info(waiter),
            _ => {
                let _ = waiter.send(Err(ExchangeError::NotInProtocol {
                    what: "device identification (CMD_VERSION)",
                    protocol: self.protocol(),
                }));
            }
        }
    }

    /// [`crate::link::LinkCommand::Identify`]: MSP identifies the device again.
    pub(crate) fn identify_again(&mut self) {
        if let Self::Msp(s) = self {
            s.identify_again();
        }
    }

    /// [`crate::link::LinkCommand::Handshake`]: Tuya runs the handshake again from `now`.
    pub(crate) fn handshake_again(&mut self, now: Instant) {
        if let Self::Tuya(s) = self {
            s.handshake_again(now);
        }
    }

    /// [`crate::link::LinkCommand::TuyaOptions`]: what the Tuya module answers the MCU.
    pub(crate) fn set_tuya_options(&mut self, options: tuya::TuyaModuleOptions) {
        if let Self::Tuya(s) = self {
            s.set_options(options);
        }
    }

    /// Whether a request of the session is due at `now`, and before or after callers' requests.
    pub(crate) fn due(&self, now: Instant) -> Option<Precedence> {
        match self {
            Self::Msp(s) => s.due().then_some(Precedence::BeforeRequests),
            Self::Servo { .. } => None,
            Self::Tuya(s) => s.due(now).then_some(Precedence::AfterRequests),
        }
    }

    /// The request due at `now`, if any; its result goes to [`Self::on_answer`].
    pub(crate) fn next_request(&mut self, now: Instant) -> Option<Request> {
        match self {
            Self::Msp(s) => s.next_request(),
            Self::Servo { .. } => None,
            Self::Tuya(s) => s.next_request(now),
        }
    }

    /// The result of the last request [`Self::next_request`] gave, at `now`: `events` gets what
    /// to report. Returns whether the session's next request follows at once (the next step of
    /// an identification or a handshake).
    pub(crate) fn on_answer(
        &mut self,
        result: Result<Reply, ExchangeError>,
        now: Instant,
        events: &mut Vec<LinkEvent>,
    ) -> bool {
        match self {
            Self::Msp(s) => s.on_answer(result, events),
            Self::Servo { .. } => false,
            Self::Tuya(s) => s.on_answer(result, now, events),
        }
    }

    /// What `p`, a frame that is not the awaited answer, is.
    pub(crate) fn unasked(&mut self, p: &Packet) -> Unasked {
        if p.direction != Direction::DeviceToHost {
            return Unasked::Echo;
        }
        match self {
            Self::Msp(_) => match p.header {
                Header::MspReply {
                    kind: msp_codec::ReplyKind::Async,
                } => Unasked::Report,
                _ => Unasked::Stale,
            },
            Self::Servo { .. } => Unasked::LateReply,
            Self::Tuya(s) => s.unasked(p),
        }
    }

    /// Whether `p`, taken as the answer to a request, is passed on as a report too: a Tuya
    /// data-point report answers a query or a data-point command and is a report all the same.
    pub(crate) fn answer_is_report(&self, p: &Packet) -> bool {
        matches!(self, Self::Tuya(_)) && p.command == tuya_codec::cmd::DP_REPORT
    }
}

#[cfg(test)]
mod tests;
