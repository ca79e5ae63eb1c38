//! The scan tab: an id range and a set of baud rates, the servos found (details, status as raw
//! hex and decoded bits, possible duplicate ids), rescanning one id, selecting a servo.

use super::{Output, Servo, error_label, ok_label, port_baud, send};
use crate::i18n::Lang;
use crate::i18n::Text;
use crate::ops::OpError;
use crate::ops::servo::{self as ops, Presence, ScanPlan, ScanReport, ScanRow};
use crate::ops::{Device, Run};
use crate::profile::Profile;
use crate::ui::Action;
use crate::ui::jobs::Job;
use crate::ui::layout::header_row;
use crate::ui::station::Station;
use crate::ui::zh::Zh;
use eframe::egui;
use std::ops::RangeInclusive;

/// The scan tab's state.
pub struct ScanState {
    /// The first id, as typed.
    pub first: String,
    /// The last id, as typed.
    pub last: String,
    /// Which of the profile's servo baud rates to scan (`None` until chosen: the profile's own
    /// rate, the factory rate).
    pub bauds: Option<Vec<u32>>,
    /// The servos found, in scan order.
    pub rows: Vec<ScanRow>,
    /// How the last scan ended (`None`: none yet, or running).
    pub outcome: Option<Result<ScanTally, OpError>>,
}

/// What the last scan says beside its rows: how many servos, how many ids it asked again, the
/// late answers, and the margin it waited with.
#[derive(Debug, Clone, PartialEq)]
pub struct ScanTally {
    /// Servos in the list.
    pub found: usize,
    /// Ids pinged again one by one.
    pub asked_again: usize,
    /// Answers that came after their window.
    pub late_answers: usize,
    /// The margin, in ms.
    pub margin_ms: f64,
    /// The ids the scan cannot say are empty: silent only while this computer was held up
    /// ([`ScanReport::unsure`]).
    pub unsure: Vec<ops::Unsure>,
    /// How far this computer was held up past a deadline of the scan, in ms, when it was.
    pub held_up_ms: Option<f64>,
}

impl ScanTally {
    fn of(report: &ScanReport, found: usize) -> Self {
        Self {
            found,
            asked_again: report.asked_again,
            late_answers: report.late_answers,
            margin_ms: report.margin_ms,
            unsure: report.unsure.clone(),
            held_up_ms: report.host_late_ms,
        }
    }

    /// Why the scan cannot vouch for the ids in [`Self::unsure`], in `lang` (`None`: it can).
    fn unsure_said(&self, lang: Lang) -> Option<String> {
        ops::unsure_said(&self.unsure, self.held_up_ms).map(|t| t.get(lang).to_string())
    }
}

impl Default for ScanState {
    fn default() -> Self {
        Self {
            first: "0".into(),
            // The last id a servo can have: the broadcast id is none's.
            last: (crate::protocol::servo::BROADCAST_ID - 1).to_string(),
            bauds: None,
            rows: Vec::new(),
            outcome: None,
        }
    }
}

/// The status byte decoded: the bits that are set (their meaning is published inconsistently).
pub fn status_bits(status: i64, lang: Lang) -> String {
    if status == 0 {
        return lang.tr("no flags", "无标志").to_string();
    }
    let bits: Vec<String> = (0..8)
        .filter(|b| status >> b & 1 == 1)
        .map(|b| b.to_string())
        .collect();
    format!("{} {}", lang.tr("bits", "位"), bits.join(", "))
}

/// Why the typed id range cannot be scanned.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum IdRangeError {
    /// The first or last id is not an id 0-254.
    NotAnId {
        /// Whether it is the first (or the last).
        first: bool,
        /// What was typed.
        text: String,
    },
    /// The first id is above the last.
    Reversed {
        /// The first id.
        first: u8,
        /// The last id.
        last: u8,
    },
}

impl IdRangeError {
    /// What is wrong, in `lang`.
    pub fn text(&self, lang: Lang) -> String {
        match self {
            IdRangeError::NotAnId { first, text } => format!(
                "{} '{text}' {}",
                if *first {
                    lang.tr("first id", "起始ID")
                } else {
                    lang.tr("last id", "结束ID")
                },
                lang.tr("is not an id 0-254", "不是0-254之间的ID")
            ),
            IdRangeError::Reversed { first, last } => format!(
                "{} {first} > {last}",
                lang.tr("the first id is above the last id:", "起始ID大于结束ID:")
            ),
        }
    }
}

