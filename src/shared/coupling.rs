//! The boundary with rapier: every read and write of rapier's rigid-body state that the
//! deformables make lives here (`docs/ARCHITECTURE.md` §5).
//!
//! * **Reading motion.** [`BodyMotion`]: how a rigid body moves over the step — fixed bodies
//!   stay put, position-based kinematic bodies go from `position()` to `next_position()`,
//!   velocity-based ones and dynamic ones are predicted from their velocity, dynamic ones plus
//!   [`rapier_drift`], what rapier's own step will add to their velocity, taken up evenly over
//!   the step.
//! * **Writing impulses.** [`apply_impulse`]: a contact or a two-way binding changes a dynamic
//!   body's velocity at once, at a point; a contact's impulse keeps the path the body has
//!   already travelled in the step (the deformables' substeps integrate it as they do their
//!   nodes). [`inv_mass_at`] is the body's side of every impulse's effective mass.
//! * **Compensating rapier's integration.** [`match_rapier_integration`]: rapier's step, which
//!   adds the drift at once and moves a body by `(N + 1)/(2N)` of it over its `N` substeps, is
//!   made to end where the deformables' substeps left a body they pushed.
//! * **Backup and restore.** [`RigidBackup`]: the dynamic bodies a deformable may push, as they
//!   were before its step, put back when the step is rolled back.
//!
//! The unit tests below pin down what these rely on in rapier's integrator: if rapier changes
//! how it integrates, they fail.

use super::math::{self, AngVector, Pose, Real, Vector, TWIST_DIM};
use super::rapier::dynamics::{
    RigidBody, RigidBodyHandle, RigidBodySet, RigidBodyType, RigidBodyVelocity,
};
use super::rapier::geometry::ColliderSet;

/// Where in the step a substep is: its length `h`, the time `t` since the step began at its
/// start and the fraction `s1` of the step at its end, the step `dt`, the restitution
/// threshold of its contacts, and how every relevant rigid body moves over the step.
#[derive(Copy, Clone, Debug)]
pub(crate) struct Substep<'a> {
    pub h: Real,
    pub t: Real,
    pub s1: Real,
    pub dt: Real,
    pub restitution_threshold: Real,
    /// How far off a two-sided surface (an open trimesh, a heightfield) nodes are kept.
    pub skin: Real,
    pub motions: &'a [BodyMotion],
}

/// How a rigid body moves over the step, by its type.
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

/// Velocity rapier's step adds to a dynamic body: gravity and user forces (torques are left
/// out). A sleeping body counts it too: a contact that pushes it wakes it.
pub(crate) fn rapier_drift(body: &RigidBody, gravity: Vector, dt: Real) -> Vector {
    if !body.is_dynamic() {
        return Vector::ZERO;
    }
    let props = body.mass_properties();
    (gravity * body.gravity_scale() * props.effective_mass() + body.user_force())
        * props.effective_inv_mass
        * dt
}

/// Makes rapier's step end a dynamic body that took contact impulses where the deformables'
/// substeps left it.
///
/// Over the step the substeps moved it with its velocity `v` (what rapier now holds) plus the
/// drift taken up evenly: `v·dt + drift·dt/2` from its start pose. Rapier integrates in `N`
/// substeps, adding the drift at once and moving it `v·dt + (N + 1)/(2N) · drift · dt`. The body
/// is moved back by the difference, `drift·dt/(2N)`, beforehand; its velocity after rapier's
/// step, `v + drift`, is the one the substeps ended with. (Without it, a box held at rest by
/// soft pads rose `g dt²/(2N)` a step and fell back.)
pub(crate) fn match_rapier_integration(
    body: &mut RigidBody,
    gravity: Vector,
    dt: Real,
    solver_iterations: usize,
) {
    let n = (solver_iterations + body.additional_solver_iterations()).max(1) as Real;
    let lag = rapier_drift(body, gravity, dt) * (-dt / (2.0 * n));
    if lag != Vector::ZERO {
        let t = body.translation();
        body.set_translation(t + lag, false);
    }
}

/// Inverse mass of the dynamic body `body` felt by an impulse along `dir` (unit) at `point`:
/// `dirᵀ M⁻¹ dir + (r × dir)ᵀ I⁻¹ (r × dir)`, with rapier's effective (lock-aware) values.
pub(crate) fn inv_mass_at(body: &RigidBody, point: Vector, dir: Vector) -> Real {
    let props = body.mass_properties();
    let rn = math::cross(point - body.center_of_mass(), dir);
    (props.effective_inv_mass * dir).dot(dir)
        + math::ang_dot(rn, props.effective_world_inv_inertia * rn)
}

