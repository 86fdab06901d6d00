//! Phase 3 of a body's step: the substep loop (forces, substep size, the integrator's velocity
//! update, the bone drive, contacts, positions).

use super::super::attach::{self, DrivenNodes};
use super::super::body::Deformable;
use super::super::contact::soft::{self, NearFacets};
use super::super::contact::soft_terms;
use super::super::contact::{self, Contact, FacetMotion, FacetSlack, FreeNode, Held};
use super::super::coupling::{self, BodyMotion, Substep};
use super::super::integrator::{AfterContacts, Integrate, Together};
use super::super::math::{self, AngVector, Real, Vector, FACET_ARITY};
use super::super::mesh::Mesh;
use super::super::rapier::dynamics::{RigidBodyHandle, RigidBodySet};
use super::super::set::DeformableHandle;
use super::super::threads;
use super::{timed, Broad, Candidates, Scratch, StageTimes, StepContext, Touch};

/// Most feature crossings resolved per surface facet and substep.
const FACET_PASSES: usize = 8;
/// Block solves of each dynamic rigid body two members push, per substep.
const BLOCK_PASSES: usize = 2;

/// What the substep loop did.
#[derive(Copy, Clone, Debug, Default)]
pub(super) struct SubstepStats {
    pub substeps: usize,
    /// Whether the body took the implicit step.
    pub implicit: bool,
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

/// The substep size from the `stable` substep (the integrator's bound under the safety
/// factor) and the crossing `limiter`, or `None` when the body is out of substeps (`stats`
/// says so).
fn substep_size(
    (stable, limiter): (Real, Real),
    ctx: &StepContext<'_>,
    remaining: Real,
    stats: &mut SubstepStats,
) -> Option<Real> {
    let settings = &ctx.settings;
    if let Some(k) = settings.fixed_substeps {
        return Some(ctx.dt / k.max(1) as Real);
    }
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
    /// This substep's node contacts with fixed and kinematic colliders, under the implicit
    /// step (the body's rigid motion answers them first, [`contact::rigid_answer`]).
    pub fixed_rows: Vec<Contact>,
    /// This substep's contacts of its nodes with other members' facets, as they ended it.
    pub held: Vec<Held>,
    /// Whether another deformable may push a dynamic body it may push.
    pub shares_bodies: bool,
    /// The step's [`pressed_substep`], from the state it began with.
    pub pressed: Option<Real>,
}

/// Runs the substeps of a group's step, the velocities advanced by `integrator`; with `soft`,
/// the members meet each other's surfaces (and their own, with self contact) every substep,
/// inside the integrator's solve with `together` ([`step_together`], in at least that many
/// substeps), else on the velocities after it ([`soft_contacts`]). Deformables held against
/// each other are damped ([`held`](super::held)) on the contacts of the substep that ends each
/// share of the step [`HELD_PERIOD`] long. Returns the time since the last such pass, for the
/// pass at the step's end, and the kinetic energy the passes took (the guard of an island
/// solved together counts it back: a pass must not hide energy the solve made).
pub(super) fn run(
    integrator: &impl Integrate,
    members: &mut [Member<'_, '_>],
    (soft, together): (bool, Option<usize>),
    ctx: &StepContext<'_>,
    bodies: &mut RigidBodySet,
) -> (Real, Real) {
    let dt = ctx.dt;
    let live: Vec<usize> = (0..members.len()).filter(|&i| members[i].live).collect();
    // The motions are read all through the loop while the other buffers change.
    let motions: Vec<Vec<BodyMotion>> = members
        .iter_mut()
        .map(|m| std::mem::take(&mut m.sc.broad.motions))
        .collect();
    let mut t = 0.0;
    let mut substeps = 0;
    let passes = (dt / HELD_PERIOD).ceil().max(1.0);
    let (mut damped, mut taken) = (0.0, 0.0);
    while let Some(h) = next_substep(integrator, members, &live, ctx, dt - t, substeps) {
        for m in members.iter_mut() {
            m.held.clear();
        }
        let h = if let Some(pieces) = together {
            let h = h
                .min(motion_bound(members, dt - t))
                .min(dt / pieces as Real);
            let at = substep_at(ctx, 0.0, h, t, &[]);
            step_together(integrator, members, (&live, &motions), ctx, &at, bodies);
            rigid_passes(members, &live, ctx, (h, t), &motions, false, bodies);
            h
        } else {
            for j in 0..live.len() {
                let i = live[order(substeps % 2 == 1, live.len(), j)];
                let m = &mut members[i];
                let at = substep_at(ctx, m.sc.broad.skin, h, t, &motions[i]);
                advance(integrator, m, ctx, &at, bodies, false);
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
            h
        };
        move_positions(integrator, members, &live, h);
        t += h;
        substeps += 1;
        if t < dt && (t * passes / dt).floor() > (damped * passes / dt).floor() {
            taken += super::damp_held(members, ctx, t - damped);
            damped = t;
        }
    }
    for (m, motions) in members.iter_mut().zip(motions) {
        m.sc.broad.motions = motions;
    }
    (t - damped, taken)
}

/// The period the damping of held deformables aims at within a step: the step is cut into
/// `ceil(dt / HELD_PERIOD)` equal shares, and a pass runs after the substep that ends each.
/// A pass sees the contacts of one substep only: run once per long step, it would miss bodies
/// that bounce apart and press together again within it (`docs/ARCHITECTURE.md` §6.10).
pub(super) const HELD_PERIOD: Real = 2e-3;

/// Most substeps an island solved together takes in a step.
const MAX_TOGETHER_SUBSTEPS: usize = 16;

/// The substep of an island solved together that splits `remaining` evenly so that no two
/// members' nodes close on each other by more than a quarter of the shortest surface edge in
/// it: the contact terms' planes, fixed for a substep, hold only that far (a tumbling cube's
/// node slides off the facet it was found on, or comes through one at a corner).
fn motion_bound(members: &[Member<'_, '_>], remaining: Real) -> Real {
    let mut reach = Real::INFINITY;
    let (mut lo, mut hi) = (
        Vector::splat(Real::INFINITY),
        Vector::splat(Real::NEG_INFINITY),
    );
    let mut spread: Real = 0.0;
    for m in members {
        reach = reach.min(m.sc.soft.soft_surface.margin());
        let body = &*m.body;
        let v = &body.state.velocities;
        let masses = &body.rest.masses;
        let mass: Real = masses.iter().sum();
        let mean = if m.live && mass > 0.0 {
            v.iter().zip(masses).map(|(v, m)| *v * *m).sum::<Vector>() / mass
        } else {
            Vector::ZERO
        };
        lo = lo.min(mean);
        hi = hi.max(mean);
        if m.live {
            let own = v.iter().map(|v| (*v - mean).length()).fold(0.0, Real::max);
            spread = spread.max(own);
        }
    }
    let closing = (hi - lo).length() + 2.0 * spread;
    if !(closing > 0.0 && reach > 0.0) {
        return remaining;
    }
    let count = (remaining * closing / reach)
        .ceil()
        .clamp(1.0, MAX_TOGETHER_SUBSTEPS as Real);
    remaining / count
}

/// Every live member's positions moved by its velocities over `h`, bound nodes placed on
/// their bones.
fn move_positions(
    integrator: &impl Integrate,
    members: &mut [Member<'_, '_>],
    live: &[usize],
    h: Real,
) {
    for &i in live {
        let m = &mut members[i];
        let body = &mut *m.body;
        // Node by node, on rayon's threads for a large body.
        let v = &body.state.velocities;
        threads::for_each_mut(&mut body.state.positions, |i, x| *x += v[i] * h);
        integrator.after_move(body);
        attach::place_on_bones(
            &body.bindings,
            &m.sc.bones.targets,
            &mut body.state.positions,
        );
        body.step.invalidate_forces();
        m.stats.substeps += 1;
    }
}

/// Share of the sleep speed below which an island's solve counts as settled
/// ([`Integrate::solve_together`]): a sweep that moves no node faster ends the sweeps.
const SETTLED_SHARE: Real = 1.0 / 16.0;

/// The step of an island the integrator solves with its contacts between deformables
/// ([`Integrate::solve_together`]): each live member's velocities and collider contacts, the
/// contacts between the members found on those velocities ([`soft_terms`]), the island's
/// solve, then each member's answer to its collider contacts.
fn step_together(
    integrator: &impl Integrate,
    members: &mut [Member<'_, '_>],
    (live, motions): (&[usize], &[Vec<BodyMotion>]),
    ctx: &StepContext<'_>,
    at: &Substep<'_>,
    bodies: &mut RigidBodySet,
) {
    let mut before: Vec<Vec<Vector>> = vec![Vec::new(); members.len()];
    for &i in live {
        let m = &mut members[i];
        let at = substep_at(ctx, m.sc.broad.skin, at.h, at.t, &motions[i]);
        before[i] = advance(integrator, m, ctx, &at, bodies, true).unwrap_or_default();
    }
    let mut terms = soft_terms::Terms::default();
    contact_terms(members, at, &mut terms.terms);
    let lifts: Vec<(Vec<_>, Carried)> = members
        .iter()
        .zip(&before)
        .zip(motions)
        .map(|((m, b), motions)| {
            let at = substep_at(ctx, m.sc.broad.skin, at.h, at.t, motions);
            let rows: &[Contact] = if b.is_empty() { &[] } else { &m.rigid_rows };
            let carried = Carried::of(rows, m.body, &m.candidates, &at, bodies);
            (lifts(&m.sc.touch, b.len()), carried)
        })
        .collect();
    // The velocities the collider contacts set, for the live members' answers after the solve.
    let sets: Vec<Vec<Vector>> = members
        .iter()
        .map(|m| {
            if m.live {
                m.body.state.velocities.clone()
            } else {
                Vec::new()
            }
        })
        .collect();
    let mut together: Vec<Together<'_>> = members
        .iter_mut()
        .zip(before)
        .zip(lifts.iter())
        .map(|((m, before), (lift, carried))| Together {
            g: ctx.gravity * m.body.gravity_scale,
            live: m.live,
            before: if m.live {
                before
            } else {
                m.body.state.velocities.clone()
            },
            lift: if m.live {
                lift.clone()
            } else {
                vec![None; m.body.num_nodes()]
            },
            carried: if m.live {
                carried.carried.clone()
            } else {
                Vec::new()
            },
            carried_velocity: if m.live {
                carried.velocity.clone()
            } else {
                Vec::new()
            },
            body: &mut *m.body,
            reactions: Vec::new(),
        })
        .collect();
    let settled = SETTLED_SHARE * ctx.settings.sleep_speed;
    let solved = integrator.solve_together(&mut together, &mut terms, (at.h, settled));
    let reactions: Vec<(Vec<Vector>, Vec<Vector>)> = together
        .into_iter()
        .map(|t| (t.before, t.reactions))
        .collect();
    if !solved {
        return;
    }
    let answers = reactions.into_iter().zip(sets).zip(&lifts);
    for (i, (((before, reactions), set), (_, carried))) in answers.enumerate() {
        let m = &mut members[i];
        if !m.live {
            continue;
        }
        let given = Given {
            before: &before,
            set: &set,
            reactions: &reactions,
            carried,
            gravity: None,
        };
        let own = substep_at(ctx, m.sc.broad.skin, at.h, at.t, &motions[i]);
        answered(m, &own, bodies, given);
    }
    after_terms(members, &terms, at);
}

/// The contact terms between the members on their current velocities: each free surface node
/// of each member against the other members' surface facets (and its own, with self contact),
/// as [`soft_contacts`] finds them, with a skin as wide as the widest member's margin so the
/// island's solve sees the contacts its sweeps may make; each starts from what the same
/// contact carried over from the last step.
fn contact_terms(
    members: &mut [Member<'_, '_>],
    at: &Substep<'_>,
    out: &mut Vec<soft_terms::Term>,
) {
    let skin = members
        .iter()
        .map(|m| m.sc.soft.soft_surface.margin())
        .fold(0.0, Real::max);
    let at = Substep { skin, ..*at };
    each_soft_hit(members, &at, false, |members, i, node, hit| {
        let (body, other, still) = sides(members, i, hit);
        out.extend(soft_terms::Term::new(body, node, other, still, hit, &at));
    });
    // Warm starts from the node's body's memory, split among the node's terms with the same
    // body (a node's terms are found together).
    let handles: Vec<DeformableHandle> = members.iter().map(|m| m.handle).collect();
    let key = |t: &soft_terms::Term| (t.node_member, t.node(), handles[t.facet_member]);
    let mut start = 0;
    while start < out.len() {
        let (member, node, _) = key(&out[start]);
        let end = start
            + out[start..]
                .iter()
                .take_while(|t| (t.node_member, t.node()) == (member, node))
                .count();
        let memory = &members[member].body.step.soft_memory;
        for t in start..end {
            let (_, node, other) = key(&out[t]);
            let found = memory.binary_search_by(|m| {
                (m.node, m.other.into_raw_parts()).cmp(&(node, other.into_raw_parts()))
            });
            if let Ok(found) = found {
                let count = out[start..end]
                    .iter()
                    .filter(|u| key(u) == key(&out[t]))
                    .count();
                let remembered = memory[found];
                out[t].warm(&remembered, 1.0 / count as Real);
            }
        }
        start = end;
    }
}

/// After the island's solve: each member's memory of its contacts, its contact counts and the
/// members it touched; a still member a push would move faster than the wake speed wakes.
fn after_terms(members: &mut [Member<'_, '_>], terms: &soft_terms::Terms, at: &Substep<'_>) {
    let handles: Vec<DeformableHandle> = members.iter().map(|m| m.handle).collect();
    for m in members.iter_mut() {
        m.body.step.soft_memory.clear();
    }
    for t in &terms.terms {
        let (i, j) = (t.node_member, t.facet_member);
        if let Some(grip) = t.grip().filter(|_| i != j) {
            let point = members[i].body.state.positions[t.node() as usize];
            members[i].held.push(Held {
                other: j,
                point,
                grip,
            });
        }
        if t.pushes() {
            let m = &mut members[i];
            if i == j {
                m.stats.self_contacts += 1;
            } else {
                m.stats.soft_contacts += 1;
                if !m.touched.contains(&j) {
                    m.touched.push(j);
                }
            }
        }
        let memory = t.memory(handles[j]);
        let list = &mut members[i].body.step.soft_memory;
        match list
            .iter_mut()
            .find(|m| m.node == memory.node && m.other == memory.other)
        {
            Some(m) => {
                m.k = m.k.max(memory.k);
                m.lambda += memory.lambda;
                m.lambda_t += memory.lambda_t;
            }
            None => list.push(memory),
        }
        // A still side pushed faster than the wake speed wakes for the next step.
        let speed = at.restitution_threshold;
        if !members[j].live && i != j {
            let b = &members[j].body;
            let w = b.rest.inv_masses[t.facet()[0] as usize];
            if t.speed_given(at.h, w) > speed {
                members[j].body.wake_up();
            }
        }
        if !members[i].live && i != j {
            let b = &members[i].body;
            if t.speed_given(at.h, b.rest.inv_masses[t.node() as usize]) > speed {
                members[i].body.wake_up();
            }
        }
    }
    for m in members.iter_mut() {
        m.body
            .step
            .soft_memory
            .sort_unstable_by_key(|m| (m.node, m.other.into_raw_parts()));
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
    // Contacts lose accuracy with the substep (ARCHITECTURE §4.1): surfaces that may meet each
    // other or themselves, and an implicit integrator's impacts taken explicitly, keep the
    // uncalibrated bound.
    let alone = members.len() == 1;
    for &i in live {
        let m = &mut members[i];
        if integrator.uses_forces(m.body) {
            // (Forces already current, as the broad phase left them, cost nothing here.)
            if !m.body.step.forces_valid {
                timed(&mut m.times.forces, || m.body.refresh_forces());
            }
        } else {
            m.stats.implicit = true;
        }
        // (Fixed substeps need no bound: the body's slack is not measured for them.)
        let calibrated = alone && ctx.settings.calibrates(m.body);
        let mut bound = integrator.bound(m.body, calibrated);
        let stable = if calibrated && !m.candidates.is_empty() {
            let g = ctx.gravity * m.body.gravity_scale;
            let safety = ctx.settings.safety;
            let pressed = *m.pressed.get_or_insert_with(|| pressed_substep(m.body, g));
            bound
                .under(safety, false)
                .max(bound.under(safety, true).min(pressed))
        } else {
            bound.under(ctx.settings.safety, calibrated)
        };
        // The limiter is exact below the cap it was evaluated under: enough while the
        // substep is too (`Deformable::refresh_forces`).
        if integrator.uses_forces(m.body) && stable > m.body.step.crossing_cap {
            m.body.step.crossing_cap = Real::INFINITY;
            m.body.step.invalidate_forces();
            timed(&mut m.times.forces, || m.body.refresh_forces());
            bound.limiter = integrator.bound(m.body, calibrated).limiter;
        }
        m.body.step.crossing_cap = 2.0 * stable;
        match substep_size((stable, bound.limiter), ctx, remaining, &mut m.stats) {
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

/// Share of the smallest cell's size that a boundary node of a body near colliders may be
/// moved in one substep by its acceleration under the element forces and gravity, for the
/// calibrated substep (`docs/ARCHITECTURE.md` §4.1).
const PRESSED_SHARE: Real = 0.01;

/// The longest substep in which no boundary node of `body` (near a collider) is moved more
/// than [`PRESSED_SHARE`] of the smallest cell by its acceleration `a` under the element
/// forces and gravity `g`: `a h²` is what a contact holding it must take back every substep.
fn pressed_substep(body: &Deformable, g: Vector) -> Real {
    let cell = body.rest.slack(&body.state.elements).cell_size;
    let (force, inv_masses) = (&body.step.acc.force, &body.rest.inv_masses);
    let most = body
        .rest
        .mesh
        .boundary_nodes()
        .iter()
        .map(|&i| (force[i as usize] * inv_masses[i as usize] + g).length())
        .fold(0.0, Real::max);
    if most > 0.0 {
        (PRESSED_SHARE * cell / most).sqrt()
    } else {
        Real::INFINITY
    }
}

/// One member's substep up to its positions: the integrator's velocities, the bone drive, the
/// contacts with rigid colliders. With `together` (an island the integrator solves with its
/// contacts between deformables, [`Integrate::solve_together`]), it stops after the first
/// contact pass and returns the velocities before it; the island's solve and [`answered`]
/// follow.
fn advance(
    integrator: &impl Integrate,
    m: &mut Member<'_, '_>,
    ctx: &StepContext<'_>,
    at: &Substep<'_>,
    bodies: &mut RigidBodySet,
    together: bool,
) -> Option<Vec<Vector>> {
    let g = ctx.gravity * m.body.gravity_scale;
    let body = &mut *m.body;
    let sc = &mut *m.sc;
    let answers = integrator.answers_contacts(body);
    // An implicit step's second contact pass clears the first's rows: their impulses must
    // reach the body at once.
    let sharing = Sharing {
        split: !m.shares_bodies,
        defer: m.shares_bodies && !answers,
        explicit: !answers,
        facet_slack: facet_slack(body, answers),
    };
    // Velocities first (the contacts act on them), from the element forces and gravity.
    body.step
        .scratch_velocities
        .copy_from_slice(&body.state.velocities);
    let contacts_follow = together || !m.candidates.is_empty();
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
    let fixed = &mut m.fixed_rows;
    fixed.clear();
    if candidates.is_empty() {
        return together.then(|| body.state.velocities.clone());
    }
    let stats = &mut m.stats;
    let before = answers.then(|| body.state.velocities.clone());
    let mut facets = 0;
    timed(&mut m.times.contacts, || {
        for c in candidates.iter_mut() {
            c.advance(at.s1, at.dt, at.motions, bodies);
        }
        // Sequential impulses in one fixed order are lopsided (a box landing flat on a
        // soft cube was kicked sideways and kept swaying): the sweeps alternate.
        let backward = stats.substeps % 2 == 1;
        facets = sweep_contacts(
            body,
            (at, backward, sharing),
            bodies,
            sc,
            (candidates, rows, answers.then_some(&mut *fixed)),
        );
        stats.facet_contacts += facets;
    });
    let mut before = before?;
    if together {
        return Some(before);
    }
    // An implicit integrator lets the rest of the body answer the contacts within the
    // step, then the contacts see the result.
    let mut touched = Vec::new();
    let alone = candidates.iter().all(|c| !c.dynamic) && body.bindings.len() == 0;
    if alone && facets == 0 {
        let x = &body.state.positions;
        let surface = body.rest.mesh.boundary_nodes();
        let state = (&x[..], &before[..], &body.rest.masses[..], surface);
        // Closing faster than gravity brings in two substeps (and the restitution threshold):
        // an impact, as `pipeline/impact.rs` tells one.
        let impact = at.restitution_threshold + 2.0 * g.length() * at.h;
        let rows = (&fixed[..], impact);
        if let Some(change) = contact::rigid_answer(state, rows, at, candidates, bodies) {
            for (v, p) in before.iter_mut().zip(x) {
                *v += change.at(*p);
            }
            let v = &mut body.state.velocities;
            v.copy_from_slice(&before);
            touched = vec![false; v.len()];
            for c in fixed.iter_mut() {
                c.solve_afresh(v, at, candidates, bodies);
                for (i, _) in c.moving_nodes() {
                    touched[i] = true;
                }
            }
        }
    }
    let lift = lifts(&sc.touch, before.len());
    let carried = Carried::of(rows, body, candidates, at, bodies);
    let after = AfterContacts {
        before: &before,
        lift: &lift,
        carried: &carried.carried,
        carried_velocity: &carried.velocity,
        touched: &touched,
    };
    let set = body.state.velocities.clone();
    let mut reactions = Vec::new();
    if integrator.after_contacts(body, g, at.h, after, &mut reactions) {
        let given = Given {
            before: &before,
            set: &set,
            reactions: &reactions,
            carried: &carried,
            gravity: Some(g * at.h),
        };
        answered(m, at, bodies, given);
    }
    None
}

/// Per node, where the substep's collider contacts left it ([`AfterContacts::lift`]).
fn lifts(touch: &Touch, nodes: usize) -> Vec<Option<(Vector, Vector)>> {
    let mut lift = vec![None; nodes];
    for c in touch.last_contact.iter().flatten() {
        if let Some(i) = c.node {
            lift[i as usize] = Some((c.point, c.normal));
        }
    }
    lift
}

/// How the contacts with dynamic bodies share them among their nodes under the implicit step:
/// each body's effective mass along a contact's normal, shared evenly among the body's
/// contacts (as its block solve shares it, §6.8), and among a contact's nodes by their
/// weights. A node whose bodies are each lighter than the whole deformable carries its share
/// ([`AfterContacts::carried`]); one that meets a heavier body is held where it goes (a
/// 1000 kg box on a 1 kg cube).
struct Carried {
    /// Per contact (row), its share of its body.
    rows: Vec<Real>,
    /// Per node, the sum of its shares.
    nodes: Vec<Real>,
    /// Per node, the sum of its shares if it carries them, else zero (empty: none carries).
    carried: Vec<Real>,
    /// Per node that carries, the velocity its shares bring: its own after the contacts, with
    /// the part along each contact's normal that of the body there before them plus the
    /// relative speed that just meets it (`Contact::meets`): where the body's surface goes
    /// unstopped. The contacts threw the node back off the body, which its share does not do.
    velocity: Vec<Vector>,
}

impl Carried {
    fn of(
        rows: &[Contact],
        body: &Deformable,
        candidates: &Candidates<'_>,
        at: &Substep<'_>,
        bodies: &RigidBodySet,
    ) -> Self {
        // Most substeps meet no dynamic body: nothing to carry, nothing allocated.
        if rows.is_empty() {
            return Carried {
                rows: Vec::new(),
                nodes: Vec::new(),
                carried: Vec::new(),
                velocity: Vec::new(),
            };
        }
        let mut count = vec![0usize; candidates.len()];
        for r in rows {
            count[r.candidate] += 1;
        }
        let mass: Real = body.rest.masses.iter().sum();
        let n = body.num_nodes();
        let (mut shares, mut nodes, mut carried) = (Vec::new(), vec![0.0; n], vec![0.0; n]);
        let mut held = vec![false; n];
        let v = &body.state.velocities;
        let mut velocity = vec![Vector::ZERO; n];
        for r in rows {
            let cand = &candidates[r.candidate];
            let w = cand.inv_mass_at(r.anchor(), r.normal, at.motions, bodies);
            let share = if w > 0.0 && cand.dynamic {
                1.0 / (w * count[r.candidate] as Real)
            } else {
                0.0
            };
            shares.push(share);
            let found = cand.found_velocity(r.anchor(), at.s1);
            for (i, weight) in r.moving_nodes() {
                nodes[i] += share * weight;
                carried[i] += share * weight;
                held[i] |= w * mass < 1.0;
                if let Some(u) = found {
                    let along = r.normal.dot(u - v[i]) + r.meets();
                    velocity[i] += r.normal * (share * weight * along);
                }
            }
        }
        for (i, (c, held)) in carried.iter_mut().zip(held).enumerate() {
            if held {
                *c = 0.0;
            }
            velocity[i] = if *c > 0.0 {
                v[i] + velocity[i] / nodes[i]
            } else {
                v[i]
            };
        }
        Carried {
            rows: shares,
            nodes,
            carried,
            velocity,
        }
    }
}

/// After the integrator answered the collider contacts: the dynamic bodies get the rest of
/// the held nodes' reactions ([`Given::pass_on`]) and the contacts see the result.
fn answered(m: &mut Member<'_, '_>, at: &Substep<'_>, bodies: &mut RigidBodySet, given: Given<'_>) {
    let body = &mut *m.body;
    let sc = &mut *m.sc;
    let candidates = &mut m.candidates;
    if candidates.is_empty() {
        return;
    }
    let unpaid = given.pass_on(body, at, (candidates, &m.rigid_rows), bodies);
    // Only a body that meets nothing but dynamic bodies lighter than itself keeps its
    // momentum with them: one that a fixed or moving collider, or a heavier body, holds
    // answers through it (its sweeps and holds lean on it; taken back, a 40 kg box thrown at
    // a 25 kg cube left with 11 % more energy than it brought).
    let carried = &given.carried;
    let carries =
        m.rigid_rows.iter().zip(&carried.rows).all(|(r, &share)| {
            share == 0.0 || r.moving_nodes().all(|(i, _)| carried.carried[i] > 0.0)
        });
    let free = candidates.iter().all(|c| c.dynamic) && body.bindings.len() == 0 && carries;
    if let (Some(gravity), true) = (given.gravity, free) {
        let centre = body.center_of_mass();
        let (mut impulse, mut moment) = unanswered(body, centre, at.h, (given.reactions, gravity));
        for (anchor, j) in &unpaid {
            impulse += *j;
            moment += math::cross(*anchor - centre, *j);
        }
        take_back(body, centre, (impulse, moment));
    }
    let sharing = Sharing {
        split: !m.shares_bodies,
        defer: false,
        explicit: false,
        facet_slack: facet_slack(body, true),
    };
    let (stats, rows) = (&mut m.stats, &mut m.rigid_rows);
    timed(&mut m.times.contacts, || {
        let backward = stats.substeps % 2 == 1;
        rows.clear();
        let solved = body.state.velocities.clone();
        let sweep = (at, backward, sharing);
        let rows = (candidates, rows, None);
        stats.facet_contacts += sweep_contacts(body, sweep, bodies, sc, rows);
        keep_motion_upright(body, &solved, at.h);
    });
}

/// Scales back the velocity changes the contacts made after an implicit solve (from `solved`)
/// node by node, halving each up to ten times (else undoing it), until carried over `h` it
/// leaves every cell of its node at [`MIN_OUT_QUALITY`] or no flatter than the solve's motion
/// would: the solve kept the cells upright, and a box corner pressing a shape-matched ball's
/// facet pushed the facet's nodes through the cells behind it, step after step, until cells
/// turned inside out. A node held back so is a hair inside the collider, and the next step's
/// contacts take it out over that step.
fn keep_motion_upright(body: &mut Deformable, solved: &[Vector], h: Real) {
    if body.state.velocities[..] == solved[..] {
        return;
    }
    let (x, v) = (&body.state.positions, &mut body.state.velocities);
    let (mesh, near) = (&body.rest.mesh, body.rest.near_facets());
    let mut end: Vec<Vector> = x.iter().zip(solved).map(|(p, u)| *p + *u * h).collect();
    let floors = |end: &[Vector], cells: &[u32]| -> Vec<Real> {
        cells
            .iter()
            .map(|&c| MIN_OUT_QUALITY.min(mesh.cell_quality(c as usize, end)))
            .collect()
    };
    for (k, &i) in mesh.boundary_nodes().iter().enumerate() {
        let i = i as usize;
        let change = v[i] - solved[i];
        if change == Vector::ZERO {
            continue;
        }
        let cells = near.cells_of_node(k);
        let floor = floors(&end, cells);
        let mut scale = 1.0;
        let mut upright = false;
        for _ in 0..=10 {
            end[i] = x[i] + (solved[i] + change * scale) * h;
            upright = cells
                .iter()
                .zip(&floor)
                .all(|(&c, &f)| mesh.cell_quality(c as usize, &end) >= f);
            if upright {
                break;
            }
            scale *= 0.5;
        }
        if !upright {
            scale = 0.0;
            end[i] = x[i] + solved[i] * h;
        }
        v[i] = solved[i] + change * scale;
    }
}

/// What an implicit step's holds gave the nodes the contacts stopped.
struct Given<'a> {
    /// Velocities before and after the contacts.
    before: &'a [Vector],
    set: &'a [Vector],
    /// The force each hold exerted on its node over the substep.
    reactions: &'a [Vector],
    /// What the contacts with dynamic bodies gave their nodes to carry.
    carried: &'a Carried,
    /// What gravity gave each node over the substep (velocity), when the body was solved
    /// alone (`None` in an island, whose contacts between its members move momentum among
    /// them).
    gravity: Option<Vector>,
}

impl Given<'_> {
    /// Gives each dynamic body the rest of its contacts' reactions: what the share of it that
    /// a node carried exerted on the node over the substep (`reactions · h` along the normal),
    /// less the impulse the contact already gave the node; a contact's part of a node's
    /// reaction is its part of what the node carried. The solve is not converged: a body's
    /// pushes are scaled down together until none sends the body away from its contact faster
    /// than the deformable side goes there (each capped on its own, in turn, rocked a box
    /// resting on four nodes; uncapped, a light box was launched).
    ///
    /// Returns what the nodes got that no body paid (a push scaled down, a hold's pull on its
    /// node, which a contact cannot exert, or its push along the contact), as impulses at the
    /// contacts' anchors.
    fn pass_on(
        &self,
        body: &Deformable,
        at: &Substep<'_>,
        (candidates, rows): (&Candidates<'_>, &[Contact]),
        bodies: &mut RigidBodySet,
    ) -> Vec<(Vector, Vector)> {
        let mut unpaid = Vec::new();
        if self.reactions.is_empty() {
            return unpaid;
        }
        let v = &body.state.velocities;
        // Per push: its row, its body, its impulse along the normal, how fast it closes.
        let mut pushes: Vec<(usize, RigidBodyHandle, Real, Real)> = Vec::new();
        for (k, (r, share)) in rows.iter().zip(&self.carried.rows).enumerate() {
            let cand = &candidates[r.candidate];
            let Some(handle) = cand.rigid(at.motions).filter(|_| *share > 0.0) else {
                continue;
            };
            let whole: Vector = r
                .moving_nodes()
                .map(|(i, w)| {
                    let part = share * w / self.carried.nodes[i];
                    let given = (self.set[i] - self.before[i]) * body.rest.masses[i];
                    (self.reactions[i] * at.h - given) * part
                })
                .sum();
            let rest = r.normal.dot(whole);
            // Only the push along the normal is passed on: the rest of what the hold gave is
            // unpaid (its tangential part, or all of a pull).
            unpaid.push((r.anchor(), whole - r.normal * rest.max(0.0)));
            if rest > 0.0 {
                let anchor = r.anchor();
                let moving =
                    cand.anchored_velocity(r.point, anchor, at.s1, at.dt, at.motions, bodies);
                let closing = r.normal.dot(moving - r.velocity(v));
                // A node held where the body goes moves with it: only carried pushes are capped.
                let carries = r.moving_nodes().all(|(i, _)| self.carried.carried[i] > 0.0);
                let closing = if carries {
                    closing.max(0.0)
                } else {
                    Real::INFINITY
                };
                pushes.push((k, handle, rest, closing));
            }
        }
        let mut done = vec![false; pushes.len()];
        for p in 0..pushes.len() {
            if done[p] {
                continue;
            }
            let handle = pushes[p].1;
            let Some(rb) = bodies.get(handle) else {
                continue;
            };
            let same: Vec<usize> = (p..pushes.len())
                .filter(|&q| pushes[q].1 == handle)
                .collect();
            // The velocity change all of the body's pushes give it, and the largest share of
            // them that separates no contact faster than its deformable side goes.
            let com = rb.center_of_mass();
            let (mut dv, mut dw) = (Vector::ZERO, AngVector::default());
            for &q in &same {
                let (k, _, rest, _) = pushes[q];
                let r = &rows[k];
                let (a, b) = coupling::impulse_response(rb, r.anchor(), -r.normal * rest);
                dv += a;
                dw += b;
            }
            let scale: Real = same.iter().fold(1.0, |scale, &q| {
                let (k, _, _, closing) = pushes[q];
                let r = &rows[k];
                let opening = -r.normal.dot(dv + math::ang_cross(dw, r.anchor() - com));
                if opening > closing {
                    scale.min(closing / opening)
                } else {
                    scale
                }
            });
            for &q in &same {
                done[q] = true;
                let (k, _, rest, _) = pushes[q];
                let r = &rows[k];
                if scale * rest > 0.0 {
                    let cand = &candidates[r.candidate];
                    let impulse = -r.normal * (scale * rest);
                    cand.apply_impulse(impulse, r.anchor(), at.motions, bodies, at.dt);
                }
                if scale < 1.0 {
                    unpaid.push((r.anchor(), r.normal * ((1.0 - scale) * rest)));
                }
            }
        }
        unpaid
    }
}

/// What the implicit solve changed of `body`'s momentum (about `centre`) beyond its holds'
/// reactions and gravity: unconverged sweeps leave the free nodes' equations unbalanced, and
/// with nodes held the body does not move as a whole by its best translation, which would
/// keep it.
fn unanswered(
    body: &Deformable,
    centre: Vector,
    h: Real,
    (reactions, gravity): (&[Vector], Vector),
) -> (Vector, AngVector) {
    let (x, v, v0) = (
        &body.state.positions,
        &body.state.velocities,
        &body.step.scratch_velocities,
    );
    let (mut p, mut l) = (Vector::ZERO, AngVector::default());
    for i in 0..x.len() {
        let held = reactions.get(i).copied().unwrap_or(Vector::ZERO) * h;
        let j = (v[i] - v0[i] - gravity) * body.rest.masses[i] - held;
        p += j;
        l += math::cross(x[i] - centre, j);
    }
    (p, l)
}

/// Takes back from `body` an impulse and a moment about its `centre` that no body gave it
/// (what its contacts' holds gave it unpaid, [`Given::pass_on`], and what its sweeps made,
/// [`unanswered`]), as a rigid body of its masses would, so that the body and the bodies it
/// touches keep their momenta: a box thrown at a free soft cube under the implicit step had
/// lost half of the pair's momentum over the hit.
fn take_back(body: &mut Deformable, centre: Vector, (impulse, moment): (Vector, AngVector)) {
    let offsets: Vec<Vector> = body.state.positions.iter().map(|x| *x - centre).collect();
    let turn = math::angular_velocity_for(&offsets, &body.rest.masses, -moment);
    let shift = -impulse / body.total_mass();
    for (v, r) in body.state.velocities.iter_mut().zip(&offsets) {
        *v += shift + math::ang_cross(turn, *r);
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
    (candidates, rows, fixed): ContactRows<'_, '_>,
) -> usize {
    node_contacts(
        body,
        sweep,
        bodies,
        (&sc.broad, &mut sc.touch),
        (candidates, rows, fixed),
    );
    facet_contacts(
        body,
        sweep,
        bodies,
        (&sc.broad, &mut sc.touch),
        (candidates, rows),
    )
}

/// How far behind a surface facet a rigid feature may start a substep and still press it
/// ([`contact::resolve_facet`]), over the facet's size, under the explicit step: a sliver.
const EXPLICIT_FACET_SLACK: Real = 1e-3;

/// [`EXPLICIT_FACET_SLACK`] under the implicit step, whose few sweeps may leave a pressed
/// facet millimetres behind the feature that pressed it: with a sliver, a light box rocking on
/// a soft 2D slab at 60 Hz lost every facet contact once a corner ended a step behind, and
/// sank through the slab.
const IMPLICIT_FACET_SLACK: Real = 0.05;

/// The facet slack for `body` in a substep where the integrator answers its contacts or not:
/// [`IMPLICIT_FACET_SLACK`] under the implicit step; in the explicit substeps of an impact
/// between implicit steps [`EXPLICIT_FACET_SLACK`] plus as far as the feature crosses the
/// facet's plane in the substep (the substep before may leave a facet a hair behind a heavy
/// feature: a box's corner on a soft 2D slab under the midpoint step was lost by an impact's
/// substeps and sank through); else [`EXPLICIT_FACET_SLACK`].
fn facet_slack(body: &Deformable, answers: bool) -> FacetSlack {
    let (slack, crossing) = if answers {
        (IMPLICIT_FACET_SLACK, 0.0)
    } else if body.step.midpoint.impact > 0.0 {
        (EXPLICIT_FACET_SLACK, 1.0)
    } else {
        (EXPLICIT_FACET_SLACK, 0.0)
    };
    FacetSlack { slack, crossing }
}

/// How a member's contacts act on the dynamic bodies it pushes, and on its own cells.
#[derive(Copy, Clone, Debug)]
struct Sharing {
    /// A body found over a node goes back out by its share: no other deformable may push it
    /// (a box pinched between two pads would be moved into the other pad).
    split: bool,
    /// The body takes the contacts' impulses in its block solve ([`rigid_passes`]), not at once.
    defer: bool,
    /// How far behind a facet a rigid feature may start a substep and still press it
    /// ([`facet_slack`]).
    facet_slack: FacetSlack,
    /// The velocities the contacts leave move the nodes as they are (the explicit step; an
    /// implicit one lets the body answer them first): a bounce is kept within the cells
    /// ([`bounce_within_cells`]).
    explicit: bool,
}

/// A member's candidates, where its contacts with dynamic bodies go, and where those with
/// fixed and kinematic colliders go if they are kept.
type ContactRows<'r, 'a> = (
    &'r mut Candidates<'a>,
    &'r mut Vec<Contact>,
    Option<&'r mut Vec<Contact>>,
);

/// Every free surface node against its candidates; each contact found is solved at once.
fn node_contacts(
    body: &mut Deformable,
    (at, backward, sharing): (&Substep<'_>, bool, Sharing),
    bodies: &mut RigidBodySet,
    (broad, touch): (&Broad, &mut Touch),
    (candidates, rows, mut fixed): ContactRows<'_, '_>,
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
        if sharing.explicit && c.bounces() {
            let rest = (&body.rest.mesh, body.rest.near_facets());
            let state = (&body.state.positions[..], &body.state.velocities[..]);
            bounce_within_cells(&mut c, rest, state, k, at.h);
        }
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
        } else if let Some(fixed) = fixed.as_mut() {
            fixed.push(c);
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

/// Most of its height over a cell a node thrown back by a contact may cover in a substep.
const BOUNCE_FRACTION: Real = 0.5;

/// Keeps as much of contact `c`'s bounce as lets surface node `k` (an index into the boundary
/// nodes) cover at most [`BOUNCE_FRACTION`] of its height over each of its cells in the
/// substep `h` (halving the bounce up to ten times, else dropping it), unless the cell closes
/// faster without it: the crossing limiter chose `h` from the velocities before the contacts
/// (`docs/ARCHITECTURE.md` §6.2). The node's velocity is taken with the whole normal change
/// and without friction's tangential one.
fn bounce_within_cells(
    c: &mut Contact,
    (mesh, near): (&Mesh, &NearFacets),
    (x, v): (&[Vector], &[Vector]),
    k: usize,
    h: Real,
) {
    let node = mesh.boundary_nodes()[k];
    let cells = near.cells_of_node(k);
    let quality = |cell: u32, vi: Vector| {
        let at = |n: u32| {
            let velocity = if n == node { vi } else { v[n as usize] };
            x[n as usize] + velocity * h
        };
        mesh.cell_quality_with(cell as usize, at)
    };
    let floors: Vec<Real> = cells
        .iter()
        .map(|&cell| {
            let q = mesh.cell_quality(cell as usize, x);
            let now = q - BOUNCE_FRACTION * q.abs();
            now.min(quality(cell, c.node_velocity(v[node as usize], 0.0)))
        })
        .collect();
    let mut keep = 1.0;
    for _ in 0..=10 {
        let vi = c.node_velocity(v[node as usize], keep);
        if cells
            .iter()
            .zip(&floors)
            .all(|(&cell, &floor)| quality(cell, vi) >= floor)
        {
            break;
        }
        keep *= 0.5;
    }
    if keep < 1.0 / 1024.0 {
        keep = 0.0;
    }
    c.keep_bounce(keep);
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
            let slack = sharing.facet_slack;
            let Some(mut c) = contact::resolve_facet(&motion, (at, slack), ids, candidates, bodies)
            else {
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
    each_soft_hit(members, at, backward, |members, i, node, hit| {
        let (body, other, still) = sides(members, i, hit);
        let Some(mut row) = soft::row(body, node, other, still, hit, at) else {
            return;
        };
        if solve_row(members, &mut row, Some(at.restitution_threshold)) {
            let other = hit.other;
            let m = &mut members[i];
            if let Some(grip) = row.grip().filter(|_| other != i) {
                let point = m.body.state.positions[node as usize];
                m.held.push(Held { other, point, grip });
            }
            if other == i {
                m.stats.self_contacts += 1;
            } else {
                m.stats.soft_contacts += 1;
                if !m.touched.contains(&other) {
                    m.touched.push(other);
                }
            }
        }
    });
}

/// Calls `each(members, i, node, hit)` for every contact [`soft::find`] finds between a free
/// surface node of member `i` and the surface facets of the other members (one side at least
/// live), or its own with self contact, the nodes of each member in turn (`backward`: last
/// first).
fn each_soft_hit(
    members: &mut [Member<'_, '_>],
    at: &Substep<'_>,
    backward: bool,
    mut each: impl FnMut(&mut [Member<'_, '_>], usize, u32, &soft::SoftHit),
) {
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
                each(members, i, node, &hit);
            }
        }
    }
}

/// The deepest any live member's surface node is inside another member, by its nearest way
/// out ([`soft::nearest_exits`]) among the facets its soft-contact table holds.
pub(super) fn deepest_inside(members: &[Member<'_, '_>]) -> Real {
    let mut exits = Vec::new();
    let mut deepest: Real = 0.0;
    for (i, m) in members.iter().enumerate().filter(|(_, m)| m.live) {
        let (start, cands) = (&m.sc.soft.soft_start, &m.sc.soft.soft_cands);
        let nodes = m.body.rest.mesh.boundary_nodes();
        for (k, &node) in nodes.iter().enumerate() {
            let (b0, b1) = (start[k] as usize, start[k + 1] as usize);
            if b0 == b1 {
                continue;
            }
            let body_of = |j: usize| (&*members[j].body, &members[j].sc.soft.soft_surface);
            let facing = m.sc.soft.soft_surface.facing(node as usize);
            let p = m.body.state.positions[node as usize];
            soft::nearest_exits(&body_of, (i, facing), p, &cands[b0..b1], &mut exits);
            for &(_, exit) in &exits {
                deepest = deepest.max(-exit);
            }
        }
    }
    deepest
}

/// The two sides of a contact `find` found for a node of member `i`: its body, the facet's
/// body (`None` with self contact) and which of them is still.
fn sides<'s>(
    members: &'s mut [Member<'_, '_>],
    i: usize,
    hit: &soft::SoftHit,
) -> (
    (usize, &'s mut Deformable),
    Option<&'s Deformable>,
    soft::Still,
) {
    if hit.other == i {
        let still = soft::Still {
            node: false,
            facet: false,
        };
        return ((i, &mut *members[i].body), None, still);
    }
    let (a, b) = pair_mut(members, i, hit.other);
    let still = soft::Still {
        node: !a.live,
        facet: !b.live,
    };
    ((i, &mut *a.body), Some(&*b.body), still)
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
