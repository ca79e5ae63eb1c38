//! Data points, generated from the profile: a control by type (bool toggle, enum selector, value
//! with range and unit, string, bitmap with its named bits lit, raw as hex). Commands go out as
//! 0x06; only the MCU's 0x07 reports change what is shown, with the time of the last report. A
//! data point reported with another type or length than the profile's is shown raw with the
//! mismatch. A command is marked by the data point's last report up to a read-back query.

use super::{Action, Station, clock, fire};
use crate::i18n::Lang;
use crate::link::{LinkCommand, ReplyTo};
use crate::ops::OpError;
use crate::ops::tuya::{self as ops, ReportedDp};
use crate::profile::{Access, DataPointDef, Value};
use crate::protocol::tuya::dp::DpType;
use crate::ui::zh::Zh;
use eframe::egui;
use std::collections::HashMap;
use std::time::{Duration, Instant};

/// How long a command waits for its read-back when the link never says the read-back ended
/// (its events lost): it is then marked unanswered.
pub const REPORT_WAIT: Duration = Duration::from_secs(30);

const GREEN: egui::Color32 = egui::Color32::from_rgb(40, 160, 60);
const ORANGE: egui::Color32 = egui::Color32::from_rgb(220, 150, 0);

/// A command sent and not yet read back.
#[derive(Debug, Clone, PartialEq)]
pub struct Pending {
    /// What was sent.
    pub value: Value,
    /// When.
    pub sent: Instant,
    /// Status queries sent before the command ([`crate::ui::station::TuyaModel::queries`]):
    /// reports after a later query are the read-back's.
    pub queries: u64,
    /// The read-back query's reply id: once it is answered, the last report says.
    pub read_back: u64,
}

/// What the last command of a data point came to.
#[derive(Debug, Clone, PartialEq)]
pub enum Mark {
    /// The MCU's last report after the command, up to the read-back, carries the value sent.
    Confirmed,
    /// The MCU's last report carries another value.
    Mismatch(Value),
    /// The MCU's last report does not fit the profile (another type or length).
    Misfit(ReportedDp),
    /// No report came.
    NoReport(Value),
    /// Refused before sending.
    Refused(OpError),
}

/// The data points' edits and sends.
#[derive(Debug, Default)]
pub struct DpView {
    /// Text typed for value, string, bitmap and raw data points, by id.
    pub edits: HashMap<u8, String>,
    /// Commands awaiting their report, by id.
    pub pending: HashMap<u8, Pending>,
    /// The outcome of each data point's last command, by id.
    pub marks: HashMap<u8, Mark>,
    /// The report log is shown from this line on ("Clear").
    log_from: u64,
    /// The connection the sends and marks belong to.
    generation: u64,
    /// The width, points, a bitmap's bit names wrap within (this frame's share of the window).
    bits_width: f32,
}

/// A value as shown, with its unit: labels by name, bools as on/off, raw as hex.
fn shown(lang: Lang, def: &DataPointDef, v: &Value) -> String {
    let f = &def.field;
    match (def.dp_type, v) {
        (DpType::Bool, Value::Int(b)) => {
            if *b != 0 {
                lang.tr("on", "开").into()
            } else {
                lang.tr("off", "关").into()
            }
        }
        (DpType::Enum, Value::Int(x)) => match f.label(*x) {
            Some(l) => lang.tr(&l.name.en, &l.name.zh).into(),
            None => format!("{x} ({})", lang.tr("not in the profile", "不在配置中")),
        },
        (DpType::String, Value::Text(s)) => format!("\"{s}\""),
        _ => format!("{}{}", f.format(v), f.unit_suffix()),
    }
}

fn allowed(lang: Lang, def: &DataPointDef) -> String {
    match def.dp_type {
        DpType::Bool => lang.tr("on / off", "开 / 关").into(),
        DpType::Enum => format!(
            "{} {}",
            def.field.labels.len(),
            lang.tr("choices", "个选项")
        ),
        DpType::Value => super::super::inputs::range_text(&def.field),
        DpType::String => lang.tr("text", "文本").into(),
        DpType::Bitmap => lang
            .tr("bit names joined by | or 0x..", "位名称用 | 连接,或 0x..")
            .into(),
        DpType::Raw => lang.tr("hex bytes", "十六进制字节").into(),
    }
}

