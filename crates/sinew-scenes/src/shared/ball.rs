//! The `ball` scene: a small stiff silicone ball dropped at a game's frame rate (issue 15).

use super::super::lib::math::{Real, UP};
use super::super::lib::mesh::{CellKind, Mesh};
use super::super::lib::model::ElementModel;
use super::super::lib::rapier::parry::shape::Ball;
use super::super::lib::BuildError;
use super::super::lib::DeformableWorld;
use super::super::lib::Integrator;
use super::super::lib::Material;
use super::fall::FallScene;
use super::sim::{BodySpec, Bounce, Sim};
use super::subject::Subject;
use super::Record;

/// A silicone ball (`Mesh::from_shape` of a ball, simplex cells) dropped on a fixed ground
/// whose top is at height 0. The record gives the cost per simulated second (times `dt` for
/// the cost per step), the bounce apex, the rest height, inverted cells and penetration.
#[derive(Copy, Clone, Debug)]
pub struct BallScene {
    /// The model under test.
    pub subject: Subject,
    /// Radius, m.
    pub radius: Real,
    /// Cell size of the mesh, m.
    pub cell_size: Real,
    /// Young's modulus, Pa.
    pub young_modulus: Real,
    /// Poisson's ratio.
    pub poisson_ratio: Real,
    /// Density, kg/m³ (or kg/m² in 2D).
    pub density: Real,
    /// Damping ratio.
    pub damping_ratio: Real,
    /// Height of the ball's bottom above the ground, m.
    pub drop_height: Real,
    /// Friction of the ball and the ground.
    pub friction: Real,
    /// Restitution of the ball and the ground.
    pub restitution: Real,
    /// Step length, s.
    pub dt: Real,
    /// Simulated time, s.
    pub seconds: Real,
    /// sinew's integrator.
    pub integrator: Integrator,
}

impl Default for BallScene {
    /// Radius 10 cm, 2 cm cells (823 nodes in 3D), E = 10⁶ Pa, ν = 0.3, ρ = 1100 kg/m³,
    /// damping ratio 0.1, bottom 0.5 m up, friction 0.5, restitution 0.5, dt 1/60 s, 3 s, edge
    /// repulsion, sinew's default integrator (what a new user runs).
    fn default() -> Self {
        BallScene {
            subject: Subject::Sinew(ElementModel::EdgeRepulsion),
            radius: 0.1,
            cell_size: 0.02,
            young_modulus: 1.0e6,
            poisson_ratio: 0.3,
            density: 1100.0,
            damping_ratio: 0.1,
            drop_height: 0.5,
            friction: 0.5,
            restitution: 0.5,
            dt: 1.0 / 60.0,
            seconds: 3.0,
            integrator: Integrator::default(),
        }
    }
}

impl BallScene {
    /// The world: a fixed ground and the ball above it.
    pub fn sim(&self) -> Result<Sim, BuildError> {
        let world = FallScene {
            dt: self.dt,
            integrator: self.integrator,
            friction: self.friction,
            restitution: self.restitution,
            ..FallScene::default()
        }
        .ground_world();
        let mesh = Mesh::from_shape(&Ball::new(self.radius), self.cell_size, CellKind::Simplex)?;
        let material = Material {
            density: self.density,
            young_modulus: self.young_modulus,
            damping_ratio: self.damping_ratio,
            poisson_ratio: self.poisson_ratio,
        };
        let mut spec = BodySpec::new(mesh, UP * (self.drop_height + self.radius), material);
        spec.friction = self.friction;
        spec.restitution = self.restitution;
        Sim::new(world, self.subject, spec, 2.0 * self.radius, None)
    }

    /// Runs the scene, calling `observe` after every step with the world and the fraction done.
    pub fn run_with(
        &self,
        mut observe: impl FnMut(&DeformableWorld, f64),
    ) -> Result<Record, BuildError> {
        let mut sim = self.sim()?;
        let steps = (self.seconds / self.dt).round().max(1.0) as usize;
        let mut bounce = Bounce::new(0.0, 2.0 * self.radius);
        for k in 0..steps {
            sim.step();
            bounce.observe(&sim);
            observe(&sim.world, (k + 1) as f64 / steps as f64);
            if sim.exploded() {
                break;
            }
        }
        let sank = bounce.max_penetration() > 0.25 * self.radius;
        let res = (2.0 * self.radius / self.cell_size).round() as usize;
        Ok(bounce.record(&sim, "ball", res, &[(sank, "sank into the ground")]))
    }

    /// Runs the scene.
    pub fn run(&self) -> Result<Record, BuildError> {
        self.run_with(|_, _| {})
    }
}
