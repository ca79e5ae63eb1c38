//! The production tab: load a plan, choose the CSV log, "Provision next" for each fresh servo,
//! a clear PASS/FAIL banner that names the failed step (NO VERDICT, amber, when the link was
//! lost during a step), and the records of this session.

use super::{Output, error_label, send};
use crate::document::DocumentError;
use crate::i18n::Lang;
use crate::i18n::Text;
use crate::ops::servo::provision::{self as prov, Outcome, Plan, ProvisionState, Record};
use crate::ops::{Device, Run};
use crate::ui::jobs::{Job, JobError, LogError};
use crate::ui::layout::header_row;
use crate::ui::settings::FileKind;
use crate::ui::station::Station;
use crate::ui::zh::Zh;
use crate::ui::{Action, files};
use eframe::egui;
use std::path::PathBuf;

/// The production tab's state.
#[derive(Default)]
pub struct ProvisionPanel {
    /// The plan file, typed or chosen.
    pub plan_path: String,
    /// The plan loaded (checked against the profile).
    pub plan: Option<Plan>,
    /// Why the plan did not load (with line and column).
    pub plan_error: Option<DocumentError>,
    /// The CSV log, typed or chosen (empty: no log).
    pub log_path: String,
    /// Ids given out in this session.
    pub state: ProvisionState,
    /// Every record of this session, newest last.
    pub history: Vec<Record>,
    /// Why the last record could not be logged (or the log cannot be written).
    pub log_error: Option<LogError>,
    /// A servo's provisioning runs: the last servo's banner is not shown meanwhile.
    pub running: bool,
    /// The operator dismissed the last servo's banner (until the next servo's record).
    pub dismissed: bool,
}

impl ProvisionPanel {
    /// Loads the plan at the path.
    pub fn load(&mut self, rt: &Station) {
        let path = PathBuf::from(self.plan_path.trim());
        match Plan::load(&path, &rt.device.profile) {
            Ok(plan) => {
                self.plan = Some(plan);
                self.plan_error = None;
                self.state = ProvisionState::new();
            }
            Err(e) => {
                self.plan = None;
                self.plan_error = Some(e);
            }
        }
    }

    /// Takes the record of the servo just provisioned (the ids given out so far in `state`,
    /// why it could not be logged): its banner is shown until dismissed or the next run.
    pub(crate) fn on_record(
        &mut self,
        record: Record,
        state: ProvisionState,
        log_error: Option<LogError>,
    ) {
        self.state = state;
        self.log_error = log_error;
        self.history.push(record);
        self.running = false;
        self.dismissed = false;
    }

    /// The plan loaded: its rate, ids, parameters and what it records, and the ids given out in
    /// this session.
    fn plan_summary(&self, ui: &mut egui::Ui, lang: Lang, rt: &Station) {
        let Some(plan) = &self.plan else {
            return;
        };
        // The recorded parameters by their names in the window's language.
        let profile = &rt.device.profile;
        let recorded: Vec<&str> = plan
            .record
            .iter()
            .map(|ident| {
                profile.find_param(ident).map_or(ident.as_str(), |p| {
                    lang.tr(&p.field.name.en, &p.field.name.zh)
                })
            })
            .collect();
        let ids = match &plan.ids {
            prov::IdSequence::Start(s) => format!("{} {s}", lang.tr("from", "起始")),
            prov::IdSequence::List(l) => format!("{l:?}"),
        };
        ui.label(format!(
            "{}: {} {} · {}: {ids} · {} {} · {}: {}",
            lang.tr("Target", "目标"),
            plan.target_baud,
            lang.tr("baud", "波特"),
            lang.tr("ids", "ID"),
            plan.params.len(),
            lang.tr("parameters", "个参数"),
            lang.tr("recorded", "记录"),
            recorded.join(", ")
        ));
        if !self.state.assigned.is_empty() {
            ui.weak(format!(
                "{}: {:?}",
                lang.tr("Ids given this session", "本次已分配ID"),
                self.state.assigned
            ));
        }
    }