impl DpView {
    /// Sends `value` to data point `def` as a 0x06 command, checked against the profile first,
    /// then a status query that reads back every data point.
    fn send(&mut self, rt: &Station, def: &DataPointDef, value: Value) -> Vec<Action> {
        let profile = &rt.device.profile;
        match ops::dp_request(profile, def, value.clone()) {
            Ok(request) => {
                let read_back = rt.link.reply_id();
                self.marks.remove(&def.id);
                self.pending.insert(
                    def.id,
                    Pending {
                        value,
                        sent: Instant::now(),
                        queries: rt.device.tuya.queries,
                        read_back,
                    },
                );
                vec![
                    fire(request),
                    // Every data point: what the command changed besides is brought too.
                    Action::Link(LinkCommand::Request {
                        request: ops::query_request(profile),
                        reply_to: ReplyTo::Event(read_back),
                    }),
                ]
            }
            Err(e) => {
                self.marks.insert(def.id, Mark::Refused(e));
                Vec::new()
            }
        }
    }

    /// Settles the commands whose read-back has ended: by the data point's last report after
    /// the command (one that came after the read-back query was sent).
    fn settle(&mut self, rt: &Station) {
        let tuya = &rt.device.tuya;
        let mut settled = Vec::new();
        for (id, p) in &self.pending {
            let ended = rt.device.replies.contains_key(&p.read_back);
            if !ended && p.sent.elapsed() < REPORT_WAIT {
                continue;
            }
            let misfit = tuya.misfits.get(id).filter(|m| m.2 > p.queries);
            let fits = tuya.dps.get(id).filter(|st| st.query > p.queries);
            let mark = match (misfit, fits) {
                // A report that fits removes the misfit: a misfit still there is the latest.
                (Some(m), _) => Mark::Misfit(m.0.clone()),
                (None, Some(st)) if st.value == p.value => Mark::Confirmed,
                (None, Some(st)) => Mark::Mismatch(st.value.clone()),
                (None, None) => Mark::NoReport(p.value.clone()),
            };
            settled.push((*id, mark));
        }
        for (id, mark) in settled {
            self.pending.remove(&id);
            self.marks.insert(id, mark);
        }
    }

    /// Draws the section. `ota` is true while a firmware update holds the link.
    pub fn show(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &Station, ota: bool) -> Vec<Action> {
        let mut actions = Vec::new();
        if self.generation != rt.device.tuya.generation {
            // A new connection: what was sent on the last one says nothing of this one.
            self.generation = rt.device.tuya.generation;
            self.pending.clear();
            self.marks.clear();
            self.log_from = 0;
        }
        self.settle(rt);
        if !self.pending.is_empty() {
            ui.ctx().request_repaint_after(Duration::from_millis(200));
        }
        let can_send = rt.connected() && !ota;
        crate::ui::layout::toolbar(ui, |ui| {
            if ui
                .add_enabled(
                    can_send,
                    egui::Button::new(lang.tr("Query status", "查询状态")),
                )
                .on_hover_text(lang.tr(
                    "0x08: the MCU reports every data point",
                    "0x08:MCU上报全部数据点",
                ))
                .clicked()
            {
                actions.push(fire(ops::query_request(&rt.device.profile)));
            }
            if let Some(t) = &rt.device.tuya.last_query {
                ui.weak(format!(
                    "{} {}",
                    lang.tr("last query at", "最近查询于"),
                    clock(t)
                ));
            }
            if ota {
                ui.colored_label(
                    ORANGE,
                    lang.tr(
                        "A firmware update is running: commands wait until it ends.",
                        "固件升级进行中:升级结束后才能下发命令。",
                    ),
                );
            }
        });
        ui.weak(lang.tr(
            "Commands go out as 0x06. Values are shown only as the MCU reports them (0x07).",
            "命令以0x06下发。只显示MCU上报(0x07)的值。",
        ));
        ui.add_space(4.0);
        let defs = rt.device.profile.data_points.clone();
        self.bits_width = (ui.available_width() * 0.3).clamp(160.0, 420.0);
        crate::ui::layout::table(ui, egui::Grid::new("tuya-dps").min_col_width(40.0), &[
                        lang.tr("Data point", "数据点"),
                        lang.tr("Reported", "上报值"),
                        lang.tr("Last report", "最近上报"),
                        lang.tr("Command", "下发"),
                        lang.tr("Allowed", "允许值"),
                        "",
                    ], |ui| {
                for def in &defs {
                    actions.extend(self.row(ui, lang, rt, def, can_send));
                    ui.end_row();
                }
            });
        since_query(ui, lang, rt);
        unknown(ui, lang, rt);
        ui.separator();
        self.log(ui, lang, rt);
        actions
    }

