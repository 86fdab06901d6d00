//! Phases 1 and 6 of a body's step: waking a sleeping body when something disturbs it, and
//! putting a still one to sleep (rapier's thresholds: [`PipelineSettings`]'s `sleep_speed` and
//! `time_until_sleep`).
//!
//! [`PipelineSettings`]: super::PipelineSettings

use super::super::body::Deformable;
use super::super::contact;
use super::super::coupling::{is_moving, is_restless};
use super::super::math::{self, Vector};
use super::super::rapier::dynamics::{RigidBodyHandle, RigidBodySet};
use super::super::rapier::geometry::{Aabb, BoundingVolume};
use super::super::set::DeformableHandle;
use super::super::threads;
use super::substep::Member;
use super::{Broad, RigidHold, StepContext};

/// Wakes a sleeping body that something disturbs (or that may no longer sleep); returns
/// whether it is still asleep.
pub(super) fn stays_asleep(
    body: &mut Deformable,
    ctx: &StepContext<'_>,
    bodies: &RigidBodySet,
    broad: &mut Broad,
) -> bool {
    if body.activation.sleeping
        && (!body.activation.can_sleep || disturbed(body, ctx, bodies, broad))
    {
        body.wake_up();
    }
    body.activation.sleeping
}

/// The dynamic bodies a deformable touched or is bound to: those that sleep and wake with it,
/// as the bodies of one of rapier's islands do.
fn held_bodies(body: &Deformable, ctx: &StepContext<'_>, out: &mut Vec<RigidBodyHandle>) {
    body.bindings.bodies(out);
    for c in &body.last.touching {
        if let Some(p) = ctx.colliders.get(*c).and_then(|c| c.parent()) {
            if !out.contains(&p) {
                out.push(p);
            }
        }
    }
}

/// Wakes the sleeping members that share a dynamic body with an awake one (`shared`),
/// transitively: a pad left asleep would give no reaction to the box the other pushes.
pub(super) fn wake_linked(
    members: &mut [Member<'_, '_>],
    shared: &[(DeformableHandle, DeformableHandle)],
) {
    let index = |h: DeformableHandle| members.iter().position(|m| m.handle == h);
    let links: Vec<(usize, usize)> = shared
        .iter()
        .filter_map(|&(a, b)| Some((index(a)?, index(b)?)))
        .collect();
    let mut changed = true;
    while changed {
        changed = false;
        for &(a, b) in &links {
            let (sa, sb) = (
                members[a].body.activation.sleeping,
                members[b].body.activation.sleeping,
            );
            let frozen = members[a].body.activation.frozen || members[b].body.activation.frozen;
            if sa != sb && !frozen {
                let k = if sa { a } else { b };
                members[k].body.wake_up();
                changed = true;
            }
        }
    }
}

/// A deformable woken since its last step (by a disturbance, a setter, an impulse at a hit)
/// wakes the dynamic bodies it holds.
pub(super) fn wake_held_bodies(
    body: &mut Deformable,
    ctx: &StepContext<'_>,
    bodies: &mut RigidBodySet,
    rigid: &mut RigidHold,
) {
    if !std::mem::take(&mut body.activation.woken) {
        return;
    }
    held_bodies(body, ctx, &mut rigid.held);
    for h in &rigid.held {
        if let Some(rb) = bodies.get_mut(*h).filter(|b| b.is_dynamic()) {
            rb.wake_up(true);
        }
    }
}

/// The report of a body that slept through the step: not simulated, contacts (and so events)
/// unchanged.
pub(super) fn report_asleep(body: &mut Deformable, detached: usize) {
    let r = &mut body.last.report;
    r.sleeping = true;
    r.substeps = 0;
    r.limiter_substeps = 0;
    r.time_forces = 0.0;
    r.time_contacts = 0.0;
    r.time_integrate = 0.0;
    r.detached = detached;
    r.attached_nodes = body.bindings.len();
}

