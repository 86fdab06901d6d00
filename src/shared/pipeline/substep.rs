//! Phase 3 of a body's step: the substep loop (forces, substep size, the integrator's velocity
//! update, the bone drive, contacts, positions).

use super::super::attach::{self, DrivenNodes};
use super::super::body::Deformable;
use super::super::contact::soft::{self, NearFacets};
use super::super::contact::{self, Contact, FacetMotion, FreeNode};
use super::super::coupling::{BodyMotion, Substep};
use super::super::integrator::{AfterContacts, Bound, Integrate};
use super::super::math::{Real, Vector, FACET_ARITY};
use super::super::mesh::Mesh;
use super::super::rapier::dynamics::{RigidBodyHandle, RigidBodySet};
use super::super::set::DeformableHandle;
use super::{timed, Broad, Candidates, Scratch, StageTimes, StepContext, Touch};

/// Most feature crossings resolved per surface facet and substep.
const FACET_PASSES: usize = 8;
/// Block solves of each dynamic rigid body two members push, per substep.
const BLOCK_PASSES: usize = 2;

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
    /// Contacts of its nodes with other deformables' facets.
    pub soft_contacts: usize,
    /// Contacts of its nodes with its own facets.
    pub self_contacts: usize,
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

/// One body of a group stepped together: those that may touch each other take every substep
/// together (the shortest any of them needs), so their contacts act on both at once.
pub(super) struct Member<'m, 'a> {
    pub handle: DeformableHandle,
    pub body: &'m mut Deformable,
    pub sc: &'m mut Scratch,
    pub candidates: Candidates<'a>,
    pub times: StageTimes,
    pub stats: SubstepStats,
    /// Simulated this step (awake, not frozen); the others stay put, met as still surfaces.
    pub live: bool,
    /// Asleep at the start of the step (reported as asleep, even if a push woke it).
    pub asleep: bool,
    /// The members its nodes touched this step.
    pub touched: Vec<usize>,
    /// This substep's contacts with dynamic rigid bodies, solved again with the island's.
    pub rigid_rows: Vec<Contact>,
    /// Whether another deformable may push a dynamic body it may push.
    pub shares_bodies: bool,
}

/// Runs the substeps of a group's step, the velocities advanced by `integrator`; with `soft`,
/// the members meet each other's surfaces (and their own, with self contact) every substep.
pub(super) fn run(
    integrator: &impl Integrate,
    members: &mut [Member<'_, '_>],
    soft: bool,
    ctx: &StepContext<'_>,
    bodies: &mut RigidBodySet,
) {
    let dt = ctx.dt;
    let live: Vec<usize> = (0..members.len()).filter(|&i| members[i].live).collect();
    // The motions are read all through the loop while the other buffers change.
    let motions: Vec<Vec<BodyMotion>> = members
        .iter_mut()
        .map(|m| std::mem::take(&mut m.sc.broad.motions))
        .collect();
    let mut t = 0.0;
    let mut substeps = 0;
    while let Some(h) = next_substep(integrator, members, &live, ctx, dt - t, substeps) {
        for j in 0..live.len() {
            let i = live[order(substeps % 2 == 1, live.len(), j)];
            let m = &mut members[i];
            let at = substep_at(ctx, m.sc.broad.skin, h, t, &motions[i]);
            advance(integrator, m, ctx, &at, bodies);
        }
        rigid_passes(
            members,
            &live,
            ctx,
            (h, t),
            &motions,
            substeps % 2 == 1,
            bodies,
        );
        if soft {
            let at = substep_at(ctx, 0.0, h, t, &[]);
            soft_contacts(members, &at, substeps % 2 == 1);
        }

        for &i in &live {
            let m = &mut members[i];
            let body = &mut *m.body;
            for (x, v) in body.state.positions.iter_mut().zip(&body.state.velocities) {
                *x += *v * h;
            }
            attach::place_on_bones(
                &body.bindings,
                &m.sc.bones.targets,
                &mut body.state.positions,
            );
            body.step.forces_valid = false;
            m.stats.substeps += 1;
        }
        t += h;
        substeps += 1;
    }
    for (m, motions) in members.iter_mut().zip(motions) {
        m.sc.broad.motions = motions;
    }
}

