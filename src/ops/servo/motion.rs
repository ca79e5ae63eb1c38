//! Motion: the requests that move, spin, damp and stop servos (sent straight to the worker, so
//! that they never wait behind a job), and the angle read.

use crate::link::{Match, ReplySpec, Request};
use crate::ops::Device;
use crate::ops::OpError;
use crate::profile::{Input, Profile, Value};
use crate::protocol::Direction;
use crate::protocol::servo::cmd;

/// The ROTATE request: servo `id` to `deci_degrees` (0.1°) over `interval_ms`, with `power` mW
/// (0: the servo's limit). Checked against the profile.
pub fn rotate_request(
    profile: &Profile,
    id: u8,
    deci_degrees: i64,
    interval_ms: i64,
    power: i64,
) -> Result<Request, OpError> {
    motion_request(
        profile,
        cmd::ROTATE,
        id,
        &[
            ("angle", deci_degrees),
            ("interval", interval_ms),
            ("power", power),
        ],
    )
}

/// A multi-turn move (ROTATE_MTURN_BY_INTERVAL): to this angle over an interval, accelerating
/// and decelerating for the times given.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MultiTurn {
    /// The target multi-turn angle, 0.1° (±1024 turns).
    pub deci_degrees: i64,
    /// The move's duration, ms.
    pub interval_ms: i64,
    /// Acceleration time, ms.
    pub t_acc_ms: i64,
    /// Deceleration time, ms.
    pub t_dec_ms: i64,
    /// Power, mW (0: the servo's limit).
    pub power: i64,
}

/// The ROTATE_MTURN_BY_INTERVAL request: servo `id` by `turn`. Checked against the profile,
/// its relations included: an interval shorter than the profile allows (the built-in servo's:
/// `t_acc + t_dec`) is refused before anything is sent, with the interval given and the least
/// allowed ([`OpError::Field`] of a [`crate::profile::FieldError::Relation`]).
pub fn multi_turn_request(profile: &Profile, id: u8, turn: MultiTurn) -> Result<Request, OpError> {
    motion_request(
        profile,
        cmd::ROTATE_MTURN_BY_INTERVAL,
        id,
        &[
            ("angle", turn.deci_degrees),
            ("interval", turn.interval_ms),
            ("t_acc", turn.t_acc_ms),
            ("t_dec", turn.t_dec_ms),
            ("power", turn.power),
        ],
    )
}

/// Wheel-mode methods (SPIN, bits 1-0).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wheel {
    /// Stop turning.
    Stop,
    /// Turn until told otherwise.
    Continuous,
    /// Turn this many turns.
    Turns(u16),
    /// Turn for this many milliseconds.
    Timed(u16),
}

/// The SPIN request: servo `id` in wheel mode at `speed` °/s, clockwise or not.
pub fn spin_request(
    profile: &Profile,
    id: u8,
    wheel: Wheel,
    clockwise: bool,
    speed: u16,
) -> Result<Request, OpError> {
    let (mode, value) = match wheel {
        Wheel::Stop => (0, 0),
        Wheel::Continuous => (1, 0),
        Wheel::Turns(n) => (2, n),
        Wheel::Timed(ms) => (3, ms),
    };
    let method = mode | if clockwise { 0x80 } else { 0 };
    motion_request(
        profile,
        cmd::SPIN,
        id,
        &[
            ("method", method),
            ("speed", speed.into()),
            ("value", value.into()),
        ],
    )
}

/// The DAMPING request: servo `id` (255: all) in damping mode with `power` mW (0: the limit).
pub fn damping_request(profile: &Profile, id: u8, power: i64) -> Result<Request, OpError> {
    motion_request(profile, cmd::DAMPING, id, &[("power", power)])
}

fn motion_request(
    profile: &Profile,
    command: u8,
    id: u8,
    values: &[(&str, i64)],
) -> Result<Request, OpError> {
    let c = super::command(profile, command)?;
    let mut inputs = vec![("servo_id".to_string(), Input::Raw(Value::Int(id.into())))];
    inputs.extend(
        values
            .iter()
            .map(|(k, v)| (k.to_string(), Input::Raw(Value::Int(*v)))),
    );
    let payload = profile.encode(c, Direction::HostToDevice, &inputs)?;
    Ok(Request::for_command(profile, c, payload).attempts(1))
}

/// "Stop all": broadcasts that stop every servo at the port's baud rate. Damping (every servo
/// knows it) stops a move or a spin; then STOP with hold (newer servos) locks them where they are.
/// Nobody answers a broadcast.
pub fn stop_all_requests(profile: &Profile) -> Vec<Request> {
    let broadcast = crate::protocol::servo::BROADCAST_ID;
    let mut out = Vec::new();
    if let Ok(r) = damping_request(profile, broadcast, 0) {
        out.push(r);
    }
    // 0x11: stop and hold.
    if let Ok(r) = motion_request(
        profile,
        cmd::STOP,
        broadcast,
        &[("mode", 0x11), ("power", 0)],
    ) {
        out.push(r);
    }
    // Nobody answers a broadcast. (The worker lets a frame cross the wire whole before a baud
    // change queued after it.)
    out.into_iter().map(|r| r.reply(ReplySpec::None)).collect()
}

/// The READ_ANGLE request to poll for servo `id`'s angle (answer: id, angle i16 in 0.1°).
pub fn read_angle_request(id: u8) -> Request {
    Request::new(cmd::READ_ANGLE, vec![id])
        .reply(ReplySpec::Required(Match::servo(cmd::READ_ANGLE, &[id])))
        .attempts(1)
}

/// The MONITOR request (newer servos) to poll for all of servo `id`'s live values.
pub fn monitor_request(id: u8) -> Request {
    Request::new(cmd::MONITOR, vec![id])
        .reply(ReplySpec::Required(Match::servo(cmd::MONITOR, &[id])))
        .attempts(1)
}

/// Reads servo `id`'s angle, 0.1°.
pub fn read_angle(dev: Device<'_>, id: u8) -> Result<i64, OpError> {
    let Device { client, profile } = dev;
    super::addressed(id, "read an angle")?;
    let c = super::command(profile, cmd::READ_ANGLE)?;
    let reply = client.request(read_angle_request(id).attempts(2))?;
    let d = profile
        .decode(
            c,
            Direction::DeviceToHost,
            reply.payload().unwrap_or_default(),
        )
        .map_err(|e| OpError::answer(&c.ident, e))?;
    match d.values.get(1).map(|v| &v.value) {
        Some(Value::Int(v)) => Ok(*v),
        _ => Err(OpError::Verify(format!("servo {id}: no angle"))),
    }
}
