//! Phase 2 of a body's step: the state saved for a rollback, the motions of the rigid bodies
//! around it, and the broad phase into candidate tables.

use super::super::body::Deformable;
use super::super::contact::{self, Candidate, Scan};
use super::super::coupling::BodyMotion;
use super::super::math::{Real, Vector};
use super::super::rapier::dynamics::{RigidBodyHandle, RigidBodySet};
use super::super::rapier::geometry::{Aabb, BoundingVolume};
use super::super::threads;
use super::{Candidates, Scratch, StepContext};

/// The index of `handle`'s motion in `motions`, added if it is not there yet (`None`: the body
/// is gone).
fn motion_of(
    motions: &mut Vec<BodyMotion>,
    handle: RigidBodyHandle,
    bodies: &RigidBodySet,
    dt: Real,
) -> Option<usize> {
    if let Some(k) = motions.iter().position(|m| m.handle == handle) {
        return Some(k);
    }
    let b = bodies.get(handle)?;
    motions.push(BodyMotion::new(handle, b, dt));
    Some(motions.len() - 1)
}

/// The box a node at `p` moving with `v` sweeps over the step under gravity `g`.
fn swept(b: &mut Aabb, p: Vector, v: Vector, g: Vector, dt: Real) {
    b.take_point(p);
    b.take_point(p + v * dt + g * (0.5 * dt * dt));
}

/// Saves the state, gathers the motions of the bodies it is bound to and of the colliders
/// near it, and fills the per-node and per-facet candidate tables of `sc`; returns the
/// candidates.
pub(super) fn prepare<'a>(
    body: &mut Deformable,
    ctx: &StepContext<'a>,
    bodies: &RigidBodySet,
    sc: &mut Scratch,
) -> Candidates<'a> {
    let dt = ctx.dt;
    let g = ctx.gravity * body.gravity_scale;
    // The deformation damping over the whole step, first: every later phase (the broad
    // phase's swept boxes, the island guard's starting energy, a rollback) sees the damped
    // velocities, and the substeps' contacts act after it.
    body.damp_deformation(dt);
    body.step.save(&body.state);

    // Bodies this deformable is bound to, and how every relevant body moves.
    sc.broad.motions.clear();
    body.bindings.bodies(&mut sc.broad.attached_bodies);
    sc.bones.attachment_motion.clear();
    for a in body.bindings.list() {
        let m = motion_of(&mut sc.broad.motions, a.body, bodies, dt);
        sc.bones.attachment_motion.push(m);
    }
    sc.bones.teleported =
        super::teleport::carry_if_jumped(body, ctx, bodies, (&sc.bones, &mut sc.broad));

    // Broad phase, once per deformable and then once per surface node.
    let surface = body.rest.mesh.boundary_nodes();
    let (x, v) = (&body.state.positions, &body.state.velocities);
    sc.broad.swept.clear();
    sc.broad.swept.extend(surface.iter().map(|&i| {
        let mut b = Aabb::new_invalid();
        swept(&mut b, x[i as usize], v[i as usize], g, dt);
        b
    }));
    let region = sc
        .broad
        .swept
        .iter()
        .fold(Aabb::new_invalid(), |r, b| r.merged(b));
    // The shortest surface edge, by its square: the square root of the least square is the
    // least of the square roots, bit for bit (it rounds correctly and never decreases).
    let x = &body.state.positions;
    let edges = body.rest.surface_edges();
    let shortest = threads::least(edges.len(), |e| {
        let [a, b] = edges[e];
        x[a as usize].distance_squared(x[b as usize])
    })
    .sqrt();
    // Element forces can turn a node around within the step: widen every box by a quarter
    // of the shortest surface edge, on top of the motion predicted from the velocities. The
    // implicit step turns nodes around over a whole frame: a node may end it as fast as the
    // fastest node of the body, in any direction (a 60 Hz shape-matching fall reached 30 mm
    // into the ground with a node thrown up by the contact and pulled down by the body).
    let size = (region.maxs - region.mins).max_element().max(1e-3);
    let turning = if ctx.settings.integrator.steps_implicitly(body) {
        // The largest length by its square (a square root keeps the order): the same bits.
        let v = &body.state.velocities;
        let fastest = threads::largest(v.len(), |i| v[i].length_squared()).sqrt();
        (fastest + g.length() * dt) * dt
    } else {
        0.0
    };
    // The explicit step's own forces move a node by `½ a dt²` over the step beyond its
    // velocity's prediction: small on a body near rest, but a body thrown by its own forces
    // (a ball inflated to 10 atm, from rest) would end the step past a collider it never saw.
    // (The first substep uses these forces, so they cost nothing.)
    let pushed = if ctx.settings.integrator.steps_implicitly(body) {
        0.0
    } else {
        body.refresh_forces();
        let (force, inv) = (&body.step.acc.force, &body.rest.inv_masses);
        let nodes = force.len().min(inv.len());
        let fastest = threads::largest(nodes, |i| (force[i] * inv[i]).length_squared()).sqrt();
        0.5 * fastest * dt * dt
    };
    let node_margin = if shortest.is_finite() {
        0.25 * shortest
    } else {
        0.0
    } + 1e-3 * size
        + 1e-4
        + turning
        + pushed;
    let extent = region.mins.abs().max(region.maxs.abs()).max_element();
    sc.broad.skin = contact::surface_skin(shortest, extent);
    let widen = node_margin + ctx.margin;
    let region = region.loosened(widen);
    let scan = ctx.scan(bodies, &body.contact);
    contact::near_colliders(&scan, region, &sc.broad.attached_bodies, &mut sc.broad.near);
    let mut candidates: Vec<Candidate<'a>> = Vec::with_capacity(sc.broad.near.len());
    for &h in &sc.broad.near {
        let Some(co) = ctx.colliders.get(h) else {
            continue;
        };
        let m = co
            .parent()
            .and_then(|p| motion_of(&mut sc.broad.motions, p, bodies, dt));
        let spacing = 0.5 * shortest.max(1e-4);
        candidates.push(contact::candidate(
            &scan,
            h,
            co,
            m,
            &sc.broad.motions,
            &region,
            spacing,
        ));
    }
    sc.broad.near.clear();
    sc.broad.near.extend(candidates.iter().map(|c| c.handle));
    sc.touch.touched_colliders.clear();
    sc.touch.touched_colliders.resize(candidates.len(), false);
    sc.rigid.backup.save(&sc.broad.motions, bodies);
    tables(body, &scan, &candidates, widen, sc);
    body.last.contacts.clear();
    candidates
}

