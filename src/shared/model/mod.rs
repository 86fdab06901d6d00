//! Element force laws.
//!
//! Each model is a family of element terms, each a pure function of its nodes' positions and
//! velocities (the `pub fn`s of each file), plus the loop that sums them into node forces.
//! Every term applies its reaction to the nodes it couples, so a free body's linear momentum
//! is conserved exactly and its angular momentum too (the shape-based element up to the
//! convergence of its rotation fit; see [`RotationFit`]).
//!
//! While summing forces each loop also accumulates, per node, a Gershgorin bound on the
//! stiffness and damping it feels (`Σ_j ‖K_ij‖`, `Σ_j ‖C_ij‖`). The pipeline turns these into
//! the largest stable substep of symplectic Euler (`h < 2/ω`), recomputed every substep so that
//! the edge-repulsion barrier, which stiffens as an element compresses, is always covered.
//! The parts of these bounds that do not change with the state (all damping; the stiffness of
//! linear springs, centroid springs and shape-based cells) are summed once per node when the
//! model is built (`NodeBounds`); a step adds them with one pass over the nodes and only
//! the barrier-like terms (nonlinear springs, ER repulsion) add stiffness per term.
//!
//! # Layout and cost
//!
//! Rest data is flat, one array per quantity (struct of arrays), indexed by term: springs by
//! spring, cell terms by *slot* `cell · n + a` (the layout of [`Mesh::cell_indices`]). Cell
//! loops are compiled once per cell arity (`SIMPLEX_ARITY`, the cube arity), so a cell's
//! vertices, rest data and outputs are fixed-size arrays and the inner loops unroll without
//! bounds checks. A step allocates nothing.
//!
//! # Summing forces without races (feature `parallel`)
//!
//! Two terms that share a node would race if both added into it from different threads. With
//! the `parallel` feature a large model is evaluated in two passes instead of one loop that
//! scatters into the nodes:
//!
//! 1. **Terms write their own slots.** Every term (spring, cell) writes the contributions it
//!    makes to each of its nodes — force, and for barrier terms the stiffness bound — into
//!    its own entries of a per-term buffer (`par_iter_mut` over the buffer, zipped with the
//!    term's rest data and, for the shape-based element, with its cell's warm-start rotation).
//!    No two terms write the same entry. The crossing limiter is a `min`-reduction, which is
//!    exact in any order.
//! 2. **Nodes gather.** Each node then sums the entries that belong to it (`par_iter_mut` over
//!    the nodes), reading them through a node → (term, slot) incidence built at construction
//!    (compressed rows: springs first, then cell slots, each in increasing term order). Each
//!    node is written by one thread only.
//!
//! The gather adds a node's contributions in exactly the order the serial loop does (constant
//! bounds, then springs in spring order, then cells in cell order), and each term's
//! contribution is computed by the same function in both paths, so the parallel forces equal
//! the serial ones bit for bit, whatever the number of threads: the result is deterministic.
//!
//! Splitting costs an extra pass over the buffers and rayon's task overhead, so only models
//! whose serial evaluation costs at least [`PARALLEL_MIN_WORK`] take the parallel path, and
//! only when rayon has more than one thread; smaller meshes run the serial loop.
//!
//! A large edge-repulsion body goes by slabs of nodes instead (`slabs.rs`), on every thread
//! count, one included: its forces are the same bits whatever the number of threads, and
//! equal the serial loop's to rounding (the slabs sum in their own order).

pub mod centroid_springs;
pub mod edge_repulsion;
#[cfg(test)]
mod fixtures;
pub(crate) mod gas;
pub mod hessian;
mod implicit;
mod lanes;
mod law;
pub mod nonlinear_springs;
#[cfg(feature = "parallel")]
mod parallel;
mod plastic;
pub mod shape_matching;
#[cfg(feature = "parallel")]
mod slabs;
mod slack;
pub mod springs;
#[cfg(all(test, feature = "parallel"))]
mod tests;
pub mod volume;

