//! Nodes bound to rigid bodies (issue 3, acceptance 1, 2, 6).

use super::support::weightless_with_bone;
use crate::dim::math::{self, Pose, Real, Vector, DIM, UP};
use crate::dim::rapier::prelude::{ColliderBuilder, RigidBodyBuilder};
use crate::dim::{AttachError, DeformableBuilder, DeformableWorld, ElementModel, Material};
use crate::scenes::LimbScene;

fn cuboid(half: Vector) -> ColliderBuilder {
    ColliderBuilder::new(crate::dim::rapier::geometry::SharedShape::new(
        crate::dim::rapier::geometry::Cuboid::new(half),
    ))
}

fn tissue(
    world: &mut DeformableWorld,
    half: Vector,
    res: usize,
    at: Vector,
) -> crate::dim::DeformableHandle {
    let t = DeformableBuilder::cuboid(half, [res; DIM])
        .model(ElementModel::EdgeRepulsion)
        .material(Material {
            density: 100.0,
            young_modulus: 2e3,
            damping_ratio: 0.1,
            ..Default::default()
        })
        .translation(at)
        .build()
        .unwrap();
    world.insert(t)
}

#[test]
fn nodes_follow_a_moving_and_turning_kinematic_bone_exactly() {
    let (mut world, bone) = weightless_with_bone();
    let collider = world
        .physics
        .insert_collider(cuboid(Vector::splat(0.3)), Some(bone));
    let h = tissue(&mut world, Vector::splat(0.5), 5, Vector::ZERO);
    let bound = world.attach_nodes_inside(h, collider, 1e-3).unwrap();
    assert_eq!(
        bound,
        3usize.pow(DIM as u32),
        "the bone binds the inner 3^DIM nodes"
    );
    let mut worst: Real = 0.0;
    for k in 1..=180 {
        let t = k as Real / 60.0;
        let mut at = Vector::ZERO;
        at[0] = 0.8 * t.sin();
        at[1] = 0.3 * t;
        let pose = Pose::from_parts(at, math::rotation_from_angle(math::planar_angle(1.5 * t)));
        world.physics.bodies[bone].set_next_kinematic_position(pose);
        world.step();
        let body = &world.physics.bodies[bone];
        let d = &world.deformables[h];
        for a in d.attachments() {
            worst = worst.max(
                body.position()
                    .transform_point(a.anchor)
                    .distance(d.positions()[a.node as usize]),
            );
        }
    }
    assert!(
        worst < 1e-4,
        "a bound node strayed {worst} m from its anchor"
    );
    // The free tissue came along.
    let bone_at = world.physics.bodies[bone].position().translation;
    let com = world.deformables[h].center_of_mass();
    assert!(
        com.distance(bone_at) < 0.2,
        "tissue left behind: centre {com:?}, bone {bone_at:?}"
    );
}

#[test]
fn a_moving_dynamic_body_drags_its_tissue_and_momentum_is_kept() {
    let mut world = DeformableWorld::new();
    world.set_dt(1.0 / 120.0);
    world.physics.gravity = Vector::ZERO;
    let mut v0 = Vector::ZERO;
    v0[0] = 2.0;
    let (body, collider) = world.physics.insert(
        RigidBodyBuilder::dynamic().linvel(v0),
        cuboid(Vector::splat(0.3)).density(100.0),
    );
    let h = tissue(&mut world, Vector::splat(0.5), 5, Vector::ZERO);
    world.attach_nodes_inside(h, collider, 1e-3).unwrap();
    let momentum = |w: &DeformableWorld| {
        let b = &w.physics.bodies[body];
        b.linvel() * b.mass() + w.deformables[h].linear_momentum()
    };
    let p0 = momentum(&world);
    let mut worst: Real = 0.0;
    for _ in 0..240 {
        world.step();
        worst = worst.max((momentum(&world) - p0).length());
    }
    assert!(
        worst < 0.01 * p0.length(),
        "momentum drifted by {worst} of {}",
        p0.length()
    );
    let d = &world.deformables[h];
    // The tissue moves with the body (its mass is ~4× the body's, so they share the speed).
    let v = d.center_of_mass_velocity()[0];
    let vb = world.physics.bodies[body].linvel()[0];
    assert!(v > 0.2 && v < 2.0, "tissue velocity {v}");
    assert!((vb - v).abs() < 0.1, "body {vb} and tissue {v} part ways");
}

