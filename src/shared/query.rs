//! Scene queries against deformables: rapier's query pipeline does not see them, so
//! [`DeformableSet`] answers ray casts, shape casts and intersection tests against each body's
//! current (deformed) surface, through the surface's bounding-volume hierarchy (refitted after
//! every step and every change of state). A [`DeformableHit`] names the body, the surface
//! facet and its nodes, so that game code can act on what it hit
//! ([`DeformableSet::apply_impulse_at`]: a shot).

use super::body::Deformable;
use super::math::{self, Pose, Real, Vector, FACET_ARITY};
use super::rapier::geometry::{BoundingVolume, InteractionGroups, Ray};
use super::rapier::parry::query::{self as parry_query, RayCast, ShapeCastOptions};
use super::rapier::parry::shape::Shape;
use super::set::{DeformableHandle, DeformableSet};

/// Where a query met a deformable's surface.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct DeformableHit {
    /// The body.
    pub deformable: DeformableHandle,
    /// The surface facet: its index in [`Mesh::boundary_facets`](super::Mesh::boundary_facets).
    pub facet: u32,
    /// The facet's nodes.
    pub nodes: [u32; FACET_ARITY],
    /// The point on the facet (for a shape cast: the contact point on the facet at the time
    /// of impact).
    pub point: Vector,
    /// The facet's outward unit normal.
    pub normal: Vector,
    /// The ray's parameter (for a shape cast: the time) at the hit.
    pub time_of_impact: Real,
}

/// Which deformables a query sees.
#[derive(Copy, Clone, Debug)]
pub struct DeformableQueryFilter {
    /// Seen: the bodies whose collision groups (see
    /// [`DeformableBuilder::collision_groups`](super::DeformableBuilder::collision_groups))
    /// interact with these, by rapier's rule.
    pub groups: InteractionGroups,
    /// A body left out (the shooter's own, say).
    pub exclude: Option<DeformableHandle>,
}

impl Default for DeformableQueryFilter {
    fn default() -> Self {
        DeformableQueryFilter {
            groups: InteractionGroups::all(),
            exclude: None,
        }
    }
}

impl DeformableQueryFilter {
    /// Sees only the bodies whose groups interact with `groups`.
    pub fn groups(groups: InteractionGroups) -> Self {
        DeformableQueryFilter {
            groups,
            ..Default::default()
        }
    }

    fn sees(&self, handle: DeformableHandle, body: &Deformable) -> bool {
        self.exclude != Some(handle) && self.groups.test(body.contact.groups)
    }
}

/// The facet `k` of `body` as a parry shape (a triangle in 3D, a segment in 2D).
fn facet(body: &Deformable, k: u32) -> ([u32; FACET_ARITY], math::FacetShape) {
    let nodes = body.rest.mesh.boundary_facets()[k as usize];
    let p: [Vector; FACET_ARITY] = std::array::from_fn(|a| body.state.positions[nodes[a] as usize]);
    (nodes, math::facet_shape(&p))
}

/// The ray's parameter where it crosses facet `k`, no later than `max`. Parry's triangle and
/// segment casts can miss a ray through a shared vertex or edge exactly (both facets missed:
/// a hole in a closed surface), so a miss is checked again against the facet's plane with
/// its barycentric weights allowed a rounding's worth below zero.
fn ray_on_facet(body: &Deformable, k: u32, ray: &Ray, max: Real) -> Option<Real> {
    let (nodes, shape) = facet(body, k);
    if let Some(t) = shape.cast_local_ray(ray, max, true) {
        return Some(t);
    }
    let p: [Vector; FACET_ARITY] = std::array::from_fn(|a| body.state.positions[nodes[a] as usize]);
    let n = math::facet_normal(&p);
    let across = n.dot(ray.dir);
    if across == 0.0 || !across.is_finite() {
        return None;
    }
    let t = n.dot(p[0] - ray.origin) / across;
    let w = math::facet_barycentric(&p, ray.point_at(t));
    (t >= 0.0 && t <= max && w.iter().all(|&w| w >= -1e-5)).then_some(t)
}

fn outward(body: &Deformable, nodes: &[u32; FACET_ARITY]) -> Vector {
    let p: [Vector; FACET_ARITY] = std::array::from_fn(|a| body.state.positions[nodes[a] as usize]);
    math::facet_normal(&p).normalize_or_zero()
}

