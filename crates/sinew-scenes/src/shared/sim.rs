//! One soft body — sinew's or rapier's — in a [`DeformableWorld`], stepped and measured the
//! same way whichever it is.

use std::time::Instant;

use super::super::lib::math::{Real, Rotation, Vector, DIM, SIMPLEX_ARITY, UP};
use super::super::lib::mesh::{CellKind, Mesh};
use super::super::lib::rapier::dynamics::{RigidBodyHandle, SoftBodyBuilder, SoftBodyHandle};
use super::super::lib::rapier::geometry::ColliderBuilder;
use super::super::lib::AttachError;
use super::super::lib::BuildError;
use super::super::lib::DeformableBuilder;
use super::super::lib::DeformableHandle;
use super::super::lib::DeformableWorld;
use super::super::lib::Integrator;
use super::super::lib::{Gas, Material, Plasticity, Stiffness, Tearing};
use super::subject::{mean_edge, Subject};
use crate::record::{Record, EXPLODED_DISTANCE, EXPLODED_SPEED};

/// The contact skin of rapier's soft bodies (its default `particle_radius`): their nodes rest
/// this far above what they lie on. Scenes that start a body at rest start it this high.
pub const RAPIER_SKIN: Real = 0.01;

/// Which body a [`Sim`] steps.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(crate) enum Soft {
    Sinew(DeformableHandle),
    Rapier(SoftBodyHandle),
}

/// A node of a rapier soft body pinned to a rigid body at a point of the body's frame.
#[derive(Copy, Clone, Debug)]
pub(crate) struct Pin {
    pub node: u32,
    body: RigidBodyHandle,
    local: Vector,
}

/// The soft body a scene drops into its world.
#[derive(Clone, Debug)]
pub(crate) struct BodySpec {
    /// Rest mesh, in body coordinates.
    pub mesh: Mesh,
    /// Where the mesh's origin goes.
    pub translation: Vector,
    /// How the mesh is turned (about its origin) before it is moved there.
    pub rotation: Rotation,
    pub material: Material,
    /// sinew only: how stiffness follows from the material.
    pub stiffness: Stiffness,
    pub friction: Real,
    pub restitution: Real,
    /// Nodes bound to rigid bodies at their initial positions.
    pub pins: Vec<(RigidBodyHandle, Vec<u32>)>,
    /// sinew only: whether the surface meets itself.
    pub self_contact: bool,
    /// sinew only: the rate of `DeformableBuilder::deformation_damping`, 1/s.
    pub deformation_damping: Real,
    /// A gas sealed in the mesh's chambers (`DeformableBuilder::gas`); rapier's body gets a
    /// volume target on its material instead, `(p + p_a)/p_a` of its rest volume (rapier 0.36
    /// has no gas).
    pub gas: Option<Gas>,
    /// Plastic flow (`DeformableBuilder::plasticity`); rapier's body gets the yield on its
    /// material, as its cells' deviatoric strain (`√(2/3)` of the yield, which a uniaxial
    /// strain at the yield has) and its edges' (`e^yield − 1`), flowing at once if sinew's does.
    pub plasticity: Option<Plasticity>,
    /// Tearing (`DeformableBuilder::tearing`); rapier's body gets the same strain as its
    /// material's `tear_strain` (a nominal strain, `e^s − 1`) and the smallest piece as its
    /// `min_piece`.
    pub tearing: Option<Tearing>,
}

impl BodySpec {
    pub fn new(mesh: Mesh, translation: Vector, material: Material) -> Self {
        BodySpec {
            mesh,
            translation,
            rotation: Rotation::IDENTITY,
            material,
            stiffness: Stiffness::FromMaterial,
            friction: 0.5,
            restitution: 0.5,
            pins: Vec::new(),
            self_contact: false,
            deformation_damping: 0.0,
            gas: None,
            plasticity: None,
            tearing: None,
        }
    }
}

/// A world holding one soft body of a given [`Subject`], with what the scenes measure on it.
///
/// Everything measured comes from node positions and velocities read back after each step,
/// so sinew's and rapier's bodies are judged alike.
pub struct Sim {
    /// The world: rigid bodies, colliders, and the soft body (in `deformables` for sinew, in
    /// `physics.soft_bodies` for rapier).
    pub world: DeformableWorld,
    subject: Subject,
    soft: Soft,
    pins: Vec<Pin>,
    mesh: Mesh,
    masses: Vec<Real>,
    rest: Vec<Vector>,
    x: Vec<Vector>,
    v: Vec<Vector>,
    /// How the mesh was turned and moved to where the body started.
    placement: (Rotation, Vector),
    size: Real,
    material: Material,
    fixed_substeps: Option<usize>,
    steps: usize,
    substeps: usize,
    max_substeps: usize,
    wall: f64,
    inverted: usize,
    max_inverted: usize,
    min_ratio: Real,
    step_min_ratio: Real,
    nan: bool,
    exploded: bool,
}

