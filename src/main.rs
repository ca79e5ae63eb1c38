use std::process::ExitCode;

fn main() -> ExitCode {
    botbench::cli::main()
}
