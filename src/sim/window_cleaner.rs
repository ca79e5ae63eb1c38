//! The window-cleaning robot: tunable parameters that SETs change and GETs read back, telemetry
//! that moves with time and with the fan and motor, actions, and faults that break one
//! self-test check each.
//!
//! A SET (220-226, 141, 147) or an action whose payload is short, too long, or holds a value
//! outside its field's range or labels is refused: nothing is stored or done, and no ack is sent
//! (the host sees a timeout, as with firmware that rejects a frame).

use super::msp_device::{
    self, Answer, MspCore, MspRobot, builtin_profile, clamp_i, reply_defaults,
};
use super::{Device, Outgoing, SimOptions};
use crate::profile::{CommandKind, Input, Value};
use crate::protocol::msp::Request;
use std::collections::BTreeSet;
use std::str::FromStr;
use std::time::{Duration, Instant};

/// The window cleaner's device code (later revision).
pub const DEVICE_CODE: u8 = 0x03;

/// A fault that breaks one self-test check.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Fault {
    /// The fan ADC stays at its idle value whatever the fan does.
    FanCurrentStuck,
    /// The wheel ADCs and motor currents stay at idle whatever the motor does.
    WheelCurrentStuck,
    /// The gyro reads ±400 counts of noise at rest (instead of ±3).
    GyroNoisy,
    /// The battery reads 10.8 V.
    BatteryLow,
    /// The water box reads absent.
    WaterBoxMissing,
    /// Corner switch 1 (bit 0) never reads pressed.
    CornerStuck,
}

impl Fault {
    /// Every fault.
    pub const ALL: [Fault; 6] = [
        Fault::FanCurrentStuck,
        Fault::WheelCurrentStuck,
        Fault::GyroNoisy,
        Fault::BatteryLow,
        Fault::WaterBoxMissing,
        Fault::CornerStuck,
    ];

    /// The name: `fan-current-stuck`, `wheel-current-stuck`, `gyro-noisy`, `battery-low`,
    /// `water-box-missing`, `corner-stuck`.
    pub fn name(self) -> &'static str {
        match self {
            Fault::FanCurrentStuck => "fan-current-stuck",
            Fault::WheelCurrentStuck => "wheel-current-stuck",
            Fault::GyroNoisy => "gyro-noisy",
            Fault::BatteryLow => "battery-low",
            Fault::WaterBoxMissing => "water-box-missing",
            Fault::CornerStuck => "corner-stuck",
        }
    }
}

impl FromStr for Fault {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let want = s.trim().replace('_', "-");
        Fault::ALL
            .into_iter()
            .find(|f| f.name().eq_ignore_ascii_case(&want))
            .ok_or_else(|| {
                let names: Vec<&str> = Fault::ALL.iter().map(|f| f.name()).collect();
                format!("unknown fault '{s}'; known: {}", names.join(", "))
            })
    }
}

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

fn lag(x: &mut f64, target: f64, dt: f64, tau: f64) {
    *x += (target - *x) * (1.0 - (-dt / tau).exp());
}

