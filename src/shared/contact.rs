//! Contact between deformables and rapier colliders (shape-based paper §2.3; `DESIGN.md` §4).
//!
//! **Candidates.** Each step, every surface node asks rapier's broad phase (its BVH, through a
//! short-lived query pipeline) for the colliders whose boxes overlap the box the node sweeps
//! during the step, widened by how far the nearby moving bodies travel. Sensors are skipped,
//! the deformable's collision groups are honoured, and the bodies it is bound to are ignored
//! unless it asks otherwise.
//!
//! **Moving colliders.** A collider's pose at any time of the step comes from its body: fixed
//! bodies stay put; kinematic bodies are interpolated from `position()` to `next_position()`
//! (position-based) or predicted from their velocity (velocity-based); dynamic bodies are
//! predicted from their current velocity plus what rapier's step will add to it (gravity and
//! user forces), and the deformable's impulses change that velocity during the step. The point
//! velocity of a contact is that of the collider's motion.
//!
//! **Node against collider**, each substep, after element forces and before `x += h v`, for
//! every free surface node, against its candidates at their end-of-substep poses:
//! * a node found inside a collider is put back on its surface where it came in (a ray cast
//!   back along its motion relative to the collider, so a thin plate is not crossed by
//!   projecting to its far side), or on the closest surface point (parry's projection onto the
//!   true closest feature) when it has no relative motion;
//! * otherwise the segment it is about to sweep, `x → x + h v`, is ray-cast against the
//!   collider, so no speed carries it through a thin collider.
//!
//! The normal velocity relative to the collider becomes `−e · (approach speed before this
//! substep's force update)` when that approach is faster than the restitution threshold (a
//! bounce), else just what closes the gap (resting contact); friction is Coulomb's (it sticks
//! when `μ` times the normal impulse is enough). `e` and `μ` combine the deformable's and the
//! collider's coefficients with rapier's rules.
//!
//! **Dynamic bodies** take the opposite of every impulse, at once, at the contact point, and
//! each impulse is computed with the effective mass of both sides (the node's or facet point's,
//! and the body's mass and inertia there): momentum is conserved, no impulse more than reverses
//! the approach it sees (no energy is created), and a body lighter than the nodes under it is
//! not launched (see [`Contact`]).
//!
//! **Rigid features against soft faces.** A rigid corner or thin edge can reach between the
//! nodes of a coarse mesh without touching any of them. So each substep the vertices of
//! cuboids and convex polytopes, points sampled along their edges (spacing half the shortest
//! surface edge), and balls (the centres of balls and of samples along capsule axes, with their
//! radius) are tested against the deformable's surface facets (triangles in 3D, segments in
//! 2D): a feature that crosses a facet during the substep (a point inside the facet's prism; a
//! ball measured from the facet point closest to its centre, so that it also meets creases)
//! moves the facet's nodes (mass- and barycentric-weighted velocity change) so the facet ends
//! the substep on the feature, with friction, and the opposite impulse goes to a dynamic body.
//! Not covered: features of trimeshes, heightfields, compound and other shapes (their surfaces
//! still stop nodes).

use super::math::{self, Pose, Real, Vector, DIM, FACET_ARITY};
use super::rapier::dynamics::{
    CoefficientCombineRule, RigidBody, RigidBodyHandle, RigidBodySet, RigidBodyType,
    RigidBodyVelocity,
};
use super::rapier::geometry::{
    Aabb, BoundingVolume, BroadPhaseBvh, Collider, ColliderHandle, ColliderSet, InteractionGroups,
    Ray,
};
use super::rapier::parry::query::DefaultQueryDispatcher;
use super::rapier::pipeline::QueryFilter;

/// Contact coefficients and filters of a deformable.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Copy, Clone, Debug, PartialEq)]
pub(crate) struct ContactMaterial {
    pub friction: Real,
    pub restitution: Real,
    pub friction_combine_rule: CoefficientCombineRule,
    pub restitution_combine_rule: CoefficientCombineRule,
    pub groups: InteractionGroups,
    pub ignore_attached_bodies: bool,
}

#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(crate) enum MotionKind {
    Fixed,
    Kinematic,
    Dynamic,
}

