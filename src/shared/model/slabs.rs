//! Edge repulsion's explicit forces on several threads by slabs of nodes (feature
//! `parallel`), in place of the two-pass evaluation of [`super::parallel`].
//!
//! The nodes are cut into a fixed number of slabs of consecutive nodes, each wider than any
//! term's span of node indices, and each term (spring or cell) belongs to the slab of its
//! lowest node: it touches only that slab and the next. The even slabs add their terms first,
//! at once on rayon's threads (slab `s` writes only slabs `s` and `s + 1`, which no other even
//! slab writes), then the odd ones. Each term is evaluated once, with no buffers and no
//! gather, and each node sums the same terms in the same order on any number of threads (one
//! thread runs the same two phases in turn), so the forces are bit for bit the same whatever
//! the thread count. They differ in rounding from the serial loop's, whose order is the terms'.

use std::ops::Range;

use rayon::prelude::*;

use super::super::math::{Real, Vector, SIMPLEX_ARITY};
use super::edge_repulsion::EdgeRepulsion;
use super::volume::Volume;

/// The fewest slabs: each phase then has work for two threads.
const MIN_SLABS: usize = 4;

/// The most slabs (a fixed count for a body, so the result does not depend on the threads).
const MAX_SLABS: usize = 16;

/// The slabs of a body.
#[derive(Clone, Debug)]
pub(crate) struct Slabs {
    slabs: Vec<Slab>,
}

/// The terms whose lowest node is in one slab (runs of consecutive springs and cells, in
/// order), and its nodes.
#[derive(Clone, Debug, Default)]
struct Slab {
    nodes: Range<usize>,
    springs: Vec<Range<usize>>,
    cells: Vec<Range<usize>>,
}

/// Adds term `t` to `runs`, extending the last run if `t` follows it.
fn push_run(runs: &mut Vec<Range<usize>>, t: usize) {
    match runs.last_mut() {
        Some(last) if last.end == t => last.end += 1,
        _ => runs.push(t..t + 1),
    }
}

impl Slabs {
    /// The slabs of `er` on `nodes` nodes: as many as fit up to [`MAX_SLABS`], a multiple of
    /// four, each wider than the terms' span of node indices; `None` if fewer than
    /// [`MIN_SLABS`] fit.
    pub fn of(er: &EdgeRepulsion, nodes: usize) -> Option<Self> {
        let span = er
            .cells
            .chunks_exact(SIMPLEX_ARITY)
            .map(|c| (c.iter().max().unwrap() - c.iter().min().unwrap()) as usize)
            .chain(er.edges.pairs.iter().map(|[i, j]| i.abs_diff(*j) as usize))
            .max()
            .unwrap_or(0);
        let count = (nodes / (span + 1)).min(MAX_SLABS) / 4 * 4;
        if count < MIN_SLABS {
            return None;
        }
        // The boundaries share the cells out evenly (by their lowest nodes: a lattice's last
        // layer of nodes has none), each slab at least a span wide.
        let lowest = |ids: &[u32]| ids.iter().copied().min().unwrap_or(0) as usize;
        let mut per_node = vec![0usize; nodes];
        for ids in er.cells.chunks_exact(SIMPLEX_ARITY) {
            per_node[lowest(ids)] += 1;
        }
        let cells = er.cells.len() / SIMPLEX_ARITY;
        let mut starts = vec![0];
        let mut sum = 0;
        for (i, n) in per_node.iter().enumerate() {
            let start = *starts.last().unwrap();
            if starts.len() < count && sum * count >= starts.len() * cells && i - start > span {
                starts.push(i);
            }
            sum += n;
        }
        if starts.len() < MIN_SLABS || nodes - starts[starts.len() - 1] <= span {
            return None;
        }
        let mut slab_of = vec![0u32; nodes];
        let mut slabs: Vec<Slab> = Vec::with_capacity(starts.len());
        for (s, &start) in starts.iter().enumerate() {
            let end = starts.get(s + 1).copied().unwrap_or(nodes);
            slab_of[start..end].fill(s as u32);
            slabs.push(Slab {
                nodes: start..end,
                ..Default::default()
            });
        }
        for (t, pair) in er.edges.pairs.iter().enumerate() {
            push_run(&mut slabs[slab_of[lowest(pair)] as usize].springs, t);
        }
        for (c, ids) in er.cells.chunks_exact(SIMPLEX_ARITY).enumerate() {
            push_run(&mut slabs[slab_of[lowest(ids)] as usize].cells, c);
        }
        Some(Slabs { slabs })
    }

