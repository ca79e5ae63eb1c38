//! The vacuum's own firmware, beyond the MCU SDK: its data points' starting values, the rules
//! that tie them together (power off stops cleaning, a cleaning mode powers the robot on, a
//! consumable reset refills its life), and the battery draining while it cleans.

use super::{TuyaMcu, dpid, status};
use crate::profile::{DataPointDef, Value};
use crate::protocol::tuya::dp::{DpType, DpValue};
use std::time::{Duration, Instant};

/// The value the vacuum starts with for a data point.
pub(super) fn initial_value(def: &DataPointDef) -> DpValue {
    let int = |v: i64| match def.dp_type {
        DpType::Bool => DpValue::Bool(v != 0),
        DpType::Value => DpValue::Value(v as i32),
        DpType::Enum => DpValue::Enum(v as u8),
        DpType::Bitmap => DpValue::Bitmap {
            bits: v as u32,
            width: def.field.ty.width().unwrap_or(1) as u8,
        },
        DpType::String => DpValue::String(v.to_string()),
        DpType::Raw => DpValue::Raw(Vec::new()),
    };
    match def.id {
        dpid::POWER => int(1),
        dpid::SUCTION => int(1),
        dpid::DIRECTION => int(4),
        dpid::BATTERY => int(80),
        dpid::EDGE_BRUSH_LIFE => int(90),
        dpid::ROLL_BRUSH_LIFE => int(85),
        dpid::FILTER_LIFE => int(70),
        // 35.0 m² (one decimal: raw 350).
        dpid::CLEAN_AREA => int(350),
        dpid::CLEAN_TIME => int(28),
        dpid::CLEAN_RECORD if def.dp_type == DpType::String => {
            DpValue::String("20180411051102008000020".into())
        }
        dpid::MAP_PARAMS if def.dp_type == DpType::Raw => DpValue::Raw(vec![0x00, 0x00, 0xFF]),
        _ => int(def.field.default.unwrap_or(0)),
    }
}

/// A data point's value as the profile's fields hold it.
pub(super) fn as_value(v: &DpValue) -> Value {
    match v {
        DpValue::Bool(b) => Value::Int(*b as i64),
        DpValue::Value(x) => Value::Int(*x as i64),
        DpValue::Enum(e) => Value::Int(*e as i64),
        DpValue::Bitmap { bits, .. } => Value::Int(*bits as i64),
        DpValue::String(s) => Value::Text(s.clone()),
        DpValue::Raw(b) => Value::Bytes(b.clone()),
    }
}

/// The status a work mode puts the robot in.
fn status_of_mode(mode: i64) -> u8 {
    match mode {
        0 => status::STANDBY,
        3 => status::WALL_CLEAN,
        4 => status::MOP_CLEAN,
        5..=7 => status::SPOT_CLEAN,
        11 => status::GOTO_CHARGE,
        _ => status::SMART_CLEAN,
    }
}

impl TuyaMcu {
    pub(super) fn int(&self, id: u8) -> i64 {
        match self.dps.get(&id).map(as_value) {
            Some(Value::Int(i)) => i,
            _ => 0,
        }
    }

    /// Sets an integer-like data point, keeping its type; returns whether it changed.
    pub(super) fn set_int(&mut self, id: u8, v: i64) -> bool {
        let Some(old) = self.dps.get(&id) else {
            return false;
        };
        let new = match old {
            DpValue::Bool(_) => DpValue::Bool(v != 0),
            DpValue::Value(_) => DpValue::Value(v as i32),
            DpValue::Enum(_) => DpValue::Enum(v as u8),
            DpValue::Bitmap { width, .. } => DpValue::Bitmap {
                bits: v as u32,
                width: *width,
            },
            _ => return false,
        };
        let changed = *old != new;
        self.dps.insert(id, new);
        changed
    }

    pub(super) fn cleaning(&self) -> bool {
        (1..=4).contains(&self.int(dpid::STATUS))
    }

    /// The firmware's rules after data point `id` was set, in the order a handler applies
    /// them. A rule leaves alone the data points in `commanded` (set by the same 0x06 frame),
    /// so that the robot never holds the opposite of what it was just told, unless the
    /// firmware is one whose rules override the command
    /// ([`super::TuyaConfig::rules_override_command`]). Each data point a rule changed is
    /// pushed to `changed`.
    pub(super) fn follow(&mut self, id: u8, commanded: &[u8], changed: &mut Vec<u8>) {
        let overrides = self.config.rules_override_command;
        let mut set = |s: &mut Self, id: u8, v: i64| {
            if (overrides || !commanded.contains(&id)) && s.set_int(id, v) {
                changed.push(id);
            }
        };
        let on = self.int(id) != 0;
        match id {
            dpid::POWER if !on => {
                set(self, dpid::CLEAN_SWITCH, 0);
                set(self, dpid::STATUS, status::STANDBY as i64);
                set(self, dpid::MODE, 0);
            }
            dpid::CLEAN_SWITCH if on => {
                set(self, dpid::POWER, 1);
                if self.int(dpid::MODE) == 0 {
                    set(self, dpid::MODE, 2);
                }
                set(self, dpid::STATUS, status::SMART_CLEAN as i64);
            }
            dpid::CLEAN_SWITCH => set(self, dpid::STATUS, status::STANDBY as i64),
            dpid::MODE => {
                let mode = self.int(dpid::MODE);
                let st = status_of_mode(mode);
                set(self, dpid::STATUS, st as i64);
                set(self, dpid::CLEAN_SWITCH, i64::from((1..=4).contains(&st)));
                if mode != 0 {
                    set(self, dpid::POWER, 1);
                }
            }
            dpid::EDGE_BRUSH_RESET if on => set(self, dpid::EDGE_BRUSH_LIFE, 100),
            dpid::ROLL_BRUSH_RESET if on => set(self, dpid::ROLL_BRUSH_LIFE, 100),
            dpid::FILTER_RESET if on => set(self, dpid::FILTER_LIFE, 100),
            _ => {}
        }
        // Whatever the order of a frame's data points, a robot powered off does not clean.
        if self.int(dpid::POWER) == 0 {
            set(self, dpid::CLEAN_SWITCH, 0);
            set(self, dpid::STATUS, status::STANDBY as i64);
        }
    }

    /// While cleaning, the battery drops 1 % every `battery_drain_every`: the report of the new
    /// level, when it dropped.
    pub(super) fn drain_battery(&mut self, now: Instant) -> Option<Vec<u8>> {
        if !self.cleaning() {
            self.last_drain = None;
            return None;
        }
        let every = self
            .config
            .battery_drain_every
            .max(Duration::from_millis(1));
        let last = *self.last_drain.get_or_insert(now);
        if now.saturating_duration_since(last) < every {
            return None;
        }
        self.last_drain = Some(last + every);
        let battery = self.int(dpid::BATTERY);
        // A little jitter in when the gauge ticks over, as a real one does.
        if self.rng.u8(0..10) == 0 || battery <= 0 {
            return None;
        }
        self.set_int(dpid::BATTERY, battery - 1);
        if self.config.sync_reports {
            self.own_report(dpid::BATTERY);
            return None;
        }
        self.report(dpid::BATTERY)
    }
}