/// The substep's contacts with each dynamic rigid body that two or more members push, solved
/// again with that body as one block ([`contact::block`]): a light box squeezed between two
/// pads takes one pad's push, then the other's, in the first pass; the block solve gives it
/// the balance of both. Rows sharing nodes (or two bodies sharing a node) meet through the
/// velocities between the block passes. A body only one member pushes keeps the single pass
/// (that member's sweep already meets it node after node).
fn rigid_passes(
    members: &mut [Member<'_, '_>],
    live: &[usize],
    ctx: &StepContext<'_>,
    (h, t): (Real, Real),
    motions: &[Vec<BodyMotion>],
    backward: bool,
    bodies: &mut RigidBodySet,
) {
    let mut pushed: Vec<(RigidBodyHandle, usize)> = Vec::new();
    for &i in live {
        let m = &members[i];
        for c in &m.rigid_rows {
            if let Some(b) = m.candidates[c.candidate].rigid(&motions[i]) {
                if !pushed.contains(&(b, i)) {
                    pushed.push((b, i));
                }
            }
        }
    }
    pushed.sort_unstable_by_key(|(b, i)| (b.into_raw_parts(), *i));
    let mut shared: Vec<RigidBodyHandle> = pushed
        .windows(2)
        .filter(|w| w[0].0 == w[1].0)
        .map(|w| w[0].0)
        .collect();
    for &i in live {
        let m = &members[i];
        for c in m.rigid_rows.iter().filter(|c| c.deferred()) {
            shared.extend(m.candidates[c.candidate].rigid(&motions[i]));
        }
    }
    shared.sort_unstable_by_key(|b| b.into_raw_parts());
    shared.dedup();
    if shared.is_empty() {
        return;
    }
    if backward {
        shared.reverse();
    }
    let mut picked: Vec<Vec<usize>> = vec![Vec::new(); members.len()];
    for _ in 0..BLOCK_PASSES {
        for &body in &shared {
            for &i in live {
                let m = &members[i];
                picked[i].clear();
                picked[i].extend((0..m.rigid_rows.len()).filter(|&k| {
                    m.candidates[m.rigid_rows[k].candidate].rigid(&motions[i]) == Some(body)
                }));
            }
            let mut sides: Vec<contact::block::BlockSide<'_, '_>> = members
                .iter_mut()
                .enumerate()
                .filter(|(i, m)| m.live && !picked[*i].is_empty())
                .map(|(i, m)| contact::block::BlockSide {
                    at: substep_at(ctx, m.sc.broad.skin, h, t, &motions[i]),
                    rows: &mut m.rigid_rows,
                    picked: &picked[i],
                    velocities: &mut m.body.state.velocities,
                    candidates: &mut m.candidates,
                    pushed: &mut m.sc.touch.pushed,
                })
                .collect();
            contact::block::solve(&mut sides, body, bodies);
        }
    }
}

fn substep_at<'a>(
    ctx: &StepContext<'_>,
    skin: Real,
    h: Real,
    t: Real,
    motions: &'a [BodyMotion],
) -> Substep<'a> {
    Substep {
        h,
        t,
        s1: ((t + h) / ctx.dt).min(1.0),
        dt: ctx.dt,
        restitution_threshold: ctx.settings.restitution_threshold,
        skin,
        motions,
    }
}

