//! The window cleaner's production self-test: a RON test plan (checked against the profile when
//! it opens, refused with line and column), run as a job with a progress bar and Cancel,
//! operator prompts as a modal that the job waits on, a results table, a PASS/FAIL banner, and
//! one JSON line per run appended to a log with the device's version and build info.

use super::jobs::{Job, JobError, JobOutput, LogError};
use super::station::Verdict;
use super::settings::FileKind;
use super::station::Station;
use super::{Action, files};
use crate::document::DocumentError;
use crate::i18n::Lang;
use crate::i18n::Text;
use crate::ops::selftest::{Interruption, Plan, Report, StepKind, StepResult};
use crate::ops::{Device, Run};
use crate::profile::Profile;
use crate::ui::zh::Zh;
use crossbeam_channel::Sender;
use eframe::egui;
use std::path::PathBuf;
use std::time::Duration;

pub mod said;

/// The plan offered first, relative to the working folder, until the app puts the shipped
/// plan's own path there ([`files::shipped_in`]).
pub const DEFAULT_PLAN: &str = "presets/window-cleaner-selftest.ron";
/// The log appended to unless the operator names another.
pub const DEFAULT_LOG: &str = "selftest-log.jsonl";

/// An operator prompt the running job waits on.
#[derive(Debug, Clone)]
pub struct Prompt {
    /// What the operator is asked to do.
    pub text: String,
    /// The answer: `true` done, `false` abort.
    answer: Sender<bool>,
}

/// The panel's state.
pub struct SelfTestPanel {
    /// The plan file's path.
    pub path: String,
    /// The log file's path (empty: no log).
    pub log_path: String,
    /// The plan opened (checked against the profile).
    pub plan: Option<Plan>,
    /// Why the last open failed, with line and column.
    pub error: Option<DocumentError>,
    /// Results of the run in progress (or the last), in step order. The last run's report is
    /// the station's verdict ([`crate::ui::station::Verdicts::selftest`]).
    pub results: Vec<StepResult>,
    /// Where the last record went, or why it could not be written.
    pub logged: Option<Result<PathBuf, LogError>>,
    /// A run is in progress.
    pub running: bool,
    /// The prompt the job waits on.
    pub prompt: Option<Prompt>,
    /// The results shown are a finished run's: they and its banner stay with the station's
    /// verdict on the unit ([`crate::ui::station::Verdicts`]), until the next run starts, the
    /// operator dismisses them or another unit identifies itself.
    pub reported: bool,
}

impl Default for SelfTestPanel {
    fn default() -> Self {
        Self {
            path: DEFAULT_PLAN.into(),
            log_path: DEFAULT_LOG.into(),
            plan: None,
            error: None,
            results: Vec::new(),
            logged: None,
            running: false,
            prompt: None,
            reported: false,
        }
    }
}

/// What this panel's jobs report (the verdict goes to the station).
#[derive(Debug, Clone)]
pub enum Output {
    /// A step's result.
    Step(StepResult),
    /// The job waits for the operator.
    Prompt(Prompt),
    /// The run ended: its results, and where its record went (or why it was not written).
    Done(Vec<StepResult>, Option<Result<PathBuf, LogError>>),
}

/// The unit of a step's first field, with a leading space (or empty).
fn unit(profile: &Profile, command: &str, fields: &[String]) -> String {
    profile
        .command(command)
        .and_then(|c| {
            let name = fields.first()?;
            c.reply.iter().find(|f| f.ident.eq_ignore_ascii_case(name))
        })
        .map_or(String::new(), |f| f.unit_suffix())
}

