//! The window cleaner's physics and telemetry: battery drain, wheel and fan currents, pressure,
//! yaw and water that move with time and with the fan and motor, and the telemetry replies
//! read from them (with the faults that hold or skew a reading).

use super::{
    EMPTY_BATTERY, Fault, IDLE_FAN_ADC, IDLE_MOTOR_AMPS, IDLE_WHEEL_ADC, Motor, WindowCleaner,
};
use crate::sim::msp_device::{Answer, clamp_i};
use std::time::{Duration, Instant};

fn lag(x: &mut f64, target: f64, dt: f64, tau: f64) {
    *x += (target - *x) * (1.0 - (-dt / tau).exp());
}

impl WindowCleaner {
    /// Moves the physical state on to `now`.
    pub(super) fn advance(&mut self, now: Instant) {
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

    pub(super) fn telemetry(&mut self, command: u8, now: Instant) -> Answer {
        match command {
            102 | 104 | 106 | 108 | 120 => self.attitude(command, now),
            103 | 107 | 110 | 111 | 117 | 118 | 123 | 146 => self.power(command),
            _ => self.sensors(command, now),
        }
    }

    /// The gyro, the accelerometer, the attitude and the loop: what a noisy gyro disturbs.
    fn attitude(&mut self, command: u8, now: Instant) -> Answer {
        let t = now.saturating_duration_since(self.start).as_secs_f64();
        let gyro_noise = if self.has(Fault::GyroNoisy) { 400 } else { 3 };
        match command {
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
            104 => {
                let diff = self.noise(gyro_noise * 2);
                let period = 20 + self.noise(1);
                Answer::ints([("gyroDiff", diff), ("loopPeriod", period)])
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
            120 => {
                let period = 20 + self.noise(1);
                Answer::ints([("loopPeriod", period)])
            }
            _ => Answer::Nothing,
        }
    }

    /// The wheels, the fan, the motors and the battery: the ADCs and the power.
    fn power(&mut self, command: u8) -> Answer {
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
            103 => Answer::ints([
                ("value1", self.fan_adc.round() as i64),
                ("value2", (wheel[0] + wheel[1]) / 2),
                ("value3", (battery * 10.0).round() as i64),
            ]),
            107 => Answer::ints([
                ("wheelAdcAvg", (wheel[0] + wheel[1]) / 2),
                ("belowCnt", 0),
                ("aboveCnt", clamp_i(self.above_count, 0, 65535)),
                ("pressure", self.pressure.round() as i64),
            ]),
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
            117 => Answer::ints([("count", 0), ("diff", wheel[0] - wheel[1])]),
            118 => Answer::ints([("current", (wheel[0] + wheel[1]) / 2)]),
            123 => {
                let l = clamp_i(self.motor_amps[0] * 100.0, 0, 65535);
                let r = clamp_i(self.motor_amps[1] * 100.0, 0, 65535);
                Answer::ints([("left", l), ("right", r)])
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

    /// The power state, the edge sensors, the corners, the air pressure, the water box, the
    /// Wi-Fi test and the pressure target.
    fn sensors(&mut self, command: u8, now: Instant) -> Answer {
        match command {
            105 => {
                let v = [self.noise(4), self.pressure.round() as i64, self.noise(2)];
                Answer::ints([("value1", v[0]), ("value2", v[1]), ("value3", v[2])])
            }
            3 => Answer::bytes("powerState", vec![1]),
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
            121 => Answer::ints([("arg1", 1200), ("arg2", 800), ("arg3", 300), ("arg4", 50)]),
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
            _ => Answer::Nothing,
        }
    }
}
