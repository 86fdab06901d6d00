//! Candidates: the colliders a deformable may touch this step, found through rapier's broad
//! phase, with their motion over the step and their point features.

use super::super::coupling::{self, BodyMotion, MotionKind};
use super::super::math::{self, AngVector, Pose, Real, Vector, DIM};
use super::super::rapier::dynamics::{CoefficientCombineRule, RigidBodyHandle, RigidBodySet};
use super::super::rapier::geometry::{
    Aabb, BoundingVolume, BroadPhaseBvh, Collider, ColliderHandle, ColliderSet,
};
use super::super::rapier::parry::query::DefaultQueryDispatcher;
use super::super::rapier::pipeline::QueryFilter;
use super::ContactMaterial;

/// What a deformable's broad phase reads: the rapier sets, whether rapier's BVH indexes every
/// collider ([`broad_phase_is_current`]), the deformable's contact material, and the step.
pub(crate) struct Scan<'a> {
    pub bodies: &'a RigidBodySet,
    pub colliders: &'a ColliderSet,
    pub broad_phase: &'a BroadPhaseBvh,
    pub indexed: bool,
    pub material: &'a ContactMaterial,
    pub gravity: Vector,
    pub dt: Real,
}

/// A point feature of a rigid collider for the facet test: a point in the collider's frame and
/// a radius (zero for polytope corners and edge samples).
#[derive(Copy, Clone, Debug)]
pub(crate) struct Feature {
    pub local: Vector,
    pub radius: Real,
}

/// A collider a deformable may touch this step.
pub(crate) struct Candidate<'a> {
    pub handle: ColliderHandle,
    pub collider: &'a Collider,
    /// Index into the step's body motions.
    pub motion: Option<usize>,
    /// Pose relative to the parent body (or absolute, without one).
    pub local_pose: Pose,
    /// Box swept over the step.
    pub swept: Aabb,
    pub dynamic: bool,
    pub friction: Real,
    pub restitution: Real,
    pub features: Vec<Feature>,
    /// Velocity rapier adds to a dynamic body in its step after this one (gravity and user
    /// forces), counted in the body's motion over this step.
    pub drift: Vector,
    /// Pose at the end of the current substep.
    pub pose: Pose,
    /// How far a dynamic body's centre of mass is at `pose` from where it is now.
    pub shift: Vector,
    /// Pose at the start of the current substep.
    pub prev_pose: Pose,
    /// The box the collider sweeps over the current substep (from `prev_pose` to `pose`),
    /// loosened by 0.1 mm: [`Candidate::update`] makes it, and every change of the poses ends
    /// there.
    pub substep_box: Aabb,
    /// Fractions of the step at the start and at the end of the current substep.
    pub start: Real,
    pub end: Real,
    /// A dynamic body's velocity and angular velocity, and its centre of mass, as the current
    /// substep's contacts found it (before their impulses).
    pub found: Option<(Vector, AngVector, Vector)>,
}