/// Each node's lumped mass: each cell's mass shared equally by its vertices (as sinew does).
pub(crate) fn lumped_masses(mesh: &Mesh, material: &Material) -> Vec<Real> {
    let arity = mesh.kind().arity() as Real;
    let mut masses = vec![0.0; mesh.nodes().len()];
    for (cell, ids) in mesh.cells().enumerate() {
        let m = material.density * mesh.rest_volumes()[cell] / arity;
        for &i in ids {
            masses[i as usize] += m;
        }
    }
    masses
}

/// Where the nodes of `spec`'s body start: the mesh turned, then moved.
pub(crate) fn rest_positions(spec: &BodySpec) -> Vec<Vector> {
    spec.mesh
        .nodes()
        .iter()
        .map(|p| spec.rotation * *p + spec.translation)
        .collect()
}

/// Puts the body of `spec` in `world` as `subject` (`rest`: its initial node positions,
/// `masses`: its lumped masses, `pins`: rapier's pinned particles).
pub(crate) fn insert_soft(
    world: &mut DeformableWorld,
    subject: Subject,
    spec: &BodySpec,
    rest: &[Vector],
    masses: &[Real],
    pins: &[u32],
    fixed_substeps: Option<usize>,
) -> Result<Soft, BuildError> {
    let mesh = &spec.mesh;
    Ok(match subject {
        Subject::Sinew(model) => {
            world.pipeline.settings.fixed_substeps = fixed_substeps;
            let mut body = DeformableBuilder::new(mesh.clone())
                .model(model)
                .material(spec.material)
                .stiffness(spec.stiffness)
                .friction(spec.friction)
                .restitution(spec.restitution)
                .translation(spec.translation)
                .rotation(spec.rotation)
                .self_contact(spec.self_contact)
                .deformation_damping(spec.deformation_damping);
            if let Some(gas) = spec.gas {
                body = body.gas(gas);
            }
            if let Some(tearing) = spec.tearing {
                body = body.tearing(tearing);
            }
            if let Some(plasticity) = spec.plasticity {
                body = body.plasticity(plasticity);
            }
            let body = body.build()?;
            let h = world.insert(body);
            for (body, nodes) in &spec.pins {
                world
                    .attach_nodes(h, *body, nodes)
                    .map_err(|e| attach_error(&e))?;
            }
            Soft::Sinew(h)
        }
        Subject::Rapier(model) => {
            if mesh.kind() != CellKind::Simplex {
                return Err(cell_kind_error(mesh.kind()));
            }
            if let Some(k) = fixed_substeps {
                let params = &mut world.physics.integration_parameters;
                params.num_solver_iterations = k.max(1);
                // rapier adds up to this many substeps on its own under fast motion.
                params.soft_bodies.max_extra_substeps = 0;
            }
            let cells: Vec<[u32; SIMPLEX_ARITY]> = mesh
                .cells()
                .map(|c| std::array::from_fn(|i| c[i]))
                .collect();
            let edges: Vec<[u32; 2]> = mesh.vertex_pairs().iter().map(|(e, _)| *e).collect();
            let pinned: Vec<u32> = pins.to_vec();
            let mut material = model.material(&spec.material, mean_edge(rest, &edges));
            if let Some(t) = spec.tearing {
                material.tear_strain = Some(t.strain.exp() - 1.0);
                material.min_piece = Some(t.smallest_piece as u32);
            }
            if let Some(p) = spec.plasticity {
                let creep = if p.flow_rate.is_finite() {
                    p.flow_rate
                } else {
                    Real::INFINITY
                };
                material.plastic_yield = Real::sqrt(2.0 / 3.0) * p.yield_strain;
                material.plastic_creep = creep;
                material.edge_plastic_yield = p.yield_strain.exp() - 1.0;
                material.edge_plastic_creep = creep;
            }
            let mut builder = SoftBodyBuilder::new(rest.to_vec())
                .cells(cells)
                .masses(masses.to_vec())
                .material(material)
                .cell_model(model.cell_model())
                .surface_collider(
                    ColliderBuilder::ball(0.0)
                        .friction(spec.friction)
                        .restitution(spec.restitution),
                )
                .particle_radius(RAPIER_SKIN)
                .pinned_particles(pinned)
                .can_sleep(false);
            if let Some(gas) = spec.gas {
                builder = builder.volume_preservation(true).volume_factor(
                    (gas.pressure + gas.ambient) / gas.ambient.max(Real::MIN_POSITIVE),
                );
            }
            #[cfg(feature = "fem")]
            {
                builder = builder.solver(model.solver());
            }
            Soft::Rapier(world.physics.insert_soft_body(builder))
        }
    })
}

