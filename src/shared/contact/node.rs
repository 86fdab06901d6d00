//! Nodes against colliders: each free surface node swept over the substep in the collider's
//! frame (see the module docs of [`super`]).

use super::super::coupling::Substep;
use super::super::math::{Pose, Real, Vector, FACET_ARITY};
use super::super::rapier::dynamics::RigidBodySet;
use super::super::rapier::geometry::{Aabb, BoundingVolume, Ray};
use super::super::rapier::parry::shape::Shape;
use super::candidates::Candidate;
use super::solve::Contact;

/// The surface a node meets, in the collider's frame.
struct NodeHit {
    /// Fraction of the substep's relative motion at which it is met (0 when touching or
    /// inside).
    toi: Real,
    /// Outward unit normal and the surface point.
    normal: Vector,
    local: Vector,
    /// Distance to the surface at the start of the substep; minus the depth when inside.
    gap: Real,
    candidate: usize,
    inside: bool,
}

impl NodeHit {
    /// Inside beats outside (the deepest first); among the others the earliest.
    fn better_than(&self, other: &NodeHit) -> bool {
        match (self.inside, other.inside) {
            (true, true) => self.gap < other.gap,
            (true, false) => true,
            (false, true) => false,
            (false, false) => self.toi < other.toi,
        }
    }
}

/// A free surface node at the start of a substep: its index, the velocity it is about to move
/// with, the velocity before this substep's force update, and its inverse mass.
#[derive(Copy, Clone, Debug)]
pub(crate) struct FreeNode {
    pub index: u32,
    pub v: Vector,
    pub v_before: Vector,
    pub inv_mass: Real,
}

