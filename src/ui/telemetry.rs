//! Live telemetry: the profile's plots (attitude, battery, …) drawn from bounded series with a
//! min/max decimation to the plot's pixel width, poll-rate and time-window controls, a cursor
//! readout, the other telemetry listed with live values, and CSV export.

use super::Action;
use super::jobs;
use super::settings::Settings;
use super::state::{AppState, Notice, Reading};
use crate::i18n::Lang;
use crate::profile::CommandKind;
use eframe::egui;
use egui_plot::{Legend, Line, Plot, PlotPoints, VLine};

/// Poll rates offered, polls a second (`None`: as fast as the wire allows).
pub const RATES: [Option<f64>; 8] = [
    Some(1.0),
    Some(2.0),
    Some(5.0),
    Some(10.0),
    Some(20.0),
    Some(50.0),
    Some(100.0),
    None,
];
/// Time windows offered, seconds.
pub const WINDOWS: [f64; 6] = [10.0, 30.0, 60.0, 120.0, 300.0, 600.0];

/// The panel's view state.
pub struct TelemetryPanel {
    /// Keep the newest data in view.
    pub follow: bool,
    /// The time under the pointer, for the readout.
    cursor: Option<f64>,
    /// Scratch for decimated points (no allocation per frame once grown).
    points: Vec<[f64; 2]>,
}

impl Default for TelemetryPanel {
    fn default() -> Self {
        Self {
            follow: true,
            cursor: None,
            points: Vec::new(),
        }
    }
}

fn rate_label(rate: Option<f64>, lang: Lang) -> String {
    match rate {
        Some(r) => format!("{r} Hz"),
        None => lang.tr("max (wire limit)", "最大(线速)").to_string(),
    }
}

impl TelemetryPanel {
    /// Draws the panel.
    pub fn show(&mut self, ui: &mut egui::Ui, saved: &Settings, rt: &AppState) -> Vec<Action> {
        let lang = saved.lang;
        let mut actions = Vec::new();
        ui.horizontal_wrapped(|ui| {
            let label = ui.label(lang.tr("Poll rate", "采样率"));
            egui::ComboBox::from_id_salt("rate")
                .selected_text(rate_label(saved.poll_hz, lang))
                .show_ui(ui, |ui| {
                    for r in RATES {
                        if ui
                            .selectable_label(saved.poll_hz == r, rate_label(r, lang))
                            .clicked()
                        {
                            actions.push(Action::SetPollRate(r));
                        }
                    }
                })
                .response
                .labelled_by(label.id);
            let paused = rt.link.polling_paused;
            let pause = if paused {
                lang.tr("Resume", "继续")
            } else {
                lang.tr("Pause", "暂停")
            };
            if ui.button(pause).clicked() {
                actions.push(Action::PausePolling(!paused));
            }
            let label = ui.label(lang.tr("Window", "时间窗"));
            egui::ComboBox::from_id_salt("window")
                .selected_text(format!("{} s", saved.window_secs))
                .show_ui(ui, |ui| {
                    for w in WINDOWS {
                        if ui
                            .selectable_label(saved.window_secs == w, format!("{w} s"))
                            .clicked()
                        {
                            actions.push(Action::SetPlotWindow(w));
                        }
                    }
                })
                .response
                .labelled_by(label.id);
            ui.checkbox(&mut self.follow, lang.tr("Follow", "跟随"));
            if ui.button(lang.tr("Export CSV", "导出 CSV")).clicked() {
                actions.push(export_csv(rt));
            }
        });
        ui.separator();
        let plots = &rt.device.profile.plots;
        let height = ((ui.available_height() - 160.0) / plots.len().max(1) as f32).max(120.0);
        let now = rt.device.t0.elapsed().as_secs_f64();
        let window = saved.window_secs;
        let link = egui::Id::unique("telemetry-x");
        let mut hovered = None;
        for plot in plots {
            ui.label(egui::RichText::new(lang.tr(&plot.name.en, &plot.name.zh)).strong());
            let set = rt.device.plots.get(&plot.id);
            let end = if self.follow {
                now
            } else {
                set.and_then(|s| s.span()).map_or(now, |s| s.1)
            };
            let width_px = ui.available_width().max(100.0) as usize;
            let cursor = self.cursor;
            let points = &mut self.points;
            let follow = self.follow;
            let resp = Plot::new(("plot", &plot.id))
                .height(height)
                .legend(Legend::default())
                .link_axis(link, [true, false])
                .allow_drag(!follow)
                .allow_zoom(!follow)
                .show(ui, |pui| {
                    if follow {
                        pui.set_plot_bounds_x(end - window..=end);
                        pui.set_auto_bounds([false, true]);
                    }
                    let bounds = pui.plot_bounds();
                    let (t0, t1) = (bounds.min()[0], bounds.max()[0]);
                    if let Some(set) = set {
                        for name in &plot.fields {
                            let Some(series) = set.get(name) else {
                                continue;
                            };
                            points.clear();
                            series.decimate(t0, t1, width_px, points);
                            pui.line(Line::new(name.clone(), PlotPoints::from(points.clone())));
                        }
                    }
                    if let Some(t) = cursor {
                        pui.vline(VLine::new("cursor", t));
                    }
                    pui.pointer_coordinate().map(|p| p.x)
                });
            if let Some(t) = resp.inner {
                hovered = Some(t);
            }
            if let (Some(t), Some(set)) = (self.cursor.or(hovered), set) {
                ui.horizontal_wrapped(|ui| {
                    ui.weak(format!("t = {t:.2} s"));
                    for name in &plot.fields {
                        if let Some(s) = set.value_at(name, t) {
                            ui.monospace(format!("{name} = {:.3}", s.v));
                        }
                    }
                });
            }
        }
        self.cursor = hovered;
        ui.separator();
        actions.extend(self.other_telemetry(ui, lang, rt));
        actions
    }

