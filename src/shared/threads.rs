//! Loops that run on rayon's threads (feature `parallel`) for a large body and give the same
//! result, bit for bit, whatever the thread count: the work is cut into fixed chunks whatever
//! the threads, and partial results combine in chunk order.
//!
//! A step alternates such loops with serial work (contacts, the integrator's bookkeeping). A
//! rayon thread left without work sleeps after a short spin, and waking it costs tens of
//! microseconds (a join of two 200 µs halves after 200 µs of serial work took 270 µs on the
//! 2-core machine of `docs/PERFORMANCE.md`, 200 µs back to back), more than a loop of a
//! mid-size body saves. So while a step with a large body runs, [`with_team`] keeps rayon's
//! other threads polling for its work instead of sleeping: those cores are busy for the
//! length of the step, and free again when it returns.

use std::ops::Range;

use super::math::Real;

/// Terms per chunk: enough that a chunk's work outweighs rayon's per-task cost.
pub(crate) const CHUNK: usize = 1024;

/// Runs `f`; with `busy` (and feature `parallel`, and more than one rayon thread), rayon's
/// other threads poll for work (`rayon::yield_now`) until `f` returns, instead of sleeping
/// between its parallel loops.
pub(crate) fn with_team<R>(busy: bool, f: impl FnOnce() -> R) -> R {
    #[cfg(feature = "parallel")]
    if busy && rayon::current_num_threads() > 1 {
        return team::run(f);
    }
    let _ = busy;
    f()
}

#[cfg(feature = "parallel")]
mod team {
    use std::cell::Cell;
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
    use std::sync::Arc;

    thread_local! {
        /// Whether this thread is polling for a team already.
        static POLLING: Cell<bool> = const { Cell::new(false) };
    }

    /// Sets the flag when dropped: the pollers stop even if the step panics.
    struct Done(Arc<AtomicBool>);

    impl Drop for Done {
        fn drop(&mut self) {
            self.0.store(true, Ordering::Release);
        }
    }

    pub(super) fn run<R>(f: impl FnOnce() -> R) -> R {
        run_counted(f, &Arc::new(AtomicUsize::new(0)))
    }

    /// [`run`], `pollers` counting the threads polling for it.
    pub(super) fn run_counted<R>(f: impl FnOnce() -> R, pollers: &Arc<AtomicUsize>) -> R {
        let done = Done(Arc::new(AtomicBool::new(false)));
        let caller = std::thread::current().id();
        for _ in 1..rayon::current_num_threads() {
            let done = Arc::clone(&done.0);
            let pollers = Arc::clone(pollers);
            rayon::spawn(move || {
                // Not on the caller (it would poll until its own step ends: never), nor
                // inside another poller (a job the step waits for may be beneath it).
                if std::thread::current().id() == caller || POLLING.with(Cell::get) {
                    return;
                }
                POLLING.with(|p| p.set(true));
                pollers.fetch_add(1, Ordering::AcqRel);
                while !done.load(Ordering::Acquire) {
                    if rayon::yield_now() != Some(rayon::Yield::Executed) {
                        std::hint::spin_loop();
                    }
                }
                pollers.fetch_sub(1, Ordering::AcqRel);
                POLLING.with(|p| p.set(false));
            });
        }
        f()
    }
}

/// The fixed chunks `0..count` is cut into by [`chunked_sum`] and [`chunked_fold`], in order:
/// a serial loop that sums its own partial results chunk by chunk, in this order, gets their
/// bits.
pub(crate) fn chunks(count: usize) -> impl Iterator<Item = Range<usize>> {
    (0..count.div_ceil(CHUNK)).map(move |c| chunk_of(c, count))
}

/// Chunk `c` of `0..count`.
fn chunk_of(c: usize, count: usize) -> Range<usize> {
    c * CHUNK..((c + 1) * CHUNK).min(count)
}

/// `Σ part(chunk)` over `0..count` cut into fixed chunks, the chunks' sums added in order (on
/// rayon's threads when there are several chunks and threads).
pub(crate) fn chunked_sum(count: usize, part: impl Fn(Range<usize>) -> Real + Sync) -> Real {
    let chunk = |c: usize| part(chunk_of(c, count));
    let chunks = count.div_ceil(CHUNK);
    #[cfg(feature = "parallel")]
    if chunks > 1 && rayon::current_num_threads() > 1 {
        use rayon::prelude::*;
        let sums: Vec<Real> = (0..chunks).into_par_iter().map(chunk).collect();
        return sums.into_iter().sum();
    }
    (0..chunks).map(chunk).sum()
}

/// `part(chunk)` over `0..count` cut into fixed chunks, the chunks' results combined in order
/// by `combine` (on rayon's threads when there are several chunks and threads).
pub(crate) fn chunked_fold<T: Send>(
    count: usize,
    part: impl Fn(Range<usize>) -> T + Sync,
    combine: impl Fn(T, T) -> T,
) -> Option<T> {
    let chunk = |c: usize| part(chunk_of(c, count));
    let chunks = count.div_ceil(CHUNK);
    #[cfg(feature = "parallel")]
    if chunks > 1 && rayon::current_num_threads() > 1 {
        use rayon::prelude::*;
        let parts: Vec<T> = (0..chunks).into_par_iter().map(chunk).collect();
        return parts.into_iter().reduce(combine);
    }
    (0..chunks).map(chunk).reduce(combine)
}