/// Copies the node state of `soft` (sinew's or rapier's body) in `world` into `x` and `v`;
/// returns whether it is non-finite and whether it blew up (non-finite, or a node past
/// [`EXPLODED_DISTANCE`] or [`EXPLODED_SPEED`]).
pub(crate) fn read_state(
    world: &DeformableWorld,
    soft: Soft,
    x: &mut [Vector],
    v: &mut [Vector],
) -> (bool, bool) {
    match soft {
        Soft::Sinew(h) => {
            if let Some(d) = world.deformables.get(h) {
                x.copy_from_slice(d.positions());
                v.copy_from_slice(d.velocities());
            }
        }
        Soft::Rapier(h) => {
            if let Some(sb) = world.physics.soft_bodies.get(h) {
                for (i, p) in sb.particles().iter().enumerate().take(x.len()) {
                    x[i] = p.position();
                    v[i] = p.velocity();
                }
            }
        }
    }
    let finite = x.iter().chain(v.iter()).all(|p| p.is_finite());
    let far = x.iter().any(|p| p.length() as f64 > EXPLODED_DISTANCE)
        || v.iter().any(|v| v.length() as f64 > EXPLODED_SPEED);
    (!finite, !finite || far)
}

/// The pins of `spec` (its nodes bound to rigid bodies at their rest positions `rest`), each
/// with its anchor in its body's frame.
pub(crate) fn pins_of(
    world: &DeformableWorld,
    spec: &BodySpec,
    rest: &[Vector],
) -> Result<Vec<Pin>, BuildError> {
    let mut pins = Vec::new();
    for (body, nodes) in &spec.pins {
        let pose = *world
            .physics
            .bodies
            .get(*body)
            .ok_or_else(|| attach_error(&AttachError::NoSuchBody(*body)))?
            .position();
        for &node in nodes {
            let p = rest.get(node as usize).copied().ok_or_else(|| {
                attach_error(&AttachError::NodeOutOfRange {
                    node,
                    nodes: rest.len(),
                })
            })?;
            pins.push(Pin {
                node,
                body: *body,
                local: pose.inverse_transform_point(p),
            });
        }
    }
    Ok(pins)
}

/// rapier's pinned particles are kinematic: moves those of `soft` (if it is rapier's) to where
/// their bones will be at the end of the coming step. (sinew's bindings follow on their own.)
pub(crate) fn drive_pins(world: &mut DeformableWorld, soft: Soft, pins: &[Pin]) {
    if let Soft::Rapier(h) = soft {
        let w = &mut world.physics;
        if let Some(sb) = w.soft_bodies.get_mut(h) {
            for pin in pins {
                if let Some(b) = w.bodies.get(pin.body) {
                    let target = b.next_position().transform_point(pin.local);
                    sb.set_particle_kinematic_target(pin.node as usize, target);
                }
            }
        }
    }
}

fn cell_kind_error(kind: CellKind) -> BuildError {
    BuildError::UnsupportedCells {
        model: "rapier soft body",
        kind: kind.name(),
    }
}