impl WindowCleaner {
    /// A window cleaner with the built-in profile, as it leaves the factory.
    pub fn new(opts: &SimOptions) -> Result<Self, String> {
        let profile = builtin_profile("window-cleaner")?;
        let baud = opts.baud.unwrap_or(profile.baud);
        let mut core = MspCore::new(profile, DEVICE_CODE, baud);
        if let Some(l) = opts.latency {
            core.latency = l;
        }
        core.quirks = opts.msp.clone();
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

    /// Moves the physical state on to `now`.
    fn advance(&mut self, now: Instant) {
        if now <= self.last {
            return;
        }
        let dt = (now - self.last).as_secs_f64().min(10.0);
        self.last = now;
        let fan = f64::from(self.fan_pwm) / 100.0;
        let running = self.motor != Motor::Stop;
        let drain = 0.0005 + 0.004 * fan + if running { 0.002 } else { 0.0 };
        self.battery = (self.battery - drain * dt).max(EMPTY_BATTERY);
        let (wheel, amps) = match self.motor {
            Motor::Stop => (IDLE_WHEEL_ADC, IDLE_MOTOR_AMPS),
            Motor::Forward => (620.0, 0.45),
            Motor::Reverse => (660.0, 0.48),
        };
        let (wheel, amps) = if self.has(Fault::WheelCurrentStuck) {
            (IDLE_WHEEL_ADC, IDLE_MOTOR_AMPS)
        } else {
            (wheel, amps)
        };
        for (i, trim) in [1.0, 0.96].into_iter().enumerate() {
            lag(&mut self.wheel_adc[i], wheel * trim, dt, 0.25);
            lag(&mut self.motor_amps[i], amps * trim, dt, 0.25);
        }
        let fan_target = if self.has(Fault::FanCurrentStuck) {
            IDLE_FAN_ADC
        } else {
            IDLE_FAN_ADC + fan * 2200.0
        };
        lag(&mut self.fan_adc, fan_target, dt, 0.4);
        let target = self.param("defaultTarget").unwrap_or(275) as f64;
        lag(&mut self.pressure, fan * target * 1.05, dt, 0.6);
        self.yaw += dt * if running { 12.0 } else { 1.5 };
        if self.yaw > 1800.0 {
            self.yaw -= 3600.0;
        }
        if self.spraying {
            self.water = (self.water - 0.01 * dt).max(0.0);
        }
        if running && self.wheel_adc[0] > 300.0 {
            self.above_count += dt * 100.0;
        }
    }

    fn telemetry(&mut self, command: u8, now: Instant) -> Answer {
        let t = now.saturating_duration_since(self.start).as_secs_f64();
        let gyro_noise = if self.has(Fault::GyroNoisy) { 400 } else { 3 };
        let wheel = [
            self.wheel_adc[0].round() as i64,
            self.wheel_adc[1].round() as i64,
        ];
        let battery = if self.has(Fault::BatteryLow) {
            10.8
        } else {
            self.battery
        };
        match command {
            3 => Answer::bytes("powerState", vec![1]),
            102 => {
                let turning = if self.motor == Motor::Stop { 0 } else { 120 };
                let a = [
                    ("gyroX", self.noise(gyro_noise)),
                    ("gyroY", self.noise(gyro_noise)),
                    ("gyroZ", turning + self.noise(gyro_noise)),
                    ("accX", self.acc_offset.0 + self.noise(6)),
                    ("accY", self.acc_offset.1 + self.noise(6)),
                    ("accZ", 4096 + self.noise(8)),
                ];
                Answer::ints(a)
            }
            103 => Answer::ints([
                ("value1", self.fan_adc.round() as i64),
                ("value2", (wheel[0] + wheel[1]) / 2),
                ("value3", (battery * 10.0).round() as i64),
            ]),
            104 => {
                let diff = self.noise(gyro_noise * 2);
                let period = 20 + self.noise(1);
                Answer::ints([("gyroDiff", diff), ("loopPeriod", period)])
            }
            105 => {
                let v = [self.noise(4), self.pressure.round() as i64, self.noise(2)];
                Answer::ints([("value1", v[0]), ("value2", v[1]), ("value3", v[2])])
            }
            106 => {
                let a = [
                    ("state", 1),
                    ("accXAvg", self.acc_offset.0.abs() + self.noise(2).abs()),
                    ("accYAvg", self.acc_offset.1.abs() + self.noise(2).abs()),
                    ("accZAvg", 4096 + self.noise(3)),
                ];
                Answer::ints(a)
            }
            107 => Answer::ints([
                ("wheelAdcAvg", (wheel[0] + wheel[1]) / 2),
                ("belowCnt", 0),
                ("aboveCnt", clamp_i(self.above_count, 0, 65535)),
                ("pressure", self.pressure.round() as i64),
            ]),
            108 => {
                let jitter = if self.has(Fault::GyroNoisy) { 60 } else { 2 };
                let x = 150.0 * (t * std::f64::consts::TAU / 4.0).sin();
                let y = 80.0 * (t * std::f64::consts::TAU / 7.0).sin() + 0.3 * t;
                let a = [
                    ("eulerX", clamp_i(x, -1800, 1800) + self.noise(jitter)),
                    ("eulerY", clamp_i(y, -1800, 1800) + self.noise(jitter)),
                    ("eulerZ", clamp_i(self.yaw, -1800, 1800)),
                ];
                Answer::ints(a)
            }
            110 => {
                let fan = self.fan_adc.round() as i64 + self.noise(3);
                let a = [
                    ("adcLeftWheel", (wheel[0] + self.noise(2)).max(0)),
                    ("adcRightWheel", (wheel[1] + self.noise(2)).max(0)),
                    ("adcFan", fan.max(0)),
                ];
                Answer::ints(a)
            }
            111 => Answer::ints([
                ("adapterVoltage", 240),
                ("batteryVoltage", clamp_i(battery * 10.0, 0, 65535)),
            ]),
            112 => {
                let mut bits = self.corners;
                if self.has(Fault::CornerStuck) {
                    bits &= !1;
                }
                Answer::ints([("corners", i64::from(bits))])
            }
            113 => {
                let reference = 101_325;
                let diff = -clamp_i(self.pressure * 4.0, 0, 32767) + self.noise(2);
                Answer::ints([
                    ("diff", diff),
                    ("live", reference + diff),
                    ("reference", reference),
                ])
            }
            114 => {
                let present = !self.has(Fault::WaterBoxMissing);
                let adc = if present {
                    clamp_i(600.0 + 2400.0 * self.water, 0, 65535) + self.noise(5)
                } else {
                    40 + self.noise(5)
                };
                Answer::ints([
                    ("status", i64::from(present)),
                    ("adc", adc.max(0)),
                    ("filteredStatus", i64::from(present)),
                ])
            }
            115 => {
                let rssi = match self.wifi_test {
                    Some(at) if now.saturating_duration_since(at) >= Duration::from_millis(500) => {
                        72 + self.noise(3)
                    }
                    _ => 0,
                };
                Answer::ints([("rssi", rssi)])
            }
            117 => Answer::ints([("count", 0), ("diff", wheel[0] - wheel[1])]),
            118 => Answer::ints([("current", (wheel[0] + wheel[1]) / 2)]),
            120 => {
                let period = 20 + self.noise(1);
                Answer::ints([("loopPeriod", period)])
            }
            121 => Answer::ints([("arg1", 1200), ("arg2", 800), ("arg3", 300), ("arg4", 50)]),
            123 => {
                let l = clamp_i(self.motor_amps[0] * 100.0, 0, 65535);
                let r = clamp_i(self.motor_amps[1] * 100.0, 0, 65535);
                Answer::ints([("left", l), ("right", r)])
            }
            142 => {
                let target = if self.fan_pwm > 0 {
                    self.param("defaultTarget").unwrap_or(275)
                } else {
                    0
                };
                Answer::ints([
                    ("target", target),
                    ("live", clamp_i(self.pressure, 0, i64::from(u32::MAX))),
                ])
            }
            146 => Answer::ints([
                ("state", 0),
                ("voltage", clamp_i(battery * 10.0, 0, 255)),
                ("current", 0),
                ("cells", 4),
            ]),
            _ => Answer::Nothing,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::msp::Reply;

    fn ask(d: &mut WindowCleaner, command: u8, data: Vec<u8>, now: Instant) -> Option<Reply> {
        msp_device::ask(d, DEVICE_CODE, command, data, now)
    }

    #[test]
    fn every_telemetry_and_get_command_answers_by_its_profile_layout() {
        let mut d = WindowCleaner::new(&SimOptions::default()).unwrap();
        let now = Instant::now();
        let profile = d.core().profile.clone();
        for cmd in &profile.commands {
            if !matches!(cmd.kind, CommandKind::Get | CommandKind::Telemetry) {
                continue;
            }
            let r = ask(&mut d, cmd.id, vec![], now);
            let r = r.unwrap_or_else(|| panic!("{} did not answer", cmd.ident));
            let decoded = profile
                .decode(cmd, crate::protocol::Direction::DeviceToHost, &r.data)
                .unwrap();
            assert!(decoded.trailing.is_empty(), "{}", cmd.ident);
        }
        assert_eq!(d.core().last_error, None);
    }

    #[test]
    fn out_of_range_set_is_refused_silently() {
        let mut d = WindowCleaner::new(&SimOptions::default()).unwrap();
        let now = Instant::now();
        assert!(ask(&mut d, 220, vec![101], now).is_none());
        assert_eq!(d.param("pwmValue"), Some(85));
        assert!(ask(&mut d, 220, vec![60, 1], now).is_none());
        let ack = ask(&mut d, 220, vec![60], now).unwrap();
        assert!(ack.data.is_empty());
        assert_eq!(d.param("pwmvalue"), Some(60));
        assert_eq!(ask(&mut d, 130, vec![], now).unwrap().data, vec![60]);
    }

    #[test]
    fn fan_and_motor_move_the_adcs_and_faults_hold_them() {
        let mut d = WindowCleaner::new(&SimOptions::default()).unwrap();
        let t0 = Instant::now();
        assert!(ask(&mut d, 211, vec![80], t0).is_some());
        assert!(ask(&mut d, 214, vec![1], t0).is_some());
        assert!(
            ask(&mut d, 214, vec![3], t0).is_none(),
            "3 is not a motor label"
        );
        let later = t0 + Duration::from_secs(2);
        let a = ask(&mut d, 110, vec![], later).unwrap().data;
        let left = u16::from_le_bytes([a[0], a[1]]);
        let fan = u16::from_le_bytes([a[4], a[5]]);
        assert!(left > 400, "{left}");
        assert!(fan > 1500, "{fan}");

        let mut f = WindowCleaner::new(&SimOptions::default()).unwrap();
        f.inject_named("fan-current-stuck").unwrap();
        f.inject(Fault::WheelCurrentStuck);
        assert!(ask(&mut f, 211, vec![80], t0).is_some());
        assert!(ask(&mut f, 214, vec![1], t0).is_some());
        let a = ask(&mut f, 110, vec![], later).unwrap().data;
        assert!(u16::from_le_bytes([a[0], a[1]]) < 50);
        assert!(u16::from_le_bytes([a[4], a[5]]) < 50);
        assert!("fan".parse::<Fault>().is_err());
    }

    #[test]
    fn corners_triggers_and_version_flags() {
        let mut d = WindowCleaner::new(&SimOptions::default()).unwrap();
        let now = Instant::now();
        d.set_corners(0b1011);
        assert_eq!(ask(&mut d, 112, vec![], now).unwrap().data, vec![0b1011]);
        d.inject(Fault::CornerStuck);
        assert_eq!(ask(&mut d, 112, vec![], now).unwrap().data, vec![0b1010]);
        let echo = ask(&mut d, 216, vec![1, 0, 2, 0, 3, 0, 0xFF, 0xFF], now).unwrap();
        assert_eq!(echo.data, vec![1, 0, 2, 0, 3, 0, 0xFF, 0xFF]);
        d.set_flags(None);
        assert_eq!(ask(&mut d, 2, vec![], now).unwrap().data.len(), 7);
    }
}
