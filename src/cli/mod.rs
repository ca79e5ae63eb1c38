//! The command line: the same library behind a CLI, for production-line scripts and tests.
//!
//! Exit codes: 0 success; 1 the device (or the data) failed, disagreed or did not answer;
//! 2 bad input (usage, out-of-range value, malformed file).

mod frame;
mod msp;
mod port;
mod preset;
mod servo;
mod sim;
mod tuya;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// What went wrong, and the exit code it earns.
#[derive(Debug)]
pub struct CliError {
    /// 1 device failure, 2 bad input.
    pub code: u8,
    /// The message for stderr.
    pub message: String,
}

impl CliError {
    /// Bad input: exit code 2.
    pub fn input(message: impl std::fmt::Display) -> Self {
        Self {
            code: 2,
            message: message.to_string(),
        }
    }

    /// The device failed or disagreed: exit code 1.
    pub fn device(message: impl std::fmt::Display) -> Self {
        Self {
            code: 1,
            message: message.to_string(),
        }
    }
}

/// Result of a subcommand: the exit code on success (0, or 1 when the data held errors).
pub type CliResult = Result<u8, CliError>;

/// botbench: tune, provision and test serial-connected robots.
#[derive(Debug, Parser)]
#[command(name = "botbench", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    command: Option<Cmd>,
}

#[derive(Debug, Subcommand)]
enum Cmd {
    /// Decode or build frames of the three protocols.
    #[command(subcommand)]
    Frame(frame::FrameCmd),
    /// Serve a simulated device on a pseudo-terminal; prints its path, then serves until killed.
    Sim(sim::SimArgs),
    /// List the device profiles and where each comes from.
    Profiles {
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// List the serial ports (USB VID:PID, serial number and product where known).
    Ports {
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// Window cleaner and solar cleanbot (MSP).
    Msp(msp::MspArgs),
    /// UART bus servos.
    Servo(servo::ServoArgs),
    /// Tuya MCU, with botbench as the Wi-Fi module.
    Tuya(tuya::TuyaArgs),
    /// Save, compare and apply presets of a device's tunable parameters.
    #[command(subcommand)]
    Preset(preset::PresetCmd),
}

/// Runs the command line with the process's arguments.
pub fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let _ = e.print();
            return ExitCode::from(if e.use_stderr() { 2 } else { 0 });
        }
    };
    match run(cli) {
        Ok(code) => ExitCode::from(code),
        Err(e) => {
            eprintln!("botbench: {}", e.message);
            ExitCode::from(e.code)
        }
    }
}

fn run(cli: Cli) -> CliResult {
    match cli.command {
        Some(Cmd::Frame(cmd)) => frame::run(cmd),
        Some(Cmd::Profiles { json }) => profiles(json),
        Some(Cmd::Ports { json }) => ports(json),
        Some(Cmd::Msp(args)) => msp::run(args),
        Some(Cmd::Servo(args)) => servo::run(args),
        Some(Cmd::Tuya(args)) => tuya::run(args),
        Some(Cmd::Preset(cmd)) => preset::run(cmd),
        Some(Cmd::Sim(args)) => sim::run(args),
        None => {
            use clap::CommandFactory;
            let _ = Cli::command().print_help();
            Ok(0)
        }
    }
}

fn registry() -> Result<crate::profile::Registry, CliError> {
    crate::profile::Registry::load().map_err(CliError::input)
}

fn profiles(json: bool) -> CliResult {
    let reg = registry()?;
    for (p, source) in reg.iter() {
        let source = match source {
            crate::profile::Source::Builtin => "built-in".to_string(),
            crate::profile::Source::File(path) => path.display().to_string(),
        };
        if json {
            let doc = serde_json::json!({
                "id": p.id, "name": p.name.en, "name_zh": p.name.zh,
                "protocol": p.protocol.name(), "baud": p.baud,
                "commands": p.commands.len(), "source": source,
            });
            println!("{doc}");
        } else {
            println!(
                "{:<16} {:<6} {:>7} baud  {:>3} commands  {} / {}  ({source})",
                p.id,
                p.protocol.name(),
                p.baud,
                p.commands.len(),
                p.name.en,
                p.name.zh
            );
        }
    }
    Ok(0)
}

fn ports(json: bool) -> CliResult {
    let ports = crate::link::serial::list_ports();
    if json {
        println!("{}", serde_json::json!({ "ports": ports }));
    } else if ports.is_empty() {
        println!("no serial ports found (pseudo-terminals are not listed; open them by path)");
    } else {
        for p in &ports {
            println!("{}", p.label());
        }
    }
    Ok(0)
}
