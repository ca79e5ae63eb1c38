//! The Yield view: the production records as `botbench report` gives them, as plots. Where
//! records go (a file or a `postgres://` URL, the window's one records setting), the records
//! waiting in the spool, first-pass and final yield per shift, the failing steps' Pareto, each
//! measurement's histogram with its limits, Cpk and drift. Refreshed when this window saves a
//! record, when the period changes, and once a minute while shown (other stations' records).

use super::records::RecordsHandle;
use super::settings::FileKind;
use super::station::Station;
use super::{Action, layout};
use crate::i18n::Lang;
use crate::ops::records::report::{MeasurementStats, ParetoStep, Query, Report, Yield};
use eframe::egui;
use egui_plot::{Bar, BarChart, GridMark, Line, Plot, PlotPoints, Points, VLine};
use std::time::{Duration, Instant};

/// How often the view asks again on its own while shown (records of other stations).
const POLL: Duration = Duration::from_secs(60);

/// The periods offered.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Period {
    /// The last 8 hours.
    Hours8,
    /// The last 24 hours.
    Hours24,
    /// The last 7 days.
    Days7,
    /// Every record.
    All,
}

impl Period {
    const ALL: [Period; 4] = [Period::Hours8, Period::Hours24, Period::Days7, Period::All];

    fn name(self, lang: Lang) -> &'static str {
        match self {
            Period::Hours8 => lang.tr("last 8 h", "最近 8 小时"),
            Period::Hours24 => lang.tr("last 24 h", "最近 24 小时"),
            Period::Days7 => lang.tr("last 7 days", "最近 7 天"),
            Period::All => lang.tr("all records", "全部记录"),
        }
    }

    fn since_ms(self) -> Option<i64> {
        let hours = match self {
            Period::Hours8 => 8,
            Period::Hours24 => 24,
            Period::Days7 => 24 * 7,
            Period::All => return None,
        };
        Some(crate::ops::records::record::now_ms() - hours * 3_600_000)
    }
}

/// The view's state.
pub struct YieldPanel {
    /// The records setting as typed (applied with its button).
    pub setting: String,
    /// The period shown.
    pub period: Period,
    /// The setting was loaded from the saved settings.
    loaded: bool,
    /// When the report was last asked for, and for which period.
    asked: Option<(Instant, Period)>,
}

impl Default for YieldPanel {
    fn default() -> Self {
        Self {
            setting: String::new(),
            period: Period::Days7,
            loaded: false,
            asked: None,
        }
    }
}

impl YieldPanel {
    /// Draws the view; returns the setting to remember when applied.
    fn draw(&mut self, ui: &mut egui::Ui, lang: Lang, state: &Station) -> Vec<Action> {
        let records = &state.records;
        if !self.loaded {
            self.setting = records.setting();
            self.loaded = true;
        }
        let mut actions = Vec::new();
        self.settings_row(ui, lang, records, &mut actions);
        let (report, stale) = records.report();
        let due = self
            .asked
            .is_none_or(|(at, p)| p != self.period || at.elapsed() >= POLL);
        if (stale || due) && !records.computing() {
            self.asked = Some((Instant::now(), self.period));
            let query = Query {
                filter: crate::ops::records::Filter {
                    since_ms: self.period.since_ms(),
                    ..Default::default()
                },
                ..Query::default()
            };
            records.refresh(query, ui.ctx());
        }
        ui.ctx().request_repaint_after(POLL);
        ui.separator();
        match report {
            None => {
                ui.label(lang.tr("Reading the records…", "正在读取记录…"));
            }
            Some(Err(e)) => {
                ui.colored_label(ui.visuals().warn_fg_color, e.get(lang));
            }
            Some(Ok(r)) => {
                egui::ScrollArea::vertical()
                    .auto_shrink([false, false])
                    .show(ui, |ui| figures(ui, lang, &r));
            }
        }
        actions
    }

