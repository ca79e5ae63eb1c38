//! `botbench sim <kind>`: serves a simulated device on a pseudo-terminal until killed.
//!
//! The first line of stdout is the pty's path, alone, so that a script can read it and open the
//! port: `port=$(botbench sim window-cleaner | head -1)`.

use super::{CliError, CliResult};
use crate::profile::Profile;
use crate::sim::msp_device::MspCore;
use crate::sim::tuya_mcu::{McuRequest, TuyaMcu};
use crate::sim::window_cleaner::WindowCleaner;
use crate::sim::{Faults, PtyServer, SharedDevice, SimKind, SimOptions, build};
use clap::Args;
use std::io::BufRead;
use std::sync::{Arc, Mutex};
use std::time::Duration;

#[derive(Debug, Args)]
pub(crate) struct SimArgs {
    /// window-cleaner, solar-cleanbot, servo-bus or tuya-vacuum; or `replay` with a capture file.
    kind: String,
    /// `replay` only: the capture (pcapng, from --capture) whose device is served.
    #[arg(value_name = "FILE")]
    capture: Option<std::path::PathBuf>,
    /// The device's UART baud rate, 300 to 4000000 (default: its profile's). A client at
    /// another rate gets no answer.
    #[arg(long, value_parser = super::checks::baud)]
    baud: Option<u32>,
    /// Probability, 0 to 1, that a reply is lost.
    #[arg(long, default_value_t = 0.0, value_parser = super::checks::probability)]
    drop: f64,
    /// Probability, 0 to 1, that a reply has a bit flipped (it then fails its checksum).
    #[arg(long, default_value_t = 0.0, value_parser = super::checks::probability)]
    corrupt: f64,
    /// Extra delay before each reply, 0 to 10000 ms.
    #[arg(long, default_value_t = 0, value_parser = super::checks::latency_ms)]
    latency_ms: u64,
    /// A board that reboots when its port opens: it hears and says nothing for this long,
    /// 0 to 60000 ms. Served on a pseudo-terminal to another program, the simulator cannot see
    /// an open: it is silent from its own start only (in the window's demo devices and in
    /// tests, each open starts it again).
    #[arg(long, value_name = "MS", default_value_t = 0, value_parser = super::checks::boot_ms)]
    boot_ms: u64,
    /// Seed of the fault dice and of the sensor noise, any number 0 to 18446744073709551615.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Servo bus only: the servo IDs on the bus, each 0 to 254, e.g. `0,1,5`.
    #[arg(long, value_delimiter = ',', value_parser = super::checks::servo_id)]
    servos: Vec<u8>,
    /// Window cleaner and servo bus: answer as firmware described by this profile (a name or
    /// a .ron file) instead of the built-in one, e.g. `window-cleaner-configurator`, or a
    /// firmware whose payloads differ from botbench's profile.
    #[arg(long)]
    profile: Option<String>,
    #[command(flatten)]
    tuya: TuyaSimArgs,
    #[command(flatten)]
    field: super::sim_field::FieldArgs,
}

