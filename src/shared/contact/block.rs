//! A dynamic rigid body and every contact row that pushes it in a substep, solved as one
//! block: the body's velocity (all its degrees of freedom) is the unknown of a small Newton
//! solve, each row's impulse the exact answer of its node side to that velocity.
//!
//! Given the body's velocity `V`, a row's impulse `P(V)` is what its node side alone would
//! take: none if the nodes separate, else the normal impulse that reaches the row's target,
//! with the friction that stops the slip if that stays inside Coulomb's cone, or slides along
//! its edge. The body must then move as its free velocity less those impulses:
//! `R(V) = V − V_free + M⁻¹ Σ Jᵀ P(V) = 0`. `P` is piecewise linear in `V` and `R` monotone, so
//! Newton's method with the rows' states taken at each iterate (a semismooth Newton) reaches
//! the solution in a few iterations, however light the body is against its rows: a 0.1 kg box
//! squeezed between two pads whose contact nodes weigh ten times more is the solution's
//! business, not a sequence of one-sided pushes that sequential impulses would balance only
//! after hundreds of passes.
//!
//! The impulses written back are the rows' answers to the final velocity, and the body takes
//! exactly their opposite, so momentum is conserved whatever the iterate. Two rows sharing a
//! node (a node row and a facet row over it) see each other only through the body within one
//! solve; the caller solves the block again for that.

use super::super::coupling::{self, Substep};
use super::super::math::{self, AngVector, Real, Vector, TWIST_DIM};
use super::super::rapier::dynamics::{RigidBody, RigidBodyHandle, RigidBodySet};
use super::candidates::{refresh_poses, Candidate};
use super::solve::Contact;

/// Newton iterations at most; a solve whose rows keep their states ends sooner.
const NEWTON_ITERATIONS: usize = 16;
/// Halvings of a Newton step that does not lower the residual.
const HALVINGS: usize = 8;

/// One deformable's side of a block: its contact rows (those in `picked` push the body), its
/// velocities and candidates, and where in the step its substep is.
pub(crate) struct BlockSide<'s, 'c> {
    pub rows: &'s mut [Contact],
    pub picked: &'s [usize],
    pub velocities: &'s mut [Vector],
    pub candidates: &'s mut [Candidate<'c>],
    pub at: Substep<'s>,
    /// The dynamic bodies its contacts pushed this step (the body is added if its rows push it).
    pub pushed: &'s mut Vec<RigidBodyHandle>,
}

/// A row as the solve sees it.
struct Row {
    side: usize,
    row: usize,
    /// The node side's velocity at the contact without this row's impulse.
    free: Vector,
    /// Lever arm from the body's centre of mass, and the velocity rapier's step adds there by
    /// the end of the substep.
    arm: Vector,
    drift: Vector,
    /// The node side's inverse mass at the contact.
    own: Real,
    normal: Vector,
    target: Real,
    friction: Real,
    /// The impulse the row had given before this solve, and what of it the body took.
    old: Vector,
    body_old: Vector,
}

/// How a row's impulse changes with the body's velocity at its anchor.
enum Slope {
    /// Separating: no impulse.
    None,
    /// Sticking: the whole relative velocity is taken, `dP = dv / own`.
    Stick(Real),
    /// Pushing without friction: `dP = a (b · dv)`.
    Push(Vector, Vector),
    /// Sliding along slip direction `t` off normal `n`: `dP = a (n · dv)` plus the turn of the
    /// friction with the slip, `c (dv − t (t · dv) − n (n · dv))` (zero in 2D).
    Slide {
        a: Vector,
        n: Vector,
        t: Vector,
        c: Real,
    },
}