    fn settings_row(
        &mut self,
        ui: &mut egui::Ui,
        lang: Lang,
        records: &RecordsHandle,
        actions: &mut Vec<Action>,
    ) {
        layout::toolbar(ui, |ui| {
            let label = ui.label(lang.tr("Records", "记录存放"));
            ui.add(
                egui::TextEdit::singleline(&mut self.setting)
                    .hint_text(lang.tr(
                        "this PC's file (default), a file, or postgres://…",
                        "本机文件(默认)、文件路径或 postgres://…",
                    ))
                    .desired_width(360.0),
            )
            .labelled_by(label.id);
            let valid = self.setting.trim().is_empty()
                || crate::ops::records::Location::parse(&self.setting).is_ok();
            if ui
                .add_enabled(valid, egui::Button::new(lang.tr("Apply", "应用")))
                .clicked()
            {
                records.configure(Some(self.setting.clone()));
                actions.push(Action::RememberFile(
                    FileKind::Records,
                    self.setting.trim().to_string(),
                ));
            }
            let period = ui.label(lang.tr("Period", "时段"));
            egui::ComboBox::from_id_salt("yield-period")
                .selected_text(self.period.name(lang))
                .show_ui(ui, |ui| {
                    for p in Period::ALL {
                        ui.selectable_value(&mut self.period, p, p.name(lang));
                    }
                })
                .response
                .labelled_by(period.id);
            if ui.button(lang.tr("Refresh", "刷新")).clicked() {
                self.asked = None;
            }
        });
        match records.location() {
            Ok(l) => {
                ui.weak(format!("{} {l}", lang.tr("Records go to", "记录写入")));
            }
            Err(e) => {
                ui.colored_label(ui.visuals().error_fg_color, e);
            }
        }
        if let Some(e) = records.error() {
            ui.colored_label(ui.visuals().error_fg_color, e);
        }
        let waiting = records.waiting();
        if waiting > 0 {
            ui.colored_label(
                ui.visuals().warn_fg_color,
                lang.tr(
                    &format!("{waiting} record(s) wait in this PC's spool for the line server"),
                    &format!("{waiting} 条记录在本机缓存中等待上传到产线服务器"),
                ),
            );
        }
    }
}

fn pct(x: f64) -> String {
    if x.is_finite() {
        format!("{:.1} %", 100.0 * x)
    } else {
        "–".into()
    }
}

/// The report's figures: drift warnings first, the yields, the Pareto, the histograms.
fn figures(ui: &mut egui::Ui, lang: Lang, r: &Report) {
    for m in &r.measurements {
        if let Some(d) = &m.drift {
            ui.colored_label(
                ui.visuals().error_fg_color,
                egui::RichText::new(lang.tr(
                    &format!(
                        "DRIFT: {} walks toward its {} limit {} {} (last 3 × {} units: {:.3} → {:.3} → {:.3}, {:.1} σ left)",
                        m.name, d.toward, d.limit, m.unit, d.window, d.means[0], d.means[1], d.means[2], d.left_sigma
                    ),
                    &format!(
                        "漂移:{} 正趋向{}限 {} {}(最近 3 × {} 台:{:.3} → {:.3} → {:.3},距限值 {:.1} σ)",
                        m.name,
                        if d.toward == "high" { "上" } else { "下" },
                        d.limit,
                        m.unit,
                        d.window,
                        d.means[0],
                        d.means[1],
                        d.means[2],
                        d.left_sigma
                    ),
                ))
                .strong(),
            );
        }
    }
    let o = &r.overall;
    ui.horizontal_wrapped(|ui| {
        big(ui, lang.tr("units", "台数"), o.units.to_string());
        big(ui, lang.tr("first-pass yield", "直通率"), pct(o.fpy()));
        big(ui, lang.tr("final yield", "最终良率"), pct(o.final_yield()));
        big(ui, lang.tr("runs", "测试次数"), o.runs.to_string());
    });
    ui.weak(format!("{} {}", lang.tr("shifts", "班次"), r.shifts));
    ui.add_space(6.0);
    let width = ui.available_width();
    let half = ((width - 12.0) / 2.0).max(280.0);
    ui.horizontal_wrapped(|ui| {
        ui.vertical(|ui| {
            ui.set_width(half);
            ui.strong(lang.tr("Yield per shift", "各班次良率"));
            yield_plot(ui, lang, &r.by_shift);
        });
        ui.vertical(|ui| {
            ui.set_width(half);
            ui.strong(lang.tr("Failing steps (Pareto)", "失败步骤(帕累托)"));
            pareto_plot(ui, lang, &r.pareto);
        });
    });
    ui.add_space(6.0);
    ui.horizontal_wrapped(|ui| {
        for (title, rows) in [
            (lang.tr("per station", "按工位"), &r.by_station),
            (lang.tr("per slot", "按治具位"), &r.by_slot),
            (lang.tr("per plan version", "按方案版本"), &r.by_plan),
        ] {
            ui.vertical(|ui| {
                ui.strong(title);
                yield_table(ui, lang, title, rows);
            });
            ui.add_space(16.0);
        }
    });
    ui.add_space(6.0);
    ui.strong(lang.tr("Measurements", "测量值"));
    let cols = if width > 900.0 { 3 } else { 2 };
    let w = (width - 12.0 * cols as f32) / cols as f32;
    for row in r.measurements.chunks(cols) {
        ui.horizontal(|ui| {
            for m in row {
                ui.vertical(|ui| {
                    ui.set_width(w);
                    histogram(ui, lang, m);
                });
            }
        });
    }
}