/// Finds the contact of one free node (position `x`) with its candidates (at their
/// end-of-substep poses): may move `x` back to a surface. The contact's target is the normal
/// velocity relative to the collider that rebounds (restitution) or just closes the gap;
/// [`Contact::solve`] applies it.
pub(crate) fn resolve_node(
    node: FreeNode,
    x: &mut Vector,
    at: &Substep<'_>,
    candidate_ids: &[u32],
    candidates: &[Candidate<'_>],
    bodies: &RigidBodySet,
) -> Option<Contact> {
    let FreeNode {
        index: i,
        v,
        v_before,
        inv_mass,
    } = node;
    let (h, s1, dt, motions) = (at.h, at.s1, at.dt, at.motions);
    let restitution_threshold = at.restitution_threshold;
    let start = *x;
    let end = start + v * h;
    let seg = Aabb::new(start.min(end), start.max(end)).loosened(1e-6);
    // Everything is measured in each collider's frame, the node taken at the start of the
    // substep against the collider's pose then (`prev_pose`) and at its predicted end against
    // the end pose: a node is inside only if it already was at the start, and the segment
    // between the two is its motion relative to the collider (a body moving into a node hits
    // it, rather than finding it inside at its end pose and teleporting it out).
    let mut best: Option<NodeHit> = None;
    for &ci in candidate_ids {
        let ci = ci as usize;
        let cand = &candidates[ci];
        let shape = cand.collider.shape();
        let (p0, p1) = (&cand.prev_pose, &cand.pose);
        let swept = shape.compute_aabb(p0).merged(&shape.compute_aabb(p1));
        if !swept.loosened(1e-4).intersects(&seg) {
            continue;
        }
        let a = p0.inverse_transform_point(start);
        let b = p1.inverse_transform_point(end);
        let hit = if shape.contains_local_point(a) {
            let rel = || v_before - cand.point_velocity(start, s1, dt, motions, bodies);
            hit_from_inside(shape, a, p0, rel, h, ci)
        } else if a != b {
            let ray = Ray::new(a, b - a);
            shape
                .cast_local_ray_and_get_normal(&ray, 1.0, true)
                .map(|hit| {
                    let local = ray.point_at(hit.time_of_impact);
                    NodeHit {
                        toi: hit.time_of_impact,
                        normal: hit.normal,
                        local,
                        gap: (a - local).dot(hit.normal).max(0.0),
                        candidate: ci,
                        inside: false,
                    }
                })
        } else {
            None
        };
        if let Some(hit) = hit {
            if best.as_ref().is_none_or(|b| hit.better_than(b)) {
                best = Some(hit);
            }
        }
    }
    let hit = best?;
    let ci = hit.candidate;
    let cand = &candidates[ci];
    let n = cand.pose.rotation * hit.normal;
    let point = cand.pose.transform_point(hit.local);
    let vc = cand.point_velocity(point, s1, dt, motions, bodies);
    let vn = (v - vc).dot(n);
    let vn_min = -hit.gap.max(0.0) / h;
    if hit.inside {
        *x = cand.prev_pose.transform_point(hit.local);
    }
    let approach = (v_before - vc).dot(n);
    let mut target = if -approach > restitution_threshold && cand.restitution > 0.0 {
        (-cand.restitution * approach).max(vn_min)
    } else {
        vn_min
    };
    if cand.dynamic && vn < target {
        // Never more than reverse the approach this impulse sees: no energy is created.
        target = target.min(-vn);
    }
    let mut nodes = [i; FACET_ARITY];
    let mut weights = [0.0; FACET_ARITY];
    let mut inv_masses = [0.0; FACET_ARITY];
    nodes[0] = i;
    weights[0] = 1.0;
    inv_masses[0] = inv_mass;
    Some(Contact {
        candidate: ci,
        point,
        anchor: cand.anchor(point),
        normal: n,
        nodes,
        weights,
        inv_masses,
        target,
        normal_impulse: 0.0,
        friction_impulse: Vector::ZERO,
    })
}

/// The surface a node found inside a collider (at `a` in the collider's frame, whose pose at
/// the start of the substep is `p0`) is put back on; `rel` gives its velocity relative to the
/// collider.
fn hit_from_inside(
    shape: &dyn Shape,
    a: Vector,
    p0: &Pose,
    rel: impl FnOnce() -> Vector,
    h: Real,
    ci: usize,
) -> Option<NodeHit> {
    // Out by the closest surface point, unless that is the far side of a thin collider
    // the node has crossed the middle of: then back out of the face it came in by (a
    // ray cast back along its motion relative to the collider, no further than it moved
    // in a substep), along that face's normal so that it is not dragged back along the
    // surface.
    // The normal comes from the feature projected on (a face's own normal), not from
    // the tiny, noisy offset of a node a hair inside.
    let (proj, feature) = shape.project_local_point_and_get_feature(a);
    let offset = proj.point - a;
    let depth = offset.length();
    let feature_normal = shape
        .feature_normal_at_point(Default::default(), feature, proj.point)
        .filter(|n| n.is_finite() && n.length_squared() > 0.5);
    if depth <= Real::EPSILON {
        // On the surface: a touching contact (gap 0), so that the velocity constraint
        // holds; skipping it let a resting node sink for a substep, be pushed out the
        // next, and chatter forever.
        feature_normal.map(|n| NodeHit {
            toi: 0.0,
            normal: n,
            local: a,
            gap: 0.0,
            candidate: ci,
            inside: false,
        })
    } else {
        let mut local = proj.point;
        let mut normal = feature_normal.unwrap_or(offset / depth);
        let rel = rel();
        if rel.length_squared() > 1e-12 {
            let back = Ray::new(a, p0.rotation.inverse() * -rel.normalize());
            let reach = rel.length() * h + 2.0 * depth + 1e-6;
            if let Some(hit) = shape.cast_local_ray_and_get_normal(&back, reach, false) {
                // Leaving the shape: the outward normal points along the ray.
                let nb = if hit.normal.dot(back.dir) < 0.0 {
                    -hit.normal
                } else {
                    hit.normal
                };
                if nb.length_squared() > 0.5 && nb.dot(normal) < 0.0 {
                    normal = nb;
                    local = a + nb * nb.dot(back.point_at(hit.time_of_impact) - a);
                }
            }
        }
        Some(NodeHit {
            toi: 0.0,
            normal,
            local,
            gap: -(local - a).length(),
            candidate: ci,
            inside: true,
        })
    }
}

/// Depth of `x` inside the deepest of the given candidates (zero when outside all).
pub(crate) fn penetration(x: Vector, candidate_ids: &[u32], candidates: &[Candidate<'_>]) -> Real {
    let mut deepest: Real = 0.0;
    for &ci in candidate_ids {
        let cand = &candidates[ci as usize];
        let shape = cand.collider.shape();
        let proj = shape.project_point(&cand.pose, x, false);
        if proj.is_inside {
            deepest = deepest.max((proj.point - x).length());
        }
    }
    deepest
}
