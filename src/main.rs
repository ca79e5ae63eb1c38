//! The `botbench` binary: the window with no arguments, the command line otherwise (see `botbench --help`).

use std::process::ExitCode;

fn main() -> ExitCode {
    botbench::cli::main()
}
