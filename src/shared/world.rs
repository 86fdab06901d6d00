//! The bundled world for the simple case: rapier's `PhysicsWorld`, a `DeformableSet` and the
//! pipeline, stepped in the right order.

use super::attach::AttachError;
use super::body::Deformable;
use super::error::BuildError;
use super::events::DeformableEventHandler;
use super::integrator::Integrator;
use super::math::Real;
use super::pipeline::{DeformablePipeline, RigidSets};
use super::rapier::dynamics::{RigidBody, RigidBodyHandle};
use super::rapier::geometry::ColliderHandle;
use super::rapier::pipeline::PhysicsWorld;
use super::report::StepReport;
use super::set::{DeformableHandle, DeformableSet};

/// Rapier's [`PhysicsWorld`] plus deformables.
///
/// With the `serde` feature the whole world is one snapshot: serialize it mid-run, deserialize
/// it later, and stepping the restored world continues bit for bit as the original would have
/// (see [`snapshot`](super::snapshot) for what is saved and what is rebuilt).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
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
    ///
    /// A body too stiff for the step is accepted: each step then takes at most
    /// `pipeline.settings.max_substeps` substeps and drops the rest of the step for that body,
    /// which its report says (`substep_cap_hit`, `lost_time`). [`DeformableWorld::try_insert`]
    /// refuses it instead.
    ///
    /// A body whose explicit substeps follow its calibrated stability bound (or on which
    /// [`Integrator::Auto`] chooses by it, or whose implicit step chooses its Newton
    /// iterations over the whole body by it) has that bound calibrated here, once, rather than
    /// in its first step: that took 10 ms for each shape-matched pad of `scenes pinch`, whose
    /// first step at 1 ms then took five times its median step, and 10 ms of the res-9 `fall`
    /// cube's first 60 Hz midpoint step (six times its median).
    pub fn insert(&mut self, deformable: Deformable) -> DeformableHandle {
        let settings = &self.pipeline.settings;
        let implicit = settings.integrator.steps_implicitly(&deformable);
        if matches!(settings.integrator, Integrator::Auto { .. })
            || settings.calibrates(&deformable)
            || (implicit && settings.global_iterations.is_none())
        {
            deformable.calibrate();
        }
        self.deformables.insert(deformable)
    }

    /// Inserts a deformable unless one step at the current `dt` would need more substeps at
    /// rest than `pipeline.settings.max_substeps` ([`BuildError::TooStiff`]); the deformable
    /// is handed back with the error.
    pub fn try_insert(
        &mut self,
        deformable: Deformable,
    ) -> Result<DeformableHandle, (Box<Deformable>, BuildError)> {
        let settings = self.pipeline.settings;
        let dt = self.physics.integration_parameters.dt;
        let calibrated = settings.calibrates(&deformable);
        let substep = deformable.substep(settings.safety, calibrated);
        let substeps = f64::from(dt) / f64::from(substep);
        let fits = substeps.partial_cmp(&(settings.max_substeps as f64))
            != Some(std::cmp::Ordering::Greater)
            && substeps.is_finite();
        if settings.fixed_substeps.is_none() && !fits {
            let err = BuildError::TooStiff {
                substeps,
                substep,
                dt,
                max_substeps: settings.max_substeps,
            };
            return Err((Box::new(deformable), err));
        }
        Ok(self.deformables.insert(deformable))
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

    /// Binds nodes of a deformable to a rigid body at their current positions.
    pub fn attach_nodes(
        &mut self,
        deformable: DeformableHandle,
        body: RigidBodyHandle,
        nodes: &[u32],
    ) -> Result<usize, AttachError> {
        let d = self
            .deformables
            .get_mut(deformable)
            .ok_or(AttachError::NoSuchDeformable)?;
        d.attach_nodes(&self.physics.bodies, body, nodes)
    }

    /// Binds every node of a deformable inside `collider` (or within `tolerance` of it) to the
    /// collider's body.
    pub fn attach_nodes_inside(
        &mut self,
        deformable: DeformableHandle,
        collider: ColliderHandle,
        tolerance: Real,
    ) -> Result<usize, AttachError> {
        let d = self
            .deformables
            .get_mut(deformable)
            .ok_or(AttachError::NoSuchDeformable)?;
        d.attach_nodes_inside(
            &self.physics.bodies,
            &self.physics.colliders,
            collider,
            tolerance,
        )
    }

    /// Removes a rigid body (and its colliders and joints) from rapier and unbinds every node
    /// bound to it.
    pub fn remove_body(&mut self, body: RigidBodyHandle) -> Option<RigidBody> {
        for (_, d) in self.deformables.iter_mut() {
            d.detach_body(body);
        }
        self.physics.remove_body(body)
    }

    /// One step: deformables first (they see colliders where rapier left them), then rapier.
    pub fn step(&mut self) -> &StepReport {
        self.step_with_events(&())
    }

    /// [`DeformableWorld::step`], sending deformable contact events to `events`.
    pub fn step_with_events(&mut self, events: &dyn DeformableEventHandler) -> &StepReport {
        let w = &mut self.physics;
        self.pipeline.step_with_events(
            w.gravity,
            &w.integration_parameters,
            &mut self.deformables,
            RigidSets {
                bodies: &mut w.bodies,
                colliders: &w.colliders,
                broad_phase: &w.broad_phase,
            },
            events,
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

#[cfg(test)]
mod tests {
    use super::super::body::DeformableBuilder;
    use super::super::math::{Vector, DIM};
    use super::super::mesh::{CellKind, Mesh};
    use super::*;

    fn cube() -> Deformable {
        let mesh = Mesh::cuboid(Vector::splat(0.1), [3; DIM], CellKind::Simplex).unwrap();
        DeformableBuilder::new(mesh).build().unwrap()
    }

    #[test]
    fn insertion_calibrates_a_body_whose_step_reads_its_bound_and_no_other() {
        let (implicit, midpoint) = (
            Integrator::Implicit { iterations: 2 },
            Integrator::Midpoint { iterations: 2 },
        );
        for (integrator, fixed, global, calibrated) in [
            (Integrator::Explicit, None, None, true),
            (Integrator::Explicit, Some(10), None, false),
            (Integrator::Auto { iterations: 2 }, None, None, true),
            // The implicit steps choose their Newton iterations by it, unless told how many.
            (implicit, None, None, true),
            (midpoint, None, None, true),
            (implicit, None, Some(0), false),
            (midpoint, None, Some(2), false),
        ] {
            let mut world = DeformableWorld::new();
            world.pipeline.settings.integrator = integrator;
            world.pipeline.settings.fixed_substeps = fixed;
            world.pipeline.settings.global_iterations = global;
            let h = world.insert(cube());
            assert_eq!(
                world.deformables[h].rest.calibrated(),
                calibrated,
                "{integrator:?}, fixed substeps {fixed:?}, global iterations {global:?}"
            );
        }
    }
}
