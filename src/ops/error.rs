//! Why an operation failed: refused before anything was sent (the variants [`OpError::is_input`]
//! names), or the link, the device or the operator ended it. Each variant carries the values
//! that explain it.

use crate::document::DocumentError;
use crate::link::{ExchangeError, LinkError};
use crate::profile::FieldError;

/// Why an operation failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OpError {
    /// A value the profile refuses (out of range with the allowed range, not a label, between
    /// steps, of the wrong type or length, an unknown field). Nothing was sent.
    #[error(transparent)]
    Value(#[from] FieldError),
    /// The profile has no such command. Nothing was sent.
    #[error("{profile} has no command {command}")]
    UnknownCommand {
        /// The profile's id.
        profile: String,
        /// The command asked for, by name or number.
        command: String,
    },
    /// The profile has no such servo parameter. Nothing was sent.
    #[error("{profile} has no parameter {param}")]
    UnknownParam {
        /// The profile's id.
        profile: String,
        /// The parameter asked for, by name or `data_id`.
        param: String,
    },
    /// A command of another kind than the operation needs (a Set to read, an Action to
    /// poll...). Nothing was sent.
    #[error("{command} is {kind}: {operation} takes {expected}{hint}")]
    WrongCommand {
        /// The command's ident.
        command: String,
        /// What it is, e.g. `a Set command`.
        kind: &'static str,
        /// The operation, e.g. `reading`.
        operation: &'static str,
        /// What the operation needs, e.g. `a Get or Telemetry command`.
        expected: &'static str,
        /// Where to look instead (`; its Get is MSP_GET_PWMVALUE`), or empty.
        hint: String,
    },
    /// A field of a Set left out whose current value cannot be kept: the device's answer does
    /// not hold it, or holds a value the profile refuses. Nothing was written.
    #[error("{command}: cannot keep the device's {field}: {why}; give {field}=VALUE")]
    CannotKeep {
        /// The Set command's ident.
        command: String,
        /// The field left out.
        field: String,
        /// Why its value cannot be kept.
        why: String,
    },
    /// Nothing to send was given. Nothing was sent.
    #[error("no {what} given: {hint}")]
    NothingGiven {
        /// What is missing, e.g. `data point`.
        what: &'static str,
        /// How to give it, e.g. `use NAME=VALUE`.
        hint: &'static str,
    },
    /// A number outside what the operation takes. Nothing was sent.
    #[error("{what} {value} is out of range; allowed {min} to {max}{note}")]
    OutOfRange {
        /// What the number is, e.g. `baud option`.
        what: &'static str,
        /// The number given.
        value: i64,
        /// The smallest allowed.
        min: i64,
        /// The largest allowed.
        max: i64,
        /// More on what is allowed (with a leading space), or empty.
        note: String,
    },
    /// A servo's id or baud option given to a broadcast write: every servo would take the same
    /// id, or move to a rate the port does not follow. Nothing was sent.
    #[error(
        "{param} is not written to every servo at once: it changes how a servo is reached; \
         give one servo its id with `servo set-id` or its rate with `servo set-baud`"
    )]
    NotBroadcast {
        /// The parameter.
        param: String,
    },
    /// A read-only servo parameter given to a write. Nothing was sent.
    #[error("{param} is read-only")]
    ReadOnly {
        /// The parameter's ident.
        param: String,
    },
    /// The broadcast address, given as a servo id to assign. Nothing was written.
    #[error(
        "id {} is the broadcast address and cannot be assigned",
        crate::protocol::servo::BROADCAST_ID
    )]
    BroadcastId,
    /// The broadcast address, given to an operation that waits for an answer: every servo
    /// would act and none answers a broadcast. Nothing was sent.
    #[error(
        "id {} is the broadcast address: every servo acts on it and none answers, so it cannot be used to {what}; give one servo's id{hint}",
        crate::protocol::servo::BROADCAST_ID
    )]
    BroadcastAnswer {
        /// What was asked, e.g. `read a parameter`.
        what: &'static str,
        /// How to broadcast on purpose, with a leading `; `, or empty.
        hint: &'static str,
    },
    /// A servo given the id it already has. Nothing was written.
    #[error("servo {id} already has id {id}")]
    SameId {
        /// The id.
        id: u8,
    },
    /// The id to assign already answers on the bus. Nothing was written.
    #[error("id {id} already answers on the bus{}", garbled.as_ref().map_or(String::new(), |g| format!(" (garbled: {g})")))]
    IdInUse {
        /// The id.
        id: u8,
        /// The frame error, when the answer came back garbled.
        garbled: Option<String>,
    },
    /// A fresh servo (id 0) given an id while other servos answer. Nothing was written.
    #[error(
        "a fresh servo (id 0) is given an id only when it is alone on the bus; ids answering: {answering:?}"
    )]
    NotAlone {
        /// The ids that answer.
        answering: Vec<u8>,
    },
    /// A servo's user block given without one of its values. Nothing was written.
    #[error("the block needs a value for {param} ({data_id})")]
    MissingValue {
        /// The parameter's ident.
        param: String,
        /// Its `data_id`.
        data_id: u8,
    },
    /// A user block that would change the servo's id or baud rate, which have their own
    /// operations (they follow the servo). Nothing was written.
    #[error(
        "the block would change {param} from {now:?} to {new:?}: change the id or baud rate with their own commands, which follow the servo"
    )]
    FollowedChange {
        /// The parameter's ident.
        param: String,
        /// What the servo holds.
        now: Option<i64>,
        /// What the block gives.
        new: Option<i64>,
    },
    /// A reset that would put the servo on an id and rate another servo already answers at.
    /// Nothing was written.
    #[error(
        "another servo answers at the factory id {id} at {baud} baud: after a reset the two would share an id; give that one another id first"
    )]
    FactoryIdTaken {
        /// The factory id.
        id: u8,
        /// The factory baud rate.
        baud: u32,
    },
    /// An empty firmware image. Nothing was sent.
    #[error("the firmware image is empty")]
    EmptyImage,
    /// A firmware image larger than the profile's largest image
    /// ([`crate::profile::Profile::ota_max_bytes`]). Nothing was sent.
    #[error("the image is {size} bytes, over the largest the profile allows ({max} bytes)")]
    ImageTooLarge {
        /// Its size in bytes.
        size: usize,
        /// The profile's largest image, in bytes.
        max: u32,
    },
    /// A document (a preset) that does not fit the profile. Nothing was written.
    #[error(transparent)]
    Document(#[from] DocumentError),
    /// The port could not be switched to a baud rate.
    #[error("cannot switch the port to {baud} baud: {error}")]
    Port {
        /// The rate.
        baud: u32,
        /// Why not.
        error: LinkError,
    },
    /// The exchange failed.
    #[error("{0}")]
    Exchange(#[from] ExchangeError),
    /// The device's answer does not fit the profile.
    #[error("{command}: the answer does not fit the profile: {error}")]
    Answer {
        /// The command.
        command: String,
        /// What does not fit.
        error: Box<FieldError>,
    },
    /// A servo that did not answer at the rate it was just given; `found` is the rate it was
    /// found at instead (the port is left there), if any.
    #[error("servo {id} did not answer at {baud} baud{}", found.map_or(", nor at any other rate".to_string(), |b| format!("; it was found at {b} baud (the port is now at {b})")))]
    NotAtNewRate {
        /// The servo.
        id: u8,
        /// The rate it was given.
        baud: u32,
        /// Where it answers instead.
        found: Option<u32>,
    },
    /// The device does not hold what was written, or is not where it should be.
    #[error("{0}")]
    Verify(String),
    /// Cancelled by the operator.
    #[error("cancelled")]
    Cancelled,
    /// Cancelled by the operator part of the way through a batch (a preset, tuning writes,
    /// servo parameters, provisioning, a self-test, an update): `done` of `total` items were
    /// carried out (written and read back), the others were not. Never a success.
    #[error(
        "cancelled after {done} of {total} {what}{}{}",
        list("; done: ", done_items),
        list("; not done: ", not_done)
    )]
    CancelledAfter {
        /// How many items were carried out.
        done: usize,
        /// How many the batch had.
        total: usize,
        /// Of what: `commands`, `parameters`, `servos`, `steps`.
        what: &'static str,
        /// The items carried out, by name (the commands written).
        done_items: Vec<String>,
        /// The items not carried out, by name.
        not_done: Vec<String>,
    },
}

