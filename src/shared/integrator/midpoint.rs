//! Implicit midpoint by Vertex Block Descent ([`Integrator::Midpoint`](super::Integrator)), kept
//! stable and its momenta exact when the sweeps do not converge.
//!
//! **The step.** Implicit midpoint, `x₁ = x₀ + h v_½`, `v₁ = v₀ + h M⁻¹ F(x_½)` with
//! `x_½ = (x₀ + x₁)/2`, is backward Euler over `θ h`, `θ = ½`: the implicit step's sweeps find
//! `q = x_θ` from `x₀` and `v₀`, the positions move by `h v_θ`, `v_θ = (q − x₀)/(θ h)`, and the
//! step ends with `v₁ = v₀ + (v_θ − v₀)/θ`. `θ = 1` is backward Euler. Converged, `θ = ½` keeps
//! linear and angular momentum, and the energy of a quadratic one: it has no numerical damping,
//! where backward Euler multiplies a mode of frequency `ω` by `1/√(1 + ω²h²)` a step.
//!
//! **Unconverged sweeps.** A few Gauss–Seidel sweeps do not converge on a body much stiffer
//! than its inertia (`k h²/m ≫ 1`), and there the midpoint step is unstable: undamped, a
//! 1 × 0.6 × 0.4 m box (E = 10⁶–10⁸ Pa, 2 sweeps, 60 Hz) tumbling or ringing gained 17 % to
//! 10⁵-fold of its energy in 10 s, and its Gauss–Seidel sweeps, which do not conserve angular
//! momentum, turned its spin by up to 90°. (Backward Euler's own unconverged step turned it by
//! up to 38° and gained up to 49 %.) So after each step the body (which nothing outside
//! touches: a midpoint step is taken only then) gets back what no force of its own could have
//! changed:
//! 1. its angular momentum about its centre of mass (gravity exerts no torque there), exactly,
//!    by a rigid rotation added to its velocities;
//! 2. its internal energy (kinetic about the centre of mass, plus elastic), set to what the
//!    step owes it, through the velocities relative to the body's rigid motion (which changes
//!    neither momentum; raised by at most [`LIFT`] of that motion's energy a step). Converged,
//!    the step changes the kinetic energy by exactly the work of the forces at the solve's
//!    point over the step's motion, `h Σ F(x_θ)·v_θ`: `K` plus the potential that work
//!    measures is what the midpoint rule conserves. What the kinetic energy changed beyond it
//!    is the sweeps' error, or the damping's or backward Euler's loss: losses are kept (none
//!    of an undamped body at `θ = ½`, whose every loss is the sweeps'), a gain only makes up
//!    earlier losses (within [`SLACK`] of the energy). The step owes the body its energy at
//!    the start, changed by the losses kept. The body's discrete energy itself
//!    (a nonlinear body's oscillates about the conserved one, ±0.2 % for the soft box of
//!    `tests/shared/energy.rs`, and beats over seconds) is set to that, so it neither drifts
//!    nor beats; what a step cannot set (the relative motion too small) is carried to the
//!    next.
//! 3. a step whose carried motion would leave a cell flatter than the solve's line searches
//!    allow ([`keeps_cells`]) is solved again by backward Euler;
//! 4. `θ` rises toward backward Euler while the steps diverge: by [`RAISE`] after a step whose
//!    energy passed what it was owed by [`SPIKE`] of it, to 1 when the relative motion held less than the
//!    excess (it lies in the elastic energy, which backward Euler removes); it comes back to
//!    `½` by [`RELAX`] a step while they do not.
//!
//! The centre of mass moves exactly at `θ = ½` (the implicit step's best translation),
//! gravity included; at `θ > ½` it ends `(θ − ½) h² g` low. A step in which a contact acts,
//! and an island solved with its contacts, take backward Euler, as does a step in which a
//! contact may act on a body whose last step was not a midpoint step: a body still ringing
//! from a contact or an impact gained energy in midpoint steps near a floor (a 10 cm ball,
//! E = 10⁵ Pa, from 6.5 J to 11 J in 18 steps after leaving a crease), and backward Euler
//! settles that ring. So does a body bound to bones
//! unless it is solved whole (`PipelineSettings::global_iterations`): its bones do work and
//! exert torques, so it keeps neither momentum nor energy of its own, and only a converged
//! solve keeps its midpoint step stable. Its bound nodes are held where their bones are at
//! `θ h`.

use super::super::body::Deformable;
use super::super::math::{self, AngVector, Real, Vector};
use super::super::model::{Accumulator, MIN_STEP_VOLUME};