/// The next substep of the group: the element forces made current, then the shortest size any
/// live member needs; `None` when the step is done or a member ran out of substeps (then the
/// whole group drops the rest of the step, each saying so).
fn next_substep(
    integrator: &impl Integrate,
    members: &mut [Member<'_, '_>],
    live: &[usize],
    ctx: &StepContext<'_>,
    remaining: Real,
    substeps: usize,
) -> Option<Real> {
    if let Some(k) = ctx.settings.fixed_substeps {
        if substeps >= k.max(1) {
            return None;
        }
    } else if remaining <= ctx.dt * 1e-6 {
        return None;
    }
    let mut h = Real::INFINITY;
    let mut out = false;
    for &i in live {
        let m = &mut members[i];
        if integrator.uses_forces(m.body) {
            timed(&mut m.times.forces, || m.body.refresh_forces());
        }
        match substep_size(integrator.bound(m.body), ctx, remaining, &mut m.stats) {
            Some(hi) => h = h.min(hi),
            None => out = true,
        }
    }
    if out {
        for &i in live {
            let stats = &mut members[i].stats;
            stats.cap_hit = true;
            stats.lost_time = remaining;
        }
        return None;
    }
    (h < Real::INFINITY).then_some(h)
}

/// One member's substep up to its positions: the integrator's velocities, the bone drive, the
/// contacts with rigid colliders.
fn advance(
    integrator: &impl Integrate,
    m: &mut Member<'_, '_>,
    ctx: &StepContext<'_>,
    at: &Substep<'_>,
    bodies: &mut RigidBodySet,
) {
    let g = ctx.gravity * m.body.gravity_scale;
    let body = &mut *m.body;
    let sc = &mut *m.sc;
    let answers = integrator.answers_contacts(body);
    // An implicit step's second contact pass clears the first's rows: their impulses must
    // reach the body at once.
    let sharing = Sharing {
        split: !m.shares_bodies,
        defer: m.shares_bodies && !answers,
    };
    // Velocities first (the contacts act on them), from the element forces and gravity.
    body.step
        .scratch_velocities
        .copy_from_slice(&body.state.velocities);
    let contacts_follow = !m.candidates.is_empty();
    integrator.advance_velocities(body, g, at.h, contacts_follow);

    // Bound nodes follow their bones.
    let nodes = DrivenNodes {
        positions: &body.state.positions,
        velocities: &mut body.state.velocities,
        inv_masses: &body.rest.inv_masses,
    };
    attach::drive_bones(
        &body.bindings,
        &sc.bones.attachment_motion,
        nodes,
        at,
        bodies,
        &mut sc.bones.targets,
    );

    // Contacts, on velocities, before positions move.
    let candidates = &mut m.candidates;
    let rows = &mut m.rigid_rows;
    rows.clear();
    if !candidates.is_empty() {
        let stats = &mut m.stats;
        let before = answers.then(|| body.state.velocities.clone());
        timed(&mut m.times.contacts, || {
            for c in candidates.iter_mut() {
                c.advance(at.s1, at.dt, at.motions, bodies);
            }
            // Sequential impulses in one fixed order are lopsided (a box landing flat on a
            // soft cube was kicked sideways and kept swaying): the sweeps alternate.
            let backward = stats.substeps % 2 == 1;
            stats.facet_contacts += sweep_contacts(
                body,
                (at, backward, sharing),
                bodies,
                sc,
                (candidates, rows),
            );
        });
        // An implicit integrator lets the rest of the body answer the contacts within the
        // step, then the contacts see the result.
        if let Some(before) = before {
            let mut lift = vec![None; before.len()];
            for c in sc.touch.last_contact.iter().flatten() {
                if let Some(i) = c.node {
                    lift[i as usize] = Some((c.point, c.normal));
                }
            }
            let after = AfterContacts {
                before: &before,
                lift: &lift,
            };
            let set = body.state.velocities.clone();
            let mut reactions = Vec::new();
            if integrator.after_contacts(body, g, at.h, after, &mut reactions) {
                let given = Given {
                    before: &before,
                    set: &set,
                    reactions: &reactions,
                };
                given.pass_on(body, at, &sc.touch, candidates, bodies);
                timed(&mut m.times.contacts, || {
                    let backward = stats.substeps % 2 == 1;
                    rows.clear();
                    let sweep = (at, backward, sharing);
                    stats.facet_contacts +=
                        sweep_contacts(body, sweep, bodies, sc, (candidates, rows));
                });
            }
        }
    }
}

