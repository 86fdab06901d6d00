//! The `manipulator` scene (shape-based elasticity paper, §3.5).

use super::super::lib::math::{Real, Vector, UP};
use super::super::lib::rapier::dynamics::RigidBodyBuilder;
use super::super::lib::rapier::geometry::ColliderBuilder;
use super::super::lib::BuildError;
use super::super::lib::DeformableWorld;
use super::fall::{cuboid, FallScene};
use super::sim::RAPIER_SKIN;
use super::Record;

/// The `fall` cube resting on the ground, struck again and again from above by a kinematic
/// paddle (0.4 m square, 0.2 m thick): after `settle` s, each strike takes `period` s — the
/// paddle goes down from 0.2 m above the cube's top until it is `depth` of the cube's size into
/// it and back along a cosine profile in the first half, then waits.
///
/// `first_failure` is the strike after which (at the end of its period) an element is left
/// inverted; `shape_error` is measured after the last strike.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct ManipulatorScene {
    /// The cube, its material and stepping (its `drop_height` and `seconds` are ignored).
    pub cube: FallScene,
    /// Number of strikes.
    pub strikes: usize,
    /// Duration of one strike, s.
    pub period: Real,
    /// How deep the paddle goes into the cube, as a fraction of its size.
    pub depth: Real,
    /// Time the cube is left to settle before the first strike, s.
    pub settle: Real,
}

impl Default for ManipulatorScene {
    /// The default `fall` cube, 20 strikes of 1 s, 40 % deep, settle 0.5 s.
    fn default() -> Self {
        ManipulatorScene {
            cube: FallScene::default(),
            strikes: 20,
            period: 1.0,
            depth: 0.4,
            settle: 0.5,
        }
    }
}

impl ManipulatorScene {
    /// Runs the strikes, calling `observe` after every step with the world and the fraction
    /// done.
    pub fn run_with(
        &self,
        mut observe: impl FnMut(&DeformableWorld, f64),
    ) -> Result<Record, BuildError> {
        let c = &self.cube;
        let mut world = c.ground_world();
        let mut half = Vector::splat(0.2 * c.size);
        half[1] = 0.1 * c.size;
        let high = c.size + RAPIER_SKIN + 0.2 * c.size + half[1];
        let travel = 0.2 * c.size + self.depth * c.size;
        let (paddle, _) = world.physics.insert(
            RigidBodyBuilder::kinematic_position_based().translation(UP * high),
            ColliderBuilder::new(cuboid(half)).friction(c.friction),
        );
        let mut sim = c.sim_in(world, RAPIER_SKIN)?;

        let total = self.settle + self.strikes as Real * self.period;
        let steps = (total / c.dt).round() as usize;
        let per_strike = (self.period / c.dt).round().max(1.0) as usize;
        let settle_steps = (self.settle / c.dt).round() as usize;
        let mut first = None;
        let mut max_penetration: Real = 0.0;
        for k in 0..steps {
            let t = (k as Real + 1.0) * c.dt - self.settle;
            let phase = if t > 0.0 {
                (t % self.period) / (0.5 * self.period)
            } else {
                2.0
            };
            let down = if phase < 2.0 {
                0.5 * travel * (1.0 - (std::f64::consts::PI as Real * phase).cos())
            } else {
                0.0
            };
            if let Some(b) = sim.world.physics.bodies.get_mut(paddle) {
                b.set_next_kinematic_translation(UP * (high - down));
            }
            sim.step();
            max_penetration = max_penetration.max(-sim.lowest());
            observe(&sim.world, (k + 1) as f64 / steps as f64);
            let done = k + 1;
            if done > settle_steps && (done - settle_steps).is_multiple_of(per_strike) {
                let strike = (done - settle_steps) / per_strike;
                if first.is_none() && sim.inverted_elements() > 0 {
                    first = Some(strike);
                }
            }
            if sim.exploded() {
                break;
            }
        }
        let mut r = sim.record("manipulator", c.resolution);
        r.rest_com = Some(sim.center_of_mass().dot(UP) as f64);
        r.max_penetration = Some(max_penetration as f64);
        r.shape_error = Some(sim.shape_error() as f64);
        r.failure = crate::record::failure(&[
            (r.exploded, "exploded"),
            (first.is_some(), "cells left inverted after a strike"),
        ]);
        r.failed = r.failure.is_some();
        r.first_failure = first.map(|s| s as f64);
        Ok(r)
    }

    /// Runs the strikes.
    pub fn run(&self) -> Result<Record, BuildError> {
        self.run_with(|_, _| {})
    }
}