/// How the simulated Tuya MCU misbehaves, as MCUs in the field do (PROTOCOL_NOTES §4,
/// TUYA_FIELD_NOTES).
#[derive(Debug, Args)]
struct TuyaSimArgs {
    /// Tuya vacuum: the version byte of the MCU's frames (0x03 by the protocol document; 0x01
    /// and 0x00 are seen in the field): 0 to 255, decimal or 0x-hex.
    #[arg(long, value_name = "BYTE", value_parser = parse_byte)]
    frame_version: Option<u8>,
    /// Tuya vacuum: report a data point on its own every MS milliseconds (a chatty MCU): 1 to
    /// 60000.
    #[arg(long, value_name = "MS", value_parser = clap::value_parser!(u64).range(1..=60_000))]
    report_every: Option<u64>,
    /// Tuya vacuum: the data point `--report-every` reports (default 6, the battery): 1 to 255.
    #[arg(long, value_name = "ID", default_value_t = 6, value_parser = clap::value_parser!(u8).range(1..))]
    report_dp: u8,
    /// Tuya vacuum: report data point ID with another type and length than the profile's,
    /// `ID:TYPE:LEN` (e.g. `3:value:4`); repeat for more.
    #[arg(long, value_name = "ID:TYPE:LEN", value_parser = crate::sim::tuya_mcu::parse_misreport)]
    misreport: Vec<(u8, crate::sim::tuya_mcu::WireForm)>,
    /// Tuya vacuum: a slow MCU, its reports to a status query MS (or MIN-MAX ms, e.g. 100-150)
    /// apart, 1 to 10000.
    #[arg(long, value_name = "MS|MIN-MAX", value_parser = crate::sim::tuya_mcu::parse_gap)]
    report_gap_ms: Option<(Duration, Duration)>,
    /// Tuya vacuum: report its own changes as 0x22 and wait for the module's 0x23 before the
    /// next (synchronous reports).
    #[arg(long)]
    sync_reports: bool,
    /// Tuya vacuum: also report a data point the profile does not have, `ID:TYPE:VALUE` (e.g.
    /// `101:value:50`); repeat for more.
    #[arg(long, value_name = "ID:TYPE:VALUE", value_parser = crate::sim::tuya_mcu::parse_unknown_dp)]
    report_unknown_dp: Vec<(u8, crate::protocol::tuya::dp::DpValue)>,
    /// Tuya vacuum: report a value the profile does not allow for data point ID, `ID=VALUE`
    /// (raw, e.g. `6=150` a battery of 150 %, `3=32` mode 32) or `ID=len:N` (a string of N
    /// bytes); repeat for more.
    #[arg(long, value_name = "ID=VALUE", value_parser = crate::sim::tuya_mcu::parse_id_value)]
    report_out_of_range: Vec<(u8, crate::sim::tuya_mcu::RawValue)>,
    /// Tuya vacuum: how a firmware update fails: `old-version` (restarts with its old
    /// version), `never-back` (never restarts), `refuse-packet:OFFSET` (stops acking there).
    #[arg(long, value_name = "FAULT", value_parser = clap::value_parser!(crate::sim::tuya_mcu::OtaFault))]
    ota_fault: Option<crate::sim::tuya_mcu::OtaFault>,
    /// Tuya vacuum: how long the MCU takes to restart after an update, 0 to 120000 ms
    /// (default 2000).
    #[arg(long, value_name = "MS", value_parser = clap::value_parser!(u64).range(0..=120_000))]
    ota_restart_ms: Option<u64>,
    /// Tuya vacuum: the version it runs after an update (default: the one the image names,
    /// else its own with the last number raised).
    #[arg(long, value_name = "X.Y.Z", value_parser = version)]
    ota_version: Option<String>,
    /// Tuya vacuum: take writes of report-only data points (the SDK refuses them).
    #[arg(long)]
    accept_read_only: bool,
    /// Tuya vacuum: take frames whatever their checksum.
    #[arg(long)]
    ignore_checksum: bool,
    /// Tuya vacuum: answer commands it does not know (the SDK ignores them).
    #[arg(long)]
    answer_unknown: bool,
    /// Tuya vacuum: leave these data points (ids 1 to 255) out of the answer to a status
    /// query, e.g. `15,19`.
    #[arg(long, value_name = "IDS", value_delimiter = ',', value_parser = clap::value_parser!(u8).range(1..=255))]
    never_report: Vec<u8>,
}

/// A dot-decimal MCU version, `1.0.1`.
pub(crate) fn version(text: &str) -> Result<String, String> {
    let t = text.trim();
    if crate::ops::tuya::is_version(t) {
        Ok(t.to_string())
    } else {
        Err(format!(
            "'{}' is not an MCU version: x.y.z, each 0 to 99 (e.g. 1.0.1)",
            crate::document::quote(text)
        ))
    }
}

