//! Ready-made scenes from `DESIGN.md` §6, shared by the examples, the tests and the benches so
//! that they all measure the same thing.

use std::time::Instant;

use super::body::DeformableBuilder;
use super::error::BuildError;
use super::material::Material;
use super::math::{self, Real, Vector, DIM, UP};
use super::mesh::CellKind;
use super::model::ElementModel;
use super::rapier::dynamics::{RigidBodyBuilder, RigidBodyHandle};
use super::rapier::geometry::ColliderBuilder;
use super::set::DeformableHandle;
use super::world::DeformableWorld;

/// A soft box (cube in 3D, square in 2D) dropped on a fixed ground whose top is at height 0.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct FallScene {
    /// Element model.
    pub model: ElementModel,
    /// Nodes per edge.
    pub resolution: usize,
    /// Cell kind of the lattice.
    pub cells: CellKind,
    /// Edge length of the box, m.
    pub size: Real,
    /// Mass of the box, kg (sets the density).
    pub mass: Real,
    /// Young's modulus, Pa.
    pub young_modulus: Real,
    /// Damping ratio.
    pub damping_ratio: Real,
    /// Height of the box's bottom at the start, m.
    pub drop_height: Real,
    /// Friction coefficient of both the box and the ground.
    pub friction: Real,
    /// Restitution coefficient of both the box and the ground.
    pub restitution: Real,
    /// Step length, s.
    pub dt: Real,
    /// Simulated duration, s.
    pub seconds: Real,
}

impl Default for FallScene {
    /// The `fall` scene: 1 m, 1 kg, E = 10⁴ Pa, bottom at 2 m (centre of mass at 2.5 m),
    /// damping ratio 0.1, friction 0.5, restitution 0.5, dt 1 ms, 3 s, 5 nodes per edge,
    /// simplex cells.
    fn default() -> Self {
        FallScene {
            model: ElementModel::EdgeRepulsion,
            resolution: 5,
            cells: CellKind::Simplex,
            size: 1.0,
            mass: 1.0,
            young_modulus: 1.0e4,
            damping_ratio: 0.1,
            drop_height: 2.0,
            friction: 0.5,
            restitution: 0.5,
            dt: 1.0e-3,
            seconds: 3.0,
        }
    }
}

/// What a fall-and-bounce run measured.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FallOutcome {
    /// Nodes of the body.
    pub nodes: usize,
    /// Cells of the body.
    pub elements: usize,
    /// Simulated time, s.
    pub sim_seconds: Real,
    /// Wall time of the stepping loop, s.
    pub wall_seconds: f64,
    /// Time of the first contact, s.
    pub first_impact: Option<Real>,
    /// Whether the body left the ground completely after the first impact.
    pub bounced: bool,
    /// Highest centre-of-mass height after leaving the ground, m (`None` without a bounce).
    pub bounce_apex_com: Option<Real>,
    /// Centre-of-mass height at the end, m.
    pub rest_com: Real,
    /// Kinetic energy at the end, J.
    pub final_kinetic_energy: Real,
    /// Deepest node penetration over the run, m.
    pub max_penetration: Real,
    /// Most inverted cells at any step.
    pub max_inverted_elements: usize,
    /// Inverted cells at the end.
    pub final_inverted_elements: usize,
    /// Smallest cell volume ratio over the run.
    pub min_volume_ratio: Real,
    /// Whether the state ever turned non-finite.
    pub non_finite: bool,
    /// Mean substeps per step.
    pub mean_substeps: Real,
    /// Largest substeps in a step.
    pub max_substeps: usize,
}

impl FallOutcome {
    /// Wall seconds per simulated second.
    pub fn wall_per_sim_second(&self) -> f64 {
        self.wall_seconds / self.sim_seconds.max(Real::MIN_POSITIVE) as f64
    }
}

impl FallScene {
    /// The world: a fixed ground (top at height 0) and the box.
    pub fn world(&self) -> Result<(DeformableWorld, DeformableHandle), BuildError> {
        let mut world = DeformableWorld::new();
        world.set_dt(self.dt);
        let mut half = Vector::splat(20.0);
        half[1] = 0.5;
        let mut ground_at = Vector::ZERO;
        ground_at[1] = -0.5;
        world.physics.insert(
            RigidBodyBuilder::fixed().translation(ground_at),
            ColliderBuilder::new(cuboid_shape(half))
                .friction(self.friction)
                .restitution(self.restitution),
        );
        let volume = self.size.powi(DIM as i32);
        let body =
            DeformableBuilder::cuboid(Vector::splat(0.5 * self.size), [self.resolution; DIM])
                .cells(self.cells)
                .model(self.model)
                .material(Material {
                    density: self.mass / volume,
                    young_modulus: self.young_modulus,
                    damping_ratio: self.damping_ratio,
                    ..Default::default()
                })
                .friction(self.friction)
                .restitution(self.restitution)
                .translation(UP * (self.drop_height + 0.5 * self.size))
                .build()?;
        let handle = world.insert(body);
        Ok((world, handle))
    }