/// How much of a free body's energy the losses its steps keep may reach before later gains
/// no longer make them up.
pub(crate) const SLACK: Real = 0.02;
/// An excess over what a free body is owed, as a share of its energy (or of its centre's
/// kinetic energy if that is larger), that marks a diverging step.
pub(crate) const SPIKE: Real = 0.01;
/// How much `θ` rises after a diverging step.
pub(crate) const RAISE: Real = 0.1;
/// Most of the energy of a free body's motion relative to its rigid motion that a step may
/// add to bring its energy up to what it is owed.
pub(crate) const LIFT: Real = 0.01;
/// How much `θ` comes down a step, back to `½`, while the steps do not diverge.
pub(crate) const RELAX: Real = 0.01;

/// How much of its energy a free body is owed, carried between its midpoint steps.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub(crate) struct Ledger {
    /// What its steps lost beyond the work of its forces that later gains may make up (≤ 0,
    /// at least `−SLACK` of its energy).
    loss: Real,
    /// Its target energy less its energy at the end of its last step: what that step could not
    /// set through its motion.
    short: Real,
}

/// What the midpoint step of one body carries between steps.
#[derive(Clone, Debug)]
pub(crate) struct MidpointState {
    /// `θ` of the next step: `½`, or up to 1 after a step whose energy could not be held.
    theta: Real,
    /// What its energy is owed (`None` after a step in which something touched it).
    ledger: Option<Ledger>,
    /// The step under way.
    pending: Option<Pending>,
    /// How long the body stays in the impact it is in (s; zero when in none:
    /// `pipeline/impact.rs`).
    pub impact: Real,
    /// The body closes fast on a collider but its explicit step was found too costly for the
    /// impact: not asked again until it stops closing.
    pub too_stiff: bool,
    /// How it came off its last impact.
    pub rebound: Rebound,
}

/// How a body came off its last impact (`pipeline/impact.rs`): the speed its centre of mass
/// receded at afterwards, and that over the speed it had closed at.
#[derive(Copy, Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub(crate) struct Rebound {
    /// The closing speed of the centre as the impact under way began (0 in none).
    pub entry: Real,
    /// The fastest the centre receded since that impact began.
    pub recede: Real,
    /// The last finished impact's receding speed (0 before any).
    pub out: Real,
    /// The last finished impact's receding over closing speed, in `[0, 1]` (1 before any).
    pub ratio: Real,
}

impl Default for Rebound {
    fn default() -> Self {
        Rebound {
            entry: 0.0,
            recede: 0.0,
            out: 0.0,
            ratio: 1.0,
        }
    }
}

impl Rebound {
    #[cfg(feature = "serde")]
    fn is_valid(&self) -> bool {
        [self.entry, self.recede, self.out]
            .iter()
            .all(|s| s.is_finite() && *s >= 0.0)
            && (0.0..=1.0).contains(&self.ratio)
    }
}

/// What of a body's [`MidpointState`] a snapshot keeps: all but the step under way (a
/// snapshot is taken between steps).
#[cfg(feature = "serde")]
#[derive(Copy, Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct MidpointCarry {
    theta: Real,
    ledger: Option<Ledger>,
    impact: Real,
    too_stiff: bool,
    /// Absent in snapshots older than it: no impact seen.
    #[serde(default)]
    rebound: Rebound,
}

impl Default for MidpointState {
    fn default() -> Self {
        MidpointState {
            theta: 0.5,
            ledger: None,
            pending: None,
            impact: 0.0,
            too_stiff: false,
            rebound: Rebound::default(),
        }
    }
}

impl MidpointState {
    /// A step not taken by the midpoint rule: the ledger starts afresh at the next one.
    pub fn forget(&mut self) {
        self.ledger = None;
        self.pending = None;
    }

    /// Whether the last step was a midpoint step.
    pub fn in_flight(&self) -> bool {
        self.ledger.is_some()
    }

    /// Whether a midpoint step is under way ([`begin`] to [`finish`]).
    pub fn under_way(&self) -> bool {
        self.pending.is_some()
    }

    /// What a snapshot keeps.
    #[cfg(feature = "serde")]
    pub fn carry(&self) -> MidpointCarry {
        MidpointCarry {
            theta: self.theta,
            ledger: self.ledger,
            impact: self.impact,
            too_stiff: self.too_stiff,
            rebound: self.rebound,
        }
    }

