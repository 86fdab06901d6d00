//! Contacts solved on velocities: one Gauss–Seidel update per contact found.

use super::super::coupling::BodyMotion;
use super::super::coupling::Substep;
use super::super::math::{Real, Vector, FACET_ARITY};
use super::super::rapier::dynamics::{RigidBodyHandle, RigidBodySet};
use super::candidates::{refresh_poses, Candidate};
use super::ContactPoint;

/// A contact between the deformable (a node, or a point of a surface facet) and a collider,
/// solved on velocities.
///
/// Impulses on a dynamic body use the effective mass of both sides: `Σ w_j²/m_j` on the
/// deformable, and the body's mass and inertia at the contact point. Each impulse is equal and
/// opposite (momentum is conserved) and applied to the body at once, so later contacts see its
/// new velocity: a light body is not launched by the whole momentum change of every node it
/// touches. The normal impulse stays non-negative and reaches at most the target relative
/// velocity (never more than the reverse of the approach: no energy is created); friction is
/// Coulomb's, at most `μ` times the normal impulse, and no more than stops the slip.
pub(crate) struct Contact {
    pub candidate: usize,
    /// Contact point, on the collider's end-of-substep pose.
    pub point: Vector,
    /// The same material point on a dynamic body's present pose (see [`Candidate::anchor`]):
    /// the contact keeps it while later impulses move the predicted pose.
    pub(super) anchor: Vector,
    /// Unit normal from the collider towards the deformable.
    pub normal: Vector,
    /// The deformable's side: nodes, barycentric weights and inverse masses (zero for a node
    /// held by a bone: its share goes to the bone).
    pub(super) nodes: [u32; FACET_ARITY],
    pub(super) weights: [Real; FACET_ARITY],
    pub(super) inv_masses: [Real; FACET_ARITY],
    /// Normal velocity of the deformable relative to the collider to reach.
    pub(super) target: Real,
    /// The part of `target` that is a bounce (restitution) rather than what closes the gap.
    pub(super) bounce: Real,
    /// The normal relative velocity when the contact was found.
    pub(super) found: Real,
    pub(super) normal_impulse: Real,
    pub(super) friction_impulse: Vector,
    /// The dynamic body has not taken this contact's impulses yet: the deformable side alone
    /// answered it, the body meeting it at its velocity, until the body's block solve
    /// ([`super::block`]) shares them out.
    pub(super) deferred: bool,
}

