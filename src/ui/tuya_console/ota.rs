//! The MCU firmware update: choose a file, check it (not empty, not over the profile's largest
//! image), confirm with the expected transfer time at the port's rate, send it in packets of the
//! size the MCU asks for, with a progress bar, rate and time left, cancel; then the wait for the
//! MCU to restart and name the new version (typed, or the one the image holds), and the result
//! with the versions before and after and the time it took to come back.

use super::{Action, Output, Station};
use crate::i18n::Lang;
use crate::i18n::Text;
use crate::ops::OpError;
pub use crate::ops::tuya::FirmwareFileError;
use crate::ops::tuya::{self as ops, OtaTiming};
use crate::ops::{Progress, Run};
use crate::ui::confirm::Decision;
use crate::ui::files;
use crate::ui::jobs::{Job, JobError};
use crate::ui::settings::FileKind;
use crate::ui::zh::Zh;
use eframe::egui;
use std::path::PathBuf;
use std::time::Instant;

const GREEN: egui::Color32 = egui::Color32::from_rgb(40, 160, 60);

/// How far an update is.
#[derive(Debug, Clone, PartialEq)]
pub struct OtaProgress {
    /// Bytes acked.
    pub done: u64,
    /// Image size.
    pub total: u64,
    /// Bytes a second so far.
    pub rate: f64,
    /// Seconds left at that rate.
    pub left: f64,
    /// The packet size the MCU asked for, once known.
    pub packet: Option<usize>,
    /// Every packet is acked: waiting for the MCU to restart and name its new version.
    pub waiting: bool,
}

/// The firmware update's state.
#[derive(Debug, Default)]
pub struct OtaView {
    /// The firmware file's path, typed or chosen.
    pub path: String,
    /// Why the file cannot be sent.
    pub error: Option<FirmwareFileError>,
    /// The file checked and awaiting confirmation, with its size when the system gives it.
    confirm: Option<(PathBuf, Option<u64>)>,
    /// The running update's progress.
    pub progress: Option<OtaProgress>,
    /// The last update's result.
    pub result: Option<Result<ops::OtaReport, JobError>>,
    /// An update was started and has not ended.
    pub running: bool,
    /// The version the MCU must name after the update, as typed; empty: the one the image
    /// holds ([`ops::image_version`]).
    pub expect_version: String,
    /// The version the running update waits for.
    expecting: Option<String>,
}

/// Seconds as `1 min 05 s` or `12 s`.
fn duration(secs: f64) -> String {
    ops::duration_text(std::time::Duration::from_secs_f64(secs.max(0.0)))
}

fn work(path: PathBuf, max: u32, typed: Option<String>) -> Job {
    Job::new(
        Text::new("OTA", "固件升级"),
        move |client, cancel, sink| {
            let done = |r: Result<ops::OtaReport, JobError>| {
                sink.panel(Output::OtaDone(r.clone()));
                r.map(|rep| {
                    let (before, after) = versions(&rep);
                    Text::new(
                        format!(
                            "{} bytes sent in {} packets of {} bytes; version {before} → {after}",
                            rep.size, rep.packets, rep.packet_size
                        ),
                        format!(
                            "已发送 {} 字节,共 {} 包,每包 {} 字节;版本 {before} → {after}",
                            rep.size, rep.packets, rep.packet_size
                        ),
                    )
                })
            };
            let file_error = |reason: String| JobError::File {
                path: path.clone(),
                reason,
            };
            // Read with the profile's bound: a file that grew past it, or a device, stops there.
            let image = match ops::read_image(&path, max) {
                Ok(i) => i,
                Err(e) => return done(Err(file_error(e.to_string()))),
            };
            let Some(version) = typed.clone().or_else(|| ops::image_version(&image)) else {
                return done(Err(file_error(
                    "the image names no single version (x.y.z): type the version the MCU must report after the update".into(),
                )));
            };
            let expect = ops::Expect {
                version,
                limit: ops::COME_BACK_LIMIT,
            };
            let started = Instant::now();
            let mut packet = None;
            let mut acked = 0u64;
            let result = ops::update(
                client,
                &image,
                max,
                &expect,
                OtaTiming::default(),
                &mut Run::new(cancel, |p: Progress| {
                    if packet.is_none() && p.done < p.total {
                        packet = Some(p.done as usize);
                    }
                    acked = p.done;
                    let rate = p.done as f64 / started.elapsed().as_secs_f64().max(1e-3);
                    sink.panel(Output::OtaProgress(OtaProgress {
                        done: p.done,
                        total: p.total,
                        rate,
                        left: p.total.saturating_sub(p.done) as f64 / rate.max(1.0),
                        packet,
                        waiting: p.done >= p.total,
                    }));
                    sink.progress(p);
                }),
            );
            done(result.map_err(|e| match e {
                OpError::Cancelled | OpError::CancelledAfter { .. } => JobError::UpdateCancelled {
                    offset: acked,
                    size: image.len(),
                },
                e => match e.lost_port() {
                    Some(why) => JobError::UpdateLinkLost {
                        offset: acked,
                        size: image.len(),
                        why: why.to_string(),
                    },
                    None => e.into(),
                },
            }))
        },
    )
}

