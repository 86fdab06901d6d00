//! A deformable taken as one rigid body against the fixed and kinematic colliders that stop
//! it, for the implicit step (`docs/ARCHITECTURE.md` §4.2, "The body's rigid motion first").
//!
//! Node contacts stop each node they find and leave the rest of the body to learn of it
//! through its elastic terms, which a few sweeps carry only a few cells into a body much
//! stiffer than `m/h²`. Here the body's linear and angular velocity (from its nodes' momentum)
//! take the contacts' impulses first, as a rigid body's would, by projected Gauss–Seidel over
//! the rows with Coulomb's cone, and every node takes the change of that rigid motion. A rigid
//! motion does not change the elastic energy: the sweeps then start where a stiff body goes,
//! with nothing stored. Not quite a rigid body's answer: a contact patch narrower than the body
//! takes its normal impulses at a shortened lever ([`normal_lever`]), so that a coarse ball
//! rolls over its flat facets as a soft one does.

use super::super::coupling::Substep;
use super::super::math::{self, AngMatrix, AngVector, Real, Vector};
use super::super::rapier::dynamics::RigidBodySet;
use super::super::threads;
use super::candidates::Candidate;
use super::solve::Contact;

/// Most Gauss–Seidel passes over the rows.
const PASSES: usize = 100;

/// The solve ends once a pass changes no impulse by more than this fraction of the largest
/// total normal impulse.
const TOLERANCE: Real = 1e-4;

/// A change of a body's rigid motion: `linear` at `centre`, and `angular` about it.
#[derive(Copy, Clone, Debug)]
pub(crate) struct RigidChange {
    pub centre: Vector,
    pub linear: Vector,
    pub angular: AngVector,
}

impl RigidChange {
    /// The change of velocity at `p`.
    pub fn at(&self, p: Vector) -> Vector {
        self.linear + math::ang_cross(self.angular, p - self.centre)
    }
}

/// A contact row as the rigid solve sees it.
struct Row {
    /// Lever arm from the centre of mass.
    arm: Vector,
    /// The lever arm of the normal impulse ([`normal_lever`]).
    lever: Vector,
    normal: Vector,
    /// The inverse effective mass along the normal at the lever (the body's mass and inertia
    /// stay as they are through the passes).
    normal_inv_mass: Real,
    /// Normal velocity relative to the collider to reach, and the collider's velocity there.
    target: Real,
    collider: Vector,
    friction: Real,
    normal_impulse: Real,
    friction_impulse: Vector,
}

/// The body's rigid motion.
struct Rigid {
    inv_mass: Real,
    inv_inertia: AngMatrix,
    linear: Vector,
    angular: AngVector,
}

impl Rigid {
    fn velocity(&self, arm: Vector) -> Vector {
        self.linear + math::ang_cross(self.angular, arm)
    }

    /// The inverse effective mass along `dir` at `arm`.
    fn inv_mass_at(&self, arm: Vector, dir: Vector) -> Real {
        let a = math::cross(arm, dir);
        self.inv_mass + math::ang_dot(a, self.inv_inertia * a)
    }

    fn apply(&mut self, arm: Vector, impulse: Vector) {
        self.linear += impulse * self.inv_mass;
        self.angular += self.inv_inertia * math::cross(arm, impulse);
    }
}

