//! The window-cleaning robot: tunable parameters that SETs change and GETs read back, telemetry
//! that moves with time and with the fan and motor, actions, and faults that break one
//! self-test check each.
//!
//! A SET (220-226, 141, 147) or an action whose payload is short, too long, or holds a value
//! outside its field's range or labels is refused: nothing is stored or done, and no ack is sent
//! (the host sees a timeout, as with firmware that rejects a frame).
//!
//! Here: the parameter store, the commands and the device plumbing; [`physics`] moves the state
//! on and reads telemetry from it; [`fault`] names the self-test faults.

use super::msp_device::{self, Answer, MspCore, MspRobot, builtin_profile, reply_defaults};
use super::{Device, Outgoing, SimOptions};
use crate::profile::{CommandKind, Input, Value};
use crate::protocol::msp::Request;
use std::collections::BTreeSet;
use std::time::Instant;

mod fault;
mod physics;
#[cfg(test)]
mod tests;

pub use fault::Fault;

/// The window cleaner's device code (later revision).
pub const DEVICE_CODE: u8 = 0x03;

/// What the wheel motor is doing (MSP_SET_MOTOR).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Motor {
    /// 0.
    Stop,
    /// 1.
    Forward,
    /// 2.
    Reverse,
}

const IDLE_WHEEL_ADC: f64 = 18.0;
const IDLE_FAN_ADC: f64 = 35.0;
const IDLE_MOTOR_AMPS: f64 = 0.02;
const FULL_BATTERY: f64 = 14.8;
const EMPTY_BATTERY: f64 = 12.0;

/// One stored parameter: the Get it belongs to, its ident, its raw value.
#[derive(Debug, Clone)]
struct Param {
    get: u8,
    ident: String,
    raw: i64,
}

/// The simulated window cleaner.
#[derive(Debug)]
pub struct WindowCleaner {
    core: MspCore,
    params: Vec<Param>,
    rng: fastrand::Rng,
    start: Instant,
    last: Instant,
    faults: BTreeSet<Fault>,
    corners: u8,
    fan_pwm: u8,
    motor: Motor,
    spraying: bool,
    voice: Option<u8>,
    wifi_test: Option<Instant>,
    acc_offset: (i64, i64),
    battery: f64,
    wheel_adc: [f64; 2],
    motor_amps: [f64; 2],
    fan_adc: f64,
    pressure: f64,
    yaw: f64,
    water: f64,
    above_count: f64,
}

impl WindowCleaner {
    /// A window cleaner with the built-in profile, as it leaves the factory.
    pub fn new(opts: &SimOptions) -> Result<Self, String> {
        let profile = builtin_profile("window-cleaner")?;
        let core = MspCore::with_options(profile, DEVICE_CODE, opts);
        Ok(Self::with_core(core, opts.seed))
    }

    /// A window cleaner answering by `core`'s profile (e.g. a user's override of it).
    pub fn with_core(core: MspCore, seed: u64) -> Self {
        let mut params = Vec::new();
        for cmd in core
            .profile
            .commands
            .iter()
            .filter(|c| c.kind == CommandKind::Get)
        {
            for (ident, raw) in reply_defaults(cmd, 0) {
                let raw = match (raw, ident.as_str()) {
                    // Unpublished PID gains: plausible ones rather than zeros.
                    (0, "kp") => 1500,
                    (0, "ki") => 200,
                    (0, "kd") => 50,
                    _ => raw,
                };
                params.push(Param {
                    get: cmd.id,
                    ident,
                    raw,
                });
            }
        }
        let now = Instant::now();
        Self {
            core,
            params,
            rng: fastrand::Rng::with_seed(seed),
            start: now,
            last: now,
            faults: BTreeSet::new(),
            corners: 0,
            fan_pwm: 0,
            motor: Motor::Stop,
            spraying: false,
            voice: None,
            wifi_test: None,
            acc_offset: (37, -21),
            battery: FULL_BATTERY,
            wheel_adc: [IDLE_WHEEL_ADC; 2],
            motor_amps: [IDLE_MOTOR_AMPS; 2],
            fan_adc: IDLE_FAN_ADC,
            pressure: 0.0,
            yaw: 0.0,
            water: 1.0,
            above_count: 0.0,
        }
    }

    /// The MSP plumbing: identity (VERSION, BUILD_INFO), latency, baud, device code.
    pub fn core(&self) -> &MspCore {
        &self.core
    }

    /// The MSP plumbing, to change.
    pub fn core_mut(&mut self) -> &mut MspCore {
        &mut self.core
    }

    /// Sets the capability flags of CMD_VERSION's 8th byte; `None` answers 7 bytes.
    pub fn set_flags(&mut self, flags: Option<u8>) {
        self.core.identity.flags = flags;
    }

    /// A parameter's raw value by field ident (case-insensitive), e.g. `pwmValue`.
    pub fn param(&self, ident: &str) -> Option<i64> {
        self.params
            .iter()
            .find(|p| p.ident.eq_ignore_ascii_case(ident))
            .map(|p| p.raw)
    }

    /// Sets a parameter directly (as a previous session would have), checked against its field.
    pub fn set_param(&mut self, ident: &str, raw: i64) -> Result<(), String> {
        let p = self
            .params
            .iter()
            .position(|p| p.ident.eq_ignore_ascii_case(ident))
            .ok_or_else(|| format!("no parameter '{ident}'"))?;
        let get = self.params[p].get;
        let field = self
            .core
            .command(get)
            .and_then(|c| c.reply.iter().find(|f| f.ident.eq_ignore_ascii_case(ident)))
            .ok_or_else(|| format!("no field '{ident}'"))?;
        field.check(&Value::Int(raw)).map_err(|e| e.to_string())?;
        self.params[p].raw = raw;
        Ok(())
    }