    /// Provision next: the CSV log checked against the plan first (a log that does not fit is
    /// said, and nothing starts), then the job.
    fn start(&mut self, rt: &Station) -> Vec<Action> {
        let mut actions = Vec::new();
        let Some(plan) = self.plan.clone() else {
            return actions;
        };
        let log = Some(PathBuf::from(self.log_path.trim())).filter(|p| !p.as_os_str().is_empty());
        match log
            .as_deref()
            .map(|path| (path, prov::check_log(path, &plan.record)))
        {
            Some((path, Err(e))) => {
                self.log_error = Some(LogError {
                    path: path.to_path_buf(),
                    reason: e.message().to_string(),
                });
            }
            _ => {
                self.log_error = None;
                if let Some(path) = &log {
                    actions.push(Action::RememberFile(
                        FileKind::ProvisionLog,
                        path.display().to_string(),
                    ));
                }
                let plan_file = Some(PathBuf::from(self.plan_path.trim()));
                actions.push(job(rt, plan, self.state.clone(), log, plan_file));
                // The last servo's banner goes as the next servo's run starts.
                self.running = true;
            }
        }
        actions
    }

    /// Draws the tab.
    pub(super) fn show(
        &mut self,
        ui: &mut egui::Ui,
        lang: Lang,
        rt: &Station,
        busy: bool,
    ) -> Vec<Action> {
        let mut actions = Vec::new();
        crate::ui::layout::toolbar(ui, |ui| {
            let event = files::row(
                ui,
                lang,
                files::Row {
                    label: lang.tr("Plan", "计划文件"),
                    hint: "servo-provision-plan.ron",
                    pick: files::Pick::Open(&["ron"]),
                    enabled: true,
                },
                &mut self.plan_path,
                &rt.dialogs,
            );
            let load = ui
                .add_enabled(
                    !self.plan_path.trim().is_empty(),
                    egui::Button::new(lang.tr("Load plan", "载入计划")),
                )
                .clicked();
            if event.go(load, &mut actions) {
                self.load(rt);
                if self.plan.is_some() {
                    actions.push(Action::RememberFile(
                        FileKind::ProvisionPlan,
                        self.plan_path.trim().to_string(),
                    ));
                }
            }
        });
        if let Some(e) = &self.plan_error {
            error_label(ui, e.in_lang(lang));
        }
        crate::ui::layout::toolbar(ui, |ui| {
            let event = files::row(
                ui,
                lang,
                files::Row {
                    label: lang.tr("CSV log", "CSV日志"),
                    hint: lang.tr("empty: no log", "留空:不记录日志"),
                    pick: files::Pick::Save("servo-provision.csv"),
                    enabled: true,
                },
                &mut self.log_path,
                &rt.dialogs,
            );
            event.go(false, &mut actions);
        });
        self.plan_summary(ui, lang, rt);
        ui.add_space(6.0);
        let can = rt.connected() && !busy && self.plan.is_some();
        let next = ui.add_enabled(
            can,
            egui::Button::new(
                egui::RichText::new(lang.tr("Provision next", "烧录下一个"))
                    .size(22.0)
                    .strong(),
            )
            .min_size(egui::vec2(260.0, 56.0)),
        );
        if next.clicked() {
            actions.extend(self.start(rt));
        }
        if let Some(e) = &self.log_error {
            error_label(ui, e.in_lang(lang));
        }
        ui.add_space(6.0);
        if self.running && !busy {
            // The job ended without a record (it could not start): the status line says why.
            self.running = false;
        }
        if self.running {
            ui.label(lang.tr("Provisioning this servo…", "正在烧录本舵机…"));
        } else if let Some(last) = self.history.last().filter(|_| !self.dismissed)
            && banner(ui, lang, last)
        {
            self.dismissed = true;
            actions.push(Action::DismissVerdicts);
        }
        if !self.history.is_empty() {
            ui.add_space(6.0);
            ui.label(self.tally(lang));
            history(ui, lang, &self.history);
        }
        actions
    }

