//! Nodes against colliders: each free surface node swept over the substep in the collider's
//! frame (see the module docs of [`super`]).

use super::super::coupling::Substep;
use super::super::math::{self, Pose, Real, Vector, FACET_ARITY};
use super::super::rapier::dynamics::RigidBodySet;
use super::super::rapier::geometry::{Aabb, BoundingVolume, Ray};
use super::super::rapier::parry::query::PointProjection;
use super::super::rapier::parry::shape::{FeatureId, Shape, ShapeType};
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
        if !cand.substep_box.intersects(&seg) {
            continue;
        }
        let a = p0.inverse_transform_point(start);
        let b = p1.inverse_transform_point(end);
        let hit = if is_two_sided(shape) {
            surface_hit(shape, a, b, at.skin, ci)
        } else if shape.contains_local_point(a) {
            let rel = || v_before - cand.point_velocity(start, s1, dt, motions, bodies);
            hit_from_inside(shape, a, b - a, p0, rel, h, ci)
        } else {
            cast_motion(shape, a, b, true).map(|(toi, normal, local)| NodeHit {
                toi,
                normal,
                local,
                gap: (a - local).dot(normal).max(0.0),
                candidate: ci,
                inside: false,
            })
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
    let mut target =
        super::normal_target(vn_min, approach, cand.restitution, restitution_threshold);
    if cand.dynamic && vn < target {
        // Never more than reverse the approach this impulse sees: no energy is created.
        target = target.min(-vn);
    }
    let bounce = (target - vn_min).max(0.0);
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
        bounce,
        found: vn,
        normal_impulse: 0.0,
        friction_impulse: Vector::ZERO,
        deferred: false,
    })
}

/// Where a node moving from `a` to `b` (the collider's frame) first meets the shape: the
/// fraction of the motion, the shape's normal there and the point. The ray is cast with a unit
/// direction over the motion's length: parry takes a short ray (a slow node's motion over a
/// substep) for one parallel to a segment or face it crosses, and misses it.
fn cast_motion(
    shape: &dyn Shape,
    a: Vector,
    b: Vector,
    solid: bool,
) -> Option<(Real, Vector, Vector)> {
    let length = (b - a).length();
    if length.is_nan() || length <= 0.0 {
        return None;
    }
    let ray = Ray::new(a, (b - a) / length);
    let hit = shape.cast_local_ray_and_get_normal(&ray, length, solid)?;
    let on = ray.point_at(hit.time_of_impact);
    Some((hit.time_of_impact / length, hit.normal, on))
}

/// Whether a shape is met as a surface from either side, without an inside: a trimesh (in 3D
/// a closed one's pseudo-normals would say inside, but an open one's, of either winding, would
/// send a node through; in 2D a point inside projects onto itself or onto an edge between two
/// triangles), a polyline, a heightfield. A node that starts inside a closed one is not
/// pushed out.
pub(crate) fn is_two_sided(shape: &dyn Shape) -> bool {
    matches!(
        shape.shape_type(),
        ShapeType::TriMesh | ShapeType::Polyline | ShapeType::HeightField
    )
}

/// How far off a two-sided surface a node is kept, so that rounding never puts it on the
/// other side: a thousandth of the body's shortest surface edge, at least a millionth of its
/// coordinates' magnitude (a few f32 ulps), at most 1 mm.
pub(crate) fn surface_skin(shortest_edge: Real, extent: Real) -> Real {
    let fine = if shortest_edge.is_finite() {
        1e-3 * shortest_edge
    } else {
        0.0
    };
    fine.min(1e-3).max(1e-6 * extent).max(1e-7)
}

/// A node (from `a` to `b` in the collider's frame) against a two-sided surface: stopped on
/// the side it came from, `skin` off the surface. A node within the skin is put back on it
/// (on its own side); one whose motion crosses the surface meets it there.
fn surface_hit(shape: &dyn Shape, a: Vector, b: Vector, skin: Real, ci: usize) -> Option<NodeHit> {
    let proj = shape.project_local_point(a, false);
    let offset = a - proj.point;
    let d = offset.length();
    if d < skin {
        // The side it is on; exactly on the surface, the side its motion comes from.
        let normal = if d > 1e-3 * skin {
            offset / d
        } else {
            // The face's normal (from the feature, or, for a heightfield that names none, from
            // a ray along the node's motion), turned to face where the node comes from.
            let (p, feature) = shape.project_local_point_and_get_feature(a);
            let motion = b - a;
            let dir = motion.normalize_or_zero();
            let reach = motion.length() + skin;
            let face = feature_normal(shape, p, feature).or_else(|| {
                cast_motion(shape, a - dir * reach, a + dir * reach, false)
                    .map(|(_, n, _)| n)
                    .filter(|n| n.is_finite() && n.length_squared() > 0.5)
            })?;
            if face.dot(motion) > 0.0 {
                -face
            } else {
                face
            }
        };
        return Some(NodeHit {
            toi: 0.0,
            normal,
            local: proj.point + normal * skin,
            gap: d - skin,
            candidate: ci,
            inside: true,
        });
    }
    // Met when the motion would bring the node within the skin, not only across the surface.
    let dir = (b - a).normalize_or_zero();
    let Some((toi, hit_normal, on)) = cast_motion(shape, a, b + dir * (2.0 * skin), false) else {
        // Parry's ray can slip between two triangles through their shared edge: then the
        // plane of the nearest point (the node is off the surface, so its offset is the
        // normal) says whether the motion comes within the skin.
        let n = offset / d;
        let end = (b - proj.point).dot(n);
        if end >= skin {
            return None;
        }
        return Some(NodeHit {
            toi: ((d - skin) / (d - end)).clamp(0.0, 1.0),
            normal: n,
            local: proj.point + n * skin,
            gap: d - skin,
            candidate: ci,
            inside: false,
        });
    };
    let toi = toi * ((b - a).length() + 2.0 * skin) / (b - a).length().max(Real::MIN_POSITIVE);
    if hit_normal.length_squared() < 0.5 {
        return None;
    }
    // Met from the side the node comes from.
    let normal = if hit_normal.dot(b - a) > 0.0 {
        -hit_normal
    } else {
        hit_normal
    };
    Some(NodeHit {
        toi,
        normal,
        local: on + normal * skin,
        gap: ((a - on).dot(normal) - skin).max(0.0),
        candidate: ci,
        inside: false,
    })
}

