//! A deformable body: rest mesh, element model and struct-of-arrays node state.

use super::attach::{self, AttachError, Attachment, Bindings};
use super::contact::{ContactMaterial, ContactPoint};
use super::embedding::Embedding;
use super::error::BuildError;
use super::material::{Gas, Material, Plasticity, Stiffness, Tearing};
use super::math::{self, AngVector, Real, Vector, DIM};
use super::mesh::Mesh;
use super::model::volume::Ratios;
use super::model::{Accumulator, ElementModel, Motion};
use super::rapier::dynamics::{RigidBodyHandle, RigidBodySet};
use super::rapier::geometry::{ColliderHandle, ColliderSet};
use super::report::DeformableReport;

mod builder;
mod parts;
mod surface;
pub(crate) mod tear;

pub use builder::DeformableBuilder;

/// A gas chamber's state ([`Deformable::chambers`]).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct ChamberState {
    /// The volume the chamber encloses now (area in 2D).
    pub volume: Real,
    /// The gas's pressure over the ambient one now, Pa: `(p + p_a) V₀ / V − p_a`.
    pub pressure: Real,
    /// The volume it enclosed as built.
    pub built_volume: Real,
}
pub(crate) use parts::{Activation, LastStep, Rest, State, StepBuffers};
pub(crate) use surface::{Surface, SurfaceTree};

/// A deformable body.
///
/// Node state is kept as separate arrays (positions, velocities, masses), so the element loops
/// stream through memory. Build one with [`DeformableBuilder`].
#[derive(Clone, Debug)]
pub struct Deformable {
    pub(crate) rest: Rest,
    pub(crate) state: State,
    pub(crate) step: StepBuffers,
    pub(crate) activation: Activation,
    pub(crate) last: LastStep,
    /// The surface's bounding-volume hierarchy (refitted when searched after the nodes moved;
    /// what queries search: [`Deformable::surface_tree`]).
    pub(crate) surface: Surface,
    /// Nodes bound to rigid bodies.
    pub(crate) bindings: Bindings,
    pub(crate) contact: ContactMaterial,
    pub(crate) gravity_scale: Real,
    /// [`DeformableBuilder::deformation_damping`](super::DeformableBuilder::deformation_damping).
    pub(crate) deformation_damping: Real,
    /// The render mesh, if one is bound ([`Deformable::set_render_mesh`]).
    pub(crate) render: Option<Embedding>,
    /// [`DeformableBuilder::tearing`](super::DeformableBuilder::tearing).
    pub(crate) tearing: Option<Tearing>,
    /// Free for the user.
    pub user_data: u128,
}

impl Deformable {
    /// The largest stable substep (s) at the current state, before the pipeline's `safety`
    /// factor: the per-node stability bounds calibrated by how far they overestimate this
    /// body's highest frequency at rest (`docs/ARCHITECTURE.md` §4.1; the pipeline uses the
    /// calibration for a body the explicit integrator steps alone), and the crossing limiter.
    /// The state is not changed (a copy of the element state is evaluated).
    pub fn stable_substep(&self) -> Real {
        let (estimate, _, limiter) = self.bounds(true);
        estimate.min(limiter)
    }

    /// The substep the pipeline takes at the current state under `safety`, calibrated or not
    /// ([`substep_under`](super::model::substep_under)), never beyond the crossing limiter.
    pub(crate) fn substep(&self, safety: Real, calibrated: bool) -> Real {
        let (estimate, certain, limiter) = self.bounds(calibrated);
        super::model::substep_under(estimate, certain, safety, calibrated).min(limiter)
    }

    /// Measures now what calibrating its stability bounds needs (once per body; otherwise on
    /// first use).
    pub(crate) fn calibrate(&self) {
        let _ = self.rest.slack(&self.state.elements);
    }

    /// The stability bounds (calibrated if asked, and as they are) and the crossing limiter.
    fn bounds(&self, calibrated: bool) -> (Real, Real, Real) {
        let mut state = self.state.elements.clone();
        let mut acc = Accumulator::new(self.state.positions.len());
        let limiter = state.accumulate(&self.state.positions, &self.state.velocities, &mut acc);
        let slack = if calibrated {
            self.rest.slack(&self.state.elements)
        } else {
            super::model::Slack::NONE
        };
        let (estimate, certain) =
            super::model::stable_substeps(&self.rest.masses, &acc.stiffness, &acc.damping, slack);
        (estimate, certain, limiter)
    }