#[cfg(feature = "parallel")]
pub(crate) use law::Varying;
pub(crate) use law::{ElementLaw, ImplicitTerms};
pub(crate) use slack::Slack;

pub(crate) use implicit::{Hold, Solve, StepInput, MIN_STEP_VOLUME};

use super::error::BuildError;
use super::material::{Plasticity, Resolved, Stiffness};
use super::math::{self, AngVector, Real, Rotation, Vector, SIMPLEX_ARITY};
use super::mesh::{CellKind, Mesh};

/// How the shape-based element finds its cell's rotation.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum RotationFit {
    /// The paper's update (its eq. 11–16), `n ≥ 1` times per substep, warm-started from the
    /// last substep's rotation. In 2D every `n` gives the exact angle (eq. 9).
    Iterative(usize),
    /// The rotation of the polar decomposition of `Σ r_i R0_iᵀ` (exact; the fixed point of the
    /// iteration).
    Polar,
}

/// Which velocity the shape-based element damps.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Copy, Clone, Debug, PartialEq, Eq, Default)]
pub enum ShapeDamping {
    /// Velocity relative to the cell's least-squares rigid motion (translation and spin):
    /// damps deformation only, conserves angular momentum. The default.
    #[default]
    RigidMotion,
    /// The paper's choice: velocity relative to the cell's centroid velocity. Also damps rigid
    /// spin, so a spinning free body slows down.
    Centroid,
}

/// The element model of a deformable.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum ElementModel {
    /// Damped linear springs on every vertex pair of every cell (Cooper & Maddock eq. 1, 3).
    Springs,
    /// [`ElementModel::Springs`] plus a spring from each vertex to its cell's centroid
    /// (Cooper & Maddock §4.1).
    CentroidSprings,
    /// Nonlinear springs `f = k(L0²/L − L)` on every vertex pair (Cooper & Maddock eq. 4).
    NonlinearSprings,
    /// The edge-repulsion (ER) element: edge springs plus a repulsion of each vertex from the
    /// line (2D) / plane (3D) of its opposite facet (Cooper & Maddock eq. 5, §6). Simplex cells
    /// only.
    EdgeRepulsion,
    /// The shape-based element: each cell pulled towards its rest shape rotated about its
    /// centroid.
    ShapeMatching {
        /// How the rotation is found.
        fit: RotationFit,
        /// Which velocity is damped.
        damping: ShapeDamping,
    },
}

impl ElementModel {
    /// The shape-based element with the paper's recommended 2 iterations and rigid-motion
    /// damping.
    pub const SHAPE_MATCHING: ElementModel = ElementModel::ShapeMatching {
        fit: RotationFit::Iterative(2),
        damping: ShapeDamping::RigidMotion,
    };

    /// All five models, the shape-based one with its defaults.
    pub const ALL: [ElementModel; 5] = [
        ElementModel::Springs,
        ElementModel::CentroidSprings,
        ElementModel::NonlinearSprings,
        ElementModel::EdgeRepulsion,
        ElementModel::SHAPE_MATCHING,
    ];

    /// A short kebab-case name ("springs", "edge-repulsion", ...).
    pub fn name(&self) -> &'static str {
        match self {
            ElementModel::Springs => "springs",
            ElementModel::CentroidSprings => "centroid-springs",
            ElementModel::NonlinearSprings => "nonlinear-springs",
            ElementModel::EdgeRepulsion => "edge-repulsion",
            ElementModel::ShapeMatching { .. } => "shape-matching",
        }
    }
}

/// Per-node accumulators filled by the force loops.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Debug, Default)]
pub(crate) struct Accumulator {
    /// Force on each node.
    pub force: Vec<Vector>,
    /// Gershgorin bound on the stiffness row of each node, N/m.
    pub stiffness: Vec<Real>,
    /// Gershgorin bound on the damping row of each node, N·s/m.
    pub damping: Vec<Real>,
}

