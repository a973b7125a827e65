//! The local aerodynamic effects behind the candidate signals: ground effect
//! (Cheeseman–Bennett), wake immersion of rotors downstream of others, and the onset of
//! the vortex-ring state (see the [`Signal`](super::Signal) variants of each).

use super::signals::in_plane_speed;

/// Ground-effect factor g = s/(1 − s), s = (R/(4 z_r))², z_r ≥ R/2 (see
/// [`Signal::GroundEffect`](super::Signal::GroundEffect)).
pub fn ground_effect_factor(rotor_radius: f64, rotor_height: f64) -> f64 {
    let z = rotor_height.max(rotor_radius / 2.0);
    let s = (rotor_radius / (4.0 * z)).powi(2);
    s / (1.0 - s)
}

/// Ground-effect factor of the hub at `hub` under the images of all the vehicle's hubs
/// `hubs` (itself included; see
/// [`Signal::MultirotorGroundEffect`](super::Signal::MultirotorGroundEffect)): each hub
/// as its north and east offset from the CG (m) and its rotor-plane height above ground
/// (m, held here at ≥ R/2).
pub(super) fn multirotor_ground_effect_factor(
    rotor_radius: f64,
    hub: [f64; 3],
    hubs: impl IntoIterator<Item = [f64; 3]>,
) -> f64 {
    let low = rotor_radius / 2.0;
    let [xi, yi, zi] = hub;
    let zi = zi.max(low);
    let s: f64 = hubs
        .into_iter()
        .map(|[xj, yj, zj]| {
            let dz = zi + zj.max(low);
            let (dx, dy) = (xi - xj, yi - yj);
            let d3 = (dx * dx + dy * dy + dz * dz).powf(1.5);
            0.25 * rotor_radius * rotor_radius * dz / d3
        })
        .sum();
    s / (1.0 - s)
}

/// Overlap of rotor `i` with the wakes of the rotors upstream of it at in-plane
/// velocities (`u`, `v`) (m/s), capped at 1 (see
/// [`Signal::WakeImmersion`](super::Signal::WakeImmersion)), into `dst`: 0 at V_h = 0.
/// Computed in blocks of samples, one pass per upstream rotor, so the loops run on vector
/// lanes (under [`crate::util::vectorized`]); the per-sample operations and their order
/// are those of the scalar definition, bit for bit.
pub(super) fn wake_overlaps(
    hubs: &[[f64; 2]],
    i: usize,
    radius: f64,
    u: &[f64],
    v: &[f64],
    dst: &mut [f64],
) {
    crate::util::vectorized(WakeOverlaps {
        hubs,
        i,
        radius,
        u,
        v,
        dst,
    });
}

/// [`wake_overlaps`] as one operation for [`crate::util::vectorized`].
struct WakeOverlaps<'a> {
    hubs: &'a [[f64; 2]],
    i: usize,
    radius: f64,
    u: &'a [f64],
    v: &'a [f64],
    dst: &'a mut [f64],
}

impl pulp::WithSimd for WakeOverlaps<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        const BLOCK: usize = 64;
        let hi = self.hubs[self.i];
        let blocks = self
            .dst
            .chunks_mut(BLOCK)
            .zip(self.u.chunks(BLOCK).zip(self.v.chunks(BLOCK)));
        for (dst, (u, v)) in blocks {
            // Unit vector of the airflow relative to the vehicle (downstream).
            let mut e = [[0.0; BLOCK]; 2];
            for k in 0..dst.len() {
                let vh = in_plane_speed(u[k], v[k]);
                e[0][k] = -u[k] / vh;
                e[1][k] = -v[k] / vh;
                // Where float sums start (`Iterator::sum`).
                dst[k] = -0.0;
            }
            for (j, hj) in self.hubs.iter().enumerate() {
                if j == self.i {
                    continue;
                }
                let d = [hi[0] - hj[0], hi[1] - hj[1]];
                for (k, o) in dst.iter_mut().enumerate() {
                    let along = d[0] * e[0][k] + d[1] * e[1][k];
                    let miss = (d[0] * e[1][k] - d[1] * e[0][k]).abs();
                    *o += if along > 0.0 {
                        (1.0 - miss / (2.0 * self.radius)).max(0.0)
                    } else {
                        0.0
                    };
                }
            }
            for (k, o) in dst.iter_mut().enumerate() {
                let vh = in_plane_speed(u[k], v[k]);
                *o = if vh == 0.0 { 0.0 } else { o.min(1.0) };
            }
        }
    }
}

