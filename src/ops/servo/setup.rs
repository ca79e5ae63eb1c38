//! Where a servo is on the bus: its id and baud rate changed (each verified, the port following
//! the servo), its user data reset to the factory id and rate, a lost servo found again.

use super::{Presence, baud_param, command, id_param, ping, read_param, switch};
use crate::link::{Client, ExchangeError, Match, ReplySpec, Request};
use crate::ops::{Cancel, OpError};
use crate::ops::{Device, Run};
use crate::profile::{Profile, Value};
use crate::protocol::servo::cmd;

/// Gives servo `old` the id `new`, refusing 255 and any id that already answers; a fresh servo
/// (id 0) must be alone on the bus. Verified at the new id afterwards.
pub fn set_id(dev: Device<'_>, old: u8, new: u8, cancel: &Cancel) -> Result<(), OpError> {
    let Device { client, profile } = dev;
    if new == crate::protocol::servo::BROADCAST_ID {
        return Err(OpError::BroadcastId);
    }
    super::addressed(old, "give a servo a new id")?;
    if new == old {
        return Err(OpError::SameId { id: new });
    }
    match ping(client, new, 2)? {
        Presence::Absent => {}
        Presence::Present => {
            return Err(OpError::IdInUse {
                id: new,
                garbled: None,
            });
        }
        Presence::PossibleDuplicate(e) => {
            return Err(OpError::IdInUse {
                id: new,
                garbled: Some(e),
            });
        }
    }
    if old == 0 {
        let found = ids_on_bus(client, cancel)?;
        if found != [0] {
            return Err(OpError::NotAlone { answering: found });
        }
    }
    match ping(client, old, 2)? {
        Presence::Present => {}
        Presence::Absent => return Err(OpError::Verify(format!("no servo answers at id {old}"))),
        Presence::PossibleDuplicate(e) => {
            return Err(OpError::Verify(format!(
                "more than one servo may share id {old}: {e}"
            )));
        }
    }
    let write = command(profile, cmd::WRITE_DATA)?;
    let id_param = id_param(profile)?;
    let req = Request::new(cmd::WRITE_DATA, vec![old, id_param.id, new])
        .reply(ReplySpec::Required(Match::servo(write.id, &[old, new])));
    let reply = client.request(req)?;
    if reply.payload().and_then(|p| p.get(2)) != Some(&1) {
        return Err(OpError::Verify(format!("servo {old} refused the id {new}")));
    }
    let now = read_param(dev, new, id_param)
        .map_err(|e| OpError::Verify(format!("no answer at the new id {new}: {e}")))?;
    if now != i64::from(new) {
        return Err(OpError::Verify(format!("servo at {new} reports id {now}")));
    }
    // Two attempts: one garbled tail of a late answer is not a servo.
    if ping(client, old, 2)? != Presence::Absent {
        return Err(OpError::Verify(format!(
            "something still answers at the old id {old}"
        )));
    }
    Ok(())
}

/// The ids that answer at the current baud rate (a garbled answer counts).
fn ids_on_bus(client: &Client, cancel: &Cancel) -> Result<Vec<u8>, OpError> {
    let ids: Vec<u8> = (0..crate::protocol::servo::BROADCAST_ID).collect();
    let (found, _) = super::scan::find_ids(client, &ids, &mut Run::quiet(cancel))?;
    Ok(found.into_iter().map(|(id, _)| id).collect())
}

/// Where a servo was found after a baud change that could not be verified: the profile's baud
/// rates searched ([`super::search`]) until it answers cleanly; the port is left there.
fn recover(dev: Device<'_>, id: u8) -> Result<Option<u32>, OpError> {
    let Device { client, profile } = dev;
    let found = super::search::search(client, id, &profile.servo_bauds(), true)?;
    Ok(found
        .into_iter()
        .find(|(_, p)| *p == Presence::Present)
        .map(|(b, _)| b))
}

