//! Plots of a fit (seed Figure 3 and time histories), as SVG and PNG with a bundled font
//! (DejaVu Sans via `ab_glyph`), so they render on machines without system fonts.
//!
//! Every plot is written to a temporary file and renamed into place, so a failed run
//! leaves no partial file.

use std::path::{Path, PathBuf};
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::sample::Axis;

/// A plot that could not be written.
#[derive(Debug, thiserror::Error)]
#[error("{path}: cannot write plot: {message}")]
pub struct PlotError {
    /// The file that was being written.
    pub path: String,
    /// What went wrong.
    pub message: String,
}

/// Measured and predicted output of one axis over time.
#[derive(Debug, Clone, Copy)]
pub struct AxisSeries<'a> {
    /// The axis (gives the unit).
    pub axis: Axis,
    /// Time, s.
    pub t: &'a [f64],
    /// Measured output (N or N m).
    pub measured: &'a [f64],
    /// The Eq. 22 model's output (N or N m).
    pub predicted: &'a [f64],
    /// The adopted (diagnosed) model's output (N or N m), drawn beside the Eq. 22
    /// model's when given.
    pub final_model: Option<&'a [f64]>,
    /// The adopted model predicts this axis with the Eq. 22 model (the final model
    /// predicted its held-out data worse): the legend says so.
    pub final_is_eq22: bool,
}

/// Residual distribution of one axis: histogram as densities and the fitted Gaussian.
#[derive(Debug, Clone)]
pub struct ResidualDensity {
    /// The axis (gives the unit).
    pub axis: Axis,
    /// Bin edges (N or N m), one more than `density`.
    pub edges: Vec<f64>,
    /// Probability density per bin (1/N or 1/(N m)).
    pub density: Vec<f64>,
    /// Mean of the fitted Gaussian (N or N m).
    pub mean: f64,
    /// Standard deviation of the fitted Gaussian (N or N m).
    pub std: f64,
}

/// Ordered residuals against standard-normal quantiles for one axis (normal probability
/// plot), with the correlation of the two (1 for perfectly Gaussian residuals).
#[derive(Debug, Clone)]
pub struct NormalProbability {
    /// The axis (gives the unit).
    pub axis: Axis,
    /// `(standard normal quantile, ordered residual in N or N m)` pairs.
    pub points: Vec<(f64, f64)>,
    /// Correlation of the pairs.
    pub correlation: f64,
}

/// Held-out R² of one axis per cross-validation fold (a held-out log, or a block of a
/// single log), of the Eq. 22 model and of the final model.
#[derive(Debug, Clone)]
pub struct FoldR2 {
    /// The axis.
    pub axis: Axis,
    /// Fold names, in order.
    pub folds: Vec<String>,
    /// The Eq. 22 model's R² per fold, %.
    pub before: Vec<f64>,
    /// The final model's R² per fold, %.
    pub after: Vec<f64>,
}

/// One added effect: its load against the residual without it (before) and with it
/// (after), at the samples the plots keep (a partial-residual plot).
#[derive(Debug, Clone, Copy)]
pub struct EffectResidual<'a> {
    /// The effect's name (the panel's caption).
    pub name: &'a str,
    /// The axis shown (gives the unit).
    pub axis: Axis,
    /// The effect's load in the final model (N or N m).
    pub load: &'a [f64],
    /// Residual of the final model without the effect (N or N m).
    pub before: &'a [f64],
    /// Residual of the final model (N or N m).
    pub after: &'a [f64],
}

/// Bars of R² below this (%) are drawn to it, with their value written on them.
const R2_FLOOR: f64 = -100.0;

const FONT: &str = "sans-serif";
const SIZE: (u32, u32) = (1500, 1100);
/// Points drawn per series: longer series are reduced to per-bucket min/max.
const MAX_POINTS: usize = 3000;

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The bundled DejaVu Sans is valid TrueType; failure would be a build defect.
        let _ = plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular());
    });
}

/// What to draw on a 3 × 2 grid of axis panels.
enum Figure<'a> {
    TimeHistories(&'a [AxisSeries<'a>]),
    Densities(&'a [ResidualDensity]),
    NormalProbability(&'a [NormalProbability]),
    FoldR2(&'a [FoldR2]),
    Effects(&'a [EffectResidual<'a>]),
}

impl Figure<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        title: &str,
    ) -> DrawResult<(), DB> {
        match self {
            Self::TimeHistories(s) => draw_time_histories(root, title, s),
            Self::Densities(d) => draw_densities(root, title, d),
            Self::NormalProbability(n) => draw_normal_probability(root, title, n),
            Self::FoldR2(f) => draw_fold_r2(root, title, f),
            Self::Effects(e) => draw_effects(root, title, e),
        }
    }
}

