//! Emitting a window row as a sample of the chunk: ω̇ and Ω̇ differentiated over the
//! window when not logged, spikes flagged (Hampel test), F = m a and M = I ω̇ + ω × I ω
//! derived when not logged, and the layout and unit statistics fed.

use super::super::MAX_ROTORS;
use super::super::derive::{SgWeights, euler_moment, specific_force_at_cg};
use super::super::error::Location;
use super::super::mapping::Signal;
use super::super::validate::{SPIKE_HALF_WINDOW, is_spike, spike_floor};
use super::LogReader;
use super::convert::Row;
use crate::sample::CHUNK_SAMPLES;

/// Scratch of the Savitzky–Golay derivative over the window.
#[derive(Debug, Default)]
pub(super) struct Differentiator {
    /// Times of the rows the derivative spans, s.
    times: Vec<f64>,
    /// Weights, reused while the time steps repeat.
    weights: SgWeights,
}

impl LogReader {
    /// Emits the sample at window index `k` into the chunk.
    fn emit(&mut self, k: usize) {
        let n = self.vehicle.rotors;
        let Some((ang_acc, omega_dot)) = self.derivatives(k) else {
            return;
        };
        self.flag_spikes(k);
        let layout = &self.convert.layout;
        // Borrowed, not copied: a row is some 600 bytes, most of them unused here.
        let row = &self.window.rows[k];
        let force = if layout.has(Signal::Force) {
            row.force
        } else {
            let a = match self.opts.derive.imu_lever_arm {
                Some(r) => specific_force_at_cg(row.specific_force, r, row.rates, ang_acc),
                None => row.specific_force,
            };
            a.map(|c| self.vehicle.mass * c)
        };
        let moment = if layout.has(Signal::Moment) {
            row.moment
        } else {
            euler_moment(&self.vehicle.inertia, row.rates, ang_acc)
        };
        let wrench = [
            force[0], force[1], force[2], moment[0], moment[1], moment[2],
        ];
        let c = &mut self.out.chunk;
        c.t.push(row.t);
        for a in 0..3 {
            c.velocity[a].push(row.velocity[a]);
            c.rates[a].push(row.rates[a]);
        }
        for i in 0..n {
            c.omega[i].push(row.omega[i]);
        }
        if let Some(dst) = &mut c.omega_dot {
            for (v, &x) in dst.iter_mut().zip(&omega_dot) {
                v.push(x);
            }
        }
        for (dst, v) in c.wrench.iter_mut().zip(wrench) {
            dst.push(v);
        }
        // The chunk carries the log's optional signals (`prepare_optional`).
        if let Some(height) = &mut c.height {
            height.push(row.height);
        }
        if let Some(attitude) = &mut c.attitude {
            for (dst, &q) in attitude.iter_mut().zip(&row.attitude) {
                dst.push(q);
            }
        }
        let tally = &mut self.tally;
        tally.layout.push(&row.omega[..n], &omega_dot[..n], &wrench);
        tally
            .unit_stats
            .push(force, self.vehicle.mass, row.rates, &row.omega[..n]);
        tally.summary.samples += 1;
        self.window.segment_samples += 1;
    }

    /// Angular and rotor accelerations of the sample at window index `k`: logged, or
    /// differentiated over the window as the plan says. `None` (the sample dropped and
    /// counted) when the segment is too short to differentiate.
    fn derivatives(&mut self, k: usize) -> Option<([f64; 3], [f64; MAX_ROTORS])> {
        let rows = &self.window.rows;
        let row = &rows[k];
        let (mut ang_acc, mut omega_dot) = (row.ang_acc, row.omega_dot);
        if !self.plan.diff_rates && !self.plan.diff_omega {
            return Some((ang_acc, omega_dot));
        }
        let n = self.vehicle.rotors;
        let d = self.opts.derive;
        let len = rows.len();
        let w = d.sg_window.min(len);
        let lo = k.saturating_sub(d.sg_window / 2).min(len - w);
        let diff = &mut self.diff;
        diff.times.clear();
        diff.times.extend(rows.range(lo..lo + w).map(|r| r.t));
        let Some(wts) = diff.weights.get(&diff.times, k - lo, d.sg_order) else {
            let msg = format!(
                "{}: {}: segment of {len} samples is too short to differentiate (sg_order {})",
                self.tally.summary.file,
                loc_text(row.loc),
                d.sg_order
            );
            self.tally
                .summary
                .count_drop("segment too short to differentiate", msg);
            return None;
        };
        let win = rows.range(lo..lo + w);
        if self.plan.diff_rates {
            ang_acc = [0.0; 3];
            for (wt, r) in wts.iter().zip(win.clone()) {
                for (acc, rate) in ang_acc.iter_mut().zip(r.rates) {
                    *acc += wt * rate;
                }
            }
        }
        if self.plan.diff_omega {
            omega_dot = [0.0; MAX_ROTORS];
            for (wt, r) in wts.iter().zip(win) {
                for (acc, w) in omega_dot[..n].iter_mut().zip(&r.omega[..n]) {
                    *acc += wt * w;
                }
            }
        }
        Some((ang_acc, omega_dot))
    }

