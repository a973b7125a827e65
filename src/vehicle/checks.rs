//! The checks of a vehicle's construction: physical validity of the mass properties,
//! the layout conditions the model needs, the Assumption 2 breaches noted for an
//! accepted layout, and the class of Definition 1.

use std::f64::consts::PI;

use super::{
    Assumption2Breach, ConfigurationClass, MAX_ROTORS, MassAndRotorProperties, Rotor,
    VehicleErrorKind,
};

pub(super) fn check_positive(field: &'static str, value: f64) -> Result<(), VehicleErrorKind> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(VehicleErrorKind::OutOfRange {
            field,
            value,
            requirement: "must be a finite number > 0",
        })
    }
}

pub(super) fn check_properties(p: &MassAndRotorProperties) -> Result<(), VehicleErrorKind> {
    check_positive("mass", p.mass)?;
    check_positive("air_density", p.air_density)?;
    check_positive("rotor_radius", p.rotor_radius)?;
    if !p.hub_height.is_finite() {
        return Err(VehicleErrorKind::OutOfRange {
            field: "hub_height",
            value: p.hub_height,
            requirement: "must be finite",
        });
    }
    if !(p.rotor_inertia.is_finite() && p.rotor_inertia >= 0.0) {
        return Err(VehicleErrorKind::OutOfRange {
            field: "rotor_inertia",
            value: p.rotor_inertia,
            requirement: "must be a finite number >= 0",
        });
    }
    check_inertia(&p.inertia)
}

/// Largest ratio of arm length to rotor radius, either way round, of a vehicle file:
/// multirotors have ℓ/R between about 1 and 5; a thousand is one length in mm.
const MAX_LENGTH_RATIO: f64 = 50.0;

/// A vehicle file's arm length `arm` ℓ (mean hub radius, m) and rotor radius `radius` R
/// (m) within [`MAX_LENGTH_RATIO`] of each other either way: beyond it one of them was
/// written in mm (a fit then runs on a vehicle a thousand times too large or small).
pub(super) fn check_length_units(arm: f64, radius: f64) -> Result<(), VehicleErrorKind> {
    let ratio = arm.max(radius) / arm.min(radius);
    if ratio <= MAX_LENGTH_RATIO {
        return Ok(());
    }
    let arm_text = format!("arm length {arm:.3} m (from the rotor positions)");
    let radius_text = format!("rotor_radius {radius} m");
    let (long, short) = if arm > radius {
        (arm_text, radius_text)
    } else {
        (radius_text, arm_text)
    };
    Err(VehicleErrorKind::Layout(format!(
        "the {long} is {ratio:.0} times the {short} (multirotors have an arm length of \
         about 1 to 5 rotor radii): one of them in mm? Lengths are in m"
    )))
}

/// Symmetric positive definite, by Sylvester's criterion on the leading minors.
fn check_inertia(i: &[[f64; 3]; 3]) -> Result<(), VehicleErrorKind> {
    if i.iter().flatten().any(|v| !v.is_finite()) {
        return Err(VehicleErrorKind::Inertia("entries must be finite".into()));
    }
    let scale = i[0][0].abs().max(i[1][1].abs()).max(i[2][2].abs());
    for (a, b) in [(0, 1), (0, 2), (1, 2)] {
        if (i[a][b] - i[b][a]).abs() > 1e-9 * scale.max(f64::MIN_POSITIVE) {
            return Err(VehicleErrorKind::Inertia(format!(
                "not symmetric: I[{a}][{b}] = {} but I[{b}][{a}] = {}",
                i[a][b], i[b][a]
            )));
        }
    }
    let m1 = i[0][0];
    let m2 = i[0][0] * i[1][1] - i[0][1] * i[1][0];
    let m3 = nalgebra::Matrix3::from_fn(|r, c| i[r][c]).determinant();
    if !(m1 > 0.0 && m2 > 0.0 && m3 > 0.0) {
        return Err(VehicleErrorKind::Inertia(format!(
            "not positive definite (leading minors {m1:.3e}, {m2:.3e}, {m3:.3e} kg m^2 powers must all be > 0)"
        )));
    }
    Ok(())
}

