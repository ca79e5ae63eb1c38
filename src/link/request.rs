//! What a caller asks of the link, and what comes back.

use crate::packet::Packet;
use crate::protocol::FrameError;
use std::time::Duration;

/// One exchange: a frame to send and the answer to wait for.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Request {
    /// The command number.
    pub command: u8,
    /// The payload (for servo frames, starting with the servo id).
    pub payload: Vec<u8>,
    /// MSP: the device code, when it is not the link's (the profile's, or the hardware code
    /// CMD_VERSION named); CMD_VERSION itself goes to 0x00.
    pub device: Option<u8>,
    /// What answer to wait for.
    pub reply: ReplySpec,
    /// Attempts before giving up (at least 1).
    pub attempts: u8,
    /// How long the device may take to start answering, beyond the wire time; `None` for the
    /// link's default.
    pub margin: Option<Duration>,
    /// Send the frame with its checksum off by one: a conformance test of how the device takes
    /// a corrupted frame ([`Request::bad_checksum`]).
    pub bad_checksum: bool,
}

impl Request {
    /// A request answered by a frame of the same command.
    pub fn new(command: u8, payload: Vec<u8>) -> Self {
        Self {
            command,
            payload,
            device: None,
            reply: ReplySpec::Required(Match::command(command)),
            attempts: 3,
            margin: None,
            bad_checksum: false,
        }
    }

    /// A request that expects no answer.
    pub fn send_only(command: u8, payload: Vec<u8>) -> Self {
        Self {
            reply: ReplySpec::None,
            attempts: 1,
            ..Self::new(command, payload)
        }
    }

    /// Sets the number of attempts.
    pub fn attempts(mut self, n: u8) -> Self {
        self.attempts = n.max(1);
        self
    }

    /// Sets the answer to wait for.
    pub fn reply(mut self, spec: ReplySpec) -> Self {
        self.reply = spec;
        self
    }

    /// Sends to this MSP device code.
    pub fn device(mut self, code: u8) -> Self {
        self.device = Some(code);
        self
    }

    /// Sends the frame with its last byte (the checksum, in every protocol here) one more than
    /// it should be: a well-behaved device drops it and answers nothing.
    pub fn bad_checksum(mut self) -> Self {
        self.bad_checksum = true;
        self
    }

    /// Sets how long the device may take to start answering.
    pub fn margin(mut self, margin: Duration) -> Self {
        self.margin = Some(margin);
        self
    }
}

/// How long the line stays quiet before a synchronous MONITOR's answers are taken as complete:
/// each servo answers after the one before (21 bytes: 22 ms at 9600 baud), a missing one leaves
/// a gap.
pub const SYNC_QUIET: Duration = Duration::from_millis(60);

/// Which incoming frame answers a request.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Match {
    /// The answer's command.
    pub command: u8,
    /// Servo: the ids an answer may come from (after an id change, the new one too). Empty: any.
    pub from: Vec<u8>,
    /// Bytes the answer's payload must start with (a servo READ_DATA answer names its
    /// parameter), so that a late answer to an earlier request is never taken for this one.
    pub prefix: Vec<u8>,
}

impl Match {
    /// An answer with this command, from anyone.
    pub fn command(command: u8) -> Self {
        Self {
            command,
            from: Vec::new(),
            prefix: Vec::new(),
        }
    }

    /// A servo answer with this command from one of `ids`.
    pub fn servo(command: u8, ids: &[u8]) -> Self {
        Self {
            command,
            from: ids.to_vec(),
            prefix: Vec::new(),
        }
    }

    /// Whether some frame could answer both: the same command, servo ids in common (or either
    /// takes any), and one prefix the start of the other.
    pub fn overlaps(&self, other: &Match) -> bool {
        let ids = self.from.is_empty()
            || other.from.is_empty()
            || self.from.iter().any(|id| other.from.contains(id));
        let prefixes =
            self.prefix.starts_with(&other.prefix) || other.prefix.starts_with(&self.prefix);
        self.command == other.command && ids && prefixes
    }

    /// Also requires the answer's payload to start with `prefix`.
    pub fn with_prefix(mut self, prefix: Vec<u8>) -> Self {
        self.prefix = prefix;
        self
    }

    /// Whether `p` (an incoming frame) is the answer. Only a reply answers: an MSP frame the
    /// device sends on its own (kind 0xFE) never does, whatever its command.
    pub fn accepts(&self, p: &Packet) -> bool {
        p.direction == crate::protocol::Direction::DeviceToHost
            && !matches!(
                p.header,
                crate::packet::Header::MspReply {
                    kind: crate::protocol::msp::ReplyKind::Async
                }
            )
            && p.command == self.command
            && (self.from.is_empty() || p.payload.first().is_some_and(|id| self.from.contains(id)))
            && p.payload.starts_with(&self.prefix)
    }
}