/// The surface a node found inside a collider (at `a` in the collider's frame, whose pose at
/// the start of the substep is `p0`) is put back on; `motion` is its motion over the substep
/// and `rel` gives its velocity, both relative to the collider.
fn hit_from_inside(
    shape: &dyn Shape,
    a: Vector,
    motion: Vector,
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
    let (proj_point, feature_normal) = match math::convex_planes(shape) {
        // A convex polytope: out through the nearest face plane. Parry's projection of a
        // point a hair inside can land on a far corner (2D) or an edge with a slanted normal
        // (3D), which threw nodes across the collider.
        Some(planes) => {
            let (n, d) = planes
                .into_iter()
                .min_by(|x, y| (x.1 - x.0.dot(a)).total_cmp(&(y.1 - y.0.dot(a))))?;
            (a + n * (d - n.dot(a)).max(0.0), Some(n))
        }
        None => {
            let (proj, feature) = shape.project_local_point_and_get_feature(a);
            (proj.point, feature_normal(shape, proj, feature))
        }
    };
    let offset = proj_point - a;
    let depth = offset.length();
    if depth <= Real::EPSILON {
        // On the surface: a touching contact (gap 0), so that the velocity constraint
        // holds; skipping it let a resting node sink for a substep, be pushed out the
        // next, and chatter forever.
        // A shape that names no normal there (voxels): the one a ray meets coming along
        // the node's motion relative to the collider.
        let normal = feature_normal.or_else(|| {
            let dir = motion.normalize_or_zero();
            let reach = motion.length() + 1e-6;
            cast_motion(shape, a - dir * reach, a + dir * reach, true)
                .map(|(_, n, _)| n)
                .filter(|n| n.is_finite() && n.length_squared() > 0.5)
        });
        normal.map(|n| NodeHit {
            toi: 0.0,
            normal: n,
            local: a,
            gap: 0.0,
            candidate: ci,
            inside: false,
        })
    } else {
        let mut local = proj_point;
        let mut normal = feature_normal.unwrap_or(offset / depth);
        // A face between two parts of a compound (or two voxels) leads into the next part,
        // not out: then only the way back out counts.
        let probe = 1e-3 * depth + 1e-6;
        let leads_inside = |p: Vector, n: Vector| shape.contains_local_point(p + n * probe);
        let internal = leads_inside(local, normal);
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
                let exit = a + nb * nb.dot(back.point_at(hit.time_of_impact) - a);
                if nb.length_squared() > 0.5
                    && (nb.dot(normal) < 0.0 || internal)
                    && !leads_inside(exit, nb)
                {
                    normal = nb;
                    local = exit;
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

/// The outward normal of the feature a point was projected on; for a compound, that of the
/// part it was projected on (a compound answers none of its own).
fn feature_normal(shape: &dyn Shape, proj: PointProjection, feature: FeatureId) -> Option<Vector> {
    let usable = |n: &Vector| n.is_finite() && n.length_squared() > 0.5;
    if let Some(n) = shape
        .feature_normal_at_point(Default::default(), feature, proj.point)
        .filter(usable)
    {
        return Some(n);
    }
    let (pose, part) = shape.as_compound()?.shapes().get(proj.subshape as usize)?;
    let local = pose.inverse_transform_point(proj.point);
    let (_, f) = part.project_local_point_and_get_feature(local);
    part.feature_normal_at_point(Default::default(), f, local)
        .filter(usable)
        .map(|n| pose.rotation * n)
}

/// Depth of `x` inside the deepest of the given candidates (zero when outside all), measured
/// in each collider's frame (a rigid pose keeps lengths).
pub(crate) fn penetration(x: Vector, candidate_ids: &[u32], candidates: &[Candidate<'_>]) -> Real {
    let mut deepest: Real = 0.0;
    for &ci in candidate_ids {
        let cand = &candidates[ci as usize];
        let local = cand.pose.inverse_transform_point(x);
        let shape = cand.collider.shape();
        // A point in a box is as deep as its nearest face (negative outside): the common
        // ground and wall, measured without a general projection.
        if let Some(cuboid) = shape.as_cuboid() {
            deepest = deepest.max((cuboid.half_extents - local.abs()).min_element());
            continue;
        }
        let proj = shape.project_local_point(local, false);
        if proj.is_inside {
            deepest = deepest.max((proj.point - local).length());
        }
    }
    deepest
}
