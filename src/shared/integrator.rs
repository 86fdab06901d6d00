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
use super::contact::soft_terms;
use super::math::Rotation;
use super::math::{Matrix, Real, Vector};
use super::model::{self, Hold, Solve, StepInput};

mod midpoint;
#[cfg(feature = "serde")]
pub(crate) use midpoint::MidpointCarry;
pub(crate) use midpoint::{MidpointState, Rebound};

/// How long the next substep may be at the body's current state.
#[derive(Copy, Clone, Debug)]
pub(crate) struct Bound {
    /// The integrator's own stability bound (s) as estimated, before the pipeline's safety
    /// factor.
    pub stable: Real,
    /// A bound (s) the substep never exceeds whatever the safety factor: for the explicit
    /// step, the uncalibrated per-node bound, which is rigorous.
    pub certain: Real,
    /// The crossing limiter's bound (s): no node crosses its opposite facet's plane within it,
    /// whatever the integrator (infinite for models without one).
    pub limiter: Real,
}

impl Bound {
    /// The stability bound under `safety` ([`model::substep_under`]).
    pub fn under(&self, safety: Real, calibrated: bool) -> Real {
        model::substep_under(self.stable, self.certain, safety, calibrated)
    }
}

/// What the contacts did, for [`Integrate::after_contacts`].
#[derive(Copy, Clone)]
pub(crate) struct AfterContacts<'a> {
    /// The velocities before the contacts.
    pub before: &'a [Vector],
    /// Per node, the point (at the collider's pose at the end of the substep) and normal of
    /// the collider surface that stopped it (it may lift off along the normal).
    pub lift: &'a [Option<(Vector, Vector)>],
    /// Per node, its share of the dynamic bodies its contacts met that are lighter than the
    /// deformable (zero for none; empty when no node meets one): it carries them
    /// ([`Hold::Carries`]) instead of being held where they go.
    pub carried: &'a [Real],
    /// Per node that carries, the velocity what it carries brings (empty when `carried` is).
    pub carried_velocity: &'a [Vector],
    /// Per node, whether a contact with a fixed or kinematic collider found it, when the body's
    /// rigid motion answered those contacts first ([`contact::rigid_answer`]; empty when it did
    /// not): such a node is held where its velocity takes it even if its own contact had
    /// nothing left to do, and the sweeps start where the velocities take the body.
    ///
    /// [`contact::rigid_answer`]: super::contact::rigid_answer
    pub touched: &'a [bool],
}

/// One way of advancing a body's velocities over a substep.
pub(crate) trait Integrate {
    /// The bound at the current state, its estimate calibrated by the body's slack if
    /// `calibrated` (else the certain bound); the element forces are current when it is called.
    fn bound(&self, body: &Deformable, calibrated: bool) -> Bound;

    /// Advances every node's velocity over `h` under the element forces and gravity `g`
    /// (bones and contacts come after, in the loop; `contacts_follow` when the body has
    /// contact candidates this substep).
    fn advance_velocities(&self, body: &mut Deformable, g: Vector, h: Real, contacts_follow: bool);

    /// After the bones and the contacts set some nodes' velocities, lets the others answer
    /// them within the substep; returns whether it did (then the loop solves the contacts
    /// once more), with `reactions` the force each held node's hold exerted on it over the
    /// substep (empty when none). Explicit integrators leave it to the next substep.
    fn after_contacts(
        &self,
        _body: &mut Deformable,
        _g: Vector,
        _h: Real,
        _at: AfterContacts<'_>,
        reactions: &mut Vec<Vector>,
    ) -> bool {
        reactions.clear();
        false
    }

    /// After the loop moved `body`'s positions by its velocities over the substep: lets a
    /// scheme whose position update is not by the end velocities set those.
    fn after_move(&self, _body: &mut Deformable) {}

    /// Whether the step reads the element forces ([`Deformable::refresh_forces`]) for `body`.
    fn uses_forces(&self, _body: &Deformable) -> bool {
        true
    }

