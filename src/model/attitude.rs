//! Signals of the attitude (the body→NED rotation of each sample's quaternion), evaluated
//! sample by sample on vector lanes: the rotation is computed with the same operations in
//! the same order as one sample at a time, so the values are those of the scalar
//! definition bit for bit.

/// Body→NED rotation of the attitude quaternion `quat` (w, x, y, z; normalised here).
#[inline(always)]
fn body_to_ned(quat: [f64; 4]) -> [[f64; 3]; 3] {
    let norm = quat.iter().map(|c| c * c).sum::<f64>().sqrt();
    crate::util::quat_to_matrix(quat.map(|c| c / norm))
}

/// `dst[k] = value(body→NED of sample k, aux[k])` for the samples of the quaternion
/// series `q` (`dst.len()` samples; `aux` another signal of the same samples).
pub(super) fn per_attitude(
    q: &[Vec<f64>; 4],
    aux: &[f64],
    dst: &mut [f64],
    value: impl Fn([[f64; 3]; 3], f64) -> f64,
) {
    let n = dst.len();
    crate::util::vectorized(PerAttitude {
        q: [&q[0][..n], &q[1][..n], &q[2][..n], &q[3][..n]],
        aux: &aux[..n],
        dst,
        value,
    });
}

/// [`per_attitude`] as one operation for [`crate::util::vectorized`].
struct PerAttitude<'a, F> {
    q: [&'a [f64]; 4],
    aux: &'a [f64],
    dst: &'a mut [f64],
    value: F,
}

impl<F: Fn([[f64; 3]; 3], f64) -> f64> pulp::WithSimd for PerAttitude<'_, F> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let Self { q, aux, dst, value } = self;
        let quats = q[0].iter().zip(q[1]).zip(q[2]).zip(q[3]);
        for ((d, &a), (((&w, &x), &y), &z)) in dst.iter_mut().zip(aux).zip(quats) {
            *d = value(body_to_ned([w, x, y, z]), a);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every element of every sample's rotation on vector lanes equals the rotation of
    /// that sample alone, bit for bit (unnormalised quaternions included).
    #[test]
    fn rotations_on_vector_lanes_equal_those_of_single_samples() {
        let n = 37;
        let q: [Vec<f64>; 4] = std::array::from_fn(|c| {
            (0..n)
                .map(|k| ((k * 7 + c * 3) as f64 * 0.37).sin() * (1.0 + c as f64 * 0.1))
                .collect()
        });
        let aux: Vec<f64> = (0..n).map(|k| k as f64 * 0.25 - 3.0).collect();
        for e in 0..9 {
            let mut dst = vec![0.0; n];
            per_attitude(&q, &aux, &mut dst, |m, a| m[e / 3][e % 3] * a);
            for k in 0..n {
                let m = body_to_ned([q[0][k], q[1][k], q[2][k], q[3][k]]);
                let expected = m[e / 3][e % 3] * aux[k];
                assert_eq!(
                    dst[k].to_bits(),
                    expected.to_bits(),
                    "element {e}, sample {k}"
                );
            }
        }
    }
}