/// Vortex-ring onset at hub descent speed `descent` (m/s, down +) and in-plane airspeed
/// `vh` (m/s) for hover inflow `nu0` (m/s) (see
/// [`Signal::VortexRing`](super::Signal::VortexRing)).
pub(super) fn vortex_ring_onset(descent: f64, vh: f64, nu0: f64) -> f64 {
    let x = (descent / nu0 - 1.0) / 0.5;
    let y = vh / nu0;
    let exponent = x * x + y * y;
    // exp(−746) is 0 in f64; libm reaches it through its slow underflow path (most
    // samples of a fast flight are far from the vortex-ring state).
    if exponent > 746.0 {
        0.0
    } else {
        crate::util::exp(-exponent)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The overlap of one sample as `Signal::WakeImmersion` defines it, sample by sample.
    fn wake_overlap_of_one_sample(hubs: &[[f64; 2]], i: usize, radius: f64, u: f64, v: f64) -> f64 {
        let vh = in_plane_speed(u, v);
        if vh == 0.0 {
            return 0.0;
        }
        let e = [-u / vh, -v / vh];
        let hi = hubs[i];
        let overlap: f64 = hubs
            .iter()
            .enumerate()
            .filter(|&(j, _)| j != i)
            .map(|(_, hj)| {
                let d = [hi[0] - hj[0], hi[1] - hj[1]];
                let along = d[0] * e[0] + d[1] * e[1];
                let miss = (d[0] * e[1] - d[1] * e[0]).abs();
                if along > 0.0 {
                    (1.0 - miss / (2.0 * radius)).max(0.0)
                } else {
                    0.0
                }
            })
            .sum();
        overlap.min(1.0)
    }

    #[test]
    fn wake_overlaps_in_blocks_equal_the_per_sample_definition_bit_for_bit() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(12);
        // Quad ×, hexa and an irregular layout; radii from touching to far apart.
        let layouts: [&[[f64; 2]]; 3] = [
            &[[0.1, 0.1], [-0.1, 0.1], [-0.1, -0.1], [0.1, -0.1]],
            &[
                [0.2, 0.0],
                [0.1, 0.17],
                [-0.1, 0.17],
                [-0.2, 0.0],
                [-0.1, -0.17],
                [0.1, -0.17],
            ],
            &[[0.3, 0.05], [-0.12, 0.2], [0.0, -0.25]],
        ];
        // Exact axes and diagonals (along = 0 and miss = 0 exactly), rest, tiny, huge.
        let mut uv: Vec<(f64, f64)> = vec![
            (0.0, 0.0),
            (-0.0, 0.0),
            (1.0, 0.0),
            (0.0, -1.0),
            (1.0, 1.0),
            (-3.0, 3.0),
            (1e-300, 0.0),
            (5e-324, -5e-324),
            (1e200, 1e200),
            (-1e-8, 2e-8),
        ];
        uv.extend(
            (0..5000).map(|_| (rng.random_range(-30.0..30.0), rng.random_range(-30.0..30.0))),
        );
        let (u, v): (Vec<f64>, Vec<f64>) = uv.into_iter().unzip();
        for hubs in layouts {
            for radius in [0.05, 0.1, 0.141, 0.3] {
                for i in 0..hubs.len() {
                    let mut dst = vec![f64::NAN; u.len()];
                    wake_overlaps(hubs, i, radius, &u, &v, &mut dst);
                    for k in 0..u.len() {
                        let want = wake_overlap_of_one_sample(hubs, i, radius, u[k], v[k]);
                        assert_eq!(
                            dst[k].to_bits(),
                            want.to_bits(),
                            "rotor {i} at ({}, {})",
                            u[k],
                            v[k]
                        );
                    }
                }
            }
        }
    }
}