    /// Whether [`Integrate::after_contacts`] does anything for `body`.
    fn answers_contacts(&self, _body: &Deformable) -> bool {
        false
    }

    /// Solves an island's members together with the contact `terms` between them, in place
    /// of [`Integrate::after_contacts`] (their velocities advanced and their collider contacts
    /// solved once); returns whether it did. Explicit integrators leave such contacts to the
    /// velocities after their step.
    ///
    /// `step`: the substep `h` and the speed (m/s) below which the solve counts as settled: it
    /// may stop once a pass moves no node faster.
    fn solve_together(
        &self,
        _members: &mut [Together<'_>],
        _terms: &mut soft_terms::Terms,
        _step: (Real, Real),
    ) -> bool {
        false
    }
}

/// Symplectic (semi-implicit) Euler: `v += (f/m + g) h`, then `x += v h` in the loop. Stable
/// below `2/ω` per node, damping included ([`model::stable_substeps`]).
#[derive(Copy, Clone, Debug, Default)]
pub(crate) struct SymplecticEuler;

impl Integrate for SymplecticEuler {
    fn bound(&self, body: &Deformable, calibrated: bool) -> Bound {
        let acc = &body.step.acc;
        let slack = if calibrated {
            body.rest.slack(&body.state.elements)
        } else {
            model::Slack::NONE
        };
        let (stable, certain) =
            model::stable_substeps(&body.rest.masses, &acc.stiffness, &acc.damping, slack);
        Bound {
            stable,
            certain,
            limiter: body.step.limiter,
        }
    }

