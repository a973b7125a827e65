//! The Feed stage between a log's reader and its consumer, the same for a fit and for
//! `predict`/`validate`: the regressor signals filtered as the loads were, Ω̈ derived from
//! Ω̇, progress counted, and the slow rotor thrusts of a diagnosis or a trim-moment model
//! filled in.

use std::sync::atomic::AtomicBool;

use super::FitRequest;
use super::request::check_cancel;
use crate::consistent_filter::ConsistentFilter;
use crate::error::Error;
use crate::identified::IdentifiedModel;
use crate::io::{self, DeriveOptions, Mapping, ReadOptions};
use crate::io::{JerkScratch, rotor_jerk};
use crate::progress::Progress;
use crate::sample::SampleChunk;
use crate::slow::SlowThrust;

/// What happens to each chunk of a log before its consumer sees it: the regressor
/// signals low-passed as the loads were when the log was made ([`ConsistentFilter`],
/// when declared), Ω̈ derived from Ω̇ ([`rotor_jerk`]), progress counted and, for a
/// diagnosis or a model with a trim moment, the slow rotor thrusts filled in
/// ([`SlowThrust`]). With either filter, chunks reach the consumer up to a few seconds of
/// samples later, in order, the last ones at [`Feed::finish`].
pub(super) struct Feed<'p, C> {
    /// The consistent filter, when the loads were smoothed.
    filter: Option<ConsistentFilter>,
    after: AfterFilter<'p, C>,
}

/// The Feed's stages after the consistent filter.
struct AfterFilter<'p, C> {
    derive: DeriveOptions,
    progress: Option<&'p Progress>,
    /// Set by the caller to stop the fit.
    cancel: Option<&'p AtomicBool>,
    jerk: JerkScratch,
    /// The slow rotor thrusts are wanted; the stage once the first chunk is in.
    slow_wanted: bool,
    slow: Option<SlowThrust>,
    consume: C,
}

impl<'p, C: FnMut(&SampleChunk) -> Result<(), Error>> Feed<'p, C> {
    /// The feed of a fit: the consistent filter of the request's loads, the slow thrusts
    /// for a diagnosis.
    pub(super) fn of_fit(req: &'p FitRequest, consume: C) -> Self {
        let mut feed = Self::new(
            jerk_options(req),
            req.effective_loads_low_pass(),
            req.diagnose.is_some(),
            consume,
        );
        feed.after.progress = req.progress.as_deref();
        feed.after.cancel = req.cancel.as_deref();
        feed
    }

    fn new(derive: DeriveOptions, low_pass: Option<f64>, slow_wanted: bool, consume: C) -> Self {
        Self {
            filter: low_pass.map(ConsistentFilter::new),
            after: AfterFilter {
                derive,
                progress: None,
                cancel: None,
                jerk: JerkScratch::default(),
                slow_wanted,
                slow: None,
                consume,
            },
        }
    }

    pub(super) fn push(&mut self, chunk: &mut SampleChunk) -> Result<(), Error> {
        check_cancel(self.after.cancel)?;
        let Self { filter, after } = self;
        match filter {
            None => after.push(chunk),
            // A copy is held: the reader's chunk goes back to it.
            Some(f) => f.push(chunk.clone(), |mut c| after.push(&mut c)),
        }
    }

    pub(super) fn finish(&mut self) -> Result<(), Error> {
        let Self { filter, after } = self;
        if let Some(f) = filter {
            f.finish(|mut c| after.push(&mut c))?;
        }
        after.finish()
    }
}

impl<C: FnMut(&SampleChunk) -> Result<(), Error>> AfterFilter<'_, C> {
    fn push(&mut self, chunk: &mut SampleChunk) -> Result<(), Error> {
        rotor_jerk(chunk, &self.derive, &mut self.jerk);
        let Self {
            progress,
            slow_wanted,
            slow,
            consume,
            ..
        } = self;
        let mut deliver = |c: &SampleChunk| deliver(*progress, consume, c);
        if !*slow_wanted {
            return deliver(chunk);
        }
        let rotors = chunk.rotor_count();
        let stage = slow.get_or_insert_with(|| SlowThrust::new(rotors));
        stage.push(chunk.clone(), |c| deliver(&c))
    }

    fn finish(&mut self) -> Result<(), Error> {
        let (progress, consume) = (self.progress, &mut self.consume);
        match self.slow.as_mut() {
            Some(stage) => stage.finish(|c| deliver(progress, consume, &c)),
            None => Ok(()),
        }
    }
}

/// Counts `chunk` in `progress` and hands it to `consume`.
fn deliver<C: FnMut(&SampleChunk) -> Result<(), Error>>(
    progress: Option<&Progress>,
    consume: &mut C,
    chunk: &SampleChunk,
) -> Result<(), Error> {
    if let Some(p) = progress {
        p.add_samples(chunk.len() as u64);
    }
    consume(chunk)
}

/// Streams the log file at `path` as `model` needs it: read with `mapping`, its regressor
/// signals low-passed as the mapping's `[loads]` says, else as the model's fit logs were
/// ([`IdentifiedModel::loads_low_pass_hz`]), cut into the chunks a fit cuts, with the rates of rotor acceleration and the slow rotor thrusts
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
    let low_pass = loads_low_pass(mapping).or(model.loads_low_pass_hz);
    let mut feed = Feed::new(
        derive,
        low_pass,
        model.structure.needs_slow_thrust(),
        consume,
    );
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

/// The cut-off (Hz) at which the loads were low-passed, from the mapping file's `[loads]`
/// table ([`io::LoadsProcessing`]).
fn loads_low_pass(mapping: Option<&Mapping>) -> Option<f64> {
    mapping.and_then(|m| m.loads).map(|l| l.low_pass_hz)
}