impl Accumulator {
    pub fn new(n: usize) -> Self {
        Accumulator {
            force: vec![Vector::ZERO; n],
            stiffness: vec![0.0; n],
            damping: vec![0.0; n],
        }
    }

    pub fn clear(&mut self) {
        self.force.fill(Vector::ZERO);
        self.stiffness.fill(0.0);
        self.damping.fill(0.0);
    }
}

/// The parts of each node's stiffness and damping bounds that do not depend on the state,
/// summed once at build time.
#[derive(Clone, Debug)]
pub(crate) struct NodeBounds {
    pub stiffness: Vec<Real>,
    pub damping: Vec<Real>,
}

impl NodeBounds {
    fn new(nodes: usize) -> Self {
        NodeBounds {
            stiffness: vec![0.0; nodes],
            damping: vec![0.0; nodes],
        }
    }

    /// Adds the bounds into `acc` (one vectorisable pass per array).
    fn add_to(&self, acc: &mut Accumulator) {
        for (a, b) in acc.stiffness.iter_mut().zip(&self.stiffness) {
            *a += *b;
        }
        for (a, b) in acc.damping.iter_mut().zip(&self.damping) {
            *a += *b;
        }
    }
}

/// With the `parallel` feature, models whose serial force evaluation costs at least this much
/// run on rayon's threads (when rayon has more than one); smaller ones run the serial loop,
/// because the split's extra pass and rayon's task overhead (some µs per parallel loop, three
/// loops per evaluation) would cost more than a second core saves.
///
/// The cost is counted in linear-spring evaluations, each cell weighted by what it costs
/// relative to a spring (callgrind, 3D): a cell of centroid springs 5, an edge-repulsion cell
/// 20, a shape-based cell 30. The threshold, about 0.2 ms of serial work on the machine it was
/// measured on, is met by 3D lattices (`DeformableBuilder::cuboid`) from 7 nodes per edge with
/// shape matching, 8 with edge repulsion, 11 with centroid springs and 18 with springs.
pub const PARALLEL_MIN_WORK: usize = 1 << 15;

/// A deformable's element model: its terms, the constant part of its node bounds and, with
/// the `parallel` feature, the buffers of the two-pass evaluation.
#[derive(Clone, Debug)]
pub(crate) struct ModelState {
    /// The model's terms: rest data and any per-cell state.
    elements: Box<dyn ElementLaw>,
    bounds: NodeBounds,
    /// The volumetric term that sets Poisson's ratio, if the model takes one.
    volume: Option<volume::Volume>,
    /// The cells' rest shapes under plastic flow, if the body flows.
    plastic: Option<plastic::Plastic>,
    /// The gas sealed in the body's chambers, if any.
    gas: Option<gas::Chambers>,
    /// Which terms touch each node, for the implicit step (made when first needed).
    incidence: std::sync::OnceLock<Option<implicit::Incidence>>,
    #[cfg(feature = "parallel")]
    split: Option<parallel::Split>,
    /// Edge repulsion's evaluation by slabs, which replaces the split where the node numbering
    /// allows it (on every thread count, one included).
    #[cfg(feature = "parallel")]
    slabs: Option<slabs::Slabs>,
}