    /// Runs the scene, calling `observe` after every step.
    pub fn run_with(
        &self,
        mut observe: impl FnMut(&DeformableWorld, DeformableHandle),
    ) -> Result<FallOutcome, BuildError> {
        let (mut world, h) = self.world()?;
        let steps = (self.seconds / self.dt).round() as usize;
        let mut out = FallOutcome {
            nodes: world.deformables[h].num_nodes(),
            elements: world.deformables[h].mesh().num_cells(),
            min_volume_ratio: 1.0,
            ..Default::default()
        };
        let mut rising_max = Real::NEG_INFINITY;
        let mut substeps_total = 0usize;
        let mut wall = 0.0;
        for _ in 0..steps {
            let t0 = Instant::now();
            let report = world.step();
            wall += t0.elapsed().as_secs_f64();
            let r = report.get(h).cloned().unwrap_or_default();
            let body = &world.deformables[h];
            let com = body.center_of_mass().dot(UP);
            substeps_total += r.substeps;
            out.max_substeps = out.max_substeps.max(r.substeps);
            out.max_penetration = out.max_penetration.max(r.max_penetration);
            out.max_inverted_elements = out.max_inverted_elements.max(r.inverted_elements);
            out.min_volume_ratio = out.min_volume_ratio.min(r.min_volume_ratio);
            out.non_finite |= r.non_finite;
            if r.contacts > 0 && out.first_impact.is_none() {
                out.first_impact = Some(world.time());
            }
            // The first flight after the first impact: airborne and rising, until the centre
            // of mass turns down.
            let vy = body.center_of_mass_velocity().dot(UP);
            if out.first_impact.is_some() && out.bounce_apex_com.is_none() && r.contacts == 0 {
                if vy > 0.0 {
                    out.bounced = true;
                    rising_max = rising_max.max(com);
                } else if out.bounced {
                    out.bounce_apex_com = Some(rising_max.max(com));
                }
            }
            observe(&world, h);
        }
        let body = &world.deformables[h];
        out.sim_seconds = world.time();
        out.wall_seconds = wall;
        out.rest_com = body.center_of_mass().dot(UP);
        out.final_kinetic_energy = body.kinetic_energy();
        out.final_inverted_elements = body.inverted_elements();
        out.mean_substeps = substeps_total as Real / steps.max(1) as Real;
        Ok(out)
    }

    /// Runs the scene.
    pub fn run(&self) -> Result<FallOutcome, BuildError> {
        self.run_with(|_, _| {})
    }
}

fn cuboid_shape(half: Vector) -> super::rapier::geometry::SharedShape {
    super::rapier::geometry::SharedShape::new(super::rapier::geometry::Cuboid::new(half))
}

/// Cooper & Maddock's limb (§5): two kinematic bones inside a slab of tissue, bound to it with
/// [`Deformable::attach_nodes_inside`]; the upper bone is held, the lower one turned about the
/// hinge at the origin, bending the limb so the tissue above the hinge is crushed.
///
/// The tissue spans `x ∈ [−1, 1]` and `±0.3` across (a square section in 3D); the bones run
/// from `±0.15` to `±0.95` along x with a half thickness of `0.1`, so the hinge region is free
/// tissue and every cell that inverts does so because of its model, not because its nodes are
/// all carried by bones.
///
/// [`Deformable::attach_nodes_inside`]: super::Deformable::attach_nodes_inside
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct LimbScene {
    /// Element model.
    pub model: ElementModel,
    /// Lattice spacing, m.
    pub spacing: Real,
    /// Tissue Young's modulus, Pa.
    pub young_modulus: Real,
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
    /// Stop at the first inverted element.
    pub stop_at_first_inversion: bool,
}

impl Default for LimbScene {
    /// 0.1 m spacing, E = 10⁴ Pa, 1000 kg/m³, ζ = 0.1, 10°/s up to 110°, dt = 10 ms, no gravity.
    fn default() -> Self {
        LimbScene {
            model: ElementModel::EdgeRepulsion,
            spacing: 0.1,
            young_modulus: 1.0e4,
            density: 1000.0,
            damping_ratio: 0.1,
            degrees_per_second: 10.0,
            max_degrees: 110.0,
            dt: 0.01,
            stop_at_first_inversion: false,
        }
    }
}

