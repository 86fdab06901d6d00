//! A user's own fall-and-bounce scenario, run and measured as the harness's scenes are: their
//! world (colliders, floors, other bodies), their mesh and material, one body dropped in it;
//! the result is a [`Record`] of plain numbers to assert on in an integration test.
//!
//! ```
//! use sinew::dim3::math::Vector;
//! use sinew::dim3::rapier::prelude::{ColliderBuilder, RigidBodyBuilder};
//! use sinew::dim3::{mesh::CellKind, DeformableWorld, ElementModel, Material, Mesh};
//! use sinew_scenes::dim3::testing::DropTest;
//!
//! let mut world = DeformableWorld::new(); // dt = 1/60 s
//! world.physics.insert(RigidBodyBuilder::fixed(), ColliderBuilder::cuboid(5.0, 0.1, 5.0));
//! let mesh = Mesh::cuboid(Vector::splat(0.25), [4; 3], CellKind::Simplex).unwrap();
//! let record = DropTest::new(world, mesh)
//!     .material(Material { density: 400.0, young_modulus: 2e4, damping_ratio: 0.5, ..Default::default() })
//!     .model(ElementModel::EdgeRepulsion)
//!     .translation(Vector::new(0.0, 1.0, 0.0))
//!     .floor_height(0.1)
//!     .seconds(3.0)
//!     .run()
//!     .unwrap();
//! assert_eq!(record.max_inverted_elements, 0);
//! assert!(record.max_penetration.unwrap() < 1e-3);
//! // Rests on the floor's top, its centre 1.4 cm lower under its weight (ρ g H²/3E = 1.6 cm).
//! assert!((record.rest_com.unwrap() - 0.336).abs() < 0.005);
//! ```
//!
//! The mesh may come from a file or an asset: a volume mesh (`sinew::dimN::mesh::io`),
//! or in 3D a surface (`sinew::dim3::surface`, features `stl`, `obj`, `gltf`) filled by
//! `Mesh::stuffed`.

use super::super::lib::math::{Real, Vector};
use super::super::lib::mesh::Mesh;
use super::super::lib::{BuildError, DeformableWorld, Material};
use super::sim::{BodySpec, Bounce, Sim};
use super::subject::Subject;
use super::Record;

/// One soft body dropped into a world of the user's (see the module docs), built in rapier's
/// style: [`DropTest::new`], then what differs from the defaults, then [`DropTest::run`].
pub struct DropTest {
    world: DeformableWorld,
    mesh: Mesh,
    material: Material,
    subject: Subject,
    translation: Vector,
    friction: Real,
    restitution: Real,
    floor_height: Real,
    seconds: Real,
}

impl DropTest {
    /// `mesh` (its rest shape, in body coordinates) dropped in `world` (the user's colliders
    /// and bodies; its `dt` is the step). Defaults: [`Material::default`], edge repulsion,
    /// at the origin, friction and restitution 0.5, the floor's top at 0, 3 s.
    pub fn new(world: DeformableWorld, mesh: Mesh) -> Self {
        DropTest {
            world,
            mesh,
            material: Material::default(),
            subject: Subject::Sinew(super::super::lib::ElementModel::EdgeRepulsion),
            translation: Vector::ZERO,
            friction: 0.5,
            restitution: 0.5,
            floor_height: 0.0,
            seconds: 3.0,
        }
    }

    /// The body's material.
    pub fn material(mut self, material: Material) -> Self {
        self.material = material;
        self
    }

    /// sinew's element model, or rapier's soft body as a peer (a [`Subject`]).
    pub fn model(mut self, subject: impl Into<Subject>) -> Self {
        self.subject = subject.into();
        self
    }

    /// Where the mesh's origin goes.
    pub fn translation(mut self, translation: Vector) -> Self {
        self.translation = translation;
        self
    }

    /// The body's friction coefficient.
    pub fn friction(mut self, friction: Real) -> Self {
        self.friction = friction;
        self
    }

    /// The body's restitution coefficient.
    pub fn restitution(mut self, restitution: Real) -> Self {
        self.restitution = restitution;
        self
    }

    /// The height of the floor's top, for the penetration and the bounce.
    pub fn floor_height(mut self, height: Real) -> Self {
        self.floor_height = height;
        self
    }

    /// Simulated time, s.
    pub fn seconds(mut self, seconds: Real) -> Self {
        self.seconds = seconds;
        self
    }

    /// Runs the drop. The record holds the first bounce's apex and the rest height (centre of
    /// mass), the deepest node below the floor's top, inverted cells (most, and at the end),
    /// the smallest volume ratio, the kinetic energy at the end, substeps and wall time.
    pub fn run(self) -> Result<Record, BuildError> {
        let dt = self.world.physics.integration_parameters.dt;
        let size: Real = self
            .mesh
            .nodes()
            .iter()
            .map(|p| p.abs().max_element() * 2.0)
            .fold(0.0, Real::max);
        let mut spec = BodySpec::new(self.mesh, self.translation, self.material);
        spec.friction = self.friction;
        spec.restitution = self.restitution;
        let mut sim = Sim::new(self.world, self.subject, spec, size.max(1e-6), None)?;
        let steps = (self.seconds / dt).round().max(1.0) as usize;
        let mut bounce = Bounce::new(self.floor_height, size.max(1e-6));
        for _ in 0..steps {
            sim.step();
            bounce.observe(&sim);
            if sim.exploded() {
                break;
            }
        }
        Ok(bounce.record(&sim, "drop", 0, &[]))
    }
}