impl ModelState {
    pub fn build(
        model: ElementModel,
        mesh: &Mesh,
        masses: &[Real],
        params: &Resolved,
        initial_rotation: Rotation,
        plasticity: Option<Plasticity>,
    ) -> Result<Self, BuildError> {
        if let Some(p) = plasticity {
            p.validate()?;
        }
        // Poisson's ratio: the model's own terms scaled by σ, plus a volumetric term.
        let poisson = match (params.stiffness, lattice_poisson(model, mesh.kind())) {
            (Stiffness::FromMaterial, Some(lattice)) => {
                Some(volume::mapping(lattice, params.material.poisson_ratio))
            }
            _ => None,
        };
        let mut scaled = *params;
        if let Some((sigma, _)) = poisson {
            scaled.material.young_modulus *= sigma;
        }
        let params = &scaled;
        let elements: Box<dyn ElementLaw> = match model {
            ElementModel::Springs => Box::new(springs::Springs::build(
                mesh,
                masses,
                params,
                springs::MATERIAL_SCALE,
                springs::Law::Linear,
            )),
            ElementModel::CentroidSprings => Box::new(centroid_springs::CentroidSprings::build(
                mesh, masses, params,
            )),
            ElementModel::NonlinearSprings => Box::new(springs::Springs::build(
                mesh,
                masses,
                params,
                nonlinear_springs::MATERIAL_SCALE,
                springs::Law::Nonlinear,
            )),
            ElementModel::EdgeRepulsion => {
                if mesh.kind() != CellKind::Simplex {
                    return Err(BuildError::UnsupportedCells {
                        model: "edge-repulsion",
                        kind: mesh.kind().name(),
                    });
                }
                Box::new(edge_repulsion::EdgeRepulsion::build(mesh, masses, params))
            }
            ElementModel::ShapeMatching { fit, damping } => {
                if let RotationFit::Iterative(0) = fit {
                    return Err(BuildError::InvalidParameter {
                        name: "RotationFit::Iterative",
                        value: 0.0,
                        expected: "at least one iteration",
                    });
                }
                Box::new(shape_matching::ShapeMatching::build(
                    mesh,
                    params,
                    fit,
                    damping,
                    initial_rotation,
                ))
            }
        };
        if plasticity.is_some() && (!elements.flows() || mesh.kind() != CellKind::Simplex) {
            return Err(BuildError::NoPlasticity {
                model: model.name(),
                kind: mesh.kind().name(),
            });
        }
        let mut bounds = NodeBounds::new(mesh.nodes().len());
        elements.constant_bounds(&mut bounds);
        let young = params.material.young_modulus;
        let volume = poisson
            .filter(|(sigma, kappa)| kappa.abs() * young > 1e-6 * sigma * young)
            .map(|(sigma, kappa)| {
                volume::Volume::build(mesh.cell_indices(), mesh.nodes(), kappa * young / sigma)
            });
        #[cfg(feature = "parallel")]
        let split = parallel::Split::build_if_large(&*elements, mesh);
        #[cfg(feature = "parallel")]
        let slabs = match (&split, elements.edge_repulsion()) {
            (Some(_), Some(er)) => slabs::Slabs::of(er, mesh.nodes().len()),
            _ => None,
        };
        let plastic =
            plasticity.map(|p| plastic::Plastic::new(p, mesh.cell_indices(), mesh.nodes()));
        Ok(ModelState {
            volume,
            plastic,
            gas: None,
            #[cfg(feature = "parallel")]
            split: split.filter(|_| slabs.is_none()),
            #[cfg(feature = "parallel")]
            slabs,
            elements,
            bounds,
            incidence: std::sync::OnceLock::new(),
        })
    }

    /// Adds element forces at `(x, v)` into `acc`; returns the largest substep the model's
    /// own limiter allows (infinite when it has none).
    pub fn accumulate(&mut self, x: &[Vector], v: &[Vector], acc: &mut Accumulator) -> Real {
        let limit = self.accumulate_elements(x, v, acc);
        if let Some(volume) = &self.volume {
            if !self.elements.sums_volume() {
                volume.accumulate(x, acc);
            }
        }
        if let Some(gas) = &self.gas {
            gas.accumulate(x, acc);
        }
        limit
    }