    /// The rest mesh.
    pub fn mesh(&self) -> &Mesh {
        &self.rest.mesh
    }

    /// The element model.
    pub fn model(&self) -> ElementModel {
        self.rest.model
    }

    /// The material.
    pub fn material(&self) -> Material {
        self.rest.params.material
    }

    /// The stiffness form.
    pub fn stiffness(&self) -> Stiffness {
        self.rest.params.stiffness
    }

    /// Node positions.
    pub fn positions(&self) -> &[Vector] {
        &self.state.positions
    }

    /// Node velocities.
    pub fn velocities(&self) -> &[Vector] {
        &self.state.velocities
    }

    /// Node masses (lumped: each cell's mass shared equally by its vertices).
    pub fn masses(&self) -> &[Real] {
        &self.rest.masses
    }

    /// Number of nodes.
    pub fn num_nodes(&self) -> usize {
        self.state.positions.len()
    }

    /// Total mass.
    pub fn total_mass(&self) -> Real {
        self.rest.masses.iter().sum()
    }

    /// Centre of mass.
    pub fn center_of_mass(&self) -> Vector {
        let mut s = Vector::ZERO;
        for (x, m) in self.state.positions.iter().zip(&self.rest.masses) {
            s += *x * *m;
        }
        s / self.total_mass()
    }

    /// Velocity of the centre of mass.
    pub fn center_of_mass_velocity(&self) -> Vector {
        self.linear_momentum() / self.total_mass()
    }

    /// Total linear momentum `Σ m v`.
    pub fn linear_momentum(&self) -> Vector {
        let mut s = Vector::ZERO;
        for (v, m) in self.state.velocities.iter().zip(&self.rest.masses) {
            s += *v * *m;
        }
        s
    }

    /// Total angular momentum about the origin `Σ x × m v`.
    pub fn angular_momentum(&self) -> AngVector {
        let mut s = math::ANG_ZERO;
        for ((x, v), m) in self
            .state
            .positions
            .iter()
            .zip(&self.state.velocities)
            .zip(&self.rest.masses)
        {
            s += math::cross(*x, *v * *m);
        }
        s
    }

    /// Kinetic energy `Σ ½ m v²`.
    pub fn kinetic_energy(&self) -> Real {
        self.state
            .velocities
            .iter()
            .zip(&self.rest.masses)
            .map(|(v, m)| 0.5 * m * v.length_squared())
            .sum()
    }

    /// Gravitational energy `−Σ m g·x` under the acceleration `g` (its gravity scale applied
    /// by the caller).
    pub(crate) fn gravity_energy(&self, g: Vector) -> Real {
        -self
            .state
            .positions
            .iter()
            .zip(&self.rest.masses)
            .map(|(x, m)| m * g.dot(*x))
            .sum::<Real>()
    }

    /// [`Deformable::kinetic_energy`] and [`Deformable::gravity_energy`] in one pass: the same
    /// sums, in the same order, side by side.
    pub(crate) fn kinetic_and_gravity_energy(&self, g: Vector) -> (Real, Real) {
        let (v, x, m) = (
            &self.state.velocities,
            &self.state.positions,
            &self.rest.masses,
        );
        // (`Sum` starts from −0: an empty or all −0 sum keeps its sign.)
        let (mut kinetic, mut gravity): (Real, Real) = (-0.0, -0.0);
        for ((v, x), m) in v.iter().zip(x).zip(m) {
            kinetic += 0.5 * m * v.length_squared();
            gravity += m * g.dot(*x);
        }
        (kinetic, -gravity)
    }

    /// Elastic energy stored in the elements.
    pub fn elastic_energy(&self) -> Real {
        self.state.elements.elastic_energy(&self.state.positions)
    }

