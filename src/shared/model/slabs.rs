//! Edge repulsion's explicit forces on several threads by slabs of nodes (feature
//! `parallel`), in place of the two-pass evaluation of [`super::parallel`].
//!
//! The nodes are cut into as many slabs of consecutive nodes as rayon has threads. Each slab
//! evaluates every spring and cell that touches it, in the serial loop's order, and adds only
//! the contributions to its own nodes: a term across a boundary is evaluated once per slab it
//! touches. Each node then sums exactly the terms, values and order of the serial loop, so the
//! forces are the serial loop's bit for bit on any number of threads, with no buffers and no
//! gather (their writes and waits cost about 0.4 ms of the 1.76 ms of a res-17 cube's kernel
//! on 2 threads). The price is the terms across the boundaries, evaluated twice: on a lattice
//! numbered layer by layer, one layer of cells in sixteen at res 17 on 2 threads.

use std::ops::Range;

use rayon::prelude::*;

use super::super::math::{Real, Vector, SIMPLEX_ARITY};
use super::edge_repulsion::EdgeRepulsion;
use super::volume::Volume;

/// Nodes of a slab, at least, per node-index span of a term: a slab's terms across its
/// boundaries (evaluated twice) are then at most about a quarter of its own.
const SPANS_PER_SLAB: usize = 4;

/// The slabs of one thread count.
#[derive(Clone, Debug)]
pub(crate) struct Slabs {
    slabs: Vec<Slab>,
}

/// The terms that touch one slab (runs of consecutive springs and cells, in order), and its
/// nodes.
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
    /// `count` slabs of `er` (on `nodes` nodes), or fewer if they would be thin against the
    /// terms' span of node indices; `None` if fewer than two.
    pub fn of(er: &EdgeRepulsion, nodes: usize, count: usize) -> Option<Self> {
        let span = er
            .cells
            .chunks_exact(SIMPLEX_ARITY)
            .map(|c| (c.iter().max().unwrap() - c.iter().min().unwrap()) as usize)
            .chain(er.edges.pairs.iter().map(|[i, j]| i.abs_diff(*j) as usize))
            .max()
            .unwrap_or(0);
        let count = count.min(nodes / (SPANS_PER_SLAB * (span + 1)));
        if count < 2 {
            return None;
        }
        let size = nodes.div_ceil(count);
        let mut slabs: Vec<Slab> = (0..nodes.div_ceil(size))
            .map(|s| Slab {
                nodes: s * size..((s + 1) * size).min(nodes),
                ..Default::default()
            })
            .collect();
        // Each term goes to every slab from its lowest node's to its highest node's.
        let touched = |ids: &[u32]| {
            let (low, high) = ids.iter().fold((usize::MAX, 0), |(l, h), &i| {
                (l.min(i as usize), h.max(i as usize))
            });
            low / size..=high / size
        };
        for (t, pair) in er.edges.pairs.iter().enumerate() {
            for s in touched(pair) {
                push_run(&mut slabs[s].springs, t);
            }
        }
        for (c, ids) in er.cells.chunks_exact(SIMPLEX_ARITY).enumerate() {
            for s in touched(ids) {
                push_run(&mut slabs[s].cells, c);
            }
        }
        Some(Slabs { slabs })
    }

    /// How many slabs.
    pub fn count(&self) -> usize {
        self.slabs.len()
    }

    /// Adds `er`'s forces and stiffness rows (with its `volume` term) at `(x, v)` into `force`
    /// and `stiffness`, as [`EdgeRepulsion::accumulate`] does; returns the crossing limiter.
    pub fn accumulate(
        &self,
        er: &EdgeRepulsion,
        (x, v, volume): (&[Vector], &[Vector], Option<&Volume>),
        force: &mut [Vector],
        stiffness: &mut [Real],
    ) -> Real {
        // Each slab's own nodes (the slabs are consecutive and cover every node).
        let mut parts = Vec::with_capacity(self.slabs.len());
        let (mut f, mut k) = (force, stiffness);
        for slab in &self.slabs {
            let (own_f, rest_f) = std::mem::take(&mut f).split_at_mut(slab.nodes.len());
            let (own_k, rest_k) = std::mem::take(&mut k).split_at_mut(slab.nodes.len());
            parts.push((slab, own_f, own_k));
            (f, k) = (rest_f, rest_k);
        }
        parts
            .into_par_iter()
            .with_max_len(1)
            .map(|(slab, f, k)| {
                let first = slab.nodes.start;
                for run in &slab.springs {
                    er.edges.add_some(run.clone(), first, (x, v), f, k);
                }
                slab.cells.iter().fold(Real::INFINITY, |limit, run| {
                    let state = (x, v, volume);
                    limit.min(er.add_cells(run.clone(), first, state, f, k))
                })
            })
            .reduce(|| Real::INFINITY, Real::min)
    }
}
