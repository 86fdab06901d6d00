//! Contacts between deformables inside the implicit step: each contact [`soft::find`] finds is
//! a term of the island's incremental potential, solved in the same Gauss–Seidel sweeps as the
//! bodies' elements (Augmented Vertex Block Descent: Giles, Diaz, Yuksel, SIGGRAPH 2025). Only
//! islands whose step energy is convex take it (shape matching,
//! `ModelState::has_convex_implicit`).
//!
//! **The constraint.** A node `i` and a facet of nodes `j` with barycentric weights `w_j` and
//! unit normal `n`, both fixed for the step: `C(x) = n·(x_i − Σ w_j x_j)`, the node's height
//! above the facet's plane, kept non-negative. A node found behind the facet is stepped out
//! onto its plane before the step (a position change, no velocity), and what is left of a depth
//! at the start is forgiven, `C̃ = C − min(C(x₀), 0)`: an old penetration is not pushed out
//! within the step, so it gives no node speed.
//!
//! **The augmented Lagrangian.** The term pushes the node out and the facet's nodes back with
//! `F = max(0, λ − k C̃)` (along `n`, by `w_j` on the facet), adding `k n nᵀ` (`k w_j² n nᵀ`)
//! to the node's Newton block while it pushes. After each sweep of the island `λ ← F` and, while
//! the node is inside, `k` grows with the depth. `λ` and `k` carry over to the next step for the
//! same node against the same body (a resting stack keeps the weight it carries, so two sweeps
//! need not find it again); `k` decays there, so it can come down.
//!
//! **The body as a whole.** A node's Newton step sees only its own cells, so a few sweeps
//! cannot move a body much stiffer than its nodes' inertia as a whole: a cube resting on
//! another sank into it sweep after sweep while `λ` grew to 16 times its weight, which the
//! next step then threw it up with. After each sweep every member no collider or bone holds
//! also takes the Newton step of its translation (its elasticity does not change under one;
//! only its inertia and its terms do), [`Terms::add_translation`].
//!
//! **Substeps.** The planes hold only near where they were found, so the island takes as many
//! substeps as keep its members from closing on each other by more than a quarter of the
//! shortest surface edge in one (the pipeline's `motion_bound`); a pile at rest takes one.
//!
//! **Friction** is Coulomb's on the step's tangential slip `u` (the node's displacement less
//! the facet point's, across `n`): `F_t = λ_t − k u` within the disc of `μ λ`, stiff while it
//! sticks and free once it slides; `λ_t` carries over as `λ` does.
//!
//! What it guarantees: the sweeps minimise backward Euler's incremental potential with the
//! terms added, so with converged sweeps no contact gives energy (a term's `λ` does work only
//! against a depth the step closes); an unconverged step leaves a depth of about `λ/k` per node
//! more than the last sweep found, which the next step's forgiveness does not push out (the
//! pipeline reports it as interpenetration). Unconverged sweeps can also pump an island (a node
//! driven into a facet harder than its penalty holds it); the pipeline's guard takes a step
//! that ended with more energy, or with a node deeper inside another body, again explicitly
//! (`pipeline/guard.rs`). Restitution between deformables under the implicit step is zero.

use super::super::body::Deformable;
use super::super::coupling::Substep;
use super::super::math::{self, Matrix, Real, Vector, FACET_ARITY};
use super::super::set::DeformableHandle;
use super::soft::{self, SoftHit, Still};

/// Penalty stiffness at a new contact, and the least a remembered one decays to, over the
/// node's inertia `m/h²`: softer, a resting stack's contacts give a little each step and
/// stiffen again, and the stack rocks instead of sleeping.
const START_STIFFNESS: Real = 5.0;
/// Largest penalty stiffness, over the node's inertia: stiffer terms that share nodes (two
/// corners crossed, each behind the other's facet) undo each other sweep after sweep, the
/// depth stays while `λ` grows to kilonewtons and throws the nodes; below it, `λ` carries the
/// load over the steps.
const MAX_STIFFNESS: Real = 10.0;
/// Growth of the penalty stiffness per sweep, over the node's inertia and per depth of the
/// facet body's depth limit: a penalty that dwarfs the nodes' inertia and elasticity makes a
/// facet node of weight `w` step `C/w` in its Newton step.
const GROWTH: Real = 10.0;
/// Share of a contact's penalty stiffness kept for the next step.
const DECAY: Real = 0.9;

