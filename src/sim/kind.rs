//! Simulators by kind: the names `botbench sim` takes, and one constructor for all of them.

use super::runner::SharedDevice;
use super::servo_bus::ServoBus;
use super::solar_cleanbot::SolarCleanbot;
use super::tuya_mcu::{TuyaConfig, TuyaMcu};
use super::window_cleaner::WindowCleaner;
use std::str::FromStr;
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// The simulated devices.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SimKind {
    /// The MSP window-cleaning robot.
    WindowCleaner,
    /// The MSP solar-panel cleaning robot.
    SolarCleanbot,
    /// A bus of UART servos.
    ServoBus,
    /// The Tuya robot-vacuum MCU.
    TuyaVacuum,
}

impl SimKind {
    /// Every kind as a station bundle names it, with the id of the profile it speaks:
    /// `("window-cleaner", "window-cleaner")`, `("servo-bus", "servo")`, … in [`SimKind::ALL`]'s
    /// order (what `ops::station::LoadContext::simulated` takes).
    pub fn names_with_profiles() -> Vec<(&'static str, &'static str)> {
        SimKind::ALL
            .iter()
            .map(|k| (k.name(), k.profile_id()))
            .collect()
    }

    /// Every kind, in the order help lists them.
    pub const ALL: [SimKind; 4] = [
        SimKind::WindowCleaner,
        SimKind::SolarCleanbot,
        SimKind::ServoBus,
        SimKind::TuyaVacuum,
    ];

    /// The command-line name: `window-cleaner`, `solar-cleanbot`, `servo-bus`, `tuya-vacuum`.
    pub fn name(self) -> &'static str {
        match self {
            SimKind::WindowCleaner => "window-cleaner",
            SimKind::SolarCleanbot => "solar-cleanbot",
            SimKind::ServoBus => "servo-bus",
            SimKind::TuyaVacuum => "tuya-vacuum",
        }
    }

    /// The id of the device profile it answers by.
    pub fn profile_id(self) -> &'static str {
        match self {
            SimKind::WindowCleaner => "window-cleaner",
            SimKind::SolarCleanbot => "solar-cleanbot",
            SimKind::ServoBus => "servo",
            SimKind::TuyaVacuum => "tuya-vacuum",
        }
    }

    /// The protocol it speaks.
    pub fn profile_protocol(self) -> crate::profile::Protocol {
        use crate::profile::Protocol;
        match self {
            SimKind::WindowCleaner | SimKind::SolarCleanbot => Protocol::Msp,
            SimKind::ServoBus => Protocol::Servo,
            SimKind::TuyaVacuum => Protocol::Tuya,
        }
    }

    /// What a transport to it calls itself: `simulated window cleaner`.
    pub fn describe(self) -> &'static str {
        match self {
            SimKind::WindowCleaner => "simulated window cleaner",
            SimKind::SolarCleanbot => "simulated solar cleanbot",
            SimKind::ServoBus => "simulated servo bus",
            SimKind::TuyaVacuum => "simulated Tuya vacuum",
        }
    }

    /// [`Self::describe`] in both languages, for the window.
    pub fn described(self) -> crate::i18n::Text {
        let zh = match self {
            SimKind::WindowCleaner => "模拟擦窗机器人",
            SimKind::SolarCleanbot => "模拟光伏清扫机器人",
            SimKind::ServoBus => "模拟舵机总线",
            SimKind::TuyaVacuum => "模拟涂鸦扫地机",
        };
        crate::i18n::Text::new(self.describe(), zh)
    }

    /// The baud rate it runs at unless told otherwise (its profile's).
    pub fn default_baud(self) -> u32 {
        super::msp_device::builtin_profile(self.profile_id())
            .map(|p| p.baud)
            .unwrap_or(115_200)
    }
}

impl std::fmt::Display for SimKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for SimKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        SimKind::ALL
            .into_iter()
            .find(|k| k.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| {
                let names: Vec<&str> = SimKind::ALL.iter().map(|k| k.name()).collect();
                format!("unknown simulator '{s}'; known: {}", names.join(", "))
            })
    }
}

/// How to build a simulator. `Default` is the device as it leaves the factory.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SimOptions {
    /// The baud rate of the device's UART; `None` is its profile's.
    pub baud: Option<u32>,
    /// How long after a request's last byte the device starts answering; `None` is the device's
    /// default (100 µs for MSP).
    pub latency: Option<Duration>,
    /// Seed of the device's sensor noise.
    pub seed: u64,
    /// Servo bus only: the IDs of the servos on the bus (empty = the simulator's default).
    pub servos: Vec<u8>,
    /// MSP devices: how the board misbehaves (unsolicited frames, garbled replies).
    pub msp: super::msp_device::MspQuirks,
    /// Servo bus only: every servo acknowledges a baud change and keeps its old rate.
    pub ignore_baud_change: bool,
    /// Servo bus only: every servo answers MONITOR with the "no data" form.
    pub monitor_no_data: bool,
}

/// The Tuya vacuum MCU with these options.
pub fn tuya_mcu(opts: &SimOptions) -> TuyaMcu {
    let mut cfg = TuyaConfig {
        seed: opts.seed,
        ..TuyaConfig::default()
    };
    if let Some(l) = opts.latency {
        cfg.latency = l;
    }
    if let Some(b) = opts.baud {
        cfg.baud = Some(b);
    }
    TuyaMcu::new(cfg)
}

/// Builds a simulator of `kind`.
pub fn build(kind: SimKind, opts: &SimOptions) -> Result<SharedDevice, String> {
    Ok(match kind {
        SimKind::WindowCleaner => Arc::new(Mutex::new(WindowCleaner::new(opts)?)),
        SimKind::SolarCleanbot => Arc::new(Mutex::new(SolarCleanbot::new(opts)?)),
        SimKind::ServoBus => {
            let ids: &[u8] = if opts.servos.is_empty() {
                &[1]
            } else {
                &opts.servos
            };
            let baud = opts.baud.unwrap_or(kind.default_baud());
            let mut bus =
                ServoBus::with_profile_ids(super::servo_bus::builtin_servo_profile(), ids, baud)?
                    .with_seed(opts.seed)
                    .with_baud_change_ignored(opts.ignore_baud_change)
                    .with_monitor_no_data(opts.monitor_no_data);
            if let Some(l) = opts.latency {
                bus = bus.with_latency(l);
            }
            Arc::new(Mutex::new(bus))
        }
        SimKind::TuyaVacuum => Arc::new(Mutex::new(tuya_mcu(opts))),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_unknown_names_list_the_known() {
        for k in SimKind::ALL {
            assert_eq!(k.name().parse::<SimKind>(), Ok(k));
        }
        let err = "toaster".parse::<SimKind>().unwrap_err();
        assert!(
            err.contains("window-cleaner") && err.contains("tuya-vacuum"),
            "{err}"
        );
    }

    #[test]
    fn builds_the_msp_kinds() {
        assert!(build(SimKind::WindowCleaner, &SimOptions::default()).is_ok());
        assert!(build(SimKind::SolarCleanbot, &SimOptions::default()).is_ok());
        assert_eq!(SimKind::WindowCleaner.default_baud(), 115_200);
    }
}
