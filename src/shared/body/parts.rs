//! The component groups a [`Deformable`](super::Deformable) is made of, as rapier groups a
//! `RigidBody`'s: what it is made of (fixed after build), its state, the step's working
//! buffers, whether it is simulated, and what the last step found.

use std::sync::OnceLock;

use super::super::contact::soft::NearFacets;
use super::super::contact::soft_terms::Memory;
use super::super::contact::ContactPoint;
use super::super::integrator::MidpointState;
use super::super::material::Resolved;
use super::super::math::{Real, Vector, DIM, FACET_ARITY};
use super::super::mesh::Mesh;
use super::super::model::volume::Ratios;
use super::super::model::{Accumulator, ElementModel, ModelState, Slack};
use super::super::rapier::geometry::ColliderHandle;
use super::super::report::DeformableReport;
use super::super::set::DeformableHandle;

/// What the body is made of: the rest mesh, the element model, the material and the lumped
/// node masses. Fixed after build.
#[derive(Clone, Debug)]
pub(crate) struct Rest {
    pub mesh: Mesh,
    pub model: ElementModel,
    pub params: Resolved,
    /// Lumped node masses: each cell's mass shared equally by its vertices.
    pub masses: Vec<Real>,
    /// Their inverses.
    pub inv_masses: Vec<Real>,
    /// The facets each surface node leaves alone in self contact, made when first needed.
    near_facets: OnceLock<NearFacets>,
    /// The surface's edges (the boundary facets' node pairs), each once, made when first
    /// needed.
    surface_edges: OnceLock<Vec<[u32; 2]>>,
    /// The interior faces, found when a tearing body first checks them.
    pub(super) faces: OnceLock<super::tear::Faces>,
    /// How far the node bounds overestimate the body's highest frequencies, measured when
    /// first needed (a pure function of the rest mesh, model and material).
    slack: OnceLock<Slack>,
}

impl Rest {
    /// Lumps the masses. The builder and a snapshot both come here, so a restored body's
    /// masses are the built body's bit for bit.
    pub fn new(mesh: Mesh, model: ElementModel, params: Resolved) -> Rest {
        let arity = mesh.kind().arity() as Real;
        let mut masses = vec![0.0; mesh.nodes().len()];
        for (cell, ids) in mesh.cells().enumerate() {
            let m = params.material.density * mesh.rest_volumes()[cell] / arity;
            for &i in ids {
                masses[i as usize] += m;
            }
        }
        let inv_masses = masses.iter().map(|m| 1.0 / m).collect();
        Rest {
            mesh,
            model,
            params,
            masses,
            inv_masses,
            near_facets: OnceLock::new(),
            surface_edges: OnceLock::new(),
            faces: OnceLock::new(),
            slack: OnceLock::new(),
        }
    }

    /// The slack of the stability bounds of `elements` (this body's model state), measured on
    /// first use.
    pub fn slack(&self, elements: &ModelState) -> Slack {
        *self.slack.get_or_init(|| {
            // The smallest cell's size: no cell is strained more than the probe's strain.
            let smallest = self
                .mesh
                .rest_volumes()
                .iter()
                .copied()
                .fold(Real::INFINITY, Real::min);
            let cell_size = smallest.powf(1.0 / DIM as Real);
            Slack::measure(elements, self.mesh.nodes(), &self.masses, cell_size)
        })
    }

    /// Takes `other`'s slack, if measured: a torn body's cells are its own, and measuring
    /// again (about 60 force evaluations) at every step of a growing crack would cost more
    /// than the steps.
    pub fn keep_slack(&self, other: &Rest) {
        if let Some(s) = other.slack.get() {
            let _ = self.slack.set(*s);
        }
    }

    /// Whether [`Rest::slack`] has been measured.
    #[cfg(test)]
    pub fn calibrated(&self) -> bool {
        self.slack.get().is_some()
    }