    /// [`ModelState::accumulate`], its limiter exact only where it is below `cap` (s): a
    /// limiter at or above `cap` may be returned as anything at or above it. Edge repulsion
    /// then leaves out the crossing times of cells whose heights and the nodes' relative
    /// speeds bound them above `cap`.
    pub fn accumulate_capped(
        &mut self,
        x: &[Vector],
        v: &[Vector],
        acc: &mut Accumulator,
        cap: Real,
    ) -> Real {
        let Some(er) = self.elements.edge_repulsion_mut() else {
            return self.accumulate(x, v, acc);
        };
        er.crossing = Some((cap, edge_repulsion::relative_speed(v)));
        let limit = self.accumulate(x, v, acc);
        if let Some(er) = self.elements.edge_repulsion_mut() {
            er.crossing = None;
        }
        limit
    }

    /// Whether [`ModelState::accumulate_measured`] measures (on the thread count of now).
    pub fn measures_in_pass(&self) -> bool {
        #[cfg(feature = "parallel")]
        if self.split.is_some() && rayon::current_num_threads() > 1 {
            return false;
        }
        self.elements.measures_in_pass() && !self.elements.sums_volume()
    }

    /// [`ModelState::accumulate_capped`] (its limiter infinite) and
    /// [`ModelState::elastic_energy_and_ratios`] at `x`, the same bits of both, in one pass over
    /// the terms, for a model that measures in its force pass and has no limiter (springs);
    /// `None`, having added nothing, for another model or when the forces are evaluated on
    /// several threads (their energy then takes its own pass).
    pub fn accumulate_measured(
        &mut self,
        x: &[Vector],
        v: &[Vector],
        acc: &mut Accumulator,
    ) -> Option<(Real, Option<volume::Ratios>)> {
        if !self.measures_in_pass() {
            return None;
        }
        assert!(v.len() == x.len() && acc.force.len() == x.len());
        assert!(acc.stiffness.len() == x.len() && acc.damping.len() == x.len());
        self.bounds.add_to(acc);
        let elastic = self.elements.accumulate_measured(x, v, acc);
        let volume = self.volume.as_ref().map(|v| v.accumulate_measured(x, acc));
        let gas = self.gas.as_ref().map(|g| {
            g.accumulate(x, acc);
            g.energy(x)
        });
        // Summed as `elastic_energy_and_ratios` sums them.
        let energy = volume.map_or(0.0, |(e, _)| e) + elastic + gas.unwrap_or(0.0);
        Some((energy, volume.map(|(_, r)| r)))
    }

    fn accumulate_elements(&mut self, x: &[Vector], v: &[Vector], acc: &mut Accumulator) -> Real {
        #[cfg(feature = "parallel")]
        if let (Some(slabs), Some(er)) = (&self.slabs, self.elements.edge_repulsion()) {
            // On any number of threads: the slabs' order is the body's, not the threads'.
            assert!(v.len() == x.len() && acc.force.len() == x.len());
            assert!(acc.stiffness.len() == x.len() && acc.damping.len() == x.len());
            self.bounds.add_to(acc);
            let state = (x, v, self.volume.as_ref());
            return slabs.accumulate(er, state, &mut acc.force, &mut acc.stiffness);
        }
        #[cfg(feature = "parallel")]
        if let Some(split) = &mut self.split {
            if rayon::current_num_threads() > 1 {
                let volume = self.volume.as_ref();
                return split.accumulate(&mut *self.elements, volume, &self.bounds, x, v, acc);
            }
        }
        self.accumulate_serial(x, v, acc)
    }

    /// The serial loop: constant bounds, then every term adding into its nodes.
    pub(crate) fn accumulate_serial(
        &mut self,
        x: &[Vector],
        v: &[Vector],
        acc: &mut Accumulator,
    ) -> Real {
        assert!(v.len() == x.len() && acc.force.len() == x.len());
        assert!(acc.stiffness.len() == x.len() && acc.damping.len() == x.len());
        self.bounds.add_to(acc);
        self.elements.accumulate(x, v, acc, self.volume.as_ref())
    }