    fn row(
        &mut self,
        ui: &mut egui::Ui,
        lang: Lang,
        rt: &Station,
        def: &DataPointDef,
        can_send: bool,
    ) -> Vec<Action> {
        let f = &def.field;
        let name = ui
            .label(format!("{} {}", def.id, lang.tr(&f.name.en, &f.name.zh)))
            .on_hover_text(format!("{} ({})", f.ident, crate::ui::zh::dp_type(def.dp_type, lang)));
        let reported = rt.device.tuya.dps.get(&def.id);
        let misfit = rt.device.tuya.misfits.get(&def.id);
        match (misfit, reported) {
            (Some((m, _, _)), _) => misfit_label(ui, lang, m),
            (None, Some(st)) if def.dp_type == DpType::Bitmap => {
                bits(ui, lang, def, &st.value, self.bits_width)
            }
            (None, Some(st)) => {
                ui.monospace(shown(lang, def, &st.value));
            }
            (None, None) => {
                ui.weak(lang.tr("not reported yet", "尚未上报"));
            }
        }
        match (misfit, reported) {
            (Some((_, t, _)), _) => ui.monospace(clock(t)),
            (None, Some(st)) => ui.monospace(clock(&st.clock)),
            (None, None) => ui.label(""),
        };
        let mut action = Vec::new();
        let writable = def.access == Access::ReadWrite;
        if !writable {
            ui.weak(lang.tr("report only", "仅上报"));
        } else {
            match def.dp_type {
                DpType::Bool => {
                    let current = reported.map(|st| st.value == Value::Int(1));
                    let mut on = current.unwrap_or(false);
                    let resp = ui
                        .add_enabled(
                            can_send && current.is_some(),
                            egui::Checkbox::new(&mut on, ""),
                        )
                        .labelled_by(name.id);
                    if resp.changed() {
                        action = self.send(rt, def, Value::Int(i64::from(on)));
                    }
                }
                DpType::Enum => {
                    let current = reported.and_then(|st| match st.value {
                        Value::Int(x) => Some(x),
                        _ => None,
                    });
                    let selected = reported.map_or_else(
                        || lang.tr("choose…", "选择…").to_string(),
                        |st| shown(lang, def, &st.value),
                    );
                    let mut chosen = None;
                    ui.add_enabled_ui(can_send, |ui| {
                        egui::ComboBox::from_id_salt(("tuya-dp", def.id))
                            .selected_text(selected)
                            .width(160.0)
                            .show_ui(ui, |ui| {
                                for l in &f.labels {
                                    if ui
                                        .selectable_label(
                                            current == Some(l.value),
                                            lang.tr(&l.name.en, &l.name.zh),
                                        )
                                        .clicked()
                                    {
                                        chosen = Some(l.value);
                                    }
                                }
                            })
                            .response
                            .labelled_by(name.id);
                    });
                    if let Some(v) = chosen {
                        action = self.send(rt, def, Value::Int(v));
                    }
                }
                _ => action = self.typed(ui, lang, rt, def, name.id, can_send),
            }
        }
        ui.weak(allowed(lang, def));
        self.mark(ui, lang, def);
        action
    }

    /// A text field for value, string, bitmap and raw data points, checked as typed; Send (or
    /// Enter) only when it is valid.
    fn typed(
        &mut self,
        ui: &mut egui::Ui,
        lang: Lang,
        rt: &Station,
        def: &DataPointDef,
        label: egui::Id,
        can_send: bool,
    ) -> Vec<Action> {
        let mut action = Vec::new();
        ui.horizontal(|ui| {
            let mut text = self.edits.get(&def.id).cloned().unwrap_or_default();
            let parsed = (!text.is_empty()).then(|| def.field.parse(&text));
            let invalid = matches!(parsed, Some(Err(_)));
            let mut edit = egui::TextEdit::singleline(&mut text)
                .desired_width(140.0)
                .hint_text(lang.tr("new value", "新值"));
            if invalid {
                edit = edit.text_color(egui::Color32::RED);
            }
            let resp = ui.add(edit).labelled_by(label);
            if resp.changed() {
                if text.is_empty() {
                    self.edits.remove(&def.id);
                } else {
                    self.edits.insert(def.id, text.clone());
                }
            }
            let entered = resp.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
            match def.field.parse(&text) {
                _ if text.is_empty() => {}
                Ok(v) => {
                    let clicked = ui
                        .add_enabled(can_send, egui::Button::new(lang.tr("Send", "下发")))
                        .clicked();
                    if (clicked || entered) && can_send {
                        self.edits.remove(&def.id);
                        action = self.send(rt, def, v);
                    }
                }
                Err(e) => {
                    ui.colored_label(
                        egui::Color32::RED,
                        format!("× {}: {e}", lang.tr("not sent", "不下发")),
                    );
                }
            }
        });
        action
    }