/// Whether something wakes a sleeping deformable: a bone it is bound to moves, a collider it
/// touched was removed, or a moving body's collider is near it.
fn disturbed(
    body: &Deformable,
    ctx: &StepContext<'_>,
    bodies: &RigidBodySet,
    broad: &mut Broad,
) -> bool {
    body.bindings.bodies(&mut broad.attached_bodies);
    if broad
        .attached_bodies
        .iter()
        .any(|h| bodies.get(*h).is_none_or(is_moving))
    {
        return true;
    }
    if body
        .last
        .touching
        .iter()
        .any(|c| !ctx.colliders.contains(*c))
    {
        return true;
    }
    let mut region = Aabb::new_invalid();
    for &i in body.rest.mesh.boundary_nodes() {
        region.take_point(body.state.positions[i as usize]);
    }
    let size = (region.maxs - region.mins).max_element().max(1e-3);
    let scan = ctx.scan(bodies, &body.contact);
    contact::near_colliders(
        &scan,
        region.loosened(ctx.margin + 1e-2 * size),
        &broad.attached_bodies,
        &mut broad.near,
    );
    let woken = broad.near.iter().any(|h| {
        ctx.colliders
            .get(*h)
            .and_then(|c| c.parent())
            .and_then(|p| bodies.get(p))
            .is_some_and(is_moving)
    });
    broad.near.clear();
    woken
}

/// After a simulated step: counts how long the body has been still (every free node moved
/// less than `sleep_speed · dt` over the step, no bone or nearby body moving, its state
/// `sane`); returns whether it has
/// been still long enough to sleep. It falls asleep ([`fall_asleep`]) with the bodies it may
/// touch, as one island, once all of them have.
pub(super) fn update(
    body: &mut Deformable,
    ctx: &StepContext<'_>,
    bodies: &RigidBodySet,
    broad: &Broad,
    sane: bool,
) -> bool {
    // A dynamic body it holds may be awake: resting on the deformable, it sleeps with it.
    let quiet = broad.motions.iter().all(|m| {
        bodies
            .get(m.handle)
            .is_some_and(|b| !is_restless(b, ctx.gravity, ctx.dt))
    });
    // Each free node's velocity over the step, from where it started: a node held on a
    // contact can end a step with the velocity of its last substep's push (a corner pressed
    // into a neighbour's facet leaves every twentieth step at 0.07 m/s, moving 10 µm a step),
    // which is no motion. Rapier 0.36 sleeps its dynamic bodies on their drift too (with twice
    // this budget).
    // The largest drift by its square, then one square root (it rounds correctly and keeps
    // the order). Measured only when it decides.
    let still = || {
        let (x, start) = (&body.state.positions, &body.step.saved_positions);
        let max_drift = threads::largest(x.len(), |i| {
            if body.is_attached(i as u32) {
                0.0
            } else {
                (x[i] - start[i]).length_squared()
            }
        })
        .sqrt();
        max_drift < ctx.settings.sleep_speed * ctx.dt
    };
    if body.activation.can_sleep && sane && quiet && still() {
        body.activation.still_time += ctx.dt;
    } else {
        body.activation.still_time = 0.0;
    }
    body.activation.still_time >= ctx.settings.time_until_sleep
}

/// Puts a body to sleep, at rest; the dynamic bodies it touched or is bound to go into `held`,
/// to sleep at the start of the next step ([`sleep_held`]).
pub(super) fn fall_asleep(
    body: &mut Deformable,
    ctx: &StepContext<'_>,
    held: &mut Vec<RigidBodyHandle>,
) {
    body.activation.sleeping = true;
    body.state.velocities.fill(Vector::ZERO);
    held_bodies(body, ctx, held);
}

/// Puts to sleep the dynamic bodies that the deformables which fell asleep last step held, if
/// they are still slow. Not in that step: the contacts moved them (the path they keep), and
/// rapier wakes a body moved in the step it was put to sleep (a box held by two sleeping pads
/// was woken, fell a step's gravity into them and was thrown out). Held up by the step's
/// contacts, it ends rapier's step at rest.
pub(super) fn sleep_held(held: &mut Vec<RigidBodyHandle>, bodies: &mut RigidBodySet) {
    for h in held.drain(..) {
        if let Some(rb) = bodies.get_mut(h).filter(|b| b.is_dynamic()) {
            let a = rb.activation();
            let slow = rb.linvel().length() <= a.normalized_linear_threshold
                && math::ang_norm(rb.angvel()) <= a.angular_threshold;
            if slow {
                rb.sleep();
            }
        }
    }
}
