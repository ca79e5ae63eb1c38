//! Long work off the UI thread: a named job thread runs an operation over a link client, sends
//! its results and progress back, and can be cancelled.

use crate::link::Client;
use crate::ops::Check;
use crate::ops::{Cancel, FieldValues, Progress};
use crossbeam_channel::{Receiver, Sender};

/// What a job reports.
#[derive(Debug, Clone)]
pub enum JobOutput {
    /// How far it got.
    Progress(Progress),
    /// A command was read: its values, or why not.
    Read(u8, Result<FieldValues, String>),
    /// A Set was written and read back: the checks, or why not.
    Wrote(u8, Result<Vec<Check>, String>),
    /// A line for the status bar.
    Note(String),
    /// For the servo bench panel.
    Servo(super::servo_bench::Output),
    /// For the Tuya console panel.
    Tuya(super::tuya_console::Output),
    /// For the device panel (ping, version, power state).
    Device(super::device::Output),
    /// For the self-test panel.
    SelfTest(super::selftest::Output),
    /// For the solar cleanbot panel.
    Solar(super::solar::Output),
    /// The job ended: a summary, or the error that ended it.
    Done(Result<String, String>),
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
}

/// A running job.
pub struct Job {
    /// What it does, for the status bar.
    pub title: String,
    /// Its latest progress.
    pub progress: Option<Progress>,
    /// Raise to stop it.
    pub cancel: Cancel,
    rx: Receiver<JobOutput>,
    done: bool,
}

impl Job {
    /// Starts `work` on a thread named `botbench-job`.
    pub fn spawn(
        title: impl Into<String>,
        client: Client,
        ctx: &eframe::egui::Context,
        work: impl FnOnce(&Client, &Cancel, &JobSink) -> Result<String, String> + Send + 'static,
    ) -> Result<Job, String> {
        let (tx, rx) = crossbeam_channel::unbounded();
        let cancel = Cancel::new();
        let sink = JobSink(tx, ctx.clone());
        let c = cancel.clone();
        std::thread::Builder::new()
            .name("botbench-job".into())
            .spawn(move || {
                let result = work(&client, &c, &sink);
                sink.send(JobOutput::Done(result));
            })
            .map_err(|e| format!("cannot start a job thread: {e}"))?;
        Ok(Job {
            title: title.into(),
            progress: None,
            cancel,
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