    fn mark(&self, ui: &mut egui::Ui, lang: Lang, def: &DataPointDef) {
        if let Some(p) = self.pending.get(&def.id) {
            ui.colored_label(
                ORANGE,
                format!(
                    "{} {}, {}",
                    lang.tr("sent", "已下发"),
                    shown(lang, def, &p.value),
                    lang.tr("waiting for the report", "等待上报")
                ),
            );
            return;
        }
        match self.marks.get(&def.id) {
            Some(Mark::Confirmed) => {
                ui.colored_label(
                    GREEN,
                    format!("✓ {}", lang.tr("reported back", "已上报确认")),
                );
            }
            Some(Mark::Mismatch(v)) => {
                ui.colored_label(
                    egui::Color32::RED,
                    format!(
                        "× {} {}",
                        lang.tr("the MCU reports", "MCU上报为"),
                        shown(lang, def, v)
                    ),
                );
            }
            Some(Mark::Misfit(m)) => {
                ui.colored_label(
                    egui::Color32::RED,
                    format!(
                        "× {} {}",
                        lang.tr("the MCU reports", "MCU上报为"),
                        misfit_text(lang, m)
                    ),
                );
            }
            Some(Mark::NoReport(v)) => {
                ui.colored_label(
                    egui::Color32::RED,
                    format!(
                        "× {} {} {}",
                        lang.tr("no report for", "未收到上报:"),
                        shown(lang, def, v),
                        lang.tr("(the MCU did not take it)", "(MCU未接受)")
                    ),
                );
            }
            Some(Mark::Refused(e)) => {
                ui.colored_label(
                    egui::Color32::RED,
                    format!("× {}: {e}", lang.tr("not sent", "不下发")),
                );
            }
            None => {
                ui.label("");
            }
        }
    }

    /// The report log, newest last.
    fn log(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &Station) {
        let lines: Vec<_> = rt
            .device
            .tuya
            .log
            .iter()
            .filter(|l| l.seq >= self.log_from)
            .collect();
        ui.horizontal(|ui| {
            ui.strong(format!(
                "{} ({})",
                lang.tr("Report log", "上报记录"),
                lines.len()
            ));
            if ui.button(lang.tr("Clear log", "清空记录")).clicked() {
                self.log_from = rt.device.tuya.log_seq;
            }
            ui.weak(format!(
                "{} {}",
                lang.tr("keeps the last", "保留最近"),
                crate::ui::station::REPORT_LOG_CAPACITY
            ));
        });
        egui::ScrollArea::vertical()
            .id_salt("tuya-report-log")
            .max_height(220.0)
            .stick_to_bottom(true)
            .show(ui, |ui| {
                for l in lines {
                    let item = &l.item;
                    let def = rt.device.profile.data_point(item.id);
                    // By the profile's name in the window's language; as reported without one.
                    let ident = def.map_or_else(
                        || item.ident.clone().unwrap_or_else(|| "?".into()),
                        |d| d.field.name.get(lang).to_string(),
                    );
                    let fits = def.zip(item.value.as_ref());
                    match (fits, &item.misfit) {
                        (Some((def, v)), None) => {
                            ui.monospace(format!(
                                "{}  {:>3} {ident} = {}",
                                clock(&l.clock),
                                item.id,
                                shown(lang, def, v)
                            ));
                        }
                        _ => {
                            ui.colored_label(
                                egui::Color32::RED,
                                format!(
                                    "{}  {:>3} {ident}: {}",
                                    clock(&l.clock),
                                    item.id,
                                    misfit_text(lang, item)
                                ),
                            );
                        }
                    }
                }
            });
    }
}

