//! `botbench sim replay FILE`: serves the device recorded in a capture on a pseudo-terminal
//! (see [`crate::capture::replay`] for how requests are answered).
//!
//! As for the other simulators, the first line of stdout is the pty's path, alone.

use super::{CliError, CliResult};
use crate::capture::{ReplayDevice, read_path};
use crate::sim::{Faults, PtyServer, SharedDevice};
use std::sync::{Arc, Mutex};
use std::time::Duration;

pub(crate) fn serve(path: Option<&std::path::Path>) -> CliResult {
    let path = path.ok_or_else(|| CliError::input("sim replay needs a capture file"))?;
    let file = read_path(path).map_err(CliError::input)?;
    if let Some(t) = &file.truncated {
        eprintln!(
            "botbench: {} is cut off ({t}); replaying what came before",
            path.display()
        );
    }
    let device = ReplayDevice::new(&file).map_err(CliError::input)?;
    let requests = device.requests();
    let device: SharedDevice = Arc::new(Mutex::new(device));
    let server = PtyServer::start(device, Faults::default()).map_err(CliError::device)?;
    super::sim::print_path(server.path())?;
    eprintln!(
        "botbench: replaying {} ({}, profile {}, {} baud, {} chunks, {requests} distinct requests) on {}; stop with Ctrl-C",
        path.display(),
        file.info.application,
        if file.info.profile.is_empty() {
            "unknown"
        } else {
            &file.info.profile
        },
        file.info.baud,
        file.chunks.len(),
        server.path()
    );
    while server.is_running() {
        std::thread::sleep(Duration::from_millis(200));
    }
    Err(CliError::device(
        "the replay stopped: the pseudo-terminal failed",
    ))
}
