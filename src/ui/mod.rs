//! The desktop window (eframe/egui): one file per panel. Panels draw from the runtime state and
//! return [`Action`]s; the app applies them once per frame. The UI never touches the port.

mod actions;
pub mod app;
mod connection;
mod device;
pub mod jobs;
mod monitor;
mod presets;
pub mod runtime;
mod selftest;
mod servo_bench;
mod solar;
mod status_bar;
mod telemetry;
mod tuning;
mod tuya_console;

pub use app::{App, PanelId, Saved};
pub use runtime::Target;
pub use solar::{Outcome as SolarOutcome, Trip as SolarTrip};

use crate::profile::{Input, Value};
use runtime::Runtime;

/// Something a panel asks the app to do.
#[derive(Debug)]
pub enum Action {
    /// Open a link.
    Connect {
        /// To what.
        target: Target,
        /// At what rate.
        baud: u32,
        /// With which profile.
        profile: String,
    },
    /// Close the link.
    Disconnect,
    /// Start a job.
    Job(JobSpec),
    /// Cancel the running job.
    CancelJob,
    /// Telemetry polls a second (`None`: as fast as the wire allows).
    SetPollRate(Option<f64>),
    /// Pause or resume telemetry polling.
    PausePolling(bool),
    /// A status-bar message.
    Say(String, bool),
    /// A command for the worker that needs no answer on this thread (stop all, Tuya options…).
    Link(crate::link::LinkCommand),
    /// Start a panel's own job.
    StartJob(JobWork),
}

/// What a job runs: on the job thread, with a link client, a cancel flag and a sink for output.
pub type Work = Box<
    dyn FnOnce(&crate::link::Client, &crate::ops::Cancel, &jobs::JobSink) -> Result<String, String>
        + Send,
>;

/// Work a panel runs as a job: on the job thread, with a link client, a cancel flag and a sink
/// for its output.
pub struct JobWork {
    /// What it does, for the status bar.
    pub title: String,
    /// The work.
    pub work: Work,
}

impl JobWork {
    /// Work titled `title`.
    pub fn new(
        title: impl Into<String>,
        work: impl FnOnce(
            &crate::link::Client,
            &crate::ops::Cancel,
            &jobs::JobSink,
        ) -> Result<String, String>
        + Send
        + 'static,
    ) -> Self {
        Self {
            title: title.into(),
            work: Box::new(work),
        }
    }
}

impl std::fmt::Debug for JobWork {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("JobWork")
            .field("title", &self.title)
            .finish_non_exhaustive()
    }
}

/// A job a panel can ask for.
#[derive(Debug, Clone)]
pub enum JobSpec {
    /// Read these commands (Get or Telemetry), one after another.
    Read(Vec<u8>),
    /// Write these Set commands with their full payloads, each read back through its Get.
    Write(Vec<(u8, Vec<(String, Input)>)>),
    /// Send one command (an action) with these inputs.
    Send(u8, Vec<(String, Input)>),
    /// Read the device's parameters and save them as a preset at this path, with a note.
    SavePreset(std::path::PathBuf, String),
    /// Write a (checked) preset, each command read back.
    ApplyPreset(Box<crate::preset::Preset>),
}