/// Checks the conditions the (general planar) model needs and returns the arm length ℓ
/// (mean hub radius), m: at most [`MAX_ROTORS`] rotors, an even count N ≥ 4, no two rotors
/// at one position, balanced spins and a mixing matrix of rank 4. Cant and height are
/// checked per rotor when the file is read.
pub(super) fn check_layout(rotors: &[Rotor], tol: f64) -> Result<f64, VehicleErrorKind> {
    let n = rotors.len();
    let fail = |condition, detail| Err(VehicleErrorKind::Assumption2 { condition, detail });
    if n > MAX_ROTORS {
        return Err(VehicleErrorKind::Layout(format!(
            "{n} rotors: at most {MAX_ROTORS} are supported"
        )));
    }
    if n < 4 || !n.is_multiple_of(2) {
        return fail(
            "even rotor count N >= 4",
            format!("the vehicle has {n} rotors"),
        );
    }
    let arm = rotors.iter().map(|r| r.x.hypot(r.y)).sum::<f64>() / n as f64;
    if arm <= 0.0 {
        return fail("rotors off the CG", "every rotor sits on the CG".into());
    }
    for i in 0..n {
        for j in i + 1..n {
            let d = (rotors[i].x - rotors[j].x).hypot(rotors[i].y - rotors[j].y);
            if d <= tol * arm {
                return Err(VehicleErrorKind::Rotor {
                    rotor: j + 1,
                    problem: format!("same position as rotor {} (duplicate rotor)", i + 1),
                });
            }
        }
    }
    let cw = rotors.iter().filter(|r| r.spin > 0.0).count();
    if 2 * cw != n {
        return fail(
            "balanced spins",
            format!(
                "{cw} rotors spin +1 and {} spin -1: the rotor torques do not cancel in hover (the model needs N/2 rotors each way)",
                n - cw
            ),
        );
    }
    check_mixing_rank(rotors, arm, tol).map(|()| arm)
}

/// The rows 1, y_i, x_i, σ_i of the mixing matrix (Eq. 20, lengths over ℓ) must be linearly
/// independent: otherwise two of thrust, roll, pitch and yaw cannot be commanded apart
/// (e.g. spins following the sign of y_i couple yaw to roll). Smallest singular value
/// relative to the largest at most `tol` counts as dependent; the error names the
/// dependency.
fn check_mixing_rank(rotors: &[Rotor], arm: f64, tol: f64) -> Result<(), VehicleErrorKind> {
    let n = rotors.len();
    let m = nalgebra::DMatrix::from_fn(n, 4, |i, c| match c {
        0 => 1.0,
        1 => rotors[i].x / arm,
        2 => rotors[i].y / arm,
        _ => rotors[i].spin,
    });
    let svd = m.svd(false, true);
    let sv = &svd.singular_values;
    let (lo, hi) = (sv.min(), sv.max());
    if lo > tol * hi {
        return Ok(());
    }
    let v_t = svd.v_t.expect("requested");
    let k = sv.imin();
    let c: Vec<f64> = (0..4).map(|j| v_t[(k, j)]).collect();
    let big = c.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
    let names = ["1", "x_i/l", "y_i/l", "spin_i"];
    let combo: Vec<String> = c
        .iter()
        .zip(names)
        .filter(|(x, _)| x.abs() > 1e-6 * big)
        .map(|(x, name)| format!("{:+.3}*{name}", x / big))
        .collect();
    Err(VehicleErrorKind::Assumption2 {
        condition: "independent thrust, roll, pitch and yaw",
        detail: format!(
            "the mixing matrix (Eq. 20) has rank 3: {} = 0 for every rotor (l = {arm:.4} m), so the rotors cannot produce thrust, roll, pitch and yaw moment independently",
            combo.join(" ")
        ),
    })
}

