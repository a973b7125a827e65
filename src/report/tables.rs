//! Paper-style text tables of a [`Report`]: FSOA (seed Tables 2–3), MMR fit per axis
//! (Table 4), parameters (Table 5), residual covariance, normality and identifiability.
//!
//! Everything printed comes from the [`Report`], so it equals the JSON to the printed
//! precision.

use std::fmt::Write;

use super::summary::{AxisRow, DiagnosisReport, FsoaReport, Report};
use crate::diagnose::Reading;
use crate::loads_scan::LowPassScan;
use crate::sample::Axis;

/// All tables, as printed by `mrsysid fit`.
pub fn render(report: &Report) -> String {
    let mut out = String::new();
    header(&mut out, report);
    for f in &report.fsoa {
        fsoa_table(&mut out, f);
    }
    fit_table(&mut out, report);
    parameter_table(&mut out, report);
    covariance_table(&mut out, report);
    normality_table(&mut out, report);
    identifiability(&mut out, report);
    if let Some(d) = &report.diagnosis {
        out.push_str(&render_diagnosis(d));
    }
    out
}

/// The diagnosis tables: ranked candidates per step, effects added with their
/// estimates, validation NRMSE/TIC/R² per axis before and after.
pub fn render_diagnosis(d: &DiagnosisReport) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "Diagnosis: effects the Eq. 22 model lacks (every decision cross-validated on the fit data)"
    );
    for (k, step) in d.steps.iter().enumerate() {
        let _ = writeln!(
            out,
            "  step {}: {}",
            k + 1,
            step.added
                .as_deref()
                .map_or("nothing added".to_string(), |a| format!("added {a}"))
        );
        let _ = writeln!(
            out,
            "    {:<26} {:>9} {:>10}  verdict",
            "candidate", "CV gain", "P"
        );
        for c in step.ranking.iter().take(8) {
            // The ranking's measure: relative cross-validated NRMSE reductions summed
            // over all axes.
            let gain: f64 = c.validation_gain.iter().sum();
            let verdict = if c.rejected.is_empty() {
                "accepted"
            } else {
                c.rejected.as_str()
            };
            let _ = writeln!(
                out,
                "    {:<26} {:>8.1}% {:>10.2e}  {verdict}",
                c.name,
                100.0 * gain,
                c.p
            );
        }
        if !step.look_alikes.is_empty() {
            let _ = writeln!(
                out,
                "    the data cannot tell {} apart from {}: both reported",
                step.added.as_deref().unwrap_or("-"),
                step.look_alikes.join(", ")
            );
        }
        if !step.not_separable.is_empty() {
            let _ = writeln!(
                out,
                "    not separable with these data: {} fits the held-out data as well",
                step.not_separable.join(", ")
            );
        }
        for w in &step.withdrawn {
            let _ = writeln!(out, "    withdrawn (tested again without it): {w}");
        }
    }
    if d.stopped_at_limit {
        let _ = writeln!(
            out,
            "  the search stopped at its limit of {} effects with candidates left",
            d.steps.len()
        );
    }
    for f in &d.findings {
        let _ = writeln!(out, "  finding: {f}");
    }
    for f in &d.below_bar {
        let _ = writeln!(out, "  present, below the importance bar: {f}");
    }
    for e in &d.effects_added {
        let axes: Vec<&str> = e.axes.iter().map(|a| a.name()).collect();
        let what = if e.model_completion {
            "model completion"
        } else if e.generic {
            "unnamed structure (generic pool)"
        } else {
            "effect"
        };
        let _ = writeln!(out, "  {what}: {} (axes {})", e.name, axes.join(", "));
        for p in &e.parameters {
            // A freed moment coefficient is estimated as moment value − force value.
            let tie = if p.reading == Reading::MomentMinusForce {
                format!(
                    " (moment value - force value: {:.1} sigma)",
                    p.estimate / p.std
                )
            } else {
                String::new()
            };
            let _ = writeln!(
                out,
                "    {} = {}{tie}",
                p.name,
                with_unit(p.reading, p.estimate, p.std, &p.unit)
            );
        }
    }
    for u in &d.unsupported {
        let _ = writeln!(
            out,
            "  not supported by these data (left out): {} (CV score {:+.1} when left out)",
            u.name, u.score_change
        );
    }
    let _ = writeln!(
        out,
        "  cross-val. {:>4} {:>12} {:>12} {:>8} {:>8} {:>8} {:>8}",
        "axis", "NRMSE before", "NRMSE after", "TIC bef.", "TIC aft.", "R2 bef.", "R2 aft."
    );
    for (b, a) in d.before.iter().zip(&d.after) {
        let _ = writeln!(
            out,
            "             {:>4} {:>11.2}% {:>11.2}% {:>8.3} {:>8.3} {:>7.1}% {:>7.1}%",
            b.axis.name(),
            100.0 * b.nrmse,
            100.0 * a.nrmse,
            b.tic,
            a.tic,
            100.0 * b.r2,
            100.0 * a.r2
        );
    }
    named_share(&mut out, d);
    for r in &d.remainder {
        let _ = writeln!(out, "  what is left: {}", r.sentence());
    }
    for e in &d.eq22_axes {
        let b = axis_row(&d.before, e.axis).map_or(f64::NAN, |r| 100.0 * r.r2);
        let mut line = format!(
            "  {} predicted by the Eq. 22 model: the final model predicted its held-out data \
             worse (R2 {b:.1}% -> {:.1}%",
            e.axis.name(),
            100.0 * e.final_held_out.r2
        );
        if let (Some(f), Some(v)) = (&e.final_validation, &d.validation) {
            let vb = axis_row(&v.before, e.axis).map_or(f64::NAN, |r| 100.0 * r.r2);
            line.push_str(&format!(
                "; on the validation logs {vb:.1}% -> {:.1}%",
                100.0 * f.r2
            ));
        }
        let _ = writeln!(out, "{line})");
    }
    if let Some(v) = &d.validation {
        for axis in &d.worse_on_validation {
            let (b, a) = (axis_row(&v.before, *axis), axis_row(&v.after, *axis));
            let [r2b, r2a, eb, ea] = [
                b.map_or(f64::NAN, |r| 100.0 * r.r2),
                a.map_or(f64::NAN, |r| 100.0 * r.r2),
                b.map_or(f64::NAN, |r| r.rmse),
                a.map_or(f64::NAN, |r| r.rmse),
            ];
            let _ = writeln!(
                out,
                "  worse than the Eq. 22 model on the validation logs' {}: R2 {r2b:.1}% -> \
                 {r2a:.1}%, RMSE {eb:.4} -> {ea:.4} (no decision saw these data)",
                axis.name(),
            );
        }
    }
    let _ = writeln!(out, "  R2 [%] per held-out data, before -> after");
    let rows: Vec<(String, &Vec<AxisRow>)> = d
        .folds
        .iter()
        .chain(&d.validation)
        .flat_map(|f| {
            [
                (format!("{} before", f.name), &f.before),
                (format!("{} after", f.name), &f.after),
            ]
        })
        .collect();
    r2_rows(&mut out, rows.iter().map(|(n, a)| (n.as_str(), *a)));
    out.push('\n');
    out
}