/// Writes `stem.svg` and `stem.png` of `figure`, each through a temporary file.
fn write_both(stem: &Path, title: &str, figure: Figure) -> Result<Vec<PathBuf>, PlotError> {
    register_font();
    let svg = stem.with_extension("svg");
    let png = stem.with_extension("png");
    let err = |p: &Path, m: String| PlotError {
        path: p.display().to_string(),
        message: m,
    };
    let tmp_svg = stem.with_extension("svg.partial");
    {
        let root = SVGBackend::new(&tmp_svg, SIZE).into_drawing_area();
        figure
            .draw(&root, title)
            .map_err(|e| err(&svg, e.to_string()))?;
        root.present().map_err(|e| err(&svg, e.to_string()))?;
    }
    let tmp_png = stem.with_extension("partial.png");
    {
        let root = BitMapBackend::new(&tmp_png, SIZE).into_drawing_area();
        figure
            .draw(&root, title)
            .map_err(|e| err(&png, e.to_string()))?;
        root.present().map_err(|e| err(&png, e.to_string()))?;
    }
    std::fs::rename(&tmp_svg, &svg).map_err(|e| err(&svg, e.to_string()))?;
    std::fs::rename(&tmp_png, &png).map_err(|e| err(&png, e.to_string()))?;
    Ok(vec![svg, png])
}

/// Measured vs predicted output over time, one panel per axis: `stem.svg`, `stem.png`.
pub fn time_histories(
    stem: &Path,
    title: &str,
    series: &[AxisSeries],
) -> Result<Vec<PathBuf>, PlotError> {
    write_both(stem, title, Figure::TimeHistories(series))
}

/// Residual histograms with fitted Gaussians (seed Figure 3), one panel per axis.
pub fn residual_densities(
    stem: &Path,
    title: &str,
    axes: &[ResidualDensity],
) -> Result<Vec<PathBuf>, PlotError> {
    write_both(stem, title, Figure::Densities(axes))
}

/// Normal probability plots (ordered residual vs inverse normal CDF), one panel per axis.
pub fn normal_probability(
    stem: &Path,
    title: &str,
    axes: &[NormalProbability],
) -> Result<Vec<PathBuf>, PlotError> {
    write_both(stem, title, Figure::NormalProbability(axes))
}

/// Held-out R² per fold, Eq. 22 model (red, left) beside the final model (blue, right),
/// one panel per axis; the title should say which colour is which.
pub fn fold_r2(stem: &Path, title: &str, axes: &[FoldR2]) -> Result<Vec<PathBuf>, PlotError> {
    write_both(stem, title, Figure::FoldR2(axes))
}

/// Per added effect (the first six), the residual without it (red) and with it (blue)
/// against its load, with the line residual = load: where the effect explains what was
/// missing, red lies along the line and blue is flat.
pub fn effect_residuals(
    stem: &Path,
    title: &str,
    effects: &[EffectResidual],
) -> Result<Vec<PathBuf>, PlotError> {
    write_both(stem, title, Figure::Effects(effects))
}

fn panels<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
) -> DrawResult<Vec<DrawingArea<DB, Shift>>, DB> {
    root.fill(&WHITE)?;
    let root = root.titled(title, (FONT, 30).into_font())?;
    Ok(root.split_evenly((3, 2)))
}

fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = crate::util::range_of(values.filter(|v| v.is_finite()));
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05).max(1e-9 * (1.0 + lo.abs().max(hi.abs())));
    (lo - pad, hi + pad)
}

/// Reduces a series to at most ~`MAX_POINTS` points keeping each bucket's min and max.
fn decimate(t: &[f64], y: &[f64]) -> Vec<(f64, f64)> {
    let n = t.len().min(y.len());
    if n <= MAX_POINTS {
        return t.iter().zip(y).map(|(&a, &b)| (a, b)).collect();
    }
    let bucket = n.div_ceil(MAX_POINTS / 2);
    let mut out = Vec::with_capacity(MAX_POINTS + 2);
    for start in (0..n).step_by(bucket) {
        let end = (start + bucket).min(n);
        let (mut imin, mut imax) = (start, start);
        for i in start..end {
            if y[i] < y[imin] {
                imin = i;
            }
            if y[i] > y[imax] {
                imax = i;
            }
        }
        let (a, b) = if imin < imax {
            (imin, imax)
        } else {
            (imax, imin)
        };
        out.push((t[a], y[a]));
        out.push((t[b], y[b]));
    }
    out
}

