//! Motor mixing into virtual actuators (seed Eq. 19–21).
//!
//! δ = M_ix Ω and δ² = M_ix Ω² with the rows of Eq. 20:
//! `[1/N …]` (thrust δt), `[−y_i …]` (aileron δa), `[x_i …]` (elevator δe) and
//! `[−σ_i …]` (rudder δr). The same matrix maps rotor accelerations Ω̇ to δ̇, which the
//! J_z δ̇r term of Eq. 22f needs.
//!
//! General planar layouts (breaking Assumption 2) use the same rows with the actual hub
//! positions, so every δ term of Eq. 22 stays exact; what changes is that the rows are no
//! longer orthogonal: with the rotor centroid off the CG, equal rotor speeds give
//! δe = Ω Σx_i and δa = −Ω Σy_i (thrust couples into pitch and roll); Σx_i y_i ≠ 0
//! couples δa and δe, Σσ_i x_i, Σσ_i y_i ≠ 0 couple δr into them. The vehicle loader
//! requires rank 4 (thrust, roll, pitch and yaw independently commandable) and balanced
//! spins (Σσ_i = 0, so δr = 0 at equal speeds).

use crate::util::dot;
use crate::vehicle::Vehicle;

/// Index of a virtual actuator in the arrays returned here (row of Eq. 20).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VirtualActuator {
    /// δt, mean rotor speed (rad/s) or mean squared speed (rad²/s²).
    Thrust = 0,
    /// δa = −Σ y_i Ω_i (m rad/s), or with Ω_i².
    Aileron = 1,
    /// δe = Σ x_i Ω_i (m rad/s), or with Ω_i².
    Elevator = 2,
    /// δr = −Σ σ_i Ω_i (rad/s), or with Ω_i².
    Rudder = 3,
}

/// The mixing matrix M_ix of Eq. 20 (4 × N).
#[derive(Debug, Clone, PartialEq)]
pub struct Mixing {
    /// Row-major 4 × N: rows δt, δa, δe, δr.
    rows: [Vec<f64>; 4],
}

impl Mixing {
    /// M_ix of a vehicle (Eq. 20).
    pub fn new(vehicle: &Vehicle) -> Self {
        let n = vehicle.rotor_count() as f64;
        let r = vehicle.rotors();
        Self {
            rows: [
                r.iter().map(|_| 1.0 / n).collect(),
                r.iter().map(|r| -r.y).collect(),
                r.iter().map(|r| r.x).collect(),
                r.iter().map(|r| -r.spin).collect(),
            ],
        }
    }

    /// Row `a` of M_ix: the weight of each rotor in virtual actuator `a`.
    pub fn row(&self, a: VirtualActuator) -> &[f64] {
        &self.rows[a as usize]
    }

    /// Rotor count N.
    pub fn rotor_count(&self) -> usize {
        self.rows[0].len()
    }

    /// δ = M_ix Ω (Eq. 21) for rotor speeds Ω (rad/s): `[δt, δa, δe, δr]`.
    /// Also gives δ̇ from Ω̇ (rad/s²), since M_ix is constant.
    pub fn actuators(&self, omega: &[f64]) -> [f64; 4] {
        self.rows.each_ref().map(|row| dot(row, omega))
    }

    /// δ² = M_ix Ω² (Eq. 19) for rotor speeds Ω (rad/s): `[δ²t, δ²a, δ²e, δ²r]`.
    pub fn squared_actuators(&self, omega: &[f64]) -> [f64; 4] {
        self.rows
            .each_ref()
            .map(|row| row.iter().zip(omega).map(|(m, w)| m * w * w).sum())
    }

    /// Batch form of [`Mixing::actuators`]: `out[a][k] = Σ_i M_ix[a][i] · x_i[k]` for rotor
    /// series `x_i` (one slice per rotor, all of length `out[a].len()`). With `square`,
    /// uses `x_i[k]²` (Eq. 19). Writes without allocating.
    pub fn mix_into<S: AsRef<[f64]>>(
        &self,
        rotor_series: &[S],
        square: bool,
        out: [&mut [f64]; 4],
    ) {
        for (row, dst) in self.rows.iter().zip(out) {
            mix_row(row, rotor_series, square, dst);
        }
    }
}

/// `dst[k] = Σ_i weights[i] · x_i[k]` (or `x_i[k]²`): rotors with zero weight are
/// skipped, the rest are taken four at a time in one vectorisable pass over the samples.
pub fn mix_row<S: AsRef<[f64]>>(
    weights: &[f64],
    rotor_series: &[S],
    square: bool,
    dst: &mut [f64],
) {
    let n = dst.len();
    let mut group: [(f64, &[f64]); 4] = [(0.0, &[]); 4];
    let mut len = 0;
    let mut first = true;
    for (&m, x) in weights.iter().zip(rotor_series) {
        if m == 0.0 {
            continue;
        }
        group[len] = (m, &x.as_ref()[..n]);
        len += 1;
        if len == 4 {
            mix_group(&group, square, first, dst);
            first = false;
            len = 0;
        }
    }
    if len > 0 {
        // Pad with zero weights on a real series so the 4-way kernel applies.
        for slot in len..4 {
            group[slot] = (0.0, group[0].1);
        }
        mix_group(&group, square, first, dst);
    } else if first {
        dst.fill(0.0);
    }
}