#[test]
fn tissue_hanging_from_one_end_swings_a_balanced_bar_down_on_that_side() {
    let mut world = DeformableWorld::new();
    world.set_dt(1.0 / 120.0);
    let anchor = world.physics.insert_body(RigidBodyBuilder::fixed());
    let mut half = Vector::splat(0.05);
    half[0] = 1.0;
    let (bar, _) = world
        .physics
        .insert(RigidBodyBuilder::dynamic(), cuboid(half).density(500.0));
    world
        .physics
        .insert_impulse_joint(anchor, bar, crate::planar_revolute().build());
    let mut at = -UP * 0.35;
    at[0] = 0.8;
    let h = tissue(&mut world, Vector::splat(0.2), 3, at);
    // Bind the top face of the tissue to the bar.
    let top: Vec<u32> = (0..world.deformables[h].num_nodes() as u32)
        .filter(|&i| world.deformables[h].positions()[i as usize].dot(UP) > -0.16)
        .collect();
    assert!(!top.is_empty());
    world.attach_nodes(h, bar, &top).unwrap();
    for _ in 0..120 {
        world.step();
    }
    let b = &world.physics.bodies[bar];
    let tip = b.position().transform_point(Vector::X * 1.0);
    assert!(
        tip.dot(UP) < -0.05,
        "the loaded end should swing down, it is at {}",
        tip.dot(UP)
    );
    // Without the tissue the bar stays level.
    let mut empty = DeformableWorld::new();
    let anchor = empty.physics.insert_body(RigidBodyBuilder::fixed());
    let (bar, _) = empty
        .physics
        .insert(RigidBodyBuilder::dynamic(), cuboid(half).density(500.0));
    empty
        .physics
        .insert_impulse_joint(anchor, bar, crate::planar_revolute().build());
    for _ in 0..120 {
        empty.step();
    }
    let tip = empty.physics.bodies[bar]
        .position()
        .transform_point(Vector::X * 1.0);
    assert!(tip.dot(UP).abs() < 1e-3);
}

#[test]
fn bindings_are_checked_and_removed_bodies_are_detached() {
    let mut world = DeformableWorld::new();
    let (body, collider) = world
        .physics
        .insert(RigidBodyBuilder::dynamic(), cuboid(Vector::splat(0.2)));
    let h = tissue(&mut world, Vector::splat(0.5), 3, Vector::ZERO);
    let n = world.deformables[h].num_nodes() as u32;
    assert_eq!(
        world.attach_nodes(h, body, &[0, n]),
        Err(AttachError::NodeOutOfRange {
            node: n,
            nodes: n as usize
        })
    );
    assert!(
        world.deformables[h].attachments().is_empty(),
        "a failed call binds nothing"
    );
    let e = world.attach_nodes_inside(h, collider, -1.0).unwrap_err();
    assert!(e.to_string().contains("tolerance"), "{e}");
    assert_eq!(world.attach_nodes_inside(h, collider, 1e-3), Ok(1));
    world.attach_nodes(h, body, &[0, 1]).unwrap();
    assert_eq!(world.deformables[h].attachments().len(), 3);
    // Re-binding a node replaces its binding.
    world.attach_nodes(h, body, &[0]).unwrap();
    assert_eq!(world.deformables[h].attachments().len(), 3);
    assert_eq!(world.deformables[h].detach_nodes(&[0]), 1);
    // Removing the body from rapier directly: the next step drops the bindings.
    world.physics.remove_body(body);
    let r = world.step().get(h).cloned().unwrap();
    assert_eq!(r.detached, 2);
    assert!(world.deformables[h].attachments().is_empty());
    assert!(world.deformables[h]
        .positions()
        .iter()
        .all(|p| p.is_finite()));
    let stale = world.attach_nodes(h, body, &[0]).unwrap_err();
    assert!(matches!(stale, AttachError::NoSuchBody(_)), "{stale}");
}

