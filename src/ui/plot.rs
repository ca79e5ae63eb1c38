//! What every live plot shares: its series drawn as lines broken at the recording's gaps (a
//! link outage, a failed poll, polling paused), one colour per field whatever the number of
//! stretches, and the sample nearest a time within reach, for a cursor readout; the axes a
//! technician reads (wall-clock time as the packet monitor shows it, the fields' unit, integers
//! without decimals) and a key of the fields' names in the window's language above the plot,
//! where it covers no data.

use super::inputs::readout_text;
use super::station::{Reading, Station};
use crate::i18n::Lang;
use crate::profile::{Command, Field, Value};
use crate::series::SeriesSet;
use eframe::egui;
use egui_plot::{AxisHints, GridInput, GridMark, Line, Plot, PlotPoints, PlotUi};
use std::ops::RangeInclusive;
use std::time::{Duration, SystemTime};

/// How far (in pixels) from the pointer a sample may be and still be read out.
pub const REACH_PX: f64 = 12.0;

/// The colour of a plot's `i`-th field (egui_plot's own sequence, fixed here so that every
/// stretch of a broken line keeps its field's colour).
pub fn color(i: usize) -> egui::Color32 {
    let h = i as f32 * (std::f32::consts::GOLDEN_RATIO - 1.0);
    egui::ecolor::Hsva::new(h.fract(), 0.85, 0.5, 1.0).into()
}

/// Scratch buffers reused from frame to frame (no allocation per frame once grown).
#[derive(Default)]
pub struct Scratch {
    points: Vec<[f64; 2]>,
    starts: Vec<usize>,
}

/// How a plot's fields are read: each field's name (in the window's language, with its unit),
/// the y axis' label, and whether every field is a whole number.
#[derive(Debug, Clone, PartialEq)]
pub struct Legend {
    /// Per field, in order: `Battery voltage (V)` / `电池电压 (V)`; a field the command does not
    /// have keeps its ident.
    pub names: Vec<String>,
    /// The y axis label: the fields' units (`V`, `g`), or "unit not published" (short enough
    /// for a plot at its least height).
    pub y_label: String,
    /// Every field is a whole number (no scale): ticks and readouts show no decimals.
    pub integer: bool,
}

impl Legend {
    /// The legend of `fields` of `cmd` (a Get or Telemetry command's reply) in `lang`.
    pub fn new(cmd: Option<&Command>, fields: &[String], lang: Lang) -> Self {
        let field = |ident: &String| -> Option<&Field> {
            cmd.and_then(|c| c.reply.iter().find(|f| &f.ident == ident))
        };
        let names = fields
            .iter()
            .map(|ident| match field(ident) {
                Some(f) if f.unit.is_empty() => lang.tr(&f.name.en, &f.name.zh).to_string(),
                Some(f) => format!("{} ({})", lang.tr(&f.name.en, &f.name.zh), f.unit),
                None => ident.clone(),
            })
            .collect();
        let mut units: Vec<&str> = fields
            .iter()
            .filter_map(field)
            .map(|f| f.unit.as_str())
            .collect();
        units.dedup();
        let y_label = match units.as_slice() {
            [one] if !one.is_empty() => one.to_string(),
            [] | [_] => lang.tr("unit not published", "单位未公布").to_string(),
            many => many.join(", "),
        };
        let integer = fields
            .iter()
            .all(|i| field(i).is_some_and(|f| f.scale == 1.0 && f.convert.is_none()));
        Self {
            names,
            y_label,
            integer,
        }
    }
}

/// The wall-clock time (local, as the packet monitor shows it) of plot time `t` seconds after
/// `t0`: `12:00:01` (with milliseconds when `millis`).
pub fn clock(t0: SystemTime, t: f64, millis: bool) -> String {
    let at = if t >= 0.0 {
        t0 + Duration::from_secs_f64(t)
    } else {
        t0 - Duration::from_secs_f64(-t)
    };
    let at = chrono::DateTime::<chrono::Local>::from(at);
    if millis {
        at.format("%H:%M:%S%.3f").to_string()
    } else {
        at.format("%H:%M:%S").to_string()
    }
}

