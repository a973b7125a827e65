//! Chunks held in a stream while zero-phase filters ([`crate::smooth::LowPass`]) fill in
//! their samples: a filter's output for a sample comes some samples after it, so each
//! chunk is held until every filter has written its last sample, then handed on in order.

use std::collections::VecDeque;

use crate::sample::SampleChunk;

/// The chunks held, oldest first, and per filter the samples of them already written.
pub(crate) struct HeldChunks {
    held: VecDeque<SampleChunk>,
    /// Per filter: samples written, counted from the oldest chunk held.
    filled: Vec<usize>,
}

impl HeldChunks {
    /// Nothing held, for `filters` filters.
    pub(crate) fn new(filters: usize) -> Self {
        Self {
            held: VecDeque::new(),
            filled: vec![0; filters],
        }
    }

    /// Holds `chunk` (the newest).
    pub(crate) fn push(&mut self, chunk: SampleChunk) {
        self.held.push_back(chunk);
    }

    /// The newest chunk held.
    pub(crate) fn newest(&self) -> &SampleChunk {
        self.held.back().expect("a chunk is held")
    }

    /// The next sample filter `f` writes: its chunk and index there; the filter's count
    /// moves on by one.
    pub(crate) fn next_slot(&mut self, f: usize) -> (&mut SampleChunk, usize) {
        let (mut chunk, mut k) = (0, self.filled[f]);
        while k >= self.held[chunk].len() {
            k -= self.held[chunk].len();
            chunk += 1;
        }
        self.filled[f] += 1;
        (&mut self.held[chunk], k)
    }

    /// Hands on the held chunks every filter has filled (all of them when `end`).
    pub(crate) fn hand_on<E>(
        &mut self,
        end: bool,
        mut out: impl FnMut(SampleChunk) -> Result<(), E>,
    ) -> Result<(), E> {
        while let Some(front) = self.held.front() {
            let n = front.len();
            if !end && self.filled.iter().any(|&f| f < n) {
                break;
            }
            let chunk = self.held.pop_front().expect("a chunk is held");
            for f in self.filled.iter_mut() {
                *f = f.saturating_sub(n);
            }
            out(chunk)?;
        }
        Ok(())
    }
}

/// `all` cut into chunks of `every` samples (the last shorter), as a reader might
/// deliver it: the filter stages' tests check their output does not depend on the cut.
#[cfg(test)]
pub(crate) fn cut(all: &SampleChunk, every: usize) -> impl Iterator<Item = SampleChunk> + '_ {
    (0..all.len()).step_by(every).map(move |start| {
        let mut c = SampleChunk::with_capacity(all.rotor_count(), every, false);
        c.extend_from(all, start..(start + every).min(all.len()));
        c
    })
}