/// The change of the rigid motion of a body (nodes at `x`, velocities `v`, masses `masses`)
/// that answers its contact `rows` (each with a fixed or kinematic collider) as a rigid body
/// would: each row's normal impulse non-negative and reaching its target normal velocity, its
/// friction in Coulomb's cone. A row whose collider the body's centre closes on faster than
/// `impact` takes the blow at its whole lever arm, the others at [`normal_lever`]'s. `None`
/// without rows or mass.
pub(crate) fn rigid_answer(
    (x, v, masses, surface): (&[Vector], &[Vector], &[Real], &[u32]),
    (rows, impact): (&[Contact], Real),
    at: &Substep<'_>,
    candidates: &[Candidate<'_>],
    bodies: &RigidBodySet,
) -> Option<RigidChange> {
    let mass: Real = masses.iter().sum();
    if rows.is_empty() || mass.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let centre = x.iter().zip(masses).map(|(p, m)| *p * *m).sum::<Vector>() / mass;
    let linear = v.iter().zip(masses).map(|(u, m)| *u * *m).sum::<Vector>() / mass;
    let arms: Vec<Vector> = x.iter().map(|p| *p - centre).collect();
    let mut momentum = math::ANG_ZERO;
    for ((r, u), m) in arms.iter().zip(v).zip(masses) {
        momentum += math::cross(*r, *u - linear) * *m;
    }
    let inv_inertia = math::inverse_inertia(&arms, masses);
    // The body's extent in any direction is its surface's.
    let outline: Vec<Vector> = surface.iter().map(|&i| arms[i as usize]).collect();
    let start = Rigid {
        inv_mass: 1.0 / mass,
        inv_inertia,
        linear,
        angular: inv_inertia * momentum,
    };
    // Each row's lever scans the outline: the rows are set up on rayon's threads, in chunks
    // of about a `CHUNK` of terms.
    let chunk = (threads::CHUNK / outline.len().max(1)).max(1);
    let mut rows: Vec<Row> = threads::collect_in(rows.len(), chunk, |r| {
        let c = &rows[r];
        let cand = &candidates[c.candidate];
        let arm = c.node_point(x) - centre;
        let collider = cand.anchored_velocity(c.point, c.anchor, at.s1, at.dt, at.motions, bodies);
        let blow = (collider - linear).dot(c.normal) > impact;
        let lever = if blow {
            arm
        } else {
            normal_lever(arm, c.normal, &outline)
        };
        Row {
            arm,
            lever,
            normal: c.normal,
            normal_inv_mass: start.inv_mass_at(lever, c.normal),
            target: c.target,
            collider,
            friction: cand.friction,
            normal_impulse: 0.0,
            friction_impulse: Vector::ZERO,
        }
    });
    let mut body = start;
    let (linear0, angular0) = (body.linear, body.angular);
    for _ in 0..PASSES {
        let mut change: Real = 0.0;
        for row in rows.iter_mut() {
            let n = row.normal;
            let k = row.normal_inv_mass;
            let vn = (body.velocity(row.lever) - row.collider).dot(n);
            let total = (row.normal_impulse + (row.target - vn) / k).max(0.0);
            let dj = total - row.normal_impulse;
            row.normal_impulse = total;
            body.apply(row.lever, n * dj);
            change = change.max(dj.abs());
            if row.friction <= 0.0 {
                continue;
            }
            let vr = body.velocity(row.arm) - row.collider;
            let vt = vr - n * vr.dot(n);
            let slip = vt.length();
            let mut total = row.friction_impulse;
            if slip > 0.0 {
                let t = vt / slip;
                total -= t * (slip / body.inv_mass_at(row.arm, t));
            }
            let total = super::coulomb(total, row.friction * row.normal_impulse);
            let dj = total - row.friction_impulse;
            row.friction_impulse = total;
            body.apply(row.arm, dj);
            change = change.max(dj.length());
        }
        let largest = rows.iter().map(|r| r.normal_impulse).fold(0.0, Real::max);
        if change <= TOLERANCE * largest {
            break;
        }
    }
    let change = RigidChange {
        centre,
        linear: body.linear - linear0,
        angular: body.angular - angular0,
    };
    (change.linear.is_finite() && math::ang_norm(change.angular).is_finite()).then_some(change)
}

/// The lever arm at which a contact at `arm` (from the centre of mass) with normal `n` takes
/// its normal impulse: its part along `n` whole, its part across `n` shortened by the square
/// of how far across the body it reaches, `(reach / extent)²`, `extent` being the body's
/// (its surface nodes at `arms`) in that direction. A flat face the body rests on reaches its edge and
/// keeps its whole lever (a cube pushed along a floor leans on its leading edge and does
/// not tip); a patch narrower than the body (a ball's) keeps a short one, so the body rolls
/// over it by deforming as the explicit step's soft contacts roll it, instead of standing on
/// a coarse mesh's flat facets as a rigid polyhedron would.
fn normal_lever(arm: Vector, n: Vector, arms: &[Vector]) -> Vector {
    let along = n * arm.dot(n);
    let across = arm - along;
    let reach = across.length();
    if reach <= 0.0 {
        return arm;
    }
    let d = across / reach;
    let extent = arms.iter().map(|a| a.dot(d)).fold(reach, Real::max);
    let share = reach / extent;
    along + across * (share * share)
}
