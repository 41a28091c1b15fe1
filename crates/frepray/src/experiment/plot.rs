//! Log-log plots of RMSE against samples per pixel and against render time, one line
//! per estimator, as PNG (drawn with plotters, encoded by `image`) and SVG; text uses
//! DejaVu Sans embedded from the `dejavu` crate, so no system font is needed.

use super::manifest::Row;
use super::ExperimentError;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use std::sync::OnceLock;

/// Size of the plots in pixels.
pub const SIZE: (u32, u32) = (1024, 720);

/// The font family the plots use, registered with plotters on first use.
const FONT: &str = "sans-serif";

/// Registers the embedded font once; false if it does not read.
fn register_font() -> bool {
    static DONE: OnceLock<bool> = OnceLock::new();
    *DONE.get_or_init(|| {
        plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular()).is_ok()
    })
}

/// One line of a plot: the estimator and its (x, y) points, x ascending.
pub type Series = (String, Vec<(f64, f64)>);

/// Writes `rmse_vs_spp` and `rmse_vs_time` (.png and .svg) into `dir`, one line per
/// estimator in `estimators` order.
pub fn write_all(dir: &Path, rows: &[Row], estimators: &[String]) -> Result<(), ExperimentError> {
    let series = |x: &dyn Fn(&Row) -> f64| -> Vec<Series> {
        estimators
            .iter()
            .map(|e| {
                let mut pts: Vec<(f64, f64)> = rows
                    .iter()
                    .filter(|r| &r.estimator == e)
                    .map(|r| (x(r), r.rmse))
                    .collect();
                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                (e.clone(), pts)
            })
            .collect()
    };
    let by_spp = series(&|r| r.spp as f64);
    let by_time = series(&|r| r.time_s);
    write_plot(
        &dir.join("rmse_vs_spp"),
        "RMSE against samples per pixel",
        "samples per pixel",
        &by_spp,
    )?;
    write_plot(
        &dir.join("rmse_vs_time"),
        "RMSE against render time",
        "render time (s)",
        &by_time,
    )
}

/// Writes `stem.png` and `stem.svg`, each whole or not at all.
pub fn write_plot(
    stem: &Path,
    title: &str,
    x_desc: &str,
    series: &[Series],
) -> Result<(), ExperimentError> {
    let (w, h) = SIZE;
    let png = stem.with_extension("png");
    let failed = |path: &Path| {
        let path = path.to_path_buf();
        move |e: &dyn std::fmt::Display| ExperimentError::Plot {
            path,
            message: e.to_string(),
        }
    };
    if !register_font() {
        return Err(failed(&png)(&"the embedded DejaVu Sans font is unreadable"));
    }
    let mut rgb = vec![0u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        draw(&root, title, x_desc, series).map_err(|e| failed(&png)(&e))?;
    }
    render::output::write_atomically(&png, |f| render::png_io::write_rgb8(f, &rgb, w, h))
        .map_err(ExperimentError::io("write", &png))?;

    let svg_path = stem.with_extension("svg");
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        draw(&root, title, x_desc, series).map_err(|e| failed(&svg_path)(&e))?;
    }
    super::report::write_text(&svg_path, &svg)
}

/// A log axis range holding every positive finite value, with a margin.
fn log_range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if hi == 0.0 {
        return 1.0..10.0;
    }
    let pad = if hi / lo < 1.5 { 2.0 } else { 1.25 };
    lo / pad..hi * pad
}

/// Tick positions 1, 2, 5 × 10^k inside `r`; every integer multiple of 10^k where that
/// leaves fewer than three; and where even that does (a range within one step, e.g.
/// 0.031 to 0.038), five ticks spread evenly in log over the whole range, to the fewest
/// significant digits that keep them apart.
fn ticks(r: &std::ops::Range<f64>) -> Vec<f64> {
    let (lo, hi) = (r.start.log10().floor() as i32, r.end.log10().ceil() as i32);
    let pick = |mults: &[f64]| -> Vec<f64> {
        (lo..=hi)
            .flat_map(|e| mults.iter().map(move |m| m * 10f64.powi(e)))
            .filter(|v| r.contains(v))
            .collect()
    };
    let k = pick(&[1.0, 2.0, 5.0]);
    if k.len() >= 3 {
        return k;
    }
    let k = pick(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
    if k.len() >= 3 {
        return k;
    }
    let (a, b) = (r.start.ln(), r.end.ln());
    let even = |digits: i32| -> Vec<f64> {
        let mut k: Vec<f64> = (1..=5)
            .map(|i| (a + (b - a) * i as f64 / 6.0).exp())
            .map(|v| {
                let scale = 10f64.powi(v.log10().floor() as i32 + 1 - digits);
                (v / scale).round() * scale
            })
            .filter(|v| r.contains(v))
            .collect();
        k.dedup();
        k
    };
    (2..=6)
        .map(even)
        .find(|k| k.len() == 5)
        .unwrap_or_else(|| even(15))
}

/// A tick label: plain for moderate values, else scientific.
fn tick(v: f64) -> String {
    if (1e-3..1e5).contains(&v.abs()) {
        let s = format!("{v:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:.1e}")
    }
}

/// Colours that stay apart on white: Tableau 10.
pub const COLOURS: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    x_desc: &str,
    series: &[Series],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let pts = || series.iter().flat_map(|s| s.1.iter());
    let xs = log_range(pts().map(|p| p.0));
    let ys = log_range(pts().map(|p| p.1));
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FONT, 26))
        .margin(16)
        .x_label_area_size(56)
        .y_label_area_size(90)
        .build_cartesian_2d(
            xs.clone().log_scale().with_key_points(ticks(&xs)),
            ys.clone().log_scale().with_key_points(ticks(&ys)),
        )?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc("RMSE")
        .label_style((FONT, 16))
        .axis_desc_style((FONT, 18))
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .draw()?;
    for (i, (name, line)) in series.iter().enumerate() {
        let c = COLOURS[i % COLOURS.len()];
        let line: Vec<(f64, f64)> = line
            .iter()
            .copied()
            .filter(|(x, y)| x.is_finite() && y.is_finite() && *x > 0.0 && *y > 0.0)
            .collect();
        chart
            .draw_series(LineSeries::new(line.clone(), c.stroke_width(2)))?
            .label(name.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], c.stroke_width(2)));
        chart.draw_series(line.iter().map(|&p| Circle::new(p, 4, c.filled())))?;
    }
    chart
        .configure_series_labels()
        .label_font((FONT, 18))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()?;
    root.present()
}

#[cfg(test)]
mod tick_tests {
    use super::ticks;

    /// Ticks cover the whole range: at least three, the first in its lower third and
    /// the last in its upper third (in log), over wide and narrow ranges alike.
    #[test]
    fn ticks_span_the_data_range() {
        for r in [1e-5..3e2, 0.031..0.038, 0.9..1.1, 12.0..95.0, 2e-3..2.2e-3] {
            let k = ticks(&r);
            assert!(k.len() >= 3, "{r:?}: {k:?}");
            let at = |v: f64| (v.ln() - r.start.ln()) / (r.end.ln() - r.start.ln());
            assert!(
                at(k[0]) < 0.34 && at(*k.last().unwrap()) > 0.66,
                "{r:?}: {k:?}"
            );
            assert!(k.iter().all(|v| r.contains(v)), "{r:?}: {k:?}");
        }
    }
}