fn big(ui: &mut egui::Ui, label: &str, value: String) {
    ui.vertical(|ui| {
        ui.label(egui::RichText::new(value).size(26.0).strong());
        ui.weak(label);
    });
    ui.add_space(24.0);
}

fn yield_table(ui: &mut egui::Ui, lang: Lang, id: &str, rows: &[Yield]) {
    egui::Grid::new(("yield-table", id))
        .striped(true)
        .spacing([12.0, 2.0])
        .show(ui, |ui| {
            layout::header_row(
                ui,
                &[
                    "",
                    lang.tr("units", "台数"),
                    lang.tr("first-pass", "直通率"),
                    lang.tr("final", "最终"),
                ],
            );
            for y in rows.iter().take(12) {
                ui.label(group_label(lang, y));
                ui.label(y.units.to_string());
                ui.label(pct(y.fpy()));
                ui.label(pct(y.final_yield()));
                ui.end_row();
            }
        });
}

/// Integer grid marks, one every `every` from 0 to `n - 1` (the groups of a plot's axis).
fn integer_marks(n: usize, every: usize) -> Vec<GridMark> {
    (0..n)
        .step_by(every.max(1))
        .map(|i| GridMark {
            value: i as f64,
            step_size: every.max(1) as f64,
        })
        .collect()
}

/// A group as `lang` shows it: `2026-12-01 C (so far)` / `2026-12-01 C(进行中)` for the shift
/// under way.
fn group_label(lang: Lang, y: &Yield) -> String {
    match lang {
        Lang::En => y.label(),
        Lang::Zh if y.so_far => format!("{}(进行中)", y.group),
        Lang::Zh => y.group.clone(),
    }
}

/// `11-28 C` for `2026-11-28 C`: a shift's label short enough for an axis.
fn short_shift(label: &str) -> String {
    label.get(5..).unwrap_or(label).to_string()
}