/// `items` after `head`, comma-separated; nothing when there are none.
fn list(head: &str, items: &[String]) -> String {
    if items.is_empty() {
        String::new()
    } else {
        format!("{head}{}", items.join(", "))
    }
}

impl OpError {
    /// A batch of `items` (of kind `what`, e.g. `commands`) cancelled before item `done`: the
    /// first `done` were carried out, the rest were not, each said by `name`.
    pub fn cancelled_after<T>(
        items: &[T],
        done: usize,
        what: &'static str,
        name: impl Fn(&T) -> String,
    ) -> Self {
        let done = done.min(items.len());
        OpError::CancelledAfter {
            done,
            total: items.len(),
            what,
            done_items: items[..done].iter().map(&name).collect(),
            not_done: items[done..].iter().map(&name).collect(),
        }
    }

    /// Why the port was lost, when that is what failed: an exchange whose port went
    /// ([`ExchangeError::Disconnected`](crate::link::ExchangeError::Disconnected)) or a baud
    /// switch on a port that went ([`OpError::Port`] with [`LinkError::Disconnected`]; a
    /// search across rates meets the loss there first). `None` for every other failure.
    pub fn lost_port(&self) -> Option<&str> {
        match self {
            OpError::Exchange(ExchangeError::Disconnected(why))
            | OpError::Port {
                error: LinkError::Disconnected(why),
                ..
            } => Some(why),
            _ => None,
        }
    }