/// Per axis, the share of the cross-validated R² gain that the named mechanisms and
/// completions carry (the final model without its unspecific terms), where the
/// diagnosis gained at least 0.01 in R².
fn named_share(out: &mut String, d: &DiagnosisReport) {
    let mut said = Vec::new();
    for (k, (b, a)) in d.before.iter().zip(&d.after).enumerate() {
        let gain = a.r2 - b.r2;
        if gain < 0.01 {
            continue;
        }
        let named = d.named_only.as_ref().map_or(a.r2, |n| n[k].r2) - b.r2;
        said.push(format!("{} {:.0} %", b.axis.name(), 100.0 * named / gain));
    }
    if !said.is_empty() {
        let _ = writeln!(
            out,
            "  share of the R2 gain carried by named mechanisms (the final model without its unspecific terms): {}",
            said.join(", ")
        );
    }
}

/// `estimate ± std unit`, in mm for lengths, ms for times, % for fractional changes
/// ([`Reading::Fraction`]) and fixed decimals for speeds and accelerations.
fn with_unit(reading: Reading, x: f64, s: f64, unit: &str) -> String {
    let fraction = reading == Reading::Fraction;
    match unit {
        "-" if fraction => format!("{:+.2} ± {:.2} %", 100.0 * x, 100.0 * s),
        "m" => format!("{:.2} ± {:.2} mm", 1e3 * x, 1e3 * s),
        "-" => format!("{x:.4e} ± {s:.1e}"),
        "s" => format!("{:.2} ± {:.2} ms", 1e3 * x, 1e3 * s),
        "m/s" => format!("{x:.2} ± {s:.2} m/s"),
        "m/s^2" => format!("{x:.3} ± {s:.3} m/s^2"),
        u => format!("{x:.4e} ± {s:.1e} {u}"),
    }
}