/// The pass/fail bounds of a step, as a person reads them (in display units), in `lang`.
pub fn bounds(kind: &StepKind, profile: &Profile, lang: Lang) -> String {
    match kind {
        StepKind::Range {
            min,
            max,
            command,
            fields,
            ..
        } => {
            let u = unit(profile, command, fields);
            format!("{min}{u} {} {max}{u}", lang.tr("to", "至"))
        }
        StepKind::Stable {
            max_spread,
            command,
            fields,
            ..
        } => format!(
            "{} ≤ {max_spread}{}",
            lang.tr("spread", "波动"),
            unit(profile, command, fields)
        ),
        StepKind::Rises {
            min_rise,
            command,
            fields,
            ..
        } => format!(
            "{} ≥ {min_rise}{}",
            lang.tr("rise", "上升"),
            unit(profile, command, fields)
        ),
        StepKind::Operator { bits, timeout, .. } => {
            let secs = timeout.as_secs_f64();
            match lang {
                Lang::En => format!("bits {bits:#06b} seen clear and set within {secs:.0} s"),
                Lang::Zh => format!("位 {bits:#06b}: {secs:.0} 秒内先清零、再置位"),
            }
        }
        StepKind::Reads { expect, .. } if expect.is_empty() => lang.tr("answers", "有应答").into(),
        StepKind::Reads {
            command, expect, ..
        } => expect
            .iter()
            .map(|(f, _, text)| format!("{} = {text}", field_name(profile, command, f, lang)))
            .collect::<Vec<_>>()
            .join(", "),
    }
}

/// Why a run of `plan` ended early (`step 'Fan current': ...`), in `lang`: its step by the
/// plan's name for it, the detail by [`said::detail`] with that step's command.
fn said_aborted(plan: &Plan, profile: &Profile, text: &str, lang: Lang) -> String {
    let step = plan
        .steps
        .iter()
        .find(|s| text.starts_with(&format!("step '{}'", s.name)));
    let Some(step) = step else {
        return said::detail(text, None, lang);
    };
    let quoted = format!("'{}'", step.name);
    let named = text.replacen(&quoted, &format!("'{}'", plan.said(&step.name, lang)), 1);
    said::detail(&named, profile.command(step.kind.command()), lang)
}

/// A command's name in `lang` (its wire name when the profile has no such command).
fn command_name(profile: &Profile, command: &str, lang: Lang) -> String {
    profile
        .command(command)
        .map_or(command.to_string(), |c| c.name.get(lang).to_string())
}

/// A reply field's name in `lang` (as written when the command has no such field).
fn field_name(profile: &Profile, command: &str, field: &str, lang: Lang) -> String {
    profile
        .command(command)
        .and_then(|c| c.reply.iter().find(|f| f.ident.eq_ignore_ascii_case(field)))
        .map_or(field.to_string(), |f| f.name.get(lang).to_string())
}

/// What a step reads (and does first), by the profile's names in `lang`.
fn what(kind: &StepKind, profile: &Profile, lang: Lang) -> String {
    let read = |command: &str, fields: &[String]| {
        let names: Vec<String> = fields
            .iter()
            .map(|f| field_name(profile, command, f, lang))
            .collect();
        format!(
            "{}: {}",
            command_name(profile, command, lang),
            names.join(", ")
        )
    };
    match kind {
        StepKind::Range {
            command, fields, ..
        }
        | StepKind::Stable {
            command, fields, ..
        } => read(command, fields),
        StepKind::Rises {
            action,
            command,
            fields,
            ..
        } => format!("{} → {}", action.text, read(command, fields)),
        StepKind::Operator { command, field, .. } => read(command, std::slice::from_ref(field)),
        StepKind::Reads { command, .. } => command_name(profile, command, lang),
    }
}

/// The colour of a run that ended with no verdict (interrupted): the self-test's, the
/// provisioning's.
pub(crate) const AMBER: egui::Color32 = egui::Color32::from_rgb(180, 90, 0);