    fn advance_velocities(&self, body: &mut Deformable, g: Vector, h: Real, _: bool) {
        let force = &body.step.acc.force;
        let inv_masses = &body.rest.inv_masses;
        // Node by node, on rayon's threads for a large body.
        super::threads::for_each_mut(&mut body.state.velocities, |i, v| {
            *v += (force[i] * inv_masses[i] + g) * h;
        });
    }
}

/// Which integrator steps the deformables ([`PipelineSettings::integrator`](super::PipelineSettings::integrator)).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Integrator {
    /// Symplectic Euler in substeps under the stability bound, the papers' integrator, which
    /// [`Integrator::Auto`] (the default) takes wherever it is cheap. Undamped free motion keeps its energy: the reported energy oscillates about
    /// a constant by O(h·ω) (5–14 % for a 5 % free vibration at the automatic substep of a
    /// 60 Hz step, 1 % at h = 1/600 s), with no trend beyond 0.05 % in 10 s at h = 1/600 s
    /// for any model (`tests/shared/energy.rs`). At the automatic substep nonlinear
    /// springs, which stiffen as they shorten, can gain: +3.7 % in 10 s for that vibration;
    /// lower [`PipelineSettings::safety`](super::PipelineSettings::safety) there.
    Explicit,
    /// Backward Euler by Vertex Block Descent: one substep per step, `iterations` Gauss–Seidel
    /// sweeps of per-node Newton steps (the cost knob; `docs/ARCHITECTURE.md` §4.2). A body
    /// with contact candidates first takes one sweep to find where it is going, the contacts
    /// act on that, then `iterations` sweeps answer them with the nodes they stopped held.
    /// Every model but centroid springs, which steps explicitly. Shape-matched deformables
    /// that may touch (or have self contact on) are solved as one island with their contacts;
    /// islands of the other models step explicitly (`docs/ARCHITECTURE.md` §4.2).
    ///
    /// Backward Euler damps deformation: undamped, a free vibration of the soft box of
    /// `tests/shared/energy.rs` (E = 10⁴ Pa) loses 17–28 % of its energy in 10 s at 60 Hz. Its
    /// prediction carries a body's rigid turn on, so a spin is kept: the same box tumbling at
    /// 1.5 rad/s keeps its energy to 0.02 % and its angular momentum to 0.2 % (made stiff,
    /// E = 10⁷–10⁸ Pa, edge repulsion, 2 or 10 sweeps: energy within +0.3–1.9 %). Use the
    /// explicit step, or [`Integrator::Midpoint`], where a ring must last.
    ///
    /// A few sweeps do not converge on a stiff, slender body, whose bending carries a load
    /// across many cells: released under its weight, the 10:1 cantilever of `scenes bending`
    /// (E = 10⁸ Pa, 1000 kg/m³, 5 nodes across) hangs straight at 60 Hz even with 50 sweeps.
    /// A Newton step over the whole body before the sweeps
    /// ([`PipelineSettings::global_iterations`](super::PipelineSettings::global_iterations),
    /// taken by default by bodies that stiff for the step, [`GLOBAL_SUBSTEPS`]) makes it ring at
    /// 4.8 Hz (Euler–Bernoulli: 5.1; shape matching 4.9) about 13.0–13.6 mm of sag (14.9),
    /// about 30× cheaper than the explicit step.
    Implicit {
        /// Sweeps per step.
        iterations: usize,
    },
    /// Implicit midpoint by Vertex Block Descent: the implicit step over half the step, its
    /// motion then carried on to the step's end, so that undamped motion keeps its energy and
    /// its angular momentum (a spin, a ring) where backward Euler removes some of each every
    /// step. Unconverged sweeps can make the midpoint rule unstable on a stiff body, so the
    /// body keeps its angular momentum exactly and ends each step with the energy the step
    /// owes it (what it had at the start less what the sweeps, the damping or backward Euler
    /// lost), set through its motion relative to its rigid motion; an excess that lies in its
    /// elastic energy the next steps remove by backward Euler (`integrator/midpoint.rs` tells
    /// how). Bodies
    /// bound to bones (unless
    /// [`PipelineSettings::global_iterations`](super::PipelineSettings::global_iterations)
    /// solves them whole: their bones do work, so nothing holds their energy and their solve must
    /// converge), steps in which a contact acts (or may act on a body still ringing from a
    /// contact), and islands solved with their contacts take backward Euler as
    /// [`Integrator::Implicit`] does, with the same `iterations`; but a body (no bone, no other
    /// deformable near, no self contact) whose centre of mass closes on a collider faster than
    /// the restitution threshold plus twice what gravity adds in a step takes that impact in
    /// explicit substeps, from the step in which one of its nodes may strike the collider
    /// until it leaves it (at most 0.1 s after the last strike), so that it bounces as it
    /// would at 1 ms
    /// (`pipeline/impact.rs`; with fixed substeps, or if the explicit step would take more
    /// than 1000 substeps a step, it keeps the implicit one). A snapshot keeps the step's
    /// state between steps (`θ`, the energy ledger, the impact).
    ///
    /// Undamped, at 60 Hz with 2 sweeps, the box of `tests/shared/energy.rs` (E = 10⁴ Pa)
    /// tumbling at 1.5 rad/s keeps its angular momentum to 10⁻⁵ and its energy within 10⁻⁵
    /// over 10 s, where backward Euler loses 20 % and 38 %; let go from a 5 % stretch, it
    /// rings on within 10⁻⁴ of its energy. A 10 cm ball (E = 10⁵–10⁶ Pa) thrown at a wall at
    /// 2–5 m/s leaves it within 4 % of the explicit 1 ms run's speed (backward Euler: it
    /// sticks), and the `fall` cube's trajectory (edge repulsion, shape matching) is within
    /// 2–5 % of its size of the common reference (backward Euler: 44–48 %), at 3–6× less than
    /// the explicit step's cost; an impact's steps cost what the explicit step's do. With
    /// `global_iterations` 10, the clamped 10:1 cantilever of `scenes bending` (E = 10⁸ Pa,
    /// res 5) rings at 5.19 Hz (edge repulsion; shape matching 5.29) against Euler–Bernoulli's
    /// 5.11 (explicit at its own substeps: 5.33 and 5.43; backward Euler: 4.84 and 4.91).
    Midpoint {
        /// Sweeps per step.
        iterations: usize,
    },
    /// Per body: the explicit step where it is cheap, [`Integrator::Midpoint`] where the
    /// explicit step would take more than [`AUTO_SUBSTEPS`] substeps a step at rest (a stiff
    /// or finely meshed body at a game's frame rate). The choice follows the body's calibrated
    /// stable substep at rest and the step length, so it changes only with `dt`; the report
    /// says which ran ([`DeformableReport::implicit`](super::DeformableReport::implicit)).
    ///
    /// The default, with 2 sweeps: at 1 ms a soft body steps explicitly as it always did,
    /// and at a game's 60 Hz the 10 cm silicone ball of `scenes ball` (823 nodes, E = 1 MPa,
    /// 103 explicit substeps a step) lands and rests in 3.5 ms a step with edge repulsion,
    /// against 16 ms explicitly. A light rigid body resting on a body it steps implicitly
    /// creeps (up to 1.5 cm a second) and does not sleep: choose [`Integrator::Explicit`]
    /// for such a scene.
    Auto {
        /// Sweeps per implicit step.
        iterations: usize,
    },
}

