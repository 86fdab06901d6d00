//! Phase 3 of a body's step: the substep loop (forces, substep size, the integrator's velocity
//! update, the bone drive, contacts, positions).

use super::super::attach::{self, DrivenNodes};
use super::super::body::Deformable;
use super::super::contact::{self, FacetMotion, FreeNode};
use super::super::coupling::Substep;
use super::super::integrator::{Bound, Integrate};
use super::super::math::{Real, Vector, FACET_ARITY};
use super::super::rapier::dynamics::RigidBodySet;
use super::{timed, Candidates, Scratch, StageTimes, StepContext};

/// Most feature crossings resolved per surface facet and substep.
const FACET_PASSES: usize = 8;

/// What the substep loop did.
#[derive(Copy, Clone, Debug, Default)]
pub(super) struct SubstepStats {
    pub substeps: usize,
    /// Substeps the crossing limiter shortened.
    pub limiter_substeps: usize,
    /// Whether the loop ran out of substeps, and the time of the step it dropped.
    pub cap_hit: bool,
    pub lost_time: Real,
    pub facet_contacts: usize,
}

/// The substep size at the current state's bound, or `None` when the body is out of substeps
/// (`stats` says so).
fn substep_size(
    bound: Bound,
    ctx: &StepContext<'_>,
    remaining: Real,
    stats: &mut SubstepStats,
) -> Option<Real> {
    let settings = &ctx.settings;
    if let Some(k) = settings.fixed_substeps {
        return Some(ctx.dt / k.max(1) as Real);
    }
    let stable = settings.safety * bound.stable;
    let limiter = bound.limiter;
    let bound = stable.min(limiter);
    if limiter < stable {
        stats.limiter_substeps += 1;
    }
    if stats.substeps + 1 >= settings.max_substeps
        || bound.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
    {
        // Out of substeps: drop the rest of the step for this body rather than take it in
        // one unstable leap (the report says how much time was lost).
        stats.cap_hit = true;
        stats.lost_time = remaining;
        None
    } else if bound.is_finite() {
        Some(remaining / (remaining / bound).ceil().max(1.0))
    } else {
        Some(remaining)
    }
}

/// Runs the substeps of one body's step, its velocities advanced by `integrator`.
pub(super) fn run(
    integrator: &impl Integrate,
    body: &mut Deformable,
    ctx: &StepContext<'_>,
    bodies: &mut RigidBodySet,
    sc: &mut Scratch,
    candidates: &mut Candidates<'_>,
    times: &mut StageTimes,
) -> SubstepStats {
    let dt = ctx.dt;
    let g = ctx.gravity * body.gravity_scale;
    let n = body.state.positions.len();
    let mut stats = SubstepStats::default();
    // The motions are read all through the loop while the other buffers change.
    let motions = std::mem::take(&mut sc.motions);
    let mut t = 0.0;
    loop {
        let remaining = dt - t;
        if let Some(k) = ctx.settings.fixed_substeps {
            if stats.substeps >= k.max(1) {
                break;
            }
        } else if remaining <= dt * 1e-6 {
            break;
        }
        timed(&mut times.forces, || body.refresh_forces());
        let Some(h) = substep_size(integrator.bound(body), ctx, remaining, &mut stats) else {
            break;
        };
        let at = Substep {
            h,
            t,
            s1: ((t + h) / dt).min(1.0),
            dt,
            restitution_threshold: ctx.settings.restitution_threshold,
            skin: sc.skin,
            motions: &motions,
        };

        // Velocities first (the contacts act on them), from the element forces and gravity.
        body.step
            .scratch_velocities
            .copy_from_slice(&body.state.velocities);
        integrator.advance_velocities(body, g, h);

        // Bound nodes follow their bones.
        let nodes = DrivenNodes {
            positions: &body.state.positions,
            velocities: &mut body.state.velocities,
            inv_masses: &body.rest.inv_masses,
        };
        attach::drive_bones(
            &body.bindings,
            &sc.attachment_motion,
            nodes,
            &at,
            bodies,
            &mut sc.targets,
        );

        // Contacts, on velocities, before positions move.
        if !candidates.is_empty() {
            timed(&mut times.contacts, || {
                for c in candidates.iter_mut() {
                    c.advance(at.s1, dt, at.motions, bodies);
                }
                // Sequential impulses in one fixed order are lopsided (a box landing flat on a
                // soft cube was kicked sideways and kept swaying): the sweeps alternate.
                let backward = stats.substeps % 2 == 1;
                node_contacts(body, &at, backward, bodies, sc, candidates);
                stats.facet_contacts += facet_contacts(body, &at, backward, bodies, sc, candidates);
            });
        }

        for i in 0..n {
            body.state.positions[i] += body.state.velocities[i] * h;
        }
        attach::place_on_bones(&body.bindings, &sc.targets, &mut body.state.positions);
        body.step.forces_valid = false;
        t += h;
        stats.substeps += 1;
    }
    sc.motions = motions;
    stats
}

