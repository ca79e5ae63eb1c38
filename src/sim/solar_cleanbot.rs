//! The solar-panel cleaning robot: drives along a panel at the speed CMD_SET_SPEED asks, turns
//! by what CMD_SET_ROTATE asks, and stores the settings of the other SET commands.
//!
//! Model (units are not published; these are the simulator's): speed in mm/s, distance in mm,
//! yaw in degrees (relative turns, at 30 °/s), pitch and roll in 0.1°. The panel is 20 m long;
//! the robot starts 2 m from its back edge and stops at either edge. The rangefinders read the
//! distance to the panel's front and back edges (mm, at most 4500). Actions whose payload is not
//! exactly their layout, or holds an unlabelled state, are refused without an ack.

use super::msp_device::{self, Answer, MspCore, MspRobot, builtin_profile, clamp_i};
use super::{Device, Outgoing, SimOptions};
use crate::profile::{CommandKind, CommandRole, Value};
use crate::protocol::msp::Request;
use std::time::Instant;

/// The solar cleanbot's device code (later revision; the seed's firmware used 0x03).
pub const DEVICE_CODE: u8 = 0x04;

const PANEL_MM: f64 = 20_000.0;
const RANGE_MAX_MM: f64 = 4_500.0;
const TURN_DEG_PER_S: f64 = 30.0;
const FULL_BATTERY: f64 = 25.2;
/// Encoder counts per mm (the raw wheel speeds).
const COUNTS_PER_MM: f64 = 10.0;

/// The cell geometry CMD_SET_CELL_INFO stores.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CellInfo {
    /// Short-side width.
    pub width: u16,
    /// 0 half cell, 1 full cell.
    pub cell_type: u8,
    /// 0 along the long side, 1 along the short side.
    pub run_dir: u8,
}

/// The simulated solar cleanbot.
#[derive(Debug)]
pub struct SolarCleanbot {
    core: MspCore,
    rng: fastrand::Rng,
    last: Instant,
    commanded: i16,
    speed: f64,
    position: f64,
    distance: f64,
    yaw: f64,
    yaw_target: f64,
    battery: f64,
    temperature: f64,
    heartbeat: i16,
    frame_rate: i16,
    cell: CellInfo,
    line_status: Vec<u8>,
    at_edge: bool,
}

fn lag(x: &mut f64, target: f64, dt: f64, tau: f64) {
    *x += (target - *x) * (1.0 - (-dt / tau).exp());
}

/// An angle in degrees folded into -180..180.
fn wrap(deg: f64) -> f64 {
    let d = (deg + 180.0).rem_euclid(360.0) - 180.0;
    if d.is_finite() { d } else { 0.0 }
}

impl SolarCleanbot {
    /// A solar cleanbot with the built-in profile, at rest.
    pub fn new(opts: &SimOptions) -> Result<Self, String> {
        let profile = builtin_profile("solar-cleanbot")?;
        let core = MspCore::with_options(profile, DEVICE_CODE, opts);
        Ok(Self::with_core(core, opts.seed))
    }