fn mix_group(group: &[(f64, &[f64]); 4], square: bool, first: bool, dst: &mut [f64]) {
    match (square, first) {
        (false, true) => mix4::<false, true>(group, dst),
        (false, false) => mix4::<false, false>(group, dst),
        (true, true) => mix4::<true, true>(group, dst),
        (true, false) => mix4::<true, false>(group, dst),
    }
}

/// `dst (=|+=) Σ_{i<4} m_i f(x_i)` with f the identity or the square.
fn mix4<const SQUARE: bool, const FIRST: bool>(g: &[(f64, &[f64]); 4], dst: &mut [f64]) {
    let n = dst.len();
    let f = |x: f64| if SQUARE { x * x } else { x };
    let [(m0, a), (m1, b), (m2, c), (m3, d)] = *g;
    let rows = a[..n].iter().zip(&b[..n]).zip(c[..n].iter().zip(&d[..n]));
    for (out, ((&a, &b), (&c, &d))) in dst.iter_mut().zip(rows) {
        let v = m0 * f(a) + m1 * f(b) + m2 * f(c) + m3 * f(d);
        *out = if FIRST { v } else { *out + v };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vehicle::{Preset, test_props as props};

    #[test]
    fn quad_x_mixing_matches_eq_20_by_hand() {
        let props = props();
        let v = Vehicle::preset("q", Preset::QuadX, 2f64.sqrt(), 1.0, props).unwrap();
        // Rotors at (±1, ±1) m: 1 FR(+), 2 RR(−), 3 RL(+), 4 FL(−) (azimuth order).
        let m = Mixing::new(&v);
        let omega = [100.0, 200.0, 300.0, 400.0];
        let d = m.actuators(&omega);
        // y = (1, 1, −1, −1), x = (1, −1, −1, 1), σ = (+, −, +, −).
        let expect = [250.0, 400.0, 0.0, 200.0];
        for (a, b) in d.iter().zip(expect) {
            assert!((a - b).abs() < 1e-9, "{d:?} vs {expect:?}");
        }
        let d2 = m.squared_actuators(&omega);
        assert!((d2[0] - (1e4 + 4e4 + 9e4 + 16e4) / 4.0).abs() < 1e-6);
        // Batch form equals the per-sample form.
        let series: Vec<Vec<f64>> = omega.iter().map(|&w| vec![w, 2.0 * w]).collect();
        let refs: Vec<&[f64]> = series.iter().map(|s| s.as_slice()).collect();
        let mut out = [[0.0; 2]; 4];
        let [a, b, c, e] = &mut out;
        m.mix_into(&refs, true, [a, b, c, e]);
        for (k, row) in out.iter().enumerate() {
            assert!((row[0] - d2[k]).abs() < 1e-6 && (row[1] - 4.0 * d2[k]).abs() < 1e-6);
        }
    }

    #[test]
    fn asymmetric_x_couples_thrust_into_pitch() {
        // Arms of 0.29 m (front) and 0.24 m (rear) at ±45°: Σx_i = √2 (0.29 − 0.24) m,
        // Σy_i = 0, Σσ_i = 0.
        let c = std::f64::consts::FRAC_1_SQRT_2;
        let rotors = [(0.29, 0.29, 1.0), (-0.24, 0.24, -1.0), (-0.24, -0.24, 1.0)]
            .into_iter()
            .chain([(0.29, -0.29, -1.0)])
            .map(|(x, y, spin)| crate::vehicle::Rotor {
                x: x * c,
                y: y * c,
                spin,
            })
            .collect();
        let props = props();
        let v = Vehicle::from_rotors("asym", props, rotors).unwrap();
        let m = Mixing::new(&v);
        // Equal speeds: δt = Ω, δa = 0, δe = Ω Σx_i, δr = 0 (to rounding).
        let d = m.actuators(&[500.0; 4]);
        let sx = 2f64.sqrt() * 0.05;
        assert!((d[0] - 500.0).abs() < 1e-12, "{d:?}");
        assert!(d[1].abs() < 1e-12 && d[3].abs() < 1e-12, "{d:?}");
        assert!((d[2] - 500.0 * sx).abs() < 1e-12, "{d:?}");
        // The rows keep the actual positions (Eq. 20): rotor 2's aileron weight is −y_2.
        assert_eq!(m.row(VirtualActuator::Aileron)[1], -0.24 * c);
    }
}