    /// The state the model carries from one substep to the next: the shape-based element's
    /// per-cell warm-start rotations (empty for the other models, whose terms are pure
    /// functions of the node state).
    pub fn warm_start(&self) -> &[Rotation] {
        self.elements.rotations()
    }

    /// Restores [`ModelState::warm_start`]. `Err(expected length)` if the length is wrong.
    pub fn set_warm_start(&mut self, rotations: &[Rotation]) -> Result<(), usize> {
        self.elements.set_rotations(rotations)
    }

    /// Seals gas in `chambers` (none: the body holds no gas).
    pub fn set_gas(&mut self, chambers: Vec<gas::Chamber>, nodes: usize) {
        self.gas = (!chambers.is_empty()).then(|| gas::Chambers::new(chambers, nodes));
    }

    /// The body's gas chambers (empty without gas).
    pub fn chambers(&self) -> &[gas::Chamber] {
        self.gas.as_ref().map_or(&[], |g| g.list())
    }

    /// The body's gas chambers, to refill (empty without gas).
    pub fn chambers_mut(&mut self) -> &mut [gas::Chamber] {
        self.gas.as_mut().map_or(&mut [], |g| g.list_mut())
    }

    /// The body's plastic flow, if it flows.
    pub fn plasticity(&self) -> Option<Plasticity> {
        self.plastic.as_ref().map(|p| p.params)
    }

    /// Each cell's plastic strain ([`plastic::Plastic::strains`]); empty if the body does not
    /// flow.
    pub fn plastic_strains(&self) -> Vec<Real> {
        self.plastic.as_ref().map_or(Vec::new(), |p| p.strains())
    }

    /// Each cell's rest vertices (by slot) under plastic flow; empty if the body does not
    /// flow.
    pub fn plastic_rest(&self) -> &[Vector] {
        self.plastic.as_ref().map_or(&[], |p| p.rest())
    }

    /// Restores [`ModelState::plastic_rest`] and the rest data derived from it;
    /// `Err(expected length)` if it does not fit the body.
    pub fn set_plastic_rest(&mut self, rest: &[Vector]) -> Result<(), usize> {
        let Some(plastic) = &mut self.plastic else {
            return if rest.is_empty() { Ok(()) } else { Err(0) };
        };
        plastic.set_rest(rest)?;
        // Only the cells that flowed: the others' rest data is the built one, bit for bit.
        let flowed = plastic.flowed();
        self.derive_rest(&flowed);
        Ok(())
    }

    /// Derives the rest data of the cells `changed` from their rest shapes.
    fn derive_rest(&mut self, changed: &[u32]) {
        let Some(plastic) = &self.plastic else {
            return;
        };
        self.elements
            .set_rest(plastic.cells(), plastic.rest(), changed);
        if let Some(volume) = &mut self.volume {
            volume.set_rest(plastic.rest(), changed);
        }
    }

    /// Flows the cells strained past yield at `x` over a step of `dt` (`plastic.rs`); returns
    /// whether any cell flowed, and the elastic energy the flow released (`None` if none
    /// flowed or the flow was undone). A flow that would raise the energy (a cell flowing
    /// along one direction while the volumetric term holds its volume, near ν = 0.5; or edges
    /// shared with cells that did not flow) is undone: flow creates no energy. An undone flow
    /// brings back the cells' rest shapes, but the rest data derived from them again may
    /// differ in the last bit (a spring's rest length is the mean over the cells sharing it).
    pub fn flow(&mut self, x: &[Vector], dt: Real) -> (bool, Option<Real>) {
        let Some(plastic) = self.plastic.as_mut() else {
            return (false, None);
        };
        let changed = plastic.flow(x, dt);
        if changed.is_empty() {
            return (false, None);
        }
        // The rest data is still derived from the shapes before the flow.
        let before = elastic_energy(&*self.elements, self.volume.as_ref(), None, x);
        self.derive_rest(&changed);
        let released = before - elastic_energy(&*self.elements, self.volume.as_ref(), None, x);
        if released < 0.0 {
            if let Some(plastic) = &mut self.plastic {
                plastic.undo();
            }
            self.derive_rest(&changed);
            return (true, None);
        }
        (true, Some(released))
    }

