//! Impacts under [`Integrator::Midpoint`]: a body closing fast on a collider takes its steps in
//! explicit substeps until the impact is over.
//!
//! A soft body's bounce is its compression given back within the contact, a few milliseconds
//! for a small or stiff body: one implicit step of a 60 Hz frame cannot resolve it. Backward
//! Euler removes it (a ball thrown at a wall stuck to it), and the midpoint rule, whose contacts
//! stop every node that the step's prediction carries past the collider, loses most of it: the
//! 10 cm ball of `tests/shared/impact.rs` (E = 10⁵ Pa) thrown at 5 m/s left at 0.02–0.17 of its
//! speed in one 60 Hz step, and came within 10 % of the 1 ms explicit run only with 32–64
//! midpoint substeps a frame (0.26–0.5 ms, 64 for E = 10⁶), about the explicit step's own
//! substep. So the impact takes the explicit step, whose rebound is the reference, and the
//! flight before and after it the midpoint step.
//!
//! A body is in an impact from the step that starts with
//! - its centre of mass closing on a candidate collider faster than the threshold,
//!   [`PipelineSettings::restitution_threshold`] plus twice what gravity adds in a step, to
//!   the body and to a dynamic collider (a body resting on a floor, or a box resting on it,
//!   closes by `g h` each step, which the contact takes back), the closing measured along the
//!   line from the collider's point nearest to the centre of mass (a tumbling body whose
//!   corner strikes while its centre hardly closes is not in an impact), and
//! - a boundary node that does not touch the collider yet, closing on it faster than the
//!   threshold and near enough to meet it within the step ([`strikes`]),
//! - under gravity, both faster than a strike that could throw the body up by a
//!   [`LIFT_SHARE`] of its size: a slower one's rebound is below what the fall trial measures,
//!   and the implicit step takes it (on the res-9 `fall` cube, which rocks on its edges for
//!   seconds, most strikes were such). A strike gives back at most its closing speed; a body
//!   still bouncing off its last impact (striking at most [`REBOUND_SPAN`] times faster than
//!   it came off it) gives back at most the share of it that impact did ([`Rebound`]). The
//!   res-9 `fall` cube comes off its first three impacts at 0.68–0.71 of the speed it struck
//!   at, and its fourth strike, at 1.2–1.3 m/s, would lift it by 4.5 % of its size at most: the
//!   implicit step takes it, where without the rebound it took five of the run's twelve
//!   explicit steps.
//!
//! So a body's flight up to the step of the contact is the midpoint step's, and a body
//! pivoting on an edge that touches (its centre closing, the nodes about the edge hardly
//! moving) is not in an impact until its face comes down. It stays in it while closing or
//! while it touches a collider (in any substep of the last step) until its centre recedes with
//! every boundary node clear of the colliders (farther than the threshold takes a node in a
//! step; a ringing node that strikes again starts a new impact), and for at most
//! the time the bar wave `√(E/ρ)` takes across the body and back, plus a step, after the last
//! step that began with a strike (its compression given back; [`SETTLE`] at most). A body
//! bound to a bone, in an island with other deformables or with self contact on, stepped with
//! [`PipelineSettings::fixed_substeps`], or whose explicit step would take more than
//! [`MAX_SUBSTEPS`] substeps a step (or `max_substeps`) keeps the implicit step.
//!
//! [`PipelineSettings::restitution_threshold`]: super::PipelineSettings::restitution_threshold
//! [`PipelineSettings::fixed_substeps`]: super::PipelineSettings::fixed_substeps
//! [`Integrator::Midpoint`]: super::super::Integrator::Midpoint

use super::super::contact::Candidate;
use super::super::coupling::BodyMotion;
use super::super::integrator::Rebound;
use super::super::material::Material;
use super::super::math::{Real, Vector};
use super::super::rapier::dynamics::RigidBodySet;
use super::substep::Member;
use super::StepContext;

/// How long a body stays in its impact after the last step that began with a strike, at most
/// (s): the rebound of a body that lands and stays is over by then.
pub(crate) const SETTLE: Real = 0.1;

/// A strike is taken explicitly only if it is fast enough to throw the body up by this share
/// of its size (`√(2 g · share · size)`): slower, its rebound is below what the fall trial
/// measures (its error bound is a tenth of the size), and the implicit step takes it.
const LIFT_SHARE: Real = 0.05;

/// How much faster than it came off its last impact a body may strike for that impact's
/// rebound to bound the strike's ([`lift_ratio`]): a bounce returns at the speed it left at,
/// plus what gravity adds over a step's rounding of the flight.
const REBOUND_SPAN: Real = 1.25;

/// The least rebound share a strike is taken to have, against a division by zero.
const MIN_RATIO: Real = 1e-3;

