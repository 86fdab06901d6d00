//! A deformable body: rest mesh, element model and struct-of-arrays node state.

use super::attach::{self, AttachError, Attachment, Bindings};
use super::contact::{ContactMaterial, ContactPoint};
use super::error::BuildError;
use super::material::{Material, Resolved, Stiffness};
use super::math::{self, AngVector, Real, Rotation, Vector, DIM};
use super::mesh::{CellKind, Mesh};
use super::model::{Accumulator, ElementModel, ModelState};
use super::rapier::dynamics::{CoefficientCombineRule, RigidBodyHandle, RigidBodySet};
use super::rapier::geometry::{ColliderHandle, ColliderSet, InteractionGroups};
use super::report::DeformableReport;

/// A deformable body.
///
/// Node state is kept as separate arrays (positions, velocities, masses), so the element loops
/// stream through memory. Build one with [`DeformableBuilder`].
#[derive(Clone, Debug)]
pub struct Deformable {
    pub(crate) mesh: Mesh,
    pub(crate) model: ElementModel,
    pub(crate) params: Resolved,
    pub(crate) state: ModelState,
    pub(crate) positions: Vec<Vector>,
    pub(crate) velocities: Vec<Vector>,
    pub(crate) masses: Vec<Real>,
    pub(crate) inv_masses: Vec<Real>,
    pub(crate) acc: Accumulator,
    /// Whether `acc` holds the forces at the current state.
    pub(crate) forces_valid: bool,
    /// The crossing limiter's bound at the current state.
    pub(crate) limiter: Real,
    pub(crate) contact: ContactMaterial,
    pub(crate) gravity_scale: Real,
    pub(crate) frozen: bool,
    pub(crate) report: DeformableReport,
    pub(crate) saved_positions: Vec<Vector>,
    pub(crate) saved_velocities: Vec<Vector>,
    pub(crate) scratch_velocities: Vec<Vector>,
    /// Nodes bound to rigid bodies.
    pub(crate) bindings: Bindings,
    /// Contacts of the last step (one per touching surface node, plus facet contacts).
    pub(crate) contacts: Vec<ContactPoint>,
    /// Colliders touched during the last step, sorted.
    pub(crate) touching: Vec<ColliderHandle>,
    /// Whether the body may fall asleep.
    pub(crate) can_sleep: bool,
    /// Whether the body is asleep (not simulated until something disturbs it).
    pub(crate) sleeping: bool,
    /// How long the body has been still, s.
    pub(crate) still_time: Real,
    /// Free for the user.
    pub user_data: u128,
}

impl Deformable {
    /// The largest stable substep (s) at the current state, from the same bound the pipeline
    /// uses before its `safety` factor: the state is not changed (a copy of the element state
    /// is evaluated).
    pub fn stable_substep(&self) -> Real {
        let mut state = self.state.clone();
        let mut acc = Accumulator::new(self.positions.len());
        let limiter = state.accumulate(&self.positions, &self.velocities, &mut acc);
        super::model::stable_substep(&self.masses, &acc.stiffness, &acc.damping).min(limiter)
    }

    /// The rest mesh.
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// The element model.
    pub fn model(&self) -> ElementModel {
        self.model
    }

    /// The material.
    pub fn material(&self) -> Material {
        self.params.material
    }

    /// The stiffness form.
    pub fn stiffness(&self) -> Stiffness {
        self.params.stiffness
    }

    /// Node positions.
    pub fn positions(&self) -> &[Vector] {
        &self.positions
    }

    /// Node velocities.
    pub fn velocities(&self) -> &[Vector] {
        &self.velocities
    }

    /// Node masses (lumped: each cell's mass shared equally by its vertices).
    pub fn masses(&self) -> &[Real] {
        &self.masses
    }

    /// Number of nodes.
    pub fn num_nodes(&self) -> usize {
        self.positions.len()
    }