/// The versions before and after an update, `unknown` where not known.
fn versions(r: &ops::OtaReport) -> (&str, &str) {
    (
        r.before_version.as_deref().unwrap_or("?"),
        r.after_version.as_deref().unwrap_or("?"),
    )
}

impl OtaView {
    /// Whether an update holds the link now.
    pub fn active(&self, rt: &Station) -> bool {
        self.running && rt.job_progress().is_some()
    }

    /// Takes what the update job reported.
    pub fn on_output(&mut self, out: Output) {
        match out {
            Output::OtaProgress(p) => self.progress = Some(p),
            Output::OtaDone(r) => {
                self.running = false;
                self.result = Some(r);
            }
            Output::ConformCheck(_) | Output::ConformDone(_) => {}
        }
    }

    /// Draws the section.
    pub fn show(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &Station) -> Vec<Action> {
        let mut actions = Vec::new();
        let max = rt.device.profile.ota_max_bytes();
        let busy = rt.job_progress().is_some();
        let active = self.active(rt);
        ui.weak(lang.tr(
            "The image goes in packets of the size the MCU asks for (256, 512 or 1024 bytes); each packet waits up to 5 s for its ack and is sent up to 3 more times.",
            "固件按MCU要求的包大小(256、512或1024字节)分包发送;每包最多等待5秒应答,最多重发3次。",
        ));
        ui.weak(format!(
            "{} {max} {}",
            lang.tr(
                "The profile allows images of at most",
                "配置允许的最大固件:"
            ),
            lang.tr("bytes.", "字节。")
        ));
        actions.extend(self.file_row(ui, lang, rt, busy, active));
        if let Some(e) = &self.error {
            ui.colored_label(
                egui::Color32::RED,
                format!("× {}: {e}", lang.tr("cannot update", "无法升级")),
            );
        }
        actions.extend(self.progress_and_result(ui, lang, active));
        if let Some(a) = self.confirm_dialog(ui, lang, rt) {
            actions.push(a);
        }
        actions
    }

    /// The firmware file (checked as soon as it is chosen) and Start update, which asks for
    /// confirmation.
    fn file_row(
        &mut self,
        ui: &mut egui::Ui,
        lang: Lang,
        rt: &Station,
        busy: bool,
        active: bool,
    ) -> Vec<Action> {
        let mut actions = Vec::new();
        let max = rt.device.profile.ota_max_bytes();
        crate::ui::layout::toolbar(ui, |ui| {
            let before = self.path.clone();
            let event = files::row(
                ui,
                lang,
                files::Row {
                    label: lang.tr("Firmware file", "固件文件"),
                    hint: "firmware.bin",
                    pick: files::Pick::Open(&[]),
                    enabled: !active,
                },
                &mut self.path,
                &rt.dialogs,
            );
            if self.path != before {
                self.error = None;
            }
            let label = lang.tr("Version after the update", "升级后的版本");
            // The label stays on the row of its box.
            crate::ui::layout::group(ui, label, |ui| {
                let l = ui.label(label);
                ui.add_enabled(
                    !active,
                    egui::TextEdit::singleline(&mut self.expect_version)
                        .hint_text(lang.tr("from the image", "取自固件"))
                        .desired_width(90.0),
                )
                .labelled_by(l.id);
            });
            // A file chosen is checked at once; it is sent only on Start update.
            if event.go(false, &mut actions) {
                self.error = ops::check_file(&PathBuf::from(self.path.trim()), max).err();
            }
            let named = !self.path.trim().is_empty();
            let start = ui.add_enabled(
                rt.connected() && !busy && named,
                egui::Button::new(lang.tr("Start update", "开始升级")),
            );
            let start = if named {
                start
            } else {
                start.on_disabled_hover_text(lang.tr(
                    "Name the firmware image first (type its path or Browse…).",
                    "请先指定固件文件(输入路径或点击浏览…)。",
                ))
            };
            if start.clicked() {
                let path = PathBuf::from(self.path.trim());
                match ops::check_file(&path, max) {
                    Ok(size) => {
                        self.error = None;
                        actions.push(Action::RememberFile(
                            FileKind::Firmware,
                            path.display().to_string(),
                        ));
                        self.confirm = Some((path, size));
                    }
                    Err(e) => self.error = Some(e),
                }
            }
        });
        actions
    }