impl Candidate<'_> {
    pub fn pose_at(
        &self,
        s: Real,
        dt: Real,
        motions: &[BodyMotion],
        bodies: &RigidBodySet,
    ) -> Pose {
        match self.motion {
            Some(m) => {
                let mut pose = motions[m].pose_at(s, dt, bodies) * self.local_pose;
                pose.translation += self.drift * (0.5 * s * s * dt);
                pose
            }
            None => self.local_pose,
        }
    }

    /// Moves to the end of the next substep (at fraction `s1` of the step).
    pub fn advance(&mut self, s1: Real, dt: Real, motions: &[BodyMotion], bodies: &RigidBodySet) {
        self.prev_pose = self.pose;
        self.start = self.end;
        self.end = s1;
        self.found = self
            .rigid(motions)
            .and_then(|b| bodies.get(b))
            .map(|rb| (rb.linvel(), rb.angvel(), rb.center_of_mass()));
        self.update(s1, dt, motions, bodies);
    }

    /// The velocity of a dynamic body at `anchor` as the current substep's contacts found it,
    /// before their impulses ([`Candidate::anchored_velocity`] at fraction `s`), or `None`.
    pub fn found_velocity(&self, anchor: Vector, s: Real) -> Option<Vector> {
        self.found
            .map(|(v, w, com)| v + math::ang_cross(w, anchor - com) + self.drift * s)
    }

    /// Recomputes the end-of-substep pose (at fraction `s1`), after an impulse changed the
    /// velocity of a dynamic body.
    pub fn update(&mut self, s1: Real, dt: Real, motions: &[BodyMotion], bodies: &RigidBodySet) {
        self.pose = self.pose_at(s1, dt, motions, bodies);
        self.substep_box = substep_box(self.collider, &self.prev_pose, &self.pose);
        self.shift = match self.rigid(motions).and_then(|b| bodies.get(b)) {
            // Rapier moves the centre of mass by `linvel · t` and turns about it.
            Some(rb) => (rb.linvel() + self.drift * (0.5 * s1)) * (s1 * dt),
            None => Vector::ZERO,
        };
    }

    /// Velocity of the collider's material point at `p` (on the end-of-substep pose, at
    /// fraction `s` of the step).
    pub fn point_velocity(
        &self,
        p: Vector,
        s: Real,
        dt: Real,
        motions: &[BodyMotion],
        bodies: &RigidBodySet,
    ) -> Vector {
        self.anchored_velocity(p, self.anchor(p), s, dt, motions, bodies)
    }

    /// Where the material point at `p` on the end-of-substep pose is on a dynamic body now
    /// (rapier's lever arms are taken from its present centre of mass), or `p` itself.
    pub fn anchor(&self, p: Vector) -> Vector {
        p - self.shift
    }

    /// [`Candidate::point_velocity`] with the anchor of `p` given: it stays that of the pose
    /// where a contact was found while later impulses move the predicted pose.
    pub fn anchored_velocity(
        &self,
        p: Vector,
        anchor: Vector,
        s: Real,
        dt: Real,
        motions: &[BodyMotion],
        bodies: &RigidBodySet,
    ) -> Vector {
        match self.motion {
            Some(_) if self.dynamic => self
                .rigid(motions)
                .and_then(|b| bodies.get(b))
                .map_or(Vector::ZERO, |rb| {
                    rb.velocity_at_point(anchor) + self.drift * s
                }),
            Some(m) if motions[m].kind != MotionKind::Fixed => {
                let body_pose = motions[m].pose_at(s, dt, bodies);
                motions[m].point_velocity(p, &body_pose, dt, bodies)
            }
            _ => Vector::ZERO,
        }
    }

    pub fn body(&self, motions: &[BodyMotion]) -> Option<RigidBodyHandle> {
        self.motion.map(|m| motions[m].handle)
    }

    /// The dynamic body behind this collider, if any.
    pub fn rigid(&self, motions: &[BodyMotion]) -> Option<RigidBodyHandle> {
        self.body(motions).filter(|_| self.dynamic)
    }

    /// Inverse mass of the dynamic body (zero for others) felt by an impulse along `dir`
    /// (unit) at `anchor`: `dirᵀ M⁻¹ dir + (r × dir)ᵀ I⁻¹ (r × dir)`, with rapier's effective
    /// (lock-aware) values.
    pub fn inv_mass_at(
        &self,
        anchor: Vector,
        dir: Vector,
        motions: &[BodyMotion],
        bodies: &RigidBodySet,
    ) -> Real {
        self.rigid(motions)
            .and_then(|b| bodies.get(b))
            .map_or(0.0, |rb| coupling::inv_mass_at(rb, anchor, dir))
    }

    /// Gives the dynamic body (if any) `impulse` at `anchor`: its velocity changes at once.
    ///
    /// Over a step the deformables move a dynamic body as a substepped integrator would: from
    /// its pose at the step's start with its velocity, plus what rapier's step adds to it
    /// (`drift`, gravity and user forces) taken up evenly over the step, and each impulse
    /// changing the velocity from the substep it acts in. So that the path already travelled
    /// stays put, the body's start pose is moved back by `Δv·t` (and `Δω·t` about its centre
    /// of mass), `t` into the step; rapier's step then moves it from there with its final
    /// velocity over the whole step ([`coupling::match_rapier_integration`]), to where the
    /// substeps left it. (Applying gravity at the start of the step, with impulses rewriting
    /// the whole path, let a box held by friction from both sides slip `g dt²/2` a step.)
    pub fn apply_impulse(
        &self,
        impulse: Vector,
        anchor: Vector,
        motions: &[BodyMotion],
        bodies: &mut RigidBodySet,
        dt: Real,
    ) {
        if let Some(rb) = self.rigid(motions).and_then(|b| bodies.get_mut(b)) {
            coupling::apply_impulse(rb, impulse, anchor, self.start * dt);
        }
    }
}