impl Row {
    /// The row's impulse (on the node side) when the body's point moves at `vb`.
    fn answer(&self, vb: Vector) -> (Vector, Slope) {
        let n = self.normal;
        let rel = self.free - vb;
        let vn = rel.dot(n);
        let pn = (self.target - vn) / self.own;
        if pn <= 0.0 {
            return (Vector::ZERO, Slope::None);
        }
        let scale = 1.0 / self.own;
        if self.friction <= 0.0 {
            return (n * pn, Slope::Push(n * scale, n));
        }
        let slip = rel - n * vn;
        let stick = -slip * scale;
        let limit = self.friction * pn;
        if stick.length() <= limit {
            return (n * pn + stick, Slope::Stick(scale));
        }
        let length = slip.length();
        let t = slip / length;
        let a = (n - t * self.friction) * scale;
        let c = limit / length;
        (n * pn - t * limit, Slope::Slide { a, n, t, c })
    }

    /// The body's velocity at the row's anchor.
    fn body_velocity(&self, v: Vector, w: AngVector) -> Vector {
        v + math::ang_cross(w, self.arm) + self.drift
    }
}

/// Solves body `body` with every row of `sides` that pushes it (see the module docs): updates
/// the rows' impulses, the nodes' velocities and the body's, and brings the body's candidates
/// to its new predicted pose.
pub(crate) fn solve(
    sides: &mut [BlockSide<'_, '_>],
    body: RigidBodyHandle,
    bodies: &mut RigidBodySet,
) {
    let Some(rb) = bodies.get(body) else {
        return;
    };
    let com = rb.center_of_mass();
    let rows = gather(sides, rb, com);
    if rows.is_empty() {
        return;
    }
    let response = |r: &Row, p: Vector| coupling::impulse_response(rb, com + r.arm, p);
    // The body's velocity without the rows' impulses.
    let mut free = math::twist_to_array(rb.linvel(), rb.angvel());
    for r in &rows {
        add(&mut free, response(r, r.body_old));
    }
    let mut twist = math::twist_to_array(rb.linvel(), rb.angvel());
    let (mut residual, mut jacobian) = evaluate(&rows, &response, twist, free);
    let mut norm = length(&residual);
    for _ in 0..NEWTON_ITERATIONS {
        if norm.is_nan() || norm <= 1e-7 {
            break;
        }
        let Some(step) = coupling::solve_dense(jacobian, residual) else {
            break;
        };
        // A full step where it lowers the residual, else the largest halving that does (the
        // rows' states switching between iterates may overshoot).
        let mut scale = 1.0;
        let mut accepted = false;
        for _ in 0..HALVINGS {
            let trial: [Real; TWIST_DIM] = std::array::from_fn(|k| twist[k] - step[k] * scale);
            let (r, j) = evaluate(&rows, &response, trial, free);
            let n = length(&r);
            if n < norm {
                (twist, residual, jacobian, norm) = (trial, r, j, n);
                accepted = true;
                break;
            }
            scale *= 0.5;
        }
        if !accepted {
            break;
        }
    }
    write_back(sides, &rows, twist, body, bodies);
}

/// The residual `R(V)` at the body's velocity `twist` and its Jacobian (by columns).
fn evaluate(
    rows: &[Row],
    response: &impl Fn(&Row, Vector) -> (Vector, AngVector),
    twist: [Real; TWIST_DIM],
    free: [Real; TWIST_DIM],
) -> ([Real; TWIST_DIM], [[Real; TWIST_DIM]; TWIST_DIM]) {
    let (v, w) = math::twist_from_array(&twist);
    let mut residual: [Real; TWIST_DIM] = std::array::from_fn(|k| twist[k] - free[k]);
    let mut jacobian = [[0.0; TWIST_DIM]; TWIST_DIM];
    for (c, col) in jacobian.iter_mut().enumerate() {
        col[c] = 1.0;
    }
    for r in rows {
        let (p, slope) = r.answer(r.body_velocity(v, w));
        add(&mut residual, response(r, p));
        if matches!(slope, Slope::None) {
            continue;
        }
        for (c, col) in jacobian.iter_mut().enumerate() {
            let mut unit = [0.0; TWIST_DIM];
            unit[c] = 1.0;
            let (uv, uw) = math::twist_from_array(&unit);
            let dv = uv + math::ang_cross(uw, r.arm);
            let dp = match slope {
                Slope::None => Vector::ZERO,
                Slope::Stick(s) => dv * s,
                Slope::Push(a, b) => a * b.dot(dv),
                Slope::Slide { a, n, t, c } => {
                    a * n.dot(dv) + (dv - t * t.dot(dv) - n * n.dot(dv)) * c
                }
            };
            add(col, response(r, dp));
        }
    }
    (residual, jacobian)
}

