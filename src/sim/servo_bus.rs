//! A daisy chain of UART bus servos (seed 002, PROTOCOL_NOTES §2) on one half-duplex line.
//!
//! Every servo keeps its own id, baud rate, user parameters and motion. A servo hears a request
//! only when it was sent at its own baud rate and names its id (or 255, broadcast, which nobody
//! answers). Two servos that answer together collide on the open-drain line: the host sees the
//! byte-wise AND of their frames. Parameter writes are checked against the servo profile.
//!
//! Angles are in 0.1° throughout, as on the wire. Clockwise spin (method bit 7) counts up.

use super::{Device, Outgoing};
use crate::profile::registry::{BUILTIN, parse};
use crate::profile::{Access, FieldType, Param, Profile, Protocol, Text, Value};
use crate::protocol::Direction;
use crate::protocol::servo::{BROADCAST_ID, Frame, ServoDecoder, cmd};
use std::collections::BTreeMap;
use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

/// The vendor SDK's command ids that [`cmd`] does not name.
pub mod ext {
    /// Angle with acceleration and deceleration times.
    pub const ROTATE_BY_INTERVAL: u8 = 11;
    /// Angle by speed.
    pub const ROTATE_BY_VELOCITY: u8 = 12;
    /// Multi-turn angle.
    pub const ROTATE_MTURN: u8 = 13;
    /// Read the multi-turn angle and turn count.
    pub const READ_ANGLE_MTURN: u8 = 16;
    /// Reset the turn count.
    pub const RESET_MTURN: u8 = 17;
    /// Read every live value at once.
    pub const MONITOR: u8 = 22;
    /// Make the present position the origin.
    pub const SET_ORIGIN: u8 = 23;
    /// Stop: release, hold or damp.
    pub const STOP: u8 = 24;
}

/// Parameter ids the simulator gives a meaning to.
pub mod param {
    /// Reply to motion commands when done (1) or not at all (0).
    pub const RESPONSE_SWITCH: u8 = 33;
    /// The bus id.
    pub const SERVO_ID: u8 = 34;
    /// The baud-rate option (1-8).
    pub const BAUDRATE: u8 = 36;
    /// Hold (1) or release (0) when a wheel-mode spin stops.
    pub const WB_LOCK_SWITCH: u8 = 47;
    /// Angle limits 51/52 apply when 1.
    pub const ANGLE_LIMIT_SWITCH: u8 = 48;
    /// Upper angle limit, 0.1°.
    pub const ANGLE_LIMIT_HIGH: u8 = 51;
    /// Lower angle limit, 0.1°.
    pub const ANGLE_LIMIT_LOW: u8 = 52;
}

/// Baud-rate options of parameter 36 (option 8 on newer servos only).
pub const BAUD_OPTIONS: [(u8, u32); 8] = [
    (1, 9_600),
    (2, 19_200),
    (3, 38_400),
    (4, 57_600),
    (5, 115_200),
    (6, 250_000),
    (7, 500_000),
    (8, 1_000_000),
];

/// The baud rate of an option of parameter 36.
pub fn baud_of_option(option: u8) -> Option<u32> {
    BAUD_OPTIONS
        .iter()
        .find(|(o, _)| *o == option)
        .map(|(_, b)| *b)
}

/// The option of parameter 36 for a baud rate.
pub fn option_of_baud(baud: u32) -> Option<u8> {
    BAUD_OPTIONS
        .iter()
        .find(|(_, b)| *b == baud)
        .map(|(o, _)| *o)
}

/// The default reply latency: how long after a request ends a servo starts answering.
pub const DEFAULT_LATENCY: Duration = Duration::from_micros(300);

/// The factory baud rate.
pub const FACTORY_BAUD: u32 = 115_200;

