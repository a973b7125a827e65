//! Values of the computed signals of one chunk: virtual actuators and their rates
//! (Eq. 19–21), the per-rotor inflow sums, |u|, |v|, |w|, V_h and its slopes, the rotation
//! and the candidate signals of [`super::local_effects`], from the vehicle constants they
//! need ([`SignalConstants`]).

use super::attitude::per_attitude;
use super::local_effects::{
    ground_effect_factor, multirotor_ground_effect_factor, vortex_ring_onset, wake_overlaps,
};
use super::signals::{Signal, in_plane_speed};
use crate::mixing::{Mixing, mix_row};
use crate::sample::SampleChunk;
use crate::vehicle::Vehicle;

/// The constants of one vehicle that the computed signals use.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct SignalConstants {
    /// Virtual-actuator rows M_ix (Eq. 20).
    mixing: Mixing,
    /// Per-rotor weights of the inflow sums, in [`Signal`] order: y_i², x_i y_i, x_i² (m²),
    /// σ_i y_i, σ_i x_i (m).
    inflow_weights: [Vec<f64>; 5],
    /// Rotor radius R and hub height h, m (ground-effect and wake signals).
    rotor_radius: f64,
    hub_height: f64,
    /// Hub positions (x_i, y_i), m, and hover inflow ν0, m/s (wake and vortex-ring
    /// signals).
    hubs: Vec<[f64; 2]>,
    nu0: f64,
}

impl SignalConstants {
    /// The constants of `vehicle`; inflow weights of magnitude at most `tiny` (m²) are
    /// rounding noise and taken as zero.
    pub(super) fn of(vehicle: &Vehicle, tiny: f64) -> Self {
        let rotors = vehicle.rotors();
        let clean = |w: f64| if w.abs() <= tiny { 0.0 } else { w };
        let inflow_weights = [
            rotors.iter().map(|r| clean(r.y * r.y)).collect(),
            rotors.iter().map(|r| clean(r.x * r.y)).collect(),
            rotors.iter().map(|r| clean(r.x * r.x)).collect(),
            rotors.iter().map(|r| clean(r.spin * r.y)).collect(),
            rotors.iter().map(|r| clean(r.spin * r.x)).collect(),
        ];
        Self {
            mixing: Mixing::new(vehicle),
            inflow_weights,
            rotor_radius: vehicle.props.rotor_radius,
            hub_height: vehicle.props.hub_height,
            hubs: rotors.iter().map(|r| [r.x, r.y]).collect(),
            nu0: vehicle.hover_induced_velocity(),
        }
    }

