//! Resting deformables sleep like rapier bodies and wake on contact or bone motion (issue 6).

use super::support::weightless_with_bone;
use crate::dim::math::{Real, Vector, DIM, UP};
use crate::dim::rapier::prelude::{ColliderBuilder, RigidBodyBuilder};
use crate::dim::{DeformableBuilder, DeformableHandle, DeformableWorld, ElementModel, Material};

fn ground(world: &mut DeformableWorld) {
    let mut half = Vector::splat(5.0);
    half[1] = 0.5;
    world.physics.insert(
        RigidBodyBuilder::fixed().translation(-UP * 0.5),
        ColliderBuilder::new(crate::dim::rapier::geometry::SharedShape::new(
            crate::dim::rapier::geometry::Cuboid::new(half),
        )),
    );
}

fn jelly(world: &mut DeformableWorld, can_sleep: bool) -> DeformableHandle {
    let body = DeformableBuilder::cuboid(Vector::splat(0.25), [4; DIM])
        .model(ElementModel::EdgeRepulsion)
        .material(Material {
            density: 1000.0,
            young_modulus: 2e4,
            damping_ratio: 0.3,
            ..Default::default()
        })
        .translation(UP * 0.3)
        .can_sleep(can_sleep)
        .build()
        .unwrap();
    world.insert(body)
}

/// Steps until `h` sleeps; returns the number of steps (panics past `limit`).
fn until_asleep(world: &mut DeformableWorld, h: DeformableHandle, limit: usize) -> usize {
    for k in 1..=limit {
        world.step();
        if world.deformables[h].is_sleeping() {
            return k;
        }
    }
    let v = world.deformables[h]
        .velocities()
        .iter()
        .map(|v| v.length())
        .fold(0.0, Real::max);
    panic!(
        "max speed {v}, still awake after {limit} steps: {:?}",
        world.report().get(h)
    );
}

#[test]
fn a_resting_body_falls_asleep_and_stays_put_without_substeps() {
    let mut world = DeformableWorld::new();
    world.set_dt(1.0 / 60.0);
    ground(&mut world);
    let h = jelly(&mut world, true);
    let steps = until_asleep(&mut world, h, 1200);
    // Not before it has been still for time_until_sleep.
    let still = world.pipeline.settings.time_until_sleep;
    assert!(steps as Real / 60.0 >= still, "asleep after {steps} steps");
    let com = world.deformables[h].center_of_mass();
    for _ in 0..120 {
        let r = world.step().get(h).unwrap().clone();
        assert!(r.sleeping && r.substeps == 0, "{r:?}");
    }
    assert_eq!(
        world.deformables[h].center_of_mass(),
        com,
        "drifted while asleep"
    );
    // It sleeps resting on the ground, not in the air.
    let lowest = world.deformables[h]
        .positions()
        .iter()
        .map(|p| p.dot(UP))
        .fold(Real::INFINITY, Real::min);
    assert!(lowest.abs() < 0.01, "asleep at height {lowest}");
}

#[test]
fn a_body_that_cannot_sleep_stays_awake() {
    let mut world = DeformableWorld::new();
    world.set_dt(1.0 / 60.0);
    ground(&mut world);
    let h = jelly(&mut world, false);
    for _ in 0..400 {
        let r = world.step().get(h).unwrap().clone();
        assert!(!r.sleeping && r.substeps > 0, "{r:?}");
    }
}

#[test]
fn a_falling_rigid_body_wakes_a_sleeping_one() {
    let mut world = DeformableWorld::new();
    world.set_dt(1.0 / 60.0);
    ground(&mut world);
    let h = jelly(&mut world, true);
    until_asleep(&mut world, h, 1200);
    let top = world.deformables[h]
        .positions()
        .iter()
        .map(|p| p.dot(UP))
        .fold(Real::NEG_INFINITY, Real::max);
    let (ball, _) = world.physics.insert(
        RigidBodyBuilder::dynamic().translation(UP * (top + 0.5)),
        ColliderBuilder::ball(0.1).density(100.0),
    );
    let mut woke = false;
    for _ in 0..120 {
        world.step();
        woke |= !world.deformables[h].is_sleeping();
    }
    assert!(woke, "the falling ball never woke the deformable");
    // How it lands is the contact tests' business; here: it was seen and woke the body.
    let _ = ball;
}

