//! A daisy chain of UART bus servos (seed 002, PROTOCOL_NOTES §2) on one half-duplex line.
//!
//! Every servo keeps its own id, baud rate, user parameters and motion. A servo hears a request
//! only when it was sent at its own baud rate and names its id (or 255, broadcast, which nobody
//! answers). The vendor SDK's bus-wide commands reach every servo (18 and 19: hold and release
//! motion commands) or the servos their records name (25: one sub-command for several servos;
//! a MONITOR sub-command is answered by each servo in turn, in the order asked). Two servos that
//! answer together collide on the open-drain line: the host sees the byte-wise AND of their
//! frames. Parameter writes are checked against the servo profile, and so is the form of the
//! temperature (°C, or a thermistor reading) in parameter 4 and MONITOR.
//!
//! Angles are in 0.1° throughout, as on the wire. Clockwise spin (method bit 7) counts up.

use super::{Device, Outgoing};
use crate::profile::registry::{BUILTIN, parse};
use crate::profile::{Profile, Protocol};
use crate::protocol::Direction;
use crate::protocol::servo::{BROADCAST_ID, Frame, ServoDecoder, Sync, Target, cmd};
use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

mod motion;
mod servo;

pub use motion::Motion;
pub use servo::SimServo;

/// The vendor SDK's command ids, as [`cmd`] names them (kept here for the simulator's callers).
pub mod ext {
    pub use crate::protocol::servo::cmd::{
        BEGIN_ASYNC, END_ASYNC, MONITOR, READ_ANGLE_MTURN, RESET_MTURN, ROTATE_BY_INTERVAL,
        ROTATE_BY_VELOCITY, ROTATE_MTURN, ROTATE_MTURN_BY_INTERVAL, ROTATE_MTURN_BY_VELOCITY,
        SET_ORIGIN, STOP, SYNC_COMMAND,
    };
}

/// Parameter ids the simulator gives a meaning to.
pub mod param {
    /// Reply to motion commands when done (1) or not at all (0).
    pub const RESPONSE_SWITCH: u8 = 33;
    /// Hold (1) or release (0) when a wheel-mode spin stops.
    pub const WB_LOCK_SWITCH: u8 = 47;
    /// Angle limits 51/52 apply when 1.
    pub const ANGLE_LIMIT_SWITCH: u8 = 48;
    /// Upper angle limit, 0.1°.
    pub const ANGLE_LIMIT_HIGH: u8 = 51;
    /// Lower angle limit, 0.1°.
    pub const ANGLE_LIMIT_LOW: u8 = 52;
}

/// The default reply latency: how long after a request ends a servo starts answering.
pub const DEFAULT_LATENCY: Duration = Duration::from_micros(300);

/// The baud rate of the empty profile that stands in should the built-in one ever fail to
/// parse (the servos' factory rate); otherwise the profile's own `baud` is used.
const FALLBACK_BAUD: u32 = 115_200;

/// Defaults for the user parameters the seed leaves open ("?" or no value): the vendor's usual
/// factory settings. The profile's own `default`s win where it has them.
pub(super) fn fallback_default(id: u8) -> i64 {
    match id {
        37 => 1,     // stall protection: limit the power
        38 => 4_000, // stall power limit, mW
        39 => 4_500, // voltage low, mV
        40 => 14_000,
        41 => 65, // °C
        42 => 12_000,
        43 => 3_000,
        48 => 0,
        49 => 0,
        50 => 3_000,
        51 => 1_800,
        52 => -1_800,
        _ => 0,
    }
}

/// The built-in servo profile (parsed once). Should it ever fail to parse, an empty profile
/// stands in: the servos then know no parameters, and never panic.
pub fn builtin_servo_profile() -> Arc<Profile> {
    static PROFILE: OnceLock<Arc<Profile>> = OnceLock::new();
    PROFILE
        .get_or_init(|| {
            let src = BUILTIN
                .iter()
                .find(|(name, _)| *name == "servo")
                .map_or("", |(_, src)| *src);
            Arc::new(
                parse("builtin:assets/profiles/servo.ron", src, Some("servo"))
                    .unwrap_or_else(|_| Profile::empty("servo", Protocol::Servo, FALLBACK_BAUD)),
            )
        })
        .clone()
}

/// What a servo handling a request knows of the bus.
struct BusCtx<'a> {
    profile: &'a Profile,
    rng: &'a mut fastrand::Rng,
    latency: Duration,
    now: Instant,
}

/// A servo's answer: a frame and when it starts, after the request ends.
struct Reply {
    command: u8,
    content: Vec<u8>,
    after: Duration,
    baud: u32,
}

/// A bus of servos: one [`Device`] on one line.
#[derive(Debug)]
pub struct ServoBus {
    servos: Vec<SimServo>,
    profile: Arc<Profile>,
    rng: fastrand::Rng,
    latency: Duration,
    decoder: ServoDecoder,
    decoder_baud: Option<u32>,
    /// When the last byte from the host arrived: a servo's receiver starts afresh after a
    /// quiet line (a request garbled by a collision does not swallow the next one).
    last_rx: Option<Instant>,
}