fn header(out: &mut String, r: &Report) {
    let _ = writeln!(
        out,
        "mrsysid {}: vehicle {} ({}, {} rotors); {} fit samples, {} validation samples ({})",
        r.tool_version,
        r.vehicle.name,
        r.vehicle.class,
        r.vehicle.rotors,
        r.samples,
        r.validation_samples,
        r.validation_source
    );
    let _ = writeln!(
        out,
        "model: Eq. 22, inflow correction {:?}, terms linear in Vh {}, J_z terms {:?}{}\n",
        r.model.inflow,
        if r.model.linear_vh_terms {
            "kept"
        } else {
            "removed"
        },
        r.model.rotor_inertia,
        r.loads_low_pass_hz.map_or(String::new(), |hz| format!(
            "; regressor signals low-passed at {hz} Hz as the loads were (consistent filtering)"
        ))
    );
    for a in &r.airborne {
        let _ = writeln!(out, "airborne only: {}: {}\n", a.log, a.describe());
    }
    if let Some(scan) = &r.loads_low_pass_scan {
        low_pass_scan(out, scan);
    }
}

/// The cut-offs tried when the loads' low-pass was estimated, with the one kept.
fn low_pass_scan(out: &mut String, scan: &LowPassScan) {
    let _ = writeln!(
        out,
        "loads low-pass estimated: {}; held-out score per cut-off tried (mean ln RMSE over \
         the axes, lower is better; * kept):",
        match (scan.chosen_hz, scan.points.len()) {
            (Some(hz), _) => format!("{hz} Hz"),
            (None, 1) => "none (no cut-off of the grid lies below a quarter of the sample \
                          rate)"
                .to_string(),
            (None, _) => "none (no cut-off paid 0.5 % over unfiltered)".to_string(),
        }
    );
    let _ = writeln!(
        out,
        "{:>10} {:>8} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7}",
        "cut-off", "score", "Fx R2", "Fy R2", "Fz R2", "Mx R2", "My R2", "Mz R2"
    );
    for p in &scan.points {
        let name = p
            .cutoff_hz
            .map_or("none".to_string(), |hz| format!("{hz} Hz"));
        let _ = write!(out, "{name:>10} {:>8.4}", p.score);
        for r2 in p.r2 {
            let _ = write!(out, " {:>7.1}", 100.0 * r2);
        }
        let mark = if p.cutoff_hz == scan.chosen_hz {
            "  *"
        } else {
            ""
        };
        let _ = writeln!(out, "{mark}");
    }
    let _ = writeln!(out);
}

/// FSOA table, one row per candidate term and one column per iteration (the seed's
/// Tables 2–3 transposed so long term names fit); `*` marks the term added.
fn fsoa_table(out: &mut String, f: &FsoaReport) {
    let _ = writeln!(
        out,
        "FSOA {}: R^2 [%] per iteration (* = term added)",
        f.axis
    );
    let width = f.terms.iter().map(String::len).max().unwrap_or(4).max(4);
    let _ = write!(out, "  {:<width$}", "term");
    for i in 1..=f.r2.len() {
        let _ = write!(out, " {:>8}", i);
    }
    out.push('\n');
    for (j, term) in f.terms.iter().enumerate() {
        let _ = write!(out, "  {term:<width$}");
        for (i, row) in f.r2.iter().enumerate() {
            let cell = match row.get(j).copied().flatten() {
                Some(v) if f.order.get(i) == Some(&j) => format!("{:.1}*", 100.0 * v),
                Some(v) => format!("{:.1}", 100.0 * v),
                None => "-".to_string(),
            };
            let _ = write!(out, " {cell:>8}");
        }
        out.push('\n');
    }
    let _ = writeln!(
        out,
        "  sigma^2 = {:.3e}; PSE keeps the first {} terms, partial F >= F_in keeps {}\n",
        f.residual_variance, f.pse_terms, f.f_in_terms
    );
}

