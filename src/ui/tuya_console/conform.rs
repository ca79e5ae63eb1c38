//! The conformance grade (issue 26, item 9): Run conformance grades the MCU's firmware against
//! the protocol ([`crate::ops::tuya::conform`]) as a job; the table of checks with PASS/FAIL and
//! the bytes that show each; the verdict; and Save report (JSON) to a file. Every grade is
//! recorded as `tuya conform` records it (run, then record).

use super::{Action, Output, Station};
use crate::i18n::{Lang, Text};
use crate::ops::tuya::conform::{self, Check, Conformance, Grade};
use crate::ops::{Device, Progress, Run};
use crate::ui::files;
use crate::ui::jobs::{Job, JobError};
use crate::ui::zh::Zh;
use eframe::egui;
use std::path::PathBuf;
use std::sync::Arc;

const GREEN: egui::Color32 = egui::Color32::from_rgb(40, 160, 60);
const ORANGE: egui::Color32 = egui::Color32::from_rgb(220, 150, 0);
/// The name Save report proposes.
const DEFAULT_REPORT: &str = "tuya-conformance.json";

/// The conformance tab's state.
#[derive(Debug, Default)]
pub struct ConformView {
    /// The last grade, or why it could not run.
    pub result: Option<Result<Conformance, JobError>>,
    /// Checks done so far by the running grade.
    pub checks: Vec<Check>,
    /// A grade was started and has not ended.
    pub running: bool,
    /// Where Save report writes, typed or chosen.
    pub save_path: String,
    /// What the last save did: the file written, or why not.
    pub saved: Option<Result<PathBuf, String>>,
}

/// The job: grades the MCU, each check sent to the panel as it ends, then records the run as
/// `tuya conform` does (kind `tuya_conform`, one step per check; kept before the verdict is
/// shown, in the spool when its store is away, as the verdict's note says).
fn work(profile: Arc<crate::profile::Profile>, records: crate::ui::records::RecordsHandle) -> Job {
    let mut records = records;
    Job::new(
        Text::new("Tuya conformance", "涂鸦协议一致性"),
        move |client, cancel, sink| {
            let options = conform::Options {
                ota: None,
                ota_max: profile.ota_max_bytes(),
            };
            let mut n = 0u64;
            let recorded = crate::ops::records::runs::tuya_conform(
                Device::new(client, &profile),
                &options,
                &crate::ops::records::runs::Given::default(),
                &mut Run::quiet(cancel),
                &mut |c| {
                    n += 1;
                    sink.panel(Output::ConformCheck(c.clone()));
                    sink.progress(Progress {
                        done: n,
                        total: 18,
                        message: Text::new(
                            format!("{}: {}", c.id, c.grade.word()),
                            format!("{}:{}", c.id, c.grade.word()),
                        ),
                    });
                },
                &mut records,
            );
            let result = recorded.outcome.map_err(JobError::from);
            sink.panel(Output::ConformDone(result.clone()));
            let kept = recorded.kept;
            result
                .map(|c| {
                    let (verdict, zh) = if c.pass() {
                        ("CONFORMS", "符合协议")
                    } else {
                        ("DOES NOT CONFORM", "不符合协议")
                    };
                    let summary = Text::new(
                        format!("{verdict} ({} checks, {:.1} s)", c.checks.len(), c.seconds),
                        format!("{zh}({} 项检查,{:.1} 秒)", c.checks.len(), c.seconds),
                    );
                    crate::ui::records::with_note(summary, &kept)
                })
                .map_err(|e| {
                    if kept.stored() {
                        e
                    } else {
                        JobError::Failed(crate::ui::records::with_note(e.said(), &kept))
                    }
                })
        },
    )
}

impl ConformView {
    /// Takes what the grade reported.
    pub fn on_output(&mut self, out: Output) {
        match out {
            Output::ConformCheck(c) => self.checks.push(c),
            Output::ConformDone(r) => {
                self.running = false;
                self.result = Some(r);
            }
            Output::OtaProgress(_) | Output::OtaDone(_) => {}
        }
    }

    /// Draws the tab.
    pub fn show(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &Station) -> Vec<Action> {
        let mut actions = Vec::new();
        ui.weak(lang.tr(
            "Grades the MCU firmware against the Tuya serial protocol: heartbeat, product info, working mode, Wi-Fi state, a status query (every data point, its type, length and range), each writable data point sent the value it reports, report-only ones refused, a bad checksum and an unknown command ignored, every answer within 5 s.",
            "按涂鸦串口协议评定MCU固件:心跳、产品信息、工作模式、WiFi状态、状态查询(每个数据点的类型、长度与范围)、每个可写数据点下发其当前值、只上报数据点拒绝下发、错误校验和与未知命令被忽略、每个应答在5秒内。",
        ));
        let busy = rt.job_progress().is_some();
        crate::ui::layout::toolbar(ui, |ui| {
            let run = ui.add_enabled(
                rt.connected() && !busy,
                egui::Button::new(lang.tr("Run conformance", "运行一致性评定")),
            );
            if run.clicked() {
                self.running = true;
                self.checks.clear();
                self.result = None;
                self.saved = None;
                actions.push(Action::StartJob(work(
                    rt.device.profile.clone(),
                    rt.records.clone(),
                )));
            }
            if self.running && busy && ui.button(lang.tr("Cancel", "取消")).clicked() {
                actions.push(Action::CancelJob);
            }
        });
        verdict(ui, lang, self.result.as_ref());
        table(ui, lang, &self.checks);
        if matches!(self.result, Some(Ok(_))) {
            self.save_row(ui, lang, rt, &mut actions);
        }
        actions
    }

