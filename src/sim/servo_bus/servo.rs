//! One simulated servo: its id, baud rate, parameters and live readings, and how it answers
//! each command.

use super::motion::{Motion, MotionCmd, mturn, wrap};
use super::{BusCtx, Reply, builtin_servo_profile, fallback_default, param};
use crate::profile::codec::int_from;
use crate::profile::{Access, ByteOrder, Field, FieldType, Param, ParamRole, Profile, Value};
use crate::protocol::servo::{BROADCAST_ID, Frame, cmd};
use std::collections::BTreeMap;
use std::time::Instant;

fn width(p: &Param) -> usize {
    p.field.ty.width().unwrap_or(1).min(4)
}

fn le_bytes(v: i64, n: usize) -> Vec<u8> {
    (v as u32).to_le_bytes()[..n.min(4)].to_vec()
}

/// A little-endian integer of a field's type: the profile codec's reading.
fn int_le(bytes: &[u8], ty: FieldType) -> i64 {
    int_from(bytes, ty, ByteOrder::Little)
}

fn u16_at(c: &[u8], at: usize) -> u16 {
    match c.get(at..at + 2) {
        Some(&[a, b]) => u16::from_le_bytes([a, b]),
        _ => 0,
    }
}

/// One simulated servo.
#[derive(Debug, Clone)]
pub struct SimServo {
    serial: u32,
    baud: u32,
    servo_type: u16,
    firmware: u16,
    extended: bool,
    pub(super) params: BTreeMap<u8, i64>,
    defaults: BTreeMap<u8, i64>,
    /// The `data_id` of the id parameter (the profile's role ServoId), if it has one.
    id_param: Option<u8>,
    /// The `data_id` of the baud-option parameter (role BaudOption), if it has one.
    baud_param: Option<u8>,
    voltage_mv: u16,
    temperature_c: u16,
    status: u8,
    /// Multi-turn angle, 0.1°, as of the last settled motion.
    pub(super) angle: f64,
    pub(super) motion: Motion,
    pub(super) queued: Option<MotionCmd>,
    /// Between BEGIN_ASYNC and END_ASYNC: motion commands are held, not run.
    pub(super) holding: bool,
    /// The motion command held (the last one received while holding).
    pub(super) held: Option<MotionCmd>,
    /// Stores a new baud option but keeps talking at its old rate (firmware that applies it
    /// only after a power cycle, or not at all).
    ignores_baud_change: bool,
    /// Answers MONITOR with its "no data" form (angle -235929599, turns 0), as servos do
    /// that have no reading to give; the vendor SDK skips such an answer.
    monitor_no_data: bool,
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
        let id_param = profile.servo_id_param().map(|p| p.id);
        let baud_param = profile.baud_option_param().map(|(p, _)| p.id);
        let baud = baud_param
            .and_then(|b| defaults.get(&b))
            .and_then(|&o| u8::try_from(o).ok())
            .and_then(|o| profile.baud_of_option(o))
            .unwrap_or(profile.baud);
        Self {
            serial,
            baud,
            servo_type: 0x0101,
            firmware: 0x0203,
            extended: true,
            params: defaults.clone(),
            defaults,
            id_param,
            baud_param,
            voltage_mv: 7_400,
            temperature_c: 32,
            status: 0,
            angle: 0.0,
            motion: Motion::Released,
            queued: None,
            holding: false,
            held: None,
            ignores_baud_change: false,
            monitor_no_data: false,
        }
    }

    /// A servo that acknowledges a baud change and keeps its old rate.
    pub fn with_baud_change_ignored(mut self, ignored: bool) -> Self {
        self.ignores_baud_change = ignored;
        self
    }

    /// A servo whose MONITOR answers carry the "no data" form (angle -235929599, turns 0).
    pub fn with_monitor_no_data(mut self, no_data: bool) -> Self {
        self.monitor_no_data = no_data;
        self
    }

    /// Sets the bus id (the id parameter).
    pub fn with_id(mut self, id: u8) -> Self {
        if let Some(p) = self.id_param {
            self.params.insert(p, id as i64);
        }
        self
    }

    /// Sets the baud rate; the baud-option parameter follows when the rate is in the built-in servo
    /// profile's baud table.
    pub fn with_baud(mut self, baud: u32) -> Self {
        self.baud = baud;
        if let Some(o) = builtin_servo_profile().option_of_baud(baud)
            && let Some(p) = self.baud_param
        {
            self.params.insert(p, o as i64);
        }
        self
    }

    /// Whether the servo answers the SDK's commands 11-25 (an old servo stays silent).
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

    /// Sets a user parameter's raw value, unchecked (and the id or baud with it, at the built-in
    /// servo profile's rate).
    pub fn with_param(mut self, id: u8, raw: i64) -> Self {
        self.store(&builtin_servo_profile(), id, raw);
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

    /// The bus id (the id parameter; 0 without one).
    pub fn id(&self) -> u8 {
        self.id_param
            .and_then(|p| self.params.get(&p))
            .and_then(|&v| u8::try_from(v).ok())
            .unwrap_or(0)
    }

    /// The actual baud rate.
    pub fn baud(&self) -> u32 {
        self.baud
    }

    /// Whether it answers commands 11-25.
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

    /// Stores parameter `id`; the baud option takes effect at once, at `profile`'s rate.
    fn store(&mut self, profile: &Profile, id: u8, raw: i64) {
        self.params.insert(id, raw);
        if Some(id) == self.baud_param
            && !self.ignores_baud_change
            && let Some(b) = u8::try_from(raw)
                .ok()
                .and_then(|o| profile.baud_of_option(o))
        {
            self.baud = b;
        }
    }

    pub(super) fn p(&self, id: u8) -> i64 {
        self.params.get(&id).copied().unwrap_or(0)
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
        }
    }

    /// The temperature as a field says the firmware sends it: °C, or the thermistor reading
    /// its conversion reads as this temperature (parameter 4 and MONITOR agree by construction).
    fn temperature_raw(&self, field: Option<&Field>) -> i64 {
        let celsius = f64::from(self.temperature_c);
        match field.and_then(|f| f.convert) {
            Some(c) => c.invert(celsius).unwrap_or(0),
            None => celsius.round() as i64,
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
            (Access::ReadWrite | Access::WriteOnly, _) => *self.params.get(&id)?,
            (Access::ReadOnly, 1) => self.live(now, rng).voltage as i64,
            (Access::ReadOnly, 2) => self.current_ma(now, rng) as i64,
            (Access::ReadOnly, 3) => self.live(now, rng).power as i64,
            (Access::ReadOnly, 4) => self.temperature_raw(Some(&p.field)),
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
        match &p.role {
            Some(ParamRole::ServoId) => raw != BROADCAST_ID as i64,
            Some(ParamRole::BaudOption { rates }) => u8::try_from(raw)
                .ok()
                .and_then(|o| rates.get(&o))
                .is_some_and(|&b| self.extended || b != 1_000_000),
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
        self.store(profile, id, raw);
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
            self.store(profile, id, raw);
        }
        true
    }

    /// Handles a request this servo heard. `Some` is what it sends back, if anything, and when.
    pub(super) fn handle(&mut self, frame: &Frame, bus: &mut BusCtx<'_>) -> Option<Reply> {
        if !self.extended && frame.command > cmd::READ_ANGLE {
            return None;
        }
        // A motion command answers only with the response switch on, once it has finished;
        // between BEGIN_ASYNC and END_ASYNC it is held instead, and not answered.
        if let Some(m) = MotionCmd::from_request(frame.command, &frame.content) {
            if self.holding {
                self.held = Some(m);
                return None;
            }
            let done = self.command_motion(m, bus.now)?;
            return (self.p(param::RESPONSE_SWITCH) == 1).then(|| Reply {
                content: vec![self.id(), 1],
                command: frame.command,
                after: done + bus.latency,
                baud: self.baud,
            });
        }
        let content = self.answer(frame, bus)?;
        // At the rate the servo is at once it has handled the request (a reset changes it).
        Some(Reply {
            content,
            command: frame.command,
            after: bus.latency,
            baud: self.baud,
        })
    }

    /// What the servo answers at once to a request that is no motion command: its parameters,
    /// read and written, and a ping; the rest is [`Self::live_answer`].
    fn answer(&mut self, frame: &Frame, bus: &mut BusCtx<'_>) -> Option<Vec<u8>> {
        let c = frame.content.as_slice();
        let id = self.id();
        match (frame.command, c.len()) {
            (cmd::PING, 1) => Some(vec![id]),
            (cmd::RESET_USER_DATA, 1) => {
                self.params = self.defaults.clone();
                if let Some(b) = self
                    .baud_param
                    .and_then(|p| u8::try_from(self.p(p)).ok())
                    .and_then(|o| bus.profile.baud_of_option(o))
                {
                    self.baud = b;
                }
                Some(vec![self.id(), 1])
            }
            (cmd::READ_DATA, 2) => {
                let mut out = vec![id, c[1]];
                out.extend(self.read_param(bus.profile, c[1], bus.now, bus.rng)?);
                Some(out)
            }
            (cmd::WRITE_DATA, n) if n >= 2 => {
                let ok = self.write_param(bus.profile, c[1], &c[2..]);
                Some(vec![self.id(), c[1], u8::from(ok)])
            }
            (cmd::READ_BATCH_DATA, 1) => {
                let mut out = vec![id];
                out.extend(self.block(bus.profile));
                Some(out)
            }
            (cmd::WRITE_BATCH_DATA, _) => {
                let ok = self.write_block(bus.profile, c.get(1..).unwrap_or_default());
                Some(vec![self.id(), u8::from(ok)])
            }
            _ => self.live_answer(frame, bus),
        }
    }

    /// What the servo answers to a request about where it is and what it does: its angle, its
    /// readings (MONITOR), a new origin, the asynchronous hold, a stop. Some answer nothing.
    fn live_answer(&mut self, frame: &Frame, bus: &mut BusCtx<'_>) -> Option<Vec<u8>> {
        let c = frame.content.as_slice();
        let now = bus.now;
        let id = self.id();
        match (frame.command, c.len()) {
            (cmd::READ_ANGLE, 1) => {
                self.advance(now);
                let a = wrap(self.current_angle(now)).round() as i16;
                let mut out = vec![id];
                out.extend(a.to_le_bytes());
                Some(out)
            }
            (cmd::READ_ANGLE_MTURN, 1) => {
                self.advance(now);
                let (angle, turns) = mturn(self.current_angle(now));
                let mut out = vec![id];
                out.extend(angle.to_le_bytes());
                out.extend(turns.to_le_bytes());
                Some(out)
            }
            (cmd::MONITOR, 1) => Some(self.monitor(bus)),
            (cmd::RESET_MTURN, 1) => {
                self.advance(now);
                let a = self.current_angle(now);
                self.rebase(a - wrap(a));
                None
            }
            (cmd::SET_ORIGIN, 2) => {
                self.advance(now);
                let a = self.current_angle(now);
                self.rebase(a);
                None
            }
            (cmd::BEGIN_ASYNC, 0) => {
                self.holding = true;
                self.held = None;
                None
            }
            (cmd::END_ASYNC, 1) => {
                self.holding = false;
                if let (0, Some(m)) = (c[0], self.held.take()) {
                    let _ = self.command_motion(m, now);
                }
                self.held = None;
                None
            }
            (cmd::STOP, 4) if (0x10..=0x12).contains(&c[1]) => {
                let stop = MotionCmd::Stop {
                    mode: c[1],
                    power: u16_at(c, 2),
                };
                let _ = self.command_motion(stop, now);
                None
            }
            _ => None,
        }
    }

    /// The MONITOR answer: voltage, current, power, temperature (as the profile's field reads
    /// it), status, angle and turns.
    fn monitor(&mut self, bus: &mut BusCtx<'_>) -> Vec<u8> {
        let now = bus.now;
        self.advance(now);
        let live = self.live(now, bus.rng);
        let (angle, turns) = if self.monitor_no_data {
            (crate::ops::servo::monitor::NO_DATA_ANGLE, 0)
        } else {
            mturn(self.current_angle(now))
        };
        let mut out = vec![self.id()];
        out.extend(live.voltage.to_le_bytes());
        out.extend(live.current.to_le_bytes());
        out.extend(live.power.to_le_bytes());
        let field = bus
            .profile
            .command_by_id(cmd::MONITOR)
            .and_then(|m| m.reply.iter().find(|f| f.ident == "temperature"));
        out.extend((self.temperature_raw(field) as u16).to_le_bytes());
        out.push(self.status);
        out.extend(angle.to_le_bytes());
        out.extend(turns.to_le_bytes());
        out
    }
}

struct Live {
    voltage: u16,
    current: u16,
    power: u16,
}
