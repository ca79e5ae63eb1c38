//! `botbench sim <kind>`: serves a simulated device on a pseudo-terminal until killed.
//!
//! The first line of stdout is the pty's path, alone, so that a script can read it and open the
//! port: `port=$(botbench sim window-cleaner | head -1)`.

use super::{CliError, CliResult};
use crate::sim::{Faults, PtyServer, SimKind, SimOptions, build};
use clap::Args;
use std::io::Write;
use std::time::Duration;

#[derive(Debug, Args)]
pub(crate) struct SimArgs {
    /// window-cleaner, solar-cleanbot, servo-bus or tuya-vacuum.
    kind: String,
    /// The device's UART baud rate (default: its profile's). A client at another rate gets no
    /// answer.
    #[arg(long)]
    baud: Option<u32>,
    /// Probability (0-1) that a reply is lost.
    #[arg(long, default_value_t = 0.0)]
    drop: f64,
    /// Probability (0-1) that a reply has a bit flipped (it then fails its checksum).
    #[arg(long, default_value_t = 0.0)]
    corrupt: f64,
    /// Extra delay before each reply, in milliseconds.
    #[arg(long, default_value_t = 0)]
    latency_ms: u64,
    /// Seed of the fault dice and of the sensor noise.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Servo bus only: the servo IDs on the bus, e.g. `0,1,5`.
    #[arg(long, value_delimiter = ',')]
    servos: Vec<u8>,
}

pub(crate) fn run(args: SimArgs) -> CliResult {
    let kind: SimKind = args.kind.parse().map_err(CliError::input)?;
    let faults = Faults {
        drop: args.drop,
        corrupt: args.corrupt,
        extra_latency: Duration::from_millis(args.latency_ms),
        silent: false,
        seed: args.seed,
    };
    faults.check().map_err(CliError::input)?;
    if args.baud == Some(0) {
        return Err(CliError::input("baud rate 0"));
    }
    let opts = SimOptions {
        baud: args.baud,
        latency: None,
        seed: args.seed,
        servos: args.servos,
    };
    let device = build(kind, &opts).map_err(CliError::input)?;
    let server = PtyServer::start(device, faults).map_err(CliError::device)?;
    let mut out = std::io::stdout().lock();
    writeln!(out, "{}", server.path())
        .and_then(|()| out.flush())
        .map_err(|e| CliError::device(format!("cannot write to stdout: {e}")))?;
    drop(out);
    eprintln!(
        "botbench: serving a {} at {} baud on {}; stop with Ctrl-C",
        kind.describe(),
        opts.baud.unwrap_or_else(|| kind.default_baud()),
        server.path()
    );
    while server.is_running() {
        std::thread::sleep(Duration::from_millis(200));
    }
    Err(CliError::device(
        "the simulator stopped: the pseudo-terminal failed",
    ))
}