    /// Values of the computed signal `s` for the samples of `chunk`, into `dst`
    /// (`chunk.len()` values). The chunk carries the signals `s` needs (see
    /// [`super::ModelStructure::check_chunk`]).
    pub(super) fn compute(&self, s: Signal, chunk: &SampleChunk, dst: &mut [f64]) {
        use crate::mixing::VirtualActuator as A;
        use Signal::*;
        let n = chunk.len();
        let rows = [A::Thrust, A::Aileron, A::Elevator, A::Rudder];
        match s {
            U | V | W | P | Q | R | RotorSpeed(_) | RotorAcceleration(_) => {}
            Vh => {
                let (u, v) = (&chunk.velocity[0][..n], &chunk.velocity[1][..n]);
                for ((d, &a), &b) in dst.iter_mut().zip(u).zip(v) {
                    *d = in_plane_speed(a, b);
                }
            }
            Dt | Da | De | Dr => {
                let row = rows[s_index(s, Dt)];
                mix_row(self.mixing.row(row), &chunk.omega, false, dst);
            }
            D2t | D2a | D2e | D2r => {
                let row = rows[s_index(s, D2t)];
                mix_row(self.mixing.row(row), &chunk.omega, true, dst);
            }
            SlowSquaredActuator(band, row) => {
                let rotors = chunk.rotor_count();
                let start = usize::from(band) * rotors;
                let slow = &present(&chunk.omega_squared_slow)[start..start + rotors];
                mix_row(
                    self.mixing.row(rows[usize::from(row) % 4]),
                    slow,
                    false,
                    dst,
                );
            }
            DrDot => {
                let omega_dot = present(&chunk.omega_dot);
                mix_row(self.mixing.row(A::Rudder), omega_dot, false, dst);
            }
            DrDDot => {
                let omega_ddot = present(&chunk.omega_ddot);
                mix_row(self.mixing.row(A::Rudder), omega_ddot, false, dst);
            }
            ActuatorRate(row) => {
                let (row, omega_dot) = (rows[usize::from(row) % 4], present(&chunk.omega_dot));
                mix_row(self.mixing.row(row), omega_dot, false, dst);
            }
            SumY2Omega | SumXYOmega | SumX2Omega | SumSigmaYOmega | SumSigmaXOmega => {
                let w = &self.inflow_weights[s_index(s, SumY2Omega)];
                mix_row(w, &chunk.omega, false, dst);
            }
            AbsU | AbsV | AbsW => {
                let src = &chunk.velocity[s_index(s, AbsU)][..n];
                dst.iter_mut().zip(src).for_each(|(d, x)| *d = x.abs());
            }
            RotorSpeedSquared(i) => {
                let src = &chunk.omega[usize::from(i)][..n];
                dst.iter_mut().zip(src).for_each(|(d, x)| *d = x * x);
            }
            SquaredActuatorRate(row) => {
                dst.fill(0.0);
                let weights = self.mixing.row(rows[usize::from(row) % 4]);
                let omega_dot = present(&chunk.omega_dot);
                for ((&m, w), wd) in weights.iter().zip(&chunk.omega).zip(omega_dot) {
                    let pairs = w[..n].iter().zip(&wd[..n]);
                    dst.iter_mut()
                        .zip(pairs)
                        .for_each(|(d, (a, b))| *d += 2.0 * m * a * b);
                }
            }
            GroundEffect => {
                let (r, h) = (self.rotor_radius, self.hub_height);
                let src = &present(&chunk.height)[..n];
                dst.iter_mut()
                    .zip(src)
                    .for_each(|(d, z)| *d = ground_effect_factor(r, z + h));
            }
            RotorGroundEffect(i) => {
                let [x, y] = self.hubs[usize::from(i)];
                let (r, h) = (self.rotor_radius, self.hub_height);
                let (height, attitude) = (present(&chunk.height), present(&chunk.attitude));
                per_attitude(attitude, height, dst, |m, z| {
                    // Third row of body→NED: the down component of a body vector.
                    let down = m[2];
                    let hub_down = down[0] * x + down[1] * y - down[2] * h;
                    ground_effect_factor(r, z - hub_down)
                });
            }
            MultirotorGroundEffect(i) => {
                let (r, h) = (self.rotor_radius, self.hub_height);
                let (height, attitude) = (present(&chunk.height), present(&chunk.attitude));
                per_attitude(attitude, height, dst, |m, z| {
                    // Body→NED of a hub's offset (x_j, y_j, −h): north, east, and the
                    // height above ground (the CG height less the down part).
                    let ned = |&[x, y]: &[f64; 2]| {
                        let [n, e, d] = m.map(|row| row[0] * x + row[1] * y - row[2] * h);
                        [n, e, z - d]
                    };
                    let hub = ned(&self.hubs[usize::from(i)]);
                    multirotor_ground_effect_factor(r, hub, self.hubs.iter().map(ned))
                });
            }
            WakeImmersion(i) => {
                let (u, v) = (&chunk.velocity[0][..n], &chunk.velocity[1][..n]);
                let (r, nu0) = (self.rotor_radius, self.nu0);
                wake_overlaps(&self.hubs, usize::from(i), r, u, v, dst);
                for (k, d) in dst.iter_mut().enumerate() {
                    let vh2 = u[k] * u[k] + v[k] * v[k];
                    *d *= vh2 / (vh2 + nu0 * nu0);
                }
            }
            DownstreamAdvance(i, backward) => {
                let x = self.hubs[usize::from(i)][0];
                let sign = if backward == 0 { 1.0 } else { -1.0 };
                let (u, omega) = (&chunk.velocity[0][..n], &chunk.omega[usize::from(i)][..n]);
                let r = self.rotor_radius;
                for ((d, &u), &w) in dst.iter_mut().zip(u).zip(omega) {
                    let along = sign * u;
                    *d = if sign * x < 0.0 && along > 0.0 && w > 0.0 {
                        along / (w * r)
                    } else {
                        0.0
                    };
                }
            }
            Airspeed => {
                let [u, v, w] = &chunk.velocity;
                for (k, d) in dst.iter_mut().enumerate() {
                    *d = (u[k] * u[k] + v[k] * v[k] + w[k] * w[k]).sqrt();
                }
            }
            WakeAdvance(i) => {
                let (u, v) = (&chunk.velocity[0][..n], &chunk.velocity[1][..n]);
                let omega = &chunk.omega[usize::from(i)][..n];
                let r = self.rotor_radius;
                wake_overlaps(&self.hubs, usize::from(i), r, u, v, dst);
                for (k, d) in dst.iter_mut().enumerate() {
                    let vh = in_plane_speed(u[k], v[k]);
                    *d *= if omega[k] > 0.0 {
                        vh / (omega[k] * r)
                    } else {
                        0.0
                    };
                }
            }
            UOverVh | VOverVh => {
                let (u, v) = (&chunk.velocity[0][..n], &chunk.velocity[1][..n]);
                let along = if s == UOverVh { u } else { v };
                for (k, d) in dst.iter_mut().enumerate() {
                    let vh = in_plane_speed(u[k], v[k]);
                    *d = if vh > 0.0 { along[k] / vh } else { 0.0 };
                }
            }
            NedToBody(e) => {
                let (k, j) = (usize::from(e) / 3, usize::from(e) % 3);
                let attitude = present(&chunk.attitude);
                // The NED→body element (k, j) is body→NED's (j, k).
                per_attitude(attitude, &attitude[0], dst, |m, _| m[j][k]);
            }
            VortexRing(i) => {
                let [x, y] = self.hubs[usize::from(i)];
                let (u, v, w) = (
                    &chunk.velocity[0][..n],
                    &chunk.velocity[1][..n],
                    &chunk.velocity[2][..n],
                );
                let (p, q) = (&chunk.rates[0][..n], &chunk.rates[1][..n]);
                for (k, d) in dst.iter_mut().enumerate() {
                    let descent = w[k] + p[k] * y - q[k] * x;
                    *d = vortex_ring_onset(descent, in_plane_speed(u[k], v[k]), self.nu0);
                }
            }
        }
    }
}

