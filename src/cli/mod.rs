//! The command line: the same library behind a CLI, for production-line scripts and tests.
//!
//! Exit codes: 0 success; 1 the device (or the data) failed, disagreed or did not answer;
//! 2 bad input (usage, out-of-range value, malformed file).

#[macro_use]
mod console;
mod checks;
mod frame;
mod msp;
mod port;
mod preset;
mod profile;
mod profiles;
mod provision;
mod records;
mod replay;
mod report;
mod servo;
mod servo_scan;
mod sim;
mod sim_field;
mod station;
mod station_headless;
mod tuya;
mod tuya_conform;
mod tuya_show;

use crate::link::PortOpener;
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
#[command(
    name = "botbench",
    version = crate::VERSION,
    about,
    long_about = None,
    after_help = "Environment: BOTBENCH_PORT is the --port of the device commands (msp, servo, \
                  tuya, preset) when none is given; without either, the port the window last \
                  connected to (when it was a port, not a built-in simulator, and is still \
                  there), said on stderr; BOTBENCH_PROFILE_DIR holds your own profiles; \
                  BOTBENCH_RECORDS the records' file. `botbench completions bash` and `botbench \
                  manpage` print shell completions and the manual page."
)]
pub struct Cli {
    #[command(subcommand)]
    command: Option<Cmd>,
}

#[derive(Debug, Subcommand)]
enum Cmd {
    /// Open the window (the default): on the built-in demo device unless --port is given.
    Gui {
        /// A serial port to connect to.
        #[arg(long, short, value_parser = checks::port_path)]
        port: Option<String>,
        /// Baud rate, 300 to 4000000.
        #[arg(long, short, value_parser = checks::baud)]
        baud: Option<u32>,
        /// Device profile.
        #[arg(long)]
        profile: Option<String>,
        /// Open on a built-in simulated device: window-cleaner, solar-cleanbot, servo-bus or
        /// tuya-vacuum (its profile unless --profile is given).
        #[arg(long, value_name = "KIND", conflicts_with = "port")]
        demo: Option<String>,
        /// The panel to show first: Device, Tuning, Telemetry, Presets, Actions, Solar,
        /// SelfTest, ServoBench, TuyaConsole or Monitor (if the device has it).
        #[arg(long, value_name = "PANEL", value_parser = parse_panel)]
        panel: Option<crate::ui::PanelId>,
        /// Tour the built-in demo devices and save a screenshot of each panel at 1280×800 and
        /// 1024×600, in English and Chinese, into DIR as <device>-<panel>-<size>-<lang>.png; then
        /// close. Saved settings are neither read nor changed.
        #[arg(long, value_name = "DIR", conflicts_with_all = ["port", "demo"])]
        screenshots: Option<std::path::PathBuf>,
    },
    /// Decode or build frames of the three protocols.
    #[command(subcommand)]
    Frame(frame::FrameCmd),
    /// Serve a simulated device on a pseudo-terminal; prints its path, then serves until killed.
    Sim(sim::SimArgs),
    /// Make a device profile from a vendor's data-point schema.
    #[command(subcommand)]
    Profile(profile::ProfileCmd),
    /// List the device profiles and where each comes from; `profiles show NAME` shows one
    /// whole (its commands, fields, servo parameters and data points).
    Profiles(profiles::ProfilesArgs),
    /// List the serial ports (USB VID:PID, serial number, product, and the adapter's driver and
    /// latency timer where the system tells them).
    Ports {
        /// Print JSON.
        #[arg(long)]
        json: bool,
        /// Set the USB adapter's latency timer of PORT to MS ms (FTDI on Linux; 1 ms makes
        /// answers reach botbench soonest), then list the ports.
        #[arg(long, num_args = 2, value_names = ["PORT", "MS"])]
        set_latency_timer: Option<Vec<String>>,
    },
    /// Window cleaner and solar cleanbot (MSP).
    Msp(msp::MspArgs),
    /// UART bus servos.
    Servo(servo::ServoArgs),
    /// Tuya MCU, with botbench as the Wi-Fi module.
    Tuya(tuya::TuyaArgs),
    /// Measure speed against the simulators through pseudo-terminals, as ratios to the wire
    /// limit (run on a release build).
    Bench {
        /// Also the 8-baud scan and the 9600-baud firmware upload (about 90 s more).
        #[arg(long)]
        long: bool,
        /// Also the field scan: default `servo scan`s of servos 0, 1, 5 served by `botbench
        /// sim servo-bus`: 20 without adapter latency, 20 behind a 16 ms latency timer, and
        /// 300 of that with two CPU-bound processes beside it, none of which may exit 0 having
        /// missed a servo (some minutes more; Ctrl-C stops it between scans, every process it
        /// started killed).
        #[arg(long)]
        field: bool,
        /// One JSON document a line.
        #[arg(long)]
        json: bool,
        /// Only the cases whose name contains this: msp-polling, msp-bad-adapter (the
        /// window's telemetry polls against msp watch's behind a bad adapter), servo-scan,
        /// servo-field-scan (with --field), servo-provision, tuya-ota, tuya-dp-report,
        /// tuya-handshake, station (4 slots at once against one alone), records-report
        /// (SQLite; and PostgreSQL when
        /// BOTBENCH_BENCH_POSTGRES=postgres://... names a server).
        #[arg(long, value_name = "CASE")]
        only: Option<String>,
    },
    /// Save, compare and apply presets of a device's tunable parameters.
    #[command(subcommand)]
    Preset(preset::PresetCmd),
    /// The production records: list, show a unit's runs, export as CSV or JSON lines.
    Records(records::RecordsCmdArgs),
    /// The line station: several fixtures on one PC, each slot running a line plan
    /// (`station new` writes an example bundle; `station BUNDLE --check` checks one).
    Station(station::StationArgs),
    /// Yield per shift, station, slot and plan; failing steps; each measurement's histogram,
    /// Cpk and drift (--html FILE for one self-contained page).
    Report(report::ReportArgs),
    /// Print a completion script for SHELL: bash, zsh, fish or powershell (e.g. `botbench
    /// completions bash > ~/.local/share/bash-completion/completions/botbench`; the .deb
    /// installs bash's, zsh's and fish's).
    Completions {
        /// bash, zsh, fish, powershell or elvish.
        shell: clap_complete::Shell,
    },
    /// Print the manual page (roff, for `man -l -`; the .deb installs it as botbench(1)).
    Manpage,
}

