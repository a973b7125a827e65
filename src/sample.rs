//! The sample stream every reader and the simulator produce and the estimator consumes:
//! the data contract (`docs/data-contract.md`) in structure-of-arrays chunks.
//!
//! Units are SI, axes body FRD: velocity u, v, w (m/s, air-relative), rates p, q, r
//! (rad/s), rotor speeds Ω_i (rad/s, positive), rotor accelerations Ω̇_i (rad/s²),
//! force F (N) and moment M (N m) on the airframe, gravity excluded.

/// Number of samples per chunk in streaming passes: one place that decides it.
/// 1024 samples × ~40 regressor columns × 8 bytes stays inside a core's L2 cache.
pub const CHUNK_SAMPLES: usize = 1024;

/// Cut-offs (−3 dB, Hz) of the slow rotor-thrust signals
/// ([`SampleChunk::omega_squared_slow`], filled by the fit pipeline): each is one form of
/// the trim moment, from below to about the bandwidth of a small multirotor's attitude
/// loop.
pub const TRIM_BANDS_HZ: [f64; 3] = [0.5, 1.0, 2.0];

/// The six force and moment axes of Eq. 22, in output order.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
pub enum Axis {
    /// Body x force F_x, N (Eq. 22a).
    Fx = 0,
    /// Body y force F_y, N (Eq. 22b).
    Fy = 1,
    /// Body z force F_z, N (Eq. 22c).
    Fz = 2,
    /// Rolling moment M_x, N m (Eq. 22d).
    Mx = 3,
    /// Pitching moment M_y, N m (Eq. 22e).
    My = 4,
    /// Yawing moment M_z, N m (Eq. 22f).
    Mz = 5,
}

impl Axis {
    /// All six axes in output order.
    pub const ALL: [Axis; 6] = [Axis::Fx, Axis::Fy, Axis::Fz, Axis::Mx, Axis::My, Axis::Mz];

    /// Short name as used in reports ("Fx" … "Mz").
    pub fn name(self) -> &'static str {
        ["Fx", "Fy", "Fz", "Mx", "My", "Mz"][self as usize]
    }

    /// Unit of the axis ("N" or "N m").
    pub fn unit(self) -> &'static str {
        if (self as usize) < 3 { "N" } else { "N m" }
    }
}

impl std::fmt::Display for Axis {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A chunk of consecutive samples, one vector per signal (structure of arrays).
///
/// Every vector holds `len()` values. An optional signal is `None` when the data do not
/// carry it, and otherwise holds `len()` values like the others.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SampleChunk {
    /// Time, s.
    pub t: Vec<f64>,
    /// Air-relative velocity u, v, w in body axes, m/s.
    pub velocity: [Vec<f64>; 3],
    /// Body rates p, q, r, rad/s.
    pub rates: [Vec<f64>; 3],
    /// Rotor speeds Ω_i, rad/s: one vector per rotor, numbered as in the vehicle.
    pub omega: Vec<Vec<f64>>,
    /// Rotor accelerations Ω̇_i, rad/s², one vector per rotor; `None` when not available.
    pub omega_dot: Option<Vec<Vec<f64>>>,
    /// Rates of the rotor accelerations Ω̈_i, rad/s³, one vector per rotor: derived from
    /// Ω̇ by the fit pipeline (`io`'s `rotor_jerk`), never read from a
    /// log; `None` when not derived.
    pub omega_ddot: Option<Vec<Vec<f64>>>,
    /// Slow part of each rotor's Ω_i², rad²/s²: its zero-phase low-pass at each cut-off
    /// of [`crate::TRIM_BANDS_HZ`], band-major (band b, rotor i at `b · N + i`).
    /// Derived by the fit pipeline for the diagnosis's trim-moment candidates, never read
    /// from a log; `None` when not derived.
    pub omega_squared_slow: Option<Vec<Vec<f64>>>,
    /// Measured force F_x, F_y, F_z (N) and moment M_x, M_y, M_z (N m), body axes,
    /// gravity excluded, in [`Axis`] order.
    pub wrench: [Vec<f64>; 6],
    /// CG height above ground, m (up); `None` when not logged.
    pub height: Option<Vec<f64>>,
    /// Attitude quaternion body→NED `[qw, qx, qy, qz]` (unit norm), one vector per
    /// component; `None` when not logged.
    pub attitude: Option<[Vec<f64>; 4]>,
}