/// A y tick: no decimals for whole-number fields (and no tick between two whole numbers),
/// otherwise as many decimals as the tick spacing needs.
pub fn y_tick(mark: GridMark, integer: bool) -> String {
    if integer {
        if mark.value.fract().abs() > 1e-9 {
            return String::new();
        }
        return format!("{:.0}", mark.value);
    }
    let mut decimals = (-mark.step_size.log10().floor()).clamp(0.0, 6.0) as i32;
    // A step of 2.5 (or 0.25) needs one decimal more than its power of ten.
    let scaled = mark.step_size * 10f64.powi(decimals);
    if (scaled - scaled.round()).abs() > 1e-6 * scaled.abs().max(1.0) && decimals < 6 {
        decimals += 1;
    }
    format!("{:.*}", decimals as usize, mark.value)
}

/// `plot` with the axes every live plot shares: x in wall-clock time since `t0`, y labelled
/// with the fields' unit, its ticks placed by [`y_marks`] and written as [`y_tick`], each
/// labelled once [`Y_LABEL_SPACING`] apart; no legend inside the plot (see [`key`]). The y
/// range is the plot's to set ([`y_range`], through [`fit_y`]): a plot drawn with these axes
/// drags and zooms in time only.
pub fn axes<'a>(plot: Plot<'a>, lang: Lang, t0: SystemTime, legend: &Legend) -> Plot<'a> {
    let integer = legend.integer;
    let y = AxisHints::new_y()
        .label(legend.y_label.clone())
        .formatter(move |mark: GridMark, _: &RangeInclusive<f64>| y_tick(mark, integer))
        .label_spacing(Y_LABEL_SPACING..=Y_LABEL_SPACING + 4.0);
    plot.x_axis_label(lang.tr("time", "时间"))
        .x_axis_formatter(move |mark: GridMark, _: &RangeInclusive<f64>| {
            clock(t0, mark.value, mark.step_size < 1.0)
        })
        .custom_y_axes(vec![y])
        .grid_spacing(GRID_SPACING..=300.0)
        .y_grid_spacer(move |input: GridInput| y_marks(input, integer))
}

/// The least distance between two labelled y ticks, points (egui_plot's own for a y axis): a
/// tick label is about 15 points high.
pub const Y_LABEL_SPACING: f32 = 20.0;
/// The least distance between two grid lines, points (egui_plot's default, set here because
/// [`y_marks`] reads the plot's scale from it).
pub const GRID_SPACING: f32 = 8.0;
/// The least air above and below the data in a range from [`y_range`], in y ticks.
const Y_AIR: f64 = 0.1;
/// Half a y tick label's height, points: the outermost labelled ticks of a range from
/// [`y_range`] are at least this far inside the data area, so that the lowest label does not
/// reach down into the time axis's labels (seen at 1024×600: "-200" drawn over "04:38:06").
const Y_LABEL_HALF: f64 = 8.0;
/// The most ticks apart a range from [`y_range`] is, however high its plot.
const MOST_APART: f64 = 6.0;

/// Tick steps, one decade: every step of a y axis is one of these times a power of ten.
const STEPS: [f64; 4] = [1.0, 2.0, 2.5, 5.0];
/// ... and of a whole-number axis under ten (2.5 is no whole number).
const WHOLE_STEPS: [f64; 4] = [1.0, 2.0, 4.0, 5.0];

/// The smallest tick step of at least `least` (a whole number for a whole-number axis, at
/// least 1), from [`STEPS`]: none is more than twice the one before.
pub fn nice_step(least: f64, integer: bool) -> f64 {
    let least = if integer { least.max(1.0) } else { least };
    if !least.is_finite() || least <= 0.0 {
        return 1.0;
    }
    let decade = 10f64.powf(least.log10().floor());
    let steps = if integer && decade < 10.0 {
        WHOLE_STEPS
    } else {
        STEPS
    };
    steps
        .iter()
        .chain(&[10.0])
        .map(|m| m * decade)
        .find(|s| *s >= least * (1.0 - 1e-9))
        .unwrap_or(10.0 * decade)
}