    /// `This session (2 passed, 1 failed)`, and `, 1 no verdict` when a link was lost: a servo
    /// whose link was lost during a step is counted neither passed nor failed.
    fn tally(&self, lang: Lang) -> String {
        let count = |f: fn(&Outcome) -> bool| self.history.iter().filter(|r| f(&r.result)).count();
        let lost = count(|o| o.link_lost().is_some());
        let no_verdict = match lost {
            0 => String::new(),
            n => format!(", {n} {}", lang.tr("no verdict", "无结论")),
        };
        format!(
            "{} ({} {}, {} {}{no_verdict})",
            lang.tr("This session", "本次记录"),
            count(Outcome::is_pass),
            lang.tr("passed", "通过"),
            count(Outcome::is_fail),
            lang.tr("failed", "失败"),
        )
    }
}

/// `link lost during <step>` in `lang`, the step as provisioning names it
/// ([`prov::step::said`]), as the self-test says it.
fn link_lost_during(step: &str, lang: Lang) -> String {
    let said = prov::step::said(step);
    let link_lost = crate::ops::selftest::Interruption::LinkLost;
    crate::ui::selftest::interruption_text(link_lost, said.get(lang), lang)
}

/// The big PASS / FAIL / NO VERDICT banner of the last servo, with Dismiss; returns whether it
/// was clicked.
fn banner(ui: &mut egui::Ui, lang: Lang, r: &Record) -> bool {
    let (fill, head, detail) = match &r.result {
        Outcome::Pass => (
            egui::Color32::from_rgb(30, 140, 60),
            "PASS".to_string(),
            format!(
                "{} {} · {} {} · {} {}",
                lang.tr("id", "ID"),
                r.id.map_or("-".into(), |v| v.to_string()),
                r.baud.map_or("-".into(), |v| v.to_string()),
                lang.tr("baud", "波特"),
                lang.tr("serial", "序列号"),
                r.serial.map_or("-".into(), |v| v.to_string()),
            ),
        ),
        Outcome::Fail { step, reason } => (
            egui::Color32::from_rgb(190, 30, 30),
            format!("FAIL · {} {step}", lang.tr("step", "步骤")),
            reason.clone(),
        ),
        Outcome::LinkLost { step, reason } => (
            crate::ui::selftest::AMBER,
            format!(
                "{} · {}",
                lang.tr("NO VERDICT", "无结论"),
                link_lost_during(step, lang)
            ),
            format!(
                "{}\n{}",
                lost_port_in(reason, lang),
                lang.tr(
                    "The servo did not fail: nothing is known of the steps not done. Provision it again.",
                    "舵机并未失败:未完成的步骤没有结果。请重新烧录。",
                )
            ),
        ),
    };
    let mut dismissed = false;
    egui::Frame::new()
        .fill(fill)
        .inner_margin(12.0)
        .corner_radius(6.0)
        .show(ui, |ui| {
            ui.set_min_width(ui.available_width());
            ui.horizontal(|ui| {
                ui.label(
                    egui::RichText::new(head)
                        .size(30.0)
                        .strong()
                        .color(egui::Color32::WHITE),
                );
                ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                    dismissed = ui.button(lang.tr("Dismiss", "关闭结论")).clicked();
                });
            });
            ui.label(
                egui::RichText::new(detail)
                    .size(15.0)
                    .color(egui::Color32::WHITE),
            );
            for m in &r.mismatches {
                ui.label(egui::RichText::new(m).color(egui::Color32::WHITE));
            }
        });
    dismissed
}