/// The per-surface-node and per-surface-facet candidate tables (compressed rows), and the
/// per-step contact buffers cleared.
fn tables(
    body: &Deformable,
    scan: &Scan<'_>,
    candidates: &[Candidate<'_>],
    widen: Real,
    sc: &mut Scratch,
) {
    let (dt, g) = (scan.dt, scan.gravity * body.gravity_scale);
    let surface = body.rest.mesh.boundary_nodes();
    sc.broad.node_start.clear();
    sc.broad.node_cands.clear();
    sc.broad.node_start.push(0);
    for (&i, b) in surface.iter().zip(&sc.broad.swept) {
        if !candidates.is_empty() && !body.is_attached(i) {
            contact::node_candidates(
                scan,
                b.loosened(widen),
                candidates,
                &mut sc.broad.node_cands,
            );
        }
        sc.broad.node_start.push(sc.broad.node_cands.len() as u32);
    }
    sc.broad.facet_start.clear();
    sc.broad.facet_cands.clear();
    sc.broad.facet_start.push(0);
    let with_features = candidates.iter().any(|c| !c.features.is_empty());
    for f in body.rest.mesh.boundary_facets() {
        if with_features && !f.iter().all(|&i| body.is_attached(i)) {
            let mut b = Aabb::new_invalid();
            for &i in f {
                swept(
                    &mut b,
                    body.state.positions[i as usize],
                    body.state.velocities[i as usize],
                    g,
                    dt,
                );
            }
            let begin = sc.broad.facet_cands.len();
            contact::node_candidates(
                scan,
                b.loosened(widen),
                candidates,
                &mut sc.broad.facet_cands,
            );
            let mut k = begin;
            while k < sc.broad.facet_cands.len() {
                if candidates[sc.broad.facet_cands[k] as usize]
                    .features
                    .is_empty()
                {
                    sc.broad.facet_cands.swap_remove(k);
                } else {
                    k += 1;
                }
            }
        }
        sc.broad.facet_start.push(sc.broad.facet_cands.len() as u32);
    }
    sc.touch.touched_nodes.clear();
    sc.touch.touched_nodes.resize(surface.len(), false);
    sc.touch.last_contact.clear();
    sc.touch.last_contact.resize(surface.len(), None);
}
