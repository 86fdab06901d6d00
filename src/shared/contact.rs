//! Node-versus-collider contact (shape-based paper §2.3; `DESIGN.md` §4).
//!
//! Each step a deformable asks rapier's broad phase (its BVH, through a short-lived query
//! pipeline) for the colliders whose boxes overlap the box swept by its surface nodes. Each
//! substep, after the element forces have updated the velocities and before positions move
//! (`x += h v`), every surface node is tested against those candidates with parry:
//!
//! * a node already inside a collider is put back on its closest surface point (parry's
//!   point projection onto the true closest feature, never an infinite plane);
//! * otherwise the segment it is about to sweep, `x → x + h v`, is ray-cast against the
//!   collider, so no speed can carry it through a thin collider.
//!
//! On contact the normal velocity relative to the collider's point velocity is set to
//! `−e · (approach speed before this substep's force update)` if that approach was faster than
//! the restitution threshold (a bounce), else to just close the gap (a resting contact); the
//! tangential velocity loses `μ · Δv_n` (Coulomb; it sticks when that is enough). `e` and `μ`
//! combine the deformable's and the collider's coefficients with rapier's rules. The momentum
//! the node gains is taken from a dynamic parent body as an impulse at the contact point.

use super::math::{Real, Vector};
use super::rapier::dynamics::{CoefficientCombineRule, RigidBodyHandle, RigidBodySet};
use super::rapier::geometry::BroadPhaseBvh;
use super::rapier::geometry::{
    Aabb, BoundingVolume, Collider, ColliderHandle, ColliderSet, InteractionGroups, Ray,
};
use super::rapier::parry::query::DefaultQueryDispatcher;
use super::rapier::pipeline::QueryFilter;

/// Contact coefficients of a deformable.
#[derive(Copy, Clone, Debug, PartialEq)]
pub(crate) struct ContactMaterial {
    pub friction: Real,
    pub restitution: Real,
    pub friction_combine_rule: CoefficientCombineRule,
    pub restitution_combine_rule: CoefficientCombineRule,
    pub groups: InteractionGroups,
}

/// A collider a deformable may touch this step.
pub(crate) struct Candidate<'a> {
    #[allow(dead_code)] // kept for contact events (next issue)
    pub handle: ColliderHandle,
    pub collider: &'a Collider,
    pub aabb: Aabb,
    pub body: Option<RigidBodyHandle>,
    pub moving: bool,
    pub dynamic: bool,
    pub friction: Real,
    pub restitution: Real,
}

/// Gathers the colliders whose broad-phase boxes overlap `region`.
pub(crate) fn gather<'a>(
    region: Aabb,
    dt: Real,
    material: &ContactMaterial,
    bodies: &RigidBodySet,
    colliders: &'a ColliderSet,
    broad_phase: &BroadPhaseBvh,
    out: &mut Vec<Candidate<'a>>,
) {
    out.clear();
    let filter = QueryFilter::default()
        .exclude_sensors()
        .groups(material.groups);
    let qp = broad_phase.as_query_pipeline(&DefaultQueryDispatcher, bodies, colliders, filter);
    for (handle, _) in qp.intersect_aabb_conservative(region) {
        // Borrow from the set itself so the reference outlives the query pipeline.
        let Some(collider) = colliders.get(handle) else {
            continue;
        };
        let parent = collider
            .parent()
            .and_then(|h| bodies.get(h).map(|b| (h, b)));
        let (moving, dynamic, sweep) = match parent {
            Some((_, b)) if !b.is_fixed() => {
                let speed = b.linvel().length()
                    + super::math::ang_norm(b.angvel())
                        * collider.compute_aabb().half_extents().length();
                (true, b.is_dynamic(), speed * dt)
            }
            _ => (false, false, 0.0),
        };
        let friction = CoefficientCombineRule::combine(
            material.friction,
            collider.friction(),
            material.friction_combine_rule,
            collider.friction_combine_rule(),
        );
        let restitution = CoefficientCombineRule::combine(
            material.restitution,
            collider.restitution(),
            material.restitution_combine_rule,
            collider.restitution_combine_rule(),
        );
        out.push(Candidate {
            handle,
            collider,
            aabb: collider.compute_aabb().loosened(sweep + 1e-4),
            body: parent.map(|(h, _)| h),
            moving,
            dynamic,
            friction,
            restitution,
        });
    }
}