    /// Elastic (stored) energy at `x`, the gas's included.
    pub fn elastic_energy(&self, x: &[Vector]) -> Real {
        elastic_energy(&*self.elements, self.volume.as_ref(), self.gas.as_ref(), x)
    }

    /// [`ModelState::elastic_energy`] at `x` (the same bits), with the cells' volume ratios
    /// from the volumetric term's pass when the model has one (`None` without).
    pub fn elastic_energy_and_ratios(&self, x: &[Vector]) -> (Real, Option<volume::Ratios>) {
        let Some(v) = &self.volume else {
            return (self.elastic_energy(x), None);
        };
        let (energy, ratios) = super::threads::chunked_fold(
            v.cells().len() / SIMPLEX_ARITY,
            |cells| v.energy_and_ratios(x, cells),
            volume::both,
        )
        .unwrap_or((0.0, volume::Ratios::NONE));
        let gas = self.gas.as_ref().map_or(0.0, |g| g.energy(x));
        (energy + self.elements.energy(x) + gas, Some(ratios))
    }
}

/// `x` squashed to `height` of its height and sheared by `shear` along the first axis (test
/// states that load the barriers and put the feet off-centre).
#[cfg(test)]
pub(crate) fn squashed(x: &[Vector], height: Real, shear: Real) -> Vec<Vector> {
    x.iter()
        .map(|p| {
            let mut q = *p;
            q[1] *= height;
            q[0] += shear * p[1];
            q
        })
        .collect()
}

/// Elastic (stored) energy of `elements`, the volumetric term and the gas at `x`, summed by
/// [`threads::chunked_sum`] (on rayon's threads for a large body, the same bits whatever the
/// thread count).
fn elastic_energy(
    elements: &dyn ElementLaw,
    volume: Option<&volume::Volume>,
    gas: Option<&gas::Chambers>,
    x: &[Vector],
) -> Real {
    use super::threads::chunked_sum;
    volume.map_or(0.0, |v| {
        chunked_sum(v.cells().len() / SIMPLEX_ARITY, |r| v.energy_of(x, r))
    }) + elements.energy(x)
        + gas.map_or(0.0, |g| g.energy(x))
}

/// The Poisson's ratio of a model's lattice (`Mesh::cuboid`'s mirrored Kuhn simplices, small
/// strain along an axis, Cauchy–Born: each model's docs), for the models that take Poisson's
/// ratio from their material: springs and nonlinear springs `5/31` (3D), `1/5` (2D); edge
/// repulsion `7/47`, `1/5`; shape matching `0.125` (measured: `tests/shared/poisson.rs`), `1/7`;
/// on simplex cells only.
pub fn lattice_poisson(model: ElementModel, kind: CellKind) -> Option<Real> {
    if kind != CellKind::Simplex {
        return None;
    }
    let three = super::math::DIM == 3;
    match model {
        ElementModel::Springs | ElementModel::NonlinearSprings => {
            Some(if three { 5.0 / 31.0 } else { 0.2 })
        }
        ElementModel::EdgeRepulsion => Some(if three { 7.0 / 47.0 } else { 0.2 }),
        ElementModel::ShapeMatching { .. } => Some(if three { 0.125 } else { 1.0 / 7.0 }),
        ElementModel::CentroidSprings => None,
    }
}

/// The cost of a serial force evaluation of `elements` in linear-spring evaluations (see
/// [`PARALLEL_MIN_WORK`]).
#[cfg(feature = "parallel")]
fn work(elements: &dyn ElementLaw, cells: usize) -> usize {
    elements.edge_springs().map_or(0, |s| s.pairs.len()) + elements.cost_per_cell() * cells
}

