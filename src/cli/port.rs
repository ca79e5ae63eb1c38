//! What the device subcommands share: the port options, opening a link, printing checks.

use super::{CliError, checks, registry};
use crate::capture::{Capture, CaptureInfo};
use crate::i18n::Text;
use crate::link::silent::{self, SettingNames};
use crate::link::{DeviceInfo, ExchangeError, LineLevel, Link, LinkOptions, PortOpener, PortSetup};
use crate::ops::{Check, OpError};
use crate::profile::{Field, Profile, Protocol};
use clap::Args;
use std::sync::Arc;

/// Port options of every device subcommand, taken before or after the subcommand's name
/// (`botbench servo --port P scan` and `botbench servo scan --port P` are the same).
#[derive(Debug, Args)]
pub(crate) struct PortArgs {
    /// The serial port (e.g. /dev/ttyUSB0, or a /dev/pts path from `botbench sim`). Required,
    /// unless BOTBENCH_PORT names one (the bench's usual port: `export
    /// BOTBENCH_PORT=/dev/ttyUSB0`).
    #[arg(long, short, global = true, env = "BOTBENCH_PORT", value_parser = checks::port_path)]
    pub port: Option<String>,
    /// Baud rate, 300 to 4000000 (default: the profile's).
    #[arg(long, short, global = true, value_parser = checks::baud)]
    pub baud: Option<u32>,
    /// Device profile name or .ron file.
    #[arg(long, global = true)]
    pub profile: Option<String>,
    /// How long the device may take to answer beyond the wire time, 1 to 5000 ms (default: the
    /// protocol's: MSP 20, servo 1.5, Tuya 300).
    #[arg(long, global = true, value_name = "MS", value_parser = checks::margin_ms)]
    pub margin_ms: Option<u64>,
    /// The DTR line right after the port opens: on, off or keep (default keep: as the adapter
    /// set it; many assert it on open, and a board wired to it reboots).
    #[arg(long, global = true, value_name = "on|off|keep", value_parser = checks::line_level)]
    pub dtr: Option<LineLevel>,
    /// The RTS line right after the port opens: on, off or keep (default keep).
    #[arg(long, global = true, value_name = "on|off|keep", value_parser = checks::line_level)]
    pub rts: Option<LineLevel>,
    /// Send nothing for this long after the port opens, 0 to 30000 ms (default 0): a board
    /// that reboots when the port opens answers only once it has booted.
    #[arg(long, global = true, value_name = "MS", value_parser = checks::boot_wait_ms)]
    pub boot_wait_ms: Option<u64>,
    /// Requests in flight at once when polling at the wire's maximum: set by `msp
    /// --poll-pipeline` (MSP only); 2 elsewhere.
    #[arg(skip = 2)]
    pub poll_pipeline: u8,
    /// Record the session to this pcapng file (Wireshark opens it; `botbench sim replay`
    /// serves it back; `botbench frame decode --capture` prints it).
    #[arg(long, global = true, value_name = "FILE")]
    pub capture: Option<std::path::PathBuf>,
    /// With --capture: write over the capture file if it exists (without it, an existing file
    /// is refused, so that no earlier capture is lost).
    #[arg(long, global = true, requires = "capture")]
    pub force: bool,
    /// Print JSON.
    #[arg(long, global = true)]
    pub json: bool,
    /// How `--port` is opened: the system's serial ports, or what the caller of
    /// [`super::run_args`] serves (a test's simulator).
    #[arg(skip)]
    pub ports: PortOpener,
}

/// Says `message` on stderr as a warning and keeps it for [`with_warnings`]: a script reading
/// `--json` sees it in the document as well.
pub(crate) fn warn(message: &str) {
    errln!("botbench: warning: {message}");
    super::console::with(|c| c.warnings.push(message.to_string()));
}

/// `doc` with the warnings said so far in this run as its `warnings` member (absent when there
/// were none).
pub(crate) fn with_warnings(mut doc: serde_json::Value) -> serde_json::Value {
    let warnings = super::console::with(|c| c.warnings.clone());
    if !warnings.is_empty()
        && let Some(map) = doc.as_object_mut()
    {
        map.insert("warnings".into(), serde_json::json!(warnings));
    }
    doc
}

