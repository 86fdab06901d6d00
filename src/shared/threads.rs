//! Loops that run on rayon's threads (feature `parallel`) for a large body and give the same
//! result, bit for bit, whatever the thread count: the work is cut into fixed chunks whatever
//! the threads, and partial results combine in chunk order.

use std::ops::Range;

use super::math::Real;

/// Terms per chunk: enough that a chunk's work outweighs rayon's per-task cost.
const CHUNK: usize = 1024;

/// `Σ part(chunk)` over `0..count` cut into fixed chunks, the chunks' sums added in order (on
/// rayon's threads when there are several chunks and threads).
pub(crate) fn chunked_sum(count: usize, part: impl Fn(Range<usize>) -> Real + Sync) -> Real {
    let chunk = |c: usize| part(c * CHUNK..((c + 1) * CHUNK).min(count));
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
    let chunk = |c: usize| part(c * CHUNK..((c + 1) * CHUNK).min(count));
    let chunks = count.div_ceil(CHUNK);
    #[cfg(feature = "parallel")]
    if chunks > 1 && rayon::current_num_threads() > 1 {
        use rayon::prelude::*;
        let parts: Vec<T> = (0..chunks).into_par_iter().map(chunk).collect();
        return parts.into_iter().reduce(combine);
    }
    (0..chunks).map(chunk).reduce(combine)
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
    #[cfg(feature = "parallel")]
    if count > CHUNK && rayon::current_num_threads() > 1 {
        use rayon::prelude::*;
        return (0..count)
            .into_par_iter()
            .with_min_len(CHUNK)
            .map(&f)
            .collect();
    }
    (0..count).map(f).collect()
}