    /// The facets each surface node leaves alone in self contact (its own and its
    /// neighbours'), made on first use.
    pub fn near_facets(&self) -> &NearFacets {
        self.near_facets.get_or_init(|| NearFacets::new(&self.mesh))
    }

    /// The surface's edges, each once (lower node first, ascending), made on first use.
    pub fn surface_edges(&self) -> &[[u32; 2]] {
        self.surface_edges.get_or_init(|| {
            let mut edges: Vec<[u32; 2]> = Vec::new();
            for f in self.mesh.boundary_facets() {
                for a in 0..FACET_ARITY {
                    for b in a + 1..FACET_ARITY {
                        edges.push([f[a].min(f[b]), f[a].max(f[b])]);
                    }
                }
            }
            edges.sort_unstable();
            edges.dedup();
            edges
        })
    }
}

/// The body's state: node positions and velocities, and the element model's own state (its
/// rest data per cell and, for shape matching, the warm-started rotations).
#[derive(Clone, Debug)]
pub(crate) struct State {
    pub positions: Vec<Vector>,
    pub velocities: Vec<Vector>,
    pub elements: ModelState,
}

/// The step's working buffers: the element forces and their stability data, and the copies
/// a rolled-back step restores.
#[derive(Clone, Debug)]
pub(crate) struct StepBuffers {
    /// Element forces, stiffness and damping per node.
    pub acc: Accumulator,
    /// Whether `acc` holds the forces at the current state.
    pub forces_valid: bool,
    /// The crossing limiter's bound at the current state: exact where it is below
    /// `crossing_cap`, else anything at or above that.
    pub limiter: Real,
    /// The substep (s) below which the next evaluation of the forces is to give the crossing
    /// limiter exactly: twice the last stable substep, which the next hardly exceeds (the
    /// substep loop evaluates again, exactly, when it does).
    pub crossing_cap: Real,
    /// The state at the start of the step (a failed step comes back to it).
    pub saved_positions: Vec<Vector>,
    pub saved_velocities: Vec<Vector>,
    /// Velocities before the substep's contacts.
    pub scratch_velocities: Vec<Vector>,
    /// What its nodes' contacts with deformables under the implicit step carried over from
    /// the last step, by node and body.
    pub soft_memory: Vec<Memory>,
    /// The implicit midpoint step's state ([`Integrator::Midpoint`](super::super::Integrator)).
    pub midpoint: MidpointState,
    /// This step's [`PipelineSettings::global_iterations`](super::super::PipelineSettings::global_iterations).
    pub global_iterations: usize,
    /// Whether [`Integrator::Auto`](super::super::Integrator::Auto) steps the body implicitly
    /// this step.
    pub auto_implicit: bool,
    /// The last measure of [`Deformable::measured_energy`](super::Deformable::measured_energy),
    /// and the forces the step's end kept for the next.
    pub energy_memo: EnergyMemo,
}

/// An elastic energy and the cells' volume ratios, and the positions they were measured at
/// (none measured yet when empty). Whatever changes the model's rest data or its gas (plastic
/// flow, a chamber refilled) clears the positions, so the positions alone say whether the
/// measure still holds.
///
/// The end of an explicit step is where the next step evaluates its first forces, so for a
/// model that measures in its force pass the step's last measure evaluates those forces too
/// ([`Deformable::measure_end`](super::Deformable::measure_end)): one pass over the cells
/// instead of two. They are kept with the velocities they were evaluated at, and taken if the
/// next evaluation finds the same state, bit for bit, and nothing dropped them since
/// ([`StepBuffers::invalidate_forces`]). A body whose state or model changes in between (a
/// setter, deformation damping, plastic flow, sleep) evaluates them again, and its next steps
/// measure the energy alone until a step ends where the next starts.
#[derive(Clone, Debug)]
pub(crate) struct EnergyMemo {
    pub at: Vec<Vector>,
    pub energy: Real,
    pub ratios: Option<Ratios>,
    /// The velocities of the last end-of-step measure.
    pub velocities: Vec<Vector>,
    /// The forces at (`at`, `velocities`), when `forces`: the next step's first.
    pub acc: Accumulator,
    /// Whether `acc` holds the forces at (`at`, `velocities`), and `limiter` their limiter.
    pub forces: bool,
    pub limiter: Real,
    /// Whether the next evaluation of the forces is the first since an end-of-step measure.
    pub pending: bool,
    /// Whether the next end-of-step measure evaluates the forces too.
    pub fuse: bool,
    /// Whether the forces were marked stale since the last end-of-step measure.
    pub dropped: bool,
    /// Whether the forces were asked for since the last end-of-step measure (the body steps
    /// explicitly).
    pub asked: bool,
}