/// Waits until every capture file is complete (their links are closed by now) and tells on
/// stderr what each holds; an error when one could not be written.
pub(crate) fn finish_captures() -> Result<(), CliError> {
    let captures = super::console::with(|c| std::mem::take(&mut c.captures));
    let mut failed = None;
    for c in captures {
        match c.stop() {
            Ok(s) => {
                let lost = if s.dropped > 0 {
                    format!(", {} chunks lost (the disk could not keep up)", s.dropped)
                } else {
                    String::new()
                };
                errln!(
                    "botbench: capture {}: {} chunks, {} bytes{lost}",
                    c.path(),
                    s.chunks,
                    s.file_bytes
                );
            }
            Err(e) => failed = Some(CliError::device(format!("capture {}: {e}", c.path()))),
        }
    }
    failed.map_or(Ok(()), Err)
}

impl PortArgs {
    /// `self`, opening `--port` with `ports`.
    pub(crate) fn with_ports(mut self, ports: &PortOpener) -> Self {
        self.ports = ports.clone();
        self
    }

    /// The port given with `--port` (or BOTBENCH_PORT); without either, in botbench's own
    /// process, the port the window last connected to ([`remembered_port`]), said on stderr.
    /// A usage error (exit 2) when there is none.
    pub fn path(&self) -> Result<&str, CliError> {
        if let Some(port) = self.port.as_deref() {
            return Ok(port);
        }
        if super::console::is_process()
            && let Some(port) = remembered_port()
        {
            errln!("botbench: no --port given: using {port}, the window's last port");
            return Ok(port);
        }
        Err(CliError::input(
            "no port given: add --port PORT (e.g. /dev/ttyUSB0, or the /dev/pts path \
             `botbench sim` prints; `botbench ports` lists this machine's ports), or set \
             BOTBENCH_PORT",
        ))
    }

    /// Loads the profile (`--profile`, else `default_profile`) and checks its protocol.
    pub fn profile(
        &self,
        default_profile: &str,
        protocol: Protocol,
    ) -> Result<Arc<Profile>, CliError> {
        let profile = registry()?
            .get(self.profile.as_deref().unwrap_or(default_profile))
            .map_err(CliError::input)?;
        if profile.protocol != protocol {
            return Err(CliError::input(format!(
                "profile '{}' speaks {}, not {}",
                profile.id,
                profile.protocol.name(),
                protocol.name()
            )));
        }
        Ok(profile)
    }

    /// The link's options: the margin, lines and boot wait given, no reconnect, the session
    /// started or not. Remembers for this run whether a boot wait was given ([`silent_hint`]).
    fn link_options(&self, start_session: bool) -> LinkOptions {
        let boot_wait_ms = self.boot_wait_ms.unwrap_or(0);
        super::console::with(|c| c.boot_wait_ms = Some(boot_wait_ms));
        LinkOptions {
            margin: self.margin_ms.map(std::time::Duration::from_millis),
            reconnect: false,
            start_session,
            poll_pipeline: usize::from(self.poll_pipeline),
            setup: PortSetup {
                dtr: self.dtr.unwrap_or_default(),
                rts: self.rts.unwrap_or_default(),
                boot_wait: std::time::Duration::from_millis(boot_wait_ms),
            },
            ..LinkOptions::default()
        }
    }

    /// The capture file to write, refused when a file is there already and `--force` was not
    /// given (exit 2, before the port is opened; what is not a file, such as a named pipe, is
    /// refused by [`Capture::create`]).
    fn check_capture(&self) -> Result<(), CliError> {
        match &self.capture {
            Some(path) if !self.force && std::fs::metadata(path).is_ok_and(|m| m.is_file()) => {
                Err(CliError::input(format!(
                    "--capture {}: the file exists; --force writes over it (an earlier capture \
                     is not lost unasked)",
                    path.display()
                )))
            }
            _ => Ok(()),
        }
    }

    /// Opens the port with `profile`, without a capture, and asks what the MSP device on it
    /// says it is (CMD_VERSION, CMD_BUILD_INFO): the identification (`None` when the device
    /// does not identify itself: silent, garbled) and the link, to be used on when `profile`
    /// fits the device and nothing is captured, else closed before the command's own link is
    /// opened with the profile that fits ([`Self::open_with`]). Errors: the port cannot be
    /// opened (exit 2).
    pub fn identify(&self, profile: Arc<Profile>) -> Result<(Option<DeviceInfo>, Link), CliError> {
        self.check_capture()?;
        let baud = self.baud.unwrap_or(profile.baud);
        let opener = self.ports.open(self.path()?, baud);
        let link = Link::open(opener, profile, self.link_options(true), None)
            .map_err(|e| CliError::input(e.to_string()))?;
        let info = link.client().device_info().ok();
        Ok((info, link))
    }