/// A node nearer a collider than this share of what it may close on it in a step touches it
/// already (contacts leave nodes on the surface).
const TOUCHING: Real = 1e-3;

/// Most explicit substeps a step may take for an impact: a body stiffer than that for its
/// mass and the step (the 10 cm silicone ball of `scenes ball`, E = 10⁶ Pa, takes 260 at
/// 60 Hz) keeps the implicit step through it.
pub(crate) const MAX_SUBSTEPS: usize = 1000;

/// Whether `members` (a group that neither touches itself nor shares a pushed body) take this
/// step explicitly because one of them is in an impact; updates each member's impact state.
pub(super) fn any(
    members: &mut [Member<'_, '_>],
    ctx: &StepContext<'_>,
    bodies: &RigidBodySet,
) -> bool {
    let settings = &ctx.settings;
    let on = settings.integrator.midpoint_rule() && settings.fixed_substeps.is_none();
    let most = MAX_SUBSTEPS.min(settings.max_substeps) as Real;
    let mut any = false;
    for m in members.iter_mut() {
        let implicit = settings.integrator.steps_implicitly(m.body);
        if !on || !implicit || !m.live || m.body.bindings.len() > 0 {
            leave(m);
            continue;
        }
        let g = ctx.gravity * m.body.gravity_scale;
        let (closing, pull) = closing_speed(m, ctx, bodies);
        let threshold = settings.restitution_threshold + 2.0 * (g.length() * ctx.dt + pull);
        let touching = !m.body.last.touching.is_empty();
        let state = &m.body.step.midpoint;
        let (left, too_stiff, mut rebound) = (state.impact, state.too_stiff, state.rebound);
        if left > 0.0 && closing < 0.0 && closing.is_finite() {
            rebound.recede = rebound.recede.max(-closing);
        }
        let mut refused = false;
        let size = extent(m.body.positions());
        // A strike that could not lift the body a [`LIFT_SHARE`] of its size is left to the
        // implicit step.
        let lift = (2.0 * g.length() * LIFT_SHARE * size).sqrt() / lift_ratio(&rebound, closing);
        let strikes_at = threshold.max(lift);
        // A body closing fast flies by the midpoint step up to the step in which a node may
        // strike the collider.
        let strike = closing > strikes_at && !too_stiff && strikes(m, ctx, bodies, strikes_at);
        let settle = settle_time(&m.body.rest.params.material, size, ctx.dt);
        let left = if strike && left <= 0.0 {
            // Whether the explicit step is affordable is asked once, as an impact starts.
            let substep = m.body.substep(settings.safety, false);
            refused = ctx.dt > substep * most;
            if refused {
                0.0
            } else {
                rebound.entry = closing;
                rebound.recede = 0.0;
                settle
            }
        } else if strike {
            settle
        } else if left > 0.0
            && (closing > threshold
                || (touching && !(closing < 0.0 && separated(m, ctx, bodies, threshold))))
        {
            (left - ctx.dt).max(0.0)
        } else {
            0.0
        };
        if state.impact > 0.0 && left <= 0.0 && rebound.entry > 0.0 {
            rebound.out = rebound.recede;
            rebound.ratio = (rebound.recede / rebound.entry).clamp(0.0, 1.0);
            rebound.entry = 0.0;
        }
        let state = &mut m.body.step.midpoint;
        state.rebound = rebound;
        state.impact = left;
        state.too_stiff = (too_stiff || refused) && closing > threshold;
        any |= left > 0.0;
    }
    any
}

/// The share of a strike's closing speed its rebound may give back: the last impact's, for a
/// strike no faster than [`REBOUND_SPAN`] times what the body came off it at (it is still
/// bouncing off it), 1 for any other (a body thrown, pushed or fallen farther since). The
/// share is taken as the last impact's though a damped body gives back somewhat more of a
/// slower strike: the lift that decides ([`LIFT_SHARE`] of the size) is half the fall trial's
/// error bound.
fn lift_ratio(rebound: &Rebound, closing: Real) -> Real {
    if rebound.entry <= 0.0 && closing <= REBOUND_SPAN * rebound.out {
        rebound.ratio.max(MIN_RATIO)
    } else {
        1.0
    }
}

/// Ends the impact of each of `members`, for a step [`any`] does not decide (a group whose
/// members may touch each other or share a pushed body).
pub(super) fn end(members: &mut [Member<'_, '_>]) {
    for m in members.iter_mut() {
        leave(m);
    }
}

fn leave(m: &mut Member<'_, '_>) {
    let state = &mut m.body.step.midpoint;
    state.impact = 0.0;
    state.too_stiff = false;
}