/// The y grid of a plot (egui_plot's y grid spacer): labelled marks at every multiple of the
/// smallest step [`nice_step`] that puts them [`Y_LABEL_SPACING`] apart (and a seventh of the
/// axis on a high plot), and finer unlabelled
/// lines between them (whole numbers only on a whole-number axis). `input.base_step_size` is
/// [`GRID_SPACING`] points in plot units. In a range from [`y_range`] there are at least three
/// labelled marks.
pub fn y_marks(input: GridInput, integer: bool) -> Vec<GridMark> {
    let (lo, hi) = input.bounds;
    let per_point = input.base_step_size / f64::from(GRID_SPACING);
    let usable = hi > lo && per_point > 0.0 && per_point.is_finite();
    if !usable {
        return Vec::new();
    }
    // Labels at least Y_LABEL_SPACING apart, and no more than about MOST_APART + 1 of them.
    let height = (hi - lo) / per_point;
    let spacing = f64::from(Y_LABEL_SPACING).max(height / (MOST_APART + 1.0));
    // egui_plot labels ticks further apart than the spacing, not as far.
    let step = nice_step(per_point * spacing * 1.001, integer);
    // Finer lines at a fifth of the step (a quarter of a 2 or a 4: 0.5 and 1).
    let mantissa = step / 10f64.powf(step.log10().floor());
    let quarter = (mantissa - 2.0).abs() < 1e-9 || (mantissa - 4.0).abs() < 1e-9;
    let fine = step / if quarter { 4.0 } else { 5.0 };
    let mut marks = Vec::new();
    let first = (lo / fine).ceil() as i64;
    let last = (hi / fine).floor() as i64;
    // Past a few hundred lines the finer ones would not be drawn anyway.
    if last - first > 1000 {
        return marks;
    }
    for i in first..=last {
        let value = i as f64 * fine;
        let on_step = ((value / step).round() * step - value).abs() < fine * 1e-6;
        if on_step {
            let value = (value / step).round() * step;
            marks.push(GridMark {
                value,
                step_size: step,
            });
        } else if !integer || value.fract().abs() < 1e-9 {
            marks.push(GridMark {
                value,
                step_size: fine,
            });
        }
    }
    marks
}

/// The y range a plot `height` points high shows `lo..=hi` (its data's lowest and highest)
/// in: whole ticks of a [`nice_step`] around the data, at least two of them apart, with a
/// little air, so that [`y_marks`] labels at least three ticks once the data area is 3
/// [`Y_LABEL_SPACING`]s high (60 points; the plots are at least 90). A flat trace is given
/// a span of its own (1 % of its value, at least 0.1, or 1 for whole numbers). `None` for no
/// data (non-finite bounds).
pub fn y_range(lo: f64, hi: f64, height: f32, integer: bool) -> Option<(f64, f64)> {
    if !lo.is_finite() || !hi.is_finite() || lo > hi {
        return None;
    }
    let least = if integer {
        1.0
    } else {
        (lo.abs().max(hi.abs()) * 0.01).max(0.1)
    };
    let (lo, hi) = if hi - lo < 2.0 * least {
        let mid = (lo + hi) / 2.0;
        ((mid - least).min(lo), (mid + least).max(hi))
    } else {
        (lo, hi)
    };
    // The most ticks apart the range may be and keep its labels Y_LABEL_SPACING apart.
    let most = ((f64::from(height) / (f64::from(Y_LABEL_SPACING) * 1.01)) - 2.0 * Y_AIR)
        .floor()
        .clamp(2.0, MOST_APART);
    let apart = |s: f64| (hi / s).ceil() - (lo / s).floor();
    let mut step = nice_step((hi - lo) / most, integer);
    while apart(step) > most {
        step = nice_step(step * 1.01, integer);
    }
    let (mut a, mut b) = ((lo / step).floor(), (hi / step).ceil());
    if b - a < 1.0 {
        (a, b) = (a - 1.0, b + 1.0);
    } else if b - a < 2.0 {
        // One tick more on the side where the data comes nearer the edge.
        if b * step - hi < lo - a * step {
            b += 1.0;
        } else {
            a -= 1.0;
        }
    }
    // Air for half a label: air * height / (b - a + 2 air) >= Y_LABEL_HALF.
    let room = f64::from(height) - 2.0 * Y_LABEL_HALF;
    let air = if room > 0.0 {
        Y_AIR.max(Y_LABEL_HALF * (b - a) / room)
    } else {
        Y_AIR
    };
    Some(((a - air) * step, (b + air) * step))
}

