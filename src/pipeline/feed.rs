//! The Feed stage between a log's reader and its consumer, the same for a fit and for
//! `predict`/`validate`: Ω̈ derived from Ω̇, progress counted, and the slow rotor thrusts
//! of a diagnosis or a trim-moment model filled in.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use super::FitRequest;
use super::request::check_cancel;
use crate::error::Error;
use crate::identified::IdentifiedModel;
use crate::io::{self, DeriveOptions, Mapping, ReadOptions};
use crate::io::{JerkScratch, rotor_jerk};
use crate::sample::SampleChunk;
use crate::slow::SlowThrust;

/// What happens to each chunk of a log before its consumer sees it: Ω̈ derived from Ω̇
/// ([`rotor_jerk`]), progress counted and, for a diagnosis or a model with a trim
/// moment, the slow rotor thrusts filled in ([`SlowThrust`]; chunks then reach the
/// consumer up to a few seconds of samples later, in order, the last ones at
/// [`Feed::finish`]).
pub(super) struct Feed<'p, C> {
    derive: DeriveOptions,
    progress: Option<&'p AtomicU64>,
    cancel: Option<&'p AtomicBool>,
    jerk: JerkScratch,
    /// The slow rotor thrusts are wanted; the stage once the first chunk is in.
    slow_wanted: bool,
    slow: Option<SlowThrust>,
    consume: C,
}

impl<'p, C: FnMut(&SampleChunk) -> Result<(), Error>> Feed<'p, C> {
    /// The feed of a fit: the slow thrusts for a diagnosis.
    pub(super) fn of_fit(req: &'p FitRequest, consume: C) -> Self {
        Self::new(jerk_options(req), req.diagnose.is_some(), consume)
            .counting(req.progress.as_deref(), req.cancel.as_deref())
    }

    fn new(derive: DeriveOptions, slow_wanted: bool, consume: C) -> Self {
        Self {
            derive,
            progress: None,
            cancel: None,
            jerk: JerkScratch::default(),
            slow_wanted,
            slow: None,
            consume,
        }
    }

    /// The feed counting its samples in `progress` and stopping once `cancel` is set.
    fn counting(self, progress: Option<&'p AtomicU64>, cancel: Option<&'p AtomicBool>) -> Self {
        Self {
            progress,
            cancel,
            ..self
        }
    }

    pub(super) fn push(&mut self, chunk: &mut SampleChunk) -> Result<(), Error> {
        check_cancel(self.cancel)?;
        rotor_jerk(chunk, &self.derive, &mut self.jerk);
        let (progress, consume) = (self.progress, &mut self.consume);
        let mut deliver = |c: &SampleChunk| {
            if let Some(p) = progress {
                p.fetch_add(c.len() as u64, Ordering::Relaxed);
            }
            consume(c)
        };
        if !self.slow_wanted {
            return deliver(chunk);
        }
        let rotors = chunk.rotor_count();
        let stage = self.slow.get_or_insert_with(|| SlowThrust::new(rotors));
        // A copy is held: the reader's chunk goes back to it.
        stage.push(chunk.clone(), |c| deliver(&c))
    }

    pub(super) fn finish(&mut self) -> Result<(), Error> {
        let (progress, consume) = (self.progress, &mut self.consume);
        match self.slow.as_mut() {
            Some(stage) => stage.finish(|c| {
                if let Some(p) = progress {
                    p.fetch_add(c.len() as u64, Ordering::Relaxed);
                }
                consume(&c)
            }),
            None => Ok(()),
        }
    }
}

/// Streams the log file at `path` as `model` needs it: read with `mapping`, cut into the
/// chunks a fit cuts, with the rates of rotor acceleration and the slow rotor thrusts
/// derived as the fit pipeline derives them (so `predict` and `validate` see the
/// samples the fit saw), each chunk handed to `consume` in order.
pub fn stream_for_model(
    model: &IdentifiedModel,
    path: &std::path::Path,
    mapping: Option<&Mapping>,
    consume: impl FnMut(&SampleChunk) -> Result<(), Error>,
) -> Result<(), Error> {
    let read = ReadOptions::default();
    let derive = mapping.and_then(|m| m.derive).unwrap_or(read.derive);
    let mut feed = Feed::new(derive, model.structure.needs_slow_thrust(), consume);
    let mut reader = io::open_log(path, &model.vehicle, mapping, &read)?;
    reader.join_segments();
    while let Some(chunk) = reader.next_chunk_mut() {
        feed.push(chunk?)?;
    }
    feed.finish()
}

/// Differentiator of the rates of rotor acceleration ([`rotor_jerk`], on the re-cut
/// chunks of every log alike): the mapping file's `[derive]` table when given, else the
/// request's read options.
fn jerk_options(req: &FitRequest) -> DeriveOptions {
    req.mapping
        .as_ref()
        .and_then(|m| m.derive)
        .unwrap_or(req.read.derive)
}
