//! The `botbench` binary: the window with no arguments, the command line otherwise (see `botbench --help`).

use std::process::ExitCode;

fn main() -> ExitCode {
    // The ports a user names are the system's serial ports.
    botbench::cli::main(botbench::link::PortOpener::system())
}