/// The fastest a member's centre of mass closes on one of its candidate colliders, along the
/// line from the collider's point nearest to it (`-∞` without candidates), and the speed
/// gravity and user forces add to that collider's body along that line in a step.
fn closing_speed(m: &Member<'_, '_>, ctx: &StepContext<'_>, bodies: &RigidBodySet) -> (Real, Real) {
    let centre = m.body.center_of_mass();
    let velocity = m.body.center_of_mass_velocity();
    let motions = &m.sc.broad.motions;
    let (mut fastest, mut pull) = (Real::NEG_INFINITY, 0.0);
    for cand in &m.candidates {
        let Some((_, normal, closing)) =
            approach(cand, (centre, velocity), ctx.dt, motions, bodies)
        else {
            continue;
        };
        if closing > fastest {
            fastest = closing;
            pull = cand.drift.dot(normal).abs();
        }
    }
    (fastest, pull)
}

/// Whether a boundary node of `m` not yet touching one of its candidate colliders closes on it
/// faster than `threshold` and may meet it within the step: it is within what it closes on the
/// collider in the step (its own speed towards the nearest point, plus what gravity and the
/// collider's body's drift add), with a tenth more for the speed the step's forces add. A body
/// pivoting on a corner or an edge (its centre closing while the nodes about the pivot hardly
/// move) strikes only when another part of it comes down.
fn strikes(
    m: &Member<'_, '_>,
    ctx: &StepContext<'_>,
    bodies: &RigidBodySet,
    threshold: Real,
) -> bool {
    let g = (ctx.gravity * m.body.gravity_scale).length();
    let dt = ctx.dt;
    node_approaches(m, dt, bodies).any(|(cand, approach)| {
        let Some((distance, _, closing)) = approach else {
            return false;
        };
        let reach = 1.1 * (closing.max(0.0) + (g + cand.drift.length()) * dt) * dt;
        closing > threshold && distance > TOUCHING * reach && distance <= reach
    })
}

/// Each candidate collider of `m` with each boundary node's [`approach`] to it (candidates
/// outermost).
fn node_approaches<'m>(
    m: &'m Member<'_, '_>,
    dt: Real,
    bodies: &'m RigidBodySet,
) -> impl Iterator<Item = (&'m Candidate<'m>, Option<(Real, Vector, Real)>)> + 'm {
    let motions = &m.sc.broad.motions;
    let (x, v) = (m.body.positions(), m.body.velocities());
    let nodes = m.body.rest.mesh.boundary_nodes();
    m.candidates.iter().flat_map(move |cand| {
        nodes.iter().map(move |&i| {
            let (p, u) = (x[i as usize], v[i as usize]);
            (cand, approach(cand, (p, u), dt, motions, bodies))
        })
    })
}

/// The largest side of the box around `x`.
fn extent(x: &[Vector]) -> Real {
    let Some(first) = x.first() else {
        return 0.0;
    };
    let (lo, hi) = x
        .iter()
        .fold((*first, *first), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    (hi - lo).max_element()
}

/// How long an impact lasts after a strike: a step more than the bar wave `√(E/ρ)` of
/// `material` takes across a body of `size` and back, the time its compression takes to be
/// given back; at most [`SETTLE`].
fn settle_time(material: &Material, size: Real, dt: Real) -> Real {
    let wave = (material.young_modulus / material.density).sqrt();
    if wave > 0.0 && wave.is_finite() {
        (2.0 * size / wave + dt).min(SETTLE)
    } else {
        SETTLE
    }
}

/// Whether every boundary node of `m` is farther from each candidate collider than a node at
/// `threshold` goes in a step: the body has left them.
fn separated(
    m: &Member<'_, '_>,
    ctx: &StepContext<'_>,
    bodies: &RigidBodySet,
    threshold: Real,
) -> bool {
    let dt = ctx.dt;
    node_approaches(m, dt, bodies)
        .all(|(_, approach)| approach.is_some_and(|(d, _, _)| d > threshold * dt))
}

/// How a point at `p` moving at `u` approaches `cand`: its distance from the collider, the
/// outward normal there and its speed toward it (`None` inside the collider or on it).
fn approach(
    cand: &Candidate<'_>,
    (p, u): (Vector, Vector),
    dt: Real,
    motions: &[BodyMotion],
    bodies: &RigidBodySet,
) -> Option<(Real, Vector, Real)> {
    let proj = cand.collider.shape().project_point(&cand.pose, p, true);
    let away = p - proj.point;
    let distance = away.length();
    if proj.is_inside || distance <= 0.0 || distance.is_nan() {
        return None;
    }
    let normal = away / distance;
    let wall = cand.point_velocity(proj.point, 0.0, dt, motions, bodies);
    Some((distance, normal, -(u - wall).dot(normal)))
}