/// Sets servo `id`'s baud option (the profile's baud table), switches the port to the new rate and verifies there.
/// If the servo is not found at the new rate, every rate is scanned for it: the error says where
/// it is, and the port is left at that rate.
pub fn set_baud(dev: Device<'_>, id: u8, option: u8) -> Result<u32, OpError> {
    let Device { client, profile } = dev;
    super::addressed(id, "change a servo's baud rate and follow it")?;
    let (baud_param, rates) = baud_param(profile)?;
    let Some(&baud) = rates.get(&option) else {
        let first = rates.keys().next().copied().unwrap_or(0);
        let last = rates.keys().next_back().copied().unwrap_or(0);
        let table: Vec<String> = rates.iter().map(|(o, b)| format!("{o}: {b}")).collect();
        return Err(OpError::OutOfRange {
            what: "baud option",
            value: option.into(),
            min: first.into(),
            max: last.into(),
            note: format!(" ({})", table.join(", ")),
        });
    };
    baud_param.field.check(&Value::Int(option.into()))?;
    match ping(client, id, 2)? {
        Presence::Present => {}
        other => {
            return Err(OpError::Verify(format!(
                "servo {id} is not answering cleanly: {other:?}"
            )));
        }
    }
    // The servo switches at once and may answer at the new rate: its answer is not awaited here.
    let req = Request::new(cmd::WRITE_DATA, vec![id, baud_param.id, option])
        .reply(ReplySpec::Optional(Match::servo(cmd::WRITE_DATA, &[id])))
        .attempts(1);
    match client.request(req) {
        Ok(_) | Err(ExchangeError::Garbled { .. } | ExchangeError::Timeout { .. }) => {}
        Err(e) => return Err(e.into()),
    }
    switch(client, baud)?;
    let verified = ping(client, id, 3)? == Presence::Present
        && read_param(dev, id, baud_param).ok() == Some(i64::from(option));
    if verified {
        return Ok(baud);
    }
    Err(OpError::NotAtNewRate {
        id,
        baud,
        found: recover(dev, id)?,
    })
}

/// Where a servo is after [`reset_user_data`]: its factory id and baud rate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Location {
    /// Its id.
    pub id: u8,
    /// Its baud rate.
    pub baud: u32,
}

/// The id and baud rate the user parameters reset to (the defaults of the profile's id and
/// baud-option parameters; id 0 and the profile's baud when it has none).
pub fn factory_location(profile: &Profile) -> Location {
    let id = profile
        .servo_id_param()
        .and_then(|p| p.field.default)
        .and_then(|v| u8::try_from(v).ok())
        .unwrap_or(0);
    let baud = profile
        .baud_option_param()
        .and_then(|(p, _)| p.field.default)
        .and_then(|v| u8::try_from(v).ok())
        .and_then(|o| profile.baud_of_option(o))
        .unwrap_or(profile.baud);
    Location { id, baud }
}

/// Restores servo `id`'s user parameters (32-53) to the factory defaults. That includes its id
/// and baud rate: refused when another servo already answers at the factory id and rate (the two
/// would then share an id). The servo is then looked for at its factory id and rate, and the port
/// is left there; if it is not found, the error says so. `baud` is the rate the servo talks at
/// now.
pub fn reset_user_data(dev: Device<'_>, id: u8, baud: u32) -> Result<Location, OpError> {
    let Device { client, profile } = dev;
    super::addressed(id, "reset a servo's user data and find it again")?;
    let reset = command(profile, cmd::RESET_USER_DATA)?;
    let home = factory_location(profile);
    let switch = |b: u32| switch(client, b);
    if home != (Location { id, baud }) {
        switch(home.baud)?;
        let there = ping(client, home.id, 2)?;
        switch(baud)?;
        if there != Presence::Absent {
            return Err(OpError::FactoryIdTaken {
                id: home.id,
                baud: home.baud,
            });
        }
    }
    match ping(client, id, 2)? {
        Presence::Present => {}
        other => {
            return Err(OpError::Verify(format!(
                "servo {id} is not answering cleanly: {other:?}"
            )));
        }
    }
    // The servo may answer from its new id and at its new rate: the answer is not awaited here.
    let req = Request::for_command(profile, reset, vec![id])
        .reply(ReplySpec::Optional(Match::servo(
            cmd::RESET_USER_DATA,
            &[id, home.id],
        )))
        .attempts(1);
    match client.request(req) {
        Ok(r) if r.payload().and_then(|p| p.get(1)) == Some(&0) => {
            return Err(OpError::Verify(format!("servo {id} refused the reset")));
        }
        Ok(_) | Err(ExchangeError::Garbled { .. } | ExchangeError::Timeout { .. }) => {}
        Err(e) => return Err(e.into()),
    }
    switch(home.baud)?;
    if ping(client, home.id, 3)? == Presence::Present {
        return Ok(home);
    }
    match recover(dev, home.id)? {
        Some(b) => Err(OpError::Verify(format!(
            "after the reset servo {} answers at {b} baud, not at {} (the port is now at {b})",
            home.id, home.baud
        ))),
        None => {
            let _ = switch(baud);
            Err(OpError::Verify(format!(
                "after the reset no servo answers at the factory id {} at any rate",
                home.id
            )))
        }
    }
}

/// Looks for servo `id` at every baud rate of the device's profile; the port is left where it
/// answered. Returns that rate.
pub fn locate(dev: Device<'_>, id: u8) -> Result<Option<u32>, OpError> {
    recover(dev, id)
}