/// Defaults for the user parameters the seed leaves open ("?" or no value): the vendor's usual
/// factory settings. The profile's own `default`s win where it has them.
fn fallback_default(id: u8) -> i64 {
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

fn empty_profile(id: &str, protocol: Protocol, baud: u32) -> Profile {
    Profile {
        id: id.to_string(),
        name: Text {
            en: id.to_string(),
            zh: id.to_string(),
        },
        protocol,
        baud,
        device_code: None,
        groups: Vec::new(),
        commands: Vec::new(),
        params: Vec::new(),
        data_points: Vec::new(),
        plots: Vec::new(),
        panels: Vec::new(),
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
                    .unwrap_or_else(|_| empty_profile("servo", Protocol::Servo, FACTORY_BAUD)),
            )
        })
        .clone()
}

fn width(p: &Param) -> usize {
    p.field.ty.width().unwrap_or(1).min(4)
}

fn le_bytes(v: i64, n: usize) -> Vec<u8> {
    (v as u32).to_le_bytes()[..n.min(4)].to_vec()
}

fn int_le(bytes: &[u8], ty: FieldType) -> i64 {
    let mut b = [0u8; 4];
    let n = bytes.len().min(4);
    b[..n].copy_from_slice(&bytes[..n]);
    let u = u32::from_le_bytes(b);
    match ty {
        FieldType::I8 => u as u8 as i8 as i64,
        FieldType::I16 => u as u16 as i16 as i64,
        FieldType::I32 => u as i32 as i64,
        _ => u as i64,
    }
}

fn u16_at(c: &[u8], at: usize) -> u16 {
    match c.get(at..at + 2) {
        Some(&[a, b]) => u16::from_le_bytes([a, b]),
        _ => 0,
    }
}

fn u32_at(c: &[u8], at: usize) -> u32 {
    match c.get(at..at + 4) {
        Some(&[a, b, d, e]) => u32::from_le_bytes([a, b, d, e]),
        _ => 0,
    }
}

fn later(start: Instant, d: Duration) -> Instant {
    start.checked_add(d).unwrap_or(start)
}

/// Wraps a multi-turn angle (0.1°) into one turn, (-180°, 180°].
fn wrap(angle: f64) -> f64 {
    let mut a = angle % 3600.0;
    if a > 1800.0 {
        a -= 3600.0;
    } else if a <= -1800.0 {
        a += 3600.0;
    }
    a
}

/// What a servo's output shaft is doing.
#[derive(Debug, Clone, PartialEq)]
pub enum Motion {
    /// Holding its angle.
    Hold,
    /// No torque: the shaft is free.
    Released,
    /// Damping mode with this holding power, mW (0 = the limit).
    Damping {
        /// The holding power.
        power: u16,
    },
    /// Angle mode: moving linearly from `from` to `to` (0.1°) over `duration` from `start`.
    Move {
        /// The angle at the start.
        from: f64,
        /// The target.
        to: f64,
        /// When the move began.
        start: Instant,
        /// How long it takes.
        duration: Duration,
    },
    /// Wheel mode: turning at `rate` (0.1°/s, signed) from `from` since `start`, for `limit` if
    /// given (turns and timed modes), else until told otherwise.
    Spin {
        /// The angle at the start.
        from: f64,
        /// 0.1° per second; positive is clockwise.
        rate: f64,
        /// When the spin began.
        start: Instant,
        /// How long it lasts, if it stops by itself.
        limit: Option<Duration>,
    },
}