/// One contact between a node and a facet (of another body, or of the node's own).
#[derive(Clone, Debug)]
pub(crate) struct Term {
    pub node_member: usize,
    pub facet_member: usize,
    node: u32,
    facet: [u32; FACET_ARITY],
    weights: [Real; FACET_ARITY],
    normal: Vector,
    /// The depth forgiven (`−min(C(x₀), 0)`).
    forgiven: Real,
    /// Whether each side moves (a still or bone-held side gives no way).
    node_moves: bool,
    facet_moves: [bool; FACET_ARITY],
    friction: Real,
    /// Penalty stiffness and the multipliers (normal push, tangential friction force).
    k: Real,
    lambda: Real,
    lambda_t: Vector,
    /// Per sweep growth of `k` per unit depth, and its cap.
    growth: Real,
    k_max: Real,
    /// The start of the step of the node and of the facet's point, for the slip.
    x0: Vector,
    q0: Vector,
}

/// What a contact carries over to the next step, kept by the node's body.
#[derive(Copy, Clone, Debug, PartialEq)]
pub(crate) struct Memory {
    pub node: u32,
    pub other: DeformableHandle,
    pub k: Real,
    pub lambda: Real,
    pub lambda_t: Vector,
}

impl Term {
    /// The term of a contact [`soft::find`] found between `node` of member `i` (`body`) and a
    /// facet of member `hit.other` (`other`; `None` with self contact), a still side giving
    /// no way (not both); steps a node found behind the facet out onto its plane. `None` when
    /// neither side can move.
    pub fn new(
        (i, body): (usize, &mut Deformable),
        node: u32,
        other: Option<&Deformable>,
        still: Still,
        hit: &SoftHit,
        at: &Substep<'_>,
    ) -> Option<Term> {
        let n_i = node as usize;
        let facet_body = other.unwrap_or(body);
        let node_moves = !still.node && !body.is_attached(node);
        let facet_moves = hit
            .facet
            .map(|j| !still.facet && !facet_body.is_attached(j));
        if !node_moves && !facet_moves.iter().any(|m| *m) {
            return None;
        }
        let friction = match other {
            Some(other) => soft::combined(body, other).0,
            None => body.contact.friction,
        };
        let q0: Vector = (0..FACET_ARITY)
            .map(|a| facet_body.state.positions[hit.facet[a] as usize] * hit.weights[a])
            .sum();
        let inertia = body.rest.masses[n_i] / (at.h * at.h);
        let depth_unit = hit.depth_limit.max(Real::MIN_POSITIVE);
        let mut term = Term {
            node_member: i,
            facet_member: hit.other,
            node,
            facet: hit.facet,
            weights: hit.weights,
            normal: hit.normal,
            forgiven: 0.0,
            node_moves,
            facet_moves,
            friction,
            k: START_STIFFNESS * inertia,
            lambda: 0.0,
            lambda_t: Vector::ZERO,
            growth: GROWTH * inertia / depth_unit,
            k_max: MAX_STIFFNESS * inertia,
            x0: Vector::ZERO,
            q0,
        };
        if node_moves {
            soft::step_out(&mut body.state.positions[n_i], hit);
        }
        term.x0 = body.state.positions[n_i];
        term.forgiven = (-term.normal.dot(term.x0 - q0)).max(0.0);
        Some(term)
    }

    /// Starts from what the same node's contact with the same body carried over, `share` of
    /// it (the node's contacts with that body split it).
    pub fn warm(&mut self, memory: &Memory, share: Real) {
        self.k = self.k.max(memory.k * DECAY);
        self.lambda = memory.lambda * share;
        // Friction acts across this term's normal only (the last step's may differ).
        let n = self.normal;
        self.lambda_t = (memory.lambda_t - n * n.dot(memory.lambda_t)) * share;
    }

    /// What this term carries over.
    pub fn memory(&self, other: DeformableHandle) -> Memory {
        Memory {
            node: self.node,
            other,
            k: self.k,
            lambda: self.lambda,
            lambda_t: self.lambda_t,
        }
    }

    pub fn node(&self) -> u32 {
        self.node
    }