    /// [`ModelState::elastic_energy_and_ratios`] at the body's positions, measured again only
    /// if they changed (bit for bit) since the last measure, or if the model's energy depends
    /// on more than the positions (shape matching's rotations): a step measures its end once
    /// for its energy bookkeeping and its report, and the next step starts there.
    pub(crate) fn measured_energy(&mut self) -> (Real, Option<Ratios>) {
        let x = &self.state.positions;
        let memo = &mut self.step.energy_memo;
        if same_bits(&memo.at, x) {
            return (memo.energy, memo.ratios);
        }
        let (energy, ratios) = self.state.elements.elastic_energy_and_ratios(x);
        if self.state.elements.warm_start().is_empty() {
            memo.at.clear();
            memo.at.extend_from_slice(x);
            (memo.energy, memo.ratios) = (energy, ratios);
        }
        (energy, ratios)
    }

    /// The measure of a step's end: [`Deformable::measured_energy`], which a body that stepped
    /// explicitly, with a model that measures in its force pass, takes in one pass with the
    /// forces the next step starts from (see [`EnergyMemo`](parts::EnergyMemo)).
    pub(crate) fn measure_end(&mut self) -> (Real, Option<Ratios>) {
        let asked = std::mem::take(&mut self.step.energy_memo.asked);
        if !(asked && self.state.elements.measures_in_pass()) {
            return self.measured_energy();
        }
        let (x, v) = (&self.state.positions, &self.state.velocities);
        let memo = &mut self.step.energy_memo;
        memo.forces = false;
        let fused = if memo.fuse {
            if memo.acc.force.len() == x.len() {
                memo.acc.clear();
            } else {
                memo.acc = Accumulator::new(x.len());
            }
            self.state.elements.accumulate_measured(x, v, &mut memo.acc)
        } else {
            None
        };
        let (measured, kept) = match fused {
            Some(measured) => {
                memo.at.clear();
                memo.at.extend_from_slice(x);
                (memo.energy, memo.ratios) = measured;
                (memo.forces, memo.limiter) = (true, Real::INFINITY);
                (measured, true)
            }
            None => {
                let measured = self.measured_energy();
                let memo = &self.step.energy_memo;
                (measured, same_bits(&memo.at, &self.state.positions))
            }
        };
        let memo = &mut self.step.energy_memo;
        let v = &self.state.velocities;
        if kept {
            memo.velocities.clear();
            memo.velocities.extend_from_slice(v);
            memo.pending = true;
            memo.dropped = false;
        }
        measured
    }

    /// Flows the cells strained past yield over a step of `dt` (plastic bodies only); returns
    /// the elastic energy released. The forces and the energy measured before are stale after
    /// any cell flowed, even a flow undone.
    pub(crate) fn flow(&mut self, dt: Real) -> Option<Real> {
        let (flowed, released) = self.state.elements.flow(&self.state.positions, dt);
        if flowed {
            self.step.invalidate_forces();
            self.step.energy_memo.at.clear();
        }
        released
    }

    /// The body's tearing ([`DeformableBuilder::tearing`](super::DeformableBuilder::tearing)),
    /// if it tears.
    pub fn tearing(&self) -> Option<Tearing> {
        self.tearing
    }

    /// The faces that tore open in the last step, each as the two cells it joined (cell
    /// indices are kept by a tear; the nodes it cut apart got copies, past the nodes there
    /// were).
    pub fn last_tears(&self) -> &[[u32; 2]] {
        &self.last.tears
    }

    /// The body's plastic flow ([`DeformableBuilder::plasticity`](super::DeformableBuilder::plasticity)),
    /// if it flows.
    pub fn plasticity(&self) -> Option<Plasticity> {
        self.state.elements.plasticity()
    }

    /// Each cell's plastic strain, the largest magnitude of the principal log strains of its
    /// rest shape against its built one (the set it keeps; `ColorField::PlasticStrain` draws
    /// it); empty if the body does not flow.
    pub fn plastic_strains(&self) -> Vec<Real> {
        self.state.elements.plastic_strains()
    }

    /// Each gas chamber's volume (area in 2D) and gauge pressure now
    /// ([`DeformableBuilder::gas`](super::DeformableBuilder::gas)); empty without gas.
    pub fn chambers(&self) -> Vec<ChamberState> {
        let x = &self.state.positions;
        self.state
            .elements
            .chambers()
            .iter()
            .map(|c| {
                let volume = c.volume(x);
                ChamberState {
                    volume,
                    pressure: c.law(volume).0,
                    built_volume: c.built_volume(),
                }
            })
            .collect()
    }