/// The velocity change `(Δv, Δω)` that `impulse` at `point` gives `body`, with rapier's
/// effective (lock-aware) mass and inertia: what [`apply_impulse`] adds.
pub(crate) fn impulse_response(
    body: &RigidBody,
    point: Vector,
    impulse: Vector,
) -> (Vector, AngVector) {
    let props = body.mass_properties();
    let torque = math::cross(point - body.center_of_mass(), impulse);
    (
        props.effective_inv_mass * impulse,
        props.effective_world_inv_inertia * torque,
    )
}

/// Gives `body` `impulse` at `point`: its velocity changes at once, and its pose is moved back
/// by the velocity change over `elapsed` (the time of the step already gone), so that where it
/// is now stays put (see [`Candidate::apply_impulse`](super::contact::Candidate::apply_impulse)).
pub(crate) fn apply_impulse(body: &mut RigidBody, impulse: Vector, point: Vector, elapsed: Real) {
    let (v0, w0) = (body.linvel(), body.angvel());
    // A strong wake-up, as rapier's contacts keep the bodies of an awake island awake: a body
    // touching an awake deformable does not fall asleep on its own; it sleeps with the
    // deformable (`pipeline/sleep.rs`).
    body.apply_impulse_at_point(impulse, point, true);
    if elapsed > 0.0 {
        let change = RigidBodyVelocity::new(body.linvel() - v0, body.angvel() - w0);
        let pose = change.integrate(-elapsed, body.position(), &body.local_center_of_mass());
        body.set_position(pose, false);
    }
}

/// Moves `body` by `delta` without touching its velocity (its pose at the start of the step, so
/// its path through the step moves with it): a body rapier's step carried into a deformable,
/// moved back out by its share.
pub(crate) fn translate(body: &mut RigidBody, delta: Vector) {
    let mut pose = *body.position();
    pose.translation += delta;
    body.set_position(pose, false);
}

/// Whether a rigid body moves this step: a dynamic body that is awake, a kinematic body with
/// a next pose or a velocity.
pub(crate) fn is_moving(body: &RigidBody) -> bool {
    match body.body_type() {
        RigidBodyType::Fixed => false,
        RigidBodyType::KinematicPositionBased => {
            let (p0, p1) = (body.position(), body.next_position());
            p0.translation != p1.translation || p0.rotation != p1.rotation
        }
        RigidBodyType::KinematicVelocityBased => {
            body.linvel() != Vector::ZERO || math::ang_norm(body.angvel()) != 0.0
        }
        _ => !body.is_sleeping(),
    }
}

/// Whether a rigid body keeps a deformable near it awake: a moving kinematic body, or a
/// dynamic one that will leave rapier's step faster than rapier lets a body fall asleep at (its
/// activation's linear and angular thresholds; the velocity counted is the present one plus
/// [`rapier_drift`]: a body the contacts hold at rest has `−drift` until rapier's step). A
/// slow dynamic body resting on a deformable sleeps with it.
pub(crate) fn is_restless(body: &RigidBody, gravity: Vector, dt: Real) -> bool {
    if !body.is_dynamic() {
        return is_moving(body);
    }
    if body.is_sleeping() {
        return false;
    }
    let a = body.activation();
    (body.linvel() + rapier_drift(body, gravity, dt)).length() > a.normalized_linear_threshold
        || math::ang_norm(body.angvel()) > a.angular_threshold
}

/// How far any collider attached to a moving body may travel in `dt` (a margin for broad-phase
/// boxes, which rapier stores at the bodies' current poses).
pub(crate) fn moving_margin(bodies: &RigidBodySet, colliders: &ColliderSet, dt: Real) -> Real {
    let mut margin: Real = 0.0;
    for (_, co) in colliders.iter() {
        let Some(body) = co.parent().and_then(|p| bodies.get(p)) else {
            continue;
        };
        if body.is_fixed() {
            continue;
        }
        let radius = co.compute_aabb().half_extents().length()
            + (co.position().translation - body.center_of_mass()).length();
        let travel =
            if body.is_kinematic() && body.body_type() == RigidBodyType::KinematicPositionBased {
                let m = BodyMotion::new(RigidBodyHandle::invalid(), body, dt);
                m.travel(radius)
            } else {
                (body.linvel().length() + math::ang_norm(body.angvel()) * radius) * dt
            };
        margin = margin.max(travel);
    }
    margin
}