/// What an implicit step's holds gave the nodes the contacts stopped.
struct Given<'a> {
    /// Velocities before and after the contacts.
    before: &'a [Vector],
    set: &'a [Vector],
    /// The force each hold exerted on its node over the substep.
    reactions: &'a [Vector],
}

impl Given<'_> {
    /// Gives each dynamic body the rest of its contacts' reactions: the push a node held
    /// against it took over the substep (`reactions · h` along the normal), less the impulse
    /// the contact already gave that node. A node stopped by a collider under the implicit
    /// step passes on the body's elastic force; its own velocity change is a fraction
    /// `m/(k h²)` of it (a 1000 kg box sank through a soft cube it pressed on).
    fn pass_on(
        &self,
        body: &Deformable,
        at: &Substep<'_>,
        touch: &Touch,
        candidates: &Candidates<'_>,
        bodies: &mut RigidBodySet,
    ) {
        if self.reactions.is_empty() {
            return;
        }
        for c in touch.last_contact.iter().flatten() {
            let Some(i) = c.node.map(|i| i as usize) else {
                continue;
            };
            let Some(cand) = candidates.iter().find(|k| k.handle == c.collider) else {
                continue;
            };
            if !cand.dynamic {
                continue;
            }
            let given = (self.set[i] - self.before[i]) * body.rest.masses[i];
            let rest = c.normal.dot(self.reactions[i] * at.h - given);
            if rest > 0.0 {
                let anchor = cand.anchor(c.point);
                cand.apply_impulse(-c.normal * rest, anchor, at.motions, bodies, at.dt);
            }
        }
    }
}

/// The `j`-th index of `len` in the sweep's order.
fn order(backward: bool, len: usize, j: usize) -> usize {
    if backward {
        len - 1 - j
    } else {
        j
    }
}