    /// The state a snapshot kept, checked: `θ` in `[½, 1]`, a finite ledger whose losses are at most zero,
    /// an impact of zero to a second, finite rebound speeds of at least zero and a ratio in
    /// `[0, 1]`.
    #[cfg(feature = "serde")]
    pub fn from_carry(c: MidpointCarry) -> Result<Self, String> {
        let ledger_ok = c
            .ledger
            .is_none_or(|l| l.loss.is_finite() && l.loss <= 0.0 && l.short.is_finite());
        if !((0.5..=1.0).contains(&c.theta)
            && ledger_ok
            && (0.0..=1.0).contains(&c.impact)
            && c.rebound.is_valid())
        {
            return Err(format!("midpoint step state out of range: {c:?}"));
        }
        Ok(MidpointState {
            theta: c.theta,
            ledger: c.ledger,
            pending: None,
            impact: c.impact,
            too_stiff: c.too_stiff,
            rebound: c.rebound,
        })
    }
}

/// The midpoint step under way.
#[derive(Clone, Debug)]
struct Pending {
    v0: Vec<Vector>,
    theta: Real,
    /// No bone moves the body: its momentum and energy are its own to keep.
    free: bool,
    /// The body's internal energy, its kinetic part and its angular momentum at the start.
    energy: Real,
    kinetic: Real,
    momentum: AngVector,
    /// The work of the elastic forces at the solve's point over the step's motion.
    work: Real,
}

/// A body's motion about its centre of mass.
struct Internal {
    centre_velocity: Vector,
    /// Each node's offset from the centre of mass.
    offsets: Vec<Vector>,
    /// Kinetic energy about the centre of mass, plus elastic.
    energy: Real,
    /// Angular momentum about the centre of mass.
    momentum: AngVector,
}

/// [`Internal`] of `body`, whose elastic energy is `elastic`.
fn internal(body: &Deformable, elastic: Real) -> Internal {
    let (x, v, m) = (
        &body.state.positions,
        &body.state.velocities,
        &body.rest.masses,
    );
    let centre = body.center_of_mass();
    let centre_velocity = body.center_of_mass_velocity();
    let offsets: Vec<Vector> = x.iter().map(|p| *p - centre).collect();
    let mut kinetic = 0.0;
    let mut momentum = math::ANG_ZERO;
    for ((r, v), m) in offsets.iter().zip(v).zip(m) {
        let u = *v - centre_velocity;
        kinetic += 0.5 * m * u.length_squared();
        momentum += math::cross(*r, u * *m);
    }
    Internal {
        centre_velocity,
        offsets,
        energy: kinetic + elastic,
        momentum,
    }
}

/// Starts a midpoint step of a body that nothing touches (no bone, no contact candidate),
/// from its velocities at the start of the step: returns the `θ` its backward-Euler solve is
/// to take.
pub(crate) fn begin(body: &mut Deformable) -> Real {
    let theta = body.step.midpoint.theta;
    let (elastic, _) = body.measured_energy();
    let start = internal(body, elastic);
    body.step.midpoint.pending = Some(Pending {
        v0: body.state.velocities.clone(),
        theta,
        free: body.bindings.len() == 0,
        energy: start.energy,
        kinetic: start.energy - elastic,
        momentum: start.momentum,
        work: 0.0,
    });
    theta
}

/// Records the work of the elastic forces over the step under way, once its solve left the
/// velocities `v_θ` at the start positions: `h Σ F(x_θ)·v_θ`.
pub(crate) fn record_work(body: &mut Deformable, h: Real) {
    let Some(theta) = body
        .step
        .midpoint
        .pending
        .as_ref()
        .filter(|p| p.free)
        .map(|p| p.theta)
    else {
        return;
    };
    let q = carried(body, theta * h);
    let mut acc = Accumulator::new(q.len());
    let still = vec![Vector::ZERO; q.len()];
    // The forces alone: no crossing limiter.
    body.state
        .elements
        .accumulate_capped(&q, &still, &mut acc, 0.0);
    let work: Real = acc
        .force
        .iter()
        .zip(&body.state.velocities)
        .map(|(f, v)| f.dot(*v))
        .sum();
    if let Some(p) = &mut body.step.midpoint.pending {
        p.work = h * work;
    }
}

/// Makes the step under way backward Euler (`θ = 1`), for the solve to be taken again.
pub(crate) fn as_backward_euler(body: &mut Deformable) {
    let state = &mut body.step.midpoint;
    state.theta = 1.0;
    if let Some(p) = &mut state.pending {
        p.theta = 1.0;
    }
}

/// `body`'s positions carried on by its velocities for `t`.
fn carried(body: &Deformable, t: Real) -> Vec<Vector> {
    let (x0, v) = (&body.state.positions, &body.state.velocities);
    x0.iter().zip(v).map(|(x, v)| *x + *v * t).collect()
}

