//! What the robot may be doing because this window told it to: every command of the profile's
//! STOP (motor, fan, spray…) last sent with other values than the STOP's. Read from the frames
//! the worker reports, so that whatever sent them (the actions panel, a control, a self-test
//! job, the STOP button) is seen the same way; a STOP command acknowledged by the device ends
//! its entry.

use crate::link::LogEntry;
use crate::profile::{Profile, Value};
use crate::protocol::Direction;
use std::collections::BTreeMap;

/// One command that left something running.
#[derive(Debug, Clone, PartialEq)]
pub struct Running {
    /// The command's id.
    pub command: u8,
    /// Its request values (raw), by field ident, in wire order.
    pub values: Vec<(String, Value)>,
    /// The device acknowledged it (otherwise it was sent and not, or not yet, answered).
    pub acknowledged: bool,
    /// Sent before the link was lost: the robot may still be doing it.
    pub before_loss: bool,
}

/// What is running, by command id.
#[derive(Debug, Default)]
pub struct RunningSet {
    entries: BTreeMap<u8, Running>,
    /// STOP requests sent and not yet acknowledged, by command id.
    stopping: Vec<u8>,
}

impl RunningSet {
    /// The commands that left something running, in id order.
    pub fn iter(&self) -> impl Iterator<Item = &Running> {
        self.entries.values()
    }

    /// Whether nothing is running.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Takes a frame the worker reported: a request of a STOP command with other values than
    /// the STOP's starts an entry, its answer acknowledges it; the STOP's own values, once
    /// acknowledged, end it.
    pub fn on_frame(&mut self, profile: &Profile, entry: &LogEntry) {
        let Ok(p) = &entry.frame else { return };
        let Some(stop) = profile.stop_values(p.command) else {
            return;
        };
        match entry.direction {
            Direction::HostToDevice => {
                let Some(cmd) = profile.command_by_id(p.command) else {
                    return;
                };
                let Ok(d) = profile.decode(cmd, Direction::HostToDevice, &p.payload) else {
                    return;
                };
                let values: Vec<(String, Value)> =
                    d.values.into_iter().map(|v| (v.ident, v.value)).collect();
                if values == stop {
                    if !self.stopping.contains(&p.command) {
                        self.stopping.push(p.command);
                    }
                } else {
                    self.stopping.retain(|c| *c != p.command);
                    self.entries.insert(
                        p.command,
                        Running {
                            command: p.command,
                            values,
                            acknowledged: false,
                            before_loss: false,
                        },
                    );
                }
            }
            Direction::DeviceToHost => {
                if let Some(i) = self.stopping.iter().position(|c| *c == p.command) {
                    self.stopping.remove(i);
                    self.entries.remove(&p.command);
                } else if let Some(r) = self.entries.get_mut(&p.command) {
                    r.acknowledged = true;
                }
            }
        }
    }

    /// The link was lost: what was running may still run, and is shown so.
    pub fn on_link_lost(&mut self) {
        self.stopping.clear();
        for r in self.entries.values_mut() {
            r.before_loss = true;
        }
    }

    /// Forgets everything (another connection).
    pub fn clear(&mut self) {
        self.entries.clear();
        self.stopping.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::packet::Packet;
    use crate::profile::{Input, Registry};
    use crate::protocol::msp;

    fn frame(profile: &Profile, ident: &str, field: &str, text: &str) -> LogEntry {
        let cmd = profile.command(ident).unwrap();
        let inputs = [(field.to_string(), Input::Text(text.into()))];
        let payload = profile
            .encode(cmd, Direction::HostToDevice, &inputs)
            .unwrap();
        let request = msp::Request {
            option: 0xff,
            device: 3,
            command: cmd.id,
            data: payload,
        };
        LogEntry {
            at: std::time::SystemTime::now(),
            direction: Direction::HostToDevice,
            frame: Ok(Packet::msp_request(request)),
            note: None,
        }
    }

    fn ack(of: &LogEntry) -> LogEntry {
        let mut a = of.clone();
        a.direction = Direction::DeviceToHost;
        if let Ok(p) = &mut a.frame {
            p.payload.clear();
        }
        a
    }

    #[test]
    fn a_fan_started_runs_until_its_stop_is_acknowledged() {
        let p = Registry::load().unwrap().get("window-cleaner").unwrap();
        let mut r = RunningSet::default();
        let on = frame(&p, "MSP_SET_FAN", "pwm", "60");
        r.on_frame(&p, &on);
        let e = r.iter().next().unwrap();
        assert_eq!((e.command, e.acknowledged), (211, false));
        r.on_frame(&p, &ack(&on));
        assert!(r.iter().next().unwrap().acknowledged);
        // Voice is not part of STOP: not tracked.
        r.on_frame(&p, &frame(&p, "MSP_PLAY_VOICE", "index", "2"));
        assert_eq!(r.iter().count(), 1);
        // A STOP not answered leaves the fan shown as running.
        let off = frame(&p, "MSP_SET_FAN", "pwm", "0");
        r.on_frame(&p, &off);
        assert_eq!(r.iter().count(), 1);
        r.on_link_lost();
        assert!(r.iter().next().unwrap().before_loss);
        r.on_frame(&p, &off);
        r.on_frame(&p, &ack(&off));
        assert!(r.is_empty());
    }
}