impl Sim {
    /// Puts the body of `spec` in `world` as `subject`. `size` is the body's size for relative
    /// measures; `fixed_substeps` replaces each solver's own substep choice.
    pub(crate) fn new(
        mut world: DeformableWorld,
        subject: Subject,
        spec: BodySpec,
        size: Real,
        fixed_substeps: Option<usize>,
    ) -> Result<Sim, BuildError> {
        let n = spec.mesh.nodes().len();
        let masses = lumped_masses(&spec.mesh, &spec.material);
        let rest = rest_positions(&spec);
        let pins = pins_of(&world, &spec, &rest)?;
        let pinned: Vec<u32> = pins.iter().map(|p| p.node).collect();
        let soft = insert_soft(
            &mut world,
            subject,
            &spec,
            &rest,
            &masses,
            &pinned,
            fixed_substeps,
        )?;
        let placement = (spec.rotation, spec.translation);
        let mesh = spec.mesh;
        let mut sim = Sim {
            world,
            subject,
            soft,
            pins,
            mesh,
            masses,
            x: rest.clone(),
            v: vec![Vector::ZERO; n],
            rest,
            placement,
            size,
            material: spec.material,
            fixed_substeps,
            steps: 0,
            substeps: 0,
            max_substeps: 0,
            wall: 0.0,
            inverted: 0,
            max_inverted: 0,
            min_ratio: 1.0,
            step_min_ratio: 1.0,
            nan: false,
            exploded: false,
        };
        sim.read_back();
        Ok(sim)
    }

    /// Sets the node velocities (the state's other measures follow at the next step).
    pub fn set_velocities(&mut self, velocities: &[Vector]) -> Result<(), BuildError> {
        match self.soft {
            Soft::Sinew(h) => {
                if let Some(d) = self.world.deformables.get_mut(h) {
                    d.set_velocities(velocities)?;
                }
            }
            Soft::Rapier(h) => {
                if velocities.len() != self.v.len() {
                    return Err(BuildError::InvalidParameter {
                        name: "velocities",
                        value: velocities.len() as Real,
                        expected: "one velocity per node",
                    });
                }
                if let Some(sb) = self.world.physics.soft_bodies.get_mut(h) {
                    for (i, v) in velocities.iter().enumerate() {
                        sb.set_particle_velocity(i, *v);
                    }
                }
            }
        }
        self.read_back();
        Ok(())
    }

    /// One step of the world; returns the wall time it took, s.
    pub fn step(&mut self) -> f64 {
        drive_pins(&mut self.world, self.soft, &self.pins);
        let t0 = Instant::now();
        let report = self.world.step();
        let wall = t0.elapsed().as_secs_f64();
        self.wall += wall;
        self.steps += 1;
        match self.soft {
            Soft::Sinew(h) => {
                let r = report.get(h).cloned().unwrap_or_default();
                self.substeps += r.substeps;
                self.max_substeps = self.max_substeps.max(r.substeps);
                self.nan |= r.non_finite;
                // sinew's own blow-up check (a cell past `max_stretch`) rolls the body back and
                // freezes it before any node is far or fast.
                self.exploded |= r.exploded || r.non_finite;
            }
            Soft::Rapier(_) => {
                let iterations = self
                    .world
                    .physics
                    .integration_parameters
                    .num_solver_iterations;
                self.substeps += iterations;
                self.max_substeps = self.max_substeps.max(iterations);
            }
        }
        self.read_back();
        wall
    }

    fn read_back(&mut self) {
        self.follow_tears();
        let (nan, exploded) = read_state(&self.world, self.soft, &mut self.x, &mut self.v);
        self.nan |= nan;
        self.exploded |= exploded;
        if let Soft::Rapier(h) = self.soft {
            // A tear renumbers rapier's particles (pieces move to new bodies): its cells are
            // not measured past it.
            let count = self
                .world
                .physics
                .soft_bodies
                .get(h)
                .map(|b| b.particles().len());
            if count != Some(self.x.len()) {
                return;
            }
        }
        let (mut inverted, mut min_ratio) = (0, Real::INFINITY);
        for c in 0..self.mesh.num_cells() {
            let q = self.mesh.cell_quality(c, &self.x);
            if q.is_nan() || q <= 0.0 {
                inverted += 1;
            }
            min_ratio = min_ratio.min(q);
        }
        self.inverted = inverted;
        self.step_min_ratio = min_ratio;
        self.max_inverted = self.max_inverted.max(inverted);
        self.min_ratio = self.min_ratio.min(min_ratio);
    }

    /// Takes sinew's torn mesh (a tear appends copies of the nodes it cut apart).
    fn follow_tears(&mut self) {
        let Some(d) = self.deformable() else {
            return;
        };
        let n = d.num_nodes();
        if n == self.x.len() {
            return;
        }
        let (rotation, translation) = self.placement;
        let old = self.rest.len();
        let mesh = d.mesh().clone();
        self.masses = d.masses().to_vec();
        self.rest.extend(
            mesh.nodes()[old..]
                .iter()
                .map(|p| rotation * *p + translation),
        );
        self.mesh = mesh;
        self.x.resize(n, Vector::ZERO);
        self.v.resize(n, Vector::ZERO);
    }