/// What answer a request waits for.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ReplySpec {
    /// None: the request is only sent.
    None,
    /// Exactly one matching frame; none is an error.
    Required(Match),
    /// One matching frame if the device sends one (a servo with its response switch off does
    /// not); none is not an error.
    Optional(Match),
    /// Every matching frame until the line is quiet for `quiet` (the answers of a servo
    /// synchronous MONITOR, each servo in turn), at least one.
    Burst {
        /// What each frame of the burst matches.
        each: Match,
        /// How long a pause ends the burst.
        quiet: Duration,
    },
    /// Tuya data-point reports (0x07) answering a status query or a data-point command: every
    /// matching frame until each of `ids` has been reported, or until a bounded time has
    /// passed (the request's and the reports' wire time twice over, plus the device's margin),
    /// at least one. Never on a pause alone: an MCU that reports on its own is never quiet.
    Reports {
        /// What each report matches.
        each: Match,
        /// The data points the answer is complete with.
        ids: Vec<u8>,
        /// The reports' expected size on the wire, in bytes: it bounds the wait.
        bytes: usize,
    },
}

impl ReplySpec {
    /// What each answering frame matches; `None` when no answer is awaited.
    pub fn each(&self) -> Option<&Match> {
        match self {
            ReplySpec::None => None,
            ReplySpec::Required(m) | ReplySpec::Optional(m) => Some(m),
            ReplySpec::Burst { each, .. } | ReplySpec::Reports { each, .. } => Some(each),
        }
    }
}

/// A successful exchange.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Reply {
    /// The answering frames (one, or a burst; none for a send-only or unanswered optional).
    pub packets: Vec<Packet>,
    /// From the request's first byte written to the answer's last frame read (a burst's last
    /// frame, not the end of the wait); zero when nothing answered (a send-only request, an
    /// unanswered optional one).
    pub rtt: Duration,
    /// Attempts used.
    pub attempts: u8,
}

impl Reply {
    /// The payload of the (first) answer.
    pub fn payload(&self) -> Option<&[u8]> {
        self.packets.first().map(|p| p.payload.as_slice())
    }
}

/// A command as an error names it: its number on the wire and, when the link's profile has
/// the command, its identifier from the protocol document. Shown as `CMD_VERSION (2)`, or
/// `command 2` when the profile does not name it. Made from the number alone (`2.into()`) where
/// an error is found (the link's worker), and named by the [`Client`](super::Client) that hands
/// it on ([`ExchangeError::named`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CommandName {
    /// The command number.
    pub id: u8,
    /// The profile's identifier for it, e.g. `CMD_VERSION`.
    pub ident: Option<String>,
}

impl From<u8> for CommandName {
    fn from(id: u8) -> Self {
        Self { id, ident: None }
    }
}

impl CommandName {
    /// `self`, named by `profile` when it has the command and no name was given yet.
    pub fn named(self, profile: &crate::profile::Profile) -> Self {
        match self.ident {
            Some(_) => self,
            None => Self {
                ident: profile.command_by_id(self.id).map(|c| c.ident.clone()),
                id: self.id,
            },
        }
    }
}

impl std::fmt::Display for CommandName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.ident {
            Some(ident) => write!(f, "{ident} ({})", self.id),
            None => write!(f, "command {}", self.id),
        }
    }
}