impl ScanState {
    /// The id range typed, or why it is not one.
    pub fn ids(&self) -> Result<RangeInclusive<u8>, IdRangeError> {
        let parse = |s: &str, first: bool| {
            s.trim()
                .parse::<u8>()
                .ok()
                .filter(|v| *v < crate::protocol::servo::BROADCAST_ID)
                .ok_or_else(|| IdRangeError::NotAnId {
                    first,
                    text: s.trim().to_string(),
                })
        };
        let a = parse(&self.first, true)?;
        let b = parse(&self.last, false)?;
        if a > b {
            return Err(IdRangeError::Reversed { first: a, last: b });
        }
        Ok(a..=b)
    }

    /// The chosen rates, in the profile's option order.
    fn chosen_bauds(&self, profile: &Profile) -> Vec<u32> {
        let chosen = self
            .bauds
            .as_deref()
            .unwrap_or(std::slice::from_ref(&profile.baud));
        profile
            .servo_bauds()
            .into_iter()
            .filter(|b| chosen.contains(b))
            .collect()
    }

    pub(super) fn on_found(&mut self, row: ScanRow) {
        if !self
            .rows
            .iter()
            .any(|r| r.id == row.id && r.baud == row.baud)
        {
            self.rows.push(row);
        }
    }

    pub(super) fn on_scanned(&mut self, result: Result<ScanReport, OpError>) {
        match result {
            Ok(report) => {
                self.outcome = Some(Ok(ScanTally::of(&report, report.rows.len())));
                self.rows = report.rows;
            }
            // Partial results stay: what was found was found.
            Err(e) => self.outcome = Some(Err(e)),
        }
    }

    pub(super) fn on_rescanned(&mut self, at: Servo, report: Result<ScanReport, OpError>) {
        match report {
            Ok(report) => {
                let tally = ScanTally::of(&report, 0);
                let rows = report.rows;
                let pos = self
                    .rows
                    .iter()
                    .position(|r| r.id == at.id && r.baud == at.baud);
                self.rows.retain(|r| !(r.id == at.id && r.baud == at.baud));
                let at_pos = pos.unwrap_or(self.rows.len()).min(self.rows.len());
                for (i, row) in rows.into_iter().enumerate() {
                    if !self
                        .rows
                        .iter()
                        .any(|r| r.id == row.id && r.baud == row.baud)
                    {
                        self.rows.insert(at_pos + i, row);
                    }
                }
                self.outcome = Some(Ok(ScanTally {
                    found: self.rows.len(),
                    ..tally
                }));
            }
            Err(e) => self.outcome = Some(Err(e)),
        }
    }

    /// A scan of the ids and rates chosen, as the Scan button starts it (`None`: the ids typed
    /// do not read).
    pub(crate) fn start(&mut self, rt: &Station) -> Option<Action> {
        let ids = self.ids().ok()?;
        self.rows.clear();
        self.outcome = None;
        let plan = ScanPlan {
            ids,
            bauds: self.chosen_bauds(&rt.device.profile),
            home_baud: port_baud(rt).unwrap_or(rt.device.profile.baud),
        };
        Some(scan_job(rt, plan, None))
    }

    /// The baud rates to scan: each a checkbox, All and Only the profile's own.
    fn baud_choice(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &Station) {
        let profile = &rt.device.profile;
        let all = profile.servo_bauds();
        let bauds = self.chosen_bauds(profile);
        crate::ui::layout::toolbar(ui, |ui| {
            ui.label(lang.tr("Baud rates:", "波特率:"));
            for b in &all {
                let mut on = bauds.contains(b);
                if ui.checkbox(&mut on, b.to_string()).changed() {
                    let mut chosen = bauds.clone();
                    chosen.retain(|c| c != b);
                    if on {
                        chosen.push(*b);
                    }
                    self.bauds = Some(chosen);
                }
            }
            let n = all.len();
            let every = match lang {
                Lang::En => format!("All {n}"),
                Lang::Zh => format!("全部{n}种"),
            };
            if ui.button(every).clicked() {
                self.bauds = Some(all.clone());
            }
            let home = profile.baud;
            let only = match lang {
                Lang::En => format!("Only {home}"),
                Lang::Zh => format!("仅{home}"),
            };
            if ui.button(only).clicked() {
                self.bauds = Some(vec![home]);
            }
        });
    }

