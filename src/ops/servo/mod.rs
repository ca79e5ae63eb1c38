//! Bus-servo operations: ping, scan, parameters, id and baud provisioning, motion, and
//! production provisioning. One file per group; the operations are re-exported here.

pub mod monitor;
mod motion;
mod params;
pub mod preset;
pub mod provision;
mod scan;
mod search;
mod setup;

pub use motion::{
    MultiTurn, Wheel, damping_request, monitor_request, multi_turn_request, read_angle,
    read_angle_request, rotate_request, spin_request, stop_all_requests,
};
pub use params::{
    baud_as_option, read_all, read_block, read_param, write_block, write_param,
    write_param_broadcast, write_params,
};
pub use scan::{SCAN_ROLES, ScanPlan, ScanReport, ScanRow, Unsure, ping_sweep, scan, unsure_said};
pub use setup::{Location, factory_location, locate, reset_user_data, set_baud, set_id};

use super::OpError;
use crate::link::{Client, ExchangeError, Match, ReplySpec, Request};
use crate::profile::{Param, ParamRole, Profile};
use crate::protocol::servo::cmd;
use serde::Serialize;
use std::collections::BTreeMap;

/// The servo id parameter: the profile's parameter with role [`ParamRole::ServoId`], or an
/// [`OpError::UnknownParam`] naming the role when the profile has none.
pub fn id_param(profile: &Profile) -> Result<&Param, OpError> {
    profile
        .servo_id_param()
        .ok_or_else(|| OpError::unknown_param(profile, "with role ServoId"))
}

/// The baud-option parameter and its option → baud table (role [`ParamRole::BaudOption`]), or
/// an [`OpError::UnknownParam`] naming the role when the profile has none.
pub fn baud_param(profile: &Profile) -> Result<(&Param, &BTreeMap<u8, u32>), OpError> {
    profile
        .baud_option_param()
        .ok_or_else(|| OpError::unknown_param(profile, "with role BaudOption"))
}

/// The serial-number parameter (role [`ParamRole::SerialNumber`]), or an
/// [`OpError::UnknownParam`] naming the role when the profile has none.
pub fn serial_param(profile: &Profile) -> Result<&Param, OpError> {
    profile
        .serial_number_param()
        .ok_or_else(|| OpError::unknown_param(profile, "with role SerialNumber"))
}

/// Whether `param` follows the servo (its id or baud option): those have their own operations,
/// never a block write or a preset.
pub fn follows_servo(param: &Param) -> bool {
    matches!(
        param.role,
        Some(ParamRole::ServoId | ParamRole::BaudOption { .. })
    )
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

/// Pings `id` with `attempts` attempts: present, absent, or a possible duplicate (two servos
/// on one id): garbled with one attempt, or, with several, garbled and then garbled again when
/// asked one ping at a time ([`scan::ask_again`]). A clean answer from another servo is its
/// late answer, not a sign of trouble at this id.
pub fn ping(client: &Client, id: u8, attempts: u8) -> Result<Presence, OpError> {
    addressed(id, "ping a servo")?;
    let req = Request::new(cmd::PING, vec![id])
        .reply(ReplySpec::Required(Match::servo(cmd::PING, &[id])))
        .attempts(attempts);
    match client.request(req) {
        Ok(_) => Ok(Presence::Present),
        Err(ExchangeError::Timeout { .. }) => Ok(Presence::Absent),
        // Garbled in one exchange of several attempts is not two servos: a retry that meets
        // the first attempt's late answer on the half-duplex line garbles both (a servo that
        // answers 5 ms late: "more than one servo answers at id 0", 2 provisionings in 24).
        // Asked one ping at a time, each listened to for the grace, it is a possible duplicate
        // only when garbled again.
        Err(ExchangeError::Garbled { .. }) if attempts > 1 => scan::ask_again(client, id),
        Err(ExchangeError::Garbled { error, .. }) => {
            Ok(Presence::PossibleDuplicate(error.to_string()))
        }
        Err(ExchangeError::Mismatch {
            got,
            from: Some(other),
            ..
        }) if got.id == cmd::PING && other != id => Ok(Presence::Absent),
        Err(ExchangeError::Mismatch { got, .. }) => {
            Ok(Presence::PossibleDuplicate(format!("answered with {got}")))
        }
        Err(e) => Err(e.into()),
    }
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

#[cfg(test)]
mod tests {
    use super::provision::{IdSequence, Plan, search_order};
    use crate::profile::registry::{BUILTIN, parse};

    /// The built-in servo profile with option 4's rate edited to `baud`.
    fn servo_with_option_4_at(baud: u32) -> crate::profile::Profile {
        let src = BUILTIN
            .iter()
            .find(|(n, _)| *n == "servo")
            .expect("built-in")
            .1;
        assert!(src.contains(" 4: 57600,"), "test setup");
        let src = src.replacen(" 4: 57600,", &format!(" 4: {baud},"), 1);
        parse("servo.ron", &src, None).expect("the edited profile loads")
    }

    #[test]
    fn an_edited_baud_table_is_what_provisioning_searches_and_accepts() {
        let edited = servo_with_option_4_at(230_400);
        let order = search_order(&edited, 230_400);
        assert_eq!(order[0], 230_400);
        assert!(!order.contains(&57_600), "{order:?}");
        assert_eq!(order.len(), edited.servo_bauds().len());

        let plan = Plan {
            target_baud: 230_400,
            ids: IdSequence::Start(1),
            params: Vec::new(),
            record: Vec::new(),
        };
        assert_eq!(plan.resolve(&edited).expect("resolves").option, 4);
        let builtin = parse(
            "servo.ron",
            BUILTIN.iter().find(|(n, _)| *n == "servo").unwrap().1,
            None,
        )
        .expect("loads");
        let err = plan.resolve(&builtin).unwrap_err();
        assert!(
            err.message.contains("not a servo baud rate"),
            "{}",
            err.message
        );
    }

    #[test]
    fn a_profile_without_the_roles_is_refused_naming_the_role() {
        let empty = crate::profile::Profile::empty("bare", crate::profile::Protocol::Servo, 9600);
        let err = super::id_param(&empty).unwrap_err();
        assert!(err.to_string().contains("role ServoId"), "{err}");
        let err = super::baud_param(&empty).unwrap_err();
        assert!(err.to_string().contains("role BaudOption"), "{err}");
        assert!(empty.servo_bauds().is_empty());
    }
}
