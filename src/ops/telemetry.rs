//! Telemetry polling: which commands the worker polls, and how often. The worker sends each poll
//! and reports its answer as a `LinkEvent::Telemetry`.

use crate::link::{Poll, Request};
use crate::profile::{Command, CommandKind, Profile, Protocol};
use std::time::Duration;

/// The poll of `cmd` (empty request, one attempt: the next poll is the retry) every `interval`
/// (`None`: as fast as the wire allows).
pub fn poll(profile: &Profile, cmd: &Command, interval: Option<Duration>) -> Poll {
    Poll {
        request: Request::for_command(profile, cmd, Vec::new()).attempts(1),
        interval,
    }
}

/// The commands to poll so that every value is live: the profile's plotted commands at `rate`
/// polls a second (`None`: as fast as the wire allows), and its other telemetry at 1 Hz.
///
/// Only MSP devices are polled this way. Tuya: the module session sends the heartbeat itself and
/// the MCU reports its data points; polling 0x00/0x01/0x08 would take the restart heartbeat's 0
/// from the session. Servo commands name a servo: the servo bench polls the servo it works on
/// itself. MSP's core commands (identity, power state) are read once by the session, not polled.
pub fn polls(profile: &Profile, rate: Option<f64>) -> Vec<Poll> {
    if profile.protocol != Protocol::Msp {
        return Vec::new();
    }
    let mut plotted: Vec<u8> = Vec::new();
    for plot in &profile.plots {
        if let Some(cmd) = profile.command(&plot.command)
            && !plotted.contains(&cmd.id)
        {
            plotted.push(cmd.id);
        }
    }
    let plot_interval = rate.map(|r| Duration::from_secs_f64(1.0 / r.max(0.1)));
    let mut polls: Vec<Poll> = plotted
        .iter()
        .filter_map(|id| profile.command_by_id(*id))
        .map(|cmd| poll(profile, cmd, plot_interval))
        .collect();
    let others = profile.commands.iter().filter(|c| {
        c.kind == CommandKind::Telemetry
            && c.request.is_empty()
            && !c.reply.is_empty()
            && !plotted.contains(&c.id)
            && !profile.is_core(c)
    });
    polls.extend(others.map(|cmd| poll(profile, cmd, Some(Duration::from_secs(1)))));
    polls
}