/// Why a run has no verdict, naming the step (`link lost during Fan current`), in `lang`.
pub(crate) fn interruption_text(why: Interruption, step: &str, lang: Lang) -> String {
    match why {
        Interruption::LinkLost => match lang {
            Lang::En => format!("link lost during {step}"),
            Lang::Zh => format!("在“{step}”步骤中连接丢失"),
        },
        Interruption::Cancelled => match lang {
            Lang::En => format!("cancelled during {step}"),
            Lang::Zh => format!("在“{step}”步骤中被取消"),
        },
        Interruption::OperatorAborted => match lang {
            Lang::En => format!("aborted by the operator during {step}"),
            Lang::Zh => format!("操作员在“{step}”步骤中中止"),
        },
    }
}

impl SelfTestPanel {
    /// Opens the plan at `path`, checking it against the profile.
    pub fn open(&mut self, rt: &Station) {
        match Plan::load(&PathBuf::from(self.path.trim()), &rt.device.profile) {
            Ok(p) => {
                self.plan = Some(p);
                self.error = None;
            }
            Err(e) => {
                self.plan = None;
                self.error = Some(e);
            }
        }
        self.results.clear();
        self.reported = false;
        self.logged = None;
    }

    fn start(&mut self, rt: &Station) -> Option<Action> {
        let plan = self.plan.clone()?;
        let profile = rt.device.profile.clone();
        let log = PathBuf::from(self.log_path.trim());
        let mut records = rt.records.clone();
        let given = crate::ops::records::runs::Given {
            plan_sha256: crate::ops::records::record::file_sha256(std::path::Path::new(
                self.path.trim(),
            )),
            ..Default::default()
        };
        self.results.clear();
        self.reported = false;
        self.logged = None;
        self.running = true;
        Some(Action::StartJob(Job::new(
            Text::new("self-test", "自检"),
            move |client, cancel, sink| {
                let mut operator = |text: &str| -> bool {
                    let (tx, rx) = crossbeam_channel::bounded(1);
                    sink.panel(Output::Prompt(Prompt {
                        text: text.to_string(),
                        answer: tx,
                    }));
                    loop {
                        if cancel.is_cancelled() {
                            return false;
                        }
                        match rx.recv_timeout(Duration::from_millis(50)) {
                            Ok(answer) => return answer,
                            Err(crossbeam_channel::RecvTimeoutError::Timeout) => {}
                            // The window went away: nobody can answer.
                            Err(crossbeam_channel::RecvTimeoutError::Disconnected) => {
                                return false;
                            }
                        }
                    }
                };
                // Run, then record (before the verdict is shown), then the JSON-lines export.
                let recorded = crate::ops::records::runs::selftest(
                    Device::new(client, &profile),
                    &plan,
                    &given,
                    &mut operator,
                    &mut Run::new(cancel, |p| sink.progress(p)),
                    &mut |r| sink.panel(Output::Step(r.clone())),
                    &mut records,
                    (!log.as_os_str().is_empty()).then_some(log.as_path()),
                );
                let (report, kept) = (recorded.outcome, recorded.kept);
                let logged = recorded
                    .export
                    .map(|r| r.map(|()| log.clone()).map_err(|e| LogError::new(&log, &e)));
                let pass = report.pass;
                let failed = |lang: Lang| -> String {
                    let names: Vec<&str> = report.failed().map(|r| plan.said(&r.name, lang)).collect();
                    names.join(", ")
                };
                let why = match &report.aborted {
                    Some(a) => Text::new(
                        a.clone(),
                        said_aborted(&plan, &profile, a, Lang::Zh),
                    ),
                    None => Text::new(failed(Lang::En), failed(Lang::Zh)),
                };
                let results = report.results.clone();
                sink.send(JobOutput::Verdict(Verdict::SelfTest(Box::new(report))));
                sink.panel(Output::Done(results, logged.clone()));
                if let Some(Err(e)) = logged {
                    return Err(e.into());
                }
                if pass {
                    Ok(crate::ui::records::with_note(Text::new("PASS", "合格"), &kept))
                } else {
                    Err(JobError::Failed(crate::ui::records::with_note(why, &kept)))
                }
            },
        )))
    }

