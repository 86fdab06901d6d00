//! The two-pass evaluation of feature `parallel` (see the module docs of [`super`]): terms
//! write their per-node contributions into their own buffer entries, then every node gathers
//! its entries through a precomputed incidence, in the serial loop's order.

use rayon::prelude::*;

use super::super::math::{Real, Vector};
use super::super::mesh::Mesh;
use super::volume::Volume;
use super::{Accumulator, ElementLaw, NodeBounds, Varying, PARALLEL_MIN_WORK};

/// Springs (and nodes) per rayon task: enough work per task that splitting costs little,
/// few enough that the threads get several tasks each on the meshes that split.
pub(crate) const TERMS_PER_TASK: usize = 512;

/// Cells per rayon task (a cell costs several springs).
pub(crate) const CELLS_PER_TASK: usize = 128;

/// A node → entries incidence in compressed rows: the entries of node `i` are
/// `entries[start[i]..start[i + 1]]`, in increasing order.
#[derive(Clone, Debug, Default)]
struct Incidence {
    start: Vec<u32>,
    entries: Vec<u32>,
}

impl Incidence {
    /// The incidence of `count` entries, entry `e` belonging to node `node_of(e)`.
    fn build(nodes: usize, count: usize, node_of: impl Fn(usize) -> usize) -> Self {
        let mut start = vec![0u32; nodes + 1];
        for e in 0..count {
            start[node_of(e) + 1] += 1;
        }
        for i in 0..nodes {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut entries = vec![0u32; count];
        for e in 0..count {
            let i = node_of(e);
            entries[fill[i] as usize] = e as u32;
            fill[i] += 1;
        }
        Incidence { start, entries }
    }

    #[inline]
    fn of(&self, node: usize) -> &[u32] {
        &self.entries[self.start[node] as usize..self.start[node + 1] as usize]
    }
}

/// The buffers and incidence of a model evaluated in two passes.
///
/// Every contribution of a term to one of its nodes is an *entry*: spring `s` has entries
/// `2s` (its first node, `+f`) and `2s + 1` (its second, `−f`); after the `2S` spring entries
/// come the cell slots, `2S + cell · n + a`. Entries are numbered in the serial loop's order,
/// so summing a node's entries in increasing order repeats the serial sums exactly. A spring
/// stores its force once (`force[s]`, the second node subtracts it), a slot at `S + slot`.
#[derive(Clone, Debug)]
pub(crate) struct Split {
    /// Node → its entries.
    nodes: Incidence,
    /// Number of spring entries (`2S`).
    spring_entries: usize,
    /// The force of each spring, then of each cell slot.
    force: Vec<Vector>,
    /// The stiffness row bound of entries `stiffness_from..`, for the terms whose bound
    /// changes with the state: nonlinear springs (`stiffness_from = 0`), the repulsions of the
    /// edge-repulsion element and the shape-matching cells' turning (the cell slots); empty
    /// for the other models.
    stiffness: Vec<Real>,
    stiffness_from: usize,
}

impl Split {
    /// The split evaluation of `elements` when the model costs enough to gain from it
    /// ([`PARALLEL_MIN_WORK`]).
    pub fn build_if_large(elements: &dyn ElementLaw, mesh: &Mesh) -> Option<Self> {
        (super::work(elements, mesh.num_cells()) >= PARALLEL_MIN_WORK)
            .then(|| Split::build(elements, mesh))
    }

    /// The split evaluation of `elements` (buffers and incidence).
    pub fn build(elements: &dyn ElementLaw, mesh: &Mesh) -> Self {
        let cells = mesh.cell_indices();
        let springs = elements.edge_springs();
        let spring_entries = 2 * springs.map_or(0, |s| s.pairs.len());
        let slots = if elements.cell_slots() {
            cells.len()
        } else {
            0
        };
        let entries = spring_entries + slots;
        let nodes = Incidence::build(mesh.nodes().len(), entries, |e| match springs {
            Some(s) if e < spring_entries => s.pairs[e >> 1][e & 1] as usize,
            _ => cells[e - spring_entries] as usize,
        });
        let stiffness_from = match elements.varying() {
            Varying::Springs => 0,
            Varying::Cells => spring_entries,
            Varying::Nothing => entries,
        };
        Split {
            nodes,
            spring_entries,
            force: vec![Vector::ZERO; entries - spring_entries / 2],
            stiffness: vec![0.0; entries - stiffness_from],
            stiffness_from,
        }
    }

    /// Evaluates every term into the buffers, then gathers them into `acc` together with the
    /// constant `bounds`. Returns the model's limiter.
    pub fn accumulate(
        &mut self,
        elements: &mut dyn ElementLaw,
        volume: Option<&Volume>,
        bounds: &NodeBounds,
        x: &[Vector],
        v: &[Vector],
        acc: &mut Accumulator,
    ) -> Real {
        assert!(v.len() == x.len() && acc.force.len() == x.len());
        assert!(acc.stiffness.len() == x.len() && acc.damping.len() == x.len());
        let (spring_force, slot_force) = self.force.split_at_mut(self.spring_entries / 2);
        let stiffness = &mut self.stiffness;
        let limit = elements.evaluate((x, v), spring_force, slot_force, stiffness, volume);
        self.gather(bounds, acc);
        limit
    }

    /// Every node sums its entries, in the order the serial loop adds them: constant bounds,
    /// then springs in spring order, then cell slots in cell order.
    fn gather(&self, bounds: &NodeBounds, acc: &mut Accumulator) {
        const CHUNK: usize = TERMS_PER_TASK;
        let out = acc
            .force
            .par_chunks_mut(CHUNK)
            .zip(acc.stiffness.par_chunks_mut(CHUNK));
        out.zip(acc.damping.par_chunks_mut(CHUNK))
            .enumerate()
            .for_each(|(t, ((force, stiffness), damping))| {
                let first = t * CHUNK;
                let constant = bounds.stiffness[first..]
                    .iter()
                    .zip(&bounds.damping[first..]);
                let out = force.iter_mut().zip(stiffness).zip(damping);
                for (a, (((f, k), c), (k_const, c_const))) in out.zip(constant).enumerate() {
                    let entries = self.nodes.of(first + a);
                    let springs = self.spring_entries;
                    let cells = entries.partition_point(|&e| (e as usize) < springs);
                    let mut force = *f;
                    for &e in &entries[..cells] {
                        let spring = self.force[e as usize >> 1];
                        if e & 1 == 0 {
                            force += spring;
                        } else {
                            force -= spring;
                        }
                    }
                    for &e in &entries[cells..] {
                        force += self.force[e as usize - springs / 2];
                    }
                    *f = force;
                    let mut stiffness = *k + *k_const;
                    if !self.stiffness.is_empty() {
                        let from = self.stiffness_from;
                        let varying = entries.partition_point(|&e| (e as usize) < from);
                        for &e in &entries[varying..] {
                            stiffness += self.stiffness[e as usize - from];
                        }
                    }
                    *k = stiffness;
                    *c += *c_const;
                }
            });
    }
}
