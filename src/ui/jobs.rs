//! Long work off the UI thread: a panel asks for a [`Job`] (`Action::StartJob`, the one way to
//! start one); the app runs it on a named job thread over a link client, and routes what it
//! reports ([`JobOutput`]) once per frame. A job can be cancelled.
//!
//! The jobs several panels share (read, write with read-back, send) are made here; each runs an
//! operation of [`crate::ops`].

use super::panel::{PanelId, PanelOutput};
use super::station::Verdict;
use crate::document::DocumentError;
use crate::i18n::Key;
use crate::i18n::Text;
use crate::link::Client;
use crate::ops::{self, Cancel, Check, FieldValues, OpError, Progress};
use crate::ops::{Device, Run};
use crate::profile::{Input, Profile};
use crossbeam_channel::{Receiver, Sender};
use std::path::PathBuf;
use std::sync::Arc;

/// What a job ends with: a summary for the status line (in both languages), or why it failed.
pub type JobResult = Result<Text, JobError>;

/// Why a job failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum JobError {
    /// Its operation failed (cancelled included).
    #[error(transparent)]
    Op(#[from] OpError),
    /// A document could not be read or saved.
    #[error(transparent)]
    Document(#[from] DocumentError),
    /// Some of a batch failed.
    #[error("{failed} of {total} {}", what.en)]
    Incomplete {
        /// How many failed.
        failed: usize,
        /// How many there were.
        total: usize,
        /// What failed, e.g. `reads failed`, in both languages.
        what: Text,
    },
    /// Cancelled part of the way through a batch.
    #[error("cancelled after {done} of {total} {what}")]
    CancelledAfter {
        /// How many were done.
        done: usize,
        /// How many there were.
        total: usize,
        /// Of what, e.g. `commands`.
        what: &'static str,
    },
    /// A firmware update cancelled part of the way: the MCU holds an incomplete image.
    #[error("cancelled after offset {offset} of {size} bytes: the MCU holds an incomplete image")]
    UpdateCancelled {
        /// Bytes acked.
        offset: u64,
        /// The image's size.
        size: usize,
    },
    /// A firmware update whose port went away part of the way: nothing is known of the MCU's
    /// image (the link, not the MCU, failed).
    #[error("link lost during the update, after offset {offset} of {size} bytes: {why}")]
    UpdateLinkLost {
        /// Bytes acked before the port went.
        offset: u64,
        /// The image's size.
        size: usize,
        /// Why the port went.
        why: String,
    },
    /// The device failed a test: what failed, in both languages.
    #[error("FAIL: {}", .0.en)]
    Failed(crate::i18n::Text),
    /// A device failed a step of its provisioning.
    #[error("FAIL at {step}: {reason}")]
    StepFailed {
        /// The step.
        step: String,
        /// Why.
        reason: String,
    },
    /// The port went away during a step (of a servo's provisioning): no verdict on the
    /// device, which did not fail the step.
    #[error("NO VERDICT: link lost during {}: {why}", step.en)]
    LinkLostDuring {
        /// The step, in both languages.
        step: crate::i18n::Text,
        /// What the link said.
        why: String,
    },
    /// A log could not be appended to.
    #[error(transparent)]
    Log(#[from] LogError),
    /// A file could not be read.
    #[error("{path}: {reason}")]
    File {
        /// The file.
        path: PathBuf,
        /// What the system said.
        reason: String,
    },
    /// The job thread could not start.
    #[error("cannot start a job thread: {0}")]
    Thread(String),
}

/// A record that could not be appended to its log (self-test, provisioning).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("cannot append to {}: {reason}", path.display())]
pub struct LogError {
    /// The log.
    pub path: PathBuf,
    /// What the system said.
    pub reason: String,
}

impl LogError {
    /// `path` could not be appended to: `error`.
    pub fn new(path: &std::path::Path, error: &std::io::Error) -> Self {
        Self {
            path: path.to_path_buf(),
            reason: error.to_string(),
        }
    }
}

/// What a job reports. What concerns the station goes to it (the device model, the status
/// line, the unit's verdicts); the rest goes to the panel that started the job, in that panel's
/// own type ([`JobSink::panel`]).
#[derive(Debug)]
pub enum JobOutput {
    /// How far it got.
    Progress(Progress),
    /// A command was read: its values, or why not (for the device model).
    Read(u8, Result<FieldValues, OpError>),
    /// A Set was written and read back: the checks, or why not (for the device model).
    Wrote(u8, Result<Vec<Check>, OpError>),
    /// A verdict on the unit on the fixture (for the station).
    Verdict(Verdict),
    /// For the panel that started the job.
    Panel(PanelOutput),
    /// The job ended: a summary, or the error that ended it.
    Done(JobResult),
}

/// Where a job sends its output.
#[derive(Debug, Clone)]
pub struct JobSink(Sender<JobOutput>, eframe::egui::Context);

impl JobSink {
    /// Sends output and wakes the UI.
    pub fn send(&self, out: JobOutput) {
        let _ = self.0.send(out);
        self.1.request_repaint();
    }

    /// Sends progress.
    pub fn progress(&self, p: Progress) {
        self.send(JobOutput::Progress(p));
    }

    /// Sends `out` to the panel that started the job (which takes it as its own type).
    pub fn panel<T: std::any::Any + Send>(&self, out: T) {
        self.send(JobOutput::Panel(PanelOutput::new(out)));
    }
}

/// What a job runs: on the job thread, with a link client, a cancel flag and a sink for output.
pub type Work = Box<dyn FnOnce(&Client, &Cancel, &JobSink) -> JobResult + Send>;

/// A job to start: a title for the status line, and its work.
pub struct Job {
    /// What it does, for the status bar, in both languages.
    pub title: Text,
    work: Work,
    /// The panel that started it, which its [`JobOutput::Panel`] output goes to (marked by
    /// [`super::panel::Panels`] when the panel returns it).
    owner: Option<PanelId>,
}

impl Job {
    /// A job titled `title` that runs `work`.
    pub fn new(
        title: impl Into<Text>,
        work: impl FnOnce(&Client, &Cancel, &JobSink) -> JobResult + Send + 'static,
    ) -> Self {
        Self {
            title: title.into(),
            work: Box::new(work),
            owner: None,
        }
    }

    /// The job, started by panel `panel` (unless it already has an owner).
    pub fn owned_by(mut self, panel: PanelId) -> Self {
        self.owner.get_or_insert(panel);
        self
    }
}

impl std::fmt::Debug for Job {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Job")
            .field("title", &self.title.en)
            .field("owner", &self.owner)
            .finish_non_exhaustive()
    }
}

/// A job that runs (or ran).
pub struct RunningJob {
    /// What it does, for the status bar, in both languages.
    pub title: Text,
    /// Its latest progress.
    pub progress: Option<Progress>,
    /// Raise to stop it.
    pub cancel: Cancel,
    /// The panel that started it, if one did.
    pub owner: Option<PanelId>,
    rx: Receiver<JobOutput>,
    done: bool,
}

impl RunningJob {
    /// Starts `job` on a thread named `botbench-job`.
    pub fn spawn(
        job: Job,
        client: Client,
        ctx: &eframe::egui::Context,
    ) -> Result<RunningJob, JobError> {
        let (tx, rx) = crossbeam_channel::unbounded();
        let cancel = Cancel::new();
        let sink = JobSink(tx, ctx.clone());
        let c = cancel.clone();
        let work = job.work;
        std::thread::Builder::new()
            .name("botbench-job".into())
            .spawn(move || {
                let result = work(&client, &c, &sink);
                sink.send(JobOutput::Done(result));
            })
            .map_err(|e| JobError::Thread(e.to_string()))?;
        Ok(RunningJob {
            title: job.title,
            progress: None,
            cancel,
            owner: job.owner,
            rx,
            done: false,
        })
    }

    /// Output that has arrived (progress is also kept on the job).
    pub fn drain(&mut self) -> Vec<JobOutput> {
        let out: Vec<JobOutput> = self.rx.try_iter().collect();
        for o in &out {
            match o {
                JobOutput::Progress(p) => self.progress = Some(p.clone()),
                JobOutput::Done(_) => self.done = true,
                _ => {}
            }
        }
        out
    }

    /// Whether it has ended.
    pub fn is_done(&self) -> bool {
        self.done
    }
}

/// Reads the commands `ids` one after another ([`ops::tuning::read_commands`]); each answer goes
/// to the device model.
pub fn read(profile: &Arc<Profile>, ids: Vec<u8>) -> Job {
    let profile = profile.clone();
    Job::new(Key::Read, move |client, cancel, sink| {
        let tally = ops::tuning::read_commands(
            Device::new(client, &profile),
            &ids,
            &mut Run::new(cancel, |p| sink.progress(p)),
            &mut |id, r| sink.send(JobOutput::Read(id, r)),
        )?;
        if tally.failed == 0 {
            Ok(Text::new(
                format!("{} read", tally.total),
                format!("已读取 {} 项", tally.total),
            ))
        } else {
            Err(JobError::Incomplete {
                failed: tally.failed,
                total: tally.total,
                what: Text::new("reads failed", "读取失败"),
            })
        }
    })
}

/// Writes these Set commands with their full payloads, each read back through its Get
/// ([`ops::tuning::write_commands`]); each result goes to the device model.
pub fn write(profile: &Arc<Profile>, writes: Vec<ops::tuning::SetWrite>) -> Job {
    let profile = profile.clone();
    Job::new(Key::Write, move |client, cancel, sink| {
        let mut done = 0;
        // Writes refused before anything was sent: not "not verified", nothing was written.
        let mut refused = 0;
        let tally = ops::tuning::write_commands(
            Device::new(client, &profile),
            &writes,
            &mut Run::new(cancel, |p| sink.progress(p)),
            &mut |id, r| {
                done += 1;
                refused += usize::from(r.as_ref().is_err_and(OpError::nothing_sent));
                sink.send(JobOutput::Wrote(id, r))
            },
        )
        .map_err(|e| match e {
            OpError::Cancelled | OpError::CancelledAfter { .. } => JobError::CancelledAfter {
                done,
                total: writes.len(),
                what: "commands",
            },
            e => e.into(),
        })?;
        if tally.failed == 0 {
            Ok(Text::new(
                format!("{} command(s) written and verified", tally.done),
                format!("{} 条命令已写入并校验", tally.done),
            ))
        } else if tally.failed == refused {
            Err(JobError::Incomplete {
                failed: refused,
                total: tally.total,
                what: Text::new("command(s) refused, nothing sent", "命令被拒绝,未发送"),
            })
        } else {
            Err(JobError::Incomplete {
                failed: tally.failed - refused,
                total: tally.total,
                what: Text::new("command(s) not verified", "命令未通过校验"),
            })
        }
    })
}

/// Sends command `id` (an action) with `inputs` and waits for its acknowledgement.
pub fn send(profile: &Arc<Profile>, id: u8, inputs: Vec<(String, Input)>) -> Job {
    let profile = profile.clone();
    Job::new(Key::Send, move |client, _cancel, _sink| {
        let ident = ops::tuning::send_command(Device::new(client, &profile), id, &inputs)?;
        let name = profile
            .command(&ident)
            .map_or_else(|| Text::same(&ident), |c| c.name.clone());
        Ok(Text::new(
            format!("{} acknowledged", name.en),
            format!("{} 已确认", name.zh),
        ))
    })
}