impl Default for Integrator {
    /// [`Integrator::Auto`] with 2 sweeps.
    fn default() -> Self {
        Integrator::Auto { iterations: 2 }
    }
}

/// Explicit substeps a step above which [`Integrator::Auto`] takes the implicit step. An
/// implicit step with 2 sweeps costs 1–3 explicit substeps (the 10 cm silicone ball of `scenes
/// ball`, 823 nodes: edge repulsion 1.4 ms a step against 0.45 ms a substep, shape matching
/// 1.0 against 0.9), and the explicit step is the more accurate, so it keeps bodies up to a
/// little more than that.
pub const AUTO_SUBSTEPS: usize = 4;

/// Explicit substeps a step at rest above which the implicit steps take a Newton step over the
/// whole body before their sweeps, unless
/// [`PipelineSettings::global_iterations`](super::PipelineSettings::global_iterations) says
/// otherwise: a body that stiff for the step (`k h²/m` large) is one whose soft modes a few
/// Gauss–Seidel sweeps do not reach (the 10:1 cantilever of `scenes bending`, 746 at 60 Hz,
/// hangs straight under 50 sweeps), where bodies under it (the `fall` cube at res 9, 90; the
/// 10 cm silicone ball, 95; the pinch's pads, 125–302) move as they should without it, which
/// costs them 2.5–4× their sweeps.
pub const GLOBAL_SUBSTEPS: usize = 400;

/// The Newton iterations a body takes over its whole when [`GLOBAL_SUBSTEPS`] asks for them:
/// 5–10 converge the 10:1 cantilever.
pub const AUTO_GLOBAL_ITERATIONS: usize = 10;

impl Integrator {
    /// Whether the implicit steps are by the midpoint rule, with impacts taken explicitly.
    pub(crate) fn midpoint_rule(&self) -> bool {
        matches!(self, Integrator::Midpoint { .. } | Integrator::Auto { .. })
    }

    /// Whether `body` takes the implicit step (one substep per step).
    pub(crate) fn steps_implicitly(&self, body: &Deformable) -> bool {
        self.implicit_for(body).is_some()
    }

    /// Whether `body` takes the implicit step with its contacts with other bodies as terms
    /// ([`Integrate::solve_together`]). Not under [`Integrator::Auto`], whose islands of bodies
    /// that may touch step explicitly: solved together with its 2 sweeps, a 3D tower of six
    /// shape-matched cubes at 60 Hz sank 2.7 mm into itself, gained 0.8 % of its energy and
    /// slid 13 cm apart in 6 s (10 sweeps hold it).
    pub(crate) fn steps_together(&self, body: &Deformable) -> bool {
        !matches!(self, Integrator::Auto { .. })
            && self.steps_implicitly(body)
            && body.state.elements.has_convex_implicit()
    }