fn length(a: &[Real; TWIST_DIM]) -> Real {
    a.iter().map(|x| x * x).sum::<Real>().sqrt()
}

/// The rows of `sides` that push `rb`, each with its impulse so far taken out of its node
/// side's velocity.
fn gather(sides: &[BlockSide<'_, '_>], rb: &RigidBody, com: Vector) -> Vec<Row> {
    let mut rows = Vec::new();
    let mut shares = Vec::new();
    for (s, side) in sides.iter().enumerate() {
        // How many of the block's rows act on each node: each row meets a node it shares as a
        // particle of that fraction of its mass (mass splitting), so that rows solved side by
        // side within the block together give a shared node the mean of what each asks, not
        // the sum.
        shares.clear();
        shares.resize(side.velocities.len(), 0.0);
        for &k in side.picked {
            side.rows[k].count_nodes(&mut shares);
        }
        for &k in side.picked {
            let c = &side.rows[k];
            let cand = &side.candidates[c.candidate];
            let own = c.split_inv_mass(&shares);
            // A row whose nodes a bone holds: the body meets them as (nearly) immovable.
            let own = own.max(1e-3 * coupling::inv_mass_at(rb, c.anchor(), c.normal));
            if own <= 0.0 {
                continue;
            }
            let old = c.normal * c.normal_impulse + c.friction_impulse;
            rows.push(Row {
                side: s,
                row: k,
                free: c.velocity(side.velocities) - old * c.inv_mass(),
                arm: c.anchor() - com,
                drift: cand.drift * side.at.s1,
                own,
                normal: c.normal,
                target: c.target,
                friction: cand.friction,
                old,
                body_old: if c.deferred() { Vector::ZERO } else { old },
            });
        }
    }
    rows
}

/// Gives each row its answer to the body's velocity `twist` and the body their opposite.
fn write_back(
    sides: &mut [BlockSide<'_, '_>],
    rows: &[Row],
    twist: [Real; TWIST_DIM],
    body: RigidBodyHandle,
    bodies: &mut RigidBodySet,
) {
    let (v, w) = math::twist_from_array(&twist);
    for r in rows {
        let (p, _) = r.answer(r.body_velocity(v, w));
        let side = &mut sides[r.side];
        let c = &mut side.rows[r.row];
        c.give(p - r.old, side.velocities);
        let pn = p.dot(c.normal);
        c.normal_impulse = pn;
        c.friction_impulse = p - c.normal * pn;
        c.deferred = false;
        let at = &side.at;
        let cand = &side.candidates[c.candidate];
        cand.apply_impulse(r.body_old - p, c.anchor(), at.motions, bodies, at.dt);
        if pn > 0.0 && !side.pushed.contains(&body) {
            side.pushed.push(body);
        }
    }
    for side in sides.iter_mut() {
        let at = &side.at;
        let found = side.picked.first().map(|&k| side.rows[k].candidate);
        if let Some(ci) = found {
            debug_assert_eq!(side.candidates[ci].rigid(at.motions), Some(body));
            refresh_poses(side.candidates, ci, at.s1, at.dt, at.motions, bodies);
        }
    }
}

/// Adds the twist `(v, w)` to `a`.
fn add(a: &mut [Real; TWIST_DIM], (v, w): (Vector, AngVector)) {
    let b = math::twist_to_array(v, w);
    for (x, y) in a.iter_mut().zip(b) {
        *x += y;
    }
}
