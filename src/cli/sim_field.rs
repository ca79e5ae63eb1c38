//! `botbench sim` options that make a simulator misbehave as real adapters, buses, hosts and
//! firmware do (PROTOCOL_NOTES §4).

use super::CliError;
use crate::sim::msp_device::{AsyncFrame, MspQuirks};
use crate::sim::{Line, SimKind, Split};
use clap::Args;
use std::time::Duration;

/// The field's misbehaviours.
#[derive(Debug, Args)]
pub(crate) struct FieldArgs {
    /// A USB adapter's latency timer, in ms (FTDI: 16 by default): the host sees the bytes the
    /// device sent only at ticks of this period, in bursts: 1 to 255.
    #[arg(long, value_name = "MS", value_parser = clap::value_parser!(u64).range(1..=255))]
    latency_timer_ms: Option<u64>,
    /// Every reply longer than N bytes reaches the host in two bursts: N bytes, then the rest
    /// --split-gap-ms later (a latency tick inside the frame): 1 to 65535.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u16).range(1..))]
    split_after: Option<u16>,
    /// With --split-after: how much later the rest of a reply is seen, 0 to 10000 ms.
    #[arg(long, value_name = "MS", default_value_t = 16, value_parser = clap::value_parser!(u64).range(0..=10_000))]
    split_gap_ms: u64,
    /// A slow host: each frame is seen up to this many ms late (random, in order), 0 to 10000.
    #[arg(long, value_name = "MS", value_parser = clap::value_parser!(u64).range(0..=10_000))]
    host_delay_ms: Option<u64>,
    /// A one-wire bus (TX and RX tied): the host reads back every request it sends.
    #[arg(long)]
    echo: bool,
    /// The port vanishes (an adapter unplugged) once N bytes have come from the host; the
    /// simulator then exits: 1 to 4294967295.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=u64::from(u32::MAX)))]
    vanish_after_bytes: Option<u64>,
    /// MSP: before each reply, an unsolicited frame (kind 0xFE) of the same command with this
    /// payload (hex, e.g. `ee`).
    #[arg(long, value_name = "HEX")]
    async_before_reply: Option<String>,
    /// MSP: push an unsolicited frame (kind 0xFE) every MS ms, 1 to 60000; --async-frame says
    /// which.
    #[arg(long, value_name = "MS", value_parser = clap::value_parser!(u64).range(1..=60_000))]
    async_every_ms: Option<u64>,
    /// MSP: the frame --async-every-ms pushes, as COMMAND:HEX (default `130:ee`).
    #[arg(long, value_name = "COMMAND:HEX", default_value = "130:ee")]
    async_frame: String,
    /// MSP: replies to this command, 0 to 255, fail their checksum (repeat for several).
    #[arg(long, value_name = "COMMAND")]
    garble_command: Vec<u8>,
    /// MSP: answer CMD_VERSION with this hardware code (and take requests to it as the
    /// board's device code), 0 to 255 or 0x00 to 0xff: a board no profile claims.
    #[arg(long, value_name = "BYTE", value_parser = super::sim::parse_byte)]
    hardware_code: Option<u8>,
    /// Servo bus: every servo acknowledges a baud change and keeps talking at its old rate.
    #[arg(long)]
    ignore_baud_change: bool,
    /// Servo bus: every servo answers MONITOR with its "no data" form (angle -235929599,
    /// turns 0), as a servo with no reading to give does.
    #[arg(long)]
    monitor_no_data: bool,
}

fn hex(what: &str, text: &str) -> Result<Vec<u8>, CliError> {
    crate::protocol::hex::parse(text).map_err(|e| CliError::input(format!("{what} '{text}': {e}")))
}

impl FieldArgs {
    /// The line's misbehaviour for a simulator of `kind`: a servo bus is half-duplex.
    pub(crate) fn line(&self, kind: SimKind) -> Result<Line, CliError> {
        let line = Line {
            latency_timer: self.latency_timer_ms.map(Duration::from_millis),
            split: self.split_after.map(|after_bytes| Split {
                after_bytes: usize::from(after_bytes),
                gap: Duration::from_millis(self.split_gap_ms),
            }),
            host_delay: self.host_delay_ms.map(Duration::from_millis),
            echo: self.echo,
            half_duplex: kind == SimKind::ServoBus,
            vanish_after_bytes: self.vanish_after_bytes,
        };
        line.check().map_err(CliError::input)?;
        Ok(line)
    }

    /// The MSP board's misbehaviour; refused for a simulator that is not an MSP device.
    pub(crate) fn msp(&self, kind: SimKind) -> Result<MspQuirks, CliError> {
        let quirks = MspQuirks {
            async_before_reply: self
                .async_before_reply
                .as_deref()
                .map(|h| hex("--async-before-reply", h))
                .transpose()?,
            async_every: match self.async_every_ms {
                None => None,
                Some(0) => return Err(CliError::input("--async-every-ms 0: give 1 ms or more")),
                Some(ms) => Some((Duration::from_millis(ms), self.async_frame()?)),
            },
            garble: self.garble_command.clone(),
            hardware_code: self.hardware_code,
        };
        if quirks != MspQuirks::default()
            && kind.profile_protocol() != crate::profile::Protocol::Msp
        {
            return Err(CliError::input(format!(
                "--async-before-reply, --async-every-ms, --garble-command and --hardware-code are for MSP devices, not a {kind}"
            )));
        }
        Ok(quirks)
    }

    /// Whether servos ignore a baud change; refused for a simulator that is not a servo bus.
    pub(crate) fn ignore_baud_change(&self, kind: SimKind) -> Result<bool, CliError> {
        if self.ignore_baud_change && kind != SimKind::ServoBus {
            return Err(CliError::input(format!(
                "--ignore-baud-change is for the servo-bus simulator, not a {kind}"
            )));
        }
        Ok(self.ignore_baud_change)
    }

    /// Whether servos answer MONITOR with no data; refused for a simulator that is not a
    /// servo bus.
    pub(crate) fn monitor_no_data(&self, kind: SimKind) -> Result<bool, CliError> {
        if self.monitor_no_data && kind != SimKind::ServoBus {
            return Err(CliError::input(format!(
                "--monitor-no-data is for the servo-bus simulator, not a {kind}"
            )));
        }
        Ok(self.monitor_no_data)
    }

    fn async_frame(&self) -> Result<AsyncFrame, CliError> {
        let bad = || {
            CliError::input(format!(
                "--async-frame '{}': give COMMAND:HEX, e.g. 130:ee",
                self.async_frame
            ))
        };
        let (command, payload) = self.async_frame.split_once(':').ok_or_else(bad)?;
        Ok(AsyncFrame {
            command: command.trim().parse().map_err(|_| bad())?,
            payload: hex("--async-frame", payload)?,
        })
    }
}