    /// Pumps gas into chamber `chamber` (or lets it out) so that its gauge pressure is
    /// `gas.pressure` now, against `gas.ambient`: a pneumatic actuator's valve. The gas's stored
    /// energy changes by the pump's work. A bad pressure is `BuildError::InvalidParameter`
    /// naming the field, a chamber the body does not have one naming `chamber`; neither changes
    /// the body.
    pub fn set_chamber_pressure(&mut self, chamber: usize, gas: Gas) -> Result<(), BuildError> {
        let x = &self.state.positions;
        let chambers = self.state.elements.chambers_mut();
        let Some(c) = chambers.get_mut(chamber) else {
            return Err(BuildError::InvalidParameter {
                name: "chamber",
                value: chamber as Real,
                expected: "the index of one of the body's gas chambers",
            });
        };
        let volume = c.volume(x);
        c.refill(gas, volume)?;
        self.step.invalidate_forces();
        self.step.energy_memo.at.clear();
        self.wake_up();
        Ok(())
    }

    /// Number of cells that are collapsed or inverted now (quality ≤ 0).
    pub fn inverted_elements(&self) -> usize {
        (0..self.rest.mesh.num_cells())
            .filter(|&c| self.rest.mesh.cell_quality(c, &self.state.positions) <= 0.0)
            .count()
    }

    /// The smallest cell quality (volume ratio) now.
    pub fn min_volume_ratio(&self) -> Real {
        (0..self.rest.mesh.num_cells())
            .map(|c| self.rest.mesh.cell_quality(c, &self.state.positions))
            .fold(Real::INFINITY, Real::min)
    }

    /// The element (internal) forces at the current state, without gravity or contacts.
    ///
    /// For the shape-based model this also advances its warm-started rotation estimates, as a
    /// substep would.
    pub fn element_forces(&mut self) -> &[Vector] {
        self.step.invalidate_forces();
        self.refresh_forces();
        &self.step.acc.force
    }

    /// Evaluates the element forces (with their per-node stiffness and damping bounds and the
    /// crossing limiter) if the state changed since they last were: the elements' side of the
    /// integrator seam (see `integrator.rs`).
    pub(crate) fn refresh_forces(&mut self) {
        if self.step.forces_valid {
            return;
        }
        let step = &mut self.step;
        let memo = &mut step.energy_memo;
        memo.asked = true;
        if std::mem::take(&mut memo.pending) {
            let (x, v) = (&self.state.positions, &self.state.velocities);
            // Fusing pays where the kept forces are the ones asked for.
            memo.fuse = !memo.dropped && same_bits(&memo.at, x) && same_bits(&memo.velocities, v);
            if memo.fuse && memo.forces {
                std::mem::swap(&mut step.acc, &mut memo.acc);
                step.limiter = memo.limiter;
                memo.forces = false;
                step.forces_valid = true;
                return;
            }
        }
        step.acc.clear();
        step.limiter = self.state.elements.accumulate_capped(
            &self.state.positions,
            &self.state.velocities,
            &mut step.acc,
            step.crossing_cap,
        );
        step.forces_valid = true;
    }

    /// The element forces the last substep used, evaluated at the positions that substep
    /// started from (zero before the first step); without gravity or contacts. Unlike
    /// [`Deformable::element_forces`] this changes nothing. The implicit integrator evaluates
    /// its own terms and leaves these as the last explicit substep left them.
    pub fn last_element_forces(&self) -> &[Vector] {
        &self.step.acc.force
    }

    /// The contacts of the last step: for each surface node that touched a collider, its last
    /// contact, then each facet contact (a rigid feature pressing a surface facet).
    pub fn contacts(&self) -> &[ContactPoint] {
        &self.last.contacts
    }

    /// The report of the last step.
    pub fn report(&self) -> &DeformableReport {
        &self.last.report
    }

    /// Whether the body is frozen (after its state turned non-finite). A frozen body is not
    /// simulated; [`Deformable::unfreeze`] resumes it.
    pub fn is_frozen(&self) -> bool {
        self.activation.frozen
    }

    /// Resumes a frozen body.
    pub fn unfreeze(&mut self) {
        self.activation.frozen = false;
        self.step.invalidate_forces();
    }