/// Builds a candidate for a collider near the deformable (`region`, world frame), with its
/// point features sampled at `spacing`.
///
/// A dynamic body moves over the step with its velocity plus what rapier's step will add to it
/// (`gravity` and user forces, `drift`), taken up evenly over the step: rapier moves it after
/// the deformables, so a body resting on a deformable would otherwise sink by `g dt²` a step
/// into it before the contacts knew. A sleeping body counts it too: a contact that pushes it
/// wakes it, and rapier's step then adds gravity.
pub(crate) fn candidate<'a>(
    scan: &Scan<'_>,
    handle: ColliderHandle,
    collider: &'a Collider,
    motion: Option<usize>,
    motions: &[BodyMotion],
    region: &Aabb,
    spacing: Real,
) -> Candidate<'a> {
    let (material, bodies, gravity, dt) = (scan.material, scan.bodies, scan.gravity, scan.dt);
    let local_pose = match (motion, collider.position_wrt_parent()) {
        (Some(_), Some(p)) => *p,
        (Some(m), None) => motions[m].pose0.inverse() * *collider.position(),
        (None, _) => *collider.position(),
    };
    let drift = match motion {
        Some(m) if motions[m].kind == MotionKind::Dynamic => bodies
            .get(motions[m].handle)
            .map_or(Vector::ZERO, |b| coupling::rapier_drift(b, gravity, dt)),
        _ => Vector::ZERO,
    };
    let (pose0, mut pose1) = match motion {
        Some(m) => (motions[m].pose0 * local_pose, motions[m].pose1 * local_pose),
        None => (local_pose, local_pose),
    };
    pose1.translation += drift * dt;
    let shape = collider.shape();
    let swept = shape
        .compute_aabb(&pose0)
        .merged(&shape.compute_aabb(&pose1))
        .loosened(1e-4);
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
    let features = features(collider, &pose0, &pose1, region, spacing);
    Candidate {
        handle,
        collider,
        motion,
        local_pose,
        swept,
        dynamic: motion.is_some_and(|m| motions[m].kind == MotionKind::Dynamic),
        friction,
        restitution,
        features,
        drift,
        pose: pose0,
        shift: Vector::ZERO,
        prev_pose: pose0,
        substep_box: substep_box(collider, &pose0, &pose0),
        start: 0.0,
        end: 0.0,
        found: None,
    }
}

/// The box `collider` sweeps from `p0` to `p1` (a still one's box once), loosened by 0.1 mm.
fn substep_box(collider: &Collider, p0: &Pose, p1: &Pose) -> Aabb {
    let shape = collider.shape();
    let end = shape.compute_aabb(p1);
    let swept = if p0 == p1 {
        end
    } else {
        shape.compute_aabb(p0).merged(&end)
    };
    swept.loosened(1e-4)
}