/// How a rigid body moves over the step.
#[derive(Copy, Clone, Debug)]
pub(crate) struct BodyMotion {
    pub handle: RigidBodyHandle,
    pub kind: MotionKind,
    pub pose0: Pose,
    pub pose1: Pose,
}

impl BodyMotion {
    pub fn new(handle: RigidBodyHandle, body: &RigidBody, dt: Real) -> Self {
        let pose0 = *body.position();
        let (kind, pose1) = match body.body_type() {
            RigidBodyType::Fixed => (MotionKind::Fixed, pose0),
            RigidBodyType::KinematicPositionBased => (MotionKind::Kinematic, *body.next_position()),
            RigidBodyType::KinematicVelocityBased => (
                MotionKind::Kinematic,
                body.predict_position_using_velocity(dt),
            ),
            // Dynamic bodies, and rapier's own soft-body proxies, which count as dynamic.
            _ => (
                MotionKind::Dynamic,
                body.predict_position_using_velocity(dt),
            ),
        };
        BodyMotion {
            handle,
            kind,
            pose0,
            pose1,
        }
    }

    /// The body's pose at fraction `s` of the step.
    pub fn pose_at(&self, s: Real, dt: Real, bodies: &RigidBodySet) -> Pose {
        match self.kind {
            MotionKind::Fixed => self.pose0,
            MotionKind::Kinematic => self.pose0.lerp(&self.pose1, s),
            MotionKind::Dynamic => bodies
                .get(self.handle)
                .map_or(self.pose0, |b| b.predict_position_using_velocity(s * dt)),
        }
    }

    /// Velocity of the material point at world position `p` (at fraction `s` of the step).
    pub fn point_velocity(
        &self,
        p: Vector,
        pose_s: &Pose,
        dt: Real,
        bodies: &RigidBodySet,
    ) -> Vector {
        match self.kind {
            MotionKind::Fixed => Vector::ZERO,
            MotionKind::Kinematic => {
                let local = pose_s.inverse_transform_point(p);
                (self.pose1.transform_point(local) - self.pose0.transform_point(local)) / dt
            }
            MotionKind::Dynamic => bodies
                .get(self.handle)
                .map_or(Vector::ZERO, |b| b.velocity_at_point(p)),
        }
    }

    /// An upper bound of how far any point within `radius` of the body origin travels.
    pub fn travel(&self, radius: Real) -> Real {
        let t = (self.pose1.translation - self.pose0.translation).length();
        let a = math::rotation_angle_between(self.pose0.rotation, self.pose1.rotation);
        t + a * radius
    }
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
    /// Fractions of the step at the start and at the end of the current substep.
    pub start: Real,
    pub end: Real,
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
                pose.translation += self.drift * (s * dt);
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
        self.update(s1, dt, motions, bodies);
    }

    /// Recomputes the end-of-substep pose (at fraction `s1`), after an impulse changed the
    /// velocity of a dynamic body.
    pub fn update(&mut self, s1: Real, dt: Real, motions: &[BodyMotion], bodies: &RigidBodySet) {
        self.pose = self.pose_at(s1, dt, motions, bodies);
        self.shift = match self.rigid(motions).and_then(|b| bodies.get(b)) {
            // Rapier moves the centre of mass by `linvel · t` and turns about it.
            Some(rb) => (rb.linvel() + self.drift) * (s1 * dt),
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
    #[allow(clippy::too_many_arguments)]
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
                .map_or(Vector::ZERO, |rb| rb.velocity_at_point(anchor) + self.drift),
            Some(m) => {
                let body_pose = motions[m].pose_at(s, dt, bodies);
                motions[m].point_velocity(p, &body_pose, dt, bodies)
            }
            None => Vector::ZERO,
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
            .map_or(0.0, |rb| {
                let props = rb.mass_properties();
                let rn = math::cross(anchor - rb.center_of_mass(), dir);
                (props.effective_inv_mass * dir).dot(dir)
                    + math::ang_dot(rn, props.effective_world_inv_inertia * rn)
            })
    }

    /// Gives the dynamic body (if any) `impulse` at `anchor`: its velocity changes at once.
    ///
    /// Over a step the deformables see a dynamic body where its present pose and velocity put
    /// it, and rapier's step then moves it with its final velocity over the whole step: a
    /// velocity change `Δv` at the start of a substep, `t` into the step, moves that whole
    /// predicted path by `Δv·s`, the part before `t` included. That is rapier's own model (one
    /// velocity per step, so that a resting body is held from the start of the step) and is
    /// kept for normal impulses. With `keep_path` (friction impulses) the body's start pose is
    /// moved back by `Δv·t` (and `Δω·t` about its centre of mass) instead, so that where it is
    /// at `t` stays put: rewriting the path sideways after each friction impulse fed a sway
    /// that grew by about 0.03 J/s (a 10 kg box on a soft cube never came to rest).
    pub fn apply_impulse(
        &self,
        impulse: Vector,
        anchor: Vector,
        motions: &[BodyMotion],
        bodies: &mut RigidBodySet,
        keep_path: bool,
        dt: Real,
    ) {
        if let Some(rb) = self.rigid(motions).and_then(|b| bodies.get_mut(b)) {
            let (v0, w0) = (rb.linvel(), rb.angvel());
            rb.apply_impulse_at_point(impulse, anchor, true);
            let elapsed = self.start * dt;
            if keep_path && elapsed > 0.0 {
                let change = RigidBodyVelocity::new(rb.linvel() - v0, rb.angvel() - w0);
                let pose = change.integrate(-elapsed, rb.position(), &rb.local_center_of_mass());
                rb.set_position(pose, false);
            }
        }
    }
}