    /// Marks the sides that `fixed(member, node)` holds in place this step as giving no way;
    /// returns whether a side still moves.
    fn hold(&mut self, fixed: &impl Fn(usize, u32) -> bool) -> bool {
        self.node_moves &= !fixed(self.node_member, self.node);
        for a in 0..FACET_ARITY {
            self.facet_moves[a] &= !fixed(self.facet_member, self.facet[a]);
        }
        self.node_moves || self.facet_moves.iter().any(|m| *m)
    }

    /// Whether it pushes at the end of the step.
    pub fn pushes(&self) -> bool {
        self.lambda > 0.0
    }

    /// How the term held at the end of the island's solve ([`Grip`](super::Grip)).
    pub fn grip(&self) -> Option<super::Grip> {
        super::Grip::of(self.normal, self.lambda)
    }

    /// The push over a step of `h` on a still side: the speed it would give that side's
    /// lightest node of inverse mass `inv_mass`.
    pub fn speed_given(&self, h: Real, inv_mass: Real) -> Real {
        (self.lambda + self.lambda_t.length()) * h * inv_mass
    }

    /// The nodes of the facet.
    pub fn facet(&self) -> &[u32; FACET_ARITY] {
        &self.facet
    }

    /// `C̃` and the slip `u` at the island's positions (`node_x`, `facet_x` the two sides').
    fn state(&self, node_x: &[Vector], facet_x: &[Vector]) -> (Real, Vector) {
        let p = node_x[self.node as usize];
        let q: Vector = (0..FACET_ARITY)
            .map(|a| facet_x[self.facet[a] as usize] * self.weights[a])
            .sum();
        let n = self.normal;
        let c = n.dot(p - q) + self.forgiven;
        let moved = (p - self.x0) - (q - self.q0);
        (c, moved - n * n.dot(moved))
    }

    /// The normal push and the friction force at a state, and whether friction sticks.
    fn forces(&self, (c, slip): (Real, Vector)) -> (Real, Vector, bool) {
        let push = (self.lambda - self.k * c).max(0.0);
        if self.friction <= 0.0 {
            return (push, Vector::ZERO, false);
        }
        let trial = self.lambda_t - slip * self.k;
        let limit = self.friction * self.lambda;
        let friction = super::coulomb(trial, limit);
        (push, friction, friction == trial && limit > 0.0)
    }

    /// Adds the term's force and Newton block at slot `slot` (0: the node; `1 + a`: the facet's
    /// `a`-th node) to `f` and `block`.
    pub fn add(
        &self,
        slot: usize,
        (node_x, facet_x): (&[Vector], &[Vector]),
        f: &mut Vector,
        block: &mut Matrix,
    ) {
        let state = self.state(node_x, facet_x);
        let (push, friction, sticks) = self.forces(state);
        if push <= 0.0 && friction == Vector::ZERO {
            return;
        }
        let share = if slot == 0 {
            1.0
        } else {
            -self.weights[slot - 1]
        };
        self.add_share(share, (push, friction, sticks), f, block);
    }

    /// Adds the term's force and Newton block for a coordinate that moves `C` by `share` per
    /// unit along the normal.
    fn add_share(
        &self,
        share: Real,
        (push, friction, sticks): (Real, Vector, bool),
        f: &mut Vector,
        block: &mut Matrix,
    ) {
        let n = self.normal;
        *f += (n * push + friction) * share;
        let mut stiffness = Matrix::ZERO;
        if push > 0.0 {
            stiffness += math::outer(n, n) * self.k;
        }
        if sticks {
            stiffness += (Matrix::IDENTITY - math::outer(n, n)) * self.k;
        }
        *block += stiffness * (share * share);
    }

    /// The dual update after a sweep of the island: `λ` and `λ_t` to the forces at `x`, `k`
    /// grown by the depth.
    pub fn update(&mut self, sides: (&[Vector], &[Vector])) {
        let state = self.state(sides.0, sides.1);
        let (push, friction, _) = self.forces(state);
        self.lambda = push;
        self.lambda_t = friction;
        if state.0 < 0.0 && push > 0.0 {
            self.k = (self.k + self.growth * -state.0).min(self.k_max);
        }
    }
}