/// Sets the y range of the plot being drawn to [`y_range`] of `extent` (the lowest and highest
/// value drawn: [`lines`]) for its data area's height.
pub fn fit_y(pui: &mut PlotUi<'_>, extent: Option<(f64, f64)>, integer: bool) {
    let height = pui.response().rect.height();
    if let Some((lo, hi)) = extent.and_then(|(lo, hi)| y_range(lo, hi, height, integer)) {
        pui.set_plot_bounds_y(lo..=hi);
    }
}

/// The fields' names in their colours, on a line above the plot (a legend inside it would
/// cover the newest data), then the plot's states as they read now (see [`states`]); then the
/// air before the plot ([`key_air`]).
pub fn key(ui: &mut egui::Ui, legend: &Legend, states: &[String]) {
    crate::ui::layout::toolbar(ui, |ui| {
        for (i, name) in legend.names.iter().enumerate() {
            ui.colored_label(color(i), format!("— {name}"));
        }
        for s in states {
            ui.separator();
            ui.strong(s);
        }
    });
    ui.add_space(key_air(ui));
}

/// The space between a plot's key and its data area, points: half a line, so that a y tick
/// label on the data area's top edge (drawn centred on it, half above) never reaches the key.
pub fn key_air(ui: &egui::Ui) -> f32 {
    ui.text_style_height(&egui::TextStyle::Body) / 2.0
}

/// A reading older than this is shown with its age.
pub const STALE: Duration = Duration::from_secs(3);

/// The plot's state fields (enums, flags, bit fields: never drawn as lines) as the last reading
/// of its command has them, names in `lang`: `Battery state: Warning (1)`, with its age when it
/// is older than [`STALE`] (`… (12 s ago)`); `Battery state: —` while no reading has one (before
/// the first, after a failed poll, after the link was lost).
pub fn states(rt: &Station, plot: &crate::profile::Plot, lang: Lang) -> Vec<String> {
    let Some(cmd) = rt.device.profile.command(&plot.command) else {
        return Vec::new();
    };
    let reading = match rt.device.readings.get(&cmd.id) {
        Some(Reading::Values(values, at)) => Some((values, at.elapsed())),
        _ => None,
    };
    plot.states
        .iter()
        .filter_map(|ident| {
            cmd.reply
                .iter()
                .find(|f| f.ident.eq_ignore_ascii_case(ident))
        })
        .map(|f| {
            let value = reading.and_then(|(values, age)| Some((values.get(&f.ident)?, age)));
            state_text(f, value, lang)
        })
        .collect()
}

/// One state as [`states`] shows it, from its value and that value's age.
fn state_text(f: &Field, value: Option<(&Value, Duration)>, lang: Lang) -> String {
    let name = lang.tr(&f.name.en, &f.name.zh);
    match value {
        Some((v, age)) if age > STALE => format!(
            "{name}: {} ({:.0} s {})",
            readout_text(f, v, lang),
            age.as_secs_f64(),
            lang.tr("ago", "前")
        ),
        Some((v, _)) => format!("{name}: {}", readout_text(f, v, lang)),
        None => format!("{name}: —"),
    }
}