impl ServoBus {
    /// A bus with these servos, the built-in servo profile, [`DEFAULT_LATENCY`] and seed 0.
    pub fn new(servos: Vec<SimServo>) -> Self {
        Self::with_profile(builtin_servo_profile(), servos)
    }

    /// A bus whose servos check writes against `profile` (a user's override, say).
    pub fn with_profile(profile: Arc<Profile>, servos: Vec<SimServo>) -> Self {
        Self {
            servos,
            profile,
            rng: fastrand::Rng::with_seed(0),
            latency: DEFAULT_LATENCY,
            decoder: ServoDecoder::new(),
            decoder_baud: None,
            last_rx: None,
        }
    }

    /// Factory-fresh servos with these ids, all at `baud`; serial numbers 1001, 1002, ...
    pub fn with_ids(ids: &[u8], baud: u32) -> Self {
        Self::new(
            ids.iter()
                .enumerate()
                .map(|(i, &id)| SimServo::fresh(1001 + i as u32).with_id(id).with_baud(baud))
                .collect(),
        )
    }

    /// Factory-fresh servos of firmware described by `profile` (its parameter defaults, the
    /// form of its temperatures) with these ids, all at `baud`; serial numbers 1001, 1002, ...
    /// Id 255 (broadcast) is refused.
    pub fn with_profile_ids(profile: Arc<Profile>, ids: &[u8], baud: u32) -> Result<Self, String> {
        if ids.contains(&BROADCAST_ID) {
            return Err("servo id 255 is the broadcast address; ids are 0-254".into());
        }
        let servos = ids
            .iter()
            .enumerate()
            .map(|(i, &id)| {
                SimServo::fresh_with(&profile, 1001 + i as u32)
                    .with_id(id)
                    .with_baud(baud)
            })
            .collect();
        Ok(Self::with_profile(profile, servos))
    }

    /// The reply latency of every servo (the vendor's servos take 0.2-1 ms).
    pub fn with_latency(mut self, latency: Duration) -> Self {
        self.latency = latency;
        self
    }

    /// Every servo acknowledges a baud change and keeps its old rate (`ignored`).
    pub fn with_baud_change_ignored(mut self, ignored: bool) -> Self {
        for s in &mut self.servos {
            *s = s.clone().with_baud_change_ignored(ignored);
        }
        self
    }

    /// Every servo answers MONITOR with the "no data" form (angle -235929599, turns 0).
    pub fn with_monitor_no_data(mut self, no_data: bool) -> Self {
        for s in &mut self.servos {
            *s = s.clone().with_monitor_no_data(no_data);
        }
        self
    }

    /// Seeds the noise on live readings.
    pub fn with_seed(mut self, seed: u64) -> Self {
        self.rng = fastrand::Rng::with_seed(seed);
        self
    }

    /// The reply latency.
    pub fn latency(&self) -> Duration {
        self.latency
    }

    /// The profile the servos follow.
    pub fn profile(&self) -> &Arc<Profile> {
        &self.profile
    }

    /// The servos, in the order they were added.
    pub fn servos(&self) -> &[SimServo] {
        &self.servos
    }

    /// A servo by serial number.
    pub fn servo_by_serial(&self, serial: u32) -> Option<&SimServo> {
        self.servos.iter().find(|s| s.serial() == serial)
    }

    /// A servo by serial number, to change it.
    pub fn servo_by_serial_mut(&mut self, serial: u32) -> Option<&mut SimServo> {
        self.servos.iter_mut().find(|s| s.serial() == serial)
    }

    /// Plugs a servo into the bus.
    pub fn add(&mut self, servo: SimServo) {
        self.servos.push(servo);
    }

    /// Unplugs the servo with this serial number.
    pub fn remove(&mut self, serial: u32) -> Option<SimServo> {
        let i = self.servos.iter().position(|s| s.serial() == serial)?;
        Some(self.servos.remove(i))
    }

    fn dispatch(&mut self, frame: &Frame, baud: u32, now: Instant) -> Vec<Outgoing> {
        let profile = self.profile.clone();
        let mut ctx = BusCtx {
            profile: &profile,
            rng: &mut self.rng,
            latency: self.latency,
            now,
        };
        let mut replies = Vec::new();
        match frame.target() {
            Target::Servo { id } => {
                for s in self.servos.iter_mut().filter(|s| s.baud() == baud) {
                    if s.id() == id
                        && let Some(r) = s.handle(frame, &mut ctx)
                    {
                        replies.push(r);
                    }
                }
            }
            Target::Broadcast | Target::Bus => {
                for s in self.servos.iter_mut().filter(|s| s.baud() == baud) {
                    let _ = s.handle(frame, &mut ctx);
                }
            }
            Target::Sync { .. } => replies = sync(&mut self.servos, frame, baud, &mut ctx),
        }
        collide(replies, baud, &mut self.rng)
    }
}

