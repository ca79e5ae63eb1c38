//! The MSP core commands: ping, the device's identity (CMD_VERSION with CMD_BUILD_INFO) and its
//! power state. Layouts: `assets/profiles/*.ron`, from the MSP protocol document.

use super::{OpError, exchange};
use crate::link::{Client, DeviceInfo};
use crate::ops::Device;
use crate::profile::{Command, Profile};
use crate::protocol::msp;
use std::time::Duration;

/// A ping's answer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Ping {
    /// From the request's first byte written to the answer's last byte read.
    pub rtt: Duration,
    /// Attempts used.
    pub attempts: u8,
}

fn core<'p>(profile: &'p Profile, id: u8, ident: &str) -> Result<&'p Command, OpError> {
    profile
        .command_by_id(id)
        .ok_or_else(|| OpError::unknown_command(profile, ident))
}

/// CMD_PING, with its round trip.
pub fn ping(dev: Device<'_>) -> Result<Ping, OpError> {
    let profile = dev.profile;
    let cmd = core(profile, msp::CMD_PING, "CMD_PING")?;
    let reply = exchange::send(dev, cmd, &[])?;
    Ok(Ping {
        rtt: reply.rtt,
        attempts: reply.attempts,
    })
}

/// What the device says of itself (CMD_VERSION, then CMD_BUILD_INFO where the device answers
/// it): the link identifies the device once per connection, and this hands out that result
/// without a new exchange (waiting for it while it is under way; a failed identification is
/// tried again). Errors: the device did not answer CMD_VERSION or its answer does not fit the
/// profile ([`OpError::Exchange`]).
pub fn identify(client: &Client) -> Result<DeviceInfo, OpError> {
    Ok(client.device_info()?)
}

/// CMD_GET_POWER_STATE's raw answer: no layout is published for it, so its bytes are kept as
/// sent.
pub fn power_state(dev: Device<'_>) -> Result<Vec<u8>, OpError> {
    let profile = dev.profile;
    let cmd = core(profile, msp::CMD_GET_POWER_STATE, "CMD_GET_POWER_STATE")?;
    let reply = exchange::send(dev, cmd, &[])?;
    Ok(reply.payload().unwrap_or_default().to_vec())
}

/// The device in a few words, for a preset's header: `hw 0x03 fw 1.4.2`.
pub fn short_description(info: &DeviceInfo) -> String {
    format!("hw {:#04x} fw {}", info.hw, info.firmware)
}

/// The device in full, for a test record: `hw 0x03 fw 1.4.2 api 2.4 build 7 (2025-06-01
/// 10:00:00)`, the date where the device gave one.
pub fn description(info: &DeviceInfo) -> String {
    let mut s = format!(
        "hw {:#04x} fw {} api {} build {}",
        info.hw, info.firmware, info.api, info.build
    );
    if let Some(d) = &info.build_date {
        s.push_str(&format!(" ({d})"));
    }
    s
}

/// What is said when the device did not identify itself (`why`): requests then go to the
/// profile's device code, which may not be this device's.
pub fn unidentified(profile: &Profile, why: &dyn std::fmt::Display) -> String {
    let code = profile
        .device_code
        .map_or(msp::DEVICE_CORE, crate::profile::DeviceCode::initial);
    format!(
        "the device did not identify itself ({why}); requests go to the profile's device code \
         {code:#04x}, which may not be this device's"
    )
}