/// Draws `fields` of `set` over `[t0, t1]`, decimated to `width_px` columns: one line per
/// unbroken stretch ([`stretches`]), all of a field's stretches under its name from `legend`
/// and colour. Returns the lowest and highest value drawn within `[t0, t1]` (`None` when
/// nothing is), for [`fit_y`].
pub fn lines(
    pui: &mut PlotUi<'_>,
    set: &SeriesSet,
    fields: &[String],
    legend: &Legend,
    (t0, t1): (f64, f64),
    width_px: usize,
    scratch: &mut Scratch,
) -> Option<(f64, f64)> {
    let mut extent: Option<(f64, f64)> = None;
    for (i, name) in fields.iter().enumerate() {
        set.decimate_segments(
            name,
            t0,
            t1,
            width_px,
            &mut scratch.points,
            &mut scratch.starts,
        );
        for p in scratch.points.iter().filter(|p| p[0] >= t0 && p[0] <= t1) {
            let (lo, hi) = extent.unwrap_or((p[1], p[1]));
            extent = Some((lo.min(p[1]), hi.max(p[1])));
        }
        let label = legend.names.get(i).unwrap_or(name);
        for stretch in stretches(&scratch.points, &scratch.starts) {
            let pts = PlotPoints::from(stretch.to_vec());
            // As drawn, point by point: egui_plot would otherwise merge points a pixel apart
            // into a filled band, which draws a filled wedge where a trace jumps or resumes.
            pui.line(
                Line::new(label.clone(), pts)
                    .color(color(i))
                    .allow_band(false),
            );
        }
    }
    extent
}

/// The unbroken stretches of `points` that [`SeriesSet::decimate_segments`] gave, each begun
/// at its index in `starts`: each is drawn as a line of its own (an open polyline, never
/// filled), so that no line joins two stretches.
pub fn stretches<'p>(
    points: &'p [[f64; 2]],
    starts: &'p [usize],
) -> impl Iterator<Item = &'p [[f64; 2]]> + 'p {
    starts.iter().enumerate().map(move |(k, &from)| {
        let to = starts.get(k + 1).copied().unwrap_or(points.len());
        &points[from.min(to)..to]
    })
}

/// A readout: the time of the sample nearest the cursor, and each field's value at it.
#[derive(Debug, Clone, PartialEq)]
pub struct Readout {
    /// The sample's own time, seconds.
    pub t: f64,
    /// (field, value) of the fields that have a sample at that time.
    pub values: Vec<(String, f64)>,
}