    /// The update's progress (with Cancel update) while it runs, then how it ended.
    fn progress_and_result(&mut self, ui: &mut egui::Ui, lang: Lang, active: bool) -> Vec<Action> {
        let mut actions = Vec::new();
        if let Some(p) = &self.progress
            && (active || self.result.is_none())
        {
            ui.add(
                egui::ProgressBar::new((p.done as f32 / p.total.max(1) as f32).min(1.0))
                    .text(format!("{} / {} B", p.done, p.total))
                    .desired_width(420.0),
            );
            crate::ui::layout::toolbar(ui, |ui| {
                ui.label(format!(
                    "{:.0} B/s, {} {}",
                    p.rate,
                    duration(p.left),
                    lang.tr("left", "剩余")
                ));
                if let Some(n) = p.packet {
                    ui.label(format!(
                        "{} {n} {}",
                        lang.tr("packets of", "每包"),
                        lang.tr("bytes (asked by the MCU)", "字节(MCU要求)")
                    ));
                }
                if p.waiting && active {
                    ui.label(format!(
                        "{} {} ({} 60 s)",
                        lang.tr("Waiting for the MCU to restart with version", "等待MCU重启并报告版本"),
                        self.expecting.as_deref().unwrap_or("?"),
                        lang.tr("at most", "最多")
                    ));
                }
                if active && ui.button(lang.tr("Cancel update", "取消升级")).clicked() {
                    actions.push(Action::CancelJob);
                }
            });
        } else if active {
            ui.label(lang.tr("Starting the update…", "正在启动升级…"));
        }
        match &self.result {
            Some(Ok(r)) if !active => {
                ui.colored_label(
                    GREEN,
                    format!(
                        "✓ {}: {} B, {} × {} B {}, {}, {} {}",
                        lang.tr("Update complete", "升级完成"),
                        r.size,
                        r.packets,
                        r.packet_size,
                        lang.tr("packets", "包"),
                        duration(r.seconds),
                        r.retries,
                        lang.tr("retries", "次重发")
                    ),
                );
                let (before, after) = versions(r);
                ui.colored_label(
                    GREEN,
                    format!(
                        "{} {before} → {after}; {} {:.1} s {}",
                        lang.tr("MCU version", "MCU版本"),
                        lang.tr("it came back", "重启后"),
                        r.back_seconds.unwrap_or_default(),
                        lang.tr("after the last packet", "恢复应答(自最后一包起)")
                    ),
                );
            }
            Some(Err(e @ JobError::UpdateLinkLost { .. })) if !active => {
                ui.colored_label(
                    egui::Color32::from_rgb(180, 90, 0),
                    format!("× {}: {}", lang.tr("No verdict", "无结论"), e.in_lang(lang)),
                );
            }
            Some(Err(e)) if !active => {
                ui.colored_label(
                    egui::Color32::RED,
                    format!("× {}: {}", lang.tr("Update failed", "升级失败"), e.in_lang(lang)),
                );
            }
            _ => {}
        }
        if self.result.is_some()
            && !active
            && ui.button(lang.tr("Dismiss", "关闭结论")).clicked()
        {
            self.result = None;
            self.progress = None;
        }
        actions
    }

    fn confirm_dialog(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &Station) -> Option<Action> {
        let (path, size) = self.confirm.clone()?;
        let max = rt.device.profile.ota_max_bytes();
        let baud = rt.link.baud().unwrap_or(rt.device.profile.baud);
        let mut decision = None;
        let modal = egui::Modal::new(egui::Id::unique("tuya-ota-confirm")).show(ui.ctx(), |ui| {
            ui.heading(lang.tr("Update the MCU firmware?", "升级MCU固件?"));
            match size {
                Some(size) => {
                    ui.label(format!("{} ({size} B)", path.display()));
                    let t = ops::transfer_time(size, ops::DEFAULT_PACKET, baud);
                    ui.label(format!(
                        "{} {} {} {baud} {} ({} {} {})",
                        lang.tr("Expected transfer time:", "预计传输时间:"),
                        ops::duration_text(t),
                        lang.tr("at", "波特率"),
                        lang.tr("baud", ""),
                        ops::DEFAULT_PACKET,
                        lang.tr("byte packets;", "字节每包;"),
                        lang.tr(
                            "less if the MCU asks for larger ones",
                            "若MCU要求更大的包则更短"
                        ),
                    ));
                }
                None => {
                    ui.label(format!(
                        "{} ({} {max} B)",
                        path.display(),
                        lang.tr("size unknown until read; at most", "读取前大小未知;最多")
                    ));
                }
            }
            ui.label(lang.tr(
                "Keep the MCU powered until the update ends.",
                "升级结束前请勿断开MCU电源。",
            ));
            decision = crate::ui::confirm::buttons(
                ui,
                lang,
                lang.tr("Update", "升级"),
                lang.tr("Do not update", "不升级"),
                rt,
            );
        });
        match crate::ui::confirm::decided(&modal, decision)? {
            Decision::Yes => {
                self.confirm = None;
                self.running = true;
                self.progress = None;
                self.result = None;
                let typed = Some(self.expect_version.trim().to_string()).filter(|v| !v.is_empty());
                self.expecting = typed.clone().or_else(|| {
                    ops::read_image(&path, max)
                        .ok()
                        .and_then(|i| ops::image_version(&i))
                });
                Some(Action::StartJob(work(path, max, typed)))
            }
            Decision::No => {
                self.confirm = None;
                None
            }
            Decision::Stop => {
                self.confirm = None;
                Some(Action::Stop)
            }
        }
    }
}