/// The conditions of Assumption 2 beyond those [`check_layout`] enforces: equal arms,
/// equal interior angles 2π/N, opposite spins of azimuthal neighbours, symmetry about
/// both body axes. The first offence of each condition is reported.
pub(super) fn assumption2_breaches(rotors: &[Rotor], arm: f64, tol: f64) -> Vec<Assumption2Breach> {
    let n = rotors.len();
    let mut out = Vec::new();
    let mut breach = |condition, detail| {
        if !out
            .iter()
            .any(|b: &Assumption2Breach| b.condition == condition)
        {
            out.push(Assumption2Breach { condition, detail });
        }
    };
    let radii: Vec<f64> = rotors.iter().map(|r| r.x.hypot(r.y)).collect();
    // Arms are compared with the median, so the odd one out is the one reported.
    let mut sorted = radii.clone();
    sorted.sort_by(f64::total_cmp);
    let median = (sorted[n / 2 - 1] + sorted[n / 2]) / 2.0;
    for (i, r) in radii.iter().enumerate() {
        if (r - median).abs() > tol * median {
            breach(
                "equal arms",
                format!(
                    "rotor {} has arm {r:.6} m, the median arm is {median:.6} m (tolerance {:.2e} m)",
                    i + 1,
                    tol * median
                ),
            );
        }
    }
    let mut order: Vec<(f64, usize)> = rotors
        .iter()
        .enumerate()
        .map(|(i, r)| (r.y.atan2(r.x).rem_euclid(2.0 * PI), i))
        .collect();
    order.sort_by(|a, b| a.0.total_cmp(&b.0));
    let gap = 2.0 * PI / n as f64;
    for k in 0..n {
        let (a0, i0) = order[k];
        let (a1, i1) = order[(k + 1) % n];
        let d = (a1 - a0).rem_euclid(2.0 * PI);
        if (d - gap).abs() > tol {
            breach(
                "equal interior angles",
                format!(
                    "rotors {} and {} are {:.4} deg apart, expected {:.4} deg",
                    i0 + 1,
                    i1 + 1,
                    d.to_degrees(),
                    gap.to_degrees()
                ),
            );
        }
        if rotors[i0].spin == rotors[i1].spin {
            breach(
                "neighbouring rotors spin in opposite directions",
                format!(
                    "neighbouring rotors {} and {} both have spin {:+}",
                    i0 + 1,
                    i1 + 1,
                    rotors[i0].spin
                ),
            );
        }
    }
    let has = |x: f64, y: f64| rotors.iter().any(|r| (r.x - x).hypot(r.y - y) <= tol * arm);
    for (i, r) in rotors.iter().enumerate() {
        if !has(r.x, -r.y) {
            breach(
                "symmetric about the body x axis",
                format!(
                    "rotor {} at ({}, {}) m has no mirror image at y = {}",
                    i + 1,
                    r.x,
                    r.y,
                    -r.y
                ),
            );
        }
        if !has(-r.x, r.y) {
            breach(
                "symmetric about the body y axis",
                format!(
                    "rotor {} at ({}, {}) m has no mirror image at x = {}",
                    i + 1,
                    r.x,
                    r.y,
                    -r.x
                ),
            );
        }
    }
    out
}

/// Definition 1 (seed §4.2).
pub(super) fn classify(rotors: &[Rotor], arm: f64, tol: f64) -> ConfigurationClass {
    if rotors.len() >= 6 {
        return ConfigurationClass::Multirotor6Plus;
    }
    let on_axis = rotors
        .iter()
        .any(|r| r.x.abs() <= tol * arm || r.y.abs() <= tol * arm);
    if on_axis {
        ConfigurationClass::QuadPlus
    } else {
        ConfigurationClass::QuadX
    }
}