/// A motion command, as queued while a non-interruptible one runs (response switch on).
#[derive(Debug, Clone, PartialEq)]
enum MotionCmd {
    /// Go to an angle; `single_turn` targets are within one turn (commands 8, 11, 12).
    Move {
        target: f64,
        single_turn: bool,
        timing: Timing,
    },
    Spin {
        rate: f64,
        limit: Option<Duration>,
    },
    SpinStop,
    Damping(u16),
    Stop {
        mode: u8,
        power: u16,
    },
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Timing {
    Interval(Duration),
    /// 0.1° per second.
    Speed(f64),
}

/// One simulated servo.
#[derive(Debug, Clone)]
pub struct SimServo {
    serial: u32,
    baud: u32,
    servo_type: u16,
    firmware: u16,
    extended: bool,
    params: BTreeMap<u8, i64>,
    defaults: BTreeMap<u8, i64>,
    voltage_mv: u16,
    temperature_c: u16,
    status: u8,
    /// Multi-turn angle, 0.1°, as of the last settled motion.
    angle: f64,
    motion: Motion,
    queued: Option<MotionCmd>,
}

impl SimServo {
    /// A servo as it leaves the factory: id 0, 115200 baud, default parameters from the built-in
    /// profile, angle 0, extended commands answered.
    pub fn fresh(serial: u32) -> Self {
        Self::fresh_with(&builtin_servo_profile(), serial)
    }

    /// A factory-fresh servo whose parameter defaults come from `profile`.
    pub fn fresh_with(profile: &Profile, serial: u32) -> Self {
        let mut defaults = BTreeMap::new();
        for p in profile.block_params() {
            defaults.insert(p.id, p.field.default.unwrap_or(fallback_default(p.id)));
        }
        let baud = defaults
            .get(&param::BAUDRATE)
            .and_then(|&o| u8::try_from(o).ok())
            .and_then(baud_of_option)
            .unwrap_or(FACTORY_BAUD);
        Self {
            serial,
            baud,
            servo_type: 0x0101,
            firmware: 0x0203,
            extended: true,
            params: defaults.clone(),
            defaults,
            voltage_mv: 7_400,
            temperature_c: 32,
            status: 0,
            angle: 0.0,
            motion: Motion::Released,
            queued: None,
        }
    }

    /// Sets the bus id (parameter 34).
    pub fn with_id(mut self, id: u8) -> Self {
        self.params.insert(param::SERVO_ID, id as i64);
        self
    }

    /// Sets the baud rate; parameter 36 follows when the rate is one of [`BAUD_OPTIONS`].
    pub fn with_baud(mut self, baud: u32) -> Self {
        self.baud = baud;
        if let Some(o) = option_of_baud(baud) {
            self.params.insert(param::BAUDRATE, o as i64);
        }
        self
    }

    /// Whether the servo answers the SDK's commands 11-24 (an old servo stays silent).
    pub fn with_extended(mut self, extended: bool) -> Self {
        self.extended = extended;
        self
    }

    /// The servo type (read-only parameter 6).
    pub fn with_type(mut self, servo_type: u16) -> Self {
        self.servo_type = servo_type;
        self
    }

    /// The firmware version (read-only parameter 7).
    pub fn with_firmware(mut self, firmware: u16) -> Self {
        self.firmware = firmware;
        self
    }

    /// Sets a user parameter's raw value, unchecked (and the id or baud with it).
    pub fn with_param(mut self, id: u8, raw: i64) -> Self {
        self.store(id, raw);
        self
    }

    /// The angle, 0.1°: the servo holds it.
    pub fn with_angle(mut self, deci_degrees: i32) -> Self {
        self.angle = deci_degrees as f64;
        self.motion = Motion::Hold;
        self.queued = None;
        self
    }

    /// The supply voltage around which readings vary, mV.
    pub fn with_voltage(mut self, mv: u16) -> Self {
        self.voltage_mv = mv;
        self
    }

    /// The temperature, °C.
    pub fn with_temperature(mut self, celsius: u16) -> Self {
        self.temperature_c = celsius;
        self
    }

    /// The raw status byte (read-only parameter 5).
    pub fn with_status(mut self, status: u8) -> Self {
        self.status = status;
        self
    }

    /// The serial number (read-only parameter 8), unique per servo.
    pub fn serial(&self) -> u32 {
        self.serial
    }

