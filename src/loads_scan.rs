//! Estimating the cut-off of consistent filtering from the data: when a user does not
//! know how the logged loads were smoothed, the fit is repeated with the regressor
//! signals low-passed at each cut-off of a grid (and once unfiltered), each scored on
//! held-out data, and the cut-off whose model predicts held-out loads best is kept.
//!
//! Why held-out prediction decides: loads smoothed when the log was made lack the fast
//! content the unfiltered regressors carry, so a model whose regressors are filtered
//! alike predicts them better, up to the log's own cut-off; below it the filter removes
//! content the loads still have and the prediction worsens again. On loads that were not
//! smoothed any filter costs (a yaw moment driven by J_z Ω̇ is lost at once), so the
//! unfiltered fit wins. The score is the mean over the six axes of ln RMSE on held-out
//! data (the Gaussian held-out log-likelihood with one variance per axis, up to
//! constants): every axis counts by its relative change, whatever its unit and however
//! poorly it is predicted. Held-out means the folds of every decision of the fit
//! (leave one log out, or contiguous blocks of one log); validation logs are not used.
//!
//! The filter's shape is the crate's ([`crate::smooth::LowPass`], sinc³); only its
//! cut-off is estimated. A log smoothed by a steeper filter (a high-order Butterworth,
//! a spline) is matched by a lower sinc³ cut-off, so the estimate is "the cut-off of
//! this filter that matches the log", not the log's nominal one.

use serde::{Deserialize, Serialize};

use crate::error::Error;
use crate::estimate::AxisMetrics;
use crate::pipeline::{self, FitOutcome, FitRequest};

/// Candidate cut-offs, Hz, from the highest down: steps of √2 (each halves or doubles
/// the filter's window every second step).
const GRID_HZ: [f64; 11] = [64.0, 45.0, 32.0, 23.0, 16.0, 11.0, 8.0, 5.7, 4.0, 2.8, 2.0];

/// Cut-offs are tried up to this fraction of the sample rate (of the fastest-sampled
/// log's median step): above it the filter's window spans about a sample each side and
/// barely acts.
const MAX_FRACTION_OF_RATE: f64 = 0.25;

/// How much lower (mean ln RMSE, so ≈ a relative RMSE change) a filtered fit's held-out
/// score must be than the unfiltered fit's for a filter to be chosen: 0.5 % of RMSE.
/// Filtering noisy regressor signals can gain a little on loads that were never smoothed
/// (less noise in the regressors); a logged smoothing gains far more (NeuroBEM: 1.0 %
/// over all six axes, 12 % on yaw; the simulator's 5 Hz smoothing: 90 %).
const MARGIN: f64 = 0.005;

/// Scores closer than this are equal: a filter whose window holds a single sample
/// passes the signals unchanged but for rounding (a 100 Hz log at 16 Hz and above).
const TIE: f64 = 1e-9;

/// Grid points below the best that may score worse before the scan stops (the score
/// falls off monotonically once the cut-off is below the log's).
const PATIENCE: usize = 3;

/// One cut-off tried.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScanPoint {
    /// The cut-off, Hz; `None` for the unfiltered fit.
    pub cutoff_hz: Option<f64>,
    /// Mean over the six axes of ln(held-out RMSE) of the final model (lower is better;
    /// the RMSEs in N and N m).
    pub score: f64,
    /// Held-out R² per axis (Fx … Mz) of the final model.
    pub r2: [f64; 6],
}

/// The cut-offs tried and the one chosen ([`crate::Identification::estimate_loads_low_pass`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LowPassScan {
    /// Every cut-off tried, in the order tried (unfiltered first, then from high to low).
    pub points: Vec<ScanPoint>,
    /// The cut-off kept, Hz, or `None`: no filter beat unfiltered by 0.5 % of RMSE.
    pub chosen_hz: Option<f64>,
}

/// Scans `req` (whose logs are fitted as they are, with their diagnosis when it is on) at
/// each cut-off; `req`'s own cut-off and its mapping's `[loads]` are ignored. The
/// request's validation logs are left out of every trial fit. Also returns the trial
/// fit at the cut-off kept, which is the request's fit when it has no validation logs.
pub(crate) fn scan(req: &FitRequest) -> Result<(LowPassScan, FitOutcome), Error> {
    let mut trial = req.clone();
    trial.validate.clear();
    if let Some(m) = trial.mapping.as_mut() {
        m.loads = None;
    }
    let mut run = |cutoff_hz: Option<f64>| -> Result<(ScanPoint, FitOutcome), Error> {
        trial.loads_low_pass_hz = cutoff_hz;
        if let Some(p) = &trial.progress {
            p.start_scan_fit(cutoff_hz);
        }
        let outcome = pipeline::run(&trial)?;
        let held_out = held_out_metrics(&outcome);
        let point = ScanPoint {
            cutoff_hz,
            score: held_out.iter().map(|m| m.rmse.ln()).sum::<f64>() / 6.0,
            r2: held_out.map(|m| m.r2),
        };
        Ok((point, outcome))
    };
    let (unfiltered, unfiltered_fit) = run(None)?;
    let top = unfiltered_fit
        .summaries
        .iter()
        .filter_map(|s| s.median_time_step)
        .fold(f64::INFINITY, |lowest, dt| {
            lowest.min(MAX_FRACTION_OF_RATE / dt)
        });
    let mut points = vec![unfiltered];
    let mut best = 0;
    // The fit at `best` once a cut-off beats unfiltered.
    let mut best_fit = None;
    let mut worse = 0;
    for &hz in GRID_HZ.iter().filter(|&&hz| hz <= top) {
        let (point, fit) = run(Some(hz))?;
        points.push(point);
        let last = points.len() - 1;
        if points[last].score < points[best].score - TIE {
            best = last;
            best_fit = Some(fit);
            worse = 0;
        } else if points[last].score > points[best].score + TIE {
            worse += 1;
            if worse == PATIENCE {
                break;
            }
        }
    }
    let filtered = points[best].score < points[0].score - MARGIN;
    let (chosen_hz, kept_fit) = match best_fit {
        Some(fit) if filtered => (points[best].cutoff_hz, fit),
        _ => (None, unfiltered_fit),
    };
    Ok((LowPassScan { points, chosen_hz }, kept_fit))
}

/// The final model's held-out metrics: after the diagnosis when it ran, else Eq. 22's
/// pooled cross-validation.
fn held_out_metrics(outcome: &FitOutcome) -> [AxisMetrics; 6] {
    match &outcome.diagnosis {
        Some(d) => d.after,
        None => outcome.cross_validation.1.pooled_metrics(),
    }
}