    /// Whether the body is asleep: it rested long enough with nothing moving near it, and is
    /// not simulated until a bone it is bound to moves, a moving or awake dynamic body comes
    /// near it, or [`Deformable::wake_up`] (or any setter of its state) is called.
    pub fn is_sleeping(&self) -> bool {
        self.activation.sleeping
    }

    /// Wakes the body up (and restarts its still-time count). The dynamic bodies it touched
    /// or is bound to wake with it at the next step.
    pub fn wake_up(&mut self) {
        self.activation.woken |= self.activation.sleeping;
        self.activation.sleeping = false;
        self.activation.still_time = 0.0;
    }

    /// Whether the body may fall asleep (see [`DeformableBuilder::can_sleep`]).
    pub fn can_sleep(&self) -> bool {
        self.activation.can_sleep
    }

    /// Allows or forbids sleeping; forbidding it wakes the body.
    pub fn set_can_sleep(&mut self, can_sleep: bool) {
        self.activation.can_sleep = can_sleep;
        if !can_sleep {
            self.wake_up();
        }
    }

    /// The rate (1/s) at which the body's deformation is damped toward its rigid motion (see
    /// [`DeformableBuilder::deformation_damping`]).
    pub fn deformation_damping(&self) -> Real {
        self.deformation_damping
    }

    /// Sets the rate of [`DeformableBuilder::deformation_damping`]; a negative or non-finite
    /// rate is an error and changes nothing.
    pub fn set_deformation_damping(&mut self, rate: Real) -> Result<(), BuildError> {
        if !(rate.is_finite() && rate >= 0.0) {
            return Err(BuildError::InvalidParameter {
                name: "deformation_damping",
                value: rate,
                expected: "a non-negative finite rate (1/s)",
            });
        }
        self.deformation_damping = rate;
        Ok(())
    }

    /// Pulls the free nodes' velocities toward their best-fit rigid motion (the velocity of
    /// their centre of mass and the angular velocity that carry their momentum and angular
    /// momentum) by `1 − exp(−rate · dt)`: their deformation's kinetic energy falls, their
    /// momentum and angular momentum stay. Bound nodes keep their bones' velocities and are
    /// left out of the fit (counted in, a body hanging from a moving bone was dragged along).
    /// Does nothing at rate 0.
    pub(crate) fn damp_deformation(&mut self, dt: Real) {
        let rate = self.deformation_damping;
        if rate <= 0.0 || dt <= 0.0 {
            return;
        }
        let free: Vec<usize> = (0..self.state.positions.len())
            .filter(|&i| !self.is_attached(i as u32))
            .collect();
        let pick = |of: &[Vector]| free.iter().map(|&i| of[i]).collect::<Vec<Vector>>();
        let masses: Vec<Real> = free.iter().map(|&i| self.rest.masses[i]).collect();
        let (x, v) = (pick(&self.state.positions), pick(&self.state.velocities));
        let Some(Motion {
            velocity,
            r,
            momentum,
        }) = Motion::of(&x, &v, &masses)
        else {
            return;
        };
        let angvel = math::angular_velocity_for(&r, &masses, momentum);
        let keep = (-rate * dt).exp();
        for (&i, r) in free.iter().zip(&r) {
            let rigid = velocity + math::ang_cross(angvel, *r);
            let u = &mut self.state.velocities[i];
            *u = rigid + (*u - rigid) * keep;
        }
        self.step.invalidate_forces();
    }

    /// Whether the body's surface meets itself (see [`DeformableBuilder::self_contact`]).
    pub fn self_contact(&self) -> bool {
        self.contact.self_contact
    }

    /// Turns self contact on or off.
    pub fn set_self_contact(&mut self, on: bool) {
        self.contact.self_contact = on;
    }

    /// Sets all node positions. Errors if the count differs or a coordinate is not finite; the
    /// state is unchanged then.
    pub fn set_positions(&mut self, positions: &[Vector]) -> Result<(), BuildError> {
        check_state("positions", positions, self.state.positions.len())?;
        self.state.positions.copy_from_slice(positions);
        // Shape matching's rotations follow the new shape (its energy reads them).
        self.state.elements.refit_rotations(positions);
        self.refit_surface();
        self.step.invalidate_forces();
        self.wake_up();
        Ok(())
    }