/// The session's records, newest first: one row each, its last column the details (why it
/// failed or had no verdict, and the values the servo does not hold), wrapped within the
/// window's width so that nothing pushes a column out of view.
fn history(ui: &mut egui::Ui, lang: Lang, records: &[Record]) {
    egui::Grid::new("servo-provision-history")
        .striped(true)
        .num_columns(6)
        .show(ui, |ui| {
            header_row(
                ui,
                &[
                    lang.tr("Time", "时间"),
                    lang.tr("Serial", "序列号"),
                    lang.tr("ID", "ID"),
                    lang.tr("Baud", "波特率"),
                    lang.tr("Result", "结果"),
                    lang.tr("Details", "详情"),
                ],
            );
            for r in records.iter().rev() {
                ui.label(&r.time);
                ui.label(r.serial.map_or("-".into(), |v| v.to_string()));
                ui.label(r.id.map_or("-".into(), |v| v.to_string()));
                ui.label(r.baud.map_or("-".into(), |v| v.to_string()));
                let reason = match &r.result {
                    Outcome::Pass => {
                        super::ok_label(ui, "PASS");
                        None
                    }
                    Outcome::Fail { step, reason } => {
                        error_label(ui, format!("FAIL ({step})"));
                        Some(reason.clone())
                    }
                    Outcome::LinkLost { step, reason } => {
                        let head = lang.tr("NO VERDICT", "无结论");
                        let during = link_lost_during(step, lang);
                        ui.colored_label(crate::ui::selftest::AMBER, format!("{head}: {during}"));
                        Some(lost_port_in(reason, lang))
                    }
                };
                ui.add(egui::Label::new(details(reason, &r.mismatches, lang)).wrap());
                ui.end_row();
            }
        });
}

/// A history row's details: the reason, then the values the servo does not hold.
fn details(reason: Option<String>, mismatches: &[String], lang: Lang) -> egui::RichText {
    let mut parts: Vec<String> = reason.into_iter().collect();
    if !mismatches.is_empty() {
        let head = lang.tr("not as written", "与写入值不一致");
        parts.push(format!("{head}: {}", mismatches.join("; ")));
    }
    egui::RichText::new(parts.join(" · ")).weak()
}

/// Why the port was lost (`reason`, as the link wrote it) in `lang`.
fn lost_port_in(reason: &str, lang: Lang) -> String {
    match lang {
        Lang::En => reason.to_string(),
        Lang::Zh => crate::ui::zh::lost_port(reason),
    }
}

fn job(
    rt: &Station,
    plan: Plan,
    mut state: ProvisionState,
    log: Option<PathBuf>,
    plan_file: Option<PathBuf>,
) -> Action {
    let profile = rt.device.profile.clone();
    let mut records = rt.records.clone();
    let given = crate::ops::records::runs::Given {
        plan_sha256: plan_file
            .as_deref()
            .and_then(crate::ops::records::record::file_sha256),
        plan_name: plan_file
            .as_deref()
            .map(crate::ops::records::runs::plan_name),
        ..Default::default()
    };
    Action::StartJob(Job::new(
        Text::new("provision", "烧录"),
        move |client, cancel, sink| {
            // Run, then record (before the verdict is shown), then the CSV export.
            let recorded = crate::ops::records::runs::provision(
                Device::new(client, &profile),
                &plan,
                &mut state,
                &given,
                &mut Run::new(cancel, |p| sink.progress(p)),
                &mut records,
                log.as_deref(),
            );
            let (record, kept) = (recorded.outcome, recorded.kept);
            let log_error = match (recorded.export, log.as_deref()) {
                (Some(Err(e)), Some(path)) => Some(LogError::new(path, &e)),
                _ => None,
            };
            let summary = match &record.result {
                Outcome::Pass => {
                    let id = record.id.map_or("-".into(), |v| v.to_string());
                    let baud = record.baud.map_or("-".into(), |v| v.to_string());
                    Ok(crate::ui::records::with_note(
                        Text::new(
                            format!("PASS: servo {id} at {baud} baud"),
                            format!("合格:舵机 {id},波特率 {baud}"),
                        ),
                        &kept,
                    ))
                }
                Outcome::Fail { step, reason } => Err(JobError::StepFailed {
                    step: step.clone(),
                    reason: reason.clone() + &crate::ui::records::note_en(&kept),
                }),
                Outcome::LinkLost { step, reason } => Err(JobError::LinkLostDuring {
                    step: prov::step::said(step),
                    why: reason.clone() + &crate::ui::records::note_en(&kept),
                }),
            };
            sink.send(crate::ui::jobs::JobOutput::Verdict(
                crate::ui::station::Verdict::Provisioned(Box::new(record.clone())),
            ));
            send(
                sink,
                Output::Provisioned {
                    record,
                    state,
                    log_error: log_error.clone(),
                },
            );
            match (summary, log_error) {
                (Ok(_), Some(e)) => Err(e.into()),
                (s, _) => s,
            }
        },
    ))
}