    /// Save report: the grade as JSON to the file in the box.
    fn save_row(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &Station, actions: &mut Vec<Action>) {
        crate::ui::layout::toolbar(ui, |ui| {
            let event = files::row(
                ui,
                lang,
                files::Row {
                    label: lang.tr("Report file", "报告文件"),
                    hint: DEFAULT_REPORT,
                    pick: files::Pick::Save(DEFAULT_REPORT),
                    enabled: true,
                },
                &mut self.save_path,
                &rt.dialogs,
            );
            let pressed = ui.button(lang.tr("Save report", "保存报告")).clicked();
            if event.go(pressed, actions)
                && let Some(Ok(grade)) = &self.result
            {
                self.saved = Some(save(&self.save_path, grade));
            }
        });
        match &self.saved {
            Some(Ok(p)) => {
                ui.colored_label(GREEN, format!("✓ {} {}", lang.tr("Saved to", "已保存到"), p.display()));
            }
            Some(Err(e)) => {
                ui.colored_label(egui::Color32::RED, format!("× {e}"));
            }
            None => {}
        }
    }
}

/// Writes the grade as JSON to `path` (a temporary file beside it, then renamed).
fn save(path: &str, grade: &Conformance) -> Result<PathBuf, String> {
    let path = PathBuf::from(path.trim());
    if path.as_os_str().is_empty() {
        return Err("name the report file first".into());
    }
    let json = serde_json::to_string_pretty(grade).map_err(|e| e.to_string())?;
    let tmp = path.with_extension("json.tmp");
    std::fs::write(&tmp, json + "\n")
        .and_then(|()| std::fs::rename(&tmp, &path))
        .map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(path)
}

/// The verdict, big enough to read from two metres.
fn verdict(ui: &mut egui::Ui, lang: Lang, result: Option<&Result<Conformance, JobError>>) {
    match result {
        Some(Ok(c)) if c.pass() => {
            let advisory = c.failed().len();
            ui.colored_label(
                GREEN,
                egui::RichText::new(format!(
                    "✓ {} ({advisory} {}, {:.1} s)",
                    lang.tr("CONFORMS", "符合协议"),
                    lang.tr("advisory not met", "项建议未满足"),
                    c.seconds
                ))
                .heading(),
            );
        }
        Some(Ok(c)) => {
            let ids: Vec<&str> = c.failed().iter().filter(|k| k.mandatory).map(|k| k.id).collect();
            ui.colored_label(
                egui::Color32::RED,
                egui::RichText::new(format!(
                    "× {}: {}",
                    lang.tr("DOES NOT CONFORM", "不符合协议"),
                    ids.join(", ")
                ))
                .heading(),
            );
        }
        Some(Err(e)) => {
            ui.colored_label(
                egui::Color32::RED,
                format!(
                    "× {}{}{}",
                    lang.tr("The grade did not finish", "评定未完成"),
                    lang.tr(": ", ":"),
                    e.in_lang(lang)
                ),
            );
        }
        None => {}
    }
}

/// The checks: id, grade, mandatory or advisory, detail, evidence.
fn table(ui: &mut egui::Ui, lang: Lang, checks: &[Check]) {
    if checks.is_empty() {
        return;
    }
    crate::ui::layout::table(ui, egui::Grid::new("tuya-conform"), &[
                    lang.tr("Check", "检查项"),
                    lang.tr("Result", "结果"),
                    lang.tr("Kind", "类别"),
                    lang.tr("What was seen", "所见"),
                    lang.tr("Evidence (bytes)", "证据(字节)"),
                ], |ui| {
            for c in checks {
                ui.label(c.id).on_hover_text(c.name);
                let color = match (c.grade, c.mandatory) {
                    (Grade::Pass, _) => GREEN,
                    (Grade::Fail, true) => egui::Color32::RED,
                    (Grade::Fail, false) => ORANGE,
                    (Grade::Skip, _) => egui::Color32::GRAY,
                };
                ui.colored_label(color, egui::RichText::new(c.grade.word()).strong());
                ui.label(if c.mandatory {
                    lang.tr("mandatory", "必需")
                } else {
                    lang.tr("advisory", "建议")
                });
                ui.label(&c.detail);
                ui.monospace(&c.evidence);
                ui.end_row();
            }
        });
}