/// Why an exchange failed. Nothing stale is ever returned in place of an answer.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ExchangeError {
    /// No answer within the deadline, after every attempt. When the link's thread woke
    /// [`HELD_UP`] or more past a deadline it had set during the exchange (a loaded computer),
    /// the silence says so: the answer may have come and the host not been there.
    #[error("no answer to {command} after {attempts} attempt(s) of {waited_ms} ms{}", host_late.map_or(String::new(), held_up))]
    Timeout {
        /// The command.
        command: CommandName,
        /// Attempts made.
        attempts: u8,
        /// How long each attempt waited, in ms.
        waited_ms: u64,
        /// The most this computer ran behind a deadline the link had set during the exchange,
        /// when [`HELD_UP`] or more: the host was held up (a loaded computer), and the answer
        /// may have come while it was. `None`: the host was on time.
        host_late: Option<Duration>,
    },
    /// Answers came back damaged (bad checksum, junk, cut short) on every attempt. On a servo bus,
    /// the sign of two servos sharing an id.
    #[error("garbled answer to {command}: {error}")]
    Garbled {
        /// The command.
        command: CommandName,
        /// The last frame error seen.
        error: FrameError,
    },
    /// Only frames that answer something else came back (a late answer to an earlier request,
    /// or a servo answering from another id).
    #[error("expected an answer to {expected}, got {got}{}", from.map_or(String::new(), |id| format!(" from servo {id}")))]
    Mismatch {
        /// The command asked.
        expected: CommandName,
        /// The command that answered.
        got: CommandName,
        /// Servo: the id it came from.
        from: Option<u8>,
    },
    /// An answer came but does not read as its command's layout (a CMD_VERSION answer too
    /// short for the profile's fields).
    #[error("the answer to {command} does not read: {reason}")]
    Unreadable {
        /// The command answered.
        command: CommandName,
        /// What is wrong with it.
        reason: String,
    },
    /// The link's protocol has no such exchange (device identification asked of a servo bus or
    /// a Tuya MCU).
    #[error("{what} is not part of the {} protocol", protocol.name())]
    NotInProtocol {
        /// What was asked.
        what: &'static str,
        /// The link's protocol.
        protocol: crate::profile::Protocol,
    },
    /// The request could not be built (payload too long).
    #[error("cannot send: {0}")]
    Encode(String),
    /// No answer, and the answers are being taken by someone else: the port said bytes had
    /// arrived and they were gone when read, or another program has the port open (a second
    /// botbench, a terminal program, ModemManager). Not the device's silence nor the wiring.
    #[error(
        "no answer to {command}: bytes are being taken by someone else reading {port} ({by}); close it and try again"
    )]
    Taken {
        /// The command.
        command: CommandName,
        /// The port.
        port: String,
        /// Who: the programs that have it open (`cat (pid 4711)`), or that the port said bytes
        /// had arrived that were gone when read.
        by: String,
    },
    /// The device identified as another kind than its profile is for (CMD_VERSION's `hw`):
    /// nothing but identification is sent to it, whatever `--strict` says.
    #[error(
        "{command} not sent: the device identifies as hardware {hw:#04x}, and profile \
         {profile} is for hardware {claimed:#04x}; choose this device's profile (--profile)"
    )]
    NotThisDevice {
        /// The command refused.
        command: CommandName,
        /// The hardware code the device gave.
        hw: u8,
        /// The hardware code the profile is for.
        claimed: u8,
        /// The profile.
        profile: String,
    },
    /// The port went away.
    #[error("link lost: {0}")]
    Disconnected(String),
    /// The link was closed or the request cancelled.
    #[error("cancelled")]
    Cancelled,
}

/// How far behind a deadline it set the link's thread may run before it counts as a late host
/// (a loaded computer): a scheduler's ordinary wake-up is well under a millisecond.
pub const HOST_LATE: Duration = Duration::from_millis(2);

/// How far behind an answer's deadline the link's thread must have run for a timeout or a scan
/// to say that this computer was held up: a few milliseconds late is common on a busy desktop
/// and explains no silence (the link looks once more when it wakes late); 20 ms is most of the
/// shortest answer window (25 ms).
pub const HELD_UP: Duration = Duration::from_millis(20);

/// `late` when it is [`HELD_UP`] or more: how late a timeout or a scan says the host ran.
pub fn held_up_by(late: Duration) -> Option<Duration> {
    (late >= HELD_UP).then_some(late)
}

/// What is said of a host that ran `late` behind an answer's deadline, in both languages: `this
/// computer was held up 31 ms past the answer's deadline (a loaded computer: the answer may have
/// come while it was): close other programs and retry`. A timeout says it after its figures, the
/// silent device's checklist first ([`crate::link::silent`]).
pub fn held_up_said(late: Duration) -> crate::i18n::Text {
    let ms = late.as_millis();
    crate::i18n::Text::new(
        format!(
            "this computer was held up {ms} ms past the answer's deadline (a loaded computer: \
             the answer may have come while it was): close other programs and retry"
        ),
        format!(
            "这台电脑在应答截止时间后被拖住了 {ms} ms(电脑负载过高:应答可能在此期间已到达):\
             请关闭其他程序后重试"
        ),
    )
}

/// [`held_up_said`] in English after a timeout's figures (` — this computer was …`).
fn held_up(late: Duration) -> String {
    format!(" — {}", held_up_said(late).en)
}

impl ExchangeError {
    /// A timeout's lateness of the host ([`ExchangeError::Timeout::host_late`]); `None` for
    /// any other error, or a host on time.
    pub fn host_late(&self) -> Option<Duration> {
        match self {
            ExchangeError::Timeout { host_late, .. } => *host_late,
            _ => None,
        }
    }

    /// `self`, a timeout during which the host ran `late` behind a deadline it had set: said
    /// as held up when `late` is [`HELD_UP`] or more (the larger lateness kept). Any other
    /// error is returned as it is.
    pub fn late_host(self, late: Duration) -> Self {
        match self {
            ExchangeError::Timeout {
                command,
                attempts,
                waited_ms,
                host_late,
            } => ExchangeError::Timeout {
                command,
                attempts,
                waited_ms,
                host_late: host_late.into_iter().chain(held_up_by(late)).max(),
            },
            other => other,
        }
    }