    /// How the last scan ended: the servos found and what it took, or why it stopped.
    fn said_outcome(&self, ui: &mut egui::Ui, lang: Lang) {
        match &self.outcome {
            Some(Ok(t)) => {
                ok_label(
                    ui,
                    format!("{} {}", t.found, lang.tr("servo(s) found", "个舵机已找到")),
                );
                ui.weak(format!(
                    "{} {}, {} {}, {} {:.1} ms",
                    t.asked_again,
                    lang.tr("id(s) asked again", "个ID重新询问"),
                    t.late_answers,
                    lang.tr("late answer(s)", "个迟到应答"),
                    lang.tr("margin", "余量"),
                    t.margin_ms
                ))
                .on_hover_text(lang.tr(
                    "Ids pinged again one by one (a damaged answer, an answer after its sweep), answers that came after their window, and the answer margin the scan waited with",
                    "逐个重新询问的ID(应答损坏或扫描结束后才到),超出等待窗口的应答,以及扫描使用的应答余量",
                ));
                if let Some(unsure) = t.unsure_said(lang) {
                    error_label(ui, unsure);
                }
            }
            Some(Err(e)) => {
                error_label(
                    ui,
                    format!(
                        "{}: {} ({} {})",
                        lang.tr("scan stopped", "扫描中止"),
                        e.in_lang(lang),
                        self.rows.len(),
                        lang.tr("found before it stopped", "个在中止前找到")
                    ),
                );
            }
            None => {}
        }
    }

    /// The servos found, one row each: select one to work on, rescan it, its details. Returns
    /// the servo selected and the rescans asked for.
    fn table(
        &self,
        ui: &mut egui::Ui,
        lang: Lang,
        rt: &Station,
        busy: bool,
        selected: Option<Servo>,
    ) -> (Option<Servo>, Vec<Action>) {
        let mut picked = None;
        let mut actions = Vec::new();
        // A narrow window scrolls the details sideways; the servo and its Rescan stay first.
        egui::ScrollArea::horizontal()
            .id_salt("servo-scan-table")
            .show(ui, |ui| {
                egui::Grid::new("servo-scan")
                    .striped(true)
                    .num_columns(11)
                    .min_col_width(40.0)
                    .show(ui, |ui| {
                        header_row(
                            ui,
                            &[
                                lang.tr("Servo", "舵机"),
                                "",
                                lang.tr("Baud", "波特率"),
                                lang.tr("Type", "型号"),
                                lang.tr("Firmware", "固件"),
                                lang.tr("Serial", "序列号"),
                                lang.tr("Voltage", "电压"),
                                lang.tr("Temperature", "温度"),
                                lang.tr("Status (raw)", "状态(原始)"),
                                lang.tr("Status (decoded)", "状态(解析)"),
                                lang.tr("Presence", "应答"),
                            ],
                        );
                        for row in &self.rows {
                            let here = Servo {
                                id: row.id,
                                baud: row.baud,
                            };
                            let clean = row.presence == Presence::Present;
                            let label = format!("{} {}", lang.tr("Servo", "舵机"), row.id);
                            let sel = ui
                                // Not while a job runs: the port follows the servo selected.
                                .add_enabled(
                                    clean && !busy,
                                    egui::Button::selectable(selected == Some(here), label),
                                )
                                .on_hover_text(lang.tr("Work on this servo", "选择此舵机进行操作"));
                            if sel.clicked() {
                                picked = Some(here);
                            }
                            // Beside its servo, so that it is in reach however narrow the window.
                            let again = ui
                                .add_enabled(
                                    rt.connected() && !busy,
                                    egui::Button::new(format!(
                                        "{} {}",
                                        lang.tr("Rescan", "重新扫描"),
                                        row.id
                                    )),
                                )
                                .on_hover_text(lang.tr(
                                    "Ping this id again at this baud rate and read its details",
                                    "在此波特率下重新检测此ID并读取信息",
                                ));
                            if again.clicked() {
                                let plan = ScanPlan {
                                    ids: row.id..=row.id,
                                    bauds: vec![row.baud],
                                    home_baud: port_baud(rt).unwrap_or(rt.device.profile.baud),
                                };
                                actions.push(scan_job(rt, plan, Some(here)));
                            }
                            details(ui, lang, rt, row);
                            ui.end_row();
                        }
                    });
            });
        (picked, actions)
    }