    /// Lets go of the nodes pinned to `body`: sinew's bindings to it are dropped, rapier's
    /// particles unpinned.
    pub(crate) fn release(&mut self, body: RigidBodyHandle) {
        match self.soft {
            Soft::Sinew(h) => {
                if let Some(d) = self.world.deformables.get_mut(h) {
                    d.detach_body(body);
                }
            }
            Soft::Rapier(h) => {
                if let Some(sb) = self.world.physics.soft_bodies.get_mut(h) {
                    for pin in self.pins.iter().filter(|p| p.body == body) {
                        sb.set_particle_pinned(pin.node as usize, false);
                    }
                }
            }
        }
        self.pins.retain(|p| p.body != body);
    }

    /// Stops moving rapier's pinned particles with their bones (after its particles were
    /// unpinned, or renumbered by a tear).
    pub(crate) fn stop_pins(&mut self) {
        self.pins.clear();
    }

    /// sinew's body, when the subject is one of sinew's models.
    pub fn deformable(&self) -> Option<&super::super::lib::Deformable> {
        match self.soft {
            Soft::Sinew(h) => self.world.deformables.get(h),
            Soft::Rapier(_) => None,
        }
    }

    /// sinew's handle of the body, when the subject is one of sinew's models.
    pub fn handle(&self) -> Option<DeformableHandle> {
        match self.soft {
            Soft::Sinew(h) => Some(h),
            Soft::Rapier(_) => None,
        }
    }

    /// The subject simulated.
    pub fn subject(&self) -> Subject {
        self.subject
    }

    /// The pinned nodes: node, body, and the node's anchor in the body's frame.
    pub fn pinned_nodes(&self) -> Vec<(u32, RigidBodyHandle, Vector)> {
        self.pins
            .iter()
            .map(|p| (p.node, p.body, p.local))
            .collect()
    }

    /// Node positions after the last step.
    pub fn positions(&self) -> &[Vector] {
        &self.x
    }

    /// Node velocities after the last step.
    pub fn velocities(&self) -> &[Vector] {
        &self.v
    }

    /// Node positions at the start.
    pub fn rest_positions(&self) -> &[Vector] {
        &self.rest
    }

    /// The rest mesh.
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// Cells inverted (signed volume ≤ 0) after the last step.
    pub fn inverted_elements(&self) -> usize {
        self.inverted
    }

    /// Smallest cell volume ratio after the last step.
    pub fn min_volume_ratio(&self) -> Real {
        self.step_min_ratio
    }

    /// Whether the state turned non-finite or blew up so far.
    pub fn exploded(&self) -> bool {
        self.exploded
    }

    /// The centre of mass.
    pub fn center_of_mass(&self) -> Vector {
        let m: Real = self.masses.iter().sum();
        self.x
            .iter()
            .zip(&self.masses)
            .map(|(p, m)| *p * *m)
            .sum::<Vector>()
            / m
    }

    /// The centre of mass velocity.
    pub fn center_of_mass_velocity(&self) -> Vector {
        let m: Real = self.masses.iter().sum();
        self.v
            .iter()
            .zip(&self.masses)
            .map(|(v, m)| *v * *m)
            .sum::<Vector>()
            / m
    }

    /// Kinetic energy, J.
    pub fn kinetic_energy(&self) -> Real {
        0.5 * self
            .v
            .iter()
            .zip(&self.masses)
            .map(|(v, m)| m * v.length_squared())
            .sum::<Real>()
    }

    /// Height of the lowest node.
    pub fn lowest(&self) -> Real {
        self.x
            .iter()
            .map(|p| p.dot(UP))
            .fold(Real::INFINITY, Real::min)
    }

    /// Largest node distance from the rest shape moved by the best rigid fit (mass-weighted
    /// centroid, polar rotation of the covariance), over the body size.
    pub fn shape_error(&self) -> Real {
        super::metrics::shape_error(&self.x, &self.rest, &self.masses, self.size)
    }

