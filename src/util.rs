//! Small helpers shared across modules: vector algebra, value ranges, quaternion rotation
//! and atomic file writes, each written once.

use std::io::Write;
use std::path::Path;

/// Smallest and largest of `values`, NaN ignored (`f64::min`/`max`); (∞, −∞) when none
/// is left. A zero extremum is +0 (`f64::min`/`max` leave the sign of a ±0 tie to the
/// order of the values; +0 makes the range a function of the set of values).
pub fn range_of(values: impl IntoIterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .into_iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        });
    (positive_zero(lo), positive_zero(hi))
}

/// `x`, with −0 made +0.
fn positive_zero(x: f64) -> f64 {
    x + 0.0
}

/// [`range_of`] of a slice, the same values at vector speed (under `vectorized`):
/// running minima and maxima in vector lanes, whose min/max skip NaN as `f64::min`/`max`
/// do (a sequential fold waits on each comparison). Every extremum is one value whatever
/// the order, a zero one once its sign is made +0.
pub fn range_of_slice(values: &[f64]) -> (f64, f64) {
    vectorized(RangeOf(values))
}

/// [`range_of_slice`] as one operation for [`vectorized`].
struct RangeOf<'a>(&'a [f64]);

impl pulp::WithSimd for RangeOf<'_> {
    type Output = (f64, f64);

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, simd: S) -> (f64, f64) {
        let (lanes, tail) = S::as_simd_f64s(self.0);
        // Two accumulators each: a min/max waits on the one before it.
        let mut lo = [simd.splat_f64s(f64::INFINITY); 2];
        let mut hi = [simd.splat_f64s(f64::NEG_INFINITY); 2];
        let (pairs, last) = lanes.as_chunks::<2>();
        for pair in pairs {
            for k in 0..2 {
                // x86's min/max return the second operand when the first is NaN.
                lo[k] = simd.min_f64s(pair[k], lo[k]);
                hi[k] = simd.max_f64s(pair[k], hi[k]);
            }
        }
        for &x in last {
            lo[0] = simd.min_f64s(x, lo[0]);
            hi[0] = simd.max_f64s(x, hi[0]);
        }
        let mut min = simd.reduce_min_f64s(simd.min_f64s(lo[0], lo[1]));
        let mut max = simd.reduce_max_f64s(simd.max_f64s(hi[0], hi[1]));
        for &x in tail {
            min = min.min(x);
            max = max.max(x);
        }
        (positive_zero(min), positive_zero(max))
    }
}

/// True when every value is finite (neither NaN nor ±∞), without branching per value.
pub fn all_finite(values: &[f64]) -> bool {
    values.iter().fold(true, |ok, x| ok & x.is_finite())
}

/// Dot product Σ aᵢbᵢ over the common length of `a` and `b`, in eight partial sums
/// (vectorisable: a single running sum waits on each addition's latency) added in a fixed
/// order, so the value depends on the inputs alone. Below eight terms, a plain running sum.
#[inline(always)]
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let split = n / 8 * 8;
    let tail: f64 = a[split..n]
        .iter()
        .zip(&b[split..n])
        .map(|(x, y)| x * y)
        .sum();
    if split == 0 {
        return tail;
    }
    // Partial sums 0–3 and 4–7 as two arrays of four, each one AVX2 register. The
    // combination below is hidden from the optimiser: seeing it, the compiler laid the
    // sums out in the order it adds them, in two-lane registers and shuffles per step.
    let (mut lo, mut hi) = ([0.0f64; 4], [0.0f64; 4]);
    for (x, y) in a[..split].chunks_exact(8).zip(b[..split].chunks_exact(8)) {
        for k in 0..4 {
            lo[k] += x[k] * y[k];
            hi[k] += x[4 + k] * y[4 + k];
        }
    }
    let (lo, hi) = std::hint::black_box((lo, hi));
    let pair = |k: usize| lo[k] + hi[k];
    let head = (pair(0) + pair(1)) + (pair(2) + pair(3));
    head + tail
}