#[test]
fn a_moving_bone_wakes_bound_tissue_and_drags_it_along() {
    let (mut world, bone) = weightless_with_bone();
    let collider = world.physics.insert_collider(
        ColliderBuilder::new(crate::dim::rapier::geometry::SharedShape::new(
            crate::dim::rapier::geometry::Cuboid::new(Vector::splat(0.1)),
        ))
        .sensor(true),
        Some(bone),
    );
    let tissue = DeformableBuilder::cuboid(Vector::splat(0.25), [5; DIM])
        .model(ElementModel::EdgeRepulsion)
        .material(Material {
            damping_ratio: 0.3,
            ..Default::default()
        })
        .build()
        .unwrap();
    let h = world.insert(tissue);
    assert!(world.attach_nodes_inside(h, collider, 1e-3).unwrap() > 0);
    until_asleep(&mut world, h, 1200);
    let com = world.deformables[h].center_of_mass();
    let mut shift = Vector::ZERO;
    shift[0] = 0.2;
    for k in 1..=60 {
        let at = shift * (k as Real / 60.0);
        world.physics.bodies[bone].set_next_kinematic_translation(at);
        let r = world.step().get(h).unwrap().clone();
        assert!(!r.sleeping, "asleep while its bone moves (step {k})");
    }
    let moved = world.deformables[h].center_of_mass() - com;
    assert!(
        moved[0] > 0.1,
        "the tissue did not follow its bone: moved {moved:?}"
    );
}

#[test]
fn a_box_on_a_jelly_sleeps_with_it_and_a_shot_wakes_both() {
    // Issue 14, acceptance 5. A dynamic box settles on a jelly: both fall asleep within 3 s of
    // settling, as one of rapier's islands would; a shot at the jelly (an impulse at a ray's
    // hit) wakes both.
    use crate::dim::rapier::geometry::Ray;
    use crate::dim::DeformableQueryFilter;
    let mut world = DeformableWorld::new();
    world.set_dt(1.0 / 60.0);
    ground(&mut world);
    let h = jelly(&mut world, true);
    let (rb, _) = world.physics.insert(
        RigidBodyBuilder::dynamic().translation(UP * 0.7),
        ColliderBuilder::new(crate::dim::rapier::geometry::SharedShape::new(
            crate::dim::rapier::geometry::Cuboid::new(Vector::splat(0.1)),
        ))
        .density(200.0)
        .friction(0.8),
    );
    // Settled: both slower than 5 cm/s (rapier's and sinew's sleep speeds) from then on.
    let mut settled = None;
    let mut both_asleep = None;
    for k in 1..=600 {
        world.step();
        let jelly_speed = world.deformables[h]
            .velocities()
            .iter()
            .map(|v| v.length())
            .fold(0.0, Real::max);
        let box_speed = world.physics.bodies[rb].linvel().length();
        if jelly_speed >= 0.05 || box_speed >= 0.05 {
            settled = None;
        } else if settled.is_none() {
            settled = Some(k);
        }
        if world.deformables[h].is_sleeping() && world.physics.bodies[rb].is_sleeping() {
            both_asleep = Some(k);
            break;
        }
    }
    let settled = settled.expect("the pair never settled");
    let both_asleep = both_asleep.unwrap_or_else(|| {
        panic!(
            "not both asleep after 10 s: jelly {}, box {}",
            world.deformables[h].is_sleeping(),
            world.physics.bodies[rb].is_sleeping()
        )
    });
    assert!(
        (both_asleep - settled) as Real / 60.0 <= 3.0,
        "settled at step {settled}, both asleep at {both_asleep}"
    );
    let resting = world.physics.bodies[rb].translation();
    // Stays asleep, put.
    for _ in 0..60 {
        world.step();
    }
    assert!(world.deformables[h].is_sleeping() && world.physics.bodies[rb].is_sleeping());
    assert_eq!(world.physics.bodies[rb].translation(), resting);
    // A shot at the jelly's side, below the ball.
    let mut origin = Vector::splat(0.0);
    origin[0] = -3.0;
    origin[1] = 0.3;
    let mut dir = Vector::splat(0.0);
    dir[0] = 1.0;
    let hit = world
        .deformables
        .cast_ray(
            &Ray::new(origin, dir),
            10.0,
            DeformableQueryFilter::default(),
        )
        .expect("the shot misses the jelly");
    assert_eq!(hit.deformable, h);
    assert!(world.deformables.apply_impulse_at(&hit, dir * 20.0));
    assert!(!world.deformables[h].is_sleeping());
    world.step();
    assert!(
        !world.physics.bodies[rb].is_sleeping(),
        "the shot woke the jelly but not the box on it"
    );
    assert!(!world.deformables[h].is_sleeping());
}