    /// Draws the tab; returns a servo the technician selected.
    pub(super) fn show(
        &mut self,
        ui: &mut egui::Ui,
        lang: Lang,
        rt: &Station,
        busy: bool,
        selected: Option<Servo>,
    ) -> (Option<Servo>, Vec<Action>) {
        let mut actions = Vec::new();
        let ids = self.ids();
        let profile = &rt.device.profile;
        let bauds = self.chosen_bauds(profile);
        ui.horizontal(|ui| {
            let l = ui.label(lang.tr("First id", "起始ID"));
            ui.add(egui::TextEdit::singleline(&mut self.first).desired_width(40.0))
                .labelled_by(l.id);
            let l = ui.label(lang.tr("Last id", "结束ID"));
            ui.add(egui::TextEdit::singleline(&mut self.last).desired_width(40.0))
                .labelled_by(l.id);
            if let Err(e) = &ids {
                error_label(ui, e.text(lang));
            }
        });
        self.baud_choice(ui, lang, rt);
        ui.horizontal(|ui| {
            let can = rt.connected() && !busy && ids.is_ok() && !bauds.is_empty();
            let scan = ui.add_enabled(
                can,
                egui::Button::new(egui::RichText::new(lang.tr("Scan", "扫描")).strong())
                    .min_size(egui::vec2(90.0, 26.0)),
            );
            if bauds.is_empty() {
                error_label(
                    ui,
                    lang.tr("choose at least one baud rate", "请至少选择一种波特率"),
                );
            }
            if scan.clicked() {
                actions.extend(self.start(rt));
            }
            self.said_outcome(ui, lang);
        });
        ui.separator();
        if self.rows.is_empty() {
            ui.weak(lang.tr("No servos listed yet.", "尚无舵机。"));
            return (None, actions);
        }
        let (picked, rescans) = self.table(ui, lang, rt, busy, selected);
        actions.extend(rescans);
        (picked, actions)
    }
}

/// A scan as a job; `again` marks the rescan of one servo.
fn scan_job(rt: &Station, plan: ScanPlan, again: Option<Servo>) -> Action {
    let profile = rt.device.profile.clone();
    let title = if again.is_some() {
        Text::new("rescan", "重新扫描")
    } else {
        Text::new("scan", "扫描")
    };
    Action::StartJob(Job::new(title, move |client, cancel, sink| {
        let result = ops::scan(
            Device::new(client, &profile),
            &plan,
            &mut Run::new(cancel, |p| sink.progress(p)),
            &mut |row| {
                if again.is_none() {
                    send(sink, Output::Found(row.clone()));
                }
            },
        );
        let summary = match &result {
            Ok(r) => Ok(Text::new(
                format!(
                    "{} servo(s) found; {} id(s) asked again, margin {:.1} ms",
                    r.rows.len(),
                    r.asked_again,
                    r.margin_ms
                ),
                format!(
                    "找到 {} 个舵机;{} 个 ID 重问,余量 {:.1} ms",
                    r.rows.len(),
                    r.asked_again,
                    r.margin_ms
                ),
            )),
            Err(e) => Err(e.clone().into()),
        };
        match again {
            Some(at) => send(sink, Output::Rescanned { at, rows: result }),
            None => send(sink, Output::Scanned(result)),
        }
        summary
    }))
}

/// A servo's details in the scan table: its rate, type, firmware, serial number, voltage,
/// temperature, status (raw and decoded) and how it answered.
fn details(ui: &mut egui::Ui, lang: Lang, rt: &Station, row: &ScanRow) {
    let opt = |v: Option<i64>| v.map_or("-".to_string(), |v| v.to_string());
    ui.label(row.baud.to_string());
    ui.label(opt(row.servo_type));
    ui.label(opt(row.firmware));
    ui.label(opt(row.serial));
    ui.label(row.voltage_mv.map_or("-".into(), |v| format!("{v} mV")));
    ui.label(crate::ui::inputs::said_in(
        row.temperature_text(&rt.device.profile),
        lang,
    ));
    ui.monospace(row.status_hex());
    ui.label(row.status.map_or("-".into(), |s| status_bits(s, lang)));
    match &row.presence {
        Presence::Present => ok_label(ui, lang.tr("ok", "正常")),
        Presence::PossibleDuplicate(e) => {
            ui.colored_label(
                egui::Color32::from_rgb(210, 40, 40),
                lang.tr("possible duplicate id", "可能存在重复ID"),
            )
            .on_hover_text(e);
        }
        Presence::Absent => {
            ui.weak(lang.tr("absent", "无应答"));
        }
    }
}
