//! Cooper & Maddock's limb (§5).

use super::super::lib::math::{self, Pose, Real, Vector, DIM};
use super::super::lib::mesh::{CellKind, Mesh};
use super::super::lib::model::ElementModel;
use super::super::lib::rapier::dynamics::{RigidBodyBuilder, RigidBodyHandle};
use super::super::lib::rapier::geometry::ColliderBuilder;
use super::super::lib::BuildError;
use super::super::lib::DeformableWorld;
use super::super::lib::Integrator;
use super::super::lib::Material;
use super::fall::cuboid;
use super::metrics::self_interpenetration;
use super::sim::{BodySpec, Sim};
use super::subject::Subject;
use super::Record;

/// Cooper & Maddock's limb (§5): two kinematic bones inside a slab of tissue, the tissue's
/// nodes inside each bone pinned to it; the upper bone is held, the lower one turned about the
/// hinge at the origin, bending the limb so the tissue above the hinge is crushed.
///
/// The tissue spans `x ∈ [−1, 1]` and `±0.3` across (a square section in 3D); the bones run
/// from `±0.15` to `±0.95` along x with a half thickness of `0.1`, so the hinge region is free
/// tissue and every cell that inverts does so because of its model, not because its nodes are
/// all carried by bones. The bones' colliders are sensors: the tissue is held by its pins only.
/// `first_failure` is the bone angle (degrees) at the first inverted cell;
/// `max_self_penetration` how deep the crease's surface went into itself
/// ([`self_interpenetration`](super::metrics::self_interpenetration), up to half a cell).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct LimbScene {
    /// What is simulated.
    pub subject: Subject,
    /// Lattice spacing, m.
    pub spacing: Real,
    /// Tissue Young's modulus, Pa.
    pub young_modulus: Real,
    /// Poisson's ratio (sinew's models on simplex cells but centroid springs, and rapier's).
    pub poisson_ratio: Real,
    /// Tissue density, kg/m³ (kg/m² in 2D).
    pub density: Real,
    /// Damping ratio.
    pub damping_ratio: Real,
    /// Bending speed, degrees per second.
    pub degrees_per_second: Real,
    /// Final angle, degrees.
    pub max_degrees: Real,
    /// Step length, s.
    pub dt: Real,
    /// A fixed substep count instead of each solver's own choice.
    pub fixed_substeps: Option<usize>,
    /// Stop at the first inverted element.
    pub stop_at_first_inversion: bool,
    /// Whether sinew's tissue has self contact on (the crease above the hinge folds onto
    /// itself).
    pub self_contact: bool,
    /// sinew's integrator.
    pub integrator: Integrator,
}

impl Default for LimbScene {
    /// 0.1 m spacing, E = 10⁴ Pa, ν = 0.3, 1000 kg/m³, ζ = 0.1, 10°/s up to 110°, dt = 10 ms,
    /// no gravity, edge-repulsion.
    fn default() -> Self {
        LimbScene {
            subject: Subject::Sinew(ElementModel::EdgeRepulsion),
            spacing: 0.1,
            young_modulus: 1.0e4,
            poisson_ratio: 0.3,
            density: 1000.0,
            damping_ratio: 0.1,
            degrees_per_second: 10.0,
            max_degrees: 110.0,
            dt: 0.01,
            fixed_substeps: None,
            stop_at_first_inversion: false,
            self_contact: false,
            integrator: Integrator::Explicit,
        }
    }
}

const BONE_CENTRE: Real = 0.55;

impl LimbScene {
    /// Nodes along the limb.
    pub fn resolution(&self) -> usize {
        (2.0 / self.spacing).round() as usize + 1
    }