    /// The bus id (parameter 34).
    pub fn id(&self) -> u8 {
        self.params
            .get(&param::SERVO_ID)
            .and_then(|&v| u8::try_from(v).ok())
            .unwrap_or(0)
    }

    /// The actual baud rate.
    pub fn baud(&self) -> u32 {
        self.baud
    }

    /// Whether it answers commands 11-24.
    pub fn extended(&self) -> bool {
        self.extended
    }

    /// A user parameter's raw value.
    pub fn param(&self, id: u8) -> Option<i64> {
        self.params.get(&id).copied()
    }

    /// Every user parameter, by id.
    pub fn params(&self) -> &BTreeMap<u8, i64> {
        &self.params
    }

    /// The status byte.
    pub fn status(&self) -> u8 {
        self.status
    }

    /// The multi-turn angle at `now`, 0.1° (interpolated during a move).
    pub fn angle_at(&self, now: Instant) -> f64 {
        let mut s = self.clone();
        s.advance(now);
        s.current_angle(now)
    }

    /// What the shaft is doing at `now`.
    pub fn motion_at(&self, now: Instant) -> Motion {
        let mut s = self.clone();
        s.advance(now);
        s.motion
    }

    fn store(&mut self, id: u8, raw: i64) {
        self.params.insert(id, raw);
        if id == param::BAUDRATE
            && let Some(b) = u8::try_from(raw).ok().and_then(baud_of_option)
        {
            self.baud = b;
        }
    }

    fn p(&self, id: u8) -> i64 {
        self.params.get(&id).copied().unwrap_or(0)
    }

    fn current_angle(&self, now: Instant) -> f64 {
        match &self.motion {
            Motion::Move {
                from,
                to,
                start,
                duration,
            } => {
                let total = duration.as_secs_f64();
                let t = now.saturating_duration_since(*start).as_secs_f64();
                if total <= 0.0 || t >= total {
                    *to
                } else {
                    from + (to - from) * t / total
                }
            }
            Motion::Spin {
                from,
                rate,
                start,
                limit,
            } => {
                let mut t = now.saturating_duration_since(*start);
                if let Some(l) = limit {
                    t = t.min(*l);
                }
                from + rate * t.as_secs_f64()
            }
            _ => self.angle,
        }
    }

    /// When the present motion ends by itself.
    fn motion_end(&self) -> Option<Instant> {
        match &self.motion {
            Motion::Move {
                start, duration, ..
            } => Some(later(*start, *duration)),
            Motion::Spin {
                start,
                limit: Some(l),
                ..
            } => Some(later(*start, *l)),
            _ => None,
        }
    }

    fn moving(&self, now: Instant) -> bool {
        self.motion_end().is_some_and(|end| end > now)
            || matches!(self.motion, Motion::Spin { limit: None, rate, .. } if rate != 0.0)
    }

    /// Settles motions that have ended by `now`, starting queued ones in turn.
    fn advance(&mut self, now: Instant) {
        while let Some(end) = self.motion_end() {
            if end > now {
                break;
            }
            self.angle = self.current_angle(end);
            self.motion = match self.motion {
                Motion::Spin { .. } if self.p(param::WB_LOCK_SWITCH) == 0 => Motion::Released,
                _ => Motion::Hold,
            };
            if let Some(q) = self.queued.take() {
                self.start(q, end);
            }
        }
    }

    fn clamp_target(&self, target: f64) -> f64 {
        let mut t = target.clamp(-1800.0, 1800.0);
        if self.p(param::ANGLE_LIMIT_SWITCH) == 1 {
            let hi = self.p(param::ANGLE_LIMIT_HIGH) as f64;
            let lo = self.p(param::ANGLE_LIMIT_LOW) as f64;
            if lo <= hi {
                t = t.clamp(lo, hi);
            }
        }
        t
    }

