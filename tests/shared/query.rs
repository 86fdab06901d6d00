//! Queries against deformables (issue 14, acceptance 4): ray casts that hit the current
//! (deformed) surface, shape casts, intersection tests, collision-group filters, and an impulse
//! at a hit.

use crate::dim::math::{Pose, Real, Vector, DIM, UP};
use crate::dim::rapier::geometry::{Ball, Group, InteractionGroups, Ray};
use crate::dim::rapier::parry::query::ShapeCastOptions;
use crate::dim::{DeformableBuilder, DeformableHandle, DeformableQueryFilter, DeformableSet};

fn cube(at: Vector) -> DeformableBuilder {
    DeformableBuilder::cuboid(Vector::splat(0.5), [5; DIM]).translation(at)
}

/// A straight line down through the body's top at `x` (every other coordinate 0.1).
fn down_at(x: Real) -> Ray {
    let mut origin = Vector::splat(0.1);
    origin[0] = x;
    origin[1] = 5.0;
    Ray::new(origin, -UP)
}

/// The earliest crossing of `ray` with any boundary facet, by brute force: the ray against
/// each facet's plane, kept if the point is inside the facet.
fn brute_force(set: &DeformableSet, h: DeformableHandle, ray: &Ray) -> Option<(u32, Real)> {
    let body = &set[h];
    let x = body.positions();
    let mut best: Option<(u32, Real)> = None;
    for (k, f) in body.mesh().boundary_facets().iter().enumerate() {
        let p: Vec<Vector> = f.iter().map(|&i| x[i as usize]).collect();
        let n = crate::dim::math::facet_normal(&p);
        let denom = n.dot(ray.dir);
        if denom.abs() < 1e-12 {
            continue;
        }
        let t = n.dot(p[0] - ray.origin) / denom;
        let at = ray.point_at(t);
        let w = crate::dim::math::facet_barycentric(&p, at);
        if t >= 0.0 && w.iter().all(|&w| w >= -1e-5) && best.is_none_or(|b| t < b.1) {
            best = Some((k as u32, t));
        }
    }
    best
}

#[test]
fn a_ray_from_above_hits_the_deformed_surface() {
    let mut set = DeformableSet::new();
    let h = set.insert(cube(Vector::ZERO).build().unwrap());
    // A dent: every node above the middle pushed down by up to 0.3 at the centre.
    let dented: Vec<Vector> = set[h]
        .positions()
        .iter()
        .map(|p| {
            let r = (*p - UP * p.dot(UP)).length();
            *p - UP * (0.3 * (1.0 - r).max(0.0) * (p.dot(UP) + 0.5).max(0.0))
        })
        .collect();
    set[h].set_positions(&dented).unwrap();
    for x in [0.0, 0.07, 0.23, -0.41] {
        let ray = down_at(x);
        let hit = set
            .cast_ray(&ray, 100.0, DeformableQueryFilter::default())
            .expect("the ray misses the body");
        assert_eq!(hit.deformable, h);
        let (facet, t) = brute_force(&set, h, &ray).unwrap();
        assert!(
            (hit.time_of_impact - t).abs() < 1e-4,
            "x = {x}: hit at t = {}, the surface is at t = {t}",
            hit.time_of_impact
        );
        let on_facet = ray.point_at(t);
        assert!((hit.point - on_facet).length() < 1e-4, "x = {x}: {hit:?}");
        // The facet reported contains the point (ties on shared edges: either facet).
        let p: Vec<Vector> = hit
            .nodes
            .iter()
            .map(|&i| set[h].positions()[i as usize])
            .collect();
        let w = crate::dim::math::facet_barycentric(&p, hit.point);
        assert!(
            w.iter().all(|&w| w >= -1e-4),
            "x = {x}: point off its facet {facet}"
        );
        assert_eq!(
            set[h].mesh().boundary_facets()[hit.facet as usize],
            hit.nodes
        );
        assert!(hit.normal.dot(UP) > 0.0, "x = {x}: normal {:?}", hit.normal);
        // Deeper than the undented top where the dent is.
        if x.abs() < 0.3 {
            assert!(hit.point.dot(UP) < 0.5 - 0.05, "x = {x}: {hit:?}");
        }
    }
    // Off the body: nothing.
    assert!(set
        .cast_ray(&down_at(3.0), 100.0, DeformableQueryFilter::default())
        .is_none());
    // Moved away (a state change refits the surface's hierarchy): hit where it is now.
    let mut side = Vector::ZERO;
    side[0] = 3.0;
    let moved: Vec<Vector> = set[h].positions().iter().map(|p| *p + side).collect();
    set[h].set_positions(&moved).unwrap();
    assert!(set
        .cast_ray(&down_at(0.1), 100.0, DeformableQueryFilter::default())
        .is_none());
    let hit = set
        .cast_ray(&down_at(3.1), 100.0, DeformableQueryFilter::default())
        .expect("the moved body is not hit");
    assert!(hit.point.dot(UP) < 0.5 - 0.05);
    set[h].set_positions(&dented).unwrap();
    // Too short: nothing.
    assert!(set
        .cast_ray(&down_at(0.0), 4.0, DeformableQueryFilter::default())
        .is_none());
}