    /// Hampel test of rates, rotor speeds and force source at window index `k`.
    fn flag_spikes(&mut self, k: usize) {
        let rows = &self.window.rows;
        let len = rows.len();
        if len < 2 * SPIKE_HALF_WINDOW + 1 {
            return;
        }
        let lo = k
            .saturating_sub(SPIKE_HALF_WINDOW)
            .min(len - 2 * SPIKE_HALF_WINDOW - 1);
        if lo + SPIKE_HALF_WINDOW != k {
            return; // one-sided windows at segment ends are not tested
        }
        let force_signal = if self.convert.layout.has(Signal::Force) {
            Signal::Force
        } else {
            Signal::SpecificForce
        };
        let groups: [(Signal, usize); 3] = [
            (Signal::Rates, 3),
            (Signal::RotorSpeeds, self.vehicle.rotors),
            (force_signal, 3),
        ];
        const WIDTH: usize = 2 * SPIKE_HALF_WINDOW + 1;
        for (signal, count) in groups {
            let floor = spike_floor(signal);
            let value = |r: &Row, comp: usize| match signal {
                Signal::Rates => r.rates[comp],
                Signal::RotorSpeeds => r.omega[comp],
                Signal::Force => r.force[comp],
                _ => r.specific_force[comp],
            };
            let mut spiked = false;
            for comp in 0..count {
                // The neighbourhood, read once into a stack array for both tests.
                let mut window = [0.0; WIDTH];
                for (v, r) in window.iter_mut().zip(rows.range(lo..lo + WIDTH)) {
                    *v = value(r, comp);
                }
                // Exact pre-test: the median is a window value, so a centre within
                // `floor` of every neighbour cannot depart from it by more than `floor`.
                let x = window[SPIKE_HALF_WINDOW];
                if window.iter().all(|v| (v - x).abs() <= floor) {
                    continue;
                }
                spiked |= is_spike(&mut window, floor);
            }
            if spiked {
                *self
                    .tally
                    .summary
                    .spikes
                    .entry(signal.key().to_string())
                    .or_default() += 1;
            }
        }
    }

    /// Emits every sample that has enough look-ahead (all, once the segment closed),
    /// stopping when the chunk is full. Trims the window behind.
    pub(super) fn emit_ready(&mut self) {
        let keep_behind = self.plan.lookahead.max(self.opts.derive.sg_window);
        while self.out.chunk.len() < CHUNK_SAMPLES && self.window.next_emit < self.window.rows.len()
        {
            let ready = self.window.closed()
                || self.window.next_emit + self.plan.lookahead < self.window.rows.len();
            if !ready {
                break;
            }
            self.emit(self.window.next_emit);
            self.window.next_emit += 1;
            if self.window.next_emit > keep_behind && !self.window.closed() {
                self.window.rows.pop_front();
                self.window.next_emit -= 1;
            }
        }
    }
}

/// A location in words, for the message of a dropped sample.
fn loc_text(loc: Location) -> String {
    match loc {
        Location::File => "file".into(),
        Location::Line(n) => format!("line {n}"),
        Location::Record(n) => format!("message {n}"),
        Location::Offset(n) => format!("byte {n}"),
        Location::Sample(n) => format!("sample {n}"),
    }
}