impl TuyaSimArgs {
    /// Whether any was given.
    fn any(&self) -> bool {
        self.frame_version.is_some()
            || self.report_every.is_some()
            || !self.misreport.is_empty()
            || self.report_gap_ms.is_some()
            || self.sync_reports
            || !self.report_unknown_dp.is_empty()
            || !self.report_out_of_range.is_empty()
            || self.ota_fault.is_some()
            || self.ota_restart_ms.is_some()
            || self.ota_version.is_some()
            || self.accept_read_only
            || self.ignore_checksum
            || self.answer_unknown
            || !self.never_report.is_empty()
    }

    /// Applies them to the MCU's settings (clap has checked their ranges).
    fn apply(&self, config: &mut crate::sim::tuya_mcu::TuyaConfig) {
        if let Some(v) = self.frame_version {
            config.frame_version = v;
        }
        if let Some(ms) = self.report_every {
            config.report_every = Some((self.report_dp, Duration::from_millis(ms)));
        }
        config.misreport.extend(self.misreport.iter().copied());
        config.report_gap = self.report_gap_ms;
        config.sync_reports = self.sync_reports;
        config
            .report_unknown_dp
            .extend(self.report_unknown_dp.iter().cloned());
        config
            .report_out_of_range
            .extend(self.report_out_of_range.iter().copied());
        config.ota_fault = self.ota_fault;
        if let Some(ms) = self.ota_restart_ms {
            config.ota_restart = Duration::from_millis(ms);
        }
        config.ota_version.clone_from(&self.ota_version);
        config.accept_read_only = self.accept_read_only;
        config.ignore_checksum = self.ignore_checksum;
        config.answer_unknown = self.answer_unknown;
        config.never_report.clone_from(&self.never_report);
    }
}

pub(super) fn parse_byte(text: &str) -> Result<u8, String> {
    let t = text.trim();
    match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(h) => u8::from_str_radix(h, 16),
        None => t.parse(),
    }
    .map_err(|_| format!("'{text}' is not a byte (0-255 or 0x00-0xff)"))
}

/// Prints a served pty's path alone on stdout's first line, flushed at once (scripts and tests
/// read it before the simulator is stopped).
pub(super) fn print_path(path: &str) -> Result<(), CliError> {
    outln!("{path}");
    super::console::flush().map_err(|e| CliError::device(format!("cannot write to stdout: {e}")))
}

pub(crate) fn run(args: SimArgs) -> CliResult {
    if args.kind == "replay" {
        return super::replay::serve(args.capture.as_deref());
    }
    let (kind, sim) = build_sim(&args)?;
    serve(kind, sim.baud, sim.device, sim.control, sim.faults)
}

/// The device `botbench sim ARGS...` serves, built in this process rather than served on a
/// pty of its own: its kind, the device, the faults of its wire and line, the control that
/// `sim` reads on stdin (`fault battery-low`, `corners 15`, `restart`) and its baud rate.
pub struct Simulated {
    /// Its kind (`None`: a capture replayed).
    pub kind: Option<SimKind>,
    /// The device.
    pub device: SharedDevice,
    /// The faults of its wire and line (`--drop`, `--latency-ms`, the field's misbehaviours).
    pub faults: Faults,
    /// What `sim` takes on stdin, for a window cleaner or a Tuya vacuum.
    pub control: Option<SimControl>,
    /// Its UART's rate.
    pub baud: u32,
}

/// The device `botbench sim ARGS...` (the kind first, as after `sim`) would serve, with the same
/// checks and errors; `replay FILE` serves the capture's device. A test serves it in lockstep
/// with its link (`PtyServer::start_lockstep`) and runs the command line against it in its own
/// process ([`super::run_args_captured`]). Errors: what `sim` would say, with its exit code.
pub fn simulated<I, T>(args: I) -> Result<Simulated, CliError>
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    #[derive(clap::Parser)]
    struct Sim {
        #[command(flatten)]
        args: SimArgs,
    }
    let all =
        std::iter::once(std::ffi::OsString::from("sim")).chain(args.into_iter().map(Into::into));
    let sim =
        <Sim as clap::Parser>::try_parse_from(all).map_err(|e| CliError::input(e.render()))?;
    if sim.args.kind == "replay" {
        return super::replay::simulated(sim.args.capture.as_deref());
    }
    build_sim(&sim.args).map(|(_, sim)| sim)
}