/// The values of signal `s` for the `n` samples of `chunk`; computed signals live at
/// `offset` in `signals`.
pub(super) fn signal_slice<'a>(
    s: Signal,
    chunk: &'a SampleChunk,
    signals: &'a [f64],
    offset: usize,
    n: usize,
) -> &'a [f64] {
    use Signal::*;
    match s {
        U => &chunk.velocity[0][..n],
        V => &chunk.velocity[1][..n],
        W => &chunk.velocity[2][..n],
        P => &chunk.rates[0][..n],
        Q => &chunk.rates[1][..n],
        R => &chunk.rates[2][..n],
        RotorSpeed(i) => &chunk.omega[usize::from(i)][..n],
        RotorAcceleration(i) => &present(&chunk.omega_dot)[usize::from(i)][..n],
        _ => &signals[offset..offset + n],
    }
}

/// Position of a fieldless signal in its block of consecutive variants starting at
/// `first` (e.g. δa in δt, δa, δe, δr).
fn s_index(s: Signal, first: Signal) -> usize {
    let order = [
        Signal::Dt,
        Signal::Da,
        Signal::De,
        Signal::Dr,
        Signal::D2t,
        Signal::D2a,
        Signal::D2e,
        Signal::D2r,
        Signal::SumY2Omega,
        Signal::SumXYOmega,
        Signal::SumX2Omega,
        Signal::SumSigmaYOmega,
        Signal::SumSigmaXOmega,
        Signal::AbsU,
        Signal::AbsV,
        Signal::AbsW,
    ];
    let at = |x| order.iter().position(|&o| o == x).expect("signal in block");
    at(s) - at(first)
}

/// The optional signal of a chunk that a computed signal needs, present since
/// [`super::ModelStructure::check_chunk`] passed the chunk.
fn present<T>(signal: &Option<T>) -> &T {
    signal
        .as_ref()
        .expect("a signal the structure needs (checked by `check_chunk`)")
}

#[cfg(test)]
mod tests {
    use crate::model::{
        Column, ModelError, ModelOptions, ModelStructure, ParamId, Parameter, Signal, Workspace,
        term,
    };
    use crate::sample::{Axis, Sample, SampleChunk};