    /// Whether the operator cancelled it ([`OpError::Cancelled`], [`OpError::CancelledAfter`]).
    pub fn is_cancel(&self) -> bool {
        matches!(self, OpError::Cancelled | OpError::CancelledAfter { .. })
    }

    /// The device's answer to `command` does not fit the profile.
    pub fn answer(command: &str, error: FieldError) -> Self {
        OpError::Answer {
            command: command.to_string(),
            error: Box::new(error),
        }
    }

    /// `profile` has no command `command` (a name or a number).
    pub fn unknown_command(profile: &crate::profile::Profile, command: impl ToString) -> Self {
        OpError::UnknownCommand {
            profile: profile.id.clone(),
            command: command.to_string(),
        }
    }

    /// `profile` has no servo parameter `param` (a name or a `data_id`).
    pub fn unknown_param(profile: &crate::profile::Profile, param: impl ToString) -> Self {
        OpError::UnknownParam {
            profile: profile.id.clone(),
            param: param.to_string(),
        }
    }

    /// Whether the operation was refused for its input, before anything was sent (the command
    /// line's exit code 2).
    pub fn is_input(&self) -> bool {
        matches!(
            self,
            OpError::Value(_)
                | OpError::UnknownCommand { .. }
                | OpError::UnknownParam { .. }
                | OpError::WrongCommand { .. }
                | OpError::NothingGiven { .. }
                | OpError::OutOfRange { .. }
                | OpError::NotBroadcast { .. }
                | OpError::ReadOnly { .. }
                | OpError::BroadcastId
                | OpError::BroadcastAnswer { .. }
                | OpError::SameId { .. }
                | OpError::IdInUse { .. }
                | OpError::NotAlone { .. }
                | OpError::MissingValue { .. }
                | OpError::FollowedChange { .. }
                | OpError::FactoryIdTaken { .. }
                | OpError::EmptyImage
                | OpError::ImageTooLarge { .. }
                | OpError::Document(_)
        )
    }

    /// Whether nothing was sent to the device: refused for its input ([`Self::is_input`]), or
    /// a Set's left-out field whose value could not be kept. What the device holds is then
    /// what was last read.
    pub fn nothing_sent(&self) -> bool {
        self.is_input() || matches!(self, OpError::CannotKeep { .. })
    }
}