impl Contact {
    /// Solves the contact, brings the candidates of the body it pushed to that body's new
    /// predicted pose, notes the body in `pushed`, and returns the contact as the step reports
    /// it (`node`: the deformable's node, `None` for a facet contact).
    pub fn settle(
        &mut self,
        velocities: &mut [Vector],
        at: &Substep<'_>,
        candidates: &mut [Candidate<'_>],
        bodies: &mut RigidBodySet,
        pushed: &mut Vec<RigidBodyHandle>,
        node: Option<u32>,
    ) -> ContactPoint {
        self.solve(velocities, at, candidates, bodies);
        refresh_poses(candidates, self.candidate, at.s1, at.dt, at.motions, bodies);
        // A deferred contact's body is noted by its block solve, which decides its push.
        if !self.deferred {
            self.note_pushed(candidates, at.motions, pushed);
        }
        ContactPoint {
            point: self.point,
            normal: self.normal,
            collider: candidates[self.candidate].handle,
            node,
        }
    }

    /// The deformable's side of the contact at node positions `x` (its barycentric point).
    pub(crate) fn node_point(&self, x: &[Vector]) -> Vector {
        self.nodes
            .iter()
            .zip(&self.weights)
            .map(|(&j, &w)| x[j as usize] * w)
            .sum()
    }

    /// Solves the contact afresh (its impulses so far forgotten) on `velocities` changed since:
    /// it pushes only as far as its target still asks.
    pub(crate) fn solve_afresh(
        &mut self,
        velocities: &mut [Vector],
        at: &Substep<'_>,
        candidates: &[Candidate<'_>],
        bodies: &mut RigidBodySet,
    ) {
        self.normal_impulse = 0.0;
        self.friction_impulse = Vector::ZERO;
        self.solve(velocities, at, candidates, bodies);
    }

    /// The normal velocity relative to the collider at which the deformable's side just meets
    /// it at the end of the substep (the target less its bounce).
    pub fn meets(&self) -> Real {
        self.target - self.bounce
    }

    /// Whether the contact's target includes a bounce.
    pub fn bounces(&self) -> bool {
        self.bounce > 0.0
    }

    /// The velocity of a node contact's node, now `v`, once the contact is solved with `keep`
    /// of its bounce and the node takes the whole change (an upper bound when a dynamic body
    /// takes a share).
    pub fn node_velocity(&self, v: Vector, keep: Real) -> Vector {
        let target = self.target - self.bounce * (1.0 - keep);
        v + self.normal * (target - self.found).max(0.0)
    }

    /// Keeps only `keep` (0–1) of the contact's bounce.
    pub fn keep_bounce(&mut self, keep: Real) {
        self.target -= self.bounce * (1.0 - keep);
        self.bounce *= keep;
    }

    /// Leaves the dynamic body out of this contact's impulses until its block solve.
    pub fn defer_body(&mut self) {
        self.deferred = true;
    }

    /// Whether the dynamic body still has this contact's impulses to take.
    pub fn deferred(&self) -> bool {
        self.deferred
    }

    /// Adds the dynamic body it pushed (with a non-zero normal impulse), if any, to `pushed`.
    fn note_pushed(
        &self,
        candidates: &[Candidate<'_>],
        motions: &[BodyMotion],
        pushed: &mut Vec<RigidBodyHandle>,
    ) {
        if self.normal_impulse > 0.0 {
            if let Some(b) = candidates[self.candidate].rigid(motions) {
                if !pushed.contains(&b) {
                    pushed.push(b);
                }
            }
        }
    }

    /// The contact point's material point on a dynamic body's present pose.
    pub fn anchor(&self) -> Vector {
        self.anchor
    }

    /// The deformable side's nodes that move (a bone's node does not), with their weights.
    pub fn moving_nodes(&self) -> impl Iterator<Item = (usize, Real)> + '_ {
        (0..FACET_ARITY)
            .filter(|&a| self.inv_masses[a] > 0.0 && self.weights[a] > 0.0)
            .map(|a| (self.nodes[a] as usize, self.weights[a]))
    }

    /// The deformable side's velocity at the contact.
    pub(crate) fn velocity(&self, velocities: &[Vector]) -> Vector {
        (0..FACET_ARITY)
            .map(|a| velocities[self.nodes[a] as usize] * self.weights[a])
            .sum()
    }

    /// The deformable side's inverse mass at the contact: `Σ w² / m`.
    pub(super) fn inv_mass(&self) -> Real {
        (0..FACET_ARITY)
            .map(|a| self.weights[a] * self.weights[a] * self.inv_masses[a])
            .sum()
    }

    /// Counts this contact once on each node it acts on, in `counts`.
    pub(super) fn count_nodes(&self, counts: &mut [Real]) {
        for a in 0..FACET_ARITY {
            if self.weights[a] > 0.0 {
                counts[self.nodes[a] as usize] += 1.0;
            }
        }
    }

    /// [`Contact::inv_mass`] with each node's mass split among the `counts` contacts on it.
    pub(super) fn split_inv_mass(&self, counts: &[Real]) -> Real {
        (0..FACET_ARITY)
            .map(|a| {
                let share = counts[self.nodes[a] as usize].max(1.0);
                self.weights[a] * self.weights[a] * self.inv_masses[a] * share
            })
            .sum()
    }

    /// `impulse` on the deformable's side alone.
    pub(super) fn give(&self, impulse: Vector, velocities: &mut [Vector]) {
        for a in 0..FACET_ARITY {
            velocities[self.nodes[a] as usize] += impulse * (self.weights[a] * self.inv_masses[a]);
        }
    }

    /// `impulse` on the deformable's side, its opposite on a dynamic body (unless deferred).
    fn apply(
        &self,
        impulse: Vector,
        velocities: &mut [Vector],
        cand: &Candidate<'_>,
        at: &Substep<'_>,
        bodies: &mut RigidBodySet,
    ) {
        self.give(impulse, velocities);
        if !self.deferred {
            cand.apply_impulse(-impulse, self.anchor, at.motions, bodies, at.dt);
        }
    }

    /// One Gauss–Seidel update: the normal impulse towards the target, then friction.
    fn solve(
        &mut self,
        velocities: &mut [Vector],
        at: &Substep<'_>,
        candidates: &[Candidate<'_>],
        bodies: &mut RigidBodySet,
    ) {
        let (s1, dt, motions) = (at.s1, at.dt, at.motions);
        let cand = &candidates[self.candidate];
        let n = self.normal;
        let own = self.inv_mass();
        let (point, anchor) = (self.point, self.anchor);
        let relative = |this: &Self, velocities: &[Vector], bodies: &RigidBodySet| {
            this.velocity(velocities)
                - cand.anchored_velocity(point, anchor, s1, dt, motions, bodies)
        };
        let deferred = self.deferred;
        let body_at = |dir: Vector, bodies: &RigidBodySet| {
            if deferred {
                0.0
            } else {
                cand.inv_mass_at(anchor, dir, motions, bodies)
            }
        };
        let k = own + body_at(n, bodies);
        if k > 0.0 {
            let vn = relative(self, velocities, bodies).dot(n);
            let total = (self.normal_impulse + (self.target - vn) / k).max(0.0);
            let dj = total - self.normal_impulse;
            self.normal_impulse = total;
            self.apply(n * dj, velocities, cand, at, bodies);
        }
        if cand.friction <= 0.0 {
            return;
        }
        let vr = relative(self, velocities, bodies);
        let vt = vr - n * vr.dot(n);
        let slip = vt.length();
        let mut total = self.friction_impulse;
        if slip > 0.0 {
            let t = vt / slip;
            let kt = own + body_at(t, bodies);
            if kt > 0.0 {
                total -= t * (slip / kt);
            }
        }
        let total = super::coulomb(total, cand.friction * self.normal_impulse);
        let dj = total - self.friction_impulse;
        self.friction_impulse = total;
        self.apply(dj, velocities, cand, at, bodies);
    }
}