/// The `j`-th index of `len` in the sweep's order.
fn order(backward: bool, len: usize, j: usize) -> usize {
    if backward {
        len - 1 - j
    } else {
        j
    }
}

/// Every free surface node against its candidates; each contact found is solved at once.
fn node_contacts(
    body: &mut Deformable,
    at: &Substep<'_>,
    backward: bool,
    bodies: &mut RigidBodySet,
    sc: &mut Scratch,
    candidates: &mut Candidates<'_>,
) {
    let surface = body.rest.mesh.boundary_nodes();
    for j in 0..surface.len() {
        let k = order(backward, surface.len(), j);
        let i = surface[k];
        let (b0, b1) = (sc.node_start[k] as usize, sc.node_start[k + 1] as usize);
        if b0 == b1 {
            continue;
        }
        let n_i = i as usize;
        let mut x = body.state.positions[n_i];
        let node = FreeNode {
            index: i,
            v: body.state.velocities[n_i],
            v_before: body.step.scratch_velocities[n_i],
            inv_mass: body.rest.inv_masses[n_i],
        };
        let Some(mut c) =
            contact::resolve_node(node, &mut x, at, &sc.node_cands[b0..b1], candidates, bodies)
        else {
            continue;
        };
        body.state.positions[n_i] = x;
        let v = &mut body.state.velocities;
        let point = c.settle(v, at, candidates, bodies, &mut sc.pushed, Some(i));
        sc.touched_nodes[k] = true;
        sc.last_contact[k] = Some(point);
        sc.touched_colliders[c.candidate] = true;
    }
}

/// Every surface facet against the point features of its candidates, the deepest crossing
/// first; returns how many contacts were solved.
fn facet_contacts(
    body: &mut Deformable,
    at: &Substep<'_>,
    backward: bool,
    bodies: &mut RigidBodySet,
    sc: &mut Scratch,
    candidates: &mut Candidates<'_>,
) -> usize {
    let facets = body.rest.mesh.boundary_facets();
    let h = at.h;
    let mut solved = 0;
    for j in 0..facets.len() {
        let f = order(backward, facets.len(), j);
        let facet = &facets[f];
        let (b0, b1) = (sc.facet_start[f] as usize, sc.facet_start[f + 1] as usize);
        if b0 == b1 {
            continue;
        }
        let inv_masses: [Real; FACET_ARITY] = std::array::from_fn(|a| {
            let i = facet[a];
            if body.is_attached(i) {
                0.0
            } else {
                body.rest.inv_masses[i as usize]
            }
        });
        let x: [Vector; FACET_ARITY] =
            std::array::from_fn(|a| body.state.positions[facet[a] as usize]);
        // The deepest crossing first, then the next one, with the facet where the last push
        // left it (each push only moves it further in): a flat face brings several features
        // across one facet at once.
        for _ in 0..FACET_PASSES {
            let y: [Vector; FACET_ARITY] = std::array::from_fn(|a| {
                let i = facet[a] as usize;
                body.state.positions[i] + body.state.velocities[i] * h
            });
            let motion = FacetMotion {
                nodes: *facet,
                x,
                y,
                inv_masses,
            };
            let ids = &sc.facet_cands[b0..b1];
            let Some(mut c) = contact::resolve_facet(&motion, at, ids, candidates, bodies) else {
                break;
            };
            let v = &mut body.state.velocities;
            let point = c.settle(v, at, candidates, bodies, &mut sc.pushed, None);
            body.last.contacts.push(point);
            sc.touched_colliders[c.candidate] = true;
            solved += 1;
        }
    }
    solved
}
