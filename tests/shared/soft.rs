//! Contact between deformables (issue 14, acceptance 2): a soft cube rests on another, a
//! collision in free space conserves momentum, an undamped impact creates no energy.

use crate::dim::math::{self, Real, Vector, DIM, SIMPLEX_ARITY, UP};
use crate::dim::rapier::geometry::{Cuboid, SharedShape};
use crate::dim::rapier::prelude::{ColliderBuilder, RigidBodyBuilder};
use crate::dim::{
    CellKind, Deformable, DeformableBuilder, DeformableHandle, DeformableWorld, ElementModel,
    Material,
};

fn cube(model: ElementModel, at: Vector, material: Material) -> DeformableBuilder {
    DeformableBuilder::cuboid(Vector::splat(0.25), [4; DIM])
        .cells(CellKind::Simplex)
        .model(model)
        .material(material)
        .translation(at)
}

/// How deep the surface nodes of `a` are inside `b`: for each one inside a cell of `b`
/// (barycentric test), its distance to the nearest boundary facet of `b`; the deepest.
fn interpenetration(a: &Deformable, b: &Deformable) -> Real {
    let xb = b.positions();
    let mut deepest: Real = 0.0;
    for &i in a.mesh().boundary_nodes() {
        let p = a.positions()[i as usize];
        let inside = b.mesh().cells().any(|cell| {
            let q: Vec<Vector> = cell.iter().map(|&j| xb[j as usize]).collect();
            let whole = math::simplex_volume(&q);
            (0..SIMPLEX_ARITY).all(|k| {
                let mut r = q.clone();
                r[k] = p;
                math::simplex_volume(&r) / whole > 1e-6
            })
        });
        if !inside {
            continue;
        }
        let depth = b
            .mesh()
            .boundary_facets()
            .iter()
            .map(|f| {
                let q: Vec<Vector> = f.iter().map(|&j| xb[j as usize]).collect();
                let n = math::facet_normal(&q).normalize();
                (q[0] - p).dot(n).abs()
            })
            .fold(Real::INFINITY, Real::min);
        deepest = deepest.max(depth);
    }
    deepest
}

fn ground(world: &mut DeformableWorld) {
    let mut half = Vector::splat(3.0);
    half[1] = 0.5;
    world.physics.insert(
        RigidBodyBuilder::fixed().translation(-UP * 0.5),
        ColliderBuilder::new(SharedShape::new(Cuboid::new(half))),
    );
}

#[test]
fn a_soft_cube_rests_on_another_every_model() {
    let material = Material {
        density: 400.0,
        young_modulus: 1e5,
        damping_ratio: 0.8,
        ..Default::default()
    };
    for model in ElementModel::ALL {
        let mut world = DeformableWorld::new();
        world.set_dt(1.0 / 60.0);
        ground(&mut world);
        let lower = world.insert(cube(model, UP * 0.25, material).build().unwrap());
        // Dropped from 5 cm above, 5 cm off the lower one's axis.
        let mut at = UP * 0.8;
        at[0] = 0.05;
        let upper = world.insert(cube(model, at, material).build().unwrap());
        // At rest: the deepest over the last second of four; during the impact: the deepest.
        let (mut worst, mut impact): (Real, Real) = (0.0, 0.0);
        for k in 0..240 {
            world.step();
            let (a, b) = (&world.deformables[upper], &world.deformables[lower]);
            let depth = interpenetration(a, b).max(interpenetration(b, a));
            if k >= 180 {
                worst = worst.max(depth);
            }
            impact = impact.max(depth);
        }
        let bottom = |h: DeformableHandle| {
            world.deformables[h]
                .positions()
                .iter()
                .map(|p| p.dot(UP))
                .fold(Real::INFINITY, Real::min)
        };
        let top_of_lower = world.deformables[lower]
            .positions()
            .iter()
            .map(|p| p.dot(UP))
            .fold(Real::NEG_INFINITY, Real::max);
        let name = model.name();
        assert!(
            worst < 1.0,
            "{name}: the cubes interpenetrated by {worst} m"
        );
        // The upper one rests on the lower one: its centre about half its size above the
        // lower one's top (it sags over the edge it overhangs).
        let com = world.deformables[upper].center_of_mass().dot(UP);
        assert!(
            com > top_of_lower + 0.2 && com < top_of_lower + 0.3,
            "{name}: upper centre at {com}, lower top {top_of_lower}"
        );
        assert!(bottom(lower) > -1e-3, "{name}: the lower cube sank");
        let speed = world.deformables[upper].center_of_mass_velocity().length();
        let r = world.report();
        let touching = r.get(upper).unwrap().soft_contacts + r.get(lower).unwrap().soft_contacts;
        assert!(touching > 0, "{name}: no soft contact reported at rest");
        // It stays on (the pair keeps a slow undamped sway: see the module docs of `soft`).
        assert!(speed < 0.1, "{name}: the upper cube moves at {speed} m/s");
        assert!(
            impact < 0.05 * 0.5,
            "{name}: the impact drove one cube {impact} m into the other"
        );
    }
}