/// Runs the command line with the process's arguments; `--port` is opened with `ports` (the
/// system's serial ports: [`PortOpener::system`]).
pub fn main(ports: PortOpener) -> ExitCode {
    ExitCode::from(run_args(std::env::args_os(), &ports))
}

/// Runs the command line with `args` (the program's name first), printing as the process
/// does, and returns its exit code (0, 1 the device failed, 2 bad input). `--port` (and the
/// window's port) is opened with `ports`: a test hands in its simulator's, served in lockstep
/// ([`crate::sim::PtyServer::serve_in`]).
pub fn run_args<I, T>(args: I, ports: &PortOpener) -> u8
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    console::scoped(console::Console::process(), || run_in_console(args, ports)).0
}

/// As [`run_args`], in a program's own process, with its own console: what it writes to
/// stdout and stderr goes to `into` (readable while it runs), it reads no operator (stdin is
/// closed) and leaves Ctrl-C alone. Several runs at once, on several threads, never mix: a test
/// runs the command line this way against a simulator served in lockstep with its link
/// ([`simulated`]), so that no verdict depends on how fast another process is scheduled.
pub fn run_args_captured<I, T>(args: I, ports: &PortOpener, into: &Captured) -> u8
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    console::scoped(console::Console::buffers(into), || {
        run_in_console(args, ports)
    })
    .0
}

pub use console::Captured;
pub use sim::{Controlled, FreshWindowCleaner, SimControl, Simulated, simulated};

/// The command line's run, on this thread's console.
fn run_in_console<I, T>(args: I, ports: &PortOpener) -> u8
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    let args: Vec<std::ffi::OsString> = args.into_iter().map(Into::into).collect();
    let json = wants_json(&args);
    let cli = match Cli::try_parse_from(args) {
        Ok(c) => c,
        Err(e) if json && e.use_stderr() => {
            let text = e.to_string();
            let message = text.trim().trim_start_matches("error: ");
            return json_failure(&CliError::input(message));
        }
        Err(e) => {
            if console::is_process() {
                let _ = e.print();
            } else if e.use_stderr() {
                err!("{}", e.render());
            } else {
                out!("{}", e.render());
            }
            return if e.use_stderr() { 2 } else { 0 };
        }
    };
    let result = run(cli, ports);
    // The links are closed by now: the capture files are complete.
    let result = match (result, port::finish_captures()) {
        (Ok(_), Err(e)) => Err(e),
        (r, _) => r,
    };
    match result {
        Ok(code) => code,
        Err(e) if json => json_failure(&e),
        Err(e) => {
            errln!("botbench: {}", bounded(&e.message));
            e.code
        }
    }
}