// The nonlinear springs' constant is half the linear springs' (their rest stiffness is 2k).
const _: () = assert!(nonlinear_springs::MATERIAL_SCALE == 0.5 * springs::MATERIAL_SCALE);

/// Reduced mass of two nodes.
#[inline]
pub(crate) fn reduced_mass(a: Real, b: Real) -> Real {
    a * b / (a + b)
}

/// Largest stable symplectic-Euler substeps for the given per-node bounds (the masses and the
/// Gershgorin stiffness and damping bounds the force loops accumulate): the smallest over the
/// nodes of `2/ω (√(1+ζ²) − ζ)`, `ω² = stiffness/m`, `ζ = damping / (2 √(stiffness · m))`,
/// first with each node's bounds divided by the body's [`Slack`] (the estimate), then as they
/// are (certain: the bounds are rigorous). Returns `(estimate, certain)`.
pub(crate) fn stable_substeps(
    masses: &[Real],
    stiffness: &[Real],
    damping: &[Real],
    slack: Slack,
) -> (Real, Real) {
    let node = |m: Real, s: Real, d: Real| {
        if s > 0.0 {
            let omega = (s / m).sqrt();
            let zeta = d / (2.0 * (s * m).sqrt());
            2.0 / omega * ((1.0 + zeta * zeta).sqrt() - zeta)
        } else if d > 0.0 {
            2.0 * m / d
        } else {
            Real::INFINITY
        }
    };
    // The least over fixed chunks (on rayon's threads for a large body): a minimum is exact
    // in any order. Without slack (both factors 1, dividing by which is exact) the estimate
    // is the certain bound, bit for bit, and is not evaluated twice.
    let count = masses.len().min(stiffness.len()).min(damping.len());
    let certain = super::threads::least(count, |i| node(masses[i], stiffness[i], damping[i]));
    let estimate = if slack.stiffness == 1.0 && slack.damping == 1.0 {
        certain
    } else {
        super::threads::least(count, |i| {
            let (s, d) = (stiffness[i] / slack.stiffness, damping[i] / slack.damping);
            node(masses[i], s, d)
        })
    };
    (estimate, certain)
}

/// The substep under `safety` from the bounds of [`stable_substeps`]: the estimate times
/// `safety`, never beyond the certain bound; without `calibrated`, the certain bound times
/// `safety` (`docs/ARCHITECTURE.md` §4.1).
pub(crate) fn substep_under(estimate: Real, certain: Real, safety: Real, calibrated: bool) -> Real {
    if calibrated {
        (safety * estimate).min(certain)
    } else {
        safety * certain
    }
}

/// A body's motion about its centre of mass: the centre's velocity, each node's offset from
/// the centre, and the angular momentum about it.
pub(crate) struct Motion {
    pub velocity: Vector,
    pub r: Vec<Vector>,
    pub momentum: AngVector,
}

impl Motion {
    /// Of nodes at `x0` moving at `v0`; `None` without mass.
    pub fn of(x0: &[Vector], v0: &[Vector], masses: &[Real]) -> Option<Self> {
        let mass: Real = masses.iter().sum();
        if mass.is_nan() || mass <= 0.0 {
            return None;
        }
        let centre = x0.iter().zip(masses).map(|(p, m)| *p * *m).sum::<Vector>() / mass;
        let velocity = v0.iter().zip(masses).map(|(v, m)| *v * *m).sum::<Vector>() / mass;
        let r: Vec<Vector> = x0.iter().map(|p| *p - centre).collect();
        let momentum = r
            .iter()
            .zip(v0)
            .zip(masses)
            .map(|((r, v), m)| math::cross(*r, (*v - velocity) * *m))
            .fold(math::ANG_ZERO, |a, b| a + b);
        Some(Motion {
            velocity,
            r,
            momentum,
        })
    }
}