impl DeformableSet {
    /// The first deformable surface along `ray` within `max_time_of_impact` (in units of the
    /// ray's direction), among the bodies `filter` sees. A ray starting inside a body meets
    /// its surface where it leaves.
    pub fn cast_ray(
        &self,
        ray: &Ray,
        max_time_of_impact: Real,
        filter: DeformableQueryFilter,
    ) -> Option<DeformableHit> {
        let mut best: Option<DeformableHit> = None;
        for (handle, body) in self.iter().filter(|(h, b)| filter.sees(*h, b)) {
            let limit = best.map_or(max_time_of_impact, |b| b.time_of_impact);
            let surface = body.surface_tree();
            let tree = surface.bvh();
            let found = tree.cast_ray(ray, limit, |k, so_far| ray_on_facet(body, k, ray, so_far));
            if let Some((k, toi)) = found {
                let (nodes, _) = facet(body, k);
                best = Some(DeformableHit {
                    deformable: handle,
                    facet: k,
                    nodes,
                    point: ray.point_at(toi),
                    normal: outward(body, &nodes),
                    time_of_impact: toi,
                });
            }
        }
        best
    }

    /// The first deformable surface a shape (at `pose`, moving at `velocity` without turning)
    /// meets within `options.max_time_of_impact` s, among the bodies `filter` sees — a
    /// character controller's sweep.
    pub fn cast_shape(
        &self,
        pose: &Pose,
        velocity: Vector,
        shape: &dyn Shape,
        options: ShapeCastOptions,
        filter: DeformableQueryFilter,
    ) -> Option<DeformableHit> {
        let mut best: Option<DeformableHit> = None;
        let start = shape.compute_aabb(pose);
        for (handle, body) in self.iter().filter(|(h, b)| filter.sees(*h, b)) {
            let limit = best.map_or(options.max_time_of_impact, |b| b.time_of_impact);
            let mut end = start;
            end.mins += velocity * limit;
            end.maxs += velocity * limit;
            let swept = start.merged(&end).loosened(options.target_distance);
            let surface = body.surface_tree();
            for k in surface.bvh().intersect_aabb(&swept) {
                let (nodes, f) = facet(body, k);
                let opts = ShapeCastOptions {
                    max_time_of_impact: best.map_or(limit, |b| b.time_of_impact),
                    ..options
                };
                let Ok(Some(hit)) = parry_query::cast_shapes(
                    pose,
                    velocity,
                    shape,
                    &Pose::IDENTITY,
                    Vector::ZERO,
                    &f,
                    opts,
                ) else {
                    continue;
                };
                if best.is_none_or(|b| hit.time_of_impact < b.time_of_impact) {
                    best = Some(DeformableHit {
                        deformable: handle,
                        facet: k,
                        nodes,
                        point: hit.witness2,
                        normal: outward(body, &nodes),
                        time_of_impact: hit.time_of_impact,
                    });
                }
            }
        }
        best
    }

    /// Calls `found` with every deformable whose surface a shape at `pose` touches or
    /// overlaps, and the first facet found touching it, among the bodies `filter` sees; stops
    /// when `found` returns `false`. A shape wholly inside a body, touching no facet, is
    /// not reported.
    pub fn intersect_shape(
        &self,
        pose: &Pose,
        shape: &dyn Shape,
        filter: DeformableQueryFilter,
        mut found: impl FnMut(DeformableHandle, u32) -> bool,
    ) {
        let bounds = shape.compute_aabb(pose);
        for (handle, body) in self.iter().filter(|(h, b)| filter.sees(*h, b)) {
            let surface = body.surface_tree();
            let touching = surface.bvh().intersect_aabb(&bounds).find(|&k| {
                let (_, f) = facet(body, k);
                parry_query::intersection_test(pose, shape, &Pose::IDENTITY, &f)
                    .is_ok_and(|i| i.intersecting)
            });
            if let Some(k) = touching {
                if !found(handle, k) {
                    return;
                }
            }
        }
    }

    /// Applies `impulse` at a hit: shared by the facet's nodes by their barycentric weights at
    /// the hit point (`Δv_i = w_i J / m_i`, so the body's momentum changes by exactly `J`),
    /// waking the body. Returns `false` (and changes nothing) if the hit's body is gone or the
    /// impulse is not finite.
    pub fn apply_impulse_at(&mut self, hit: &DeformableHit, impulse: Vector) -> bool {
        let Some(body) = self.get_mut(hit.deformable) else {
            return false;
        };
        let n = body.state.positions.len();
        if !impulse.is_finite() || hit.nodes.iter().any(|&i| i as usize >= n) {
            return false;
        }
        let p: [Vector; FACET_ARITY] =
            std::array::from_fn(|a| body.state.positions[hit.nodes[a] as usize]);
        let w = math::facet_barycentric(&p, hit.point).map(|w| w.clamp(0.0, 1.0));
        let total: Real = w.iter().sum();
        for (&node, &w) in hit.nodes.iter().zip(&w) {
            let i = node as usize;
            let share = if total > 0.0 {
                w / total
            } else {
                1.0 / FACET_ARITY as Real
            };
            body.state.velocities[i] += impulse * (share * body.rest.inv_masses[i]);
        }
        body.step.invalidate_forces();
        body.wake_up();
        true
    }
}