/// The node contacts, then the facet contacts, of one sweep; returns how many facet contacts
/// were solved.
fn sweep_contacts(
    body: &mut Deformable,
    sweep: (&Substep<'_>, bool, Sharing),
    bodies: &mut RigidBodySet,
    sc: &mut Scratch,
    (candidates, rows): (&mut Candidates<'_>, &mut Vec<Contact>),
) -> usize {
    node_contacts(
        body,
        sweep,
        bodies,
        (&sc.broad, &mut sc.touch),
        (candidates, rows),
    );
    facet_contacts(
        body,
        sweep,
        bodies,
        (&sc.broad, &mut sc.touch),
        (candidates, rows),
    )
}

/// How a member meets the dynamic bodies it pushes.
#[derive(Copy, Clone, Debug)]
struct Sharing {
    /// A body found over a node goes back out by its share: no other deformable may push it
    /// (a box pinched between two pads would be moved into the other pad).
    split: bool,
    /// The body takes the contacts' impulses in its block solve ([`rigid_passes`]), not at once.
    defer: bool,
}

/// Every free surface node against its candidates; each contact found is solved at once.
fn node_contacts(
    body: &mut Deformable,
    (at, backward, sharing): (&Substep<'_>, bool, Sharing),
    bodies: &mut RigidBodySet,
    (broad, touch): (&Broad, &mut Touch),
    (candidates, rows): (&mut Candidates<'_>, &mut Vec<Contact>),
) {
    let surface = body.rest.mesh.boundary_nodes();
    for j in 0..surface.len() {
        let k = order(backward, surface.len(), j);
        let i = surface[k];
        let (b0, b1) = (
            broad.node_start[k] as usize,
            broad.node_start[k + 1] as usize,
        );
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
        let Some(mut c) = contact::resolve_node(
            node,
            &mut x,
            at,
            &broad.node_cands[b0..b1],
            candidates,
            bodies,
        ) else {
            continue;
        };
        let start = body.state.positions[n_i];
        if x != start {
            // A dynamic body found over the node (rapier's step carried it there) goes back
            // out by its share of the two inverse masses, the node by the rest; not one that
            // another deformable may push (a box pinched between two pads would be moved
            // into the other pad).
            let cand = &candidates[c.candidate];
            if sharing.split && cand.dynamic {
                let w_body = cand.inv_mass_at(c.anchor(), c.normal, at.motions, bodies);
                let share = w_body / (w_body + node.inv_mass);
                if share > 0.0 && share.is_finite() {
                    let out = x - start;
                    let timing = (at.s1, at.dt);
                    contact::translate_body(
                        candidates,
                        c.candidate,
                        -out * share,
                        timing,
                        at.motions,
                        bodies,
                    );
                    x = start + out * (1.0 - share);
                }
            }
            let rest = (&body.rest.mesh, body.rest.near_facets());
            x = keep_cells_upright(rest, &mut body.state.positions, k, (start, x));
        }
        body.state.positions[n_i] = x;
        if sharing.defer && candidates[c.candidate].dynamic {
            c.defer_body();
        }
        let v = &mut body.state.velocities;
        let point = c.settle(v, at, candidates, bodies, &mut touch.pushed, Some(i));
        touch.touched_nodes[k] = true;
        touch.last_contact[k] = Some(point);
        touch.touched_colliders[c.candidate] = true;
        if candidates[c.candidate].dynamic {
            rows.push(c);
        }
    }
}

/// Smallest quality (volume ratio) a node moved out of a collider may leave a cell of it at,
/// unless the cell was flatter before.
const MIN_OUT_QUALITY: Real = 0.1;

/// The position of surface node `k` (an index into the boundary nodes) moved from `start`
/// towards `out` (out of a collider it was found inside) as far as keeps each of its cells at
/// [`MIN_OUT_QUALITY`] or no flatter than it was (halving the move up to ten times, else not
/// moving it): a collider that rapier's step moved centimetres into a body (a spinning box
/// knocked back into a ball by the box beside it) would have had the node moved through its
/// own cell and inverted it; the contact holds the node where it stays, and later substeps
/// move it on.
fn keep_cells_upright(
    (mesh, near): (&Mesh, &NearFacets),
    x: &mut [Vector],
    k: usize,
    (start, out): (Vector, Vector),
) -> Vector {
    let cells = near.cells_of_node(k);
    let node = mesh.boundary_nodes()[k] as usize;
    x[node] = start;
    let floors: Vec<Real> = cells
        .iter()
        .map(|&c| MIN_OUT_QUALITY.min(mesh.cell_quality(c as usize, x)))
        .collect();
    let mut step = out - start;
    for _ in 0..=10 {
        x[node] = start + step;
        let upright = cells
            .iter()
            .zip(&floors)
            .all(|(&c, &floor)| mesh.cell_quality(c as usize, x) >= floor);
        if upright {
            return x[node];
        }
        step *= 0.5;
    }
    x[node] = start;
    start
}

/// Every surface facet against the point features of its candidates, the deepest crossing
/// first; returns how many contacts were solved.
fn facet_contacts(
    body: &mut Deformable,
    (at, backward, sharing): (&Substep<'_>, bool, Sharing),
    bodies: &mut RigidBodySet,
    (broad, touch): (&Broad, &mut Touch),
    (candidates, rows): (&mut Candidates<'_>, &mut Vec<Contact>),
) -> usize {
    let facets = body.rest.mesh.boundary_facets();
    let h = at.h;
    let mut solved = 0;
    for j in 0..facets.len() {
        let f = order(backward, facets.len(), j);
        let facet = &facets[f];
        let (b0, b1) = (
            broad.facet_start[f] as usize,
            broad.facet_start[f + 1] as usize,
        );
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
            let ids = &broad.facet_cands[b0..b1];
            let Some(mut c) = contact::resolve_facet(&motion, at, ids, candidates, bodies) else {
                break;
            };
            if sharing.defer && candidates[c.candidate].dynamic {
                c.defer_body();
            }
            let v = &mut body.state.velocities;
            let point = c.settle(v, at, candidates, bodies, &mut touch.pushed, None);
            body.last.contacts.push(point);
            touch.touched_colliders[c.candidate] = true;
            if candidates[c.candidate].dynamic {
                rows.push(c);
            }
            solved += 1;
        }
    }
    solved
}

/// Every free surface node of each member against the surface facets of the other members
/// (one side at least live), and its own with self contact (see
/// [`soft`](super::super::contact::soft)): each contact found is solved at once.
fn soft_contacts(members: &mut [Member<'_, '_>], at: &Substep<'_>, backward: bool) {
    let (mut hits, mut exits) = (Vec::new(), Vec::new());
    for i in 0..members.len() {
        if members[i].body.activation.frozen {
            continue;
        }
        let surface = members[i].body.rest.mesh.boundary_nodes().len();
        for j in 0..surface {
            let k = order(backward, surface, j);
            let m = &members[i];
            let (b0, b1) = (
                m.sc.soft.soft_start[k] as usize,
                m.sc.soft.soft_start[k + 1] as usize,
            );
            if b0 == b1 {
                continue;
            }
            let node = m.body.rest.mesh.boundary_nodes()[k];
            let cands = &m.sc.soft.soft_cands[b0..b1];
            let body_of = |j: usize| (&*members[j].body, &members[j].sc.soft.soft_surface);
            soft::find(body_of, i, node, cands, at, (&mut hits, &mut exits));
            // A still member's nodes meet only live members' facets.
            let still = !members[i].live;
            hits.retain(|h| !still || (h.other != i && members[h.other].live));
            for hit in hits.drain(..) {
                let Some(mut row) = new_row(members, i, node, &hit, at) else {
                    continue;
                };
                if solve_row(members, &mut row, Some(at.restitution_threshold)) {
                    let other = hit.other;
                    let m = &mut members[i];
                    if other == i {
                        m.stats.self_contacts += 1;
                    } else {
                        m.stats.soft_contacts += 1;
                        if !m.touched.contains(&other) {
                            m.touched.push(other);
                        }
                    }
                }
            }
        }
    }
}

/// The row of a contact `find` found for `node` of member `i`.
fn new_row(
    members: &mut [Member<'_, '_>],
    i: usize,
    node: u32,
    hit: &soft::SoftHit,
    at: &Substep<'_>,
) -> Option<soft::SoftRow> {
    if hit.other == i {
        let still = soft::Still {
            node: false,
            facet: false,
        };
        return soft::row((i, members[i].body), node, None, still, hit, at);
    }
    let (a, b) = pair_mut(members, i, hit.other);
    let still = soft::Still {
        node: !a.live,
        facet: !b.live,
    };
    soft::row((i, a.body), node, Some(b.body), still, hit, at)
}

/// One update of a soft row on its members' velocities; whether it applied an impulse. With
/// `wake_speed` (its first update), a still side it would push faster than that wakes for the
/// next step.
fn solve_row(
    members: &mut [Member<'_, '_>],
    row: &mut soft::SoftRow,
    wake_speed: Option<Real>,
) -> bool {
    let (i, j) = (row.node_member, row.facet_member);
    let impulse = if i == j {
        row.solve(&mut members[i].body.state.velocities, None)
    } else {
        let (a, b) = pair_mut(members, i, j);
        let impulse = row.solve(
            &mut a.body.state.velocities,
            Some(&mut b.body.state.velocities),
        );
        if let Some(speed) = wake_speed {
            let (node, facet) = row.wakes(impulse, a.body, b.body, speed);
            if node && !a.live {
                a.body.wake_up();
            }
            if facet && !b.live {
                b.body.wake_up();
            }
        }
        impulse
    };
    impulse != Vector::ZERO
}

/// Two distinct elements of a slice, mutably.
fn pair_mut<T>(v: &mut [T], i: usize, j: usize) -> (&mut T, &mut T) {
    assert!(i != j);
    if i < j {
        let (lo, hi) = v.split_at_mut(j);
        (&mut lo[i], &mut hi[0])
    } else {
        let (lo, hi) = v.split_at_mut(i);
        (&mut hi[0], &mut lo[j])
    }
}