    /// How long `c` runs when started from `from` (0.1°).
    fn plan(&self, c: &MotionCmd, from: f64) -> Duration {
        match c {
            MotionCmd::Move {
                target,
                single_turn,
                timing,
            } => match timing {
                Timing::Interval(d) => *d,
                Timing::Speed(speed) if *speed > 0.0 => {
                    let (from, to) = if *single_turn {
                        (wrap(from), self.clamp_target(*target))
                    } else {
                        (from, *target)
                    };
                    Duration::from_secs_f64(((to - from).abs() / speed).min(1.0e7))
                }
                Timing::Speed(_) => Duration::ZERO,
            },
            MotionCmd::Spin { limit, .. } => limit.unwrap_or(Duration::ZERO),
            _ => Duration::ZERO,
        }
    }

    /// Starts `c` at `at` (the present angle is settled first). Returns how long it runs.
    fn start(&mut self, c: MotionCmd, at: Instant) -> Duration {
        self.angle = self.current_angle(at);
        let duration = self.plan(&c, self.angle);
        self.motion = match c {
            MotionCmd::Move {
                target,
                single_turn,
                ..
            } => {
                let (from, to) = if single_turn {
                    (wrap(self.angle), self.clamp_target(target))
                } else {
                    (self.angle, target)
                };
                self.angle = from;
                Motion::Move {
                    from,
                    to,
                    start: at,
                    duration,
                }
            }
            MotionCmd::Spin { rate, limit } => Motion::Spin {
                from: self.angle,
                rate,
                start: at,
                limit,
            },
            MotionCmd::SpinStop if self.p(param::WB_LOCK_SWITCH) == 0 => Motion::Released,
            MotionCmd::SpinStop => Motion::Hold,
            MotionCmd::Damping(power) => Motion::Damping { power },
            MotionCmd::Stop { mode: 0x10, .. } => Motion::Released,
            MotionCmd::Stop { mode: 0x12, power } => Motion::Damping { power },
            MotionCmd::Stop { .. } => Motion::Hold,
        };
        duration
    }

    /// Runs a motion command. With the response switch on, a command that arrives while a
    /// finite motion runs waits for it (a queue of one; more are dropped). Returns how long from
    /// `now` until the command has finished, or `None` if it was dropped.
    fn command_motion(&mut self, c: MotionCmd, now: Instant) -> Option<Duration> {
        self.advance(now);
        let queued_mode = self.p(param::RESPONSE_SWITCH) == 1;
        let busy_until = self.motion_end().filter(|end| *end > now);
        match busy_until {
            Some(end) if queued_mode => {
                if self.queued.is_some() {
                    return None;
                }
                let from = match &self.motion {
                    Motion::Move { to, .. } => *to,
                    _ => self.current_angle(end),
                };
                let d = self.plan(&c, from);
                self.queued = Some(c);
                Some(end.saturating_duration_since(now) + d)
            }
            _ => {
                self.queued = None;
                Some(self.start(c, now))
            }
        }
    }

    fn current_ma(&self, now: Instant, rng: &mut fastrand::Rng) -> u16 {
        let base: u16 = if self.moving(now) {
            250
        } else {
            match self.motion {
                Motion::Hold => 40,
                Motion::Damping { .. } => 20,
                _ => 6,
            }
        };
        base + rng.u16(0..=base / 8 + 2)
    }

    fn live(&self, now: Instant, rng: &mut fastrand::Rng) -> Live {
        let voltage = self
            .voltage_mv
            .saturating_add(rng.u16(0..=40))
            .saturating_sub(20);
        let current = self.current_ma(now, rng);
        let power = (voltage as u32 * current as u32 / 1000).min(u16::MAX as u32) as u16;
        Live {
            voltage,
            current,
            power,
            temperature: self.temperature_c,
        }
    }