    /// The profile's other telemetry, with the values the last reads brought.
    fn other_telemetry(&self, ui: &mut egui::Ui, lang: Lang, rt: &AppState) -> Vec<Action> {
        let mut actions = Vec::new();
        let cmds: Vec<_> = rt
            .device
            .profile
            .commands
            .iter()
            .filter(|c| c.kind == CommandKind::Telemetry && !c.reply.is_empty())
            .collect();
        ui.horizontal(|ui| {
            ui.strong(lang.tr("Other telemetry", "其他数据"));
            let busy = rt.job_progress().is_some();
            if ui
                .add_enabled(
                    rt.connected() && !busy,
                    egui::Button::new(lang.tr("Read all", "全部读取")),
                )
                .clicked()
            {
                actions.push(Action::StartJob(jobs::read(
                    &rt.device.profile,
                    cmds.iter().map(|c| c.id).collect(),
                )));
            }
        });
        egui::ScrollArea::vertical()
            .id_salt("other")
            .max_height(150.0)
            .show(ui, |ui| {
                egui::Grid::new("other-grid")
                    .striped(true)
                    .num_columns(2)
                    .show(ui, |ui| {
                        for cmd in cmds {
                            ui.label(lang.tr(&cmd.name.en, &cmd.name.zh))
                                .on_hover_text(&cmd.ident);
                            match rt.device.readings.get(&cmd.id) {
                                Some(Reading::Values(values, at)) => {
                                    let text: Vec<String> = values
                                        .iter()
                                        .map(|(k, v)| {
                                            let shown = cmd
                                                .reply
                                                .iter()
                                                .find(|f| f.ident == k)
                                                .map_or(format!("{v:?}"), |f| f.display(v));
                                            format!("{k}={shown}")
                                        })
                                        .collect();
                                    ui.monospace(text.join("  ")).on_hover_text(format!(
                                        "{:.1} s ago",
                                        at.elapsed().as_secs_f64()
                                    ));
                                }
                                Some(Reading::Failed(e)) => {
                                    ui.colored_label(egui::Color32::RED, e.to_string());
                                }
                                None => {
                                    ui.weak(lang.tr("not read yet", "尚未读取"));
                                }
                            }
                            ui.end_row();
                        }
                    });
            });
        actions
    }
}

/// Asks where to save and writes every plot's series as CSV.
fn export_csv(rt: &AppState) -> Action {
    let Some(path) = rfd::FileDialog::new()
        .set_file_name("telemetry.csv")
        .add_filter("CSV", &["csv"])
        .save_file()
    else {
        return Action::Notify(Notice::info(
            "export cancelled (no file chosen, or no file dialog on this system)",
        ));
    };
    match write_csv(rt, &path) {
        Ok(n) => Action::Notify(Notice::info(format!(
            "{n} plot(s) written to {}",
            path.display()
        ))),
        Err(e) => Action::Notify(Notice::error(e.to_string())),
    }
}

/// Writes every plotted series to `path` as one CSV (a column per `plot.field`, a row per time),
/// atomically. Returns the number of plots written.
pub fn write_csv(
    rt: &AppState,
    path: &std::path::Path,
) -> Result<usize, crate::document::DocumentError> {
    let mut all = crate::series::SeriesSet::new(crate::series::DEFAULT_CAPACITY);
    let mut n = 0;
    for plot in &rt.device.profile.plots {
        let Some(set) = rt.device.plots.get(&plot.id) else {
            continue;
        };
        n += 1;
        for (name, series) in set.iter() {
            let column = format!("{}.{name}", plot.id);
            for s in series.iter() {
                let _ = all.push(&column, s.t, s.v);
            }
        }
    }
    let mut buf = Vec::new();
    all.write_csv(&mut buf)
        .map_err(|e| crate::document::DocumentError::io(path, "write", &e))?;
    crate::document::write_atomic(path, &buf)?;
    Ok(n)
}
