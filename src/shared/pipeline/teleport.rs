//! Bones that jump (issue 15): a bone teleported, respawned, or given a kinematic target far
//! away asks its bound nodes to cover in one step what no tissue can follow. Stretched that far,
//! a body ground at the substep cap step after step (explicit, a 10 m jump at 60 Hz: 19 999
//! substeps a step, cells inverted) or turned cells inside out (implicit). Such a body is
//! carried along instead: when a bound node would have to move faster than
//! [`PipelineSettings::teleport_speed`](super::PipelineSettings::teleport_speed), the whole
//! body moves by the rigid motion that best takes its bound nodes to where their bones end
//! the step, velocities turned with it, and the bones are taken to be there for the whole step.
//! The report's [`teleported`](super::super::DeformableReport::teleported) says so.

use super::super::body::Deformable;
use super::super::coupling::MotionKind;
use super::super::math::{self, Matrix, Real, Rotation, Vector, DIM};
use super::super::rapier::dynamics::RigidBodySet;
use super::{BoneDrive, Broad, StepContext};

/// Carries `body` with its bones if they jumped (see the module docs); returns whether it did.
pub(super) fn carry_if_jumped(
    body: &mut Deformable,
    ctx: &StepContext<'_>,
    bodies: &RigidBodySet,
    (bones, broad): (&BoneDrive, &mut Broad),
) -> bool {
    let dt = ctx.dt;
    let reach = ctx.settings.teleport_speed * dt;
    if !(reach.is_finite() && reach > 0.0) {
        return false;
    }
    // Where each node bound to a fixed or kinematic bone is, and where its bone ends the step.
    // (A node bound to a dynamic body follows it at the velocity level, centimetres behind.)
    let x = &body.state.positions;
    let mut pairs: Vec<(Vector, Vector)> = Vec::new();
    for (k, a) in body.bindings.list().iter().enumerate() {
        let Some(m) = bones.attachment_motion[k] else {
            continue;
        };
        if broad.motions[m].kind == MotionKind::Dynamic {
            continue;
        }
        let end = broad.motions[m]
            .pose_at(1.0, dt, bodies)
            .transform_point(a.anchor);
        pairs.push((x[a.node as usize], end));
    }
    let jump = pairs
        .iter()
        .map(|(from, to)| from.distance(*to))
        .fold(0.0, Real::max);
    if pairs.is_empty() || jump <= reach {
        return false;
    }
    let (rotation, from, to) = rigid_fit(&pairs);
    let state = &mut body.state;
    for p in &mut state.positions {
        *p = to + rotation * (*p - from);
    }
    for v in &mut state.velocities {
        *v = rotation * *v;
    }
    let turned: Vec<Rotation> = state
        .elements
        .warm_start()
        .iter()
        .map(|q| rotation * *q)
        .collect();
    // The warm starts have the body's own length: this cannot fail.
    let _ = state.elements.set_warm_start(&turned);
    body.step.invalidate_forces();
    // The bound nodes stay on their bones where the bones end: no drag back along the jump.
    for m in bones.attachment_motion.iter().flatten() {
        let motion = &mut broad.motions[*m];
        if motion.kind != MotionKind::Dynamic {
            motion.pose0 = motion.pose1;
        }
    }
    true
}

/// The rotation and the two centroids of the rigid motion `x ↦ to + R (x − from)` that best
/// takes the first points of `pairs` to the second (least squares; a translation alone for
/// fewer than `DIM` points).
fn rigid_fit(pairs: &[(Vector, Vector)]) -> (Rotation, Vector, Vector) {
    let n = pairs.len() as Real;
    let from = pairs.iter().map(|p| p.0).sum::<Vector>() / n;
    let to = pairs.iter().map(|p| p.1).sum::<Vector>() / n;
    if pairs.len() < DIM {
        return (Rotation::IDENTITY, from, to);
    }
    let mut a = Matrix::ZERO;
    for (f, t) in pairs {
        a += math::outer(*t - to, *f - from);
    }
    (math::polar_rotation(a), from, to)
}
