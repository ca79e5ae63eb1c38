//! The faults that break one window-cleaner self-test check each, by name.

use std::str::FromStr;

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