    /// Opens the plan at the path typed or chosen, and remembers the path if it opens.
    fn open_and_remember(&mut self, rt: &Station) -> Vec<Action> {
        self.open(rt);
        if self.plan.is_none() {
            return Vec::new();
        }
        vec![Action::RememberFile(
            FileKind::SelfTestPlan,
            self.path.trim().to_string(),
        )]
    }

    /// Forgets the last run's results once the station's verdict on its unit is gone (dismissed,
    /// or another unit identified itself).
    fn forget_gone_verdict(&mut self, rt: &Station) {
        if self.reported && !self.running && rt.verdicts.selftest.is_none() {
            self.results.clear();
            self.logged = None;
            self.reported = false;
        }
    }

    /// The report of the run shown: the station's verdict on its unit, once the run has ended.
    fn report<'a>(&self, rt: &'a Station) -> Option<&'a Report> {
        let ours = !self.running && self.reported;
        rt.verdicts.selftest.as_deref().filter(|_| ours)
    }

    /// Draws the panel.
    fn draw(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &Station) -> Vec<Action> {
        let mut actions = Vec::new();
        let busy = rt.job_progress().is_some();
        if self.running
            && !busy
            && self.report(rt).is_none()
            && rt.job.as_ref().is_none_or(|j| j.is_done())
        {
            // The job ended without a report (it could not start).
            self.running = false;
        }
        crate::ui::layout::toolbar(ui, |ui| {
            let event = files::row(
                ui,
                lang,
                files::Row {
                    label: lang.tr("Test plan", "测试方案"),
                    hint: "window-cleaner-selftest.ron",
                    pick: files::Pick::Open(&["ron"]),
                    enabled: !self.running,
                },
                &mut self.path,
                &rt.dialogs,
            );
            let open = ui
                .add_enabled(
                    !self.running,
                    egui::Button::new(lang.tr("Open plan", "打开方案")),
                )
                .clicked();
            if event.go(open, &mut actions) {
                actions.extend(self.open_and_remember(rt));
            }
        });
        crate::ui::layout::toolbar(ui, |ui| {
            let event = files::row(
                ui,
                lang,
                files::Row {
                    label: lang.tr("Log file (JSON lines)", "日志文件(JSON 行)"),
                    hint: lang.tr("empty: no log", "留空:不记录"),
                    pick: files::Pick::Save(DEFAULT_LOG),
                    enabled: !self.running,
                },
                &mut self.log_path,
                &rt.dialogs,
            );
            event.go(false, &mut actions);
        });
        if let Some(e) = &self.error {
            ui.colored_label(
                egui::Color32::RED,
                format!(
                    "{}\n{}",
                    lang.tr("The plan was refused:", "测试方案被拒绝:"),
                    e.in_lang(lang)
                ),
            );
        }
        let Some(plan) = &self.plan else {
            if self.error.is_none() {
                ui.weak(lang.tr("Open a test plan to start.", "请先打开测试方案。"));
            }
            return actions;
        };
        let (name, steps) = (plan.said(&plan.name, lang).to_string(), plan.steps.len());
        crate::ui::layout::toolbar(ui, |ui| {
            ui.strong(name);
            ui.weak(format!("{steps} {}", lang.tr("steps", "个步骤")));
            let can_run = rt.connected() && !busy && !self.running;
            if ui
                .add_enabled(
                    can_run,
                    egui::Button::new(lang.tr("Run self-test", "运行自检")),
                )
                .clicked()
            {
                let log = self.log_path.trim().to_string();
                if !log.is_empty() {
                    actions.push(Action::RememberFile(FileKind::SelfTestLog, log));
                }
                actions.extend(self.start(rt));
            }
            if self.running && ui.button(lang.tr("Cancel", "取消")).clicked() {
                actions.push(Action::CancelJob);
            }
        });
        if self.running
            && let Some((_, fraction, msg)) = rt.job_progress()
        {
            ui.add(
                egui::ProgressBar::new(fraction)
                    .show_percentage()
                    .text(msg.get(lang)),
            );
        }
        actions.extend(self.banner(ui, lang, rt));
        ui.separator();
        self.table(ui, lang, rt);
        self.prompt_modal(ui, lang);
        actions
    }

    /// The verdict's banner: PASS, FAIL naming the steps the unit failed, or NO VERDICT when
    /// the run was interrupted (`link lost during <step>`) before any step failed; with
    /// Dismiss. Returns [`Action::DismissVerdicts`] when clicked.
    fn banner(&self, ui: &mut egui::Ui, lang: Lang, rt: &Station) -> Option<Action> {
        let report = self.report(rt)?;
        let said = |name: &str| match &self.plan {
            Some(plan) => plan.said(name, lang).to_string(),
            None => name.to_string(),
        };
        let failed: Vec<String> = report.failed().map(|r| said(&r.name)).collect();
        let interrupted = report
            .interrupted()
            .map(|(r, why)| interruption_text(why, &said(&r.name), lang));
        let (head, color) = if report.pass {
            ("PASS", egui::Color32::from_rgb(0, 140, 60))
        } else if failed.is_empty() && interrupted.is_some() {
            (lang.tr("NO VERDICT", "无结论"), AMBER)
        } else {
            ("FAIL", egui::Color32::from_rgb(200, 30, 30))
        };
        let white = |t: String| egui::RichText::new(t).color(egui::Color32::WHITE);
        let mut dismissed = false;
        egui::Frame::new()
            .fill(color)
            .inner_margin(8.0)
            .show(ui, |ui| {
                ui.set_width(ui.available_width());
                ui.horizontal(|ui| {
                    ui.label(white(head.into()).size(28.0).strong());
                    ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                        dismissed = ui.button(lang.tr("Dismiss", "关闭结论")).clicked();
                    });
                });
                if !failed.is_empty() {
                    let line = format!("{} {}", lang.tr("Failed:", "未通过:"), failed.join(", "));
                    ui.label(white(line));
                }
                match (&interrupted, &report.aborted) {
                    (Some(text), _) => {
                        ui.label(white(text.clone()).strong());
                        if failed.is_empty() {
                            ui.label(white(
                                lang.tr(
                                    "Nothing is known of the steps not run: test this unit again.",
                                    "未运行的步骤没有结果:请重新测试本机。",
                                )
                                .into(),
                            ));
                        }
                    }
                    (None, Some(a)) => {
                        let line = format!(
                            "{} {}",
                            lang.tr("Ended early:", "提前结束:"),
                            self.aborted(a, rt, lang)
                        );
                        ui.label(white(line));
                    }
                    (None, None) => {}
                }
            });
        if let Some(d) = &report.device {
            ui.monospace(format!(
                "{} {}",
                lang.tr("Device:", "设备:"),
                said::device(d, lang)
            ));
        }
        if !report.safe_state.is_empty() {
            let lines: Vec<String> = report
                .safe_state
                .iter()
                .map(|l| said::detail(l, None, lang))
                .collect();
            ui.weak(format!(
                "{} {}",
                lang.tr("Started from the safe state:", "从安全状态开始:"),
                lines.join("; ")
            ));
        }
        match &self.logged {
            Some(Ok(p)) => {
                ui.label(format!(
                    "{} {}",
                    lang.tr("Record appended to", "记录已追加到"),
                    p.display()
                ));
            }
            Some(Err(e)) => {
                ui.colored_label(egui::Color32::RED, e.in_lang(lang));
            }
            None => {
                ui.weak(lang.tr("Not logged (no log file).", "未记录(未指定日志文件)。"));
            }
        }
        dismissed.then_some(Action::DismissVerdicts)
    }

    /// Why the run shown ended early, in `lang` ([`said_aborted`]).
    fn aborted(&self, text: &str, rt: &Station, lang: Lang) -> String {
        match &self.plan {
            Some(plan) => said_aborted(plan, &rt.device.profile, text, lang),
            None => said::detail(text, None, lang),
        }
    }

    fn table(&self, ui: &mut egui::Ui, lang: Lang, rt: &Station) {
        let profile = &rt.device.profile;
        let reported = self.report(rt).is_some();
        let Some(plan) = &self.plan else { return };
        egui::ScrollArea::both().auto_shrink(false).show(ui, |ui| {
            // Four text columns share what the PASS/FAIL column leaves, the names of what is
            // read taking the most; names wrap between words only, and Measured and Result
            // stay in the window at 1024 px.
            let gap = ui.spacing().item_spacing.x;
            let share = (ui.available_width() - 60.0 - 5.0 * gap).max(320.0);
            let [w_check, w_reads, w_bounds, w_measured] =
                [0.2, 0.34, 0.24, 0.22].map(|f| share * f);
            let words = |ui: &mut egui::Ui,
                         w: f32,
                         text: &str,
                         style: fn(egui::RichText) -> egui::RichText| {
                crate::ui::layout::words_cell(ui, w, text, style);
            };
            let cell = |ui: &mut egui::Ui, text: egui::RichText| {
                crate::ui::layout::wrapped_cell(ui, w_measured, egui::Label::new(text));
            };
            crate::ui::layout::table(ui, egui::Grid::new("selftest-results"), &[
                            lang.tr("Check", "检查项"),
                            lang.tr("Reads", "读取"),
                            lang.tr("Bounds", "判定范围"),
                            lang.tr("Measured", "测量值"),
                            lang.tr("Result", "结果"),
                        ], |ui| {
                    // The identity step appears only when it failed.
                    for r in self.results.iter().filter(|r| r.kind == "Identify") {
                        let (en, zh) = said::IDENTITY_STEP;
                        words(ui, w_check, lang.tr(en, zh), |t| t);
                        words(ui, w_reads, "CMD_VERSION", |t| t);
                        words(ui, w_bounds, "—", |t| t);
                        let cmd = profile.command("CMD_VERSION");
                        cell(ui, said::detail(&r.detail, cmd, lang).into());
                        ui.colored_label(egui::Color32::RED, "FAIL");
                        ui.end_row();
                    }
                    let done = self.results.iter().filter(|r| r.kind != "Identify").count();
                    for (i, step) in plan.steps.iter().enumerate() {
                        words(ui, w_check, plan.said(&step.name, lang), |t| t);
                        words(ui, w_reads, &what(&step.kind, profile, lang), |t| t.weak());
                        words(ui, w_bounds, &bounds(&step.kind, profile, lang), |t| {
                            t.monospace()
                        });
                        match self.results.iter().find(|r| r.name == step.name) {
                            Some(r) if r.interrupted.is_some() => {
                                let cmd = profile.command(step.kind.command());
                                cell(ui, said::detail(&r.detail, cmd, lang).into());
                                ui.colored_label(AMBER, lang.tr("interrupted", "中断"));
                            }
                            Some(r) => {
                                let cmd = profile.command(step.kind.command());
                                cell(ui, said::detail(&r.detail, cmd, lang).into());
                                if r.pass {
                                    ui.colored_label(egui::Color32::from_rgb(0, 140, 60), "PASS");
                                } else {
                                    ui.colored_label(egui::Color32::RED, "FAIL");
                                }
                            }
                            None if self.running && i == done => {
                                ui.label(lang.tr("running…", "进行中…"));
                                ui.label("");
                            }
                            None if reported => {
                                ui.weak(lang.tr("not run", "未运行"));
                                ui.label("");
                            }
                            None => {
                                ui.label("");
                                ui.label("");
                            }
                        }
                        ui.end_row();
                    }
                });
        });
    }

    fn prompt_modal(&mut self, ui: &mut egui::Ui, lang: Lang) {
        let Some(prompt) = &self.prompt else { return };
        let text = match &self.plan {
            Some(plan) => plan.said(&prompt.text, lang),
            None => prompt.text.as_str(),
        };
        let mut answer = None;
        egui::Modal::new(egui::Id::unique("selftest-prompt")).show(ui.ctx(), |ui| {
            ui.heading(lang.tr("Operator action needed", "需要操作员操作"));
            ui.label(egui::RichText::new(text).size(18.0));
            ui.label(lang.tr(
                "Do it now, then press Done: the test watches for the result.",
                "请立即操作,然后按“完成”:测试将检测结果。",
            ));
            ui.horizontal(|ui| {
                if ui.button(lang.tr("Done", "完成")).clicked() {
                    answer = Some(true);
                }
                if ui.button(lang.tr("Abort test", "中止测试")).clicked() {
                    answer = Some(false);
                }
            });
        });
        // Closing by Escape or a click outside is not an answer: the job keeps waiting.
        if let Some(a) = answer
            && let Some(p) = self.prompt.take()
        {
            let _ = p.answer.send(a);
        }
    }

    /// Shows `results` as a finished run's, beside the station's verdict on the unit (the
    /// screenshot tour's run).
    pub(crate) fn show_finished(&mut self, results: Vec<StepResult>) {
        self.take_output(Output::Done(results, None));
    }

    /// Takes what one of its jobs reported.
    fn take_output(&mut self, out: Output) {
        match out {
            Output::Step(r) => self.results.push(r),
            Output::Prompt(p) => self.prompt = Some(p),
            Output::Done(results, logged) => {
                self.results = results;
                self.reported = true;
                self.logged = logged;
                self.running = false;
                self.prompt = None;
            }
        }
    }
}

