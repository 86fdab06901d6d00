//! Rigid features (corners, edge samples, balls) against the deformable's surface facets (see
//! the module docs of [`super`]).

use super::super::coupling::Substep;
use super::super::math::{self, Real, Vector, FACET_ARITY};
use super::super::rapier::dynamics::RigidBodySet;
use super::candidates::Candidate;
use super::solve::Contact;

/// A surface facet over a substep: its nodes, their positions at the start (`x`) and predicted
/// at the end (`y`), and their inverse masses (zero for a node held by a bone).
#[derive(Copy, Clone, Debug)]
pub(crate) struct FacetMotion {
    pub nodes: [u32; FACET_ARITY],
    pub x: [Vector; FACET_ARITY],
    pub y: [Vector; FACET_ARITY],
    pub inv_masses: [Real; FACET_ARITY],
}

/// How far behind a facet a rigid feature may start a substep and still press it: `slack`
/// times the facet's size, plus `crossing` times how far the feature goes through the facet's
/// plane in the substep.
#[derive(Copy, Clone, Debug)]
pub(crate) struct FacetSlack {
    pub slack: Real,
    pub crossing: Real,
}

/// Tests the features of the facet's candidates against the facet (nodes `facet.nodes`, inverse
/// masses `facet.inv_masses`), which moves from `facet.x` (substep start) to `facet.y` (predicted
/// end), both outward oriented. A feature counts only if it crosses the facet's plane during the substep
/// (outside at the start, within the [`FacetSlack`], and behind it at the end)
/// inside the facet's prism (a round feature: see [`separation`]): a feature deep behind one
/// facet belongs to another. Returns the deepest crossing, as a contact whose target puts the
/// facet on the feature at the end of the substep.
pub(crate) fn resolve_facet(
    facet: &FacetMotion,
    (at, allowed): (&Substep<'_>, FacetSlack),
    candidate_ids: &[u32],
    candidates: &[Candidate<'_>],
    bodies: &RigidBodySet,
) -> Option<Contact> {
    let FacetMotion {
        nodes: facet,
        x,
        y,
        inv_masses,
    } = facet;
    let (h, s1, dt, motions) = (at.h, at.s1, at.dt, at.motions);
    let unit = |q: &[Vector; FACET_ARITY]| -> Option<Vector> {
        let normal = math::facet_normal(q);
        let len = normal.length();
        (len > Real::MIN_POSITIVE).then(|| normal / len)
    };
    let (n0, n) = (unit(x)?, unit(y)?);
    let mut size: Real = 0.0;
    for a in 0..FACET_ARITY {
        for b in a + 1..FACET_ARITY {
            size = size.max(y[a].distance(y[b]));
        }
    }
    let tolerance = allowed.slack * size;
    let denom_of = |w: &[Real; FACET_ARITY]| -> Real {
        w.iter().zip(inv_masses).map(|(w, im)| w * w * im).sum()
    };
    // (depth, candidate, point, weights, direction, separation at the start)
    let mut best: Option<(Real, usize, Vector, [Real; FACET_ARITY], Vector, Real)> = None;
    for &ci in candidate_ids {
        let cand = &candidates[ci as usize];
        for f in &cand.features {
            let c = cand.pose.transform_point(f.local);
            let Some((d, u, w)) = separation(y, n, c, f.radius) else {
                continue;
            };
            if d >= 0.0 {
                continue;
            }
            // At the start, outside the facet's plane (where the feature was over the facet
            // then, or else along the normal).
            let c0 = cand.prev_pose.transform_point(f.local);
            let d0 = separation(x, n0, c0, f.radius)
                .map_or_else(|| n0.dot(c0 - x[0]) - f.radius, |(d0, _, _)| d0);
            if d0 < -tolerance - allowed.crossing * (d0 - d).max(0.0) {
                continue;
            }
            // And only as deep at the end as the substep's motion took it, within half the
            // facet: a facet of a rolling ball turns, and a box corner that its prism swept
            // across, 16 cm behind its new plane, was pushed out at 9 m/s in one 60 Hz step.
            let moved: Vector = (0..FACET_ARITY).map(|a| (y[a] - x[a]) * w[a]).sum();
            let closed = n.dot((c - c0) - moved);
            if d < d0.min(0.0) + closed.min(0.0) - 0.5 * size - tolerance {
                continue;
            }
            if denom_of(&w) <= 0.0 {
                continue;
            }
            if best.is_none_or(|b| d < b.0) {
                best = Some((d, ci as usize, c - u * f.radius, w, u, d0));
            }
        }
    }
    let (d, ci, point, weights, u, d0) = best?;
    // The facet point's normal velocity relative to the feature must change by −d/h (d < 0) for
    // them to meet at the end of the substep; a feature that was already a hair inside at the
    // start (within the tolerance) is not pushed out within this one substep (at h of a
    // fraction of a millisecond even a tenth of a millimetre becomes a separating velocity of
    // metres per second, energy from nowhere that made a resting box bounce), but over a step.
    let already = d0.min(0.0);
    let d = d - already * (1.0 - (h / dt).min(1.0));
    let v_facet: Vector = (0..FACET_ARITY)
        .map(|a| (y[a] - x[a]) * (weights[a] / h))
        .sum();
    let normal = -u;
    let vn = (v_facet - candidates[ci].point_velocity(point, s1, dt, motions, bodies)).dot(normal);
    Some(Contact {
        candidate: ci,
        point,
        anchor: candidates[ci].anchor(point),
        normal,
        nodes: *facet,
        weights,
        inv_masses: *inv_masses,
        target: vn - d / h,
        bounce: 0.0,
        found: vn,
        normal_impulse: 0.0,
        friction_impulse: Vector::ZERO,
        deferred: false,
    })
}

/// Signed separation of a feature (centre `c`, radius `r`) from a facet `q` of unit outward
/// normal `n`, the direction in which it is measured, and the barycentric weights of the
/// facet point it is measured from; `None` when the feature does not belong to the facet.
///
/// A point feature (`r = 0`) belongs to the facet whose prism holds it and is measured along
/// the normal. A round feature is measured from the facet point closest to its centre, along
/// the line between them: a ball over the crease between two tilted facets touches the crease
/// itself, which is in neither facet's prism once the ball's lowest point is taken along
/// either facet's normal. A round feature whose centre is behind the facet's plane counts only
/// inside the prism (measured along the normal): beside the facet it belongs to a neighbour.
fn separation(
    q: &[Vector; FACET_ARITY],
    n: Vector,
    c: Vector,
    r: Real,
) -> Option<(Real, Vector, [Real; FACET_ARITY])> {
    let prism = math::facet_barycentric(q, c);
    let in_prism = prism.iter().all(|&w| w >= -1e-3);
    if r > 0.0 {
        let w = closest_on_facet(q, c, prism);
        let offset = c - facet_point(q, &w);
        let dist = offset.length();
        if n.dot(offset) > 0.0 && dist > Real::MIN_POSITIVE {
            return Some((dist - r, offset / dist, w));
        }
    }
    in_prism.then(|| (n.dot(c - q[0]) - r, n, prism))
}

fn facet_point(q: &[Vector; FACET_ARITY], w: &[Real; FACET_ARITY]) -> Vector {
    q.iter().zip(w).map(|(p, w)| *p * *w).sum()
}

/// Barycentric weights of the point of facet `q` closest to `c`, given those of `c`'s
/// projection on the facet's plane (or line).
fn closest_on_facet(
    q: &[Vector; FACET_ARITY],
    c: Vector,
    projected: [Real; FACET_ARITY],
) -> [Real; FACET_ARITY] {
    if projected.iter().all(|&w| w >= 0.0) {
        return projected;
    }
    // Outside: the closest point is on the boundary, the closest over the edges.
    let mut best = (Real::INFINITY, projected);
    for a in 0..FACET_ARITY {
        for b in a + 1..FACET_ARITY {
            let e = q[b] - q[a];
            let l2 = e.length_squared();
            let t = if l2 > Real::MIN_POSITIVE {
                ((c - q[a]).dot(e) / l2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let d2 = (q[a] + e * t).distance_squared(c);
            if d2 < best.0 {
                let mut w = [0.0; FACET_ARITY];
                w[a] = 1.0 - t;
                w[b] = t;
                best = (d2, w);
            }
        }
    }
    best.1
}
