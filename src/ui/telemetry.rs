//! Live telemetry: the profile's plots (attitude, battery, …) drawn from bounded series with a
//! min/max decimation to the plot's pixel width and broken at gaps, poll-rate and time-window
//! controls, a cursor readout of the sample under the pointer, the other telemetry listed with
//! live values in a part of its own, and CSV export to a typed or chosen file.

use super::jobs;
use super::settings::{FileKind, Settings};
use super::station::{Notice, Reading, Station};
use super::{Action, files, plot};
use crate::i18n::Lang;
use crate::i18n::Text;
use crate::profile::CommandKind;
use crate::ui::zh::Zh;
use eframe::egui;
use egui_plot::{Plot, VLine};

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
    /// Keep the newest data in view (where polling was paused, while it is).
    pub follow: bool,
    /// The time under the pointer while it is over a plot (as of the last frame).
    cursor: Option<f64>,
    /// Scratch for decimated points (no allocation per frame once grown).
    scratch: plot::Scratch,
    /// What each plot showed when last drawn, in profile order.
    pub shown: Vec<Shown>,
    /// The CSV export's file (typed, or chosen with Browse).
    pub csv_path: String,
    /// Where the plots' scroll area showed them when last drawn.
    pub plots_view: egui::Rect,
}

/// The least height of a plot's drawing (its data area, without axes), points: below it the
/// plots scroll instead of shrinking.
pub const MIN_PLOT_HEIGHT: f32 = 100.0;

/// The height a plot takes beside its data area: its title, key and readout line above and
/// below it, the air under the key ([`plot::key_air`]), and its x axis (tick labels and the
/// axis' label).
fn plot_chrome(ui: &egui::Ui) -> f32 {
    3.0 * line_height(ui) + plot::key_air(ui) + x_axis_height(ui)
}

/// A line of body text with the space after it.
fn line_height(ui: &egui::Ui) -> f32 {
    ui.text_style_height(&egui::TextStyle::Body) + ui.spacing().item_spacing.y
}

/// The x axis under a plot's data area: its tick labels and its label, with some air.
fn x_axis_height(ui: &egui::Ui) -> f32 {
    2.0 * line_height(ui) + 4.0
}

/// What one plot showed when last drawn.
#[derive(Debug, Clone, PartialEq)]
pub struct Shown {
    /// The plot's id.
    pub id: String,
    /// Its time range, seconds.
    pub x: (f64, f64),
    /// The cursor readout under it, if any.
    pub readout: Option<plot::Readout>,
    /// Its fields' names, y axis label and number format, in the window's language.
    pub legend: plot::Legend,
    /// Where the plot was drawn: its data area (time `x.0..x.1` left to right, values
    /// `y.0..y.1` bottom to top), without its axes.
    pub rect: egui::Rect,
    /// Its value range, in the fields' display units.
    pub y: (f64, f64),
}

impl Default for TelemetryPanel {
    fn default() -> Self {
        Self {
            follow: true,
            cursor: None,
            scratch: plot::Scratch::default(),
            shown: Vec::new(),
            csv_path: String::new(),
            plots_view: egui::Rect::NOTHING,
        }
    }
}

/// Over how many of the newest seconds the achieved poll rate is counted.
const ACHIEVED_OVER: f64 = 2.0;

/// The poll rate achieved: samples a second of the first plot's first field over the newest
/// [`ACHIEVED_OVER`] seconds, while samples are coming (`None` when paused, lost, or too few).
pub fn achieved_rate(rt: &Station) -> Option<f64> {
    if rt.link.polling_paused {
        return None;
    }
    let plot = rt.device.profile.plots.first()?;
    let series = rt.device.plots.get(&plot.id)?.get(plot.fields.first()?)?;
    let now = rt.device.t0.elapsed().as_secs_f64();
    let fresh = series.latest()?.t > now - ACHIEVED_OVER;
    fresh.then(|| series.rate(ACHIEVED_OVER)).flatten()
}

/// The poll rate achieved, beside the one asked for.
fn achieved_label(ui: &mut egui::Ui, lang: Lang, rt: &Station) {
    let text = match achieved_rate(rt) {
        Some(r) => format!("{} {r:.1} Hz", lang.tr("achieved", "实际")),
        None => format!("{} —", lang.tr("achieved", "实际")),
    };
    // As wide as its widest reading in either language: a changing rate moves nothing after it.
    let width = crate::ui::layout::text_width(
        ui,
        &crate::ui::layout::body_font(ui),
        ["achieved 1000.0 Hz", "实际 1000.0 Hz"],
    );
    let height = ui.spacing().interact_size.y;
    ui.add_sized([width, height], egui::Label::new(text))
        .on_hover_text(lang.tr(
            "Answers a second over the last 2 s: what the device, the adapter and the link achieve",
            "最近 2 秒每秒收到的应答数:设备、适配器与链路实际达到的采样率",
        ));
}