#[test]
fn limb_springs_collapse_and_edge_repulsion_holds() {
    let springs = LimbScene {
        subject: ElementModel::Springs.into(),
        stop_at_first_inversion: true,
        ..Default::default()
    }
    .run()
    .unwrap();
    let angle = springs
        .first_failure
        .expect("springs must invert an element before 110°");
    assert!(angle < 110.0);
    let er = LimbScene::default().run().unwrap();
    assert_eq!(er.first_failure, None, "ER inverted an element: {er:?}");
    assert!(
        (er.sim_s * 10.0 - 110.0).abs() < 0.5,
        "stopped early: {er:?}"
    );
    assert!(!er.nan && !er.exploded);
    let strayed = er.max_anchor_error.expect("the limb measures anchors");
    assert!(strayed < 1e-4, "bound nodes strayed {strayed}");
}

/// One step after a jump: substeps, frozen, teleported, inverted cells.
type AfterJump = (usize, bool, bool, usize);

/// A 0.5 m cube hanging from a kinematic bone by its top nodes at 60 Hz, settled for a second;
/// then the bone is sent `jump` m sideways and turned a quarter in one step. Per step after:
/// substeps, frozen, teleported, inverted cells; and how far the cube's centre of mass is,
/// after the jump's step, from where the bone's motion takes it.
fn hang_and_jump(
    model: ElementModel,
    integrator: crate::dim::Integrator,
    jump: Real,
) -> (Vec<AfterJump>, usize, Real) {
    let mut world = DeformableWorld::new();
    world.set_dt(1.0 / 60.0);
    world.pipeline.settings.integrator = integrator;
    let bone = world
        .physics
        .insert_body(RigidBodyBuilder::kinematic_position_based().translation(UP));
    let t = DeformableBuilder::cuboid(Vector::splat(0.25), [5; DIM])
        .model(model)
        .material(Material {
            density: 1000.0,
            young_modulus: 1e4,
            damping_ratio: 0.1,
            ..Default::default()
        })
        .translation(UP * 0.75)
        .build()
        .unwrap();
    let h = world.insert(t);
    let top: Vec<u32> = (0..world.deformables[h].num_nodes() as u32)
        .filter(|&i| world.deformables[h].positions()[i as usize].dot(UP) > 0.99)
        .collect();
    world.attach_nodes(h, bone, &top).unwrap();
    for _ in 0..60 {
        world.step();
    }
    let resting = world.pipeline.report().get(h).unwrap().substeps;
    let offset = world.deformables[h].center_of_mass() - world.physics.bodies[bone].translation();
    let b = &mut world.physics.bodies[bone];
    let mut to = *b.position();
    to.translation += Vector::X * jump;
    to.rotation =
        math::rotation_from_angle(math::cross(Vector::X, UP) * std::f32::consts::FRAC_PI_2);
    b.set_next_kinematic_position(to);
    let mut after = Vec::new();
    let mut error = 0.0;
    for k in 0..10 {
        world.step();
        let r = world.pipeline.report().get(h).unwrap();
        after.push((r.substeps, r.frozen, r.teleported, r.inverted_elements));
        if k == 0 {
            let b = &world.physics.bodies[bone];
            let expected = b.translation() + *b.rotation() * offset;
            error = world.deformables[h].center_of_mass().distance(expected);
        }
    }
    (after, resting, error)
}

#[test]
fn a_bone_that_jumps_carries_its_body_along_under_either_integrator() {
    // Sent 1 m and 10 m and turned a quarter in one 60 Hz step, the bone takes the body with
    // it: the next steps cost what resting did (10 m once kept the explicit step at its 19 999
    // substep cap with cells inverted), and the report says so on the jump's step.
    for integrator in [
        crate::dim::Integrator::Explicit,
        crate::dim::Integrator::Implicit { iterations: 2 },
    ] {
        for model in [ElementModel::EdgeRepulsion, ElementModel::SHAPE_MATCHING] {
            for jump in [1.0, 10.0] {
                let (after, resting, error) = hang_and_jump(model, integrator, jump);
                let what = format!("{} {integrator:?} {jump} m: {after:?}", model.name());
                assert!(after[0].2 && after[1..].iter().all(|a| !a.2), "{what}");
                assert!(after.iter().all(|a| !a.1 && a.3 == 0), "{what}");
                assert!(after.iter().all(|a| a.0 <= 2 * resting.max(1)), "{what}");
                assert!(
                    error < 0.02,
                    "{what}: centre of mass {error} m off the bone's"
                );
            }
        }
    }
}