    /// Whether `body` takes the implicit step, and its sweeps.
    pub(crate) fn implicit_for(&self, body: &Deformable) -> Option<usize> {
        match *self {
            Integrator::Implicit { iterations } | Integrator::Midpoint { iterations }
                if body.state.elements.has_implicit() =>
            {
                Some(iterations.max(1))
            }
            Integrator::Auto { iterations }
                if body.step.auto_implicit && body.state.elements.has_implicit() =>
            {
                Some(iterations.max(1))
            }
            _ => None,
        }
    }
}

impl Integrate for Integrator {
    fn bound(&self, body: &Deformable, calibrated: bool) -> Bound {
        match self.implicit_for(body) {
            // Unconditionally stable, and the line search keeps cells upright.
            Some(_) => Bound {
                stable: Real::INFINITY,
                certain: Real::INFINITY,
                limiter: Real::INFINITY,
            },
            None => SymplecticEuler.bound(body, calibrated),
        }
    }

    fn advance_velocities(&self, body: &mut Deformable, g: Vector, h: Real, contacts_follow: bool) {
        let Some(iterations) = self.implicit_for(body) else {
            return SymplecticEuler.advance_velocities(body, g, h, contacts_follow);
        };
        // Bound nodes keep the velocity the last bone drive gave them; the drive follows. When
        // contacts follow, this solve only tells them where the body is going (the solve after
        // them starts afresh): one sweep.
        if self.midpoint_rule() && !contacts_follow && takes_midpoint(body) {
            return midpoint_pass(body, g, h, iterations);
        }
        if !contacts_follow {
            body.step.midpoint.forget();
        }
        let held = held_nodes(body, h, None);
        if contacts_follow {
            // Where the body is going, for the contacts: the solve after them starts afresh,
            // so this one takes neither the Newton step over the body nor more than a sweep.
            let global = std::mem::take(&mut body.step.global_iterations);
            implicit_pass(body, g, h, 1, &held, false, &mut Vec::new());
            body.step.global_iterations = global;
        } else {
            implicit_pass(body, g, h, iterations, &held, false, &mut Vec::new());
        }
    }

    fn after_move(&self, body: &mut Deformable) {
        midpoint::finish(body);
    }

    fn answers_contacts(&self, body: &Deformable) -> bool {
        self.implicit_for(body).is_some()
    }

    fn solve_together(
        &self,
        members: &mut [Together<'_>],
        terms: &mut soft_terms::Terms,
        step: (Real, Real),
    ) -> bool {
        self.implicit_together(members, terms, step)
    }

    /// The implicit step evaluates its own terms.
    fn uses_forces(&self, body: &Deformable) -> bool {
        self.implicit_for(body).is_none()
    }

    fn after_contacts(
        &self,
        body: &mut Deformable,
        g: Vector,
        h: Real,
        at: AfterContacts<'_>,
        reactions: &mut Vec<Vector>,
    ) -> bool {
        reactions.clear();
        let Some(iterations) = self.implicit_for(body) else {
            return false;
        };
        let held = held_nodes(body, h, Some(at));
        let stopped = held
            .iter()
            .enumerate()
            .any(|(i, x)| *x != Hold::Free && !body.is_attached(i as u32));
        if stopped {
            // The nodes the contacts set are held where their velocities take them; the
            // others answer them in the same step, from the start.
            let warm = !at.touched.is_empty();
            implicit_pass(body, g, h, iterations, &held, warm, reactions);
        } else if self.midpoint_rule() && takes_midpoint(body) && body.step.midpoint.in_flight() {
            // No contact acted on a body in flight by the midpoint step (not one still ringing
            // from a contact or an impact, which backward Euler settles): its step, from the
            // start.
            body.state
                .velocities
                .copy_from_slice(&body.step.scratch_velocities);
            midpoint_pass(body, g, h, iterations);
        } else if iterations > 1 {
            // No contact acted: the prediction was the step; it takes the remaining sweeps.
            implicit_pass(body, g, h, iterations - 1, &held, true, reactions);
        }
        true
    }
}

/// A member of an island the implicit step solves with its contacts between deformables
/// ([`Integrator::solve_together`]).
pub(crate) struct Together<'a> {
    pub body: &'a mut Deformable,
    /// Simulated this step; a still member's nodes stay put.
    pub live: bool,
    pub g: Vector,
    /// The velocities before the collider contacts, and where those left each node.
    pub before: Vec<Vector>,
    pub lift: Vec<Option<(Vector, Vector)>>,
    pub carried: Vec<Real>,
    pub carried_velocity: Vec<Vector>,
    /// Out: the force each held node's hold exerted on it over the step.
    pub reactions: Vec<Vector>,
}