fn draw_time_histories<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    series: &[AxisSeries],
) -> DrawResult<(), DB> {
    for (area, s) in panels(root, title)?.iter().zip(series) {
        let (t0, t1) = range(s.t.iter().copied());
        let final_model = s.final_model.unwrap_or(&[]);
        let (y0, y1) = range(
            s.measured
                .iter()
                .chain(s.predicted)
                .chain(final_model)
                .copied(),
        );
        let mut chart = ChartBuilder::on(area)
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(80)
            .caption(s.axis.name(), (FONT, 24))
            .build_cartesian_2d(t0..t1, y0..y1)?;
        chart
            .configure_mesh()
            .x_desc("time [s]")
            .y_desc(format!("{} [{}]", s.axis.name(), s.axis.unit()))
            .label_style((FONT, 16))
            .draw()?;
        let lines = [
            (s.measured, BLACK, "measured"),
            (s.predicted, RED, "Eq. 22 model"),
            (
                final_model,
                BLUE,
                if s.final_is_eq22 {
                    "final model (Eq. 22 here)"
                } else {
                    "final model"
                },
            ),
        ];
        for (values, colour, label) in lines.into_iter().filter(|l| !l.0.is_empty()) {
            let points = decimate(s.t, values);
            let mut runs = runs_without_gaps(&points).into_iter();
            if let Some(first) = runs.next() {
                chart
                    .draw_series(LineSeries::new(
                        first.iter().copied(),
                        colour.stroke_width(1),
                    ))?
                    .label(label)
                    .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], colour));
            }
            for run in runs {
                chart.draw_series(LineSeries::new(run.iter().copied(), colour.stroke_width(1)))?;
            }
        }
        chart
            .configure_series_labels()
            .label_font((FONT, 16))
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()?;
    }
    Ok(())
}

/// Splits a time series where the time step exceeds 5× its median (held-out segments,
/// logs laid end to end), so no line is drawn across a gap.
fn runs_without_gaps(points: &[(f64, f64)]) -> Vec<&[(f64, f64)]> {
    let mut steps: Vec<f64> = points.windows(2).map(|w| w[1].0 - w[0].0).collect();
    if steps.is_empty() {
        return vec![points];
    }
    steps.sort_by(f64::total_cmp);
    let limit = 5.0 * steps[steps.len() / 2];
    let mut runs = Vec::new();
    let mut start = 0;
    for i in 1..points.len() {
        if points[i].0 - points[i - 1].0 > limit {
            runs.push(&points[start..i]);
            start = i;
        }
    }
    runs.push(&points[start..]);
    runs
}

fn gaussian(x: f64, mean: f64, std: f64) -> f64 {
    let z = (x - mean) / std;
    (-0.5 * z * z).exp() / (std * (2.0 * std::f64::consts::PI).sqrt())
}

fn draw_densities<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    axes: &[ResidualDensity],
) -> DrawResult<(), DB> {
    for (area, d) in panels(root, title)?.iter().zip(axes) {
        let (x0, x1) = range(d.edges.iter().copied());
        let peak = d.density.iter().copied().fold(0.0, f64::max);
        let curve_peak = if d.std > 0.0 {
            gaussian(d.mean, d.mean, d.std)
        } else {
            0.0
        };
        let y1 = peak.max(curve_peak).max(f64::MIN_POSITIVE) * 1.1;
        let mut chart = ChartBuilder::on(area)
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(80)
            .caption(format!("{} residual", d.axis.name()), (FONT, 24))
            .build_cartesian_2d(x0..x1, 0.0..y1)?;
        chart
            .configure_mesh()
            .x_desc(format!("residual [{}]", d.axis.unit()))
            .y_desc(format!("probability density [1/{}]", d.axis.unit()))
            .label_style((FONT, 16))
            .draw()?;
        let bars = d
            .edges
            .windows(2)
            .zip(&d.density)
            .map(|(e, &h)| Rectangle::new([(e[0], 0.0), (e[1], h)], BLUE.mix(0.35).filled()));
        chart.draw_series(bars)?;
        if d.std > 0.0 {
            let curve = (0..=200).map(|i| {
                let x = x0 + (x1 - x0) * i as f64 / 200.0;
                (x, gaussian(x, d.mean, d.std))
            });
            chart.draw_series(LineSeries::new(curve, RED.stroke_width(2)))?;
        }
    }
    Ok(())
}