    /// How many slabs.
    #[cfg(test)]
    pub fn count(&self) -> usize {
        self.slabs.len()
    }

    /// Adds `er`'s forces and stiffness rows (with its `volume` term) at `(x, v)` into `force`
    /// and `stiffness`, as [`EdgeRepulsion::accumulate`] does, the even slabs' terms then the
    /// odd ones'; returns the crossing limiter.
    pub fn accumulate(
        &self,
        er: &EdgeRepulsion,
        state: (&[Vector], &[Vector], Option<&Volume>),
        force: &mut [Vector],
        stiffness: &mut [Real],
    ) -> Real {
        let parallel = rayon::current_num_threads() > 1;
        let mut limit = Real::INFINITY;
        for phase in 0..2 {
            limit = limit.min(if parallel {
                self.phase_parallel(phase, er, state, force, stiffness)
            } else {
                self.slabs
                    .iter()
                    .skip(phase)
                    .step_by(2)
                    .map(|slab| slab.add(er, state, 0, force, stiffness))
                    .fold(Real::INFINITY, Real::min)
            });
        }
        limit
    }

    /// The slabs of one phase (0 even, 1 odd) at once on rayon's threads, each on its nodes
    /// and the next slab's.
    fn phase_parallel(
        &self,
        phase: usize,
        er: &EdgeRepulsion,
        state: (&[Vector], &[Vector], Option<&Volume>),
        force: &mut [Vector],
        stiffness: &mut [Real],
    ) -> Real {
        let mut windows = Vec::with_capacity(self.slabs.len() / 2 + 1);
        let (mut f, mut k) = (force, stiffness);
        let mut at = 0;
        for (s, slab) in self.slabs.iter().enumerate().skip(phase).step_by(2) {
            let end = self
                .slabs
                .get(s + 1)
                .map_or(slab.nodes.end, |n| n.nodes.end);
            let (_, rest_f) = std::mem::take(&mut f).split_at_mut(slab.nodes.start - at);
            let (_, rest_k) = std::mem::take(&mut k).split_at_mut(slab.nodes.start - at);
            let (own_f, rest_f) = rest_f.split_at_mut(end - slab.nodes.start);
            let (own_k, rest_k) = rest_k.split_at_mut(end - slab.nodes.start);
            windows.push((slab, own_f, own_k));
            (f, k, at) = (rest_f, rest_k, end);
        }
        windows
            .into_par_iter()
            .with_max_len(1)
            .map(|(slab, f, k)| slab.add(er, state, slab.nodes.start, f, k))
            .reduce(|| Real::INFINITY, Real::min)
    }
}

impl Slab {
    /// Adds the slab's springs, then its cells, into `force` and `stiffness`, which hold the
    /// nodes from `first` on; returns the cells' crossing limiter.
    fn add(
        &self,
        er: &EdgeRepulsion,
        (x, v, volume): (&[Vector], &[Vector], Option<&Volume>),
        first: usize,
        force: &mut [Vector],
        stiffness: &mut [Real],
    ) -> Real {
        for run in &self.springs {
            er.edges
                .add_some(run.clone(), first, (x, v), force, stiffness);
        }
        self.cells.iter().fold(Real::INFINITY, |limit, run| {
            let state = (x, v, volume);
            limit.min(er.add_cells(run.clone(), first, state, force, stiffness))
        })
    }
}
