//! The integrator seam: how a body's velocities advance over one substep.
//!
//! The substep loop (`pipeline/substep.rs`) owns the order of a substep: make the element
//! forces current, ask the integrator for its stability bound, choose the substep, let the
//! integrator advance the velocities, then drive the bones, solve the contacts on those
//! velocities and move the positions by them. The integrator sees only the body's elements,
//! through [`Deformable::refresh_forces`] (forces, per-node stiffness and damping bounds, the
//! crossing limiter) and the model's energy, never contacts or bindings. A second integrator
//! implements [`Integrate`] and the loop, the contacts and the attachments stay as they are.

use super::body::Deformable;
use super::math::{Real, Vector};
use super::model;

/// How long the next substep may be at the body's current state.
#[derive(Copy, Clone, Debug)]
pub(crate) struct Bound {
    /// The integrator's own stability bound (s), before the pipeline's safety factor.
    pub stable: Real,
    /// The crossing limiter's bound (s): no node crosses its opposite facet's plane within it,
    /// whatever the integrator (infinite for models without one).
    pub limiter: Real,
}

/// One way of advancing a body's velocities over a substep.
pub(crate) trait Integrate {
    /// The bound at the current state; the element forces are current when it is called.
    fn bound(&self, body: &Deformable) -> Bound;

    /// Advances every node's velocity over `h` under the element forces and gravity `g`
    /// (bones and contacts come after, in the loop).
    fn advance_velocities(&self, body: &mut Deformable, g: Vector, h: Real);
}

/// Symplectic (semi-implicit) Euler: `v += (f/m + g) h`, then `x += v h` in the loop. Stable
/// below `2/ω` per node, damping included ([`model::stable_substep`]).
#[derive(Copy, Clone, Debug, Default)]
pub(crate) struct SymplecticEuler;

impl Integrate for SymplecticEuler {
    fn bound(&self, body: &Deformable) -> Bound {
        let acc = &body.step.acc;
        Bound {
            stable: model::stable_substep(&body.rest.masses, &acc.stiffness, &acc.damping),
            limiter: body.step.limiter,
        }
    }

    fn advance_velocities(&self, body: &mut Deformable, g: Vector, h: Real) {
        let force = &body.step.acc.force;
        let inv_masses = &body.rest.inv_masses;
        for ((v, f), w) in body.state.velocities.iter_mut().zip(force).zip(inv_masses) {
            *v += (*f * *w + g) * h;
        }
    }
}