fn rate_label(rate: Option<f64>, lang: Lang) -> String {
    match rate {
        Some(r) => format!("{r} Hz"),
        None => lang.tr("max (wire limit)", "最大(线速)").to_string(),
    }
}

/// The telemetry commands listed under the plots: every one with a reply, but the core ones
/// (version, power state, build info), which the device panel reads and shows.
fn other_commands(rt: &Station) -> Vec<&crate::profile::Command> {
    let profile = &rt.device.profile;
    profile
        .commands
        .iter()
        .filter(|c| c.kind == CommandKind::Telemetry && !c.reply.is_empty())
        .filter(|c| !profile.is_core(c))
        .collect()
}

impl TelemetryPanel {
    /// Draws the panel.
    fn draw(&mut self, ui: &mut egui::Ui, saved: &Settings, rt: &Station) -> Vec<Action> {
        let lang = saved.lang;
        let mut actions = Vec::new();
        crate::ui::layout::toolbar(ui, |ui| {
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
            achieved_label(ui, lang, rt);
            let paused = rt.link.polling_paused;
            let pause = if paused {
                lang.tr("Resume", "继续")
            } else {
                lang.tr("Pause", "暂停")
            };
            if ui.add(super::inputs::steady_button(pause)).clicked() {
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
        });
        crate::ui::layout::toolbar(ui, |ui| {
            let event = files::row(
                ui,
                lang,
                files::Row {
                    label: lang.tr("CSV file", "CSV 文件"),
                    hint: "telemetry.csv",
                    pick: files::Pick::Save("telemetry.csv"),
                    enabled: true,
                },
                &mut self.csv_path,
                &rt.dialogs,
            );
            let export = ui.button(lang.tr("Export CSV", "导出 CSV")).clicked();
            if event.go(export, &mut actions) {
                actions.extend(export_csv(rt, &self.csv_path));
            }
        });
        ui.separator();
        // The other telemetry below, in a part the technician can resize: by default room for
        // every command, up to 45 % of the panel, and never so much that a plot at its least
        // height does not fit above it (on a 600-point screen the plots come first).
        let cmds = other_commands(rt);
        let avail = ui.available_height();
        let row_h = ui.spacing().interact_size.y + ui.spacing().item_spacing.y;
        let wanted = (cmds.len() as f32 + 2.0) * row_h;
        let one_plot = MIN_PLOT_HEIGHT + plot_chrome(ui);
        // Its heading, two rows and the panel's margins: less and its content would be drawn
        // over the plots (egui clips a panel's content to the size it reports).
        let least = row_h * 3.0 + 2.0 * 8.0;
        let most = (avail - one_plot).max(least);
        let default = wanted.clamp(avail * 0.25, avail * 0.45).clamp(least, most);
        egui::Panel::bottom("other-telemetry")
            .frame(super::backdrop::bar(ui.style()))
            .resizable(true)
            .default_size(default)
            // Kept so when the window shrinks (the part keeps its size from a larger window).
            .size_range(least..=most)
            .show(ui, |ui| {
                actions.extend(self.other_telemetry(ui, lang, rt, &cmds))
            });
        self.plots(ui, saved, rt);
        actions
    }

    /// The profile's plots, sharing the height left, each at least [`MIN_PLOT_HEIGHT`] (below
    /// that they scroll, with their scroll bar shown); each with its cursor readout below it,
    /// on a line kept whether or not there is one, so that nothing below moves.
    fn plots(&mut self, ui: &mut egui::Ui, saved: &Settings, rt: &Station) {
        let lang = saved.lang;
        let plots = &rt.device.profile.plots;
        let text_h = ui.text_style_height(&egui::TextStyle::Body);
        let chrome = plot_chrome(ui);
        let n = plots.len().max(1) as f32;
        // The plot widget's height: its data area and its x axis.
        let height =
            ((ui.available_height() - n * chrome) / n).max(MIN_PLOT_HEIGHT) + x_axis_height(ui);
        let window = saved.window_secs;
        let follow = self.follow;
        let link = egui::Id::unique("telemetry-x");
        let cursor = self.cursor;
        let mut hovered = None;
        self.shown.clear();
        let scrolled = egui::ScrollArea::vertical()
            .id_salt("plots")
            .auto_shrink(false)
            .show(ui, |ui| {
                for p in plots {
                    ui.label(egui::RichText::new(lang.tr(&p.name.en, &p.name.zh)).strong());
                    let legend =
                        plot::Legend::new(rt.device.profile.command(&p.command), &p.fields, lang);
                    plot::key(ui, &legend, &plot::states(rt, p, lang));
                    let set = rt.device.plots.get(&p.id);
                    let end = if follow {
                        rt.plot_end()
                    } else {
                        set.and_then(|s| s.span()).map_or(rt.plot_end(), |s| s.1)
                    };
                    let width_px = ui.available_width().max(100.0) as usize;
                    let scratch = &mut self.scratch;
                    let plot = Plot::new(("plot", &p.id)).height(height);
                    let integer = legend.integer;
                    // In time only: the y range fits what is drawn (plot::fit_y).
                    let resp = plot::axes(plot, lang, rt.device.t0_wall, &legend)
                        .link_axis(link, [true, false])
                        .allow_drag([!follow, false])
                        .allow_zoom([!follow, false])
                        .allow_scroll([!follow, false])
                        // The readout below says what is under the cursor, from samples only.
                        .show_x(false)
                        .show_y(false)
                        .show(ui, |pui| {
                            let x = if follow {
                                pui.set_plot_bounds_x(end - window..=end);
                                (end - window, end)
                            } else {
                                let b = pui.plot_bounds();
                                (b.min()[0], b.max()[0])
                            };
                            let dx = pui.transform().dpos_dvalue_x().abs().max(1e-12);
                            let readout = match (cursor, set) {
                                (Some(t), Some(set)) => {
                                    plot::nearest(set, &p.fields, t, plot::REACH_PX / dx)
                                }
                                _ => None,
                            };
                            let extent = set.and_then(|set| {
                                plot::lines(pui, set, &p.fields, &legend, x, width_px, scratch)
                            });
                            plot::fit_y(pui, extent, integer);
                            if let Some(r) = &readout {
                                let gray = egui::Color32::from_gray(140);
                                pui.vline(VLine::new("", r.t).stroke(egui::Stroke::new(1.0, gray)));
                            }
                            let over = pui.response().hovered();
                            let t = pui.pointer_coordinate().map(|c| c.x).filter(|_| over);
                            (t, readout, x)
                        });
                    let (t, readout, x) = resp.inner;
                    if t.is_some() {
                        hovered = t;
                    }
                    readout_line(ui, lang, rt, p, readout.as_ref(), text_h);
                    self.shown.push(Shown {
                        id: p.id.clone(),
                        x,
                        readout,
                        legend,
                        rect: resp.response.rect,
                        y: resp.transform.bounds().range_y().into_inner(),
                    });
                }
            });
        self.plots_view = scrolled.inner_rect;
        self.cursor = hovered;
    }

    /// The profile's other telemetry, with the values the last reads brought, in all the room
    /// its part of the panel has.
    fn other_telemetry(
        &self,
        ui: &mut egui::Ui,
        lang: Lang,
        rt: &Station,
        cmds: &[&crate::profile::Command],
    ) -> Vec<Action> {
        let mut actions = Vec::new();
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
        // Both ways, and down to one row: long readings scroll sideways instead of widening the
        // panel past the window, and a low part keeps its heading above its rows.
        let row_h = ui.spacing().interact_size.y + ui.spacing().item_spacing.y;
        egui::ScrollArea::both()
            .id_salt("other")
            .min_scrolled_height(ui.spacing().interact_size.y)
            .auto_shrink(false)
            .min_scrolled_height(row_h)
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
                                            // By the field's name and a named value by its
                                            // name, in the window's language.
                                            match cmd.reply.iter().find(|f| f.ident == k) {
                                                Some(f) => {
                                                    let shown = match f.range_mark(v) {
                                                        Some(mark) => format!(
                                                            "{} {}",
                                                            super::inputs::short_text(f, v, lang),
                                                            crate::ui::zh::value_marks(&mark, lang)
                                                        ),
                                                        None => {
                                                            super::inputs::short_text(f, v, lang)
                                                        }
                                                    };
                                                    format!("{}: {shown}", f.name.get(lang))
                                                }
                                                None => format!("{k}: {v:?}"),
                                            }
                                        })
                                        .collect();
                                    ui.monospace(text.join("  ")).on_hover_text(format!(
                                        "{:.1} {}",
                                        at.elapsed().as_secs_f64(),
                                        lang.tr("s ago", "秒前")
                                    ));
                                }
                                Some(Reading::Failed(e)) => {
                                    ui.colored_label(egui::Color32::RED, e.in_lang(lang));
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

/// The readout under a plot: the sample's time and each field's value, on a line of its own
/// that is there (empty) when there is nothing to read out.
fn readout_line(
    ui: &mut egui::Ui,
    lang: Lang,
    rt: &Station,
    p: &crate::profile::Plot,
    readout: Option<&plot::Readout>,
    text_h: f32,
) {
    let (rect, _) = ui.allocate_exact_size(
        egui::vec2(ui.available_width(), text_h + 2.0),
        egui::Sense::hover(),
    );
    let Some(r) = readout else { return };
    let mut line = ui.new_child(
        egui::UiBuilder::new()
            .max_rect(rect)
            .layout(egui::Layout::left_to_right(egui::Align::Center)),
    );
    line.set_clip_rect(rect.intersect(ui.clip_rect()));
    line.weak(plot::clock(rt.device.t0_wall, r.t, true));
    let cmd = rt.device.profile.command(&p.command);
    for (ident, v) in &r.values {
        let f = cmd.and_then(|c| c.reply.iter().find(|f| &f.ident == ident));
        let text = match f {
            Some(f) => format!(
                "{} = {:.*}{}",
                lang.tr(&f.name.en, &f.name.zh),
                f.decimals(),
                v,
                f.unit_suffix()
            ),
            None => format!("{ident} = {v}"),
        };
        line.monospace(text);
    }
}

/// Writes every plot's series as CSV to the typed (or chosen) `path`; says what happened.
fn export_csv(rt: &Station, path: &str) -> Vec<Action> {
    let path = path.trim();
    if path.is_empty() {
        return vec![Action::Notify(Notice::error(Text::new(
            "export: give the CSV file's path (type it, or Browse)",
            "导出:请给出 CSV 文件路径(输入,或点击浏览)",
        )))];
    }
    let path = std::path::PathBuf::from(path);
    match write_csv(rt, &path) {
        Ok(n) => vec![
            Action::RememberFile(FileKind::TelemetryCsv, path.display().to_string()),
            Action::Notify(Notice::info(Text::new(
                format!("{n} plot(s) written to {}", path.display()),
                format!("{n} 个图已写入 {}", path.display()),
            ))),
        ],
        Err(e) => vec![Action::Notify(Notice::error(e.said()))],
    }
}

/// Writes every plotted series to `path` as one CSV (a column per `plot.field`, a row per time),
/// atomically. Returns the number of plots written.
pub fn write_csv(
    rt: &Station,
    path: &std::path::Path,
) -> Result<usize, crate::document::DocumentError> {
    let mut all = crate::series::SeriesSet::new(crate::series::DEFAULT_CAPACITY);
    let mut format = crate::series::CsvFormat {
        start: Some(rt.device.t0_wall),
        decimals: Vec::new(),
    };
    let mut decimals = std::collections::HashMap::new();
    let mut n = 0;
    let profile = &rt.device.profile;
    for plot in &profile.plots {
        let Some(set) = rt.device.plots.get(&plot.id) else {
            continue;
        };
        n += 1;
        let fields = profile.command(&plot.command).map(|c| &c.reply);
        for (name, series) in set.iter() {
            let column = format!("{}.{name}", plot.id);
            for s in series.iter() {
                let _ = all.push(&column, s.t, s.v);
            }
            // At the field's precision, as the window shows it.
            let field = fields.and_then(|f| f.iter().find(|f| f.ident.eq_ignore_ascii_case(name)));
            let d = field.map(|f| f.convert.map_or_else(|| f.decimals(), |c| c.decimals()));
            decimals.insert(column, d);
        }
    }
    format.decimals = all
        .iter()
        .map(|(column, _)| decimals.get(column).copied().flatten())
        .collect();
    let mut buf = Vec::new();
    all.write_csv_as(&mut buf, &format)
        .map_err(|e| crate::document::DocumentError::io(path, "write", &e))?;
    crate::document::write_atomic(path, &buf)?;
    Ok(n)
}

impl crate::ui::PanelId {
    /// Live plots and telemetry.
    pub const TELEMETRY: crate::ui::PanelId = crate::ui::PanelId::new("Telemetry");
}

impl crate::ui::Panel for TelemetryPanel {
    fn id(&self) -> crate::ui::PanelId {
        crate::ui::PanelId::TELEMETRY
    }

    fn name(&self, lang: Lang) -> &'static str {
        lang.tr("Telemetry", "实时数据")
    }

    fn kind(&self) -> Option<crate::profile::PanelKind> {
        Some(crate::profile::PanelKind::Telemetry)
    }

    fn show(&mut self, ui: &mut egui::Ui, cx: &crate::ui::panel::Cx<'_>) -> Vec<Action> {
        self.draw(ui, cx.settings, cx.station)
    }

    fn restore(&mut self, settings: &Settings) {
        if let Some(p) = settings.file(FileKind::TelemetryCsv) {
            self.csv_path = p.to_string();
        }
    }

    fn live(&self, station: &Station) -> bool {
        station.connected() && !station.link.polling_paused
    }
}
