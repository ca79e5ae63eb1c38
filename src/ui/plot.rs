//! What every live plot shares: its series drawn as lines broken at the recording's gaps (a
//! link outage, a failed poll, polling paused), one colour per field whatever the number of
//! stretches, and the sample nearest a time within reach, for a cursor readout.

use crate::series::SeriesSet;
use eframe::egui;
use egui_plot::{Line, PlotPoints, PlotUi};

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

/// Draws `fields` of `set` over `[t0, t1]`, decimated to `width_px` columns: one line per
/// unbroken stretch, all of a field's stretches under its name (one legend entry) and colour.
pub fn lines(
    pui: &mut PlotUi<'_>,
    set: &SeriesSet,
    fields: &[String],
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
            pui.line(Line::new(name.clone(), pts).color(color(i)));
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