    /// A solar cleanbot answering by `core`'s profile.
    pub fn with_core(core: MspCore, seed: u64) -> Self {
        let heartbeat = core
            .profile
            .command_with_role(CommandRole::Heartbeat)
            .and_then(|c| c.request.first())
            .and_then(|f| f.default)
            .and_then(|d| i16::try_from(d).ok())
            .unwrap_or(1);
        Self {
            core,
            rng: fastrand::Rng::with_seed(seed),
            last: Instant::now(),
            commanded: 0,
            speed: 0.0,
            position: 2_000.0,
            distance: 0.0,
            yaw: 0.0,
            yaw_target: 0.0,
            battery: FULL_BATTERY,
            temperature: 28.0,
            heartbeat,
            frame_rate: 30,
            cell: CellInfo {
                width: 182,
                cell_type: 0,
                run_dir: 0,
            },
            line_status: vec![0; 9],
            at_edge: false,
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

    /// The speed last commanded (CMD_SET_SPEED).
    pub fn commanded_speed(&self) -> i16 {
        self.commanded
    }

    /// The actual speed, mm/s.
    pub fn speed(&self) -> f64 {
        self.speed
    }

    /// Distance travelled since start, mm (signed: reversing subtracts).
    pub fn distance(&self) -> f64 {
        self.distance
    }

    /// The yaw, degrees.
    pub fn yaw(&self) -> f64 {
        self.yaw
    }

    /// The battery voltage, volts.
    pub fn battery(&self) -> f64 {
        self.battery
    }

    /// Sets the battery voltage (volts), e.g. to test the warning and critical states.
    pub fn set_battery(&mut self, volts: f64) {
        if volts.is_finite() {
            self.battery = volts.clamp(0.0, 30.0);
        }
    }

    /// The heartbeat interval (CMD_SET_HEARTBEAT), seconds.
    pub fn heartbeat(&self) -> i16 {
        self.heartbeat
    }

    /// The vision frame rate (CMD_FRAMERATE).
    pub fn frame_rate(&self) -> i16 {
        self.frame_rate
    }

    /// The cell geometry (CMD_SET_CELL_INFO).
    pub fn cell_info(&self) -> CellInfo {
        self.cell
    }

    /// The grid-line payload last set (CMD_SET_LINE_STATUS), as CMD_GET_LINE_STATUS returns it.
    pub fn line_status(&self) -> &[u8] {
        &self.line_status
    }

    fn battery_state(&self) -> i64 {
        match self.battery {
            v if v < 5.0 => 3,
            v if v < 21.0 => 2,
            v if v < 22.2 => 1,
            _ => 0,
        }
    }

    fn noise(&mut self, amplitude: i64) -> i64 {
        self.rng.i64(-amplitude..=amplitude)
    }

    fn advance(&mut self, now: Instant) {
        if now <= self.last {
            return;
        }
        let dt = (now - self.last).as_secs_f64().min(10.0);
        self.last = now;
        lag(&mut self.speed, f64::from(self.commanded), dt, 0.3);
        let step = self.speed * dt;
        let next = (self.position + step).clamp(0.0, PANEL_MM);
        self.at_edge = next <= 0.0 || next >= PANEL_MM;
        if self.at_edge {
            self.speed = 0.0;
        }
        self.distance += next - self.position;
        self.position = next;
        let turn = wrap(self.yaw_target - self.yaw);
        let max = TURN_DEG_PER_S * dt;
        self.yaw = wrap(self.yaw + turn.clamp(-max, max));
        let load = self.speed.abs() / 500.0 + if turn.abs() > 0.5 { 0.5 } else { 0.0 };
        self.battery = (self.battery - (0.0005 + 0.004 * load) * dt).max(0.0);
        lag(&mut self.temperature, 28.0 + 25.0 * load.min(1.0), dt, 60.0);
    }

    fn turning(&self) -> bool {
        wrap(self.yaw_target - self.yaw).abs() > 0.5
    }

    fn telemetry(&mut self, command: u8) -> Answer {
        match command {
            3 => Answer::bytes("powerState", vec![1]),
            97 => {
                let front = (PANEL_MM - self.position).min(RANGE_MAX_MM);
                let back = self.position.min(RANGE_MAX_MM);
                let n = [self.noise(3), self.noise(3), self.noise(3), self.noise(3)];
                Answer::ints([
                    ("leftFront", clamp_i(front, 0, 65535) + n[0].abs()),
                    ("rightFront", clamp_i(front, 0, 65535) + n[1].abs()),
                    ("leftBack", clamp_i(back, 0, 65535) + n[2].abs()),
                    ("rightBack", clamp_i(back, 0, 65535) + n[3].abs()),
                    ("sampleRate", 20),
                ])
            }
            102 => {
                let turn_rate = if self.turning() { 300 } else { 0 };
                let mut bytes = Vec::with_capacity(12);
                let values = [
                    self.noise(3),
                    self.noise(3),
                    turn_rate + self.noise(3),
                    self.noise(6),
                    1060 + self.noise(6),
                    3955 + self.noise(6),
                ];
                for v in values {
                    bytes.extend_from_slice(
                        &(clamp_i(v as f64, -32768, 32767) as i16).to_le_bytes(),
                    );
                }
                Answer::bytes("data", bytes)
            }
            103 => Answer::bytes("data", self.line_status.clone()),
            104 => {
                let w = if self.turning() { 150.0 } else { 0.0 };
                let left = (self.speed + w) * COUNTS_PER_MM;
                let right = (self.speed - w) * COUNTS_PER_MM;
                let (lo, hi) = (i64::from(i32::MIN), i64::from(i32::MAX));
                Answer::ints([
                    ("leftRawSpeed", clamp_i(left, lo, hi)),
                    ("rightRawSpeed", clamp_i(right, lo, hi)),
                    ("averageSpeed", clamp_i(self.speed, -32768, 32767)),
                    ("moveDistance", clamp_i(self.distance, -32768, 32767)),
                ])
            }
            105 => {
                let width = f64::from(self.cell.width.max(1));
                let cells = clamp_i(self.distance.abs() / width, 0, 65535) as u16;
                Answer::bytes("data", cells.to_le_bytes().to_vec())
            }
            108 => {
                let yaw = clamp_i(self.yaw, -180, 180);
                let pitch = 150 + self.noise(2);
                let roll = self.noise(4);
                let merge = yaw + self.noise(1);
                Answer::ints([
                    ("yaw", yaw),
                    ("pitch", pitch),
                    ("roll", roll),
                    ("mergeYaw", merge),
                ])
            }
            // System tasks: 2 bytes of loop period (0.1 ms) and 1 byte of CPU load (%), a layout
            // of this simulator's own (none is published).
            109 => {
                let period = (20 + self.noise(1)) as u16;
                let mut bytes = period.to_le_bytes().to_vec();
                bytes.push((23 + self.noise(2)) as u8);
                Answer::bytes("data", bytes)
            }
            110 => {
                let thr = clamp_i(1500.0 + f64::from(self.commanded) / 2.0, 1000, 2000);
                Answer::ints([
                    ("thr", thr),
                    ("yaw", 1500),
                    ("arm", if self.commanded != 0 { 2000 } else { 1000 }),
                    ("mode", 1000),
                    ("sucker", 2000),
                    ("brush", if self.commanded != 0 { 2000 } else { 1000 }),
                    ("failsafe", 0),
                ])
            }
            130 => Answer::ints([
                ("voltage", clamp_i(self.battery * 100.0, 0, 65535)),
                ("state", self.battery_state()),
            ]),
            132 => Answer::ints([(
                "temperature",
                clamp_i(self.temperature / 10.0, -32768, 32767),
            )]),
            133 => {
                let mode = if self.turning() {
                    2
                } else if self.speed.abs() > 1.0 {
                    1
                } else {
                    0
                };
                Answer::ints([("moveMode", mode), ("pathState", i64::from(self.at_edge))])
            }
            _ => Answer::Nothing,
        }
    }

    fn act(&mut self, req: &Request) -> Answer {
        let Some(decoded) = self.core.decode_request(req) else {
            return Answer::Nothing;
        };
        if !decoded.trailing.is_empty() {
            return Answer::Nothing;
        }
        let mut values = Vec::new();
        for v in &decoded.values {
            if v.field.check(&v.value).is_err() {
                return Answer::Nothing;
            }
            let Value::Int(raw) = v.value else {
                return Answer::Nothing;
            };
            values.push(raw);
        }
        let first = values.first().copied().unwrap_or(0);
        let i16_of = |x: i64| i16::try_from(x).unwrap_or(0);
        // The heartbeat and the drive are where the profile's roles put them.
        let role = self.core.command(req.command).and_then(|c| c.role);
        match req.command {
            _ if role == Some(CommandRole::Heartbeat) => self.heartbeat = i16_of(first),
            _ if role == Some(CommandRole::Drive) => self.commanded = i16_of(first),
            99 => self.yaw_target = wrap(self.yaw_target + f64::from(i16_of(first))),
            101 => self.line_status = req.data.clone(),
            111 => self.frame_rate = i16_of(first),
            134 => {
                self.cell = CellInfo {
                    width: u16::try_from(first).unwrap_or(0),
                    cell_type: values
                        .get(1)
                        .and_then(|v| u8::try_from(*v).ok())
                        .unwrap_or(0),
                    run_dir: values
                        .get(2)
                        .and_then(|v| u8::try_from(*v).ok())
                        .unwrap_or(0),
                }
            }
            _ => return Answer::Nothing,
        }
        Answer::Ack
    }

    fn answer(&mut self, req: &Request) -> Answer {
        let Some(kind) = self.core.command(req.command).map(|c| c.kind) else {
            return Answer::Nothing;
        };
        match kind {
            CommandKind::Telemetry if req.data.is_empty() => self.telemetry(req.command),
            CommandKind::Action => self.act(req),
            // Firmware transfer and power notify have no published layout: not simulated.
            _ => Answer::Nothing,
        }
    }
}

impl MspRobot for SolarCleanbot {
    fn msp_core(&mut self) -> &mut MspCore {
        &mut self.core
    }

    fn advance(&mut self, now: Instant) {
        SolarCleanbot::advance(self, now);
    }

    fn answer(&mut self, req: &Request, _now: Instant) -> Answer {
        SolarCleanbot::answer(self, req)
    }
}

impl Device for SolarCleanbot {
    fn receive(&mut self, bytes: &[u8], baud: u32, now: Instant) -> Vec<Outgoing> {
        msp_device::receive(self, bytes, baud, now)
    }

    fn tick(&mut self, now: Instant) -> Vec<Outgoing> {
        SolarCleanbot::advance(self, now);
        self.core.pushes(now)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::msp::Reply;
    use std::time::Duration;

    fn ask(d: &mut SolarCleanbot, command: u8, data: Vec<u8>, now: Instant) -> Option<Reply> {
        msp_device::ask(d, DEVICE_CODE, command, data, now)
    }

    #[test]
    fn every_telemetry_command_answers_by_its_profile_layout() {
        let mut d = SolarCleanbot::new(&SimOptions::default()).unwrap();
        let now = Instant::now();
        let profile = d.core().profile.clone();
        for cmd in profile
            .commands
            .iter()
            .filter(|c| c.kind == CommandKind::Telemetry)
        {
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
    fn speed_moves_the_robot_and_rotate_turns_it_gradually() {
        let mut d = SolarCleanbot::new(&SimOptions::default()).unwrap();
        let t0 = Instant::now();
        assert!(ask(&mut d, 100, 300i16.to_le_bytes().to_vec(), t0).is_some());
        assert!(ask(&mut d, 99, 90i16.to_le_bytes().to_vec(), t0).is_some());
        d.tick(t0 + Duration::from_secs(1));
        assert!(d.yaw() > 20.0 && d.yaw() < 40.0, "{}", d.yaw());
        d.tick(t0 + Duration::from_secs(4));
        assert!((d.yaw() - 90.0).abs() < 1.0, "{}", d.yaw());
        assert!(d.distance() > 500.0, "{}", d.distance());
        assert!((d.speed() - 300.0).abs() < 5.0);
    }

    #[test]
    fn bad_labels_are_refused_and_battery_state_follows_voltage() {
        let mut d = SolarCleanbot::new(&SimOptions::default()).unwrap();
        let now = Instant::now();
        assert!(ask(&mut d, 134, vec![182, 0, 2, 0], now).is_none());
        assert!(ask(&mut d, 134, vec![166, 0, 1, 1], now).is_some());
        assert_eq!(d.cell_info().width, 166);
        d.set_battery(21.5);
        let b = ask(&mut d, 130, vec![], now).unwrap().data;
        assert_eq!(b, vec![0x66, 0x08, 1]);
    }
}
