//! The bundled world for the simple case: rapier's `PhysicsWorld`, a `DeformableSet` and the
//! pipeline, stepped in the right order.

use super::body::Deformable;
use super::math::Real;
use super::pipeline::DeformablePipeline;
use super::rapier::pipeline::PhysicsWorld;
use super::report::StepReport;
use super::set::{DeformableHandle, DeformableSet};

/// Rapier's [`PhysicsWorld`] plus deformables.
pub struct DeformableWorld {
    /// The rigid-body world (bodies, colliders, joints, gravity, `integration_parameters.dt`).
    pub physics: PhysicsWorld,
    /// The deformables.
    pub deformables: DeformableSet,
    /// The deformable pipeline (its `settings` are yours to change).
    pub pipeline: DeformablePipeline,
    time: Real,
    steps: u64,
}

impl Default for DeformableWorld {
    fn default() -> Self {
        Self::new()
    }
}

impl DeformableWorld {
    /// An empty world with rapier's defaults (gravity `-9.81` along y, `dt = 1/60` s).
    pub fn new() -> Self {
        DeformableWorld {
            physics: PhysicsWorld::new(),
            deformables: DeformableSet::new(),
            pipeline: DeformablePipeline::new(),
            time: 0.0,
            steps: 0,
        }
    }

    /// Inserts a deformable.
    pub fn insert(&mut self, deformable: Deformable) -> DeformableHandle {
        self.deformables.insert(deformable)
    }

    /// Sets the step length (rapier's `integration_parameters.dt`).
    pub fn set_dt(&mut self, dt: Real) {
        self.physics.integration_parameters.dt = dt;
    }

    /// Simulated time, s.
    pub fn time(&self) -> Real {
        self.time
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// One step: deformables first (they see colliders where rapier left them), then rapier.
    pub fn step(&mut self) -> &StepReport {
        if self.steps == 0 {
            // Rapier fills its broad phase during a step; before the first one it is empty and
            // the deformables would see no collider.
            self.physics.detect_collisions(&(), &());
        }
        let w = &mut self.physics;
        self.pipeline.step(
            w.gravity,
            &w.integration_parameters,
            &mut self.deformables,
            &mut w.bodies,
            &w.colliders,
            &w.broad_phase,
        );
        self.physics.step();
        self.time += self.physics.integration_parameters.dt;
        self.steps += 1;
        self.pipeline.report()
    }

    /// The report of the last step.
    pub fn report(&self) -> &StepReport {
        self.pipeline.report()
    }
}