impl JobSpec {
    /// Starts the job on the runtime's link.
    pub fn start(self, rt: &mut Runtime) {
        let profile = rt.profile.clone();
        match self {
            JobSpec::Read(ids) => rt.start_job("read", move |client, cancel, sink| {
                let tally = crate::ops::tuning::read_commands(
                    client,
                    &profile,
                    &ids,
                    cancel,
                    &mut |p| sink.send(jobs::JobOutput::Progress(p)),
                    &mut |id, r| sink.send(jobs::JobOutput::Read(id, r.map_err(|e| e.to_string()))),
                )
                .map_err(|e| e.to_string())?;
                if tally.failed == 0 {
                    Ok(format!("{} read", tally.total))
                } else {
                    Err(format!("{} of {} reads failed", tally.failed, tally.total))
                }
            }),
            JobSpec::Write(items) => rt.start_job("write", move |client, cancel, sink| {
                let mut done = 0;
                let tally = crate::ops::tuning::write_commands(
                    client,
                    &profile,
                    &items,
                    cancel,
                    &mut |p| sink.send(jobs::JobOutput::Progress(p)),
                    &mut |id, r| {
                        done += 1;
                        sink.send(jobs::JobOutput::Wrote(id, r.map_err(|e| e.to_string())))
                    },
                )
                .map_err(|e| match e {
                    crate::ops::OpError::Cancelled => {
                        format!("cancelled after {done} of {} commands", items.len())
                    }
                    e => e.to_string(),
                })?;
                if tally.failed == 0 {
                    Ok(format!("{} command(s) written and verified", tally.done))
                } else {
                    Err(format!(
                        "{} of {} command(s) not verified",
                        tally.failed, tally.total
                    ))
                }
            }),
            JobSpec::SavePreset(path, note) => {
                rt.start_job("save preset", move |client, cancel, sink| {
                    let mut preset =
                        crate::ops::preset::capture(client, &profile, cancel, &mut |p| {
                            sink.send(jobs::JobOutput::Progress(p))
                        })
                        .map_err(|e| e.to_string())?;
                    preset.note = note;
                    preset
                        .save_annotated(&path, &profile)
                        .map_err(|e| e.to_string())?;
                    Ok(format!("saved to {}", path.display()))
                })
            }
            JobSpec::ApplyPreset(preset) => {
                rt.start_job("apply preset", move |client, cancel, sink| {
                    let mut total = 0;
                    let mut bad = 0;
                    crate::ops::preset::apply_each(
                        client,
                        &profile,
                        &preset,
                        cancel,
                        &mut |p| sink.send(jobs::JobOutput::Progress(p)),
                        &mut |command, checks| {
                            total += checks.len();
                            bad += checks.iter().filter(|c| !c.ok()).count();
                            if let Some(cmd) = profile.command(command) {
                                sink.send(jobs::JobOutput::Wrote(cmd.id, Ok(checks.to_vec())));
                            }
                        },
                    )
                    .map_err(|e| e.to_string())?;
                    if bad == 0 {
                        Ok(format!("{total} field(s) written and verified"))
                    } else {
                        Err(format!(
                            "{bad} of {total} field(s) do not hold the preset's value"
                        ))
                    }
                })
            }
            JobSpec::Send(id, inputs) => rt.start_job("send", move |client, _cancel, _sink| {
                let ident = crate::ops::tuning::send_command(client, &profile, id, &inputs)
                    .map_err(|e| e.to_string())?;
                Ok(format!("{ident} acknowledged"))
            }),
        }
    }
}

/// A value as a person reads it, by the field's format.
pub fn shown(field: &crate::profile::Field, v: &Value) -> String {
    field.format(v)
}

/// Opens the window. `target`, `baud` and `profile` override the saved settings.
pub fn run(
    target: Option<Target>,
    baud: Option<u32>,
    profile: Option<String>,
    panel: Option<PanelId>,
) -> Result<(), String> {
    let options = eframe::NativeOptions {
        viewport: eframe::egui::ViewportBuilder::default()
            .with_inner_size([1200.0, 780.0])
            .with_min_inner_size([800.0, 500.0])
            .with_title("botbench"),
        ..Default::default()
    };
    eframe::run_native(
        "botbench",
        options,
        Box::new(move |cc| {
            let mut saved: Saved = cc
                .storage
                .and_then(|s| eframe::get_value(s, eframe::APP_KEY))
                .unwrap_or_default();
            if let Some(t) = target {
                saved.target = t;
            }
            if let Some(b) = baud {
                saved.baud = b;
            }
            if let Some(p) = profile {
                saved.profile = p;
            }
            if let Some(p) = panel {
                saved.panel = p;
            }
            let app = App::new(&cc.egui_ctx, saved)
                .map_err(|e| -> Box<dyn std::error::Error + Send + Sync> { e.into() })?;
            Ok(Box::new(app))
        }),
    )
    .map_err(|e| e.to_string())
}