/// A bitmap: its value and each named bit, lit when set, four names a line: the row takes the
/// height of its lines (a wrapped line in a grid cell was drawn over the next row).
fn bits(ui: &mut egui::Ui, lang: Lang, def: &DataPointDef, v: &Value, width: f32) {
    let Value::Int(raw) = v else {
        ui.monospace(format!("{v:?}"));
        return;
    };
    ui.vertical(|ui| {
        // The names wrap within the column's share of the window (DP 18's eight fault names
        // pushed the Command column off an 800 px window).
        ui.set_max_width(width);
        ui.monospace(format!("{raw:#04x}"));
        crate::ui::layout::toolbar(ui, |ui| {
            for b in &def.field.bits {
                let name = lang.tr(&b.name.en, &b.name.zh);
                if b.bit < 64 && raw >> b.bit & 1 == 1 {
                    ui.label(
                        egui::RichText::new(name)
                            .color(egui::Color32::WHITE)
                            .background_color(egui::Color32::from_rgb(200, 40, 40)),
                    );
                } else {
                    ui.weak(name);
                }
            }
        });
    });
}

/// Since the last status query: how many of the profile's reported data points came (reports
/// are taken whenever they come: a slow MCU's late ones count), and which are still missing.
fn since_query(ui: &mut egui::Ui, lang: Lang, rt: &Station) {
    let tuya = &rt.device.tuya;
    let Some(t) = &tuya.last_query else {
        return;
    };
    let profile = &rt.device.profile;
    let ids: Vec<&DataPointDef> = profile.data_points.iter().filter(|d| d.access.reported()).collect();
    let came = |id: u8| {
        tuya.dps.get(&id).is_some_and(|st| st.query >= tuya.queries)
            || tuya.misfits.get(&id).is_some_and(|m| m.2 >= tuya.queries)
    };
    let missing: Vec<String> = ids
        .iter()
        .filter(|d| !came(d.id))
        .map(|d| format!("{} {}", d.id, d.field.name.get(lang)))
        .collect();
    let heard = ids.len() - missing.len();
    let text = format!(
        "{} {}: {heard} / {} {}",
        lang.tr("Since the query at", "自查询"),
        clock(t),
        ids.len(),
        lang.tr("data points reported", "个数据点已上报")
    );
    if missing.is_empty() {
        ui.label(text);
    } else {
        ui.colored_label(
            ORANGE,
            format!("{text}; {} {}", lang.tr("still missing:", "仍未上报:"), missing.join(", ")),
        );
    }
}

/// The data points the profile does not have, read by their own type and length.
fn unknown(ui: &mut egui::Ui, lang: Lang, rt: &Station) {
    let tuya = &rt.device.tuya;
    if tuya.unknown_dps.is_empty() {
        return;
    }
    ui.add_space(4.0);
    ui.strong(lang.tr(
        "Data points not in the profile (read by their own type and length)",
        "配置中没有的数据点(按其自身类型与长度解析)",
    ));
    egui::Grid::new("tuya-unknown-dps").striped(true).show(ui, |ui| {
        for (d, t) in tuya.unknown_dps.values() {
            let ty = DpType::from_byte(d.wire_type).map_or_else(|| format!("{:#04x}", d.wire_type), |t| crate::ui::zh::dp_type(t, lang).to_string());
            ui.label(format!("dp {}", d.id));
            ui.monospace(format!("{ty}, {} B", d.raw.len()));
            ui.monospace(d.shown(&rt.device.profile));
            ui.monospace(clock(t));
            ui.end_row();
        }
    });
}

/// A report that does not fit the profile: its raw bytes and the mismatch.
fn misfit_text(lang: Lang, m: &ReportedDp) -> String {
    let why = m.misfit.as_ref().map_or_else(String::new, |e| {
        format!("{}{}", lang.tr(": ", ":"), e.in_lang(lang))
    });
    format!(
        "{} {}{why}",
        lang.tr("raw", "原始字节"),
        crate::protocol::hex::format(&m.raw)
    )
}

/// A reported value that does not fit the profile, in the value's column.
fn misfit_label(ui: &mut egui::Ui, lang: Lang, m: &ReportedDp) {
    ui.colored_label(egui::Color32::RED, misfit_text(lang, m))
        .on_hover_text(lang.tr(
            "Reported with another type or length than the profile's data point, or a value it does not allow",
            "上报的类型、长度或数值与配置中的数据点不符",
        ));
}