/// The dynamic bodies a deformable may push in its step, as they were before it: handle, pose,
/// linear and angular velocity.
#[derive(Clone, Debug, Default)]
pub(crate) struct RigidBackup(Vec<(RigidBodyHandle, Pose, Vector, AngVector)>);

impl RigidBackup {
    /// Saves the dynamic bodies among `motions`.
    pub fn save(&mut self, motions: &[BodyMotion], bodies: &RigidBodySet) {
        self.0.clear();
        for m in motions.iter().filter(|m| m.kind == MotionKind::Dynamic) {
            if let Some(rb) = bodies.get(m.handle) {
                self.0
                    .push((m.handle, *rb.position(), rb.linvel(), rb.angvel()));
            }
        }
    }

    /// Puts every saved body back as it was (a blow-up must not launch them).
    pub fn restore(&self, bodies: &mut RigidBodySet) {
        for (h, pose, linvel, angvel) in &self.0 {
            if let Some(rb) = bodies.get_mut(*h) {
                rb.set_position(*pose, false);
                rb.set_linvel(*linvel, false);
                rb.set_angvel(*angvel, false);
            }
        }
    }
}

/// Solves `A x = b` (`a` by columns) by Gaussian elimination with partial pivoting; `None` if
/// `A` is singular.
pub(crate) fn solve_dense(
    a: [[Real; TWIST_DIM]; TWIST_DIM],
    b: [Real; TWIST_DIM],
) -> Option<[Real; TWIST_DIM]> {
    // Row-major copy with the right-hand side appended.
    let mut m = [[0.0; TWIST_DIM + 1]; TWIST_DIM];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, col) in a.iter().enumerate() {
            row[j] = col[i];
        }
        row[TWIST_DIM] = b[i];
    }
    for k in 0..TWIST_DIM {
        let pivot = (k..TWIST_DIM).max_by(|&i, &j| m[i][k].abs().total_cmp(&m[j][k].abs()))?;
        if m[pivot][k].abs() < 1e-12 {
            return None;
        }
        m.swap(k, pivot);
        let pivot_row = m[k];
        for row in m.iter_mut().skip(k + 1) {
            let f = row[k] / pivot_row[k];
            for (x, p) in row.iter_mut().zip(pivot_row).skip(k) {
                *x -= f * p;
            }
        }
    }
    let mut x = [0.0; TWIST_DIM];
    for k in (0..TWIST_DIM).rev() {
        let tail: Real = (k + 1..TWIST_DIM).map(|j| m[k][j] * x[j]).sum();
        x[k] = (m[k][TWIST_DIM] - tail) / m[k][k];
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    //! What the coupling relies on in rapier's integrator, checked against rapier itself.

    use super::super::math::{Real, Vector, UP};
    use super::super::rapier::dynamics::RigidBodyBuilder;
    use super::super::rapier::geometry::ColliderBuilder;
    use super::super::rapier::pipeline::PhysicsWorld;
    use super::*;

    #[test]
    fn the_dense_solve_answers_a_system_that_needs_pivoting() {
        // A zero on the diagonal: elimination without row swaps would divide by it.
        let mut a = [[0.0; TWIST_DIM]; TWIST_DIM];
        for (c, col) in a.iter_mut().enumerate() {
            for (r, x) in col.iter_mut().enumerate() {
                *x = if r == c {
                    (r % 2) as Real * 3.0
                } else {
                    1.0 / (1 + r + c) as Real
                };
            }
        }
        let x: [Real; TWIST_DIM] = std::array::from_fn(|k| k as Real - 1.5);
        let b: [Real; TWIST_DIM] =
            std::array::from_fn(|r| (0..TWIST_DIM).map(|c| a[c][r] * x[c]).sum());
        let solved = solve_dense(a, b).unwrap();
        for k in 0..TWIST_DIM {
            assert!(
                (solved[k] - x[k]).abs() < 1e-3,
                "{k}: {} for {}",
                solved[k],
                x[k]
            );
        }
        assert!(solve_dense([[0.0; TWIST_DIM]; TWIST_DIM], b).is_none());
    }

    /// A world without ground holding one dynamic ball thrown sideways with a user force.
    fn thrown() -> (PhysicsWorld, RigidBodyHandle) {
        let mut world = PhysicsWorld::new();
        world.integration_parameters.dt = 1.0 / 60.0;
        let mut side = Vector::ZERO;
        side[0] = 1.5;
        let (h, _) = world.insert(
            RigidBodyBuilder::dynamic()
                .translation(UP * 2.0)
                .linvel(side)
                .can_sleep(false),
            ColliderBuilder::ball(0.2).density(500.0),
        );
        world.bodies[h].add_force(side * 3.0, true);
        (world, h)
    }

    fn close(a: Vector, b: Vector, tolerance: Real) -> bool {
        (a - b).length() <= tolerance * (1.0 + b.length())
    }

    #[test]
    fn rapier_drift_is_the_velocity_rapier_adds_in_its_step() {
        let (mut world, h) = thrown();
        let dt = world.integration_parameters.dt;
        let before = world.bodies[h].linvel();
        let drift = rapier_drift(&world.bodies[h], world.gravity, dt);
        world.step();
        let gained = world.bodies[h].linvel() - before;
        assert!(
            close(gained, drift, 1e-5),
            "rapier added {gained:?}, the coupling predicts {drift:?}"
        );
    }

    #[test]
    fn after_the_compensation_rapier_moves_a_body_with_its_whole_new_velocity() {
        let (mut world, h) = thrown();
        let dt = world.integration_parameters.dt;
        let iterations = world.integration_parameters.num_solver_iterations;
        let start = world.bodies[h].translation();
        let v = world.bodies[h].linvel();
        let drift = rapier_drift(&world.bodies[h], world.gravity, dt);
        match_rapier_integration(&mut world.bodies[h], world.gravity, dt, iterations);
        world.step();
        let moved = world.bodies[h].translation() - start;
        let predicted = (v + drift * 0.5) * dt;
        assert!(
            close(moved, predicted, 1e-5),
            "rapier moved the body {moved:?}, the contacts predict {predicted:?}"
        );
        // Without the compensation it would not: the test can fail.
        let (mut plain, h) = thrown();
        let start = plain.bodies[h].translation();
        plain.step();
        let moved = plain.bodies[h].translation() - start;
        assert!(
            !close(moved, predicted, 1e-5),
            "rapier's substeps lag: {moved:?}"
        );
    }

    #[test]
    fn a_dynamic_body_is_predicted_where_rapier_puts_it_without_forces() {
        let (mut world, h) = thrown();
        world.gravity = Vector::ZERO;
        world.bodies[h].reset_forces(true);
        world.bodies[h].set_angvel(math::planar_angle(2.0), true);
        let dt = world.integration_parameters.dt;
        let motion = BodyMotion::new(h, &world.bodies[h], dt);
        world.step();
        let at = *world.bodies[h].position();
        assert!(close(motion.pose1.translation, at.translation, 1e-5));
        assert!(math::rotation_angle_between(motion.pose1.rotation, at.rotation) < 1e-5);
    }

    #[test]
    fn a_kinematic_body_ends_the_step_at_its_next_position() {
        let mut world = PhysicsWorld::new();
        let h = world.insert_body(RigidBodyBuilder::kinematic_position_based());
        let target = Pose::from_translation(UP * 0.3);
        world.bodies[h].set_next_kinematic_position(target);
        let motion = BodyMotion::new(h, &world.bodies[h], world.integration_parameters.dt);
        assert!(is_moving(&world.bodies[h]));
        world.step();
        let end = motion.pose_at(1.0, world.integration_parameters.dt, &world.bodies);
        assert_eq!(end.translation, world.bodies[h].translation());
    }

    #[test]
    fn an_impulse_keeps_the_path_already_travelled() {
        let (mut world, h) = thrown();
        let rb = &mut world.bodies[h];
        let before = *rb.position();
        let point = rb.center_of_mass();
        let mut push = Vector::ZERO;
        push[0] = 0.4;
        apply_impulse(rb, push, point, 0.01);
        let dv = push * rb.mass_properties().effective_inv_mass;
        // The pose moved back by the velocity change over the elapsed time.
        assert!(close(
            rb.translation(),
            before.translation - dv * 0.01,
            1e-6
        ));
        let (mut world, h) = thrown();
        let rb = &mut world.bodies[h];
        let point = rb.center_of_mass();
        apply_impulse(rb, push, point, 0.0);
        assert_eq!(rb.translation(), before.translation);
    }

    #[test]
    fn a_backup_restores_pose_and_velocities() {
        let (mut world, h) = thrown();
        let motions = [BodyMotion::new(h, &world.bodies[h], 0.01)];
        let mut backup = RigidBackup::default();
        backup.save(&motions, &world.bodies);
        let (pose, v) = (*world.bodies[h].position(), world.bodies[h].linvel());
        world.step();
        assert_ne!(world.bodies[h].translation(), pose.translation);
        backup.restore(&mut world.bodies);
        assert_eq!(*world.bodies[h].position(), pose);
        assert_eq!(world.bodies[h].linvel(), v);
    }
}
