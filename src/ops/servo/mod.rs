//! Bus-servo operations: ping, scan, parameters, id and baud provisioning, motion, and
//! production provisioning. One file per group; the operations are re-exported here.

pub mod monitor;
mod motion;
mod params;
pub mod preset;
pub mod provision;
mod scan;
mod setup;

pub use motion::{
    Wheel, damping_request, monitor_request, read_angle, read_angle_request, rotate_request,
    spin_request, stop_all_requests,
};
pub use params::{
    read_all, read_block, read_param, write_block, write_param, write_param_broadcast, write_params,
};
pub use scan::{ScanPlan, ScanReport, ScanRow, scan};
pub use setup::{Location, factory_location, locate, reset_user_data, set_baud, set_id};

use super::OpError;
use crate::link::{Client, ExchangeError, Match, ReplySpec, Request};
use crate::profile::{Param, Profile};
use crate::protocol::servo::cmd;
use serde::Serialize;

/// Baud rates by option number 1-8 (option 8 on newer servos only).
pub const BAUDS: [u32; 8] = [
    9600, 19200, 38400, 57600, 115_200, 250_000, 500_000, 1_000_000,
];

/// The `data_id` of the servo id parameter.
pub const PARAM_ID: u8 = 34;
/// The `data_id` of the baud-rate option parameter.
pub const PARAM_BAUD: u8 = 36;

/// The baud rate of option 1-8.
pub fn baud_of_option(option: u8) -> Option<u32> {
    BAUDS.get(usize::from(option).checked_sub(1)?).copied()
}

/// The option 1-8 of a baud rate.
pub fn option_of_baud(baud: u32) -> Option<u8> {
    BAUDS.iter().position(|&b| b == baud).map(|i| i as u8 + 1)
}

/// What answers at one id.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(tag = "status", content = "detail", rename_all = "snake_case")]
pub enum Presence {
    /// One servo answered cleanly.
    Present,
    /// Nothing answered.
    Absent,
    /// Answers came back garbled: possibly two servos on one id.
    PossibleDuplicate(String),
}

/// Refuses the broadcast address for an operation that waits for an answer from servo `id`
/// (`what` it is): nothing is sent.
pub fn addressed(id: u8, what: &'static str) -> Result<(), OpError> {
    if id == crate::protocol::servo::BROADCAST_ID {
        return Err(OpError::BroadcastAnswer { what, hint: "" });
    }
    Ok(())
}

/// Pings `id` with `attempts` attempts: present, absent, or garbled on every attempt (possibly
/// two servos on one id). A clean answer from another servo is its late answer, not a sign of
/// trouble at this id.
pub fn ping(client: &Client, id: u8, attempts: u8) -> Result<Presence, OpError> {
    addressed(id, "ping a servo")?;
    let req = Request::new(cmd::PING, vec![id])
        .reply(ReplySpec::Required(Match::servo(cmd::PING, &[id])))
        .attempts(attempts);
    match client.request(req) {
        Ok(_) => Ok(Presence::Present),
        Err(ExchangeError::Timeout { .. }) => Ok(Presence::Absent),
        Err(ExchangeError::Garbled { error, .. }) => {
            Ok(Presence::PossibleDuplicate(error.to_string()))
        }
        Err(ExchangeError::Mismatch {
            got: cmd::PING,
            from: Some(other),
            ..
        }) if other != id => Ok(Presence::Absent),
        Err(ExchangeError::Mismatch { got, .. }) => Ok(Presence::PossibleDuplicate(format!(
            "answered with command {got}"
        ))),
        Err(e) => Err(e.into()),
    }
}

/// The parameter `id` of the profile, or why there is none.
fn param_by_id(profile: &Profile, id: u8) -> Result<&Param, OpError> {
    profile
        .param(id)
        .ok_or_else(|| OpError::unknown_param(profile, id))
}

/// The command `id` of the profile, or why there is none.
fn command(profile: &Profile, id: u8) -> Result<&crate::profile::Command, OpError> {
    profile
        .command_by_id(id)
        .ok_or_else(|| OpError::unknown_command(profile, id))
}

/// Switches the port to `baud` (where the servo to work on talks).
pub fn switch(client: &Client, baud: u32) -> Result<(), OpError> {
    client
        .set_baud(baud)
        .map_err(|error| OpError::Port { baud, error })
}