fn yield_plot(ui: &mut egui::Ui, lang: Lang, rows: &[Yield]) {
    let labels: Vec<String> = rows
        .iter()
        .map(|y| short_shift(&group_label(lang, y)))
        .collect();
    let n = rows.len();
    // About 70 points per label: every k-th shift is named when they are many.
    let every = ((n as f32 * 70.0) / ui.available_width().max(1.0)).ceil() as usize;
    let fpy: Vec<[f64; 2]> = rows
        .iter()
        .enumerate()
        .map(|(i, y)| [i as f64, 100.0 * y.fpy()])
        .collect();
    let fin: Vec<[f64; 2]> = rows
        .iter()
        .enumerate()
        .map(|(i, y)| [i as f64, 100.0 * y.final_yield()])
        .collect();
    // Room below the lowest point for the key, so that it covers no data.
    let lowest = fpy
        .iter()
        .chain(&fin)
        .map(|p| p[1])
        .filter(|v| v.is_finite())
        .fold(100.0f64, f64::min);
    let fpy_name = lang.tr("first-pass yield", "直通率").to_string();
    let fin_name = lang.tr("final yield", "最终良率").to_string();
    Plot::new("yield-per-shift")
        .height(200.0)
        .legend(egui_plot::Legend::default().position(egui_plot::Corner::LeftBottom))
        .y_axis_label("%")
        .include_y(100.0)
        .include_y((lowest - (100.0 - lowest).max(2.0) * 0.6).max(0.0))
        .y_grid_spacer(|input| super::plot::y_marks(input, false))
        .include_x(-0.5)
        .include_x(n as f64 - 0.5)
        .allow_drag(false)
        .allow_zoom(false)
        .allow_scroll(false)
        .x_grid_spacer(move |_| integer_marks(n, every))
        .x_axis_formatter(move |mark, _| {
            let i = mark.value.round();
            if (mark.value - i).abs() < 1e-6 && i >= 0.0 {
                labels.get(i as usize).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        })
        .show(ui, |pui| {
            pui.line(Line::new(fpy_name.clone(), PlotPoints::from(fpy.clone())).color(BAD));
            pui.points(
                Points::new(fpy_name, PlotPoints::from(fpy))
                    .radius(3.0)
                    .color(BAD),
            );
            pui.line(Line::new(fin_name.clone(), PlotPoints::from(fin.clone())).color(GOOD));
            pui.points(
                Points::new(fin_name, PlotPoints::from(fin))
                    .radius(3.0)
                    .color(GOOD),
            );
        });
}

const GOOD: egui::Color32 = egui::Color32::from_rgb(46, 125, 50);
const BAD: egui::Color32 = egui::Color32::from_rgb(198, 40, 40);
const BARS: egui::Color32 = egui::Color32::from_rgb(84, 110, 122);

/// A recorded step's name as `lang` shows it: in 中文 where the step is known ([`step_zh`]),
/// else as recorded.
pub fn step_name(lang: Lang, recorded: &str) -> String {
    match lang {
        Lang::Zh => step_zh(recorded).unwrap_or_else(|| recorded.to_string()),
        Lang::En => recorded.to_string(),
    }
}

/// The 中文 name of a step the records keep in English, where botbench knows it: the line
/// station's steps ([`crate::ops::station::plan::title_zh`]), the shipped self-test plan's
/// steps (its `zh` map), provisioning's and a preset apply's own steps, the generated
/// records' steps; `None` for another plan's step.
pub fn step_zh(recorded: &str) -> Option<String> {
    static KNOWN: std::sync::OnceLock<std::collections::BTreeMap<String, String>> =
        std::sync::OnceLock::new();
    let known = KNOWN.get_or_init(|| {
        use crate::ops::servo::provision::step;
        let provisioning = step::ALL.map(|s| (s, step::said(s).zh));
        let mut known: std::collections::BTreeMap<String, String> =
            crate::ops::records::demo::STEP_NAMES_ZH
                .iter()
                .copied()
                .chain(crate::ops::records::runs::PRESET_STEPS_ZH)
                .map(|(en, zh)| (en.to_string(), zh.to_string()))
                .chain(provisioning.map(|(en, zh)| (en.to_string(), zh)))
                .collect();
        let profile = crate::profile::Registry::builtin().and_then(|r| r.get("window-cleaner"));
        for (file, text) in crate::ui::files::SHIPPED {
            if let Ok(profile) = &profile
                && let Ok(plan) = crate::ops::selftest::Plan::parse(file, text, profile)
            {
                known.extend(plan.zh);
            }
        }
        known
    });
    known
        .get(recorded)
        .cloned()
        .or_else(|| crate::ops::station::plan::title_zh(recorded))
}

/// The failing steps as horizontal bars, the most failures on top, each step named on the
/// axis and its count and share on hover.
fn pareto_plot(ui: &mut egui::Ui, lang: Lang, steps: &[ParetoStep]) {
    if steps.is_empty() {
        ui.label(lang.tr("No step failed.", "没有失败的步骤。"));
        return;
    }
    let shown: Vec<ParetoStep> = steps.iter().take(8).cloned().collect();
    let n = shown.len();
    // The most failures on top: the first step at the highest position.
    let labels: Vec<String> = shown.iter().rev().map(|p| step_name(lang, &p.step)).collect();
    let bars: Vec<Bar> = shown
        .iter()
        .enumerate()
        .map(|(i, p)| {
            Bar::new((n - 1 - i) as f64, p.count as f64)
                .width(0.7)
                .name(format!(
                    "{}: {} ({}, {} {})",
                    step_name(lang, &p.step),
                    p.count,
                    pct(p.share),
                    lang.tr("cumulative", "累计"),
                    pct(p.cumulative)
                ))
        })
        .collect();
    // The axis' labels are drawn smaller than the body text; the body font's width is ample.
    let font = layout::body_font(ui);
    let name_width =
        layout::text_width(ui, &font, labels.iter().map(String::as_str)).max(60.0) + 12.0;
    Plot::new("pareto")
        .height(200.0)
        .x_axis_label(lang.tr("failures", "失败次数"))
        .allow_drag(false)
        .allow_zoom(false)
        .allow_scroll(false)
        .include_x(0.0)
        .include_y(-0.5)
        .include_y(n as f64 - 0.5)
        .y_axis_min_width(name_width)
        // Every step named: marks one apart, each given the weight of the whole axis so that
        // egui_plot does not fade its label as it does a fine grid's.
        .y_grid_spacer(move |_| {
            integer_marks(n, 1)
                .into_iter()
                .map(|m| GridMark {
                    step_size: n.max(1) as f64,
                    ..m
                })
                .collect()
        })
        .y_axis_formatter(move |mark, _| {
            let i = mark.value.round();
            if (mark.value - i).abs() < 1e-6 && i >= 0.0 {
                labels.get(i as usize).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        })
        .show(ui, |pui| {
            pui.bar_chart(
                BarChart::new(lang.tr("failures", "失败次数"), bars)
                    .horizontal()
                    .color(BAD),
            );
        });
}

fn histogram(ui: &mut egui::Ui, lang: Lang, m: &MeasurementStats) {
    let title = if m.unit.is_empty() {
        m.name.clone()
    } else {
        format!("{} ({})", m.name, m.unit)
    };
    ui.strong(&title);
    let cpk = m.cpk.map_or("–".into(), |c| format!("{c:.2}"));
    let low_cpk = m.cpk.is_some_and(|c| c < 1.33);
    ui.horizontal(|ui| {
        ui.weak(format!(
            "n {}  {} {:.4}  σ {:.4}",
            m.n,
            lang.tr("mean", "均值"),
            m.mean,
            m.sigma
        ));
        let text = egui::RichText::new(format!("Cpk {cpk}"));
        if low_cpk {
            ui.colored_label(BAD, text.strong());
        } else {
            ui.label(text);
        }
    });
    let bars: Vec<Bar> = m
        .bins
        .iter()
        .enumerate()
        .map(|(i, &c)| {
            let a = m.bin_start + m.bin_width * i as f64;
            let inside = m.low.is_none_or(|l| a + m.bin_width > l) && m.high.is_none_or(|h| a < h);
            Bar::new(a + m.bin_width / 2.0, c as f64)
                .width(m.bin_width)
                .fill(if inside { BARS } else { BAD })
        })
        .collect();
    // Counts from 0, at least three of them labelled (about 100 points of data area).
    let most = m.bins.iter().copied().max().unwrap_or(0) as f64;
    let (low, high) = super::plot::y_range(0.0, most, 100.0, true).unwrap_or((0.0, 1.0));
    Plot::new(("histogram", &m.name, &m.unit))
        .height(140.0)
        .include_y(low.max(-0.5))
        .include_y(high)
        .y_grid_spacer(|input| super::plot::y_marks(input, true))
        .allow_drag(false)
        .allow_zoom(false)
        .allow_scroll(false)
        .show_y(false)
        .show(ui, |pui| {
            pui.bar_chart(BarChart::new(title.clone(), bars));
            for (v, name) in [
                (m.low, lang.tr("low limit", "下限")),
                (m.high, lang.tr("high limit", "上限")),
            ] {
                if let Some(v) = v {
                    pui.vline(VLine::new(name, v).color(BAD).width(2.0));
                }
            }
            pui.vline(
                VLine::new(lang.tr("mean", "均值"), m.mean)
                    .color(egui::Color32::from_rgb(25, 118, 210)),
            );
        });
}

impl crate::ui::PanelId {
    /// Production records: yield, failing steps, measurements.
    pub const YIELD: crate::ui::PanelId = crate::ui::PanelId::new("Yield");
}

impl crate::ui::Panel for YieldPanel {
    fn id(&self) -> crate::ui::PanelId {
        crate::ui::PanelId::YIELD
    }

    fn name(&self, lang: Lang) -> &'static str {
        lang.tr("Yield", "良率")
    }

    fn show(&mut self, ui: &mut egui::Ui, cx: &crate::ui::panel::Cx<'_>) -> Vec<Action> {
        self.draw(ui, cx.lang, cx.station)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shift_under_way_is_said_so_in_the_windows_language() {
        let mut y = Yield {
            group: "2026-12-07 A".into(),
            units: 3,
            runs: 4,
            first_pass: 2,
            final_pass: 3,
            so_far: true,
        };
        assert_eq!(group_label(Lang::En, &y), "2026-12-07 A (so far)");
        assert_eq!(group_label(Lang::Zh, &y), "2026-12-07 A(进行中)");
        y.so_far = false;
        assert_eq!(group_label(Lang::Zh, &y), "2026-12-07 A");
    }
}