/// Cross product a × b.
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Rotation matrix of a unit quaternion `[w, x, y, z]` (body → world).
pub fn quat_to_matrix(q: [f64; 4]) -> [[f64; 3]; 3] {
    let [w, x, y, z] = q;
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

/// Writes `bytes` to `path` whole or not at all: through a hidden temporary sibling
/// file, flushed to disk, then renamed over `path` (the temporary file is removed on
/// failure).
pub fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    let name = path
        .file_name()
        .ok_or_else(|| std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a file path"))?;
    let tmp = dir.join(format!(
        ".{}.tmp{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    result.inspect_err(|_| {
        let _ = std::fs::remove_file(&tmp);
    })
}

/// `f` of every item, in item order, on up to `threads` threads: free threads take the
/// next item in turn, so the result does not depend on `threads` (nor on scheduling)
/// when `f` is a function of its item alone.
pub(crate) fn map_on_threads<T: Sync, R: Send>(
    items: &[T],
    threads: usize,
    f: impl Fn(&T) -> R + Sync,
) -> Vec<R> {
    let workers = threads.clamp(1, items.len().max(1));
    if workers == 1 {
        return items.iter().map(f).collect();
    }
    let next = std::sync::atomic::AtomicUsize::new(0);
    let slots: Vec<std::sync::Mutex<Option<R>>> =
        items.iter().map(|_| Default::default()).collect();
    let work = || {
        loop {
            let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            let Some(item) = items.get(i) else {
                break;
            };
            let r = f(item);
            *slots[i].lock().unwrap_or_else(|e| e.into_inner()) = Some(r);
        }
    };
    std::thread::scope(|scope| {
        for _ in 1..workers {
            scope.spawn(work);
        }
        work();
    });
    // A worker that panicked re-raised its panic at the end of the scope, so every slot
    // holds its result here.
    slots
        .into_iter()
        .filter_map(|s| s.into_inner().unwrap_or_else(|e| e.into_inner()))
        .collect()
}

/// `op`, compiled for AVX2 and FMA where the CPU has them (pulp's runtime dispatch, as
/// faer's own kernels use): the vector loops `op.with_simd` inlines (mark them
/// `#[inline(always)]`) run four lanes wide instead of two. The values are the same bit
/// for bit: Rust never fuses a product and a sum into an FMA, and no loop's order of
/// operations depends on the lane count.
pub(crate) fn vectorized<Op: pulp::WithSimd>(op: Op) -> Op::Output {
    #[cfg(target_arch = "x86_64")]
    if let Some(simd) = pulp::x86::V3::try_new() {
        return pulp::Simd::vectorize(simd, op);
    }
    op.with_simd(pulp::Scalar)
}

/// e^x, libm's value bit for bit, with the upper halves of the vector registers cleared
/// first where the CPU has AVX (`vzeroupper`). glibc's `exp` opens with legacy-SSE
/// instructions; called while the upper register state is dirty (most likely from glibc's
/// AVX-512 `memmove`, which writes zmm16–31) each call stalls on an SSE/AVX state
/// transition: measured ~130 ns a call instead of ~6 ns on this project's 2-core Xeon VMs,
/// 10 % of a diagnosed fit (docs/benchmarks.md, "libm's `exp` unstalled").
pub(crate) fn exp(x: f64) -> f64 {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the CPU has AVX, the only requirement of `clear_upper_registers`.
        unsafe { clear_upper_registers() };
    }
    x.exp()
}

/// `vzeroupper`: zeroes bits 128 and up of the vector registers. It is never inlined into
/// code without AVX, and the x86-64 calling convention lets any call clobber those bits,
/// so no caller keeps a value there across it.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
fn clear_upper_registers() {
    std::arch::x86_64::_mm256_zeroupper();
}

