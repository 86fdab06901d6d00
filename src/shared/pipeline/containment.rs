//! Phase 4 of a body's step: a body that blew up is rolled back and frozen.

use super::super::body::Deformable;
use super::super::math::{Real, Vector, DIM};
use super::super::model::volume::Ratios;
use super::super::rapier::dynamics::RigidBodySet;
use super::super::threads;
use super::{RigidHold, StepContext, Touch};

/// Checks the state after the substeps: non-finite, so far out that it can only be a blow-up
/// (|x| or |v| above 1e8), or a cell stretched past `max_stretch` in every direction. Such a
/// body is rolled back to the start of the step and frozen, and the dynamic bodies it pushed
/// get their state back; the report says which.
///
/// Returns the cell qualities of the state the body ends the step in, when it was sane (one
/// pass over the cells serves the stretch test, the report and, for the springs models, the
/// next step's first forces: [`Deformable::measure_end`]), or `None` after a rollback.
pub(super) fn contain(
    body: &mut Deformable,
    ctx: &StepContext<'_>,
    bodies: &mut RigidBodySet,
    (rigid, touch): (&RigidHold, &mut Touch),
) -> Option<Quality> {
    let finite = within(&body.state.positions, 1e8) && within(&body.state.velocities, 1e8);
    let most = ctx.settings.max_stretch.powi(DIM as i32);
    let quality = finite.then(|| Quality::of(body, most));
    let exploded = quality.is_some_and(|q| q.stretched);
    body.last.report.non_finite = !finite;
    body.last.report.exploded = exploded;
    if !finite || exploded {
        body.step.restore(&mut body.state);
        body.activation.frozen = true;
        // A blow-up must not launch the bodies it pushed; restored, they took no impulse of
        // this body's and get no compensation for one.
        rigid.backup.restore(bodies);
        touch.pushed.clear();
    }
    quality.filter(|_| !exploded)
}

/// Whether every component of `values` is finite and below `bound` in magnitude: 64 vectors at
/// a time without a branch each, so that the comparisons vectorize.
fn within(values: &[Vector], bound: Real) -> bool {
    values.chunks(64).all(|chunk| {
        chunk
            .iter()
            .fold(true, |ok, v| ok & v.abs().cmplt(Vector::splat(bound)).all())
    })
}

/// The cells' quality (signed volume over rest volume) over a body, and its elastic energy
/// (measured in the same pass over the cells when the model has a volumetric term).
#[derive(Copy, Clone, Debug)]
pub(super) struct Quality {
    /// Cells collapsed or inverted (quality ≤ 0).
    pub inverted: usize,
    /// The smallest quality.
    pub min_ratio: Real,
    /// Whether a cell's quality is above the stretch limit it was measured with.
    pub stretched: bool,
    /// The elastic energy.
    pub elastic: Real,
}

