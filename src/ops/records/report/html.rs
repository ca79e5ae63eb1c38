//! The report as one self-contained HTML file: tables, and the plots as inline SVG drawn by
//! plotters (no script, no style sheet or font fetched: it opens offline in any browser and
//! prints as it shows).

use super::{MeasurementStats, ParetoStep, Report, Yield};
use plotters::prelude::*;

/// A plot's size in px.
const PLOT: (u32, u32) = (560, 260);
/// The colours: pass, fail, limits, mean.
const GOOD: RGBColor = RGBColor(46, 125, 50);
const BAD: RGBColor = RGBColor(198, 40, 40);
const BARS: RGBColor = RGBColor(84, 110, 122);

/// Text for HTML.
fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn pct(x: f64) -> String {
    if x.is_finite() {
        format!("{:.1} %", 100.0 * x)
    } else {
        "–".into()
    }
}

/// A number to five significant digits, trailing zeros dropped (`24.014`, `0.0241`, `1.6`).
pub fn num(x: f64) -> String {
    if !x.is_finite() {
        return "–".into();
    }
    let magnitude = if x == 0.0 {
        0
    } else {
        x.abs().log10().floor() as i32
    };
    let d = (4 - magnitude).clamp(0, 8) as usize;
    let s = format!("{x:.d$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// The whole page. `period` says what was asked (`since 2026-12-01 06:00, station line3`).
pub fn page(report: &Report, period: &str) -> String {
    let mut h = String::new();
    h.push_str("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">");
    h.push_str("<title>botbench report</title><style>");
    h.push_str(
        "body{font-family:sans-serif;margin:24px;color:#212121;max-width:1200px}\
         h1{font-size:22px;margin:0 0 4px}h2{font-size:18px;margin:28px 0 8px;border-bottom:1px solid #bbb}\
         h3{font-size:15px;margin:16px 0 4px}\
         table{border-collapse:collapse;margin:6px 0 12px}td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}\
         th{background:#eceff1}td.l,th.l{text-align:left}.bad{color:#c62828;font-weight:bold}\
         .good{color:#2e7d32}.warn{background:#fff3e0;border:2px solid #ef6c00;padding:8px 12px;margin:8px 0}\
         .meta{color:#555}.grid{display:flex;flex-wrap:wrap;gap:16px}.card{border:1px solid #ddd;padding:8px}",
    );
    h.push_str("</style></head><body>\n");
    h.push_str(&format!(
        "<h1>Production records: yield, failures, capability</h1>\n<p class=\"meta\">{} · {} · shifts {} · \
         generated {} by botbench {}</p>\n",
        esc(&report.source),
        esc(period),
        esc(&report.shifts),
        esc(&chrono::Local::now().format("%Y-%m-%d %H:%M").to_string()),
        esc(crate::VERSION)
    ));
    if report.waiting > 0 {
        h.push_str(&format!(
            "<p class=\"warn\">{} record(s) wait in this PC's spool and are not in this report.</p>\n",
            report.waiting
        ));
    }
    h.push_str(&drift_warnings(report));
    let o = &report.overall;
    h.push_str(&format!(
        "<h2 id=\"yield\">Yield</h2><p><b>{}</b> units, <b>{}</b> runs: first-pass yield <b>{}</b>, final yield <b>{}</b>.</p>\n",
        o.units,
        o.runs,
        pct(o.fpy()),
        pct(o.final_yield())
    ));
    if !report.by_shift.is_empty() {
        h.push_str(
            "<p><b>Yield per shift</b>: <span style=\"color:#c62828\">● first-pass yield</span> \
             <span style=\"color:#2e7d32\">● final yield</span></p>",
        );
        h.push_str(&yield_plot(&report.by_shift));
    }
    h.push_str("<div class=\"grid\">");
    for (title, rows) in [
        ("Per shift", &report.by_shift),
        ("Per station", &report.by_station),
        ("Per slot", &report.by_slot),
        ("Per plan version", &report.by_plan),
    ] {
        h.push_str(&format!("<div><h3>{title}</h3>{}</div>", yield_table(rows)));
    }
    h.push_str("</div>\n<h2 id=\"failures\">Failures (Pareto)</h2>\n");
    if report.pareto.is_empty() {
        h.push_str("<p>No step failed.</p>\n");
    } else {
        h.push_str(&pareto_plot(&report.pareto));
        h.push_str(
            "<table><tr><th class=\"l\">step</th><th class=\"l\">reason</th><th>failures</th></tr>",
        );
        for c in &report.causes {
            h.push_str(&format!(
                "<tr><td class=\"l\">{}</td><td class=\"l\">{}</td><td>{}</td></tr>",
                esc(&c.step),
                esc(&c.reason),
                c.count
            ));
        }
        h.push_str("</table>\n");
    }
    h.push_str("<h2 id=\"measurements\">Measurements</h2>\n");
    h.push_str(&measurement_table(report));
    h.push_str("<div class=\"grid\">");
    for m in &report.measurements {
        h.push_str(&format!("<div class=\"card\">{}</div>", histogram_plot(m)));
    }
    h.push_str("</div>\n</body></html>\n");
    h
}

/// A warning line for each measurement that drifts toward a limit.
fn drift_warnings(report: &Report) -> String {
    let mut h = String::new();
    let drifting: Vec<&MeasurementStats> = report
        .measurements
        .iter()
        .filter(|m| m.drift.is_some())
        .collect();
    for m in &drifting {
        if let Some(d) = &m.drift {
            h.push_str(&format!(
                "<p class=\"warn\"><b>Drift: {}</b> walks toward its {} limit {} {}: the means of the last 3 × {} units \
                 {} → {} → {} (moved {:.1} σ; {:.1} σ left)</p>\n",
                esc(&m.name),
                d.toward,
                num(d.limit),
                esc(&m.unit),
                d.window,
                num(d.means[0]),
                num(d.means[1]),
                num(d.means[2]),
                d.moved_sigma,
                d.left_sigma
            ));
        }
    }
    h
}

fn yield_table(rows: &[Yield]) -> String {
    let mut t = String::from(
        "<table><tr><th class=\"l\">group</th><th>units</th><th>runs</th><th>first-pass</th><th>final</th></tr>",
    );
    for y in rows {
        let class = if y.fpy() < 0.9 { " class=\"bad\"" } else { "" };
        t.push_str(&format!(
            "<tr><td class=\"l\">{}</td><td>{}</td><td>{}</td><td{class}>{}</td><td>{}</td></tr>",
            esc(&y.label()),
            y.units,
            y.runs,
            pct(y.fpy()),
            pct(y.final_yield())
        ));
    }
    t.push_str("</table>");
    t
}

fn measurement_table(report: &Report) -> String {
    let mut t = String::from(
        "<table><tr><th class=\"l\">measurement</th><th>unit</th><th>low</th><th>high</th><th>n</th>\
         <th>failed</th><th>mean</th><th>σ</th><th>min</th><th>max</th><th>Cpk</th><th class=\"l\">drift</th></tr>",
    );
    for m in &report.measurements {
        let lim = |v: Option<f64>| v.map(num).unwrap_or_else(|| "–".into());
        let cpk = match m.cpk {
            Some(c) if c < 1.33 => format!("<td class=\"bad\">{c:.2}</td>"),
            Some(c) => format!("<td class=\"good\">{c:.2}</td>"),
            None => "<td>–</td>".into(),
        };
        let drift = match &m.drift {
            Some(d) => format!(
                "<td class=\"l bad\">toward {} ({:.1} σ)</td>",
                d.toward, d.moved_sigma
            ),
            None => "<td class=\"l\">none</td>".into(),
        };
        t.push_str(&format!(
            "<tr><td class=\"l\">{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>\
             <td>{}</td><td>{}</td>{cpk}{drift}</tr>",
            esc(&m.name),
            esc(&m.unit),
            lim(m.low),
            lim(m.high),
            m.n,
            m.failed,
            num(m.mean),
            num(m.sigma),
            num(m.min),
            num(m.max)
        ));
    }
    t.push_str("</table>\n");
    t
}

/// Draws with plotters into an SVG string; a drawing error leaves a note instead of a plot.
fn svg(
    size: (u32, u32),
    draw: impl FnOnce(&DrawingArea<SVGBackend<'_>, plotters::coord::Shift>) -> Result<(), String>,
) -> String {
    let mut out = String::new();
    let result = {
        let root = SVGBackend::with_string(&mut out, size).into_drawing_area();
        let r = root
            .fill(&WHITE)
            .map_err(|e| e.to_string())
            .and_then(|_| draw(&root));
        r.and_then(|_| root.present().map_err(|e| e.to_string()))
    };
    match result {
        Ok(()) => out,
        Err(e) => format!("<p class=\"bad\">plot not drawn: {}</p>", esc(&e)),
    }
}

fn yield_plot(rows: &[Yield]) -> String {
    let n = rows.len();
    svg((PLOT.0 * 2, PLOT.1), |root| {
        let lo = rows
            .iter()
            .map(|y| y.fpy().min(y.final_yield()))
            .filter(|x| x.is_finite())
            .fold(1.0f64, f64::min);
        let floor = ((lo * 10.0).floor() / 10.0).clamp(0.0, 0.9);
        let mut chart = ChartBuilder::on(root)
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(50)
            .build_cartesian_2d(-0.5f64..(n as f64 - 0.5), floor * 100.0..100.0)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_labels(n.min(12))
            .x_label_formatter(&|x| {
                let i = x.round();
                if (x - i).abs() < 0.01 && i >= 0.0 {
                    rows.get(i as usize).map(|y| y.label()).unwrap_or_default()
                } else {
                    String::new()
                }
            })
            .y_desc("%")
            .y_label_formatter(&|y| format!("{y:.0}"))
            .disable_x_mesh()
            .draw()
            .map_err(|e| e.to_string())?;
        let fpy: Vec<(f64, f64)> = rows
            .iter()
            .enumerate()
            .map(|(i, y)| (i as f64, 100.0 * y.fpy()))
            .collect();
        let fin: Vec<(f64, f64)> = rows
            .iter()
            .enumerate()
            .map(|(i, y)| (i as f64, 100.0 * y.final_yield()))
            .collect();
        chart
            .draw_series(LineSeries::new(fpy.clone(), BAD.stroke_width(2)))
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(fpy.iter().map(|p| Circle::new(*p, 3, BAD.filled())))
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(LineSeries::new(fin.clone(), GOOD.stroke_width(2)))
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(fin.iter().map(|p| Circle::new(*p, 3, GOOD.filled())))
            .map_err(|e| e.to_string())?;
        Ok(())
    })
}

fn pareto_plot(steps: &[ParetoStep]) -> String {
    let shown: Vec<&ParetoStep> = steps.iter().take(10).collect();
    let n = shown.len();
    let top = shown.first().map_or(1, |p| p.count).max(1) as f64;
    svg((PLOT.0 * 2, PLOT.1 + 40), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption("Failing steps", ("sans-serif", 16))
            .margin(10)
            .x_label_area_size(60)
            .y_label_area_size(50)
            .right_y_label_area_size(50)
            .build_cartesian_2d(-0.5f64..(n as f64 - 0.5), 0.0..top * 1.1)
            .map_err(|e| e.to_string())?
            .set_secondary_coord(-0.5f64..(n as f64 - 0.5), 0.0f64..100.0);
        chart
            .configure_mesh()
            .x_labels(n)
            .x_label_formatter(&|x| {
                let i = x.round();
                if (x - i).abs() < 0.01 && i >= 0.0 {
                    shown
                        .get(i as usize)
                        .map(|p| p.step.clone())
                        .unwrap_or_default()
                } else {
                    String::new()
                }
            })
            .y_desc("failures")
            .y_label_formatter(&|y| format!("{y:.0}"))
            .disable_x_mesh()
            .draw()
            .map_err(|e| e.to_string())?;
        chart
            .configure_secondary_axes()
            .y_desc("cumulative %")
            .y_label_formatter(&|y| format!("{y:.0}"))
            .draw()
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(shown.iter().enumerate().map(|(i, p)| {
                Rectangle::new(
                    [(i as f64 - 0.35, 0.0), (i as f64 + 0.35, p.count as f64)],
                    BAD.mix(0.75).filled(),
                )
            }))
            .map_err(|e| e.to_string())?;
        let cum: Vec<(f64, f64)> = shown
            .iter()
            .enumerate()
            .map(|(i, p)| (i as f64, 100.0 * p.cumulative))
            .collect();
        chart
            .draw_secondary_series(LineSeries::new(cum.clone(), BLACK.stroke_width(2)))
            .map_err(|e| e.to_string())?;
        chart
            .draw_secondary_series(cum.iter().map(|p| Circle::new(*p, 3, BLACK.filled())))
            .map_err(|e| e.to_string())?;
        Ok(())
    })
}

fn histogram_plot(m: &MeasurementStats) -> String {
    let x0 = m.bin_start;
    let x1 = m.bin_start + m.bin_width * m.bins.len() as f64;
    let top = m.bins.iter().copied().max().unwrap_or(1).max(1) as f64;
    let caption = if m.unit.is_empty() {
        m.name.clone()
    } else {
        format!("{} ({})", m.name, m.unit)
    };
    let stats = format!(
        "n {}  mean {}  σ {}  Cpk {}",
        m.n,
        num(m.mean),
        num(m.sigma),
        m.cpk.map_or("–".into(), |c| format!("{c:.2}"))
    );
    svg(PLOT, |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(&caption, ("sans-serif", 15))
            .margin(8)
            .x_label_area_size(34)
            .y_label_area_size(44)
            .build_cartesian_2d(x0..x1, 0.0..top * 1.15)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_labels(6)
            .x_label_formatter(&|x| num(*x))
            .y_label_formatter(&|y| format!("{y:.0}"))
            .y_desc("units")
            .disable_x_mesh()
            .draw()
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(m.bins.iter().enumerate().map(|(i, &c)| {
                let a = x0 + m.bin_width * i as f64;
                let inside =
                    m.low.is_none_or(|l| a + m.bin_width > l) && m.high.is_none_or(|h| a < h);
                let colour = if inside { BARS } else { BAD };
                Rectangle::new(
                    [(a, 0.0), (a + m.bin_width, c as f64)],
                    colour.mix(0.8).filled(),
                )
            }))
            .map_err(|e| e.to_string())?;
        for (limit, name) in [(m.low, "low"), (m.high, "high")] {
            if let Some(l) = limit {
                chart
                    .draw_series(LineSeries::new(
                        vec![(l, 0.0), (l, top * 1.15)],
                        BAD.stroke_width(2),
                    ))
                    .map_err(|e| e.to_string())?;
                chart
                    .draw_series(std::iter::once(Text::new(
                        format!("{name} {}", num(l)),
                        (l, top * 1.12),
                        ("sans-serif", 12).into_font().color(&BAD),
                    )))
                    .map_err(|e| e.to_string())?;
            }
        }
        if m.mean.is_finite() {
            chart
                .draw_series(LineSeries::new(
                    vec![(m.mean, 0.0), (m.mean, top * 1.0)],
                    BLUE.stroke_width(1),
                ))
                .map_err(|e| e.to_string())?;
        }
        root.draw(&Text::new(
            stats.clone(),
            (60, PLOT.1 as i32 - 14),
            ("sans-serif", 12).into_font(),
        ))
        .map_err(|e| e.to_string())
    })
}