#[test]
fn a_fast_but_possible_bone_motion_is_no_jump() {
    // 0.5 m in a 60 Hz step is 30 m/s, under the 50 m/s of a jump: the body is dragged, not
    // carried (its centre of mass lags the bone by centimetres).
    let (after, _, error) = hang_and_jump(
        ElementModel::EdgeRepulsion,
        crate::dim::Integrator::Explicit,
        0.5,
    );
    assert!(after.iter().all(|a| !a.2), "{after:?}");
    assert!(error > 0.05, "{error}");
}

#[test]
fn a_light_body_bound_to_a_soft_cube_rests_on_it() {
    // A box bound by the top layer of a soft cube resting on the ground, its centre 0.4 m above
    // the nodes that hold it: a 1.6 kg box at 1 ms (each node's impulse sized as if it alone
    // pulled the box, it rang up to 40 m/s and the cube blew up; springs and shape matching to
    // thousands) and a 8 g box at 60 Hz. The cube settles from where it was set down (it rings
    // at under 1 m/s); nothing blows up or gains speed.
    let material = Material {
        density: 500.0,
        young_modulus: 3e4,
        damping_ratio: 0.1,
        ..Default::default()
    };
    for (model, dt, res, density) in [
        (ElementModel::EdgeRepulsion, 1e-3, 5, 200.0),
        (ElementModel::SHAPE_MATCHING, 1e-3, 5, 200.0),
        (ElementModel::Springs, 1e-3, 5, 200.0),
        (ElementModel::SHAPE_MATCHING, 1.0 / 60.0, 3, 1.0),
        (ElementModel::EdgeRepulsion, 1.0 / 60.0, 3, 20.0),
    ] {
        let mut world = DeformableWorld::new();
        world.set_dt(dt);
        world.physics.insert(
            RigidBodyBuilder::fixed().translation(-UP * 0.5),
            cuboid(Vector::splat(0.5) * 40.0 * (Vector::ONE - UP) + UP * 0.5),
        );
        let cube = DeformableBuilder::cuboid(Vector::splat(0.25), [res; DIM])
            .model(model)
            .material(material)
            .translation(UP * 0.26)
            .build()
            .unwrap();
        let cube = world.insert(cube);
        let (weight, _) = world.physics.insert(
            RigidBodyBuilder::dynamic().translation(UP * 0.9),
            cuboid(Vector::splat(0.1)).density(density),
        );
        let top: Vec<u32> = world.deformables[cube]
            .positions()
            .iter()
            .enumerate()
            .filter(|(_, p)| p.dot(UP) > 0.45)
            .map(|(i, _)| i as u32)
            .collect();
        world.attach_nodes(cube, weight, &top).unwrap();
        world.pipeline.settings.time_until_sleep = Real::INFINITY;
        let steps = (2.0 / dt) as usize;
        let mut fastest: Real = 0.0;
        for k in 0..steps {
            world.step();
            let body = &world.deformables[cube];
            assert!(
                !body.is_frozen(),
                "{} at {dt}: froze at step {k}",
                model.name()
            );
            if k >= steps / 2 {
                let speed = body.velocities().iter().map(|v| v.length());
                fastest = speed.fold(fastest, Real::max);
            }
        }
        let name = model.name();
        assert!(
            fastest < 1.5,
            "{name} at {dt}: nodes at {fastest} m/s in the second second"
        );
        let b = &world.physics.bodies[weight];
        assert!(
            b.linvel().length() < 1.5,
            "{name} at {dt}: box at {}",
            b.linvel()
        );
        let height = b.translation().dot(UP);
        assert!(
            (0.7..0.95).contains(&height),
            "{name} at {dt}: box at {height} m"
        );
    }
}