    /// Sets all node velocities. Errors if the count differs or a component is not finite; the
    /// state is unchanged then.
    pub fn set_velocities(&mut self, velocities: &[Vector]) -> Result<(), BuildError> {
        check_state("velocities", velocities, self.state.velocities.len())?;
        self.state.velocities.copy_from_slice(velocities);
        self.step.invalidate_forces();
        self.wake_up();
        Ok(())
    }

    /// Gives every node the same velocity.
    pub fn set_uniform_velocity(&mut self, velocity: Vector) -> Result<(), BuildError> {
        check_state("velocity", &[velocity], 1)?;
        self.state.velocities.fill(velocity);
        self.step.invalidate_forces();
        self.wake_up();
        Ok(())
    }

    /// The current bindings, in the order they were made.
    pub fn attachments(&self) -> &[Attachment] {
        self.bindings.list()
    }

    /// Whether a node is bound to a body.
    pub fn is_attached(&self, node: u32) -> bool {
        self.bindings.is_bound(node)
    }

    /// Binds `nodes` to `body` at their current positions (re-binding nodes already bound
    /// elsewhere). Returns how many nodes were bound. Nothing changes on error.
    pub fn attach_nodes(
        &mut self,
        bodies: &RigidBodySet,
        body: RigidBodyHandle,
        nodes: &[u32],
    ) -> Result<usize, AttachError> {
        let rb = bodies.get(body).ok_or(AttachError::NoSuchBody(body))?;
        if let Some(&node) = nodes
            .iter()
            .find(|&&n| n as usize >= self.state.positions.len())
        {
            return Err(AttachError::NodeOutOfRange {
                node,
                nodes: self.state.positions.len(),
            });
        }
        self.bindings
            .bind(body, rb.position(), &self.state.positions, nodes);
        self.bindings_changed();
        Ok(nodes.len())
    }

    /// Binds every node inside `collider`, or within `tolerance` of it, to the collider's
    /// parent body — how tissue is skinned onto a bone. Returns how many nodes were bound.
    pub fn attach_nodes_inside(
        &mut self,
        bodies: &RigidBodySet,
        colliders: &ColliderSet,
        collider: ColliderHandle,
        tolerance: Real,
    ) -> Result<usize, AttachError> {
        if !(tolerance.is_finite() && tolerance >= 0.0) {
            return Err(AttachError::BadTolerance(tolerance));
        }
        let co = colliders
            .get(collider)
            .ok_or(AttachError::NoSuchCollider(collider))?;
        let body = co
            .parent()
            .ok_or(AttachError::ColliderWithoutBody(collider))?;
        let nodes = attach::nodes_inside(co, &self.state.positions, tolerance);
        self.attach_nodes(bodies, body, &nodes)
    }

    /// Unbinds the given nodes (those not bound are ignored). Returns how many were unbound.
    pub fn detach_nodes(&mut self, nodes: &[u32]) -> usize {
        if nodes.is_empty() || self.bindings.len() == 0 {
            return 0;
        }
        let dropped = self.bindings.unbind(nodes);
        self.bindings_changed();
        dropped
    }

    /// Unbinds every node bound to `body`. Returns how many were unbound.
    pub fn detach_body(&mut self, body: RigidBodyHandle) -> usize {
        let dropped = self.bindings.retain(|a| a.body != body);
        self.bindings_changed();
        dropped
    }

    /// Unbinds every node.
    pub fn detach_all(&mut self) {
        self.bindings.retain(|_| false);
        self.bindings_changed();
    }

    /// Drops bindings to bodies no longer in the set; returns how many.
    pub(crate) fn prune_attachments(&mut self, bodies: &RigidBodySet) -> usize {
        let dropped = self.bindings.retain(|a| bodies.contains(a.body));
        if dropped > 0 {
            self.bindings_changed();
        }
        dropped
    }

