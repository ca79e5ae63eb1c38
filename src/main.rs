//! The `botbench` binary: the window with no arguments, the command line otherwise (see `botbench --help`).

use std::process::ExitCode;

fn main() -> ExitCode {
    // `RUST_LOG=botbench=debug` shows the link's decisions (late answers, margin changes,
    // reconnects, fences, dropped events) on stderr, for the command line and the window alike;
    // without RUST_LOG nothing is logged.
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("off")).init();
    // The ports a user names are the system's serial ports.
    botbench::cli::main(botbench::link::PortOpener::system())
}
