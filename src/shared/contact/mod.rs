//! Contact between deformables and rapier colliders (shape-based paper §2.3;
//! `docs/ARCHITECTURE.md` §6).
//!
//! **Candidates.** Each step, every surface node asks rapier's broad phase (its BVH, through a
//! short-lived query pipeline) for the colliders whose boxes overlap the box the node sweeps
//! during the step, widened by how far the nearby moving bodies travel. Sensors are skipped,
//! the deformable's collision groups are honoured, and the bodies it is bound to are ignored
//! unless it asks otherwise.
//!
//! **Moving colliders.** A collider's pose at any time of the step comes from its body: fixed
//! bodies stay put; kinematic bodies are interpolated from `position()` to `next_position()`
//! (position-based) or predicted from their velocity (velocity-based); dynamic bodies are
//! predicted from their current velocity plus what rapier's step will add to it (gravity and
//! user forces, taken up evenly over the step), and the deformable's impulses change that
//! velocity from the substep they act in (the path already travelled stays). The point
//! velocity of a contact is that of the collider's motion.
//!
//! **Node against collider**, each substep, after element forces and before `x += h v`, for
//! every free surface node, against its candidates at their end-of-substep poses:
//! * a node found inside a collider is put back on its surface where it came in (a ray cast
//!   back along its motion relative to the collider, so a thin plate is not crossed by
//!   projecting to its far side), or on the closest surface point (parry's projection onto the
//!   true closest feature) when it has no relative motion;
//! * otherwise the segment it is about to sweep, `x → x + h v`, is ray-cast against the
//!   collider, so no speed carries it through a thin collider.
//!
//! The normal velocity relative to the collider becomes `−e · (approach speed before this
//! substep's force update)` when that approach is faster than the restitution threshold (a
//! bounce; under the explicit step no more of it than lets the node cover half its height in
//! its cells over the substep, `docs/ARCHITECTURE.md` §6.2), else just what closes the gap (resting contact);
//! friction is Coulomb's (it sticks when `μ` times the normal impulse is enough). `e` and `μ`
//! combine the deformable's and the collider's coefficients with rapier's rules.
//!
//! **Dynamic bodies** take the opposite of every impulse, at once, at the contact point, and
//! each impulse is computed with the effective mass of both sides (the node's or facet point's,
//! and the body's mass and inertia there): momentum is conserved, no impulse more than reverses
//! the approach it sees (no energy is created), and a body lighter than the nodes under it is
//! not launched (see [`Contact`]).
//!
//! **Rigid features against soft faces.** A rigid corner or thin edge can reach between the
//! nodes of a coarse mesh without touching any of them. So each substep the vertices of
//! cuboids and convex polytopes, points sampled along their edges (spacing half the shortest
//! surface edge), and balls (the centres of balls and of samples along capsule axes, with their
//! radius) are tested against the deformable's surface facets (triangles in 3D, segments in
//! 2D): a feature that crosses a facet during the substep (a point inside the facet's prism; a
//! ball measured from the facet point closest to its centre, so that it also meets creases)
//! moves the facet's nodes (mass- and barycentric-weighted velocity change) so the facet ends
//! the substep on the feature, with friction, and the opposite impulse goes to a dynamic body.
//! Not covered: features of trimeshes, heightfields, compound and other shapes (their surfaces
//! still stop nodes).
//!
//! **Level shapes.** Trimeshes, polylines and heightfields are two-sided surfaces a node is
//! kept a skin off, on the side it is on; convex polytopes are left through the nearest face
//! plane; compounds and voxels by the face of the part a node came in through
//! (`docs/ARCHITECTURE.md` §6.2).
//!
//! Files: [`candidates`] (the broad phase and each candidate's motion and features), `node`
//! (nodes against colliders), `facet` (rigid features against surface facets), `solve` (the
//! velocity update of one contact), [`block`] (a dynamic body and all the contacts that push it
//! in a substep, solved together).

pub(crate) mod block;
pub(crate) mod candidates;
mod facet;
mod node;
pub(crate) mod soft;
pub(crate) mod soft_terms;
mod solve;
mod whole;

pub(crate) use candidates::{
    broad_phase_is_current, candidate, near_colliders, node_candidates, translate_body, Candidate,
    Scan,
};
pub(crate) use facet::{resolve_facet, FacetMotion, FacetSlack};
pub(crate) use node::{penetration, resolve_node, surface_skin, FreeNode};
pub(crate) use solve::Contact;
pub(crate) use whole::rigid_answer;

use super::math::{Real, Vector};
use super::rapier::dynamics::CoefficientCombineRule;
use super::rapier::geometry::{ColliderHandle, InteractionGroups};

/// Contact coefficients and filters of a deformable.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Copy, Clone, Debug, PartialEq)]
pub(crate) struct ContactMaterial {
    pub friction: Real,
    pub restitution: Real,
    pub friction_combine_rule: CoefficientCombineRule,
    pub restitution_combine_rule: CoefficientCombineRule,
    pub groups: InteractionGroups,
    pub ignore_attached_bodies: bool,
    /// Whether the body's surface nodes meet its own surface facets.
    #[cfg_attr(feature = "serde", serde(default))]
    pub self_contact: bool,
}

/// A contact between a deformable and a collider.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct ContactPoint {
    /// Point on the collider's surface, world frame.
    pub point: Vector,
    /// The collider's outward normal there.
    pub normal: Vector,
    /// The collider.
    pub collider: ColliderHandle,
    /// The node that touched the collider, or `None` for a facet contact (a rigid feature
    /// pressing a surface facet).
    pub node: Option<u32>,
}

/// The normal relative velocity a contact aims for: `closing` (what just closes the gap, or
/// leaves the skin), or, when the approach before this substep's forces was faster than
/// `threshold`, the bounce `−e · approach` if that separates faster (rule 4 of
/// `docs/ARCHITECTURE.md` §4.3: from the approach before the force update, else resting nodes
/// chatter).
pub(crate) fn normal_target(
    closing: Real,
    approach: Real,
    restitution: Real,
    threshold: Real,
) -> Real {
    if -approach > threshold && restitution > 0.0 {
        closing.max(-restitution * approach)
    } else {
        closing
    }
}

/// How a contact between two deformables ended its solve: its push (impulse or force, never
/// zero) along `normal`.
#[derive(Copy, Clone, Debug)]
pub(crate) struct Grip {
    pub normal: Vector,
    pub push: Real,
}

impl Grip {
    /// The grip of a contact pushing by `push` along `normal`, `None` when it does not push.
    pub fn of(normal: Vector, push: Real) -> Option<Grip> {
        (push > 0.0).then_some(Grip { normal, push })
    }
}

/// A contact of one of an island member's nodes with another member's facet in the last
/// substep: the other member, the node's position when the contact was solved (before the
/// substep moved it), and the contact's grip.
#[derive(Copy, Clone, Debug)]
pub(crate) struct Held {
    pub other: usize,
    pub point: Vector,
    pub grip: Grip,
}

/// An accumulated friction impulse kept in Coulomb's disc: at most `limit` (`μ` times the
/// accumulated normal impulse) long.
pub(crate) fn coulomb(total: Vector, limit: Real) -> Vector {
    let len = total.length();
    if len > limit {
        total * (limit / len)
    } else {
        total
    }
}