/// A synchronous command (25): each record goes to the servo it names as the single command
/// `sub_command`. A MONITOR sub-command is answered by each servo in turn, in the order asked,
/// each reply starting when the one before has ended; the other sub-commands are not answered.
/// Old servos do not know command 25 and stay silent.
fn sync(servos: &mut [SimServo], frame: &Frame, baud: u32, ctx: &mut BusCtx<'_>) -> Vec<Reply> {
    let Ok(sync) = Sync::parse(&frame.content) else {
        return Vec::new();
    };
    let mut replies: Vec<Reply> = Vec::new();
    let mut next = ctx.latency;
    for record in sync.records {
        let Some(&id) = record.first() else { continue };
        let single = Frame::request(sync.sub_command, record.to_vec());
        for s in servos
            .iter_mut()
            .filter(|s| s.baud() == baud && s.extended() && s.id() == id && id != BROADCAST_ID)
        {
            let Some(mut r) = s.handle(&single, ctx) else {
                continue;
            };
            if sync.sub_command == cmd::MONITOR {
                r.after = next;
                next += crate::link::wire_time(r.content.len() + 5, r.baud);
                replies.push(r);
            }
        }
    }
    replies
}

/// Frames that leave at the same moment at the same rate share the open-drain line: the host
/// sees their wired AND. Two servos never start in step to the bit (their latencies differ by a
/// few bit times), so each later frame is skewed by 2-5 bits; identical replies (a PING answered
/// by two servos on one id) come out garbled too, never as a clean frame.
fn collide(replies: Vec<Reply>, request_baud: u32, rng: &mut fastrand::Rng) -> Vec<Outgoing> {
    let mut groups: Vec<(Duration, u32, Vec<Vec<u8>>)> = Vec::new();
    for r in replies {
        let Ok(bytes) = Frame::reply(r.command, r.content).encode() else {
            continue;
        };
        match groups
            .iter_mut()
            .find(|(after, baud, _)| *after == r.after && *baud == r.baud)
        {
            Some((_, _, frames)) => frames.push(bytes),
            None => groups.push((r.after, r.baud, vec![bytes])),
        }
    }
    groups.sort_by_key(|(after, _, _)| *after);
    groups
        .into_iter()
        .map(|(after, baud, frames)| Outgoing {
            after,
            bytes: wired_and(&frames, rng),
            baud: (baud != request_baud).then_some(baud),
        })
        .collect()
}

/// The bytes a UART receives from frames driven onto one open-drain line together, each after
/// the first starting a few bit times later than the one before.
fn wired_and(frames: &[Vec<u8>], rng: &mut fastrand::Rng) -> Vec<u8> {
    match frames {
        [] => return Vec::new(),
        [one] => return one.clone(),
        _ => {}
    }
    // 8N1: start bit 0, data LSB first, stop bit 1; the idle line is 1.
    let mut line: Vec<bool> = Vec::new();
    let mut offset = 0usize;
    for (i, frame) in frames.iter().enumerate() {
        if i > 0 {
            offset += rng.usize(2..=5);
        }
        let bits = frame.iter().flat_map(|&b| {
            std::iter::once(false)
                .chain((0..8).map(move |k| b >> k & 1 == 1))
                .chain(std::iter::once(true))
        });
        for (k, bit) in bits.enumerate() {
            let at = offset + k;
            if at >= line.len() {
                line.resize(at + 1, true);
            }
            line[at] &= bit;
        }
    }
    // A receiver: wait for a start bit, sample eight data bits, skip the stop bit.
    let mut out = Vec::new();
    let mut i = 0;
    while i < line.len() {
        if line[i] {
            i += 1;
            continue;
        }
        let mut byte = 0u8;
        for k in 0..8 {
            if line.get(i + 1 + k).copied().unwrap_or(true) {
                byte |= 1 << k;
            }
        }
        out.push(byte);
        i += 10;
    }
    out
}

impl Device for ServoBus {
    fn receive(&mut self, bytes: &[u8], baud: u32, now: Instant) -> Vec<Outgoing> {
        if self.decoder_baud != Some(baud) {
            self.decoder.clear();
            self.decoder_baud = Some(baud);
        }
        // A gap of a few byte times ends whatever partial frame the receiver holds.
        let started = now - crate::link::wire_time(bytes.len(), baud);
        let quiet = crate::link::wire_time(3, baud) + Duration::from_micros(500);
        if self
            .last_rx
            .is_some_and(|last| started.saturating_duration_since(last) > quiet)
        {
            self.decoder.clear();
        }
        self.last_rx = Some(now);
        self.decoder.push(bytes);
        let frames: Vec<Frame> = self
            .decoder
            .by_ref()
            .filter_map(Result::ok)
            .filter(|f| f.direction == Direction::HostToDevice)
            .collect();
        let mut out = Vec::new();
        for f in &frames {
            out.extend(self.dispatch(f, baud, now));
        }
        out
    }
}