/// A chunk whose signal vectors do not all hold one value per time stamp: the first
/// such signal and what is wrong ([`SampleChunk::check_lengths`]).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ChunkShapeError {
    /// The signal, as the data contract names it (e.g. `omega3`, `qw`, `omega_dot`).
    pub signal: String,
    /// What is wrong, e.g. `1 values for 2 time stamps`.
    pub problem: String,
}

impl SampleChunk {
    /// An empty chunk for `rotors` rotors, with room for `capacity` samples, carrying
    /// rotor accelerations when `with_omega_dot` (and no other optional signal).
    pub fn with_capacity(rotors: usize, capacity: usize, with_omega_dot: bool) -> Self {
        let v = || Vec::with_capacity(capacity);
        Self {
            t: v(),
            velocity: [v(), v(), v()],
            rates: [v(), v(), v()],
            omega: (0..rotors).map(|_| v()).collect(),
            omega_dot: with_omega_dot.then(|| (0..rotors).map(|_| v()).collect()),
            omega_ddot: None,
            omega_squared_slow: None,
            wrench: [v(), v(), v(), v(), v(), v()],
            height: None,
            attitude: None,
        }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// True when the chunk holds no sample.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Number of rotors.
    pub fn rotor_count(&self) -> usize {
        self.omega.len()
    }

    /// Rotor count and optional signals of the chunk.
    pub fn signals(&self) -> Signals {
        Signals {
            rotors: self.rotor_count(),
            omega_dot: self.omega_dot.is_some(),
            omega_ddot: self.omega_ddot.is_some(),
            omega_squared_slow: self.omega_squared_slow.is_some(),
            height: self.height.is_some(),
            attitude: self.attitude.is_some(),
        }
    }

    /// Removes all samples, keeping the allocations and the optional signals carried
    /// (each stays `Some`, empty).
    pub fn clear(&mut self) {
        self.t.clear();
        self.velocity.iter_mut().for_each(Vec::clear);
        self.rates.iter_mut().for_each(Vec::clear);
        self.omega.iter_mut().for_each(Vec::clear);
        self.omega_dot.iter_mut().flatten().for_each(Vec::clear);
        self.omega_ddot.iter_mut().flatten().for_each(Vec::clear);
        self.omega_squared_slow
            .iter_mut()
            .flatten()
            .for_each(Vec::clear);
        self.wrench.iter_mut().for_each(Vec::clear);
        self.height.iter_mut().for_each(Vec::clear);
        self.attitude.iter_mut().flatten().for_each(Vec::clear);
    }

    /// Appends one sample. `omega_dot` must be given exactly when the chunk carries it;
    /// `height` and `attitude` exactly when it carries them or holds no sample yet (the
    /// first sample that gives one makes the chunk carry it).
    pub fn push(&mut self, s: &Sample) {
        self.t.push(s.t);
        for k in 0..3 {
            self.velocity[k].push(s.velocity[k]);
            self.rates[k].push(s.rates[k]);
        }
        for (dst, &w) in self.omega.iter_mut().zip(&s.omega) {
            dst.push(w);
        }
        if let Some(omega_dot) = &mut self.omega_dot {
            for (dst, &w) in omega_dot.iter_mut().zip(&s.omega_dot) {
                dst.push(w);
            }
        }
        for (dst, &f) in self.wrench.iter_mut().zip(&s.wrench) {
            dst.push(f);
        }
        if let Some(h) = s.height {
            self.height.get_or_insert_with(Vec::new).push(h);
        }
        if let Some(q) = s.attitude {
            let dst = self.attitude.get_or_insert_with(Default::default);
            for (dst, &c) in dst.iter_mut().zip(&q) {
                dst.push(c);
            }
        }
    }

    /// Appends samples `range` of `src` (same rotor count and optional signals).
    pub fn extend_from(&mut self, src: &SampleChunk, range: std::ops::Range<usize>) {
        self.append_each(src, |dst, src| match src.get(range.clone()) {
            // A sweep's samples come one or two at a time: a call of `memmove` per
            // signal and sample cost more than the copy.
            Some(s) if s.len() <= 4 => s.iter().for_each(|&x| dst.push(x)),
            Some(s) => dst.extend_from_slice(s),
            None => {}
        });
    }

    /// Appends the samples of `src` at the indices `rows`, in that order (same rotor count
    /// and optional signals): one gather per signal, where [`SampleChunk::extend_from`]
    /// per run of a few samples (a sweep's alternating hold-out) cost a call per signal
    /// and run.
    pub fn extend_from_rows(&mut self, src: &SampleChunk, rows: &[usize]) {
        self.append_each(src, |dst, src| {
            if !src.is_empty() {
                dst.extend(rows.iter().map(|&i| src[i]));
            }
        });
    }

    /// `append(dst, src)` for every series of `src` and the same series of this chunk
    /// (the rotor series of each kind made as many as `src` has first, none when it
    /// carries none; a height or attitude `src` carries added empty when this chunk does
    /// not carry it).
    fn append_each(&mut self, src: &SampleChunk, mut append: impl FnMut(&mut Vec<f64>, &[f64])) {
        append(&mut self.t, &src.t);
        for k in 0..3 {
            append(&mut self.velocity[k], &src.velocity[k]);
            append(&mut self.rates[k], &src.rates[k]);
        }
        let mut rotors = |dst: &mut Vec<Vec<f64>>, src: &[Vec<f64>]| {
            dst.resize_with(src.len(), Vec::new);
            for (d, s) in dst.iter_mut().zip(src) {
                append(d, s);
            }
        };
        rotors(&mut self.omega, &src.omega);
        for (dst, src) in [
            (&mut self.omega_dot, &src.omega_dot),
            (&mut self.omega_ddot, &src.omega_ddot),
            (&mut self.omega_squared_slow, &src.omega_squared_slow),
        ] {
            match src {
                Some(src) => rotors(dst.get_or_insert_with(Vec::new), src),
                None => *dst = None,
            }
        }
        for (d, s) in self.wrench.iter_mut().zip(&src.wrench) {
            append(d, s);
        }
        if let Some(s) = &src.height {
            append(self.height.get_or_insert_with(Vec::new), s);
        }
        if let Some(src) = &src.attitude {
            let dst = self.attitude.get_or_insert_with(Default::default);
            for (d, s) in dst.iter_mut().zip(src) {
                append(d, s);
            }
        }
    }

    /// Copies sample `k` out of the chunk (without Ω̈, which [`Sample`] does not carry).
    pub fn sample(&self, k: usize) -> Sample {
        Sample {
            t: self.t[k],
            velocity: self.velocity.each_ref().map(|v| v[k]),
            rates: self.rates.each_ref().map(|v| v[k]),
            omega: self.omega.iter().map(|v| v[k]).collect(),
            omega_dot: self.omega_dot.iter().flatten().map(|v| v[k]).collect(),
            wrench: self.wrench.each_ref().map(|v| v[k]),
            height: self.height.as_ref().map(|h| h[k]),
            attitude: self.attitude.as_ref().map(|q| q.each_ref().map(|v| v[k])),
        }
    }

    /// Checks that every signal vector holds [`Self::len`] values (and an optional rotor
    /// signal one vector per rotor); else names the first signal that does not and what
    /// is wrong.
    pub(crate) fn check_lengths(&self) -> Result<(), ChunkShapeError> {
        let n = self.len();
        let shape = |signal: String, problem: String| ChunkShapeError { signal, problem };
        let mut required: Vec<(String, usize)> = Vec::new();
        for (k, name) in ["u", "v", "w"].iter().enumerate() {
            required.push((name.to_string(), self.velocity[k].len()));
        }
        for (k, name) in ["p", "q", "r"].iter().enumerate() {
            required.push((name.to_string(), self.rates[k].len()));
        }
        for (k, name) in ["fx", "fy", "fz", "mx", "my", "mz"].iter().enumerate() {
            required.push((name.to_string(), self.wrench[k].len()));
        }
        for (i, w) in self.omega.iter().enumerate() {
            required.push((format!("omega{}", i + 1), w.len()));
        }
        let rotors = self.omega.len();
        let bands = TRIM_BANDS_HZ.len();
        for (name, series, count, what) in [
            (
                "omega_dot",
                &self.omega_dot,
                rotors,
                format!("rotor acceleration series for {rotors} rotors"),
            ),
            (
                "omega_ddot",
                &self.omega_ddot,
                rotors,
                format!("series of rotor-acceleration rates for {rotors} rotors"),
            ),
            (
                "omega_squared_slow",
                &self.omega_squared_slow,
                bands * rotors,
                format!("slow thrust series for {rotors} rotors in {bands} bands"),
            ),
        ] {
            let Some(series) = series else { continue };
            if series.len() != count {
                return Err(shape(name.into(), format!("{} {what}", series.len())));
            }
            for (i, w) in series.iter().enumerate() {
                required.push((format!("{name}{}", i + 1), w.len()));
            }
        }
        let mut optional: Vec<(String, usize)> = Vec::new();
        if let Some(h) = &self.height {
            optional.push(("height".into(), h.len()));
        }
        if let Some(q) = &self.attitude {
            for (k, name) in ["qw", "qx", "qy", "qz"].iter().enumerate() {
                optional.push((name.to_string(), q[k].len()));
            }
        }
        if self.omega.is_empty() && n > 0 {
            return Err(shape("omega".into(), "no rotor speed series".into()));
        }
        for (name, len) in required {
            if len != n {
                return Err(shape(name, format!("{len} values for {n} time stamps")));
            }
        }
        for (name, len) in optional {
            if len != n {
                return Err(shape(
                    name,
                    format!("{len} values for {n} time stamps (give all or none)"),
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extend_from_copies_exactly_the_range() {
        let mut a = SampleChunk::with_capacity(2, 4, true);
        for k in 0..4 {
            let x = k as f64;
            a.push(&Sample {
                t: x,
                velocity: [x, x + 1.0, x + 2.0],
                rates: [x; 3],
                omega: vec![100.0 + x, 200.0 + x],
                omega_dot: vec![x, -x],
                wrench: [x; 6],
                height: None,
                attitude: None,
            });
        }
        let mut b = SampleChunk::with_capacity(2, 4, true);
        b.extend_from(&a, 1..3);
        assert_eq!(b.len(), 2);
        assert_eq!(b.sample(0), a.sample(1));
        assert_eq!(b.sample(1), a.sample(2));
        // Gathered rows 3, 0, 2 (with Ω̈ and attitude) equal the runs appended one by one.
        a.omega_ddot = Some(
            a.omega
                .iter()
                .map(|w| w.iter().map(|x| -x).collect())
                .collect(),
        );
        a.attitude = Some(std::array::from_fn(|c| {
            (0..4).map(|k| (c * k) as f64).collect()
        }));
        let (mut by_rows, mut by_runs) = (SampleChunk::default(), SampleChunk::default());
        by_rows.extend_from_rows(&a, &[3, 0, 2]);
        for k in [3, 0, 2] {
            by_runs.extend_from(&a, k..k + 1);
        }
        assert_eq!(by_rows.len(), 3);
        assert_eq!(by_rows.omega_ddot, by_runs.omega_ddot);
        assert_eq!(by_rows.attitude, by_runs.attitude);
        assert_eq!(by_rows.sample(0), a.sample(3));
        assert_eq!(by_rows.sample(1), a.sample(0));
        assert_eq!(by_rows.sample(2), a.sample(2));
    }

    /// The length check passes a well-formed chunk and names the first malformed signal
    /// of one that is not, with what is wrong.
    #[test]
    fn check_lengths_names_the_malformed_signal() {
        let mut c = SampleChunk::with_capacity(2, 2, true);
        for k in 0..2 {
            c.push(&Sample {
                t: k as f64,
                omega: vec![100.0; 2],
                omega_dot: vec![0.0; 2],
                ..Sample::default()
            });
        }
        assert_eq!(c.check_lengths(), Ok(()));
        let shape = |signal: &str, problem: &str| {
            Err(ChunkShapeError {
                signal: signal.into(),
                problem: problem.into(),
            })
        };
        let mut short = c.clone();
        short.omega[1].pop();
        assert_eq!(
            short.check_lengths(),
            shape("omega2", "1 values for 2 time stamps")
        );
        let mut partial = c.clone();
        partial.height = Some(vec![1.0]);
        assert_eq!(
            partial.check_lengths(),
            shape("height", "1 values for 2 time stamps (give all or none)")
        );
        let mut three = c.clone();
        three.attitude = Some([vec![1.0; 2], vec![0.0; 2], vec![0.0; 2], Vec::new()]);
        assert_eq!(
            three.check_lengths(),
            shape("qz", "0 values for 2 time stamps (give all or none)")
        );
        let mut rotors = c.clone();
        rotors.omega_dot.as_mut().expect("Ω̇ carried").pop();
        assert_eq!(
            rotors.check_lengths(),
            shape("omega_dot", "1 rotor acceleration series for 2 rotors")
        );
    }
}

/// Rotor count and which optional signals (Ω̇, height, attitude) data carry: they decide
/// which model terms and candidate effects the data can support.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Signals {
    /// Number of rotor speed series.
    pub rotors: usize,
    /// Rotor accelerations Ω̇_i present.
    pub omega_dot: bool,
    /// Rates of the rotor accelerations Ω̈_i present (derived by the fit pipeline).
    pub omega_ddot: bool,
    /// Slow parts of the rotors' Ω² present (derived by the fit pipeline).
    pub omega_squared_slow: bool,
    /// CG height present.
    pub height: bool,
    /// Attitude quaternion present.
    pub attitude: bool,
}

/// One sample of the data contract (array of structures form, for convenience APIs).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Sample {
    /// Time, s.
    pub t: f64,
    /// Air-relative velocity u, v, w in body axes, m/s.
    pub velocity: [f64; 3],
    /// Body rates p, q, r, rad/s.
    pub rates: [f64; 3],
    /// Rotor speeds Ω_i, rad/s.
    pub omega: Vec<f64>,
    /// Rotor accelerations Ω̇_i, rad/s² (empty when not available).
    pub omega_dot: Vec<f64>,
    /// Force (N) and moment (N m) in [`Axis`] order.
    pub wrench: [f64; 6],
    /// CG height above ground, m, when logged.
    pub height: Option<f64>,
    /// Attitude quaternion body→NED `[qw, qx, qy, qz]`, when logged.
    pub attitude: Option<[f64; 4]>,
}

impl Sample {
    /// Rotor count and optional signals of the sample.
    pub fn signals(&self) -> Signals {
        Signals {
            rotors: self.omega.len(),
            omega_dot: !self.omega_dot.is_empty(),
            omega_ddot: false,
            omega_squared_slow: false,
            height: self.height.is_some(),
            attitude: self.attitude.is_some(),
        }
    }
}