/// The simulated device `args` describe, and its kind.
fn build_sim(args: &SimArgs) -> Result<(SimKind, Simulated), CliError> {
    if let Some(extra) = &args.capture {
        return Err(CliError::input(format!(
            "unexpected argument '{}': only `sim replay` takes a file",
            extra.display()
        )));
    }
    let kind: SimKind = args.kind.parse().map_err(CliError::input)?;
    if args.tuya.any() && kind != SimKind::TuyaVacuum {
        return Err(CliError::input(format!(
            "the Tuya options (--frame-version, --report-every, --misreport, --report-gap-ms, ...) are for the tuya-vacuum simulator, not {kind}"
        )));
    }
    let faults = Faults {
        drop: args.drop,
        corrupt: args.corrupt,
        extra_latency: Duration::from_millis(args.latency_ms),
        silent: false,
        boot: Duration::from_millis(args.boot_ms),
        seed: args.seed,
        line: args.field.line(kind)?,
    };
    faults.check().map_err(CliError::input)?;
    let opts = SimOptions {
        baud: args.baud,
        latency: None,
        seed: args.seed,
        servos: args.servos.clone(),
        msp: args.field.msp(kind)?,
        ignore_baud_change: args.field.ignore_baud_change(kind)?,
        monitor_no_data: args.field.monitor_no_data(kind)?,
    };
    let firmware = firmware(args, kind)?;
    let (device, controlled) = device(args, kind, firmware, &opts)?;
    // Served through a lift, so that `next` presents a fresh unit after a silence.
    let (lift, handle) = crate::sim::fixture::Lift::new(device);
    let device: SharedDevice = Arc::new(Mutex::new(lift));
    let control = controlled.map(|c| SimControl::new(c, Some(handle)));
    let sim = Simulated {
        kind: Some(kind),
        device,
        faults,
        control,
        baud: opts.baud.unwrap_or_else(|| kind.default_baud()),
    };
    Ok((kind, sim))
}

/// The profile `--profile` names, checked to be of the simulator's protocol.
fn firmware(args: &SimArgs, kind: SimKind) -> Result<Option<Arc<Profile>>, CliError> {
    let Some(name) = &args.profile else {
        return Ok(None);
    };
    let p = super::registry()?.get(name).map_err(CliError::input)?;
    if p.protocol != kind.profile_protocol() {
        return Err(CliError::input(format!(
            "profile '{}' speaks {}, a {} speaks {}",
            p.id,
            p.protocol.name(),
            kind.name(),
            kind.profile_protocol().name()
        )));
    }
    Ok(Some(p))
}