/// What a node's contact did this substep.
pub(crate) struct NodeContact {
    pub body: Option<RigidBodyHandle>,
    pub dynamic: bool,
    pub point: Vector,
    pub impulse: Vector,
}

/// Resolves one node against the candidates: may move `x` back to the surface and change `v`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn resolve_node(
    x: &mut Vector,
    v: &mut Vector,
    v_before: Vector,
    mass: Real,
    h: Real,
    restitution_threshold: Real,
    candidates: &[Candidate<'_>],
    bodies: &RigidBodySet,
) -> Option<NodeContact> {
    let start = *x;
    let motion = *v * h;
    let end = start + motion;
    let seg = Aabb::new(start.min(end), start.max(end)).loosened(1e-6);
    // (time of impact, normal, point on the surface, candidate, inside)
    let mut best: Option<(Real, Vector, Vector, usize, bool)> = None;
    for (ci, cand) in candidates.iter().enumerate() {
        if !cand.aabb.intersects(&seg) {
            continue;
        }
        let shape = cand.collider.shape();
        let pose = cand.collider.position();
        if shape.contains_point(pose, start) {
            let proj = shape.project_point(pose, start, false);
            let out = proj.point - start;
            let depth = out.length();
            let normal = if depth > Real::EPSILON {
                out / depth
            } else {
                continue;
            };
            if best.is_none_or(|b| !b.4 || depth > (b.2 - start).length()) {
                best = Some((0.0, normal, proj.point, ci, true));
            }
        } else if motion.length_squared() > 0.0 {
            let ray = Ray::new(start, motion);
            if let Some(hit) = shape.cast_ray_and_get_normal(pose, &ray, 1.0, true) {
                if best.is_none_or(|b| !b.4 && hit.time_of_impact < b.0) {
                    best = Some((
                        hit.time_of_impact,
                        hit.normal,
                        ray.point_at(hit.time_of_impact),
                        ci,
                        false,
                    ));
                }
            }
        }
    }
    let (_, n, point, ci, inside) = best?;
    let cand = &candidates[ci];
    let vc = match cand.body {
        Some(b) if cand.moving => bodies
            .get(b)
            .map_or(Vector::ZERO, |b| b.velocity_at_point(point)),
        _ => Vector::ZERO,
    };
    let vr = *v - vc;
    let vn = vr.dot(n);
    let gap = if inside {
        0.0
    } else {
        (start - point).dot(n).max(0.0)
    };
    let vn_min = -gap / h;
    let v_old = *v;
    if inside {
        *x = point;
    }
    if vn < vn_min {
        let approach = (v_before - vc).dot(n);
        let vn_new = if -approach > restitution_threshold && cand.restitution > 0.0 {
            -cand.restitution * approach
        } else {
            vn_min
        };
        let dvn = vn_new - vn;
        let vt = vr - n * vn;
        let vt_len = vt.length();
        let vt_new = if vt_len > 0.0 {
            vt * (1.0 - cand.friction * dvn / vt_len).max(0.0)
        } else {
            Vector::ZERO
        };
        *v = vc + n * vn_new + vt_new;
    }
    Some(NodeContact {
        body: cand.body,
        dynamic: cand.dynamic,
        point,
        impulse: (v_old - *v) * mass,
    })
}

/// Depth of `x` inside the deepest candidate (zero when outside all).
pub(crate) fn penetration(x: Vector, candidates: &[Candidate<'_>]) -> Real {
    let mut deepest: Real = 0.0;
    for cand in candidates {
        if !cand.aabb.contains_local_point(x) {
            continue;
        }
        let shape = cand.collider.shape();
        let pose = cand.collider.position();
        let proj = shape.project_point(pose, x, false);
        if proj.is_inside {
            deepest = deepest.max((proj.point - x).length());
        }
    }
    deepest
}
