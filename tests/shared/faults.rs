//! Faults injected into a running world (issue 7, containment): what the step report says,
//! and that the rapier world and the other deformables go on unchanged.

use std::sync::mpsc::channel;

use crate::dim::math::{Real, Vector, DIM, UP};
use crate::dim::rapier::geometry::{Cuboid, SharedShape};
use crate::dim::rapier::prelude::{ColliderBuilder, RigidBodyBuilder};
use crate::dim::{
    BuildError, ChannelEventCollector, DeformableBuilder, DeformableContactEvent, DeformableWorld,
    Integrator, Material, Stiffness,
};

fn ground(world: &mut DeformableWorld) -> crate::dim::rapier::geometry::ColliderHandle {
    let mut half = Vector::splat(20.0);
    half[1] = 0.5;
    world
        .physics
        .insert(
            RigidBodyBuilder::fixed().translation(-UP * 0.5),
            ColliderBuilder::new(SharedShape::new(Cuboid::new(half))),
        )
        .1
}

fn jelly() -> DeformableBuilder {
    DeformableBuilder::cuboid(Vector::splat(0.25), [3; DIM])
}

/// A world with a ball falling freely far from everything, a well-behaved deformable and one
/// that explodes (one forced substep with a huge stiffness, kicked out of rest).
#[test]
fn a_blow_up_freezes_only_that_body_and_the_world_goes_on() {
    let mut world = DeformableWorld::new();
    world.set_dt(1.0 / 60.0);
    // The explicit step, forced to one substep (the implicit one would be stable).
    world.pipeline.settings.integrator = Integrator::Explicit;
    world.pipeline.settings.fixed_substeps = Some(1);
    let bad = world.insert(
        jelly()
            .stiffness(Stiffness::Raw { k: 1e9, c: 0.0 })
            .translation(UP * 5.0)
            .build()
            .unwrap(),
    );
    let mut kick = world.deformables[bad].positions().to_vec();
    kick[0] += Vector::splat(0.05);
    world.deformables[bad].set_positions(&kick).unwrap();
    let mut far = Vector::ZERO;
    far[0] = 10.0;
    // Soft enough to be stable at one 60 Hz substep (the default E = 10⁵ with ν = 0.3 is not:
    // it needs five).
    let good = world.insert(
        jelly()
            .material(Material {
                young_modulus: 1e4,
                ..Default::default()
            })
            .translation(far + UP * 5.0)
            .build()
            .unwrap(),
    );
    let (ball, _) = world.physics.insert(
        RigidBodyBuilder::dynamic().translation(-far + UP * 5.0),
        ColliderBuilder::ball(0.1),
    );
    let mut frozen_at = None;
    let steps = 60;
    for k in 0..steps {
        let r = world.step();
        let b = r.get(bad).unwrap();
        if b.non_finite || b.exploded {
            assert!(b.frozen, "the step that blew up freezes the body");
            frozen_at.get_or_insert(k);
        }
        let g = r.get(good).unwrap();
        assert!(!g.frozen && !g.non_finite, "the other body is not touched");
    }
    let k = frozen_at.expect("the explosion is reported");
    assert!(world.deformables[bad].is_frozen());
    let d = &world.deformables[bad];
    assert!(d
        .positions()
        .iter()
        .chain(d.velocities())
        .all(|p| p.is_finite()));
    // Frozen: not simulated any more, its last finite state kept.
    let before = d.positions().to_vec();
    world.step();
    assert_eq!(world.deformables[bad].positions(), &before[..]);
    assert!(world.report().get(bad).unwrap().frozen);
    // The ball fell freely all along: y(t) = y0 − g t²/2 (within rapier's integration).
    let t = (steps + 1) as Real / 60.0;
    let y = world.physics.bodies[ball].translation().dot(UP);
    let free = 5.0 - 0.5 * 9.81 * t * t;
    assert!((y - free).abs() < 0.05, "ball at {y}, free fall {free}");
    // So did the good deformable.
    let g = &world.deformables[good];
    assert!(
        g.center_of_mass().dot(UP) < 5.0 - 0.4 * 9.81 * t * t,
        "step {k}"
    );
    assert!(g.positions().iter().all(|p| p.is_finite()));
}

#[test]
fn non_finite_state_from_the_user_is_refused() {
    let mut world = DeformableWorld::new();
    let h = world.insert(jelly().build().unwrap());
    let before = world.deformables[h].positions().to_vec();
    let mut bad = before.clone();
    bad[3][1] = Real::NAN;
    let e = world.deformables[h].set_positions(&bad).unwrap_err();
    assert!(
        matches!(e, BuildError::NonFiniteCoordinate { node: 3, .. }),
        "{e}"
    );
    let mut fast = vec![Vector::ZERO; before.len()];
    fast[2][0] = Real::INFINITY;
    let e = world.deformables[h].set_velocities(&fast).unwrap_err();
    assert!(
        matches!(e, BuildError::NonFiniteCoordinate { node: 2, .. }),
        "{e}"
    );
    let e = world.deformables[h]
        .set_positions(&before[1..])
        .unwrap_err();
    assert!(e.to_string().contains(&before.len().to_string()), "{e}");
    assert_eq!(world.deformables[h].positions(), &before[..], "unchanged");
    world.step();
    assert!(!world.deformables[h].is_frozen());
}

#[test]
fn the_substep_cap_drops_the_rest_of_the_step_and_says_so() {
    let mut world = DeformableWorld::new();
    world.set_dt(1.0 / 60.0);
    world.pipeline.settings.integrator = Integrator::Explicit;
    world.pipeline.settings.max_substeps = 3;
    let h = world.insert(
        jelly()
            .stiffness(Stiffness::Raw { k: 1e7, c: 0.0 })
            .build()
            .unwrap(),
    );
    let r = world.step().get(h).cloned().unwrap();
    assert!(r.substep_cap_hit, "{r:?}");
    assert!(r.lost_time > 0.0 && r.lost_time <= 1.0 / 60.0, "{r:?}");
    assert!(r.substeps < 3, "{r:?}");
    let d = &world.deformables[h];
    assert!(!d.is_frozen() && d.positions().iter().all(|p| p.is_finite()));
}

#[test]
fn a_collider_removed_under_a_resting_body_lets_it_fall() {
    let mut world = DeformableWorld::new();
    world.set_dt(1.0 / 60.0);
    let floor = ground(&mut world);
    let h = world.insert(jelly().translation(UP * 0.25).build().unwrap());
    let (tx, rx) = channel();
    let events = ChannelEventCollector::new(tx);
    for _ in 0..60 {
        world.step_with_events(&events);
    }
    assert!(
        world.report().get(h).unwrap().contacts > 0,
        "resting on the floor"
    );
    world.physics.remove_collider(floor);
    for _ in 0..30 {
        world.step_with_events(&events);
    }
    let got: Vec<DeformableContactEvent> = rx.try_iter().collect();
    assert!(
        got.contains(&DeformableContactEvent::Stopped {
            deformable: h,
            collider: floor
        }),
        "{got:?}"
    );
    let d = &world.deformables[h];
    assert!(
        d.center_of_mass().dot(UP) < -0.5,
        "it fell through where the floor was"
    );
    assert_eq!(world.report().get(h).unwrap().contacts, 0);
}