/// The simulated device, with `firmware` when given. The Tuya MCU and the window cleaner take
/// commands on stdin (see `control`), so a typed handle to them is kept.
fn device(
    args: &SimArgs,
    kind: SimKind,
    firmware: Option<Arc<Profile>>,
    opts: &SimOptions,
) -> Result<(SharedDevice, Option<Controlled>), CliError> {
    Ok(match (kind, firmware) {
        (SimKind::WindowCleaner, Some(p)) => {
            let core =
                MspCore::with_options(p.clone(), crate::sim::window_cleaner::DEVICE_CODE, opts);
            let wc = Arc::new(Mutex::new(WindowCleaner::with_core(core, opts.seed)));
            let fresh: FreshWindowCleaner =
                Arc::new(Mutex::new(fresh_window_cleaner(Some(p), opts.clone())));
            (wc.clone(), Some(Controlled::WindowCleaner(wc, fresh)))
        }
        (SimKind::ServoBus, Some(p)) => {
            let ids: &[u8] = if opts.servos.is_empty() {
                &[1]
            } else {
                &opts.servos
            };
            let baud = opts.baud.unwrap_or_else(|| kind.default_baud());
            let bus = crate::sim::servo_bus::ServoBus::with_profile_ids(p.clone(), ids, baud)
                .map_err(CliError::input)?
                .with_seed(opts.seed)
                .with_baud_change_ignored(opts.ignore_baud_change)
                .with_monitor_no_data(opts.monitor_no_data);
            let bus = Arc::new(Mutex::new(bus));
            (bus.clone(), Some(Controlled::Servos(bus, p, baud)))
        }
        (_, Some(_)) => {
            return Err(CliError::input(
                "--profile is for the window-cleaner and servo-bus simulators",
            ));
        }
        (SimKind::TuyaVacuum, None) => {
            let mcu = tuya_vacuum(args, opts)?;
            (mcu.clone(), Some(Controlled::Tuya(mcu)))
        }
        (SimKind::WindowCleaner, None) => {
            let wc = Arc::new(Mutex::new(
                WindowCleaner::new(opts).map_err(CliError::input)?,
            ));
            let fresh: FreshWindowCleaner =
                Arc::new(Mutex::new(fresh_window_cleaner(None, opts.clone())));
            (wc.clone(), Some(Controlled::WindowCleaner(wc, fresh)))
        }
        (SimKind::ServoBus, None) => {
            let p = crate::sim::servo_bus::builtin_servo_profile();
            device(args, kind, Some(p), opts)?
        }
        (kind, None) => (build(kind, opts).map_err(CliError::input)?, None),
    })
}

/// Makes unit `n` of a window cleaner as `sim` was asked for it: seed `n`, factory settings.
pub type FreshWindowCleaner = Arc<Mutex<dyn FnMut(u64) -> Result<WindowCleaner, String> + Send>>;

fn fresh_window_cleaner(
    firmware: Option<Arc<Profile>>,
    opts: SimOptions,
) -> impl FnMut(u64) -> Result<WindowCleaner, String> + Send {
    move |seed| {
        let opts = SimOptions {
            seed,
            ..opts.clone()
        };
        match &firmware {
            Some(p) => {
                let core = MspCore::with_options(
                    p.clone(),
                    crate::sim::window_cleaner::DEVICE_CODE,
                    &opts,
                );
                Ok(WindowCleaner::with_core(core, seed))
            }
            None => WindowCleaner::new(&opts),
        }
    }
}

/// The simulated Tuya vacuum MCU, with the options of `sim tuya-vacuum` (a data point reported
/// on its own must be one of the vacuum's).
fn tuya_vacuum(args: &SimArgs, opts: &SimOptions) -> Result<Arc<Mutex<TuyaMcu>>, CliError> {
    let mut mcu = crate::sim::tuya_mcu(opts);
    let profile = crate::sim::tuya_mcu::builtin_vacuum_profile();
    if let Some(id) = args.tuya.report_every.and(Some(args.tuya.report_dp))
        && profile.data_point(id).is_none()
    {
        return Err(CliError::input(format!(
            "--report-dp {id}: the vacuum has no data point {id}"
        )));
    }
    for (id, _) in &args.tuya.report_unknown_dp {
        if profile.data_point(*id).is_some() {
            return Err(CliError::input(format!(
                "--report-unknown-dp {id}: data point {id} is in the vacuum's profile; pick an id it lacks (e.g. 101)"
            )));
        }
    }
    for (id, _) in &args.tuya.report_out_of_range {
        if profile.data_point(*id).is_none() {
            return Err(CliError::input(format!(
                "--report-out-of-range {id}: the vacuum has no data point {id}"
            )));
        }
    }
    args.tuya.apply(mcu.config_mut());
    Ok(Arc::new(Mutex::new(mcu)))
}