fn fit_table(out: &mut String, r: &Report) {
    let _ = writeln!(out, "MMR fit per axis (Table 4)");
    let _ = writeln!(
        out,
        "  {:<4} {:>10} {:>8} {:>8} {:>12} | {:>10} {:>8} {:>8}",
        "axis", "NRMSE [%]", "TIC", "R2 [%]", "RMSE", "val NRMSE%", "val TIC", "val R2%"
    );
    for (a, v) in r.axes.iter().zip(&r.validation) {
        let _ = writeln!(
            out,
            "  {:<4} {:>10.2} {:>8.3} {:>8.1} {:>12.4e} | {:>10.2} {:>8.3} {:>8.1}",
            a.axis.name(),
            100.0 * a.nrmse,
            a.tic,
            100.0 * a.r2,
            a.rmse,
            100.0 * v.nrmse,
            v.tic,
            100.0 * v.r2
        );
    }
    if r.cross_validation.len() > 2 {
        // A single log's folds are its blocks (`block k/K (a-b s)`), several logs' the logs
        // or the groups the user named (`group <name>`).
        let first = &r.cross_validation[0].name;
        let held_out = if first.starts_with("block ") {
            "each block predicted by the model fitted on the rest of the log less its guards"
        } else if first.starts_with("group ") {
            "each group of logs predicted by the model fitted on the other groups"
        } else {
            "each log predicted by the model fitted on the others"
        };
        let _ = writeln!(out, "  cross-validated R2 [%] ({held_out})");
        r2_rows(
            out,
            r.cross_validation
                .iter()
                .map(|f| (f.name.as_str(), &f.axes)),
        );
    }
    out.push('\n');
}

/// One line of R² [%] per axis for each named row, under an axis header.
fn r2_rows<'a>(out: &mut String, rows: impl Iterator<Item = (&'a str, &'a Vec<AxisRow>)>) {
    let _ = writeln!(
        out,
        "    {:<44} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7}",
        "", "Fx", "Fy", "Fz", "Mx", "My", "Mz"
    );
    for (name, axes) in rows {
        let _ = write!(out, "    {:<44}", truncate(name, 44));
        for a in axes {
            let _ = write!(out, " {:>7.1}", 100.0 * a.r2);
        }
        out.push('\n');
    }
}

fn truncate(s: &str, n: usize) -> String {
    if s.chars().count() <= n {
        s.to_string()
    } else {
        let keep: String = s.chars().take(n - 1).collect();
        format!("{keep}~")
    }
}

/// Power of ten k such that |x|·10^k lies in [1, 1000), for a readable scaled estimate.
fn scale_exponent(x: f64) -> i32 {
    if x == 0.0 || !x.is_finite() {
        0
    } else {
        -(x.abs().log10().floor() as i32).div_euclid(3) * 3
    }
}

fn p_value(p: f64) -> String {
    if p == 0.0 {
        "< 1e-300".to_string()
    } else if p < 1e-3 {
        format!("{p:.2e}")
    } else {
        format!("{p:.3}")
    }
}