    /// Opens the port with a profile already loaded.
    pub fn open_with(&self, profile: Arc<Profile>, start_session: bool) -> Result<Link, CliError> {
        self.check_capture()?;
        let baud = self.baud.unwrap_or(profile.baud);
        let options = self.link_options(start_session);
        let port = self.path()?;
        let mut opener = self.ports.open(port, baud);
        if let Some(path) = &self.capture {
            let info = CaptureInfo::new(port, baud, &profile.id, options.margin);
            let capture = Capture::create(path, info).map_err(CliError::input)?;
            opener = capture.wrap(opener);
            super::console::with(|c| c.captures.push(capture));
        }
        let link = Link::open(opener, profile.clone(), options, None)
            .map_err(|e| CliError::input(e.to_string()))?;
        Ok(link)
    }
}

/// Maps an operation's error to an exit code: refused for its input 2, everything else 1. A
/// device that never answered gets the technician's checklist beside the error.
pub(crate) fn op_error(e: OpError) -> CliError {
    if e.is_cancel() {
        CliError {
            code: EXIT_CANCELLED,
            message: e.to_string(),
        }
    } else if e.is_input() {
        CliError::input(e)
    } else if let OpError::Exchange(e @ ExchangeError::Timeout { .. }) = e {
        unanswered(e)
    } else {
        CliError::device(e)
    }
}

/// Maps a failed exchange to exit code 1 (with the checklist when nothing answered).
pub(crate) fn exchange_error(e: ExchangeError) -> CliError {
    match e {
        e @ ExchangeError::Timeout { .. } => unanswered(e),
        e => CliError::device(e),
    }
}

/// A timeout, exit code 1, with the checklist after it: led by the loaded computer when this
/// computer was held up past the answer's deadline (said there, once, not in the timeout too).
fn unanswered(e: ExchangeError) -> CliError {
    let late = e.host_late();
    let said = match e {
        ExchangeError::Timeout {
            command,
            attempts,
            waited_ms,
            ..
        } => ExchangeError::Timeout {
            command,
            attempts,
            waited_ms,
            host_late: None,
        },
        e => e,
    };
    CliError::device(format!("{said}{}", silent_hint_after(late)))
}

/// The exit code of an operation the operator cancelled (Ctrl-C), as shells give SIGINT.
pub(crate) const EXIT_CANCELLED: u8 = 130;

/// The settings the silent-device checklist names, as the command line names them: its options.
fn option_names() -> SettingNames {
    SettingNames {
        baud: Text::same("--baud"),
        profile: Text::same("--profile"),
        boot_wait: Text::same("--boot-wait-ms 2000"),
        lines: Text::same("--dtr off --rts off (or on)"),
    }
}

/// What to check when a device never answers (the link's [`silent::checklist`], naming the
/// options), after `; `: a board that reboots on open too when this run opened its port with no
/// boot wait.
pub(crate) fn silent_hint() -> String {
    silent_hint_after(None)
}

/// [`silent_hint`] after a timeout during which this computer was held up `host_late` past the
/// answer's deadline (`None`: on time): then the loaded computer leads, the wiring follows.
pub(crate) fn silent_hint_after(host_late: Option<std::time::Duration>) -> String {
    let waited = super::console::with(|c| c.boot_wait_ms).is_some_and(|ms| ms > 0);
    let checks = silent::SilentCheck::list_after(waited, host_late);
    format!("; {}", silent::checklist(&checks, &option_names()).en)
}

/// Prints read-back checks; returns exit code 1 if any mismatched.
pub(crate) fn print_checks(
    checks: &[Check],
    field_of: impl Fn(&str) -> Option<Field>,
    json: bool,
) -> u8 {
    print_checks_with(checks, &[], field_of, json, None)
}

