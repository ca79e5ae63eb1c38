//! A station's job: started unless one runs, cancelled, its progress, and its output delivered
//! where it belongs: readings and writes to the device model, a verdict to the unit's verdicts,
//! the end to the status line, the rest to the panel that started it.

use super::{Notice, Station};
use crate::i18n::Text;
use crate::ui::Action;
use crate::ui::jobs::{Job, JobError, JobOutput, RunningJob};
use crate::ui::zh::Zh;

impl Station {
    /// Starts `job` on the link unless one is running; says why not in the status line.
    pub fn start_job(&mut self, job: Job) {
        if self.job.as_ref().is_some_and(|j| !j.is_done()) {
            self.notify(Notice::error(Text::new(
                "wait for the running job to finish, or cancel it",
                "请等待正在运行的任务结束,或取消它",
            )));
            return;
        }
        let Some(conn) = &self.link.connection else {
            self.notify(Notice::error(Text::new("not connected", "未连接")));
            return;
        };
        match RunningJob::spawn(job, conn.link.client(), &self.ctx) {
            Ok(job) => self.job = Some(job),
            Err(e) => self.notify(Notice::error(e.said())),
        }
    }

    /// Raises the running job's cancel flag.
    pub fn cancel_job(&self) {
        if let Some(j) = &self.job {
            j.cancel.cancel();
        }
    }

    /// What the running job has reported since the last frame (its progress is also kept on
    /// the job).
    pub fn take_job_output(&mut self) -> Vec<JobOutput> {
        self.job.as_mut().map(RunningJob::drain).unwrap_or_default()
    }

    /// The running job's title and progress (fraction done, what it is doing), if a job runs.
    pub fn job_progress(&self) -> Option<(&Text, f32, Text)> {
        let job = self.job.as_ref().filter(|j| !j.is_done())?;
        let (f, msg) = job
            .progress
            .as_ref()
            .map_or((0.0, Text::same("")), |p| (p.fraction(), p.message.clone()));
        Some((&job.title, f, msg))
    }

    /// The status line's message for a job that ended: its title, then its summary or why it
    /// failed.
    pub fn job_done(&mut self, result: Result<Text, JobError>) {
        let title = self
            .job
            .as_ref()
            .map_or_else(|| Text::new("job", "任务"), |j| j.title.clone());
        let notice = match result {
            Ok(summary) => Notice::info(title.then(": ", &summary)),
            Err(e) => Notice::error(title.then(": ", &e.said())),
        };
        self.notify(notice);
    }

    /// Delivers what the running job reported since the last frame; returns what the panel it
    /// went to asked for.
    pub(super) fn deliver_job_output(&mut self) -> Vec<Action> {
        let owner = self.job.as_ref().and_then(|j| j.owner);
        let mut actions = Vec::new();
        for out in self.take_job_output() {
            match out {
                JobOutput::Progress(_) => {}
                JobOutput::Read(id, r) => self.device.on_read(id, r),
                JobOutput::Wrote(set, r) => self.device.on_written(set, r),
                JobOutput::Verdict(v) => self.verdicts.take(v),
                JobOutput::Done(r) => self.job_done(r),
                JobOutput::Panel(out) => {
                    if let Some(to) = owner {
                        actions.extend(self.with_panels(|p, st| p.deliver(to, out, st)));
                    }
                }
            }
        }
        actions
    }
}