fn draw_fold_r2<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    axes: &[FoldR2],
) -> DrawResult<(), DB> {
    for (area, f) in panels(root, title)?.iter().zip(axes) {
        let lowest = f.before.iter().chain(&f.after).copied().fold(0.0, f64::min);
        let y0 = (lowest.max(R2_FLOOR) / 25.0).floor() * 25.0;
        let n = f.folds.len().max(1);
        let mut chart = ChartBuilder::on(area)
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(80)
            .caption(f.axis.name(), (FONT, 24))
            .build_cartesian_2d(-0.5..n as f64 - 0.5, y0..100.0)?;
        let names = f.folds.clone();
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(2 * n + 1)
            .x_label_formatter(&move |x| {
                let k = x.round();
                match names.get(k as usize) {
                    Some(name) if (x - k).abs() < 1e-9 && k >= 0.0 => {
                        // A block by its number alone: its span would overlap the next.
                        name.split(" (")
                            .next()
                            .unwrap_or(name)
                            .chars()
                            .take(22)
                            .collect()
                    }
                    _ => String::new(),
                }
            })
            .y_desc("held-out R² [%]")
            .label_style((FONT, 16))
            .draw()?;
        for (values, colour, offset) in [(&f.before, RED, -0.4), (&f.after, BLUE, 0.0)] {
            let bars = values.iter().enumerate().map(move |(k, &r2)| {
                let x = k as f64 + offset;
                Rectangle::new([(x, y0.max(r2)), (x + 0.4, 0.0)], colour.mix(0.6).filled())
            });
            chart.draw_series(bars)?;
            let clipped =
                values
                    .iter()
                    .enumerate()
                    .filter(|(_, r2)| **r2 < y0)
                    .map(move |(k, r2)| {
                        Text::new(
                            format!("{r2:.0}"),
                            (k as f64 + offset, y0 + 0.08 * (100.0 - y0)),
                            (FONT, 14).into_font(),
                        )
                    });
            chart.draw_series(clipped)?;
        }
    }
    Ok(())
}

fn draw_effects<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    effects: &[EffectResidual],
) -> DrawResult<(), DB> {
    for (area, e) in panels(root, title)?.iter().zip(effects) {
        let (x0, x1) = range(e.load.iter().copied());
        let (y0, y1) = range(e.before.iter().chain(e.after).chain(e.load).copied());
        let caption: String = e.name.chars().take(48).collect();
        let mut chart = ChartBuilder::on(area)
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(80)
            .caption(format!("{caption} ({})", e.axis.name()), (FONT, 20))
            .build_cartesian_2d(x0..x1, y0..y1)?;
        chart
            .configure_mesh()
            .x_desc(format!("effect's load [{}]", e.axis.unit()))
            .y_desc(format!("residual [{}]", e.axis.unit()))
            .label_style((FONT, 16))
            .draw()?;
        for (values, colour) in [(e.before, RED), (e.after, BLUE)] {
            let points = e.load.iter().zip(values).map(|(&x, &y)| (x, y));
            chart.draw_series(points.map(|p| Circle::new(p, 2, colour.mix(0.5).filled())))?;
        }
        chart.draw_series(LineSeries::new([(x0, x0), (x1, x1)], BLACK.stroke_width(1)))?;
    }
    Ok(())
}

fn draw_normal_probability<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    axes: &[NormalProbability],
) -> DrawResult<(), DB> {
    for (area, np) in panels(root, title)?.iter().zip(axes) {
        let (x0, x1) = range(np.points.iter().map(|p| p.0));
        let (y0, y1) = range(np.points.iter().map(|p| p.1));
        let mut chart = ChartBuilder::on(area)
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(80)
            .caption(
                format!("{} (correlation {:.4})", np.axis.name(), np.correlation),
                (FONT, 24),
            )
            .build_cartesian_2d(x0..x1, y0..y1)?;
        chart
            .configure_mesh()
            .x_desc("standard normal quantile [-]")
            .y_desc(format!("ordered residual [{}]", np.axis.unit()))
            .label_style((FONT, 16))
            .draw()?;
        chart.draw_series(np.points.iter().map(|&p| Circle::new(p, 2, BLUE.filled())))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn series_break_at_gaps_only() {
        let mut p: Vec<(f64, f64)> = (0..100).map(|i| (i as f64 * 0.01, 0.0)).collect();
        p.extend((0..100).map(|i| (5.0 + i as f64 * 0.01, 0.0)));
        let runs = runs_without_gaps(&p);
        assert_eq!(
            runs.iter().map(|r| r.len()).collect::<Vec<_>>(),
            vec![100, 100]
        );
    }

    #[test]
    fn decimation_keeps_extremes_and_bounds_point_count() {
        let t: Vec<f64> = (0..100_000).map(|i| i as f64 * 1e-3).collect();
        let mut y: Vec<f64> = t.iter().map(|x| x.sin()).collect();
        y[54_321] = 10.0;
        y[7] = -10.0;
        let d = decimate(&t, &y);
        assert!(d.len() <= MAX_POINTS + 2, "{}", d.len());
        assert!(d.iter().any(|p| p.1 == 10.0) && d.iter().any(|p| p.1 == -10.0));
    }
}