/// An island's contact terms, and per member which of them each of its nodes takes part in.
#[derive(Clone, Debug, Default)]
pub(crate) struct Terms {
    pub terms: Vec<Term>,
    /// Per member (CSR over its nodes): `(term, slot)` for each moving side of a term.
    start: Vec<Vec<u32>>,
    slots: Vec<Vec<(u32, u8)>>,
    /// Per member, the terms it takes part in.
    by_member: Vec<Vec<u32>>,
}

impl Terms {
    /// Indexes the terms by node, for members of `nodes` nodes each, the nodes that
    /// `fixed(member, node)` holds in place this step giving no way. A term neither side of
    /// which can move is dropped: its depth cannot change within the step, so its `λ` would
    /// only grow sweep after sweep.
    pub fn index(&mut self, nodes: &[usize], fixed: impl Fn(usize, u32) -> bool) {
        self.terms.retain_mut(|t| t.hold(&fixed));
        let mut entries: Vec<Vec<(u32, u32, u8)>> = vec![Vec::new(); nodes.len()];
        for (t, term) in self.terms.iter().enumerate() {
            if term.node_moves {
                entries[term.node_member].push((term.node, t as u32, 0));
            }
            for a in 0..FACET_ARITY {
                if term.facet_moves[a] {
                    let slot = (a + 1) as u8;
                    entries[term.facet_member].push((term.facet[a], t as u32, slot));
                }
            }
        }
        self.by_member = vec![Vec::new(); nodes.len()];
        for (t, term) in self.terms.iter().enumerate() {
            self.by_member[term.node_member].push(t as u32);
            if term.facet_member != term.node_member {
                self.by_member[term.facet_member].push(t as u32);
            }
        }
        self.start = Vec::with_capacity(nodes.len());
        self.slots = Vec::with_capacity(nodes.len());
        for (list, &n) in entries.iter_mut().zip(nodes) {
            list.sort_unstable();
            let mut start = vec![0u32; n + 1];
            for e in list.iter() {
                start[e.0 as usize + 1] += 1;
            }
            for i in 0..n {
                start[i + 1] += start[i];
            }
            self.slots.push(list.iter().map(|e| (e.1, e.2)).collect());
            self.start.push(start);
        }
    }

    /// Whether no node of member `m` takes part in a term.
    pub fn none_for(&self, m: usize) -> bool {
        self.slots.get(m).is_none_or(|s| s.is_empty())
    }

    /// Adds the terms at node `i` of member `m` (its positions `own`, the other members' in
    /// `xs`, `xs[m]` not read) to its force and block.
    pub fn add(
        &self,
        (m, i): (usize, usize),
        own: &[Vector],
        xs: &[Vec<Vector>],
        f: &mut Vector,
        block: &mut Matrix,
    ) {
        let Some(start) = self.start.get(m) else {
            return;
        };
        let side = |j: usize| if j == m { own } else { &xs[j][..] };
        for &(t, slot) in &self.slots[m][start[i] as usize..start[i + 1] as usize] {
            let term = &self.terms[t as usize];
            let sides = (side(term.node_member), side(term.facet_member));
            term.add(slot as usize, sides, f, block);
        }
    }

    /// Adds the terms of member `m` to the force and stiffness of a translation of it as a
    /// whole (each term by how far the translation moves its `C`).
    pub fn add_translation(
        &self,
        m: usize,
        xs: &[Vec<Vector>],
        f: &mut Vector,
        block: &mut Matrix,
    ) {
        let Some(list) = self.by_member.get(m) else {
            return;
        };
        for &t in list {
            let term = &self.terms[t as usize];
            let mut share = 0.0;
            if term.node_member == m && term.node_moves {
                share += 1.0;
            }
            if term.facet_member == m {
                for a in 0..FACET_ARITY {
                    if term.facet_moves[a] {
                        share -= term.weights[a];
                    }
                }
            }
            if share.abs() < 1e-9 {
                continue;
            }
            let state = term.state(&xs[term.node_member], &xs[term.facet_member]);
            let forces = term.forces(state);
            if forces.0 <= 0.0 && forces.1 == Vector::ZERO {
                continue;
            }
            term.add_share(share, forces, f, block);
        }
    }

    /// The dual update of every term at the island's positions `xs`.
    pub fn update(&mut self, xs: &[Vec<Vector>]) {
        for term in &mut self.terms {
            term.update((&xs[term.node_member], &xs[term.facet_member]));
        }
    }
}