/// What a limb run measured.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LimbOutcome {
    /// Nodes of the tissue.
    pub nodes: usize,
    /// Cells of the tissue.
    pub elements: usize,
    /// Nodes bound to the bones.
    pub attached_nodes: usize,
    /// Bone angle (degrees) at the first inverted element, if any.
    pub first_inversion_degrees: Option<Real>,
    /// Angle reached, degrees.
    pub final_degrees: Real,
    /// Most inverted elements at any step.
    pub max_inverted_elements: usize,
    /// Smallest volume ratio over the run.
    pub min_volume_ratio: Real,
    /// Largest distance of a bound node from its anchor over the run, m.
    pub max_anchor_error: Real,
    /// Whether the state turned non-finite.
    pub non_finite: bool,
    /// Wall time of the stepping loop, s.
    pub wall_seconds: f64,
}

impl LimbScene {
    /// The world: tissue, the held upper bone and the turning lower bone.
    pub fn world(
        &self,
    ) -> Result<(DeformableWorld, DeformableHandle, RigidBodyHandle), BuildError> {
        let mut world = DeformableWorld::new();
        world.set_dt(self.dt);
        world.physics.gravity = Vector::ZERO;
        let mut half = Vector::splat(0.3);
        half[0] = 1.0;
        let mut res = [0usize; DIM];
        for (d, r) in res.iter_mut().enumerate() {
            *r = (2.0 * half[d] / self.spacing).round() as usize + 1;
        }
        let tissue = DeformableBuilder::cuboid(half, res)
            .model(self.model)
            .material(Material {
                density: self.density,
                young_modulus: self.young_modulus,
                damping_ratio: self.damping_ratio,
                ..Default::default()
            })
            .build()?;
        let tissue = world.insert(tissue);
        let mut bone_half = Vector::splat(0.1);
        bone_half[0] = 0.4;
        let mut bone_handles = Vec::new();
        for side in [-1.0, 1.0] {
            let body = world.physics.insert_body(
                RigidBodyBuilder::kinematic_position_based().translation(Vector::X * (0.55 * side)),
            );
            let collider = world
                .physics
                .insert_collider(ColliderBuilder::new(cuboid_shape(bone_half)), Some(body));
            world
                .attach_nodes_inside(tissue, collider, 0.01 * self.spacing)
                .map_err(|_| BuildError::InvalidParameter {
                    name: "bone",
                    value: side,
                    expected: "a bone that binds tissue",
                })?;
            bone_handles.push(body);
        }
        Ok((world, tissue, bone_handles[1]))
    }

    /// Runs the bend, calling `observe` after every step with the current angle in degrees.
    pub fn run_with(
        &self,
        mut observe: impl FnMut(&DeformableWorld, DeformableHandle, Real),
    ) -> Result<LimbOutcome, BuildError> {
        let (mut world, h, lower) = self.world()?;
        let body = &world.deformables[h];
        let mut out = LimbOutcome {
            nodes: body.num_nodes(),
            elements: body.mesh().num_cells(),
            attached_nodes: body.attachments().len(),
            min_volume_ratio: 1.0,
            ..Default::default()
        };
        let steps = (self.max_degrees / self.degrees_per_second / self.dt).round() as usize;
        let mut wall = 0.0;
        for k in 0..steps {
            let degrees = self.degrees_per_second * self.dt * (k + 1) as Real;
            let rotation = math::rotation_from_angle(math::planar_angle(degrees.to_radians()));
            let pose = super::math::Pose::from_parts(rotation * (Vector::X * 0.55), rotation);
            if let Some(b) = world.physics.bodies.get_mut(lower) {
                b.set_next_kinematic_position(pose);
            }
            let t0 = Instant::now();
            let report = world.step().get(h).cloned().unwrap_or_default();
            wall += t0.elapsed().as_secs_f64();
            out.final_degrees = degrees;
            out.max_inverted_elements = out.max_inverted_elements.max(report.inverted_elements);
            out.min_volume_ratio = out.min_volume_ratio.min(report.min_volume_ratio);
            out.non_finite |= report.non_finite;
            let tissue = &world.deformables[h];
            for a in tissue.attachments() {
                if let Some(b) = world.physics.bodies.get(a.body) {
                    let err = b
                        .position()
                        .transform_point(a.anchor)
                        .distance(tissue.positions()[a.node as usize]);
                    out.max_anchor_error = out.max_anchor_error.max(err);
                }
            }
            observe(&world, h, degrees);
            if report.inverted_elements > 0 && out.first_inversion_degrees.is_none() {
                out.first_inversion_degrees = Some(degrees);
                if self.stop_at_first_inversion {
                    break;
                }
            }
            if report.non_finite {
                break;
            }
        }
        out.wall_seconds = wall;
        Ok(out)
    }

    /// Runs the bend.
    pub fn run(&self) -> Result<LimbOutcome, BuildError> {
        self.run_with(|_, _, _| {})
    }
}