impl Default for EnergyMemo {
    fn default() -> Self {
        EnergyMemo {
            at: Vec::new(),
            energy: 0.0,
            ratios: None,
            velocities: Vec::new(),
            acc: Accumulator::default(),
            forces: false,
            limiter: Real::INFINITY,
            pending: false,
            fuse: true,
            dropped: false,
            asked: false,
        }
    }
}

impl StepBuffers {
    pub fn new(acc: Accumulator, forces_valid: bool, limiter: Real, state: &State) -> Self {
        StepBuffers {
            acc,
            forces_valid,
            limiter,
            crossing_cap: Real::INFINITY,
            saved_positions: state.positions.clone(),
            saved_velocities: state.velocities.clone(),
            scratch_velocities: state.velocities.clone(),
            soft_memory: Vec::new(),
            midpoint: MidpointState::default(),
            global_iterations: 0,
            auto_implicit: false,
            energy_memo: EnergyMemo::default(),
        }
    }
}

impl StepBuffers {
    /// Keeps the state a failed step comes back to.
    pub fn save(&mut self, state: &State) {
        self.saved_positions.copy_from_slice(&state.positions);
        self.saved_velocities.copy_from_slice(&state.velocities);
    }

    /// Puts the saved state back; the element forces are stale then.
    pub fn restore(&mut self, state: &mut State) {
        state.positions.copy_from_slice(&self.saved_positions);
        state.velocities.copy_from_slice(&self.saved_velocities);
        self.invalidate_forces();
    }

    /// Marks the element forces stale: the state or the model changed.
    pub fn invalidate_forces(&mut self) {
        self.forces_valid = false;
        self.energy_memo.forces = false;
        self.energy_memo.dropped = true;
    }
}

/// Whether the body is simulated: asleep, frozen after a non-finite state, or awake.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Activation {
    /// Whether the body may fall asleep.
    pub can_sleep: bool,
    /// Whether the body is asleep (not simulated until something disturbs it).
    pub sleeping: bool,
    /// How long the body has been still, s.
    pub still_time: Real,
    /// Frozen after its state turned non-finite; not simulated until unfrozen.
    pub frozen: bool,
    /// Woken since the last step: the dynamic bodies it holds wake with it.
    pub woken: bool,
}

impl Activation {
    pub fn awake(can_sleep: bool) -> Self {
        Activation {
            can_sleep,
            sleeping: false,
            still_time: 0.0,
            frozen: false,
            woken: false,
        }
    }
}

/// What the last step found.
#[derive(Clone, Debug, Default)]
pub(crate) struct LastStep {
    pub report: DeformableReport,
    /// One per touching surface node, plus facet contacts.
    pub contacts: Vec<ContactPoint>,
    /// Colliders touched, sorted.
    pub touching: Vec<ColliderHandle>,
    /// Deformables touched (a node of either on a facet of the other), sorted.
    pub touching_bodies: Vec<DeformableHandle>,
    /// The cells each side of each face that tore open in the step.
    pub tears: Vec<[u32; 2]>,
    /// The crack torn last, while its release crosses the body.
    pub crack: Option<super::tear::Crack>,
}
