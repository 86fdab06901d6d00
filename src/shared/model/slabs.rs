//! Edge repulsion's explicit forces by slabs of nodes (feature `parallel`; see
//! [`Slabs`]), in place of the two-pass evaluation of [`super::parallel`].

use std::ops::Range;

use rayon::prelude::*;

use super::super::math::{Real, Vector, SIMPLEX_ARITY};
use super::edge_repulsion::EdgeRepulsion;
use super::volume::Volume;

/// Edge repulsion's evaluation by [`SLABS`] slabs of consecutive nodes, each wider than any
/// term's span of node indices, so that every spring and cell lies in one slab or across two
/// neighbours. Three phases, one after the other: the terms inside each slab, all slabs at
/// once; those across the boundaries after even slabs; those across the others. The groups of
/// a phase own disjoint runs of nodes and add straight into them (no buffers, no gather), each
/// in its own term order, so a node sums its terms in the same order on any number of
/// threads: the same bits on one thread as on many (the serial loop's order differs: other
/// bits, the same forces to rounding). On a lattice numbered layer by layer, one layer of
/// cells in sixteen (res 17) runs alone.
#[derive(Clone, Debug)]
pub(crate) struct Slabs {
    phases: [Vec<Group>; 3],
}

/// Slabs of edge repulsion's explicit evaluation: few, so that few terms cross a boundary.
const SLABS: usize = 4;

/// The terms of one group (runs of consecutive springs and cells, in order), and the run of
/// nodes they touch.
#[derive(Clone, Debug, Default)]
struct Group {
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
    /// The slabs of `er` (on `nodes` nodes), if its numbering makes them.
    pub fn of(er: &EdgeRepulsion, nodes: usize) -> Option<Self> {
        let span = er
            .cells
            .chunks_exact(SIMPLEX_ARITY)
            .map(|c| (c.iter().max().unwrap() - c.iter().min().unwrap()) as usize)
            .chain(er.edges.pairs.iter().map(|[i, j]| i.abs_diff(*j) as usize))
            .max()
            .unwrap_or(0);
        let size = nodes.div_ceil(SLABS);
        if size <= span {
            return None;
        }
        let count = nodes.div_ceil(size);
        let run = |first: usize, slabs: usize| first * size..((first + slabs) * size).min(nodes);
        let group = |nodes| Group {
            nodes,
            ..Default::default()
        };
        // Per slab, the terms inside it and those across the boundary after it.
        let mut inside: Vec<Group> = (0..count).map(|s| group(run(s, 1))).collect();
        let mut across: Vec<Group> = (0..count - 1).map(|s| group(run(s, 2))).collect();
        let place = |ids: &[u32]| {
            let (low, high) = ids.iter().fold((usize::MAX, 0), |(l, h), &i| {
                (l.min(i as usize / size), h.max(i as usize / size))
            });
            match high - low {
                0 => Some((low, false)),
                1 => Some((low, true)),
                _ => None,
            }
        };
        for (s, pair) in er.edges.pairs.iter().enumerate() {
            let (slab, boundary) = place(pair)?;
            let groups = if boundary { &mut across } else { &mut inside };
            push_run(&mut groups[slab].springs, s);
        }
        for (c, ids) in er.cells.chunks_exact(SIMPLEX_ARITY).enumerate() {
            let (slab, boundary) = place(ids)?;
            let groups = if boundary { &mut across } else { &mut inside };
            push_run(&mut groups[slab].cells, c);
        }
        let (even, odd): (Vec<_>, Vec<_>) = across
            .into_iter()
            .enumerate()
            .partition(|(s, _)| s % 2 == 0);
        let strip = |v: Vec<(usize, Group)>| v.into_iter().map(|(_, g)| g).collect();
        Some(Slabs {
            phases: [inside, strip(even), strip(odd)],
        })
    }

    /// Adds `er`'s forces and stiffness rows (with its `volume` term) at `(x, v)` into `force`
    /// and `stiffness`; returns the crossing limiter.
    pub fn accumulate(
        &self,
        er: &EdgeRepulsion,
        (x, v, volume): (&[Vector], &[Vector], Option<&Volume>),
        force: &mut [Vector],
        stiffness: &mut [Real],
    ) -> Real {
        let mut limit = Real::INFINITY;
        for phase in &self.phases {
            // Each group's own nodes (the groups are in node order and do not overlap).
            let mut parts = Vec::with_capacity(phase.len());
            let (mut f, mut k, mut at) = (&mut force[..], &mut stiffness[..], 0);
            for g in phase {
                let (_, rest_f) = std::mem::take(&mut f).split_at_mut(g.nodes.start - at);
                let (_, rest_k) = std::mem::take(&mut k).split_at_mut(g.nodes.start - at);
                let (own_f, rest_f) = rest_f.split_at_mut(g.nodes.len());
                let (own_k, rest_k) = rest_k.split_at_mut(g.nodes.len());
                parts.push((g, own_f, own_k));
                (f, k, at) = (rest_f, rest_k, g.nodes.end);
            }
            let phase_limit = parts
                .into_par_iter()
                .with_max_len(1)
                .map(|(g, f, k)| {
                    let first = g.nodes.start;
                    for run in &g.springs {
                        er.edges.add_some(run.clone(), first, (x, v), f, k);
                    }
                    g.cells.iter().fold(Real::INFINITY, |limit, run| {
                        let state = (x, v, volume);
                        limit.min(er.add_cells(run.clone(), first, state, f, k))
                    })
                })
                .reduce(|| Real::INFINITY, Real::min);
            limit = limit.min(phase_limit);
        }
        limit
    }
}