    /// The surface's hierarchy at the current positions.
    pub(crate) fn surface_tree(&self) -> std::sync::RwLockReadGuard<'_, SurfaceTree> {
        self.surface.search(&self.rest.mesh, &self.state.positions)
    }

    /// The nodes moved: the surface's hierarchy is refitted by the next search, the render
    /// mesh, if there is one, brought to the current positions now.
    pub(crate) fn refit_surface(&mut self) {
        self.surface.moved();
        if let Some(render) = &mut self.render {
            render.update(&self.state.positions);
        }
    }

    /// Binds a render mesh to this body: `vertices` (given in the body's rest frame, where
    /// its [`mesh`](Self::mesh)'s nodes are) and `facets` over them (triangles in 3D,
    /// segments in 2D), each vertex carried by the cell around it ([`Embedding`]). From then
    /// on every step, and every change of the positions, moves it; read it with
    /// [`render_mesh`](Self::render_mesh). Replaces any render mesh bound before. Errors as
    /// [`Embedding::bind`]; the body is unchanged then.
    pub fn set_render_mesh(
        &mut self,
        vertices: &[Vector],
        facets: Vec<[u32; math::FACET_ARITY]>,
    ) -> Result<(), BuildError> {
        let mut render = Embedding::bind(&self.rest.mesh, vertices, facets)?;
        render.update(&self.state.positions);
        self.render = Some(render);
        Ok(())
    }

    /// The render mesh at the current positions, if one is bound.
    pub fn render_mesh(&self) -> Option<&Embedding> {
        self.render.as_ref()
    }

    /// Unbinds the render mesh.
    pub fn clear_render_mesh(&mut self) {
        self.render = None;
    }

    fn bindings_changed(&mut self) {
        self.step.invalidate_forces();
        self.wake_up();
    }
}

/// Whether `a` and `b` hold the same vectors, bit for bit.
fn same_bits(a: &[Vector], b: &[Vector]) -> bool {
    // The differing bits OR-ed together, 64 vectors at a time without a branch each, so that
    // the comparisons vectorize.
    let differ = |a: &Vector, b: &Vector| {
        let (a, b) = (a.to_array(), b.to_array());
        (0..a.len()).fold(0, |d, k| d | (a[k].to_bits() ^ b[k].to_bits()))
    };
    a.len() == b.len()
        && a.chunks(64)
            .zip(b.chunks(64))
            .all(|(a, b)| a.iter().zip(b).fold(0, |d, (a, b)| d | differ(a, b)) == 0)
}

pub(crate) fn check_state(
    what: &'static str,
    values: &[Vector],
    expected: usize,
) -> Result<(), BuildError> {
    if values.len() != expected {
        return Err(BuildError::WrongLength {
            what,
            got: values.len(),
            expected,
        });
    }
    if let Some((node, p)) = values.iter().enumerate().find(|(_, p)| !p.is_finite()) {
        return Err(BuildError::NonFiniteCoordinate {
            node,
            coordinates: (0..DIM).map(|d| p[d]).collect(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::mesh::CellKind;
    use super::*;

    #[test]
    fn the_energy_is_measured_again_whenever_a_node_moved() {
        for model in [
            ElementModel::EdgeRepulsion,
            ElementModel::Springs,
            ElementModel::SHAPE_MATCHING,
        ] {
            let mut body = DeformableBuilder::cuboid(Vector::splat(0.5), [3; DIM])
                .cells(CellKind::Simplex)
                .model(model)
                .build()
                .unwrap();
            let rest = body.positions().to_vec();
            let mut bent = rest.clone();
            bent[0] += Vector::splat(0.05);
            let fresh = |body: &Deformable| {
                let x = &body.state.positions;
                body.state.elements.elastic_energy_and_ratios(x)
            };
            for x in [&bent, &rest, &bent] {
                body.set_positions(x).unwrap();
                assert_eq!(body.measured_energy(), fresh(&body), "{model:?}");
                assert_eq!(
                    body.measured_energy(),
                    fresh(&body),
                    "{model:?}, measured twice"
                );
            }
            // Moved by the step itself, not through a setter.
            body.state.positions[1][0] += 1e-3;
            assert_eq!(
                body.measured_energy(),
                fresh(&body),
                "{model:?}, one node moved"
            );
            assert!(
                body.measured_energy().0 > fresh_at(&body, &rest),
                "{model:?}"
            );
        }
    }

    /// The elastic energy of `body`'s model at `x`.
    fn fresh_at(body: &Deformable, x: &[Vector]) -> Real {
        body.state.elements.elastic_energy(x)
    }
}
