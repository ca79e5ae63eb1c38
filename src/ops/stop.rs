//! STOP: the profile's stop commands (motors, fan, spray off; the solar cleanbot's speed 0),
//! built once here for whoever sends them: the window's STOP button (straight to the worker's
//! queue, ahead of a running job's next request) and the self-test's safe state (on its
//! client, each answer waited for).

use super::{OpError, exchange};
use crate::link::Request;
use crate::ops::Device;
use crate::profile::Profile;

/// How often each STOP request is sent before it counts as unanswered: a stop is the same
/// however often it arrives.
pub const ATTEMPTS: u8 = 3;

/// The STOP's requests in the profile's order, each checked against the profile; empty when
/// the profile names no STOP. `(command ident, request)`.
pub fn requests(profile: &Profile) -> Result<Vec<(String, Request)>, OpError> {
    profile
        .stop_commands()
        .into_iter()
        .map(|(cmd, inputs)| {
            Ok((
                cmd.ident.clone(),
                exchange::request(profile, cmd, &inputs, ATTEMPTS)?,
            ))
        })
        .collect()
}

/// What one STOP command did.
#[derive(Debug, Clone, PartialEq)]
pub struct Stopped {
    /// As a person reads it: `MSP_SET_FAN pwm=0`.
    pub what: String,
    /// Acknowledged, or why not.
    pub result: Result<(), OpError>,
}

/// Sends every STOP command in order and waits for each answer; one that fails does not keep
/// the next from being sent. Empty when the profile names no STOP.
pub fn stop(dev: Device<'_>) -> Vec<Stopped> {
    let Device { client, profile } = dev;
    profile
        .stop_commands()
        .into_iter()
        .map(|(cmd, inputs)| {
            let what = std::iter::once(cmd.ident.clone())
                .chain(inputs.iter().map(|(k, v)| match v {
                    crate::profile::Input::Text(t) => format!("{k}={t}"),
                    crate::profile::Input::Raw(r) => format!("{k}={r:?}"),
                }))
                .collect::<Vec<_>>()
                .join(" ");
            let result = exchange::request(profile, cmd, &inputs, ATTEMPTS)
                .and_then(|r| client.request(r).map(|_| ()).map_err(OpError::from));
            Stopped { what, result }
        })
        .collect()
}