/// Point features of a collider that can reach `region` during the step.
fn features(
    collider: &Collider,
    pose0: &Pose,
    pose1: &Pose,
    region: &Aabb,
    spacing: Real,
) -> Vec<Feature> {
    let shape = collider.shape();
    let mut out = Vec::new();
    // A still collider's two poses are one.
    let poses: &[&Pose] = if pose0 == pose1 {
        &[pose0]
    } else {
        &[pose0, pose1]
    };
    let near = |p: Vector| {
        poses
            .iter()
            .any(|pose| region.contains_local_point(pose.transform_point(p)))
    };
    let polytope =
        |points: &[Vector], edges: &[[usize; 2]], radius: Real, out: &mut Vec<Feature>| {
            for &p in points {
                if near(p) {
                    out.push(Feature { local: p, radius });
                }
            }
            // Edges are features in 3D only: in 2D a polygon's edges are its faces, which the
            // node test already covers.
            for &[a, b] in edges.iter().filter(|_| DIM == 3) {
                let (pa, pb) = (points[a], points[b]);
                // Clip the edge (in the world, at both poses) to the region, then sample it.
                let mut range: Option<(Real, Real)> = None;
                for pose in poses {
                    let (wa, wb) = (pose.transform_point(pa), pose.transform_point(pb));
                    let len = (wb - wa).length();
                    if len <= Real::EPSILON {
                        continue;
                    }
                    if let Some((t0, t1)) = region.clip_line_parameters(wa, (wb - wa) / len) {
                        let (t0, t1) = ((t0 / len).max(0.0), (t1 / len).min(1.0));
                        if t0 <= t1 {
                            range =
                                Some(range.map_or((t0, t1), |(r0, r1)| (r0.min(t0), r1.max(t1))));
                        }
                    }
                }
                let Some((t0, t1)) = range else { continue };
                let length = (pb - pa).length() * (t1 - t0);
                let n = ((length / spacing).ceil() as usize).clamp(1, 256);
                for k in 0..=n {
                    let t = t0 + (t1 - t0) * k as Real / n as Real;
                    if t > 0.0 && t < 1.0 {
                        out.push(Feature {
                            local: pa + (pb - pa) * t,
                            radius,
                        });
                    }
                }
            }
        };
    if let Some(c) = shape.as_cuboid() {
        let corners: Vec<Vector> = (0..1usize << DIM)
            .map(|bits| {
                let mut p = c.half_extents;
                for d in 0..DIM {
                    if bits & (1 << d) != 0 {
                        p[d] = -p[d];
                    }
                }
                p
            })
            .collect();
        let mut edges = Vec::new();
        for a in 0..corners.len() {
            for d in 0..DIM {
                let b = a ^ (1 << d);
                if a < b {
                    edges.push([a, b]);
                }
            }
        }
        polytope(&corners, &edges, 0.0, &mut out);
    } else if let Some((points, edges)) = math::convex_outline(shape) {
        polytope(&points, &edges, 0.0, &mut out);
    } else if let Some(ball) = shape.as_ball() {
        out.push(Feature {
            local: Vector::ZERO,
            radius: ball.radius,
        });
    } else if let Some(cap) = shape.as_capsule() {
        // The axis is sampled in both dimensions: each sample stands for a ball.
        let len = cap.segment.length();
        let k = ((len / spacing).ceil() as usize).clamp(1, 256);
        for j in 0..=k {
            let p = cap.segment.a + (cap.segment.b - cap.segment.a) * (j as Real / k as Real);
            if near(p) || j == 0 || j == k {
                out.push(Feature {
                    local: p,
                    radius: cap.radius,
                });
            }
        }
    }
    out
}

/// Whether rapier's broad phase indexes every collider. It is filled by rapier's step, so
/// before the first step, or after colliders were added since the last, it is not; the
/// candidates are then found by testing every collider's box instead.
pub(crate) fn broad_phase_is_current(
    broad_phase: &BroadPhaseBvh,
    bodies: &RigidBodySet,
    colliders: &ColliderSet,
) -> bool {
    let qp = broad_phase.as_query_pipeline(
        &DefaultQueryDispatcher,
        bodies,
        colliders,
        QueryFilter::default(),
    );
    qp.bvh.leaf_count() as usize == colliders.len()
}