#[test]
fn filters_choose_which_bodies_a_query_sees() {
    let mut set = DeformableSet::new();
    let top = set.insert(
        cube(UP * 2.0)
            .collision_groups(InteractionGroups::new(
                Group::GROUP_2,
                Group::ALL,
                Default::default(),
            ))
            .build()
            .unwrap(),
    );
    let bottom = set.insert(cube(Vector::ZERO).build().unwrap());
    let ray = down_at(0.1);
    let first = |filter| set.cast_ray(&ray, 100.0, filter).map(|h| h.deformable);
    assert_eq!(first(DeformableQueryFilter::default()), Some(top));
    let only_1 = InteractionGroups::new(Group::GROUP_1, Group::GROUP_1, Default::default());
    assert_eq!(first(DeformableQueryFilter::groups(only_1)), Some(bottom));
    let skip_top = DeformableQueryFilter {
        exclude: Some(top),
        ..Default::default()
    };
    assert_eq!(first(skip_top), Some(bottom));
}

#[test]
fn a_ball_cast_down_meets_the_top_and_an_overlapping_ball_intersects() {
    let mut set = DeformableSet::new();
    let h = set.insert(cube(Vector::ZERO).build().unwrap());
    let ball = Ball::new(0.2);
    let pose = Pose::from_translation(UP * 2.0);
    let hit = set
        .cast_shape(
            &pose,
            -UP,
            &ball,
            ShapeCastOptions::with_max_time_of_impact(10.0),
            DeformableQueryFilter::default(),
        )
        .expect("the ball misses the body");
    assert_eq!(hit.deformable, h);
    // From 2.0 down to the top at 0.5, less the radius.
    assert!(
        (hit.time_of_impact - 1.3).abs() < 1e-3,
        "time of impact {}",
        hit.time_of_impact
    );
    assert!((hit.point.dot(UP) - 0.5).abs() < 1e-3, "{hit:?}");
    let mut seen = Vec::new();
    set.intersect_shape(
        &Pose::from_translation(UP * 0.6),
        &ball,
        DeformableQueryFilter::default(),
        |d, _| {
            seen.push(d);
            true
        },
    );
    assert_eq!(seen, vec![h]);
    seen.clear();
    set.intersect_shape(
        &Pose::from_translation(UP * 0.8),
        &ball,
        DeformableQueryFilter::default(),
        |d, _| {
            seen.push(d);
            true
        },
    );
    assert!(seen.is_empty(), "a ball 0.1 above the top intersects");
}

#[test]
fn an_impulse_at_a_hit_changes_the_momentum_by_exactly_that() {
    let mut set = DeformableSet::new();
    let h = set.insert(cube(Vector::ZERO).build().unwrap());
    let hit = set
        .cast_ray(&down_at(0.13), 100.0, DeformableQueryFilter::default())
        .unwrap();
    let before = set[h].linear_momentum();
    let mut j = Vector::splat(0.3);
    j[1] = -2.0;
    assert!(set.apply_impulse_at(&hit, j));
    let change = set[h].linear_momentum() - before;
    assert!(
        (change - j).length() < 1e-5 * j.length(),
        "{change:?} for {j:?}"
    );
    // Only the hit facet's nodes moved.
    let moving: Vec<usize> = (0..set[h].num_nodes())
        .filter(|&i| set[h].velocities()[i] != Vector::ZERO)
        .collect();
    assert!(moving.iter().all(|&i| hit.nodes.contains(&(i as u32))));
    assert!(!set.apply_impulse_at(&hit, Vector::splat(Real::NAN)));
}

#[test]
fn a_ray_follows_a_falling_body() {
    let mut world = crate::dim::DeformableWorld::new();
    let h = world.insert(cube(UP * 3.0).build().unwrap());
    for _ in 0..30 {
        world.step();
    }
    let top = world.deformables[h]
        .positions()
        .iter()
        .map(|p| p.dot(UP))
        .fold(Real::NEG_INFINITY, Real::max);
    assert!(top < 3.5 - 1.0, "the body did not fall: top {top}");
    let hit = world
        .deformables
        .cast_ray(&down_at(0.1), 100.0, DeformableQueryFilter::default())
        .unwrap();
    assert!((hit.point.dot(UP) - top).abs() < 1e-3, "{hit:?}, top {top}");
}