/// P(X > `x`) of the distribution `d` for a statistic that may come out NaN or infinite
/// from degenerate data: 1 (no evidence) for NaN or `x` ≤ 0, 0 for +∞. statrs' F and
/// χ² survival functions panic on a NaN argument (the regularised beta's range check).
pub(crate) fn survival(d: &impl statrs::distribution::ContinuousCDF<f64, f64>, x: f64) -> f64 {
    if x.is_nan() || x <= 0.0 {
        1.0
    } else if x == f64::INFINITY {
        0.0
    } else {
        d.sf(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A NaN or infinite statistic gives a P-value instead of statrs' panic (a NaN F
    /// reached the FSOA on an independent-simulator response-surface set).
    #[test]
    fn survival_of_degenerate_statistics_is_defined() {
        let f = statrs::distribution::FisherSnedecor::new(1.0, 100.0).unwrap();
        assert_eq!(survival(&f, f64::NAN), 1.0);
        assert_eq!(survival(&f, -1.0), 1.0);
        assert_eq!(survival(&f, f64::INFINITY), 0.0);
        // An ordinary value as statrs gives it: F(1, 100) at 3.936 is its 95 % point.
        assert!((survival(&f, 3.936) - 0.05).abs() < 1e-3);
    }

    /// The lane-wise range, in the AVX2 and the baseline code, equals the sequential fold
    /// bit for bit (a zero extremum +0 in both) on every length 0–40 and mixes of ±0, NaN, ±∞ and ordinary values.
    #[test]
    fn range_of_slice_equals_the_sequential_fold() {
        let pool = [
            0.0,
            -0.0,
            1.5,
            -2.25,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            3e-310,
        ];
        let mut state = 12345u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1);
            (state >> 33) as usize
        };
        let mut zero_extremum = 0;
        for case in 0..4000 {
            let len = case % 41;
            let v: Vec<f64> = (0..len)
                .map(|_| match next() % 4 {
                    0 => (next() % 1000) as f64 / 7.0 - 70.0,
                    _ => pool[next() % pool.len()],
                })
                .collect();
            let (a, b) = (range_of_slice(&v), range_of(v.iter().copied()));
            let scalar = pulp::WithSimd::with_simd(RangeOf(&v), pulp::Scalar);
            for (got, code) in [(a, "vector"), (scalar, "baseline")] {
                assert_eq!(
                    (got.0.to_bits(), got.1.to_bits()),
                    (b.0.to_bits(), b.1.to_bits()),
                    "{code} code, {v:?}"
                );
            }
            if b.0 == 0.0 || b.1 == 0.0 {
                zero_extremum += 1;
                assert!(
                    b.0.to_bits() != (-0.0f64).to_bits() && b.1.to_bits() != (-0.0f64).to_bits()
                );
            }
            assert_eq!(all_finite(&v), v.iter().all(|x| x.is_finite()));
        }
        assert!(
            zero_extremum > 100,
            "±0 ties are exercised: {zero_extremum}"
        );
    }

    #[test]
    fn dot_is_the_running_sum_below_eight_terms_and_exact_on_integers() {
        let a: Vec<f64> = (0..37).map(|i| (i as f64 * 0.37).sin()).collect();
        let b: Vec<f64> = (0..37).map(|i| (i as f64 * 1.3).cos()).collect();
        for n in 0..a.len() {
            let running: f64 = a[..n].iter().zip(&b[..n]).map(|(x, y)| x * y).sum();
            if n < 8 {
                // The same additions in the same order (mixing and simulator values).
                assert_eq!(
                    dot(&a[..n], &b[..n]).to_bits(),
                    running.to_bits(),
                    "n = {n}"
                );
            } else {
                // Another summation order: rounding-level difference only.
                assert!((dot(&a[..n], &b[..n]) - running).abs() <= 1e-14, "n = {n}");
            }
            // Small integers: every product and partial sum is exact in f64.
            let ints: Vec<f64> = (0..n).map(|i| (i % 7) as f64 - 3.0).collect();
            let exact: i64 = (0..n as i64).map(|i| (i % 7 - 3) * (i % 7 - 3)).sum();
            assert_eq!(dot(&ints, &ints), exact as f64, "n = {n}");
        }
        // The common length of unequal slices.
        assert_eq!(dot(&[1.0; 20], &[2.0; 11]), 22.0);
    }

    #[test]
    fn exp_returns_libms_value_bit_for_bit() {
        // Normal, subnormal, zero and overflowing results and the special values: the
        // register clearing must not change a bit of any of them.
        let mut xs = vec![
            0.0, -0.0, 1.0, -1.0, 709.7, 709.8, -708.0, -740.0, -746.0, -1e9,
        ];
        xs.extend([
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MIN_POSITIVE,
        ]);
        xs.extend((0..2000).map(|i| -40.0 + i as f64 * 0.0437));
        for x in xs {
            assert_eq!(exp(x).to_bits(), x.exp().to_bits(), "exp({x})");
        }
    }

    #[test]
    fn mapping_on_threads_keeps_item_order_for_any_thread_count() {
        let items: Vec<u64> = (0..1000).collect();
        // Uneven work, so threads finish items out of order.
        let f = |&x: &u64| (0..(x % 7) * 1000).fold(x, |a, b| a.wrapping_mul(31).wrapping_add(b));
        let serial: Vec<u64> = items.iter().map(f).collect();
        for threads in [0, 1, 2, 3, 8, 2000] {
            assert_eq!(
                map_on_threads(&items, threads, f),
                serial,
                "{threads} threads"
            );
        }
        assert!(map_on_threads(&[] as &[u64], 4, f).is_empty());
    }
}