/// Collects the colliders that the broad phase reports near `region` (one BVH query per
/// deformable), skipping sensors, filtered groups and (optionally) bound bodies.
pub(crate) fn near_colliders(
    scan: &Scan<'_>,
    region: Aabb,
    attached_bodies: &[RigidBodyHandle],
    out: &mut Vec<ColliderHandle>,
) {
    let (material, bodies, colliders) = (scan.material, scan.bodies, scan.colliders);
    let (indexed, broad_phase) = (scan.indexed, scan.broad_phase);
    out.clear();
    let filter = QueryFilter::default()
        .exclude_sensors()
        .groups(material.groups);
    let keep = |co: &Collider| {
        !(material.ignore_attached_bodies
            && co.parent().is_some_and(|p| attached_bodies.contains(&p)))
    };
    if indexed {
        let qp = broad_phase.as_query_pipeline(&DefaultQueryDispatcher, bodies, colliders, filter);
        for (handle, co) in qp.intersect_aabb_conservative(region) {
            if keep(co) {
                out.push(handle);
            }
        }
    } else {
        for (handle, co) in colliders.iter() {
            if filter.test(bodies, handle, co) && keep(co) && co.compute_aabb().intersects(&region)
            {
                out.push(handle);
            }
        }
    }
    out.sort_unstable_by_key(|h| h.into_raw_parts());
}

/// Up to this many candidates, [`node_candidates`] tests each one's swept box rather than
/// query the tree.
const FEW_CANDIDATES: usize = 8;

/// Per-node broad phase: the candidates whose swept boxes meet `node_box`, as indices into
/// `candidates`, appended to `out`. Among a few the boxes are tested one by one, which is
/// cheaper than a query of the tree; among many the tree picks those near the node first.
/// (The tree's boxes are rapier's, from its last step, and may lag a moving collider's swept
/// box: among many, a candidate must be near the node in both.)
#[inline]
pub(crate) fn node_candidates(
    scan: &Scan<'_>,
    node_box: Aabb,
    candidates: &[Candidate<'_>],
    out: &mut Vec<u32>,
) {
    if !scan.indexed || candidates.len() <= FEW_CANDIDATES {
        for (k, c) in candidates.iter().enumerate() {
            if c.swept.intersects(&node_box) {
                out.push(k as u32);
            }
        }
    } else {
        near_in_tree(scan, node_box, candidates, out);
    }
}

/// [`node_candidates`] among many: those the tree finds near `node_box`.
fn near_in_tree(scan: &Scan<'_>, node_box: Aabb, candidates: &[Candidate<'_>], out: &mut Vec<u32>) {
    let (material, bodies, colliders) = (scan.material, scan.bodies, scan.colliders);
    let broad_phase = scan.broad_phase;
    let filter = QueryFilter::default()
        .exclude_sensors()
        .groups(material.groups);
    let qp = broad_phase.as_query_pipeline(&DefaultQueryDispatcher, bodies, colliders, filter);
    for (handle, _) in qp.intersect_aabb_conservative(node_box) {
        if let Ok(k) =
            candidates.binary_search_by_key(&handle.into_raw_parts(), |c| c.handle.into_raw_parts())
        {
            if candidates[k].swept.intersects(&node_box) {
                out.push(k as u32);
            }
        }
    }
}

/// Moves the dynamic body of candidate `ci` by `delta` (see [`coupling::translate`]) and its
/// candidates' poses with it, at the start of the substep as at its end.
pub(crate) fn translate_body(
    candidates: &mut [Candidate<'_>],
    ci: usize,
    delta: Vector,
    (s1, dt): (Real, Real),
    motions: &[BodyMotion],
    bodies: &mut RigidBodySet,
) {
    let Some(rb) = candidates[ci]
        .rigid(motions)
        .and_then(|b| bodies.get_mut(b))
    else {
        return;
    };
    coupling::translate(rb, delta);
    let m = candidates[ci].motion;
    for c in candidates.iter_mut().filter(|c| c.motion == m) {
        c.prev_pose.translation += delta;
        c.update(s1, dt, motions, bodies);
    }
}

/// After an impulse to the dynamic body behind candidate `ci`, moves that body's candidates to
/// their end-of-substep poses predicted from its new velocity (later contacts of the same
/// substep then see where it really goes).
pub(crate) fn refresh_poses(
    candidates: &mut [Candidate<'_>],
    ci: usize,
    s1: Real,
    dt: Real,
    motions: &[BodyMotion],
    bodies: &RigidBodySet,
) {
    let Some(m) = candidates[ci].motion.filter(|_| candidates[ci].dynamic) else {
        return;
    };
    for c in candidates.iter_mut().filter(|c| c.motion == Some(m)) {
        c.update(s1, dt, motions, bodies);
    }
}
