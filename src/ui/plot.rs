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
use egui_plot::{GridMark, Line, Plot, PlotPoints, PlotUi};
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
    let decimals = (-mark.step_size.log10().floor()).clamp(0.0, 6.0) as usize;
    format!("{:.*}", decimals, mark.value)
}

/// `plot` with the axes every live plot shares: x in wall-clock time since `t0`, y labelled
/// with the fields' unit and ticked as [`y_tick`]; no legend inside the plot (see [`key`]).
pub fn axes<'a>(plot: Plot<'a>, lang: Lang, t0: SystemTime, legend: &Legend) -> Plot<'a> {
    let integer = legend.integer;
    plot.x_axis_label(lang.tr("time", "时间"))
        .y_axis_label(legend.y_label.clone())
        .x_axis_formatter(move |mark: GridMark, _: &RangeInclusive<f64>| {
            clock(t0, mark.value, mark.step_size < 1.0)
        })
        .y_axis_formatter(move |mark: GridMark, _: &RangeInclusive<f64>| y_tick(mark, integer))
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
/// unbroken stretch, all of a field's stretches under its name from `legend` and colour.
pub fn lines(
    pui: &mut PlotUi<'_>,
    set: &SeriesSet,
    fields: &[String],
    legend: &Legend,
    (t0, t1): (f64, f64),
    width_px: usize,
    scratch: &mut Scratch,
) {
    for (i, name) in fields.iter().enumerate() {
        set.decimate_segments(
            name,
            t0,
            t1,
            width_px,
            &mut scratch.points,
            &mut scratch.starts,
        );
        let n = scratch.starts.len();
        for k in 0..n {
            let from = scratch.starts[k];
            let to = scratch
                .starts
                .get(k + 1)
                .copied()
                .unwrap_or(scratch.points.len());
            let pts = PlotPoints::from(scratch.points[from..to].to_vec());
            let label = legend.names.get(i).unwrap_or(name);
            pui.line(Line::new(label.clone(), pts).color(color(i)));
        }
    }
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