    /// Sets the four corner switches (bit 0 = corner 1), as an operator covering them.
    pub fn set_corners(&mut self, bits: u8) {
        self.corners = bits & 0x0F;
    }

    /// Injects a fault.
    pub fn inject(&mut self, fault: Fault) {
        self.faults.insert(fault);
    }

    /// Injects a fault by name (see [`Fault::name`]).
    pub fn inject_named(&mut self, name: &str) -> Result<(), String> {
        self.inject(name.parse()?);
        Ok(())
    }

    /// Clears a fault.
    pub fn clear_fault(&mut self, fault: Fault) {
        self.faults.remove(&fault);
    }

    /// The faults in force.
    pub fn faults(&self) -> Vec<Fault> {
        self.faults.iter().copied().collect()
    }

    /// The fan PWM last set by MSP_SET_FAN (0-100).
    pub fn fan_pwm(&self) -> u8 {
        self.fan_pwm
    }

    /// What the motor is doing.
    pub fn motor(&self) -> Motor {
        self.motor
    }

    /// Whether the spray is on.
    pub fn spraying(&self) -> bool {
        self.spraying
    }

    /// The voice last played (MSP_PLAY_VOICE).
    pub fn last_voice(&self) -> Option<u8> {
        self.voice
    }

    /// Sets the battery voltage (volts), e.g. to test a low-battery warning.
    pub fn set_battery(&mut self, volts: f64) {
        if volts.is_finite() {
            self.battery = volts.clamp(0.0, 25.0);
        }
    }

    fn has(&self, f: Fault) -> bool {
        self.faults.contains(&f)
    }

    fn noise(&mut self, amplitude: i64) -> i64 {
        if amplitude <= 0 {
            0
        } else {
            self.rng.i64(-amplitude..=amplitude)
        }
    }

    /// Handles a SET or an action whose payload passed its fields' checks.
    fn act(&mut self, req: &Request, values: Vec<(String, i64)>, now: Instant) -> Answer {
        let first = values.first().map_or(0, |v| v.1);
        match req.command {
            116 => {
                self.wifi_test = Some(now);
                Answer::Ack
            }
            205 => {
                self.acc_offset = (0, 0);
                Answer::Ack
            }
            208 => {
                self.voice = u8::try_from(first).ok();
                Answer::Ack
            }
            209 => {
                self.spraying = first == 1;
                Answer::Ack
            }
            211 => {
                self.fan_pwm = u8::try_from(first).unwrap_or(0);
                Answer::Ack
            }
            214 => {
                self.motor = match first {
                    1 => Motor::Forward,
                    2 => Motor::Reverse,
                    _ => Motor::Stop,
                };
                Answer::Ack
            }
            215 | 216 => Answer::Fields(
                values
                    .into_iter()
                    .map(|(k, v)| (k, Input::Raw(Value::Int(v))))
                    .collect(),
            ),
            _ => Answer::Nothing,
        }
    }

    fn answer(&mut self, req: &Request, now: Instant) -> Answer {
        let Some(cmd) = self.core.command(req.command) else {
            return Answer::Nothing;
        };
        let (kind, pair) = (cmd.kind, cmd.pair);
        match kind {
            CommandKind::Get => {
                let get = req.command;
                Answer::Fields(
                    self.params
                        .iter()
                        .filter(|p| p.get == get)
                        .map(|p| (p.ident.clone(), Input::Raw(Value::Int(p.raw))))
                        .collect(),
                )
            }
            CommandKind::Telemetry => {
                if req.data.is_empty() {
                    self.telemetry(req.command, now)
                } else {
                    Answer::Nothing
                }
            }
            CommandKind::Set | CommandKind::Action => {
                let Some(values) = self.checked_values(req) else {
                    return Answer::Nothing;
                };
                if kind == CommandKind::Action {
                    return self.act(req, values, now);
                }
                let Some(get) = pair else {
                    return Answer::Nothing;
                };
                for (ident, raw) in values {
                    if let Some(p) = self
                        .params
                        .iter_mut()
                        .find(|p| p.get == get && p.ident == ident)
                    {
                        p.raw = raw;
                    }
                }
                Answer::Ack
            }
            // Raw commands (firmware transfer, power notify, leak detection) have no published
            // layout: this simulator does not implement them and stays silent.
            CommandKind::Raw => Answer::Nothing,
        }
    }

    /// The payload's integer values when it is exactly the command's layout and every value is
    /// allowed by its field.
    fn checked_values(&self, req: &Request) -> Option<Vec<(String, i64)>> {
        let decoded = self.core.decode_request(req)?;
        if !decoded.trailing.is_empty() {
            return None;
        }
        let mut out = Vec::new();
        for v in &decoded.values {
            v.field.check(&v.value).ok()?;
            let Value::Int(raw) = v.value else {
                return None;
            };
            out.push((v.ident.clone(), raw));
        }
        Some(out)
    }
}

impl MspRobot for WindowCleaner {
    fn msp_core(&mut self) -> &mut MspCore {
        &mut self.core
    }

    fn advance(&mut self, now: Instant) {
        WindowCleaner::advance(self, now);
    }

    fn answer(&mut self, req: &Request, now: Instant) -> Answer {
        WindowCleaner::answer(self, req, now)
    }
}

impl Device for WindowCleaner {
    fn receive(&mut self, bytes: &[u8], baud: u32, now: Instant) -> Vec<Outgoing> {
        msp_device::receive(self, bytes, baud, now)
    }

    fn tick(&mut self, now: Instant) -> Vec<Outgoing> {
        WindowCleaner::advance(self, now);
        self.core.pushes(now)
    }
}