impl Quality {
    /// At the body's positions (`most`: the stretch limit, infinite for none), by the body's
    /// end-of-step measure.
    pub fn of(body: &mut Deformable, most: Real) -> Quality {
        let limited = most.is_finite();
        let (elastic, ratios) = body.measure_end();
        let (mesh, x) = (&body.rest.mesh, &body.state.positions);
        let ratios = ratios.unwrap_or_else(|| {
            let part = |cells: std::ops::Range<usize>| {
                let mut r = Ratios::NONE;
                for c in cells {
                    let ratio = mesh.cell_quality(c, x);
                    if ratio <= 0.0 {
                        r.inverted += 1;
                    }
                    r.least = r.least.min(ratio);
                    r.most = r.most.max(ratio);
                }
                r
            };
            threads::chunked_fold(mesh.num_cells(), part, Ratios::and).unwrap_or(Ratios::NONE)
        });
        Quality {
            inverted: ratios.inverted,
            min_ratio: ratios.least,
            stretched: limited && ratios.most > most,
            elastic,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::super::body::DeformableBuilder;
    use super::super::super::math::UP;
    use super::super::super::model::{Accumulator, ElementModel};
    use super::super::super::rapier::geometry::{Cuboid, SharedShape};
    use super::super::super::rapier::prelude::{ColliderBuilder, RigidBodyBuilder};
    use super::super::super::world::DeformableWorld;
    use super::*;

    #[test]
    fn a_springs_step_ends_with_the_forces_its_next_step_starts_from() {
        use super::super::super::material::{FlowIn, Plasticity};
        // A soft plastic cube flows on landing: flows drop the kept forces, and a flow undone
        // (one that would raise the energy) may move rest lengths by their last bit.
        let plastic = Plasticity {
            yield_strain: 0.002,
            flow_rate: Real::INFINITY,
            max_strain: 1.0,
            flow: FlowIn::Both,
        };
        let cases = [
            (ElementModel::Springs, None),
            (ElementModel::NonlinearSprings, None),
            (ElementModel::Springs, Some(plastic)),
        ];
        for (model, plasticity) in cases {
            let scene = || {
                let mut world = DeformableWorld::new();
                let mut half = Vector::splat(5.0);
                half[1] = 0.5;
                world.physics.insert(
                    RigidBodyBuilder::fixed().translation(-UP * 0.5),
                    ColliderBuilder::new(SharedShape::new(Cuboid::new(half))),
                );
                let mut body = DeformableBuilder::cuboid(Vector::splat(0.25), [5; DIM])
                    .model(model)
                    .translation(UP * 0.3);
                if let Some(p) = plasticity {
                    body = body.plasticity(p);
                }
                let h = world.insert(body.build().unwrap());
                (world, h)
            };
            let ((mut world, h), (mut twin, _)) = (scene(), scene());
            let (mut kept_steps, mut flowed) = (0, 0.0);
            for step in 0..40 {
                world.step();
                let body = world.deformables.get_mut(h).unwrap();
                flowed += body.report().plastic_dissipation;
                let memo = &body.step.energy_memo;
                assert!(
                    plasticity.is_some() || memo.forces && memo.pending,
                    "{model:?}, step {step}"
                );
                // What the next step takes is what it would evaluate.
                let (x, v) = (&body.state.positions, &body.state.velocities);
                let mut fresh = Accumulator::new(x.len());
                let limit = body.state.elements.accumulate(x, v, &mut fresh);
                let kept = memo.forces.then(|| memo.acc.clone());
                body.refresh_forces();
                assert!(!body.step.energy_memo.forces, "{model:?}: not taken");
                let bits = |a: &Accumulator| {
                    let f = a.force.iter().flat_map(|f| f.to_array()).map(Real::to_bits);
                    let k = a.stiffness.iter().chain(&a.damping).map(|k| k.to_bits());
                    f.chain(k).collect::<Vec<_>>()
                };
                if let Some(kept) = kept {
                    kept_steps += 1;
                    assert_eq!(bits(&kept), bits(&fresh), "{model:?}, step {step}");
                }
                assert_eq!(bits(&body.step.acc), bits(&fresh), "{model:?}, step {step}");
                assert_eq!(body.step.limiter, limit);
                // The twin evaluates every step's first forces afresh: the same steps.
                let twin_body = twin.deformables.get_mut(h).unwrap();
                let v = twin_body.velocities().to_vec();
                twin_body.set_velocities(&v).unwrap();
                twin.step();
                let twin_body = twin.deformables.get(h).unwrap();
                assert_eq!(
                    (twin_body.positions(), twin_body.velocities()),
                    (
                        world.deformables.get(h).unwrap().positions(),
                        world.deformables.get(h).unwrap().velocities()
                    ),
                    "{model:?}, step {step}"
                );
            }
            assert!(kept_steps > 0, "{model:?}: no step kept its forces");
            assert_eq!(
                flowed > 0.0,
                plasticity.is_some(),
                "{model:?}: released {flowed} J"
            );
        }
    }

    #[test]
    fn a_body_on_a_moving_bone_keeps_its_forces_from_step_to_step() {
        use super::super::super::math::Pose;
        // The bone places its nodes within the step: the next step starts where this one
        // ended.
        let mut world = DeformableWorld::new();
        let bone = world
            .physics
            .insert_body(RigidBodyBuilder::kinematic_position_based());
        let body = DeformableBuilder::cuboid(Vector::splat(0.25), [4; DIM])
            .model(ElementModel::Springs)
            .build()
            .unwrap();
        let h = world.insert(body);
        world.attach_nodes(h, bone, &[0, 1, 2]).unwrap();
        let mut kept = 0;
        for k in 1..=30 {
            let mut at = Vector::ZERO;
            at[0] = 0.01 * k as Real;
            let pose = Pose::from_translation(at);
            world.physics.bodies[bone].set_next_kinematic_position(pose);
            world.step();
            let memo = &world.deformables.get(h).unwrap().step.energy_memo;
            kept += usize::from(memo.forces && memo.fuse);
        }
        assert!(kept >= 29, "kept forces at {kept} of 30 steps");
    }

    #[test]
    fn a_body_whose_state_changes_between_steps_stops_keeping_forces_and_takes_it_up_again() {
        let mut world = DeformableWorld::new();
        let body = DeformableBuilder::cuboid(Vector::splat(0.25), [4; DIM])
            .model(ElementModel::Springs)
            .build()
            .unwrap();
        let h = world.insert(body);
        world.step();
        assert!(world.deformables.get(h).unwrap().step.energy_memo.forces);
        // Pushed between steps: the kept forces are not those of the state the step starts
        // from, and the next step's end measures the energy alone.
        for _ in 0..2 {
            let body = world.deformables.get_mut(h).unwrap();
            body.state.velocities[0] += Vector::splat(1e-3);
            world.step();
            let memo = &world.deformables.get(h).unwrap().step.energy_memo;
            assert!(!memo.fuse && !memo.forces && memo.pending);
        }
        // Left alone, the next step finds the state the last ended in, and keeps forces again.
        world.step();
        assert!(world.deformables.get(h).unwrap().step.energy_memo.fuse);
        world.step();
        assert!(world.deformables.get(h).unwrap().step.energy_memo.forces);
        // Forces asked for between steps, at the same state: the kept ones are dropped, and
        // the next step's end does not evaluate forces it would drop again.
        world.deformables.get_mut(h).unwrap().element_forces();
        world.step();
        let memo = &world.deformables.get(h).unwrap().step.energy_memo;
        assert!(!memo.fuse && !memo.forces && memo.pending);
        world.step();
        assert!(world.deformables.get(h).unwrap().step.energy_memo.fuse);
    }
}