/// The sample of `fields` nearest time `t`, if one lies within `reach` seconds of it (never a
/// time at which nothing was measured), with every field's value at that sample's time.
pub fn nearest(set: &SeriesSet, fields: &[String], t: f64, reach: f64) -> Option<Readout> {
    let best = fields
        .iter()
        .filter_map(|f| set.value_at(f, t))
        .filter(|s| (s.t - t).abs() <= reach)
        .min_by(|a, b| (a.t - t).abs().total_cmp(&(b.t - t).abs()))?;
    // The fields of one plot come from one command: they share sample times.
    let values = fields
        .iter()
        .filter_map(|f| {
            let s = set.value_at(f, best.t)?;
            (s.t == best.t && !s.v.is_nan()).then(|| (f.clone(), s.v))
        })
        .collect();
    Some(Readout { t: best.t, values })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mark(value: f64, step_size: f64) -> GridMark {
        GridMark { value, step_size }
    }

    #[test]
    fn whole_numbers_tick_without_decimals_and_scaled_values_with_what_the_step_needs() {
        assert_eq!(y_tick(mark(3.0, 0.5), true), "3");
        assert_eq!(
            y_tick(mark(3.5, 0.5), true),
            "",
            "no tick between whole numbers"
        );
        assert_eq!(y_tick(mark(2.75, 0.05), false), "2.75");
        assert_eq!(y_tick(mark(20.0, 10.0), false), "20");
        assert_eq!(y_tick(mark(2.5, 2.5), false), "2.5");
        assert_eq!(y_tick(mark(12.75, 0.25), false), "12.75");
        assert_eq!(y_tick(mark(25.0, 25.0), false), "25");
    }

    /// The ticks egui_plot labels on a y axis `height` points high over `range`: the marks of
    /// [`y_marks`] with a text ([`y_tick`]) whose step puts them at least
    /// [`Y_LABEL_SPACING`] apart (egui_plot's own rule, axis.rs `add_tick_labels`).
    fn labelled(range: (f64, f64), height: f32, integer: bool) -> Vec<String> {
        labelled_marks(range, height, integer)
            .into_iter()
            .map(|m| y_tick(m, integer))
            .collect()
    }

    /// The marks [`labelled`] writes.
    fn labelled_marks(range: (f64, f64), height: f32, integer: bool) -> Vec<GridMark> {
        let per_point = (range.1 - range.0) / f64::from(height);
        let input = GridInput {
            bounds: range,
            base_step_size: per_point * f64::from(GRID_SPACING),
        };
        y_marks(input, integer)
            .into_iter()
            .filter(|m| m.step_size / per_point > f64::from(Y_LABEL_SPACING))
            .filter(|m| !y_tick(*m, integer).is_empty())
            .collect()
    }

    /// Data-area heights of the plots at 1024×600 and 1280×800: the solar panel's (its plot
    /// 130 points with its x axis), the least a telemetry plot has, and the two telemetry plots
    /// of the window cleaner sharing each window's height.
    const HEIGHTS: [f32; 4] = [88.0, 100.0, 150.0, 260.0];

    #[test]
    fn a_flat_trace_and_a_normal_one_get_at_least_three_labelled_ticks_at_every_height() {
        let cases: [(&str, f64, f64, bool); 6] = [
            ("battery flat at 12.6 V", 12.6, 12.6, false),
            ("battery and adapter voltage", 12.6, 24.0, false),
            ("attitude", -12.5, 31.0, false),
            ("a flat zero", 0.0, 0.0, false),
            ("whole numbers, flat", 35.0, 35.0, true),
            ("whole numbers, an ADC", 18.0, 1350.0, true),
        ];
        for (what, lo, hi, integer) in cases {
            for height in HEIGHTS {
                let range = y_range(lo, hi, height, integer).unwrap();
                assert!(
                    range.0 <= lo && range.1 >= hi,
                    "{what} at {height}: {range:?} holds the data"
                );
                let ticks = labelled(range, height, integer);
                assert!(
                    ticks.len() >= 3,
                    "{what} at {height} points over {range:?}: labelled ticks {ticks:?}"
                );
                assert!(ticks.len() <= 8, "{what} at {height}: {ticks:?}");
                // The outermost ticks sit half a label inside the data area.
                let per_point = (range.1 - range.0) / f64::from(height);
                let marks = labelled_marks(range, height, integer);
                let (low, high) = (marks[0].value, marks[marks.len() - 1].value);
                assert!(
                    (low - range.0) / per_point >= Y_LABEL_HALF - 1e-6
                        && (range.1 - high) / per_point >= Y_LABEL_HALF - 1e-6,
                    "{what} at {height}: ticks {low}..{high} in {range:?}"
                );
            }
        }
        // The flat battery reads in tenths of a volt around its value.
        let range = y_range(12.6, 12.6, 100.0, false).unwrap();
        assert_eq!(
            labelled(range, 100.0, false),
            ["12.4", "12.5", "12.6", "12.7", "12.8"]
        );
    }

    #[test]
    fn egui_plots_own_range_for_a_flat_trace_labelled_one_tick() {
        // What egui_plot gave a flat 12.6 V trace in a 60 s window (its span is the x span),
        // with its own log-10 grid: one labelled tick. y_marks labels several.
        let range = (12.6 - 30.0, 12.6 + 30.0);
        let height = 100.0;
        let per_point = (range.1 - range.0) / height;
        let input = |_: ()| GridInput {
            bounds: range,
            base_step_size: per_point * f64::from(GRID_SPACING),
        };
        let egui_own: Vec<GridMark> = egui_plot::log_grid_spacer(10)(input(()))
            .into_iter()
            .filter(|m| m.step_size / per_point > f64::from(Y_LABEL_SPACING))
            .collect();
        assert_eq!(egui_own.len(), 1, "{egui_own:?}");
        assert!(labelled(range, height as f32, false).len() >= 3);
    }

    #[test]
    fn a_tick_step_is_one_two_two_and_a_half_or_five_times_a_power_of_ten() {
        assert_eq!(nice_step(0.07, false), 0.1);
        assert_eq!(nice_step(0.11, false), 0.2);
        assert_eq!(nice_step(2.2, false), 2.5);
        assert_eq!(nice_step(3.0, false), 5.0);
        assert_eq!(nice_step(0.3, true), 1.0);
        assert_eq!(nice_step(2.2, true), 4.0);
        assert_eq!(nice_step(22.0, true), 25.0);
    }

    #[test]
    fn each_stretch_is_its_own_line() {
        let points = [[0.0, 1.0], [1.0, 1.0], [5.0, 2.0], [6.0, 2.0], [7.0, 2.0]];
        let parts: Vec<&[[f64; 2]]> = stretches(&points, &[0, 2]).collect();
        assert_eq!(parts, [&points[..2], &points[2..]]);
        assert_eq!(stretches(&points, &[]).count(), 0);
    }

    #[test]
    fn the_legend_names_fields_in_the_windows_language_with_their_unit() {
        let p = crate::sim::msp_device::builtin_profile("window-cleaner").unwrap();
        let plot = p
            .plots
            .iter()
            .find(|pl| pl.command.contains("BATTERY") || pl.id.contains("batt"));
        let plot = plot.unwrap_or(&p.plots[0]);
        let cmd = p.command(&plot.command);
        let en = Legend::new(cmd, &plot.fields, Lang::En);
        let zh = Legend::new(cmd, &plot.fields, Lang::Zh);
        for ((ident, en), zh) in plot.fields.iter().zip(&en.names).zip(&zh.names) {
            let f = cmd
                .unwrap()
                .reply
                .iter()
                .find(|f| &f.ident == ident)
                .unwrap();
            assert!(en.starts_with(&f.name.en), "{en}");
            assert!(zh.starts_with(&f.name.zh), "{zh}");
            if !f.unit.is_empty() {
                assert!(en.ends_with(&format!("({})", f.unit)), "{en}");
            }
        }
        assert!(!en.y_label.is_empty() && !zh.y_label.is_empty());
        assert_eq!(
            Legend::new(None, &["eulerX".to_string()], Lang::Zh).y_label,
            "单位未公布"
        );
    }

    #[test]
    fn a_state_reads_by_its_name_with_its_age_once_stale_and_a_dash_without_a_value() {
        let p = crate::sim::msp_device::builtin_profile("solar-cleanbot").unwrap();
        let f = p.command("CMD_BATTERY_STATE").unwrap().reply[1].clone();
        let warning = Value::Int(1);
        let fresh = Some((&warning, Duration::from_millis(200)));
        assert_eq!(
            state_text(&f, fresh, Lang::En),
            "Battery state: Warning (1)"
        );
        assert_eq!(state_text(&f, fresh, Lang::Zh), "电池状态: 警告 (1)");
        let old = Some((&warning, Duration::from_secs(12)));
        assert_eq!(
            state_text(&f, old, Lang::En),
            "Battery state: Warning (1) (12 s ago)"
        );
        assert_eq!(state_text(&f, None, Lang::En), "Battery state: —");
    }

    #[test]
    fn the_readout_is_a_sample_within_reach_or_nothing() {
        let mut set = SeriesSet::new(100);
        for i in 0..5 {
            set.push("a", 10.0 + f64::from(i), f64::from(i)).unwrap();
            set.push("b", 10.0 + f64::from(i), -f64::from(i)).unwrap();
        }
        let fields = ["a".to_string(), "b".to_string()];
        let r = nearest(&set, &fields, 12.2, 0.5).unwrap();
        assert_eq!(r.t, 12.0);
        assert_eq!(r.values, [("a".into(), 2.0), ("b".into(), -2.0)]);
        assert_eq!(nearest(&set, &fields, -23.0, 0.5), None, "before any data");
        assert_eq!(
            nearest(&set, &fields, 12.6, 0.3),
            None,
            "between samples, out of reach"
        );
        assert_eq!(
            nearest(
                &set,
                &SeriesSet::new(10)
                    .iter()
                    .map(|(n, _)| n.to_string())
                    .collect::<Vec<_>>(),
                12.0,
                1.0
            ),
            None
        );
    }
}
