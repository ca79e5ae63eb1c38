//! `botbench sim replay FILE`: serves the device recorded in a capture on a pseudo-terminal
//! (see [`crate::capture::replay`] for how requests are answered).
//!
//! As for the other simulators, the first line of stdout is the pty's path, alone.

use super::sim::Simulated;
use super::{CliError, CliResult};
use crate::capture::{ReplayDevice, read_path};
use crate::sim::{Faults, PtyServer, SharedDevice};
use std::sync::{Arc, Mutex};
use std::time::Duration;

pub(crate) fn serve(path: Option<&std::path::Path>) -> CliResult {
    let path = path.ok_or_else(|| CliError::input("sim replay needs a capture file"))?;
    let (device, said) = replay_device(path)?;
    let server = PtyServer::start(device, Faults::default()).map_err(CliError::device)?;
    super::sim::print_path(server.path())?;
    errln!(
        "botbench: replaying {said} on {}; stop with Ctrl-C",
        server.path()
    );
    while server.is_running() {
        std::thread::sleep(Duration::from_millis(200));
    }
    Err(CliError::device(
        "the replay stopped: the pseudo-terminal failed",
    ))
}

/// The device `sim replay FILE` serves, built in this process (see [`super::sim::simulated`]).
pub(crate) fn simulated(path: Option<&std::path::Path>) -> Result<Simulated, CliError> {
    let path = path.ok_or_else(|| CliError::input("sim replay needs a capture file"))?;
    let (device, _) = replay_device(path)?;
    let baud = read_path(path).map_err(CliError::input)?.info.baud;
    Ok(Simulated {
        kind: None,
        device,
        faults: Faults::default(),
        control: None,
        baud,
    })
}

/// The device recorded in the capture at `path`, and what it is, said (a capture cut off is
/// said on stderr).
fn replay_device(path: &std::path::Path) -> Result<(SharedDevice, String), CliError> {
    let file = read_path(path).map_err(CliError::input)?;
    if let Some(t) = &file.truncated {
        errln!(
            "botbench: {} is cut off ({t}); replaying what came before",
            path.display()
        );
    }
    let device = ReplayDevice::new(&file).map_err(CliError::input)?;
    let requests = device.requests();
    let said = format!(
        "{} ({}, profile {}, {} baud, {} chunks, {requests} distinct requests)",
        path.display(),
        file.info.application,
        if file.info.profile.is_empty() {
            "unknown"
        } else {
            &file.info.profile
        },
        file.info.baud,
        file.chunks.len(),
    );
    Ok((Arc::new(Mutex::new(device)), said))
}