fn parameter_table(out: &mut String, r: &Report) {
    match &r.inference_withheld {
        None => {
            let _ = writeln!(
                out,
                "MMR parameter estimates (Table 5), t-tests with {} degrees of freedom",
                r.degrees_of_freedom
            );
        }
        Some(why) => {
            let _ = writeln!(
                out,
                "MMR parameter estimates (Table 5); std, t and P not reported: {why}"
            );
        }
    }
    let _ = writeln!(
        out,
        "  {:<14} {:>7} {:>11} {:>11} {:>9} {:>10} {:>11}  unit",
        "parameter", "scale", "estimate", "std", "|t0|", "P-value", "std (col.)"
    );
    for p in &r.parameters {
        let k = scale_exponent(p.estimate);
        let s = 10f64.powi(k);
        let withheld = r.inference_withheld.is_some();
        let coloured = p
            .std_coloured
            .filter(|_| !withheld)
            .map_or("-".to_string(), |c| format!("{:.4}", c * s));
        let (std, t, pv) = if withheld {
            ("-".to_string(), "-".to_string(), "-".to_string())
        } else {
            (
                format!("{:.4}", p.std * s),
                format!("{:.1}", p.t.abs()),
                p_value(p.p),
            )
        };
        let _ = writeln!(
            out,
            "  {:<14} {:>7} {:>11.4} {std:>11} {t:>9} {pv:>10} {coloured:>11}  {}",
            p.name,
            format!("x1e{k}"),
            p.estimate * s,
            p.unit
        );
    }
    out.push('\n');
}

fn covariance_table(out: &mut String, r: &Report) {
    let _ = writeln!(out, "Residual covariance R (units N and N m)");
    let names = ["Fx", "Fy", "Fz", "Mx", "My", "Mz"];
    let _ = write!(out, "  {:<4}", "");
    for n in names {
        let _ = write!(out, " {n:>11}");
    }
    out.push('\n');
    for (n, row) in names.iter().zip(&r.residual_covariance) {
        let _ = write!(out, "  {n:<4}");
        for v in row {
            let _ = write!(out, " {v:>11.3e}");
        }
        out.push('\n');
    }
    out.push('\n');
}

fn normality_table(out: &mut String, r: &Report) {
    if r.normality.is_empty() {
        return;
    }
    let _ = writeln!(out, "Residual normality (Figure 3) and whiteness");
    let _ = writeln!(
        out,
        "  {:<4} {:>12} {:>12} {:>14} {:>10}",
        "axis", "mean", "std", "normal corr.", "lag-1 ac"
    );
    for n in &r.normality {
        let _ = writeln!(
            out,
            "  {:<4} {:>12.4e} {:>12.4e} {:>14.4} {:>10.3}",
            n.axis.name(),
            n.mean,
            n.std,
            n.normal_probability_correlation,
            n.lag1_autocorrelation
        );
    }
    out.push('\n');
}

fn identifiability(out: &mut String, r: &Report) {
    let _ = writeln!(out, "Identifiability");
    for c in &r.identifiability {
        let vif = c.max_vif.as_ref().map_or(String::new(), |(n, v)| {
            format!(", largest VIF {v:.3e} ({n})")
        });
        if c.max_vif.is_none() {
            let _ = writeln!(out, "  {:<7} no columns left (all dropped)", c.problem);
        } else {
            let _ = writeln!(
                out,
                "  {:<7} condition number {:.3e}{vif}",
                c.problem, c.condition_number
            );
        }
    }
    for d in &r.dropped_parameters {
        let why = match &d.cause {
            Some(cause) if d.aliased_with.is_empty() => cause.clone(),
            _ => format!("not separable from {}", d.aliased_with.join(", ")),
        };
        let _ = writeln!(out, "  WARNING {}: dropped {} ({why})", d.problem, d.name);
    }
    out.push('\n');
}

/// The row of `axis` among `rows`, if any.
fn axis_row(rows: &[AxisRow], axis: Axis) -> Option<&AxisRow> {
    rows.iter().find(|r| r.axis == axis)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scale_puts_estimates_in_one_to_a_thousand() {
        for (x, k) in [
            (0.0154, 3),
            (21.4, 0),
            (3.0e-5, 6),
            (-0.00136, 3),
            (1234.0, -3),
        ] {
            let e = scale_exponent(x);
            assert_eq!(e, k, "{x}");
            let s = x.abs() * 10f64.powi(e);
            assert!((1.0..1000.0).contains(&s), "{x}: {s}");
        }
    }
}