    /// The bytes of a parameter's value, or `None` if the servo has no such parameter.
    fn read_param(
        &self,
        profile: &Profile,
        id: u8,
        now: Instant,
        rng: &mut fastrand::Rng,
    ) -> Option<Vec<u8>> {
        let p = profile.param(id)?;
        let n = width(p);
        let v: i64 = match (p.access, id) {
            (Access::ReadWrite, _) => *self.params.get(&id)?,
            (Access::ReadOnly, 1) => self.live(now, rng).voltage as i64,
            (Access::ReadOnly, 2) => self.current_ma(now, rng) as i64,
            (Access::ReadOnly, 3) => self.live(now, rng).power as i64,
            (Access::ReadOnly, 4) => self.temperature_c as i64,
            (Access::ReadOnly, 5) => self.status as i64,
            (Access::ReadOnly, 6) => self.servo_type as i64,
            (Access::ReadOnly, 7) => self.firmware as i64,
            (Access::ReadOnly, 8) => self.serial as i64,
            (Access::ReadOnly, _) => 0,
        };
        Some(le_bytes(v, n))
    }

    /// Whether `raw` may be stored in parameter `p` of this servo.
    fn writable(&self, p: &Param, raw: i64) -> bool {
        if p.access != Access::ReadWrite || p.field.check(&Value::Int(raw)).is_err() {
            return false;
        }
        match p.id {
            param::SERVO_ID => raw != BROADCAST_ID as i64,
            param::BAUDRATE => u8::try_from(raw)
                .ok()
                .and_then(baud_of_option)
                .is_some_and(|b| self.extended || b != 1_000_000),
            _ => true,
        }
    }

    fn write_param(&mut self, profile: &Profile, id: u8, data: &[u8]) -> bool {
        let Some(p) = profile.param(id) else {
            return false;
        };
        if data.len() != width(p) {
            return false;
        }
        let raw = int_le(data, p.field.ty);
        if !self.writable(p, raw) {
            return false;
        }
        self.store(id, raw);
        true
    }

    fn block(&self, profile: &Profile) -> Vec<u8> {
        let mut out = Vec::with_capacity(32);
        for p in profile.block_params() {
            out.extend(le_bytes(self.p(p.id), width(p)));
        }
        out
    }

    fn write_block(&mut self, profile: &Profile, block: &[u8]) -> bool {
        let mut values = Vec::new();
        let mut at = 0;
        for p in profile.block_params() {
            let n = width(p);
            let Some(bytes) = block.get(at..at + n) else {
                return false;
            };
            let raw = int_le(bytes, p.field.ty);
            if !self.writable(p, raw) {
                return false;
            }
            values.push((p.id, raw));
            at += n;
        }
        if at != block.len() {
            return false;
        }
        for (id, raw) in values {
            self.store(id, raw);
        }
        true
    }

