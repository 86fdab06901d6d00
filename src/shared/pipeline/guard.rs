//! Phase 3's check of an island the implicit step solved with its contacts between
//! deformables: a step that ends with more energy than it started with, or with a body
//! further inside another, is taken again by the explicit step.
//!
//! The island's solve minimises backward Euler's (or the midpoint rule's) incremental
//! potential with the contact terms added, which gives no energy and keeps the bodies apart
//! when its sweeps converge. They do not always: a node can be driven into a facet harder
//! than the contact's penalty holds it, stepped out of it at every substep and keep its speed
//! into it, while the push that answers it throws the other body; or it passes a facet between
//! the substeps' contact searches, where the explicit step's many small substeps would have met
//! it. Both are rare while a pile collapses and absent at rest, so the guard compares the
//! island's energy and deepest interpenetration at the end of the step with its start; a step
//! that gained more than [`ENERGY_SHARE`] of its energy scale, or ended a node deeper than
//! [`DEPTH_SHARE`] of the smallest member's extent inside another (and deeper than it
//! started), is rolled back (the members, the dynamic bodies they may push, their contact
//! memory) and taken again in at least [`SPLIT`] substeps (each finds its contacts afresh, and
//! a shorter step converges further); failing again, by the explicit substeps, which need no
//! convergence. (Straight to the explicit step, a shape-matched pile of fifty cubes cost 20 %
//! more than without the guard; through the shorter substeps, 15 % less, the explicit steps
//! being rarer than the sweeps' failures were costly.)
//!
//! The energy is each live member's kinetic, elastic and gravitational energy; an island with
//! a member bound to a bone is not checked (the bone does work on it).

use super::super::contact::soft_terms::Memory;
use super::super::math::Real;
use super::super::rapier::dynamics::RigidBodySet;
use super::substep::{self, Member, SubstepStats};
use super::{box_sides, StepContext};

/// Share of the island's energy scale a step may gain: the scale is the live members' kinetic
/// and elastic energy and each one's weight times its own extent (what a body resting on the
/// ground can give back).
pub(super) const ENERGY_SHARE: Real = 1e-3;

/// Substeps at least of a step taken again implicitly, before the explicit step.
pub(super) const SPLIT: usize = 4;

/// Share of the smallest live member's extent a node may end inside another member.
pub(super) const DEPTH_SHARE: Real = 1e-2;

/// The island at the start of the step: its energy and deepest interpenetration, and what a
/// rollback puts back.
pub(super) struct Guard {
    energy: Real,
    scale: Real,
    inside: Real,
    memories: Vec<Vec<Memory>>,
}

impl Guard {
    /// Before the substeps; `None` when the island is not checked.
    pub fn start(members: &[Member<'_, '_>], ctx: &StepContext<'_>) -> Option<Guard> {
        if members.iter().any(|m| m.live && m.body.bindings.len() > 0) {
            return None;
        }
        let (energy, scale) = energy(members, ctx);
        Some(Guard {
            energy,
            scale,
            inside: substep::deepest_inside(members),
            memories: members
                .iter()
                .map(|m| m.body.step.soft_memory.clone())
                .collect(),
        })
    }

    /// After the substeps: whether the step gained energy or sank a node into another body
    /// beyond the bounds; `taken`: the kinetic energy the damping of held bodies took within
    /// the substeps, counted back.
    pub fn failed(&self, members: &[Member<'_, '_>], ctx: &StepContext<'_>, taken: Real) -> bool {
        let (now, _) = energy(members, ctx);
        let now = now + taken;
        if now > self.energy + ENERGY_SHARE * self.scale {
            return true;
        }
        let smallest = members
            .iter()
            .filter(|m| m.live)
            .map(|m| box_sides(&m.body.state.positions).max_element())
            .fold(Real::INFINITY, Real::min);
        let inside = substep::deepest_inside(members);
        inside > self.inside && inside > DEPTH_SHARE * smallest
    }

    /// Puts the live members back at the start of the step, with the dynamic bodies they may
    /// push and their contact memory, ready for another run of the substeps.
    pub fn roll_back(&self, members: &mut [Member<'_, '_>], bodies: &mut RigidBodySet) {
        for (m, memory) in members.iter_mut().zip(&self.memories) {
            if !m.live {
                continue;
            }
            let body = &mut *m.body;
            body.step.restore(&mut body.state);
            body.step.soft_memory.clone_from(memory);
            body.step.midpoint.forget();
            body.last.contacts.clear();
            m.sc.rigid.backup.restore(bodies);
            let touch = &mut m.sc.touch;
            touch.pushed.clear();
            touch.touched_nodes.fill(false);
            touch.touched_colliders.fill(false);
            touch.last_contact.fill(None);
            m.stats = SubstepStats::default();
            m.touched.clear();
        }
    }
}

/// The live members' energy (kinetic, elastic, gravitational) and its scale
/// ([`ENERGY_SHARE`]).
fn energy(members: &[Member<'_, '_>], ctx: &StepContext<'_>) -> (Real, Real) {
    let (mut energy, mut scale) = (0.0, 0.0);
    for m in members.iter().filter(|m| m.live) {
        let body = &*m.body;
        let g = ctx.gravity * body.gravity_scale;
        let (kinetic, elastic) = (body.kinetic_energy(), body.elastic_energy());
        let weight = body.rest.masses.iter().sum::<Real>() * g.length();
        energy += kinetic + elastic + body.gravity_energy(g);
        scale += kinetic + elastic + weight * box_sides(&body.state.positions).max_element();
    }
    (energy, scale)
}