/// Serves `device` on a pty until the port vanishes (as asked) or the pty fails: the path on
/// stdout's first line, the control commands on stdin.
fn serve(
    kind: SimKind,
    baud: u32,
    device: SharedDevice,
    control: Option<SimControl>,
    faults: Faults,
) -> CliResult {
    let vanish_after = faults.line.vanish_after_bytes;
    let server = PtyServer::start(device, faults).map_err(CliError::device)?;
    print_path(server.path())?;
    errln!(
        "botbench: serving a {} at {baud} baud on {}; stop with Ctrl-C",
        kind.describe(),
        server.path()
    );
    if let Some(control) = control {
        errln!("botbench: {}", control.help());
        let spawned = std::thread::Builder::new()
            .name("sim-control".into())
            .spawn(move || control.serve_stdin());
        if let Err(e) = spawned {
            errln!("botbench: no stdin control: {e}");
        }
    }
    while server.is_running() {
        std::thread::sleep(Duration::from_millis(20));
    }
    Err(CliError::device(match vanish_after {
        Some(n) => format!("the port vanished after {n} bytes from the host, as asked"),
        None => "the simulator stopped: the pseudo-terminal failed".into(),
    }))
}

/// Commands typed on the simulator's stdin, for what a device does on its own, and `next`: the
/// unit lifted off the fixture for [`crate::sim::fixture::SWAP_GAP`] and a fresh one placed
/// (a new seed, factory settings; a servo bus: one fresh servo at id 0 with a new serial
/// number), as a line operator swaps units.
pub struct SimControl {
    device: Controlled,
    lift: Option<crate::sim::fixture::LiftHandle>,
    /// Units presented so far (1: the first).
    units: std::sync::atomic::AtomicU32,
}

/// The simulated device `sim` controls, typed.
pub enum Controlled {
    /// The Tuya vacuum's MCU: its own requests, a restart.
    Tuya(Arc<Mutex<TuyaMcu>>),
    /// The window cleaner: faults, corners, battery; and how a fresh one is made.
    WindowCleaner(Arc<Mutex<WindowCleaner>>, FreshWindowCleaner),
    /// A servo bus: its profile and baud rate, for a fresh servo.
    Servos(
        Arc<Mutex<crate::sim::servo_bus::ServoBus>>,
        Arc<Profile>,
        u32,
    ),
}

impl SimControl {
    /// Control of `device`, served through a [`crate::sim::fixture::Lift`] whose handle is
    /// `lift` (`None`: `next` swaps at once, with no silence).
    pub fn new(device: Controlled, lift: Option<crate::sim::fixture::LiftHandle>) -> Self {
        Self {
            device,
            lift,
            units: std::sync::atomic::AtomicU32::new(1),
        }
    }