    /// A record with everything common to all scenes filled in.
    pub(crate) fn record(&self, scene: &str, res: usize) -> Record {
        let params = &self.world.physics.integration_parameters;
        Record {
            scene: scene.to_string(),
            dim: DIM,
            model: self.subject.name().to_string(),
            iterations: self.subject.iterations(),
            integrator: integrator_name(self.subject, self.world.pipeline.settings.integrator),
            sweeps: sweeps(self.subject, self.world.pipeline.settings.integrator),
            res,
            nodes: self.x.len(),
            elements: self.mesh.num_cells(),
            dt: params.dt as f64,
            substep_mode: if self.fixed_substeps.is_some() {
                "fixed"
            } else {
                "auto"
            }
            .to_string(),
            substeps: self.substeps as f64 / self.steps.max(1) as f64,
            max_substeps: self.max_substeps,
            sim_s: self.world.time() as f64,
            wall_s: self.wall,
            young: self.material.young_modulus as f64,
            poisson: self.material.poisson_ratio as f64,
            min_vol_ratio: self.min_ratio as f64,
            max_inverted_elements: self.max_inverted,
            final_inverted_elements: self.inverted,
            final_kinetic_energy: self.kinetic_energy() as f64,
            nan: self.nan,
            exploded: self.exploded,
            ..Record::default()
        }
    }
}

fn attach_error(e: &AttachError) -> BuildError {
    BuildError::InvalidParameter {
        name: "pins",
        value: Real::NAN,
        expected: match e {
            AttachError::NoSuchBody(_) => "pins on existing bodies",
            AttachError::NodeOutOfRange { .. } => "pinned nodes in range",
            _ => "valid pins",
        },
    }
}

/// The first bounce of a dropped body and its deepest penetration below a floor, followed step
/// by step: the apex is the highest centre of mass between the first impact's lowest point
/// (the body rising while within 5 % of its size of the floor) and the next turn downwards.
pub(crate) struct Bounce {
    floor: Real,
    size: Real,
    rising: bool,
    highest: Real,
    apex: Option<Real>,
    max_penetration: Real,
}

impl Bounce {
    pub fn new(floor: Real, size: Real) -> Self {
        Bounce {
            floor,
            size,
            rising: false,
            highest: Real::NEG_INFINITY,
            apex: None,
            max_penetration: 0.0,
        }
    }

    /// The deepest node below the floor so far.
    pub fn max_penetration(&self) -> Real {
        self.max_penetration
    }

    /// Takes the state after a step.
    pub fn observe(&mut self, sim: &Sim) {
        let lowest = sim.lowest() - self.floor;
        self.max_penetration = self.max_penetration.max(-lowest);
        if self.apex.is_some() {
            return;
        }
        let com = sim.center_of_mass().dot(UP);
        let vy = sim.center_of_mass_velocity().dot(UP);
        self.rising |= vy > 0.0 && lowest < 0.05 * self.size;
        if self.rising {
            self.highest = self.highest.max(com);
            if vy <= 0.0 {
                self.apex = Some(self.highest);
            }
        }
    }

    /// The run's record with the apex, the rest height and the penetration, failed on a
    /// non-finite state, an explosion, an inverted cell at the end, or the first of `more`.
    pub fn record(&self, sim: &Sim, scene: &str, res: usize, more: &[(bool, &str)]) -> Record {
        let mut r = sim.record(scene, res);
        r.bounce_apex_com = self.apex.map(|a| a as f64);
        r.rest_com = Some(sim.center_of_mass().dot(UP) as f64);
        r.max_penetration = Some(self.max_penetration as f64);
        let mut failures = vec![
            (r.nan, "non-finite state"),
            (r.exploded, "exploded"),
            (r.final_inverted_elements > 0, "ended with inverted cells"),
        ];
        failures.extend_from_slice(more);
        r.failure = crate::record::failure(&failures);
        r.failed = r.failure.is_some();
        r
    }
}

/// sinew's integrator's name for a record (`None` for rapier's bodies).
pub(super) fn integrator_name(subject: Subject, integrator: Integrator) -> Option<String> {
    match (subject, integrator) {
        (Subject::Rapier(_), _) => None,
        (_, Integrator::Explicit) => Some("explicit".to_string()),
        (_, Integrator::Implicit { .. }) => Some("implicit".to_string()),
        (_, Integrator::Midpoint { .. }) => Some("midpoint".to_string()),
        (_, Integrator::Auto { .. }) => Some("auto".to_string()),
    }
}

/// The implicit integrator's sweeps for a record (`None` otherwise).
pub(super) fn sweeps(subject: Subject, integrator: Integrator) -> Option<usize> {
    match (subject, integrator) {
        (
            Subject::Sinew(_),
            Integrator::Implicit { iterations }
            | Integrator::Midpoint { iterations }
            | Integrator::Auto { iterations },
        ) => Some(iterations),
        _ => None,
    }
}