/// Whether the command line asks for `--json` (before a `--`, which ends the options).
fn wants_json(args: &[std::ffi::OsString]) -> bool {
    args.iter()
        .skip(1)
        .take_while(|a| *a != "--")
        .any(|a| a == "--json")
}

/// A failure of a `--json` command: the message on stderr as ever, and on stdout the document
/// `{"error": MESSAGE, "exit": CODE}` (1 the device failed, 2 bad input), so that a script
/// reading stdout always gets JSON. Returns the exit code.
fn json_failure(e: &CliError) -> u8 {
    errln!("botbench: {}", bounded(&e.message));
    outln!(
        "{}",
        serde_json::json!({ "error": bounded(&e.message), "exit": e.code })
    );
    e.code
}

/// The most lines of one error message (a document's problems, one a line).
const MESSAGE_LINES: usize = 40;

/// A message kept to a screen: each line clipped (input it quotes kept to a line or so), at
/// most [`MESSAGE_LINES`] lines.
fn bounded(message: &str) -> String {
    let lines: Vec<&str> = message.lines().collect();
    let mut out: Vec<String> = lines
        .iter()
        .take(MESSAGE_LINES)
        .map(|l| crate::document::clip_message(l))
        .collect();
    if lines.len() > MESSAGE_LINES {
        out.push(format!(
            "  … and {} more lines",
            lines.len() - MESSAGE_LINES
        ));
    }
    out.join("\n")
}

fn run(cli: Cli, opener: &PortOpener) -> CliResult {
    match cli.command {
        Some(Cmd::Frame(cmd)) => frame::run(cmd),
        Some(Cmd::Profiles(args)) => profiles::run(args),
        Some(Cmd::Profile(cmd)) => profile::run(cmd),
        Some(Cmd::Ports {
            json,
            set_latency_timer,
        }) => ports(json, set_latency_timer),
        Some(Cmd::Msp(args)) => msp::run(args, opener),
        Some(Cmd::Servo(args)) => servo::run(args, opener),
        Some(Cmd::Tuya(args)) => tuya::run(args, opener),
        Some(Cmd::Bench {
            long,
            field,
            json,
            only,
        }) => bench(long, field, json, only.as_deref()),
        Some(Cmd::Preset(cmd)) => preset::run(cmd, opener),
        Some(Cmd::Records(args)) => records::run(args),
        Some(Cmd::Report(args)) => report::run(args),
        Some(Cmd::Station(args)) => station::run(args, opener),
        Some(Cmd::Sim(args)) => sim::run(args),
        Some(Cmd::Completions { shell }) => completions(shell),
        Some(Cmd::Manpage) => manpage(),
        Some(Cmd::Gui {
            port,
            baud,
            profile,
            demo,
            panel,
            screenshots,
        }) => gui(port, baud, profile, demo, panel, screenshots, opener),
        None => gui(None, None, None, None, None, None, opener),
    }
}

fn registry() -> Result<crate::profile::Registry, CliError> {
    crate::profile::Registry::load_from(console::user_profiles().as_deref())
        .map_err(CliError::input)
}

fn ports(json: bool, set_latency_timer: Option<Vec<String>>) -> CliResult {
    if let Some(args) = set_latency_timer {
        let [port, ms] = args.as_slice() else {
            return Err(CliError::input("--set-latency-timer takes PORT and MS"));
        };
        let max = crate::system::adapter::platform::MAX_LATENCY_TIMER_MS;
        let ms: u32 = ms
            .trim()
            .parse()
            .ok()
            .filter(|ms| (1..=max).contains(ms))
            .ok_or_else(|| {
                CliError::input(format!(
                    "--set-latency-timer {port} {ms}: the latency timer is 1 to {max} ms"
                ))
            })?;
        if !std::path::Path::new(port).exists() {
            return Err(CliError::input(format!(
                "--set-latency-timer: there is no port {port} (`botbench ports` lists them)"
            )));
        }
        let now = crate::system::adapter::set_latency_timer(port, ms).map_err(CliError::device)?;
        if !json {
            outln!("{port}: latency timer set to {now} ms");
        }
    }
    let ports = crate::system::list_ports();
    if json {
        outln!("{}", serde_json::json!({ "ports": ports }));
    } else if ports.is_empty() {
        outln!("no serial ports found (pseudo-terminals are not listed; open them by path)");
    } else {
        for p in &ports {
            outln!("{}", p.label());
        }
    }
    Ok(0)
}

