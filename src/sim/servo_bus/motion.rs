//! How a simulated servo moves: angle mode, wheel mode, damping, stops, the one-command queue
//! of the response switch, and the commands held between BEGIN_ASYNC and END_ASYNC.

use super::param;
use super::servo::SimServo;
use crate::protocol::servo::cmd;
use std::time::{Duration, Instant};

pub(super) fn later(start: Instant, d: Duration) -> Instant {
    start.checked_add(d).unwrap_or(start)
}

/// Wraps a multi-turn angle (0.1°) into one turn, (-180°, 180°].
pub(super) fn wrap(angle: f64) -> f64 {
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
pub(super) enum MotionCmd {
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

impl MotionCmd {
    /// The motion a request asks for (commands 7, 8, 9 and 11-15, by their seed and SDK
    /// layouts), or `None` for any other request. Acceleration and deceleration times are taken
    /// but not simulated: every move is linear.
    pub(super) fn from_request(command: u8, c: &[u8]) -> Option<Self> {
        let u16_at = |at: usize| {
            c.get(at..at + 2)
                .map_or(0, |b| u16::from_le_bytes([b[0], b[1]]))
        };
        let u32_at = |at: usize| {
            c.get(at..at + 4)
                .map_or(0, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        };
        let ms = |v: u32| Duration::from_millis(u64::from(v));
        let single = |timing| MotionCmd::Move {
            target: f64::from(u16_at(1) as i16),
            single_turn: true,
            timing,
        };
        let multi = |timing| MotionCmd::Move {
            target: f64::from(u32_at(1) as i32),
            single_turn: false,
            timing,
        };
        Some(match (command, c.len()) {
            (cmd::SPIN, 6) => {
                let method = c[1];
                let speed = f64::from(u16_at(2));
                let value = u16_at(4);
                let sign = if method & 0x80 != 0 { 1.0 } else { -1.0 };
                let rate = sign * speed * 10.0;
                match method & 0x03 {
                    0 => MotionCmd::SpinStop,
                    1 => MotionCmd::Spin { rate, limit: None },
                    2 => {
                        let secs = if speed > 0.0 {
                            f64::from(value) * 360.0 / speed
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
                        limit: Some(ms(u32::from(value))),
                    },
                }
            }
            (cmd::ROTATE, 7) | (cmd::ROTATE_BY_INTERVAL, 11) => {
                single(Timing::Interval(ms(u32::from(u16_at(3)))))
            }
            (cmd::ROTATE_BY_VELOCITY, 11) => single(Timing::Speed(f64::from(u16_at(3)))),
            (cmd::DAMPING, 3) => MotionCmd::Damping(u16_at(1)),
            (cmd::ROTATE_MTURN, 11) | (cmd::ROTATE_MTURN_BY_INTERVAL, 15) => {
                multi(Timing::Interval(ms(u32_at(5))))
            }
            (cmd::ROTATE_MTURN_BY_VELOCITY, 13) => multi(Timing::Speed(f64::from(u16_at(5)))),
            _ => return None,
        })
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Timing {
    Interval(Duration),
    /// 0.1° per second.
    Speed(f64),
}

impl SimServo {
    pub(super) fn current_angle(&self, now: Instant) -> f64 {
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

    pub(super) fn moving(&self, now: Instant) -> bool {
        self.motion_end().is_some_and(|end| end > now)
            || matches!(self.motion, Motion::Spin { limit: None, rate, .. } if rate != 0.0)
    }

    /// Settles motions that have ended by `now`, starting queued ones in turn.
    pub(super) fn advance(&mut self, now: Instant) {
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
    pub(super) fn command_motion(&mut self, c: MotionCmd, now: Instant) -> Option<Duration> {
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

    /// Subtracts `shift` (0.1°) from every angle the servo knows: a new origin.
    pub(super) fn rebase(&mut self, shift: f64) {
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
pub(super) fn mturn(angle: f64) -> (i32, i16) {
    let a = angle.round().clamp(i32::MIN as f64, i32::MAX as f64) as i32;
    let turns = (angle / 3600.0)
        .trunc()
        .clamp(i16::MIN as f64, i16::MAX as f64) as i16;
    (a, turns)
}