    #[test]
    fn candidate_signals_evaluate_as_documented() {
        use Signal::*;
        let v = crate::model::test_quad();
        let mut s = ModelStructure::eq22(&v, ModelOptions::default());
        let extra = |axis, label: &str, terms| Column {
            axis,
            param: ParamId::default(),
            label: label.into(),
            terms,
        };
        let x = s.add_parameter(
            Parameter {
                name: "x".into(),
                unit: "-".into(),
            },
            vec![
                extra(Axis::Fx, "u|u|", vec![term(1.0, &[U, AbsU])]),
                extra(Axis::Fz, "W3^2", vec![term(2.0, &[RotorSpeedSquared(2)])]),
                extra(
                    Axis::My,
                    "d2e_dot",
                    vec![term(1.0, &[SquaredActuatorRate(2)])],
                ),
                extra(
                    Axis::Mz,
                    "g*W1_dot",
                    vec![term(1.0, &[GroundEffect, RotorAcceleration(0)])],
                ),
            ],
        );
        let sample = Sample {
            velocity: [-3.0, 1.0, 0.5],
            omega: vec![100.0, 200.0, 300.0, 400.0],
            omega_dot: vec![10.0, 20.0, 30.0, 40.0],
            height: Some(0.1),
            ..Sample::default()
        };
        let mut chunk = SampleChunk::with_capacity(4, 1, true);
        chunk.push(&sample);
        let mut ws = Workspace::default();
        s.assemble(&chunk, &mut ws).unwrap();
        let value = |label: &str| {
            let j = (0..s.columns.len())
                .find(|&j| s.columns[j].param == x && s.columns[j].label == label)
                .unwrap();
            ws.column(j)[0]
        };
        assert_eq!(value("u|u|"), -9.0);
        assert_eq!(value("W3^2"), 2.0 * 300.0 * 300.0);
        // δ̇²e = Σ x_i 2 Ω_i Ω̇_i, x = ℓ/√2 (1, −1, −1, 1).
        let arm = 0.25 / 2f64.sqrt();
        let expect = arm * 2.0 * (100.0 * 10.0 - 200.0 * 20.0 - 300.0 * 30.0 + 400.0 * 40.0);
        assert!((value("d2e_dot") - expect).abs() < 1e-9 * expect.abs());
        // Rotor plane 0.15 m up, R = 0.1: s = (0.1/0.6)² = 1/36, g = s/(1 − s) = 1/35.
        assert!((value("g*W1_dot") - 10.0 / 35.0).abs() < 1e-12);
        // Wake and vortex-ring onset: rear rotors sit in the front rotors' wakes in
        // forward flight; descent at ν0 in hover is the centre of the vortex-ring bump.
        let nu0 = v.hover_induced_velocity();
        let fwd = Sample {
            velocity: [10.0, 0.0, nu0],
            omega: vec![100.0; 4],
            omega_dot: vec![0.0; 4],
            height: Some(1.0),
            ..Sample::default()
        };
        let mut c2 = SampleChunk::with_capacity(4, 1, true);
        c2.push(&fwd);
        let y = s.add_parameter(
            Parameter {
                name: "y".into(),
                unit: "-".into(),
            },
            vec![
                extra(Axis::Fz, "wake1", vec![term(1.0, &[WakeImmersion(0)])]),
                extra(Axis::Fz, "wake2", vec![term(1.0, &[WakeImmersion(1)])]),
                extra(Axis::Fz, "vrs1", vec![term(1.0, &[VortexRing(0)])]),
            ],
        );
        s.assemble(&c2, &mut ws).unwrap();
        let col = |label: &str| {
            let j = (0..s.columns.len())
                .find(|&j| s.columns[j].param == y && s.columns[j].label == label)
                .unwrap();
            ws.column(j)[0]
        };
        assert_eq!(col("wake1"), 0.0, "front-right rotor is upstream");
        assert!((col("wake2") - 100.0 / (100.0 + nu0 * nu0)).abs() < 1e-12);
        let vrs = (-(10.0 / nu0).powi(2)).exp();
        assert!((col("vrs1") - vrs).abs() < 1e-12);
        // Without a height signal the ground-effect column cannot be built.
        let mut no_height = chunk.clone();
        no_height.height = None;
        assert_eq!(
            s.assemble(&no_height, &mut ws),
            Err(ModelError::MissingHeight)
        );
    }
}