fn bench(long: bool, field: bool, json: bool, only: Option<&str>) -> CliResult {
    crate::bench::check_only(only, field).map_err(CliError::input)?;
    if cfg!(debug_assertions) {
        errln!(
            "botbench: this is a debug build; run `cargo run --release -- bench` for real figures"
        );
    }
    let cancel = if field {
        port::cancel_on_ctrl_c()
    } else {
        crate::ops::Cancel::new()
    };
    let figures = crate::bench::run_all(long, field, only, &cancel, &mut |f| {
        if json {
            outln!("{}", serde_json::to_string(f).unwrap_or_default());
        } else {
            // One convention: times in ms, speed as the share of the wire limit reached
            // (the wire's own time over the time taken: 1.00 is the limit).
            outln!(
                "{:<56} {:>10.2} ms  wire {:>10.2} ms  {:>5.2} of the wire limit  {}",
                f.name,
                f.seconds * 1e3,
                f.wire_seconds * 1e3,
                f.wire_ratio,
                f.notes
            );
        }
    })
    .map_err(CliError::device)?;
    let failed: Vec<&str> = figures
        .iter()
        .filter(|f| f.failed.is_some())
        .map(|f| f.name.as_str())
        .collect();
    if failed.is_empty() {
        Ok(0)
    } else {
        errln!(
            "botbench: {} of {} bench case(s) failed: {}",
            failed.len(),
            figures.len(),
            failed.join(", ")
        );
        Ok(1)
    }
}

/// `botbench completions SHELL`: the completion script on stdout.
fn completions(shell: clap_complete::Shell) -> CliResult {
    let mut script = Vec::new();
    clap_complete::generate(
        shell,
        &mut <Cli as clap::CommandFactory>::command(),
        "botbench",
        &mut script,
    );
    out!("{}", String::from_utf8_lossy(&script));
    Ok(0)
}

/// `botbench manpage`: botbench(1) in roff on stdout.
fn manpage() -> CliResult {
    let mut page = Vec::new();
    clap_mangen::Man::new(<Cli as clap::CommandFactory>::command())
        .render(&mut page)
        .map_err(|e| CliError::device(format!("cannot render the manual page: {e}")))?;
    out!("{}", String::from_utf8_lossy(&page));
    Ok(0)
}

/// A panel by its name, as in the saved settings.
fn parse_panel(name: &str) -> Result<crate::ui::PanelId, String> {
    crate::ui::PanelId::parse(name).ok_or_else(|| {
        let known: Vec<&str> = crate::ui::PanelId::all()
            .into_iter()
            .map(|id| id.as_str())
            .collect();
        format!("unknown panel '{name}'; known: {}", known.join(", "))
    })
}

fn gui(
    port: Option<String>,
    baud: Option<u32>,
    mut profile: Option<String>,
    demo: Option<String>,
    panel: Option<crate::ui::PanelId>,
    screenshots: Option<std::path::PathBuf>,
    ports: &PortOpener,
) -> CliResult {
    let mut target = port.map(crate::ui::Target::Port);
    if let Some(kind) = demo {
        let kind: crate::sim::SimKind = kind.parse().map_err(CliError::input)?;
        profile = profile.or_else(|| Some(kind.profile_id().to_string()));
        target = Some(crate::ui::Target::Demo(kind.name().to_string()));
    }
    if let Some(p) = &profile {
        registry()?.get(p).map_err(CliError::input)?;
    }
    if let Some(why) = crate::system::display::missing() {
        return Err(no_display(why));
    }
    crate::ui::run(target, baud, profile, panel, screenshots, ports.clone()).map_err(|e| {
        let e = e.to_string();
        if crate::system::display::is_unreachable(&e) {
            // The window system's own words name its source files: said in ours.
            no_display("the display named could not be reached")
        } else {
            CliError::device(format!("cannot open the window: {e}"))
        }
    })?;
    Ok(0)
}

/// The window cannot be shown here (`why`): exit 2, a bad environment rather than a device
/// failure, with where the command line is.
fn no_display(why: &str) -> CliError {
    CliError::input(format!(
        "no display: the window needs X11 or Wayland; the command line works without one \
         (botbench --help). Here {why}."
    ))
}