    /// Total mass.
    pub fn total_mass(&self) -> Real {
        self.masses.iter().sum()
    }

    /// Centre of mass.
    pub fn center_of_mass(&self) -> Vector {
        let mut s = Vector::ZERO;
        for (x, m) in self.positions.iter().zip(&self.masses) {
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
        for (v, m) in self.velocities.iter().zip(&self.masses) {
            s += *v * *m;
        }
        s
    }

    /// Total angular momentum about the origin `Σ x × m v`.
    pub fn angular_momentum(&self) -> AngVector {
        let mut s = math::ANG_ZERO;
        for ((x, v), m) in self
            .positions
            .iter()
            .zip(&self.velocities)
            .zip(&self.masses)
        {
            s += math::cross(*x, *v * *m);
        }
        s
    }

    /// Kinetic energy `Σ ½ m v²`.
    pub fn kinetic_energy(&self) -> Real {
        self.velocities
            .iter()
            .zip(&self.masses)
            .map(|(v, m)| 0.5 * m * v.length_squared())
            .sum()
    }

    /// Elastic energy stored in the elements.
    pub fn elastic_energy(&self) -> Real {
        self.state.elastic_energy(&self.positions)
    }

    /// Number of cells that are collapsed or inverted now (quality ≤ 0).
    pub fn inverted_elements(&self) -> usize {
        (0..self.mesh.num_cells())
            .filter(|&c| self.mesh.cell_quality(c, &self.positions) <= 0.0)
            .count()
    }

    /// The smallest cell quality (volume ratio) now.
    pub fn min_volume_ratio(&self) -> Real {
        (0..self.mesh.num_cells())
            .map(|c| self.mesh.cell_quality(c, &self.positions))
            .fold(Real::INFINITY, Real::min)
    }

    /// The element (internal) forces at the current state, without gravity or contacts.
    ///
    /// For the shape-based model this also advances its warm-started rotation estimates, as a
    /// substep would.
    pub fn element_forces(&mut self) -> &[Vector] {
        self.acc.clear();
        self.limiter = self
            .state
            .accumulate(&self.positions, &self.velocities, &mut self.acc);
        self.forces_valid = true;
        &self.acc.force
    }

    /// The element forces the last substep used, evaluated at the positions that substep
    /// started from (zero before the first step); without gravity or contacts. Unlike
    /// [`Deformable::element_forces`] this changes nothing.
    pub fn last_element_forces(&self) -> &[Vector] {
        &self.acc.force
    }

    /// The contacts of the last step: for each surface node that touched a collider, its last
    /// contact, then each facet contact (a rigid feature pressing a surface facet).
    pub fn contacts(&self) -> &[ContactPoint] {
        &self.contacts
    }

    /// The report of the last step.
    pub fn report(&self) -> &DeformableReport {
        &self.report
    }

    /// Whether the body is frozen (after its state turned non-finite). A frozen body is not
    /// simulated; [`Deformable::unfreeze`] resumes it.
    pub fn is_frozen(&self) -> bool {
        self.frozen
    }

    /// Resumes a frozen body.
    pub fn unfreeze(&mut self) {
        self.frozen = false;
        self.forces_valid = false;
    }

    /// Whether the body is asleep: it rested long enough with nothing moving near it, and is
    /// not simulated until a bone it is bound to moves, a moving or awake dynamic body comes
    /// near it, or [`Deformable::wake_up`] (or any setter of its state) is called.
    pub fn is_sleeping(&self) -> bool {
        self.sleeping
    }

    /// Wakes the body up (and restarts its still-time count).
    pub fn wake_up(&mut self) {
        self.sleeping = false;
        self.still_time = 0.0;
    }

    /// Whether the body may fall asleep (see [`DeformableBuilder::can_sleep`]).
    pub fn can_sleep(&self) -> bool {
        self.can_sleep
    }

    /// Allows or forbids sleeping; forbidding it wakes the body.
    pub fn set_can_sleep(&mut self, can_sleep: bool) {
        self.can_sleep = can_sleep;
        if !can_sleep {
            self.wake_up();
        }
    }

    /// Sets all node positions. Errors if the count differs or a coordinate is not finite; the
    /// state is unchanged then.
    pub fn set_positions(&mut self, positions: &[Vector]) -> Result<(), BuildError> {
        check_state("positions", positions, self.positions.len())?;
        self.positions.copy_from_slice(positions);
        self.forces_valid = false;
        self.wake_up();
        Ok(())
    }

    /// Sets all node velocities. Errors if the count differs or a component is not finite; the
    /// state is unchanged then.
    pub fn set_velocities(&mut self, velocities: &[Vector]) -> Result<(), BuildError> {
        check_state("velocities", velocities, self.velocities.len())?;
        self.velocities.copy_from_slice(velocities);
        self.forces_valid = false;
        self.wake_up();
        Ok(())
    }

    /// Gives every node the same velocity.
    pub fn set_uniform_velocity(&mut self, velocity: Vector) -> Result<(), BuildError> {
        check_state("velocity", &[velocity], 1)?;
        self.velocities.fill(velocity);
        self.forces_valid = false;
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
        if let Some(&node) = nodes.iter().find(|&&n| n as usize >= self.positions.len()) {
            return Err(AttachError::NodeOutOfRange {
                node,
                nodes: self.positions.len(),
            });
        }
        self.bindings
            .bind(body, rb.position(), &self.positions, nodes);
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
        let nodes = attach::nodes_inside(co, &self.positions, tolerance);
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

    fn bindings_changed(&mut self) {
        self.forces_valid = false;
        self.wake_up();
    }
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

/// Lumped node masses (each cell's mass shared equally by its vertices) and their inverses.
/// A snapshot rebuilds them with this same function, so they come back bit for bit.
pub(crate) fn lumped_masses(mesh: &Mesh, params: &Resolved) -> (Vec<Real>, Vec<Real>) {
    let arity = mesh.kind().arity() as Real;
    let mut masses = vec![0.0; mesh.nodes().len()];
    for (cell, ids) in mesh.cells().enumerate() {
        let m = params.material.density * mesh.rest_volumes()[cell] / arity;
        for &i in ids {
            masses[i as usize] += m;
        }
    }
    let inv_masses = masses.iter().map(|m| 1.0 / m).collect();
    (masses, inv_masses)
}

enum Source {
    Mesh(Mesh),
    Cuboid {
        half_extents: Vector,
        resolution: [usize; DIM],
    },
}

/// Builds a [`Deformable`], rapier-style: a named constructor, then `mut self -> Self`
/// setters, then [`DeformableBuilder::build`], which validates everything and returns a
/// typed [`BuildError`] instead of panicking.
#[must_use = "a builder does nothing until `.build()` is called"]
pub struct DeformableBuilder {
    source: Source,
    cells: CellKind,
    model: ElementModel,
    material: Material,
    stiffness: Stiffness,
    translation: Vector,
    rotation: Rotation,
    linvel: Vector,
    friction: Real,
    restitution: Real,
    friction_combine_rule: CoefficientCombineRule,
    restitution_combine_rule: CoefficientCombineRule,
    gravity_scale: Real,
    groups: InteractionGroups,
    ignore_attached_bodies: bool,
    can_sleep: bool,
    deny_warnings: bool,
    user_data: u128,
}

impl DeformableBuilder {
    /// A deformable over an existing rest mesh.
    pub fn new(mesh: Mesh) -> Self {
        Self::with_source(Source::Mesh(mesh))
    }

    /// A box lattice `[-half_extents, half_extents]` with `resolution[d]` nodes along axis `d`
    /// (see [`Mesh::cuboid`]); simplex cells unless [`DeformableBuilder::cells`] says otherwise.
    pub fn cuboid(half_extents: Vector, resolution: [usize; DIM]) -> Self {
        Self::with_source(Source::Cuboid {
            half_extents,
            resolution,
        })
    }

    fn with_source(source: Source) -> Self {
        DeformableBuilder {
            source,
            cells: CellKind::Simplex,
            model: ElementModel::EdgeRepulsion,
            material: Material::default(),
            stiffness: Stiffness::FromMaterial,
            translation: Vector::ZERO,
            rotation: Rotation::IDENTITY,
            linvel: Vector::ZERO,
            friction: 0.5,
            restitution: 0.0,
            friction_combine_rule: CoefficientCombineRule::Average,
            restitution_combine_rule: CoefficientCombineRule::Average,
            gravity_scale: 1.0,
            groups: InteractionGroups::all(),
            ignore_attached_bodies: true,
            can_sleep: true,
            deny_warnings: false,
            user_data: 0,
        }
    }

    /// Cell kind of a [`DeformableBuilder::cuboid`] lattice (ignored for an explicit mesh).
    pub fn cells(mut self, kind: CellKind) -> Self {
        self.cells = kind;
        self
    }

    /// The element model (default: [`ElementModel::EdgeRepulsion`]).
    pub fn model(mut self, model: ElementModel) -> Self {
        self.model = model;
        self
    }

    /// The material (default: [`Material::default`]).
    pub fn material(mut self, material: Material) -> Self {
        self.material = material;
        self
    }

    /// The stiffness form (default: from the material).
    pub fn stiffness(mut self, stiffness: Stiffness) -> Self {
        self.stiffness = stiffness;
        self
    }

    /// Translation applied to the rest mesh.
    pub fn translation(mut self, translation: Vector) -> Self {
        self.translation = translation;
        self
    }

    /// Rotation applied to the rest mesh (about the mesh origin, before the translation).
    pub fn rotation(mut self, rotation: Rotation) -> Self {
        self.rotation = rotation;
        self
    }

    /// Initial velocity of every node.
    pub fn linvel(mut self, linvel: Vector) -> Self {
        self.linvel = linvel;
        self
    }

    /// Friction coefficient against colliders (default 0.5), combined with the collider's.
    pub fn friction(mut self, friction: Real) -> Self {
        self.friction = friction;
        self
    }

    /// Restitution coefficient against colliders (default 0), combined with the collider's.
    pub fn restitution(mut self, restitution: Real) -> Self {
        self.restitution = restitution;
        self
    }

    /// Rule combining the friction coefficients (rapier's; default average).
    pub fn friction_combine_rule(mut self, rule: CoefficientCombineRule) -> Self {
        self.friction_combine_rule = rule;
        self
    }

    /// Rule combining the restitution coefficients (rapier's; default average).
    pub fn restitution_combine_rule(mut self, rule: CoefficientCombineRule) -> Self {
        self.restitution_combine_rule = rule;
        self
    }

    /// Multiplier of gravity for this body (default 1).
    pub fn gravity_scale(mut self, scale: Real) -> Self {
        self.gravity_scale = scale;
        self
    }

    /// Which colliders this body may touch (rapier's collision groups).
    pub fn collision_groups(mut self, groups: InteractionGroups) -> Self {
        self.groups = groups;
        self
    }

    /// Whether contacts ignore the colliders of the bodies this deformable is bound to
    /// (default `true`: tissue skinned onto a bone overlaps it by construction).
    pub fn ignore_attached_bodies(mut self, ignore: bool) -> Self {
        self.ignore_attached_bodies = ignore;
        self
    }

    /// Whether [`Mesh::diagnose`]'s warnings (coincident nodes, a surface that is not
    /// manifold, separate pieces) are errors ([`BuildError::MeshWarning`], the first one
    /// found); default `false`: they are legal, and a cut mesh may be meant.
    pub fn deny_warnings(mut self, deny: bool) -> Self {
        self.deny_warnings = deny;
        self
    }

    /// Whether the body may fall asleep when it rests (default `true`, as rapier's bodies;
    /// thresholds in [`PipelineSettings`](super::PipelineSettings)).
    pub fn can_sleep(mut self, can_sleep: bool) -> Self {
        self.can_sleep = can_sleep;
        self
    }

    /// Free user data.
    pub fn user_data(mut self, data: u128) -> Self {
        self.user_data = data;
        self
    }

    /// Validates everything and builds the deformable.
    pub fn build(self) -> Result<Deformable, BuildError> {
        let mesh = match self.source {
            Source::Mesh(m) => m,
            Source::Cuboid {
                half_extents,
                resolution,
            } => Mesh::cuboid(half_extents, resolution, self.cells)?,
        };
        if self.deny_warnings {
            if let Some(w) = mesh.diagnose().into_iter().next() {
                return Err(BuildError::MeshWarning(w));
            }
        }
        let params = Resolved::new(self.material, self.stiffness)?;
        let finite = |name, v: Vector| {
            if v.is_finite() {
                Ok(())
            } else {
                Err(BuildError::InvalidParameter {
                    name,
                    value: (0..DIM)
                        .map(|d| v[d])
                        .find(|c| !c.is_finite())
                        .unwrap_or(Real::NAN),
                    expected: "finite components",
                })
            }
        };
        finite("translation", self.translation)?;
        finite("linvel", self.linvel)?;
        let range = |name, v: Real, lo: Real, hi: Real, expected| {
            if v.is_finite() && v >= lo && v <= hi {
                Ok(())
            } else {
                Err(BuildError::InvalidParameter {
                    name,
                    value: v,
                    expected,
                })
            }
        };
        range(
            "friction",
            self.friction,
            0.0,
            Real::MAX,
            "a non-negative finite coefficient",
        )?;
        range("restitution", self.restitution, 0.0, 1.0, "0 ≤ e ≤ 1")?;
        range(
            "gravity_scale",
            self.gravity_scale,
            -Real::MAX,
            Real::MAX,
            "a finite scale",
        )?;
        let rotation = self.rotation.normalize();
        if !rotation.is_finite() {
            return Err(BuildError::InvalidParameter {
                name: "rotation",
                value: Real::NAN,
                expected: "a finite rotation",
            });
        }

        let n = mesh.nodes().len();
        let (masses, inv_masses) = lumped_masses(&mesh, &params);
        let state = ModelState::build(self.model, &mesh, &masses, &params, rotation)?;
        let positions: Vec<Vector> = mesh
            .nodes()
            .iter()
            .map(|p| rotation * *p + self.translation)
            .collect();
        let mut report = DeformableReport {
            nodes: n,
            elements: mesh.num_cells(),
            min_volume_ratio: 1.0,
            ..Default::default()
        };
        report.frozen = false;
        Ok(Deformable {
            state,
            params,
            model: self.model,
            velocities: vec![self.linvel; n],
            saved_positions: positions.clone(),
            saved_velocities: vec![self.linvel; n],
            scratch_velocities: vec![self.linvel; n],
            bindings: Bindings::new(n),
            touching: Vec::new(),
            can_sleep: self.can_sleep,
            sleeping: false,
            still_time: 0.0,
            contacts: Vec::new(),
            positions,
            masses,
            inv_masses,
            acc: Accumulator::new(n),
            forces_valid: false,
            limiter: Real::INFINITY,
            contact: ContactMaterial {
                friction: self.friction,
                restitution: self.restitution,
                friction_combine_rule: self.friction_combine_rule,
                restitution_combine_rule: self.restitution_combine_rule,
                groups: self.groups,
                ignore_attached_bodies: self.ignore_attached_bodies,
            },
            gravity_scale: self.gravity_scale,
            frozen: false,
            report,
            mesh,
            user_data: self.user_data,
        })
    }
}