    /// The commands it takes, as `sim` says them.
    pub fn help(&self) -> &'static str {
        match self.device {
            Controlled::Tuya(_) => {
                "stdin commands: time | utc-time | wifi-test | reset-wifi | reset-wifi-mode 0|1 | net-status | mac | rssi | stop-heartbeat | extended SUB | send CMD [HEX] | oversize BYTES | dp ID VALUE | restart | next"
            }
            Controlled::WindowCleaner(..) => {
                "stdin commands: fault NAME | clear | corners BITS | battery VOLTS | next"
            }
            Controlled::Servos(..) => "stdin commands: next",
        }
    }

    /// `next`: lifts the unit off (silent for [`crate::sim::fixture::SWAP_GAP`], and until a
    /// station has seen the fixture empty) and puts a fresh one in its place. Errors: a fresh unit could not be made.
    fn next_unit(&self) -> Result<(), String> {
        use std::sync::atomic::Ordering;
        if let Some(lift) = &self.lift {
            lift.lift_for(crate::sim::fixture::SWAP_GAP);
        }
        let n = self.units.fetch_add(1, Ordering::SeqCst) + 1;
        match &self.device {
            Controlled::Tuya(m) => {
                let mut m = m.lock().map_err(|_| "simulator poisoned")?;
                let fresh = TuyaMcu::new(m.config().clone());
                *m = fresh;
            }
            Controlled::WindowCleaner(w, fresh) => {
                let unit = (fresh.lock().map_err(|_| "simulator poisoned")?)(u64::from(n))?;
                *w.lock().map_err(|_| "simulator poisoned")? = unit;
            }
            Controlled::Servos(bus, profile, baud) => {
                let servo = crate::sim::servo_bus::SimServo::fresh_with(profile, 1000 + n)
                    .with_id(0)
                    .with_baud(*baud);
                let fresh =
                    crate::sim::servo_bus::ServoBus::with_profile(profile.clone(), vec![servo])
                        .with_seed(u64::from(n));
                *bus.lock().map_err(|_| "simulator poisoned")? = fresh;
            }
        }
        Ok(())
    }

    fn serve_stdin(self) {
        for line in std::io::stdin().lock().lines() {
            let Ok(line) = line else { return };
            let words: Vec<&str> = line.split_whitespace().collect();
            if words.is_empty() {
                continue;
            }
            match self.apply(&words) {
                Ok(()) => errln!("botbench: ok: {line}"),
                Err(e) => errln!("botbench: {e}; {}", self.help()),
            }
        }
    }

    /// Carries out one command typed on stdin (`corners 15`, `fault battery-low`, `restart`).
    /// Errors: an unknown command or a bad argument, said as `sim` says it.
    pub fn type_line(&self, line: &str) -> Result<(), String> {
        let words: Vec<&str> = line.split_whitespace().collect();
        if words.is_empty() {
            return Err("no command".into());
        }
        self.apply(&words)
    }

    fn apply(&self, words: &[&str]) -> Result<(), String> {
        let arg = |i: usize| words.get(i).copied().ok_or("missing argument");
        if words[0] == "next" {
            return self.next_unit();
        }
        match &self.device {
            Controlled::Servos(..) => return Err(format!("unknown command '{}'", words[0])),
            Controlled::Tuya(m) => {
                let mut m = m.lock().map_err(|_| "simulator poisoned")?;
                match words[0] {
                    "restart" => m.restart(),
                    "send" => {
                        let command = crate::profile::codec::parse_id(arg(1)?)
                            .ok_or("send takes a command byte, e.g. send 0x99 01 02")?;
                        let data = crate::protocol::hex::parse(&words[2..].join(" "))
                            .map_err(|e| e.to_string())?;
                        m.send_frame(command, data);
                    }
                    "oversize" => m.send_oversize(
                        arg(1)?
                            .parse()
                            .map_err(|_| "oversize takes a frame length in bytes")?,
                    ),
                    "dp" => {
                        let id =
                            crate::profile::codec::parse_id(arg(1)?).ok_or("dp takes ID VALUE")?;
                        let v: i64 = arg(2)?
                            .parse()
                            .map_err(|_| "dp takes ID VALUE (a number)")?;
                        if !m.set_dp_raw(id, v) {
                            return Err(format!("the vacuum has no number data point {id}"));
                        }
                    }
                    word => m.request(McuRequest::parse(word, words.get(1).copied())?),
                }
            }
            Controlled::WindowCleaner(w, _) => {
                let mut w = w.lock().map_err(|_| "simulator poisoned")?;
                match words[0] {
                    "fault" => w.inject_named(arg(1)?)?,
                    "clear" => {
                        for f in w.faults() {
                            w.clear_fault(f);
                        }
                    }
                    "corners" => w.set_corners(arg(1)?.parse().map_err(|_| "BITS is 0-15")?),
                    "battery" => w.set_battery(arg(1)?.parse().map_err(|_| "VOLTS is a number")?),
                    other => return Err(format!("unknown command '{other}'")),
                }
            }
        }
        Ok(())
    }
}