impl crate::ui::PanelId {
    /// The window cleaner's production self-test.
    pub const SELF_TEST: crate::ui::PanelId = crate::ui::PanelId::new("SelfTest");
}

impl crate::ui::Panel for SelfTestPanel {
    fn id(&self) -> crate::ui::PanelId {
        crate::ui::PanelId::SELF_TEST
    }

    fn name(&self, lang: Lang) -> &'static str {
        lang.tr("Self-test", "产线自检")
    }

    fn kind(&self) -> Option<crate::profile::PanelKind> {
        Some(crate::profile::PanelKind::SelfTest)
    }

    fn show(&mut self, ui: &mut egui::Ui, cx: &crate::ui::panel::Cx<'_>) -> Vec<Action> {
        self.draw(ui, cx.lang, cx.station)
    }

    fn tick(&mut self, station: &Station) -> Vec<Action> {
        self.forget_gone_verdict(station);
        Vec::new()
    }

    /// An operator prompt is answered on this panel: it asks to be shown.
    fn on_output(&mut self, out: crate::ui::panel::PanelOutput, _station: &Station) -> Vec<Action> {
        let Some(out) = out.take::<Output>() else {
            return Vec::new();
        };
        let prompt = matches!(out, Output::Prompt(_));
        self.take_output(out);
        if prompt {
            vec![Action::ShowPanel(crate::ui::PanelId::SELF_TEST)]
        } else {
            Vec::new()
        }
    }

    /// The plan and log last used; the shipped plan when none was used yet.
    fn restore(&mut self, settings: &crate::ui::Settings) {
        if let Some(p) = settings.file(FileKind::SelfTestLog) {
            self.log_path = p.to_string();
        }
        if let Some(p) = crate::ui::app::file_or_shipped(
            settings,
            FileKind::SelfTestPlan,
            "window-cleaner-selftest.ron",
        ) {
            self.path = p;
        }
    }
}