/// The largest `value(i)` over `0..count`, at least 0 (a NaN is passed over). `max` is exact,
/// so for values that are never −0 any order gives the same bits: four running maxima per
/// chunk, so that the comparisons do not wait on each other, and the chunks on rayon's threads
/// for a large body.
pub(crate) fn largest(count: usize, value: impl Fn(usize) -> Real + Sync) -> Real {
    extreme(count, 0.0, |a: Real, b| a.max(b), value)
}

/// The least `value(i)` over `0..count`, at most infinity (a NaN is passed over), as
/// [`largest`].
pub(crate) fn least(count: usize, value: impl Fn(usize) -> Real + Sync) -> Real {
    extreme(count, Real::INFINITY, |a: Real, b| a.min(b), value)
}

/// `value(i)` over `0..count` combined from `start` by `pick` (an exact choice, a minimum or a
/// maximum, order-free but for the sign of a zero), in four running picks per chunk.
fn extreme(
    count: usize,
    start: Real,
    pick: impl Fn(Real, Real) -> Real + Copy + Sync,
    value: impl Fn(usize) -> Real + Sync,
) -> Real {
    let part = |r: Range<usize>| {
        let mut best = [start; 4];
        let mut i = r.start;
        while i + 4 <= r.end {
            for (k, b) in best.iter_mut().enumerate() {
                *b = pick(*b, value(i + k));
            }
            i += 4;
        }
        for j in i..r.end {
            best[0] = pick(best[0], value(j));
        }
        best.into_iter().fold(start, pick)
    };
    chunked_fold(count, part, pick).unwrap_or(start)
}

/// Whether `test(i)` holds for every `i` in `0..count` (on rayon's threads when there are
/// several chunks and threads).
pub(crate) fn all(count: usize, test: impl Fn(usize) -> bool + Sync) -> bool {
    #[cfg(feature = "parallel")]
    if count > CHUNK && rayon::current_num_threads() > 1 {
        use rayon::prelude::*;
        return (0..count).into_par_iter().with_min_len(CHUNK).all(&test);
    }
    (0..count).all(test)
}

/// `f(i, item)` for every item, each independent of the others (on rayon's threads when there
/// are several chunks and threads).
pub(crate) fn for_each_mut<T: Send>(items: &mut [T], f: impl Fn(usize, &mut T) + Sync) {
    #[cfg(feature = "parallel")]
    if items.len() > CHUNK && rayon::current_num_threads() > 1 {
        use rayon::prelude::*;
        items
            .par_iter_mut()
            .with_min_len(CHUNK)
            .enumerate()
            .for_each(|(i, item)| f(i, item));
        return;
    }
    items
        .iter_mut()
        .enumerate()
        .for_each(|(i, item)| f(i, item));
}

/// `[f(0), f(1), …, f(count − 1)]` (on rayon's threads when there are several chunks and
/// threads).
pub(crate) fn collect<T: Send>(count: usize, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    collect_in(count, CHUNK, f)
}

/// [`collect`] in chunks of `chunk` items, for items that each cost many terms.
pub(crate) fn collect_in<T: Send>(
    count: usize,
    chunk: usize,
    f: impl Fn(usize) -> T + Sync,
) -> Vec<T> {
    #[cfg(feature = "parallel")]
    if count > chunk && rayon::current_num_threads() > 1 {
        use rayon::prelude::*;
        return (0..count)
            .into_par_iter()
            .with_min_len(chunk)
            .map(&f)
            .collect();
    }
    let _ = chunk;
    (0..count).map(f).collect()
}

#[cfg(all(test, feature = "parallel"))]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::Arc;
    use std::time::{Duration, Instant};

    /// Whether the team's pollers all stopped within five seconds.
    fn stopped(pollers: &AtomicUsize) -> bool {
        let start = Instant::now();
        while pollers.load(Ordering::Acquire) > 0 {
            if start.elapsed() > Duration::from_secs(5) {
                return false;
            }
            std::thread::yield_now();
        }
        true
    }

    #[test]
    fn a_parallel_team_does_the_work_and_lets_the_threads_go_even_after_a_panic() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let sum = |k: usize| chunked_sum(10 * CHUNK + k, |r| r.map(|i| i as Real).sum());
        let pollers = Arc::new(AtomicUsize::new(0));
        let (sums, polled) = pool.install(|| {
            team::run_counted(
                || {
                    // The other thread starts polling (within seconds, on a loaded machine).
                    let start = Instant::now();
                    while pollers.load(Ordering::Acquire) == 0
                        && start.elapsed() < Duration::from_secs(5)
                    {
                        std::thread::sleep(Duration::from_micros(100));
                    }
                    let polled = pollers.load(Ordering::Acquire);
                    let sums: Vec<Real> = (0..50)
                        .map(|k| {
                            std::thread::sleep(Duration::from_micros(100));
                            sum(k)
                        })
                        .collect();
                    (sums, polled)
                },
                &pollers,
            )
        });
        assert_eq!(polled, 1, "the other thread polls while the work runs");
        assert_eq!(sums, (0..50).map(sum).collect::<Vec<_>>());
        assert!(
            stopped(&pollers),
            "a poller still runs after the team's work"
        );
        let panicked = pool.install(|| {
            std::panic::catch_unwind(|| {
                team::run_counted(
                    || {
                        sum(0);
                        panic!("a step that fails");
                    },
                    &pollers,
                )
            })
        });
        assert!(panicked.is_err());
        assert!(
            stopped(&pollers),
            "a poller still runs after the team's step panicked"
        );
    }
}