    /// The world (tissue, the held upper bone, the turning lower bone) and the lower bone.
    pub fn sim(&self) -> Result<(Sim, RigidBodyHandle), BuildError> {
        let mut world = DeformableWorld::new();
        world.set_dt(self.dt);
        world.pipeline.settings.integrator = self.integrator;
        world.physics.gravity = Vector::ZERO;
        let mut half = Vector::splat(0.3);
        half[0] = 1.0;
        let mut res = [0usize; DIM];
        for (d, r) in res.iter_mut().enumerate() {
            *r = (2.0 * half[d] / self.spacing).round() as usize + 1;
        }
        let mesh = Mesh::cuboid(half, res, CellKind::Simplex)?;
        let mut bone_half = Vector::splat(0.1);
        bone_half[0] = 0.4;
        let tolerance = 0.01 * self.spacing;
        let mut pins = Vec::new();
        for side in [-1.0, 1.0] {
            let body = world.physics.insert_body(
                RigidBodyBuilder::kinematic_position_based()
                    .translation(Vector::X * (BONE_CENTRE * side)),
            );
            let collider = world.physics.insert_collider(
                ColliderBuilder::new(cuboid(bone_half)).sensor(true),
                Some(body),
            );
            let co = &world.physics.colliders[collider];
            let nodes: Vec<u32> = (0..mesh.nodes().len() as u32)
                .filter(|&i| {
                    co.shape()
                        .distance_to_point(co.position(), mesh.nodes()[i as usize], true)
                        <= tolerance
                })
                .collect();
            pins.push((body, nodes));
        }
        let lower = pins[1].0;
        let mut spec = BodySpec::new(
            mesh,
            Vector::ZERO,
            Material {
                density: self.density,
                young_modulus: self.young_modulus,
                damping_ratio: self.damping_ratio,
                poisson_ratio: self.poisson_ratio,
            },
        );
        spec.pins = pins;
        spec.self_contact = self.self_contact;
        let sim = Sim::new(world, self.subject, spec, 2.0, self.fixed_substeps)?;
        Ok((sim, lower))
    }

    /// Runs the bend, calling `observe` after every step with the world and the fraction done.
    pub fn run_with(
        &self,
        mut observe: impl FnMut(&DeformableWorld, f64),
    ) -> Result<Record, BuildError> {
        let (mut sim, lower) = self.sim()?;
        let pins = sim.pinned_nodes();
        let steps = (self.max_degrees / self.degrees_per_second / self.dt).round() as usize;
        let mut first = None;
        let mut anchor_error: Real = 0.0;
        let mut self_penetration: Real = 0.0;
        for k in 0..steps {
            let degrees = self.degrees_per_second * self.dt * (k + 1) as Real;
            let rotation = math::rotation_from_angle(math::planar_angle(degrees.to_radians()));
            let pose = Pose::from_parts(rotation * (Vector::X * BONE_CENTRE), rotation);
            if let Some(b) = sim.world.physics.bodies.get_mut(lower) {
                b.set_next_kinematic_position(pose);
            }
            sim.step();
            for (node, body, local) in &pins {
                if let Some(b) = sim.world.physics.bodies.get(*body) {
                    let err = b
                        .position()
                        .transform_point(*local)
                        .distance(sim.positions()[*node as usize]);
                    anchor_error = anchor_error.max(err);
                }
            }
            self_penetration = self_penetration.max(self_interpenetration(
                sim.mesh(),
                sim.positions(),
                0.5 * self.spacing,
            ));
            observe(&sim.world, (k + 1) as f64 / steps as f64);
            if sim.inverted_elements() > 0 && first.is_none() {
                first = Some(degrees);
                if self.stop_at_first_inversion {
                    break;
                }
            }
            if sim.exploded() {
                break;
            }
        }
        let mut r = sim.record("limb", self.resolution());
        r.failure = crate::record::failure(&[
            (first.is_some(), "inverted cells"),
            (r.exploded, "exploded"),
        ]);
        r.failed = r.failure.is_some();
        r.first_failure = first.map(|d| d as f64);
        r.max_anchor_error = Some(anchor_error as f64);
        r.max_self_penetration = Some(self_penetration as f64);
        Ok(r)
    }

    /// Runs the bend.
    pub fn run(&self) -> Result<Record, BuildError> {
        self.run_with(|_, _| {})
    }
}