/// Two cubes of different densities thrown at each other in free space (no gravity).
fn collide(damping_ratio: Real) -> (DeformableWorld, DeformableHandle, DeformableHandle) {
    let mut world = DeformableWorld::new();
    world.set_dt(1.0 / 240.0);
    world.physics.gravity = Vector::ZERO;
    let material = |density| Material {
        density,
        young_modulus: 1e5,
        damping_ratio,
        ..Default::default()
    };
    let mut left = Vector::ZERO;
    left[0] = -0.4;
    let mut right = Vector::ZERO;
    right[0] = 0.4;
    right[1] = 0.1;
    let mut v = Vector::ZERO;
    v[0] = 2.0;
    let a = world.insert(
        cube(ElementModel::EdgeRepulsion, left, material(300.0))
            .linvel(v)
            .can_sleep(false)
            .build()
            .unwrap(),
    );
    let b = world.insert(
        cube(ElementModel::EdgeRepulsion, right, material(800.0))
            .linvel(-v * 0.5)
            .can_sleep(false)
            .build()
            .unwrap(),
    );
    (world, a, b)
}

#[test]
fn a_soft_soft_collision_conserves_momentum() {
    let (mut world, a, b) = collide(0.1);
    let momentum = |w: &DeformableWorld| {
        w.deformables[a].linear_momentum() + w.deformables[b].linear_momentum()
    };
    let before = momentum(&world);
    let scale = world.deformables[a].linear_momentum().length()
        + world.deformables[b].linear_momentum().length();
    let mut touched = false;
    for _ in 0..240 {
        world.step();
        let (da, db) = (&world.deformables[a], &world.deformables[b]);
        touched |= da.center_of_mass_velocity()[0] < 1.5;
        let drift = (momentum(&world) - before).length() / scale;
        assert!(drift < 1e-4, "momentum drifted by {drift} (relative)");
        assert!(interpenetration(da, db) < 0.01 * 0.5);
    }
    assert!(touched, "the cubes never met");
    // They bounced apart: the lighter one now goes back.
    assert!(world.deformables[a].center_of_mass_velocity()[0] < 0.0);
}

#[test]
fn an_undamped_soft_soft_impact_creates_no_energy() {
    let (mut world, a, b) = collide(0.0);
    let energy = |w: &DeformableWorld| {
        let (da, db) = (&w.deformables[a], &w.deformables[b]);
        da.kinetic_energy() + da.elastic_energy() + db.kinetic_energy() + db.elastic_energy()
    };
    let before = energy(&world);
    let mut most: Real = before;
    for _ in 0..240 {
        world.step();
        most = most.max(energy(&world));
    }
    assert!(
        most <= before * (1.0 + 1e-3),
        "energy rose from {before} J to {most} J"
    );
}

#[test]
fn a_soft_soft_collision_sends_one_start_and_one_stop() {
    use crate::dim::{ChannelEventCollector, DeformableContactEvent};
    let (mut world, a, b) = collide(0.1);
    let (sender, receiver) = std::sync::mpsc::channel();
    let collector = ChannelEventCollector::new(sender);
    let mut got = Vec::new();
    for _ in 0..240 {
        world.step_with_events(&collector);
        got.extend(receiver.try_iter());
    }
    let (first, second) = if a.into_raw_parts() < b.into_raw_parts() {
        (a, b)
    } else {
        (b, a)
    };
    assert_eq!(
        got,
        vec![
            DeformableContactEvent::PairStarted {
                deformable: first,
                other: second
            },
            DeformableContactEvent::PairStopped {
                deformable: first,
                other: second
            },
        ],
        "the cubes meet once and part"
    );
}