/// Prints read-back checks, marking the fields in `kept` (not given: the device's own values
/// written back) as such, with `extra` (name, value) as one more member of the JSON document;
/// returns exit code 1 if any mismatched.
pub(crate) fn print_checks_with(
    checks: &[Check],
    kept: &[&str],
    field_of: impl Fn(&str) -> Option<Field>,
    json: bool,
    extra: Option<(&str, serde_json::Value)>,
) -> u8 {
    let bad = checks.iter().filter(|c| !c.ok()).count();
    let is_kept = |field: &str| kept.iter().any(|k| k.eq_ignore_ascii_case(field));
    if json {
        let mut doc = serde_json::json!({
            "verified": bad == 0,
            "fields": checks.iter().map(|c| serde_json::json!({
                "field": c.field, "written": c.written, "read": c.read, "ok": c.ok(),
                "kept": is_kept(&c.field),
            })).collect::<Vec<_>>(),
        });
        if let Some((name, value)) = extra {
            doc[name] = value;
        }
        outln!("{}", with_warnings(doc));
    } else {
        for c in checks {
            let (w, r) = match field_of(&c.field) {
                // With the unit, as `get` shows a value.
                Some(f) => (
                    format!("{}{}", f.format(&c.written), f.unit_suffix()),
                    format!("{}{}", f.format(&c.read), f.unit_suffix()),
                ),
                None => (format!("{:?}", c.written), format!("{:?}", c.read)),
            };
            let how = if is_kept(&c.field) {
                "kept (not given: the device's value), "
            } else {
                ""
            };
            if c.ok() {
                outln!("{:<24} {w:>12}  {how}verified", c.field);
            } else {
                outln!("{:<24} {w:>12}  {how}MISMATCH: device holds {r}", c.field);
            }
        }
        if checks.is_empty() {
            outln!("sent and acknowledged (no read-back for this command)");
        }
    }
    u8::from(bad > 0)
}

/// `FIELD=VALUE` arguments as named text inputs (`what` names the left side in errors: `FIELD`,
/// `NAME`). A name is needed before the `=`; the value may be empty (a text field).
pub(crate) fn parse_assignments(
    args: &[String],
    what: &str,
) -> Result<Vec<(String, crate::profile::Input)>, CliError> {
    args.iter()
        .map(|kv| {
            let quoted = crate::document::quote(kv);
            let (k, v) = kv
                .split_once('=')
                .ok_or_else(|| CliError::input(format!("'{quoted}' is not {what}=VALUE")))?;
            if k.trim().is_empty() {
                return Err(CliError::input(format!(
                    "'{quoted}' has no {what} before the '='; write {what}=VALUE"
                )));
            }
            Ok((
                k.trim().to_string(),
                crate::profile::Input::Text(v.to_string()),
            ))
        })
        .collect()
}

/// A cancel flag raised by Ctrl-C, so that a long operation stops safely (a motor is stopped, a
/// write is not left half-done and unreported). A second Ctrl-C exits at once.
pub(crate) fn cancel_on_ctrl_c() -> crate::ops::Cancel {
    if let Some(captured) = super::console::captured_ctrl_c() {
        // A run in another program's process: Ctrl-C is that program's, which raises it with
        // `Captured::interrupt`.
        return captured;
    }
    let cancel = crate::ops::Cancel::new();
    let flag = cancel.clone();
    let result = ctrlc::set_handler(move || {
        if flag.is_cancelled() {
            std::process::exit(130);
        }
        errln!("botbench: stopping safely (Ctrl-C again to quit at once)");
        flag.cancel();
    });
    if let Err(e) = result {
        errln!("botbench: Ctrl-C will not stop safely: {e}");
    }
    cancel
}

/// The port the window last connected to, as it saved it (eframe's storage file: on Linux
/// `$XDG_DATA_HOME/botbench/app.ron`, else `~/.local/share/botbench/app.ron`, the settings under
/// eframe's app key), when that was a port by path that exists now. `None` for the built-in
/// simulated devices, a window never run, a port no longer there, or a file that cannot be
/// read or parsed (the command line then asks for `--port`, as without a window). Read once
/// per process.
fn remembered_port() -> Option<&'static str> {
    static REMEMBERED: std::sync::OnceLock<Option<String>> = std::sync::OnceLock::new();
    REMEMBERED
        .get_or_init(|| match crate::ui::Settings::saved_by_window()?.target {
            crate::ui::Target::Port(path) if std::path::Path::new(&path).exists() => Some(path),
            _ => None,
        })
        .as_deref()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The checklist moved down to the link (issue 25, item 10); the command line says it word
    /// for word as before, with and without a boot wait given.
    #[test]
    fn the_silent_checklist_reads_as_the_command_line_always_said_it() {
        let said = |waited| {
            let checks = silent::SilentCheck::list(waited);
            format!("; {}", silent::checklist(&checks, &option_names()).en)
        };
        let hint = "; nothing answered: is the device powered, its TX wired to the adapter's RX \
                    (and RX to TX, GND to GND), at this baud rate (--baud) and with this profile \
                    (--profile)?";
        assert_eq!(said(true), hint);
        assert_eq!(
            said(false),
            format!(
                "{hint} Or is it a board that reboots when the port opens (its USB adapter \
                 toggles DTR/RTS)? Give it time with --boot-wait-ms 2000, or set the lines right \
                 after the open: --dtr off --rts off (or on)."
            )
        );
    }
}