    /// Handles a request this servo heard. `Some` is what it sends back, if anything, and when.
    fn handle(&mut self, frame: &Frame, bus: &mut BusCtx<'_>) -> Option<Reply> {
        let c = frame.content.as_slice();
        let id = self.id();
        let baud = self.baud;
        let now = bus.now;
        let latency = bus.latency;
        let immediate = |content: Vec<u8>, s: &Self| Reply {
            content,
            command: frame.command,
            after: latency,
            baud: s.baud,
        };
        // A motion command answers only with the response switch on, once it has finished.
        let motion = |s: &mut Self, m: MotionCmd| -> Option<Reply> {
            let done = s.command_motion(m, now)?;
            (s.p(param::RESPONSE_SWITCH) == 1).then(|| Reply {
                content: vec![s.id(), 1],
                command: frame.command,
                after: done + latency,
                baud,
            })
        };
        if !self.extended && frame.command > cmd::READ_ANGLE {
            return None;
        }
        match (frame.command, c.len()) {
            (cmd::PING, 1) => Some(immediate(vec![id], self)),
            (cmd::RESET_USER_DATA, 1) => {
                self.params = self.defaults.clone();
                if let Some(b) = u8::try_from(self.p(param::BAUDRATE))
                    .ok()
                    .and_then(baud_of_option)
                {
                    self.baud = b;
                }
                Some(immediate(vec![self.id(), 1], self))
            }
            (cmd::READ_DATA, 2) => {
                let mut out = vec![id, c[1]];
                out.extend(self.read_param(bus.profile, c[1], now, bus.rng)?);
                Some(immediate(out, self))
            }
            (cmd::WRITE_DATA, n) if n >= 2 => {
                let ok = self.write_param(bus.profile, c[1], &c[2..]);
                Some(immediate(vec![self.id(), c[1], u8::from(ok)], self))
            }
            (cmd::READ_BATCH_DATA, 1) => {
                let mut out = vec![id];
                out.extend(self.block(bus.profile));
                Some(immediate(out, self))
            }
            (cmd::WRITE_BATCH_DATA, _) => {
                let ok = self.write_block(bus.profile, c.get(1..).unwrap_or_default());
                Some(immediate(vec![self.id(), u8::from(ok)], self))
            }
            (cmd::SPIN, 6) => {
                let method = c[1];
                let speed = u16_at(c, 2) as f64;
                let value = u16_at(c, 4) as u64;
                let sign = if method & 0x80 != 0 { 1.0 } else { -1.0 };
                let rate = sign * speed * 10.0;
                let m = match method & 0x03 {
                    0 => MotionCmd::SpinStop,
                    1 => MotionCmd::Spin { rate, limit: None },
                    2 => {
                        let secs = if speed > 0.0 {
                            value as f64 * 360.0 / speed
                        } else {
                            0.0
                        };
                        MotionCmd::Spin {
                            rate,
                            limit: Some(Duration::from_secs_f64(secs)),
                        }
                    }
                    _ => MotionCmd::Spin {
                        rate,
                        limit: Some(Duration::from_millis(value)),
                    },
                };
                motion(self, m)
            }
            (cmd::ROTATE, 7) => {
                let m = MotionCmd::Move {
                    target: u16_at(c, 1) as i16 as f64,
                    single_turn: true,
                    timing: Timing::Interval(Duration::from_millis(u16_at(c, 3) as u64)),
                };
                motion(self, m)
            }
            (cmd::DAMPING, 3) => motion(self, MotionCmd::Damping(u16_at(c, 1))),
            (cmd::READ_ANGLE, 1) => {
                self.advance(now);
                let a = wrap(self.current_angle(now)).round() as i16;
                let mut out = vec![id];
                out.extend(a.to_le_bytes());
                Some(immediate(out, self))
            }
            (ext::ROTATE_BY_INTERVAL, 11) => {
                let m = MotionCmd::Move {
                    target: u16_at(c, 1) as i16 as f64,
                    single_turn: true,
                    timing: Timing::Interval(Duration::from_millis(u16_at(c, 3) as u64)),
                };
                motion(self, m)
            }
            (ext::ROTATE_BY_VELOCITY, 11) => {
                let m = MotionCmd::Move {
                    target: u16_at(c, 1) as i16 as f64,
                    single_turn: true,
                    timing: Timing::Speed(u16_at(c, 3) as f64),
                };
                motion(self, m)
            }
            (ext::ROTATE_MTURN, 11) => {
                let m = MotionCmd::Move {
                    target: u32_at(c, 1) as i32 as f64,
                    single_turn: false,
                    timing: Timing::Interval(Duration::from_millis(u32_at(c, 5) as u64)),
                };
                motion(self, m)
            }
            (ext::READ_ANGLE_MTURN, 1) => {
                self.advance(now);
                let (angle, turns) = mturn(self.current_angle(now));
                let mut out = vec![id];
                out.extend(angle.to_le_bytes());
                out.extend(turns.to_le_bytes());
                Some(immediate(out, self))
            }
            (ext::RESET_MTURN, 1) => {
                self.advance(now);
                let a = self.current_angle(now);
                let shift = a - wrap(a);
                self.rebase(shift);
                None
            }
            (ext::MONITOR, 1) => {
                self.advance(now);
                let live = self.live(now, bus.rng);
                let (angle, turns) = mturn(self.current_angle(now));
                let mut out = vec![id];
                out.extend(live.voltage.to_le_bytes());
                out.extend(live.current.to_le_bytes());
                out.extend(live.power.to_le_bytes());
                out.extend(ntc_adc(live.temperature).to_le_bytes());
                out.push(self.status);
                out.extend(angle.to_le_bytes());
                out.extend(turns.to_le_bytes());
                Some(immediate(out, self))
            }
            (ext::SET_ORIGIN, 2) => {
                self.advance(now);
                let a = self.current_angle(now);
                self.rebase(a);
                None
            }
            (ext::STOP, 4) if (0x10..=0x12).contains(&c[1]) => {
                let _ = self.command_motion(
                    MotionCmd::Stop {
                        mode: c[1],
                        power: u16_at(c, 2),
                    },
                    now,
                );
                None
            }
            _ => None,
        }
    }

