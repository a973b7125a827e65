//! How the pipeline's work is spread over threads without the results depending on it:
//! logs as jobs on a pool ([`run_jobs`], results in job order), a log's second pass in
//! segments cut by its length alone ([`segments`]) whose results are folded in order
//! ([`run_in_order`]).

use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use super::FitRequest;
use super::split::Role;
use crate::error::{Error, RequestError};
use crate::source::LogSource;

/// Runs `per_log(job index, path, role, share)` for every job on up to `req.threads`
/// threads; results come back in job order, so merged statistics do not depend on
/// scheduling. `share` is the number of threads a job may use: `req.threads` divided
/// among the logs worked on at once (at least 1).
pub(super) fn run_jobs<T: Send>(
    jobs: &[(LogSource, Role)],
    req: &FitRequest,
    per_log: impl Fn(usize, &LogSource, Role, usize) -> Result<T, Error> + Sync,
) -> Result<Vec<T>, Error> {
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<Result<T, Error>>>> =
        Mutex::new((0..jobs.len()).map(|_| None).collect());
    let threads = req.threads.max(1);
    let workers = threads.min(jobs.len().max(1));
    let share = (threads / workers).max(1);
    std::thread::scope(|scope| {
        for _ in 0..workers {
            scope.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some((path, role)) = jobs.get(i) else {
                        break;
                    };
                    let r = per_log(i, path, *role, share);
                    results.lock().unwrap_or_else(|e| e.into_inner())[i] = Some(r);
                }
            });
        }
    });
    results
        .into_inner()
        .unwrap_or_else(|e| e.into_inner())
        .into_iter()
        .map(|r| r.unwrap_or_else(|| Err(RequestError::WorkerStopped.into())))
        .collect()
}

/// Most chunks per segment of a log's second pass (`second_pass::pass_log`): a log of up
/// to 64 chunks (65 536 samples) is one segment.
const SEGMENT_CHUNKS: usize = 64;

/// A longer log is cut into a multiple of this many segments of equal length (to a
/// chunk), so that 1, 2, 3 or 6 threads finish their last segments together: with
/// segments of 64 chunks and a short last one, one thread of two idled for up to a
/// segment at the end (~5 % of a 1 M-sample diagnosed fit).
const SEGMENT_GROUP: usize = 6;

/// The chunks of each segment of a log of `chunks` chunks, in order: one segment of up to
/// [`SEGMENT_CHUNKS`], else the fewest multiple of [`SEGMENT_GROUP`] segments of at most
/// that many, equal to a chunk (the longer first). A function of the length alone, so
/// results never depend on the thread count.
pub(super) fn segments(chunks: usize) -> Vec<std::ops::Range<usize>> {
    let n = if chunks <= SEGMENT_CHUNKS {
        1
    } else {
        chunks.div_ceil(SEGMENT_CHUNKS * SEGMENT_GROUP) * SEGMENT_GROUP
    };
    let (size, longer) = (chunks / n, chunks % n);
    let mut start = 0;
    (0..n)
        .map(|k| {
            let range = start..start + size + usize::from(k < longer);
            start = range.end;
            range
        })
        .collect()
}

/// Runs `task(i)` for i in 0..n on up to `threads` threads, handing the results to
/// `fold` in index order as they come in (tasks are taken in index order, so at most
/// about `threads` results wait). The first error in index order is returned.
pub(super) fn run_in_order<T: Send>(
    n: usize,
    threads: usize,
    task: impl Fn(usize) -> Result<T, Error> + Sync,
    fold: &mut (impl FnMut(T) -> Result<(), Error> + Send),
) -> Result<(), Error> {
    struct Done<'f, T, F> {
        next: usize,
        waiting: std::collections::BTreeMap<usize, T>,
        fold: &'f mut F,
        failed: Option<(usize, Error)>,
    }
    let done = Mutex::new(Done {
        next: 0,
        waiting: Default::default(),
        fold,
        failed: None,
    });
    let take = AtomicUsize::new(0);
    let work = || {
        loop {
            let i = take.fetch_add(1, Ordering::Relaxed);
            let stop = |d: &Done<T, _>| d.failed.as_ref().is_some_and(|f| f.0 < i);
            if i >= n || stop(&done.lock().unwrap_or_else(|e| e.into_inner())) {
                break;
            }
            let result = task(i);
            let mut d = done.lock().unwrap_or_else(|e| e.into_inner());
            let d = &mut *d;
            match result {
                Ok(r) => {
                    d.waiting.insert(i, r);
                }
                Err(e) => {
                    if d.failed.as_ref().is_none_or(|f| i < f.0) {
                        d.failed = Some((i, e));
                    }
                }
            }
            while d.failed.is_none() {
                let Some(r) = d.waiting.remove(&d.next) else {
                    break;
                };
                d.next += 1;
                if let Err(e) = (d.fold)(r) {
                    d.failed = Some((d.next - 1, e));
                }
            }
        }
    };
    let workers = threads.clamp(1, n.max(1));
    std::thread::scope(|scope| {
        for _ in 1..workers {
            scope.spawn(work);
        }
        work();
    });
    let done = done.into_inner().unwrap_or_else(|e| e.into_inner());
    match done.failed {
        Some((_, e)) => Err(e),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Segments cover the chunks in order, at most [`SEGMENT_CHUNKS`] each and equal to a
    /// chunk, in a multiple of [`SEGMENT_GROUP`] once there is more than one.
    #[test]
    fn segments_are_equal_to_a_chunk_and_a_multiple_of_six() {
        assert_eq!(segments(0), vec![0..0]);
        assert_eq!(segments(64), vec![0..64]);
        assert_eq!(
            segments(65),
            vec![0..11, 11..22, 22..33, 33..44, 44..55, 55..65]
        );
        for chunks in [65, 71, 384, 385, 977, 9766] {
            let cuts = segments(chunks);
            assert_eq!(cuts.len() % SEGMENT_GROUP, 0, "{chunks}");
            assert_eq!((cuts[0].start, cuts[cuts.len() - 1].end), (0, chunks));
            assert!(cuts.windows(2).all(|w| w[0].end == w[1].start));
            let lens: Vec<usize> = cuts.iter().map(|c| c.len()).collect();
            let (lo, hi) = (lens.iter().min().unwrap(), lens.iter().max().unwrap());
            assert!(hi - lo <= 1 && *hi <= SEGMENT_CHUNKS, "{chunks}: {lens:?}");
        }
        // The 1 M-sample sweep: 18 segments of 54–55 chunks, where 64-chunk segments left
        // a 17-chunk last one.
        assert_eq!(segments(977).len(), 18);
    }
}
