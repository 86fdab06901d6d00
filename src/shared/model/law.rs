//! The protocol every element model implements: [`ElementLaw`].
//!
//! A model is built from its mesh and material (each model's `build`), then asked for its
//! forces and stiffness bounds (the serial loop, and with the `parallel` feature its terms
//! written one entry each for the two-pass evaluation), its elastic energy, the bounds that do
//! not change with the state, and the per-cell state it carries between substeps (shape
//! matching's warm-start rotations). For the implicit step a model names the term families it
//! is made of ([`ImplicitTerms`]): the Vertex Block Descent sweeps (`implicit.rs`) and the
//! Newton step over the whole body (`implicit/global.rs`) sum each family's gradient and
//! block at a node, so a model made of existing families needs no code there, and a model
//! that names none keeps the explicit step.

use super::super::math::{Real, Rotation, Vector};
use super::edge_repulsion::EdgeRepulsion;
use super::shape_matching::ShapeMatching;
use super::springs::Springs;
use super::volume::Volume;
use super::{Accumulator, NodeBounds};

/// The term families of a model that the implicit step sums at a node (the volumetric term,
/// which any model may carry, is the step's own).
#[derive(Copy, Clone, Default)]
pub(crate) struct ImplicitTerms<'a> {
    /// Springs on node pairs (the edges of a cell), linear or nonlinear, with their dashpots.
    pub springs: Option<&'a Springs>,
    /// Edge repulsion's repulsions of each vertex from its opposite facet.
    pub repulsion: Option<&'a EdgeRepulsion>,
    /// Shape-matched cells, their rotations held through the step.
    pub shape: Option<&'a ShapeMatching>,
}

/// Which entries of the two-pass evaluation (`parallel.rs`) carry a stiffness bound that
/// changes with the state.
#[cfg(feature = "parallel")]
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(crate) enum Varying {
    /// Every entry, springs first (nonlinear springs).
    Springs,
    /// The cell slots (repulsions, shape-matched cells turning).
    Cells,
    /// None: all of the model's bounds are constant.
    Nothing,
}

/// One element model's rest data and the per-cell state it carries, and what the pipeline
/// asks of it.
pub(crate) trait ElementLaw: std::fmt::Debug + Send + Sync {
    /// A copy of the model (a body's state is cloned for rollbacks and measurements).
    fn boxed_clone(&self) -> Box<dyn ElementLaw>;

    /// Adds the model's forces at `(x, v)` and its state-dependent stiffness bounds into
    /// `acc`, term by term in a fixed order; returns the largest substep its limiter allows
    /// (infinite without one). `volume` is the body's volumetric term, for a model that
    /// evaluates it in its own pass over the cells ([`ElementLaw::sums_volume`]).
    fn accumulate(
        &mut self,
        x: &[Vector],
        v: &[Vector],
        acc: &mut Accumulator,
        volume: Option<&Volume>,
    ) -> Real;

    /// Whether [`ElementLaw::accumulate`] evaluates the volumetric term (otherwise it takes
    /// its own pass).
    fn sums_volume(&self) -> bool {
        false
    }

    /// The elastic energy at `x`, without the volumetric term (summed in fixed chunks: the
    /// same bits on any thread count).
    fn energy(&self, x: &[Vector]) -> Real;

    /// Whether [`ElementLaw::accumulate_measured`] measures the energy in the force pass
    /// itself (its default takes a second pass).
    fn measures_in_pass(&self) -> bool {
        false
    }

    /// [`ElementLaw::accumulate`] and [`ElementLaw::energy`] at `x` (the same bits of both),
    /// for a model whose forces take no volumetric term; returns the energy. The limiter is
    /// not measured: only a model without one answers [`ElementLaw::measures_in_pass`].
    fn accumulate_measured(&mut self, x: &[Vector], v: &[Vector], acc: &mut Accumulator) -> Real {
        self.accumulate(x, v, acc, None);
        self.energy(x)
    }

    /// Adds every term's state-independent stiffness and damping bounds into `bounds`.
    fn constant_bounds(&self, bounds: &mut NodeBounds);

    /// The per-cell state carried from one substep to the next (shape matching's warm-start
    /// rotations; empty for a model whose terms are pure functions of the node state).
    fn rotations(&self) -> &[Rotation] {
        &[]
    }

    /// Restores [`ElementLaw::rotations`]; `Err(expected length)` if the length is wrong.
    fn set_rotations(&mut self, rotations: &[Rotation]) -> Result<(), usize> {
        if rotations.is_empty() {
            Ok(())
        } else {
            Err(0)
        }
    }

    /// Whether plastic flow reaches this model's rest data ([`ElementLaw::set_rest`]): a body
    /// of a model that does not flow cannot be built with plasticity.
    fn flows(&self) -> bool {
        false
    }

    /// Derives the rest data of the cells `changed` (in order) from every cell's rest
    /// vertices `rest` (by slot; `cells` their node indices), after plastic flow
    /// (`plastic.rs`); only models that [flow](ElementLaw::flows) are asked.
    fn set_rest(&mut self, cells: &[u32], rest: &[Vector], changed: &[u32]) {
        let _ = (cells, rest, changed);
    }

    /// The term families the implicit step sums for this model; `None`: the model keeps the
    /// explicit step.
    fn implicit_terms(&self) -> Option<ImplicitTerms<'_>> {
        None
    }

    /// Whether the implicit step's energy is convex (its rotations held): only then does the
    /// step take contacts between bodies as terms of it.
    fn convex_implicit(&self) -> bool {
        false
    }

    /// The shape-matched cells, whose rotations the implicit step refits and keeps.
    fn shape_mut(&mut self) -> Option<&mut ShapeMatching> {
        None
    }

    /// The edge-repulsion terms, for their evaluation by slabs of nodes (`slabs.rs`).
    #[cfg(any(test, feature = "parallel"))]
    fn edge_repulsion(&self) -> Option<&EdgeRepulsion> {
        None
    }

    /// The edge-repulsion terms, to set up their next evaluation.
    fn edge_repulsion_mut(&mut self) -> Option<&mut EdgeRepulsion> {
        None
    }

    /// The springs on node pairs, for the two-pass evaluation's spring entries.
    #[cfg(feature = "parallel")]
    fn edge_springs(&self) -> Option<&Springs>;

    /// The cost of a cell's terms in linear-spring evaluations (`PARALLEL_MIN_WORK`).
    #[cfg(feature = "parallel")]
    fn cost_per_cell(&self) -> usize;

    /// Whether the two-pass evaluation gives every cell slot an entry.
    #[cfg(feature = "parallel")]
    fn cell_slots(&self) -> bool {
        true
    }

    /// Which entries' stiffness bounds change with the state.
    #[cfg(feature = "parallel")]
    fn varying(&self) -> Varying;

    /// The first pass of the two-pass evaluation at `state` (positions, velocities): each
    /// spring's force into `spring_force`, each cell slot's into `slot_force`, the varying
    /// stiffness bounds into `stiffness` (entries from the first varying one,
    /// [`ElementLaw::varying`]); returns the limiter.
    #[cfg(feature = "parallel")]
    fn evaluate(
        &mut self,
        state: (&[Vector], &[Vector]),
        spring_force: &mut [Vector],
        slot_force: &mut [Vector],
        stiffness: &mut [Real],
        volume: Option<&Volume>,
    ) -> Real;
}

impl Clone for Box<dyn ElementLaw> {
    fn clone(&self) -> Self {
        self.boxed_clone()
    }
}
