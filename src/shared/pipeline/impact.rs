//! Impacts under [`Integrator::Midpoint`]: a body closing fast on a collider takes its steps in
//! explicit substeps until the impact is over.
//!
//! A soft body's bounce is its compression given back within the contact, a few milliseconds
//! for a small or stiff body: one implicit step of a 60 Hz frame cannot resolve it. Backward
//! Euler removes it (a ball thrown at a wall stuck to it), and the midpoint rule, whose contacts
//! stop every node that the step's prediction carries past the collider, loses most of it: the
//! 10 cm ball of issue 28 (E = 10⁵ Pa) thrown at 5 m/s left at 0.02–0.17 of its speed in one
//! 60 Hz step, and came within 10 % of the 1 ms explicit run only with 32–64 midpoint substeps
//! a frame (0.26–0.5 ms, 64 for E = 10⁶), about the explicit step's own substep. So the impact
//! takes the explicit step, whose rebound is the reference, and the flight before and after it
//! the midpoint step.
//!
//! A body is in an impact from the step that starts with its centre of mass closing on a
//! candidate collider faster than [`PipelineSettings::restitution_threshold`] plus twice what
//! gravity adds in a step (a body resting on a floor closes on it by `g h` each step, which its
//! contact takes back), the closing measured along the line from the collider's nearest point;
//! it stays in it while closing and, once that stops, while it still touches a collider, for
//! at most [`SETTLE`]. A body bound to a bone, in an island with other deformables, or whose
//! explicit step would take more than [`MAX_SUBSTEPS`] substeps a step, keeps the midpoint
//! step.
//!
//! [`PipelineSettings::restitution_threshold`]: super::PipelineSettings::restitution_threshold
//! [`Integrator::Midpoint`]: super::super::Integrator::Midpoint

use super::super::integrator::Integrator;
use super::super::math::Real;
use super::super::rapier::dynamics::RigidBodySet;
use super::substep::Member;
use super::StepContext;

/// How long a body that stopped closing on a collider but still touches one stays in its
/// impact (s): the rebound of a body that lands and stays is over by then.
pub(crate) const SETTLE: Real = 0.1;

/// Most explicit substeps a step may take for an impact: a body stiffer than that for its
/// mass and the step (the 10 cm silicone ball of `scenes ball`, E = 10⁶ Pa, takes 260 at
/// 60 Hz) keeps the midpoint step through it.
pub(crate) const MAX_SUBSTEPS: usize = 1000;

/// Whether `members` (a group that neither touches itself nor shares a pushed body) take this
/// step explicitly because one of them is in an impact; updates each member's impact state.
pub(super) fn any(
    members: &mut [Member<'_, '_>],
    ctx: &StepContext<'_>,
    bodies: &RigidBodySet,
) -> bool {
    if !matches!(ctx.settings.integrator, Integrator::Midpoint { .. }) {
        return false;
    }
    let mut any = false;
    for m in members.iter_mut() {
        let body = &*m.body;
        if !m.live || body.bindings.len() > 0 {
            continue;
        }
        let g = ctx.gravity * body.gravity_scale;
        let threshold = ctx.settings.restitution_threshold + 2.0 * g.length() * ctx.dt;
        let closing = closing_speed(m, ctx, bodies);
        let touching = !m.body.last.touching.is_empty();
        let left = m.body.step.midpoint.impact;
        // Whether the explicit step is affordable is asked once, as an impact starts.
        let affordable = || {
            let substep = ctx.settings.safety * m.body.stable_substep();
            ctx.dt <= substep * MAX_SUBSTEPS as Real
        };
        let left = if closing > threshold && (left > 0.0 || affordable()) {
            SETTLE
        } else if touching {
            (left - ctx.dt).max(0.0)
        } else {
            0.0
        };
        m.body.step.midpoint.impact = left;
        any |= left > 0.0;
    }
    any
}

/// The fastest a member's centre of mass closes on one of its candidate colliders, along the
/// line from the collider's point nearest to it (`-∞` without candidates).
fn closing_speed(m: &Member<'_, '_>, ctx: &StepContext<'_>, bodies: &RigidBodySet) -> Real {
    let centre = m.body.center_of_mass();
    let velocity = m.body.center_of_mass_velocity();
    let motions = &m.sc.broad.motions;
    let mut fastest = Real::NEG_INFINITY;
    for cand in &m.candidates {
        let proj = cand
            .collider
            .shape()
            .project_point(&cand.pose, centre, true);
        let away = centre - proj.point;
        let length = away.length();
        if proj.is_inside || length <= 0.0 || length.is_nan() {
            continue;
        }
        let normal = away / length;
        let wall = cand.point_velocity(proj.point, 0.0, ctx.dt, motions, bodies);
        fastest = fastest.max(-(velocity - wall).dot(normal));
    }
    fastest
}