/// Whether carrying the solve's motion (the velocities, `v_θ`) on to the step's end keeps
/// every cell of `body` no flatter than [`MIN_STEP_VOLUME`] of its rest volume, or than the
/// solve left it: the solve's line searches keep `x_θ` upright, but `x₀ + h v_θ` goes
/// `1/θ` times as far (a soft box let go from half its length turned cells inside out).
pub(crate) fn keeps_cells(body: &Deformable, h: Real, theta: Real) -> bool {
    let (mid, end) = (carried(body, theta * h), carried(body, h));
    let mesh = &body.rest.mesh;
    (0..mesh.num_cells()).all(|c| {
        let q = mesh.cell_quality(c, &end);
        q >= MIN_STEP_VOLUME || q >= mesh.cell_quality(c, &mid)
    })
}

/// Ends a midpoint step after the positions moved by `h v_θ`: the end velocities, then, for a
/// free body, its angular momentum and energy kept (see the module docs). After a step
/// [`begin`] did not start (another integrator's), the ledger starts afresh.
pub(crate) fn finish(body: &mut Deformable) {
    let Some(pending) = body.step.midpoint.pending.take() else {
        body.step.midpoint.forget();
        return;
    };
    let theta = pending.theta;
    for (v, v0) in body.state.velocities.iter_mut().zip(&pending.v0) {
        *v = *v0 + (*v - *v0) / theta;
    }
    body.state.elements.refit_rotations(&body.state.positions);
    if !pending.free {
        // Its bones do work and exert torques: nothing of its own to keep.
        body.step.midpoint.ledger = None;
        return;
    }
    let (energy, momentum) = (pending.energy, pending.momentum);
    let (elastic, _) = body.measured_energy();
    let masses = &body.rest.masses;
    let now = internal(body, elastic);
    let turn = math::angular_velocity_for(&now.offsets, masses, momentum - now.momentum);
    for (v, r) in body.state.velocities.iter_mut().zip(&now.offsets) {
        *v += math::ang_cross(turn, *r);
    }
    let now = internal(body, elastic);
    let undamped = body.rest.params.undamped() && body.deformation_damping() == 0.0;
    let theta_half = pending.theta == 0.5;
    let state = &mut body.step.midpoint;
    let carried = state.ledger.unwrap_or_default();
    // What the step changed beyond the work of the body's forces (the solve's error, and the
    // damping's and backward Euler's losses): losses are kept, gains only up to earlier losses
    // (within `SLACK` of the energy).
    let injected = (now.energy - elastic) - pending.kinetic - pending.work;
    // Undamped at `θ = ½`, every loss is the sweeps': none is kept.
    let kept = if undamped && theta_half {
        0.0
    } else {
        injected.min(-carried.loss)
    };
    let loss = (carried.loss + kept).max(-SLACK * energy);
    let target = energy + carried.short + kept;
    let mut theta = (state.theta - RELAX).max(0.5);
    let spin = math::angular_velocity_for(&now.offsets, masses, now.momentum);
    let rigid = |r: Vector| now.centre_velocity + math::ang_cross(spin, r);
    let relative: Real = body
        .state
        .velocities
        .iter()
        .zip(&now.offsets)
        .zip(masses)
        .map(|((v, r), m)| 0.5 * m * (*v - rigid(*r)).length_squared())
        .sum();
    let excess = now.energy - target;
    // The energy is set to the target through the motion relative to the rigid one, which
    // changes neither momentum; raised by at most `LIFT` of that motion's energy.
    let change = excess.min(relative).max(-LIFT * relative);
    if change != 0.0 && relative > 0.0 {
        let scale = (1.0 - change / relative).max(0.0).sqrt();
        for (v, r) in body.state.velocities.iter_mut().zip(&now.offsets) {
            let w = rigid(*r);
            *v = w + (*v - w) * scale;
        }
    }
    // Rounding makes a tiny excess, even of a body moving rigidly (its internal energy about
    // zero: an edge-repulsion box at rest reads ±4·10⁻⁵ J): only one above `SPIKE` of the
    // energy or of the centre's kinetic energy marks a diverging step.
    let centre = 0.5 * masses.iter().sum::<Real>() * now.centre_velocity.length_squared();
    let tolerance = SPIKE * energy.max(centre);
    if excess - relative > tolerance {
        theta = 1.0;
    } else if excess > tolerance {
        theta = (body.step.midpoint.theta + RAISE).min(1.0);
    }
    let state = &mut body.step.midpoint;
    state.ledger = Some(Ledger {
        loss,
        short: target - (now.energy - change),
    });
    state.theta = theta;
}