    /// `self` with every command it speaks of named by `profile` (`no answer to CMD_VERSION
    /// (2)`, not `command 2`); the numbers stay as they were.
    pub fn named(self, profile: &crate::profile::Profile) -> Self {
        use ExchangeError as E;
        match self {
            E::Timeout {
                command,
                attempts,
                waited_ms,
                host_late,
            } => E::Timeout {
                command: command.named(profile),
                attempts,
                waited_ms,
                host_late,
            },
            E::Garbled { command, error } => E::Garbled {
                command: command.named(profile),
                error,
            },
            E::Mismatch {
                expected,
                got,
                from,
            } => E::Mismatch {
                expected: expected.named(profile),
                got: got.named(profile),
                from,
            },
            E::Unreadable { command, reason } => E::Unreadable {
                command: command.named(profile),
                reason,
            },
            E::Taken { command, port, by } => E::Taken {
                command: command.named(profile),
                port,
                by,
            },
            E::NotThisDevice {
                command,
                hw,
                claimed,
                profile: id,
            } => E::NotThisDevice {
                command: command.named(profile),
                hw,
                claimed,
                profile: id,
            },
            other => other,
        }
    }
}

impl Request {
    /// The request for a profile command with an encoded payload: the answer it waits for
    /// follows the command's definition (MSP: the same command, sent to the command's device
    /// code if it has one; servo: the same command from the addressed servo, optional where the
    /// servo answers only with its response switch on, none for broadcast; Tuya: the reply
    /// command, the reports of its data points for a query or a data-point command).
    pub fn for_command(
        profile: &crate::profile::Profile,
        cmd: &crate::profile::Command,
        payload: Vec<u8>,
    ) -> Self {
        use crate::profile::Protocol;
        let mut r = Request::new(cmd.id, payload);
        r.device = cmd.device;
        match profile.protocol {
            Protocol::Msp => {}
            Protocol::Servo => {
                use crate::protocol::servo::{Frame, Target, cmd::MONITOR};
                // The first content byte is not always a servo id (commands 18, 19, 25).
                r.reply = match Frame::request(cmd.id, r.payload.clone()).target() {
                    Target::Servo { id } => {
                        let m = Match::servo(cmd.id, &[id]);
                        if cmd.reply_optional {
                            ReplySpec::Optional(m)
                        } else {
                            ReplySpec::Required(m)
                        }
                    }
                    // One MONITOR reply from each servo named, in turn.
                    Target::Sync {
                        sub_command: MONITOR,
                        ids,
                    } if !ids.is_empty() => ReplySpec::Burst {
                        each: Match::servo(MONITOR, &ids),
                        quiet: SYNC_QUIET,
                    },
                    Target::Sync { .. } | Target::Broadcast | Target::Bus => ReplySpec::None,
                };
            }
            Protocol::Tuya => {
                use crate::link::session::tuya::{command_ids, reports_reply};
                use crate::protocol::tuya::cmd::{DP_COMMAND, DP_REPORT};
                let answer = cmd.reply_command.unwrap_or(cmd.id);
                r.reply = if answer == DP_REPORT {
                    // A data-point command is answered by a report of each data point it
                    // sets; a query by a report of every data point.
                    let ids = if cmd.id == DP_COMMAND {
                        command_ids(&r.payload)
                    } else {
                        profile.data_points.iter().map(|d| d.id).collect()
                    };
                    reports_reply(profile, &ids)
                } else {
                    ReplySpec::Required(Match::command(answer))
                };
            }
        }
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::servo;

    #[test]
    fn a_late_answer_naming_another_parameter_is_not_taken() {
        let want = Match::servo(servo::cmd::READ_DATA, &[1]).with_prefix(vec![1, 36]);
        let late = Packet::servo(servo::Frame::reply(servo::cmd::READ_DATA, vec![1, 34, 7]));
        let right = Packet::servo(servo::Frame::reply(servo::cmd::READ_DATA, vec![1, 36, 5]));
        let other_servo = Packet::servo(servo::Frame::reply(servo::cmd::READ_DATA, vec![2, 36, 5]));
        assert!(!want.accepts(&late));
        assert!(want.accepts(&right));
        assert!(!want.accepts(&other_servo));
        // A request from the host (an echo on a one-wire bus) is never an answer.
        let echo = Packet::servo(servo::Frame::request(servo::cmd::READ_DATA, vec![1, 36]));
        assert!(!want.accepts(&echo));
    }
}