/// Fewest sweeps an island solved with its contact terms is given (it stops sooner once
/// settled): with two, a cube dropped on another (`StackScene`) ended 51 mm inside it in 3D;
/// with four, 0.2 mm.
const MIN_TOGETHER_SWEEPS: usize = 4;

impl Integrator {
    /// [`Integrate::solve_together`] for the implicit step: an island whose members may touch
    /// each other (or themselves):
    /// after each member's first sweep and its collider contacts, the members' sweeps run in
    /// turn, each node's Newton step taking in the contact `terms` it is part of
    /// ([`soft_terms`]), then the terms' dual update; the velocities are the result. The
    /// sweeps stop early once one moves no node faster than `settled` (m/s): a pile at rest
    /// takes one or two. Returns `false` (and does nothing) unless every live member takes
    /// the implicit step.
    fn implicit_together(
        &self,
        members: &mut [Together<'_>],
        terms: &mut soft_terms::Terms,
        (h, settled): (Real, Real),
    ) -> bool {
        let mut iterations = 0;
        for m in members.iter().filter(|m| m.live) {
            match self.implicit_for(m.body) {
                Some(k) => iterations = k,
                None => return false,
            }
        }
        let iterations = iterations.max(MIN_TOGETHER_SWEEPS);
        let nodes: Vec<usize> = members.iter().map(|m| m.body.num_nodes()).collect();
        let holds: Vec<Vec<Hold>> = members
            .iter()
            .map(|m| {
                let at = AfterContacts {
                    before: &m.before,
                    lift: &m.lift,
                    carried: &m.carried,
                    carried_velocity: &m.carried_velocity,
                    touched: &[],
                };
                held_nodes(m.body, h, Some(at))
            })
            .collect();
        terms.index(&nodes, |m, i| {
            members[m].live
                && matches!(
                    holds[m][i as usize],
                    Hold::At(_) | Hold::Pressed(_) | Hold::Contact { .. }
                )
        });
        // A member that neither a collider stopped nor another member touches goes on from
        // where its first sweep went; the others start afresh (as [`Integrate::after_contacts`]
        // does): a first sweep blind to the member under it let a body resting on it fall
        // `g h²`, which the sweeps then spent their passes taking back.
        let starts: Vec<Option<Vec<Vector>>> = members
            .iter()
            .zip(&holds)
            .enumerate()
            .map(|(k, (m, held))| {
                let body = &*m.body;
                let stopped = held
                    .iter()
                    .enumerate()
                    .any(|(i, x)| *x != Hold::Free && !body.is_attached(i as u32));
                (!stopped && terms.none_for(k)).then(|| {
                    let x0 = &body.state.positions;
                    x0.iter()
                        .zip(&body.state.velocities)
                        .map(|(x, v)| *x + *v * h)
                        .collect()
                })
            })
            .collect();
        let mut xs: Vec<Vec<Vector>> = members
            .iter()
            .map(|m| m.body.state.positions.clone())
            .collect();
        let mut reactions: Vec<Vec<Vector>> = vec![Vec::new(); members.len()];
        let rotations: Vec<Option<Vec<Rotation>>> = {
            let solves: Vec<Option<Solve<'_>>> = members
                .iter()
                .zip(&holds)
                .zip(&starts)
                .zip(xs.iter_mut())
                .map(|(((m, held), start), x)| {
                    if !m.live {
                        return None;
                    }
                    let body = &*m.body;
                    let input = StepInput {
                        x0: &body.state.positions,
                        v0: &body.step.scratch_velocities,
                        masses: &body.rest.masses,
                        held,
                        start: start.as_deref(),
                        gravity: m.g,
                        h,
                        iterations,
                        global: 0,
                        chords: true,
                    };
                    body.state.elements.begin_implicit(&input, x)
                })
                .collect();
            let mut last: Vec<Vec<Vector>> = Vec::new();
            for sweep in 0..iterations {
                last.clone_from(&xs);
                let backward = sweep % 2 == 1;
                for j in 0..members.len() {
                    let k = if backward { members.len() - 1 - j } else { j };
                    let Some(solve) = &solves[k] else {
                        continue;
                    };
                    let mut x = std::mem::take(&mut xs[k]);
                    let plain = terms.none_for(k);
                    solve.sweep(&mut x, backward, |i, own, f, block| {
                        if !plain {
                            terms.add((k, i), own, &xs, f, block);
                        }
                    });
                    xs[k] = x;
                }
                move_as_wholes(&solves, terms, &mut xs);
                terms.update(&xs);
                let fastest = xs
                    .iter()
                    .zip(&last)
                    .flat_map(|(x, last)| x.iter().zip(last).map(|(p, q)| (*p - *q).length()))
                    .fold(0.0, Real::max);
                if fastest < settled * h {
                    break;
                }
            }
            solves
                .into_iter()
                .zip(xs.iter_mut())
                .zip(reactions.iter_mut())
                .enumerate()
                .map(|(k, ((solve, x), reactions))| {
                    // A member that touches no other moves freely as a whole.
                    solve.and_then(|s| s.finish(x, reactions, terms.none_for(k)))
                })
                .collect()
        };
        for (((m, x), rotations), (held, r)) in members
            .iter_mut()
            .zip(&xs)
            .zip(rotations)
            .zip(holds.iter().zip(reactions))
        {
            if !m.live {
                continue;
            }
            let body = &mut *m.body;
            body.state.elements.keep_rotations(rotations);
            let x0 = &body.state.positions;
            for (i, v) in body.state.velocities.iter_mut().enumerate() {
                if !matches!(held[i], Hold::At(_)) {
                    *v = (x[i] - x0[i]) / h;
                }
            }
            m.reactions = r;
        }
        true
    }
}

/// The Newton steps of the translation of each member that no collider or bone holds and
/// that takes part in a contact term ([`soft_terms`]: what a node's step cannot do alone).
fn move_as_wholes(solves: &[Option<Solve<'_>>], terms: &soft_terms::Terms, xs: &mut [Vec<Vector>]) {
    for (k, solve) in solves.iter().enumerate() {
        let Some(solve) = solve.as_ref().filter(|s| s.all_free()) else {
            continue;
        };
        if terms.none_for(k) {
            continue;
        }
        // Two steps: the first may cross where a term starts or stops pushing.
        for _ in 0..2 {
            let (mut f, inertia) = solve.inertia_as_a_whole(&xs[k]);
            let mut block = Matrix::IDENTITY * inertia;
            terms.add_translation(k, xs, &mut f, &mut block);
            let shift = block.inverse() * f;
            if !shift.is_finite() {
                break;
            }
            xs[k].iter_mut().for_each(|p| *p += shift);
        }
    }
}

/// How each node is held: a bound node where its bone takes it, and (after the contacts) a
/// node whose velocity a contact changed where that velocity takes it, free to lift off a
/// collider along its normal.
fn held_nodes(body: &Deformable, h: Real, after: Option<AfterContacts<'_>>) -> Vec<Hold> {
    let (x0, v) = (&body.state.positions, &body.state.velocities);
    (0..x0.len())
        .map(|i| {
            let at = x0[i] + v[i] * h;
            if body.is_attached(i as u32) {
                return Hold::At(at);
            }
            match after {
                Some(a) if v[i] != a.before[i] && a.carried.get(i).is_some_and(|&m| m > 0.0) => {
                    Hold::Carries {
                        target: x0[i] + a.carried_velocity[i] * h,
                        mass: a.carried[i],
                    }
                }
                Some(a) if v[i] != a.before[i] || a.touched.get(i) == Some(&true) => {
                    match a.lift[i] {
                        Some((point, normal)) => {
                            // If it lifts off, the lowest it may end: where the contact set it less
                            // the part of that which rises from where it was (a bounce), but never
                            // under the collider's surface (a collider moving into it carries it).
                            let rise = normal.dot(at - x0[i]).max(0.0);
                            let off = normal.dot(at - point).max(0.0);
                            Hold::Contact {
                                target: at,
                                normal,
                                low: at - normal * rise.min(off),
                            }
                        }
                        None => Hold::Pressed(at),
                    }
                }
                _ => Hold::Free,
            }
        })
        .collect()
}

/// Whether `body` takes the midpoint step where nothing touches it: a body bound to bones only
/// when it is solved whole (`integrator/midpoint.rs` tells why).
fn takes_midpoint(body: &Deformable) -> bool {
    body.bindings.len() == 0 || body.step.global_iterations > 0
}

/// The midpoint step of a body nothing touches, from its velocities at the start of the step,
/// or backward Euler if carrying its motion on would flatten a cell. Bound nodes are held where
/// their bones are at `θ h`.
fn midpoint_pass(body: &mut Deformable, g: Vector, h: Real, iterations: usize) {
    let theta = midpoint::begin(body);
    let held = held_nodes(body, theta * h, None);
    implicit_pass(
        body,
        g,
        theta * h,
        iterations,
        &held,
        false,
        &mut Vec::new(),
    );
    if !midpoint::keeps_cells(body, h, theta) {
        midpoint::as_backward_euler(body);
        let held = held_nodes(body, h, None);
        implicit_pass(body, g, h, iterations, &held, false, &mut Vec::new());
    }
    midpoint::record_work(body, h);
}

/// One implicit solve of `body` over `h` (free nodes from their velocity at the start of the
/// substep, `step.scratch_velocities`), the result turned into velocities; `warm` starts the
/// sweeps from where the current velocities lead.
fn implicit_pass(
    body: &mut Deformable,
    g: Vector,
    h: Real,
    iterations: usize,
    held: &[Hold],
    warm: bool,
    reactions: &mut Vec<Vector>,
) {
    let mut x = Vec::new();
    let start: Option<Vec<Vector>> = warm.then(|| {
        let x0 = &body.state.positions;
        x0.iter()
            .zip(&body.state.velocities)
            .map(|(x, v)| *x + *v * h)
            .collect()
    });
    let input = StepInput {
        x0: &body.state.positions,
        v0: &body.step.scratch_velocities,
        masses: &body.rest.masses,
        held,
        start: start.as_deref(),
        gravity: g,
        h,
        iterations,
        global: body.step.global_iterations,
        chords: !body.step.midpoint.under_way(),
    };
    body.state.elements.implicit_step(&input, &mut x, reactions);
    let x0 = &body.state.positions;
    for (i, v) in body.state.velocities.iter_mut().enumerate() {
        if !matches!(held[i], Hold::At(_)) {
            *v = (x[i] - x0[i]) / h;
        }
    }
}