    /// Subtracts `shift` (0.1°) from every angle the servo knows: a new origin.
    fn rebase(&mut self, shift: f64) {
        self.angle -= shift;
        match &mut self.motion {
            Motion::Move { from, to, .. } => {
                *from -= shift;
                *to -= shift;
            }
            Motion::Spin { from, .. } => *from -= shift,
            _ => {}
        }
    }
}

/// Multi-turn angle (i32, 0.1°) and whole turns (i16).
fn mturn(angle: f64) -> (i32, i16) {
    let a = angle.round().clamp(i32::MIN as f64, i32::MAX as f64) as i32;
    let turns = (angle / 3600.0)
        .trunc()
        .clamp(i16::MIN as f64, i16::MAX as f64) as i16;
    (a, turns)
}

/// A plausible raw NTC reading (12-bit ADC, falling as it warms) for a temperature in °C.
fn ntc_adc(celsius: u16) -> u16 {
    3_000u16.saturating_sub(celsius.saturating_mul(18))
}

struct Live {
    voltage: u16,
    current: u16,
    power: u16,
    temperature: u16,
}

struct BusCtx<'a> {
    profile: &'a Profile,
    rng: &'a mut fastrand::Rng,
    latency: Duration,
    now: Instant,
}

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

    /// The reply latency of every servo (the vendor's servos take 0.2-1 ms).
    pub fn with_latency(mut self, latency: Duration) -> Self {
        self.latency = latency;
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
        self.servos.iter().find(|s| s.serial == serial)
    }

    /// A servo by serial number, to change it.
    pub fn servo_by_serial_mut(&mut self, serial: u32) -> Option<&mut SimServo> {
        self.servos.iter_mut().find(|s| s.serial == serial)
    }

    /// Plugs a servo into the bus.
    pub fn add(&mut self, servo: SimServo) {
        self.servos.push(servo);
    }

    /// Unplugs the servo with this serial number.
    pub fn remove(&mut self, serial: u32) -> Option<SimServo> {
        let i = self.servos.iter().position(|s| s.serial == serial)?;
        Some(self.servos.remove(i))
    }

    fn dispatch(&mut self, frame: &Frame, baud: u32, now: Instant) -> Vec<Outgoing> {
        let Some(&target) = frame.content.first() else {
            return Vec::new();
        };
        let broadcast = target == BROADCAST_ID;
        let profile = self.profile.clone();
        let mut ctx = BusCtx {
            profile: &profile,
            rng: &mut self.rng,
            latency: self.latency,
            now,
        };
        let mut replies = Vec::new();
        for s in &mut self.servos {
            if s.baud != baud || (!broadcast && s.id() != target) {
                continue;
            }
            if let Some(r) = s.handle(frame, &mut ctx)
                && !broadcast
            {
                replies.push(r);
            }
        }
        collide(replies, baud, &mut self.rng)
    }
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