/// Builds a candidate for a collider near the deformable (`region`, world frame), with its
/// point features sampled at `spacing`.
///
/// A dynamic body moves over the step with its velocity plus what rapier's step will add to it
/// (`gravity` and user forces, `drift`): rapier moves it after the deformables, so a body
/// resting on a deformable would otherwise start every step sunk by `g dt²` into it (past the
/// facet test's start tolerance), and be supported only when already inside.
#[allow(clippy::too_many_arguments)]
pub(crate) fn candidate<'a>(
    handle: ColliderHandle,
    collider: &'a Collider,
    motion: Option<usize>,
    motions: &[BodyMotion],
    material: &ContactMaterial,
    region: &Aabb,
    spacing: Real,
    bodies: &RigidBodySet,
    gravity: Vector,
    dt: Real,
) -> Candidate<'a> {
    let local_pose = match (motion, collider.position_wrt_parent()) {
        (Some(_), Some(p)) => *p,
        (Some(m), None) => motions[m].pose0.inverse() * *collider.position(),
        (None, _) => *collider.position(),
    };
    let drift = match motion {
        Some(m) if motions[m].kind == MotionKind::Dynamic => bodies
            .get(motions[m].handle)
            .map_or(Vector::ZERO, |b| rapier_drift(b, gravity, dt)),
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
        start: 0.0,
        end: 0.0,
    }
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
    let near = |p: Vector| {
        region.contains_local_point(pose0.transform_point(p))
            || region.contains_local_point(pose1.transform_point(p))
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
                for pose in [pose0, pose1] {
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
#[allow(clippy::too_many_arguments)]
pub(crate) fn near_colliders(
    region: Aabb,
    indexed: bool,
    material: &ContactMaterial,
    attached_bodies: &[RigidBodyHandle],
    bodies: &RigidBodySet,
    colliders: &ColliderSet,
    broad_phase: &BroadPhaseBvh,
    out: &mut Vec<ColliderHandle>,
) {
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

/// Per-node broad phase: the candidates whose BVH boxes overlap `node_box`, as indices into
/// `candidates`, appended to `out`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn node_candidates(
    node_box: Aabb,
    indexed: bool,
    material: &ContactMaterial,
    bodies: &RigidBodySet,
    colliders: &ColliderSet,
    broad_phase: &BroadPhaseBvh,
    candidates: &[Candidate<'_>],
    out: &mut Vec<u32>,
) {
    if !indexed {
        for (k, c) in candidates.iter().enumerate() {
            if c.swept.intersects(&node_box) {
                out.push(k as u32);
            }
        }
        return;
    }
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

/// A contact between the deformable (a node, or a point of a surface facet) and a collider,
/// solved on velocities.
///
/// Impulses on a dynamic body use the effective mass of both sides: `Σ w_j²/m_j` on the
/// deformable, and the body's mass and inertia at the contact point. Each impulse is equal and
/// opposite (momentum is conserved) and applied to the body at once, so later contacts see its
/// new velocity: a light body is not launched by the whole momentum change of every node it
/// touches. The normal impulse stays non-negative and reaches at most the target relative
/// velocity (never more than the reverse of the approach: no energy is created); friction is
/// Coulomb's, at most `μ` times the normal impulse, and no more than stops the slip.
pub(crate) struct Contact {
    pub candidate: usize,
    /// Contact point, on the collider's end-of-substep pose.
    pub point: Vector,
    /// The same material point on a dynamic body's present pose (see [`Candidate::anchor`]):
    /// the contact keeps it while later impulses move the predicted pose.
    anchor: Vector,
    /// Unit normal from the collider towards the deformable.
    pub normal: Vector,
    /// The deformable's side: nodes, barycentric weights and inverse masses (zero for a node
    /// held by a bone: its share goes to the bone).
    nodes: [u32; FACET_ARITY],
    weights: [Real; FACET_ARITY],
    inv_masses: [Real; FACET_ARITY],
    /// Normal velocity of the deformable relative to the collider to reach.
    target: Real,
    normal_impulse: Real,
    friction_impulse: Vector,
}

impl Contact {
    /// Adds the dynamic body it pushed (with a non-zero normal impulse), if any, to `pushed`.
    pub fn note_pushed(
        &self,
        candidates: &[Candidate<'_>],
        motions: &[BodyMotion],
        pushed: &mut Vec<RigidBodyHandle>,
    ) {
        if self.normal_impulse > 0.0 {
            if let Some(b) = candidates[self.candidate].rigid(motions) {
                if !pushed.contains(&b) {
                    pushed.push(b);
                }
            }
        }
    }

    fn velocity(&self, velocities: &[Vector]) -> Vector {
        (0..FACET_ARITY)
            .map(|a| velocities[self.nodes[a] as usize] * self.weights[a])
            .sum()
    }

    fn inv_mass(&self) -> Real {
        (0..FACET_ARITY)
            .map(|a| self.weights[a] * self.weights[a] * self.inv_masses[a])
            .sum()
    }

    /// `impulse` on the deformable's side, its opposite on a dynamic body (see
    /// [`Candidate::apply_impulse`] for `keep_path`).
    #[allow(clippy::too_many_arguments)]
    fn apply(
        &self,
        impulse: Vector,
        velocities: &mut [Vector],
        cand: &Candidate<'_>,
        motions: &[BodyMotion],
        bodies: &mut RigidBodySet,
        keep_path: bool,
        dt: Real,
    ) {
        for a in 0..FACET_ARITY {
            velocities[self.nodes[a] as usize] += impulse * (self.weights[a] * self.inv_masses[a]);
        }
        cand.apply_impulse(-impulse, self.anchor, motions, bodies, keep_path, dt);
    }

    /// One Gauss–Seidel update: the normal impulse towards the target, then friction.
    #[allow(clippy::too_many_arguments)]
    pub fn solve(
        &mut self,
        velocities: &mut [Vector],
        s1: Real,
        dt: Real,
        candidates: &[Candidate<'_>],
        motions: &[BodyMotion],
        bodies: &mut RigidBodySet,
    ) {
        let cand = &candidates[self.candidate];
        let n = self.normal;
        let own = self.inv_mass();
        let (point, anchor) = (self.point, self.anchor);
        let relative = |this: &Self, velocities: &[Vector], bodies: &RigidBodySet| {
            this.velocity(velocities)
                - cand.anchored_velocity(point, anchor, s1, dt, motions, bodies)
        };
        let k = own + cand.inv_mass_at(anchor, n, motions, bodies);
        if k > 0.0 {
            let vn = relative(self, velocities, bodies).dot(n);
            let total = (self.normal_impulse + (self.target - vn) / k).max(0.0);
            let dj = total - self.normal_impulse;
            self.normal_impulse = total;
            self.apply(n * dj, velocities, cand, motions, bodies, false, dt);
        }
        if cand.friction <= 0.0 {
            return;
        }
        let vr = relative(self, velocities, bodies);
        let vt = vr - n * vr.dot(n);
        let slip = vt.length();
        let mut total = self.friction_impulse;
        if slip > 0.0 {
            let t = vt / slip;
            let kt = own + cand.inv_mass_at(anchor, t, motions, bodies);
            if kt > 0.0 {
                total -= t * (slip / kt);
            }
        }
        let limit = cand.friction * self.normal_impulse;
        let len = total.length();
        if len > limit {
            total *= limit / len;
        }
        let dj = total - self.friction_impulse;
        self.friction_impulse = total;
        self.apply(dj, velocities, cand, motions, bodies, true, dt);
    }
}

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

/// Finds the contact of one free node `i` (position `x`, velocity `v`, inverse mass
/// `inv_mass`) with its candidates (at their end-of-substep poses): may move `x` back to a
/// surface. The contact's target is the normal velocity relative to the collider that
/// rebounds (restitution) or just closes the gap; [`Contact::solve`] applies it.
#[allow(clippy::too_many_arguments)]
pub(crate) fn resolve_node(
    i: u32,
    x: &mut Vector,
    v: Vector,
    v_before: Vector,
    inv_mass: Real,
    h: Real,
    s1: Real,
    dt: Real,
    restitution_threshold: Real,
    candidate_ids: &[u32],
    candidates: &[Candidate<'_>],
    motions: &[BodyMotion],
    bodies: &RigidBodySet,
) -> Option<Contact> {
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
                let rel = v_before - cand.point_velocity(start, s1, dt, motions, bodies);
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

/// Velocity rapier's step adds to a dynamic body: gravity and user forces (torques are left
/// out), none while it sleeps.
pub(crate) fn rapier_drift(body: &RigidBody, gravity: Vector, dt: Real) -> Vector {
    if !body.is_dynamic() || body.is_sleeping() {
        return Vector::ZERO;
    }
    let props = body.mass_properties();
    (gravity * body.gravity_scale() * props.effective_mass() + body.user_force())
        * props.effective_inv_mass
        * dt
}

/// Makes rapier's step move a dynamic body that took contact impulses as the contacts
/// predicted: with its velocity plus the whole [`rapier_drift`] over the step.
///
/// Rapier integrates in `N` substeps, so a body gains `drift` of velocity but moves only
/// `(N + 1)/(2N) · drift · dt` of it. The contacts that just held a resting body set its
/// velocity to `−drift`, for it to end the step at rest where it is; rapier would lift it by
/// the difference and leave it at rest there, to fall back the next step, and so on (a resting
/// body kept reporting a downward velocity of about `(N − 1)/(2N) · g dt`). The body is moved
/// back by that difference beforehand.
pub(crate) fn match_rapier_integration(
    body: &mut RigidBody,
    gravity: Vector,
    dt: Real,
    solver_iterations: usize,
) {
    let n = (solver_iterations + body.additional_solver_iterations()).max(1) as Real;
    let lag = rapier_drift(body, gravity, dt) * (dt * (n - 1.0) / (2.0 * n));
    if lag != Vector::ZERO {
        let t = body.translation();
        body.set_translation(t + lag, false);
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

/// Tests the features of the facet's candidates against the facet (nodes `facet`, inverse
/// masses `inv_masses`), which moves from `x` (substep start) to `y` (predicted end), both
/// outward oriented. A feature counts only if it crosses the facet's plane during the substep
/// (outside at the start, within a sliver of tolerance, and behind it at the end) inside the
/// facet's prism (a round feature: see [`separation`]): a feature deep behind one facet belongs
/// to another. Returns the deepest crossing, as a contact whose target puts the facet on the
/// feature at the end of the substep.
#[allow(clippy::too_many_arguments)]
pub(crate) fn resolve_facet(
    facet: &[u32; FACET_ARITY],
    x: &[Vector; FACET_ARITY],
    y: &[Vector; FACET_ARITY],
    inv_masses: &[Real; FACET_ARITY],
    h: Real,
    s1: Real,
    dt: Real,
    candidate_ids: &[u32],
    candidates: &[Candidate<'_>],
    motions: &[BodyMotion],
    bodies: &RigidBodySet,
) -> Option<Contact> {
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
    let tolerance = 1e-3 * size;
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
            if d0 < -tolerance {
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
        normal_impulse: 0.0,
        friction_impulse: Vector::ZERO,
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
