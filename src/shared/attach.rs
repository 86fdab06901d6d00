//! Nodes bound to rigid bodies ("bones"): the bindings and the bone drive
//! (`docs/ARCHITECTURE.md` §7).
//!
//! A node is bound to a rigid body at a local anchor (its position in the body's frame when it
//! was attached). Every substep:
//! * on a **fixed or kinematic** body the node gets the velocity `(target − x)/h` that takes it
//!   to its anchor's position at the end of the substep (the body's pose interpolated between
//!   `position()` and `next_position()`, or predicted from its velocity for a velocity-based
//!   kinematic body), and after the positions move it is put exactly on that target;
//! * on a **dynamic** body the binding is two-way, on velocities: the node is driven towards
//!   the anchor's velocity plus a fifth of its position error per substep
//!   (`v_anchor + 0.2 (anchor − x)/h`: a full correction on a body whose joints rapier solves
//!   later feeds energy into the pair), and the opposite impulse goes to the body at the
//!   anchor. All the nodes bound to one body are solved with it at once (the body's velocity
//!   the unknown of one small dense solve), so however light the body, it moves as its nodes
//!   together pull it. Linear momentum of nodes + body is conserved exactly; angular momentum
//!   up to the impulses' moment over each node's position error (they act at the anchors).
//!
//! Bound nodes are not tested against colliders as nodes. A surface facet with bound nodes
//! still meets rigid features; its bound nodes count with zero inverse mass there (the bone
//! takes their share). A binding to a body that has been removed from the rigid-body set is
//! dropped at the next step (the step report counts it).

use super::coupling::{self, MotionKind, Substep};
use super::math::{self, Real, Vector, TWIST_DIM};
use super::rapier::dynamics::{RigidBody, RigidBodyHandle, RigidBodySet};
use super::rapier::geometry::{Collider, ColliderHandle};

/// A node bound to a rigid body.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Attachment {
    /// The node.
    pub node: u32,
    /// The body.
    pub body: RigidBodyHandle,
    /// The anchor in the body's local frame.
    pub anchor: Vector,
}

/// Why nodes could not be bound.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum AttachError {
    /// The rigid body is not in the set (never inserted, or removed).
    #[error("rigid body {0:?} is not in the rigid-body set (removed, or never inserted)")]
    NoSuchBody(RigidBodyHandle),
    /// The collider is not in the set.
    #[error("collider {0:?} is not in the collider set (removed, or never inserted)")]
    NoSuchCollider(ColliderHandle),
    /// The collider has no parent rigid body to bind to.
    #[error("collider {0:?} has no parent rigid body to bind nodes to")]
    ColliderWithoutBody(ColliderHandle),
    /// A node index is out of range.
    #[error("node {node} does not exist: the deformable has {nodes} nodes")]
    NodeOutOfRange {
        /// The index given.
        node: u32,
        /// Number of nodes.
        nodes: usize,
    },
    /// The deformable handle is stale.
    #[error("the deformable is not in the set (removed, or never inserted)")]
    NoSuchDeformable,
    /// A tolerance is negative or not finite.
    #[error("tolerance must be non-negative and finite, got {0}")]
    BadTolerance(Real),
}

/// Fraction of a dynamically bound node's position error corrected per substep.
const DYNAMIC_BINDING_CORRECTION: Real = 0.2;

/// A deformable's bindings: the list, in the order they were made, and per node its binding.
#[derive(Clone, Debug, Default)]
pub(crate) struct Bindings {
    list: Vec<Attachment>,
    /// Per node: index into `list`.
    of_node: Vec<Option<u32>>,
}

impl Bindings {
    /// No bindings on a body of `nodes` nodes.
    pub fn new(nodes: usize) -> Self {
        Bindings {
            list: Vec::new(),
            of_node: vec![None; nodes],
        }
    }

    /// The bindings of `list` on a body of `nodes` nodes; `Err` names a node bound twice, out
    /// of range, or bound at a non-finite anchor.
    #[cfg_attr(not(feature = "serde"), allow(dead_code))]
    pub fn from_list(list: Vec<Attachment>, nodes: usize) -> Result<Self, String> {
        let mut of_node = vec![None; nodes];
        for (k, a) in list.iter().enumerate() {
            let slot = of_node
                .get_mut(a.node as usize)
                .ok_or_else(|| format!("binding of node {} of {nodes}", a.node))?;
            if slot.is_some() || !a.anchor.is_finite() {
                return Err(format!(
                    "node {} bound twice or at a non-finite anchor",
                    a.node
                ));
            }
            *slot = Some(k as u32);
        }
        Ok(Bindings { list, of_node })
    }

    /// The bindings, in the order they were made.
    pub fn list(&self) -> &[Attachment] {
        &self.list
    }

    /// Number of bound nodes.
    pub fn len(&self) -> usize {
        self.list.len()
    }

    /// Whether a node is bound.
    pub fn is_bound(&self, node: u32) -> bool {
        self.of_node.get(node as usize).is_some_and(|a| a.is_some())
    }

    /// The bodies nodes are bound to, each once, in the order of their first binding.
    pub fn bodies(&self, out: &mut Vec<RigidBodyHandle>) {
        out.clear();
        for a in &self.list {
            if !out.contains(&a.body) {
                out.push(a.body);
            }
        }
    }

    /// Binds `nodes` (all in range) at their `positions` to `body`, whose pose is `pose`,
    /// re-binding nodes bound elsewhere.
    pub fn bind(
        &mut self,
        body: RigidBodyHandle,
        pose: &super::math::Pose,
        positions: &[Vector],
        nodes: &[u32],
    ) {
        self.unbind(nodes);
        for &node in nodes {
            let anchor = pose.inverse_transform_point(positions[node as usize]);
            self.list.push(Attachment { node, body, anchor });
        }
        self.reindex();
    }

    /// Unbinds the given nodes (those not bound are ignored). Returns how many were unbound.
    pub fn unbind(&mut self, nodes: &[u32]) -> usize {
        let before = self.list.len();
        if nodes.is_empty() || before == 0 {
            return 0;
        }
        let mut drop = vec![false; self.of_node.len()];
        for &n in nodes {
            if let Some(d) = drop.get_mut(n as usize) {
                *d = true;
            }
        }
        self.list.retain(|a| !drop[a.node as usize]);
        self.reindex();
        before - self.list.len()
    }

    /// Keeps the bindings for which `keep` holds; returns how many were dropped.
    pub fn retain(&mut self, keep: impl FnMut(&Attachment) -> bool) -> usize {
        let before = self.list.len();
        self.list.retain(keep);
        if self.list.len() != before {
            self.reindex();
        }
        before - self.list.len()
    }

    fn reindex(&mut self) {
        let n = self.of_node.len();
        self.of_node.clear();
        self.of_node.resize(n, None);
        for (k, a) in self.list.iter().enumerate() {
            self.of_node[a.node as usize] = Some(k as u32);
        }
    }
}

/// The nodes whose `positions` are inside `collider`, or within `tolerance` of it.
pub(crate) fn nodes_inside(collider: &Collider, positions: &[Vector], tolerance: Real) -> Vec<u32> {
    let pose = collider.position();
    (0..positions.len() as u32)
        .filter(|&i| {
            collider
                .shape()
                .distance_to_point(pose, positions[i as usize], true)
                <= tolerance
        })
        .collect()
}

/// A body's node arrays as the bone drive sees them.
pub(crate) struct DrivenNodes<'a> {
    pub positions: &'a [Vector],
    pub velocities: &'a mut [Vector],
    pub inv_masses: &'a [Real],
}

/// The bone drive, once per substep after the velocity update and before contacts: every
/// bound node gets the velocity that takes it to its anchor at the end of the substep. On a
/// fixed or kinematic body the node's end position is that target (`targets[k]`, set after
/// the positions move); on a dynamic body the binding is two-way, at the velocity level (see
/// the module docs), and its target is `None`. `motion_of[k]` indexes the motion of binding
/// `k`'s body in `at.motions` (`None`: the body is gone).
pub(crate) fn drive_bones(
    bindings: &Bindings,
    motion_of: &[Option<usize>],
    nodes: DrivenNodes<'_>,
    at: &Substep<'_>,
    bodies: &mut RigidBodySet,
    targets: &mut Vec<Option<Vector>>,
) {
    let (h, s1, dt, t) = (at.h, at.s1, at.dt, at.t);
    targets.clear();
    // The dynamic bindings: binding, its anchor now and the velocity that corrects a fifth of
    // its position error, taken once, before the passes that share the impulses.
    let mut dynamic: Vec<(usize, Vector, Vector)> = Vec::new();
    for (k, a) in bindings.list.iter().enumerate() {
        let Some(m) = motion_of[k] else {
            targets.push(None);
            continue;
        };
        let motion = at.motions[m];
        let i = a.node as usize;
        let target = motion.pose_at(s1, dt, bodies).transform_point(a.anchor);
        let desired = (target - nodes.positions[i]) / h;
        if motion.kind == MotionKind::Dynamic {
            let anchor_now = motion.pose_at(t / dt, dt, bodies).transform_point(a.anchor);
            // Velocity-level binding: the anchor's velocity plus a fraction of the
            // position error per substep (a full correction on a body whose joints
            // rapier solves later feeds energy into the pair).
            let bias = (anchor_now - nodes.positions[i]) * (DYNAMIC_BINDING_CORRECTION / h);
            dynamic.push((k, anchor_now, bias));
            targets.push(None);
        } else {
            nodes.velocities[i] = desired;
            targets.push(Some(target));
        }
    }
    // Each body with all the nodes bound to it at once: one pass of impulses, each sized as if
    // its node alone pulled the body, over-drove a light body (a 1.6 kg box bound to nine
    // nodes of a soft cube rang up to 78 m/s in 0.4 s), and sequential passes converge slowly
    // on one.
    dynamic.sort_by_key(|&(k, _, _)| (bindings.list[k].body.into_raw_parts(), k));
    for group in dynamic.chunk_by(|a, b| bindings.list[a.0].body == bindings.list[b.0].body) {
        let Some(rb) = bodies.get_mut(bindings.list[group[0].0].body) else {
            continue;
        };
        let nodes_of = group.iter().map(|&(k, anchor, bias)| {
            let i = bindings.list[k].node as usize;
            (i, anchor, bias)
        });
        let rows: Vec<(usize, Vector, Vector)> = nodes_of
            .filter(|&(i, _, _)| nodes.inv_masses[i] > 0.0)
            .collect();
        solve_bound_body(rb, &rows, nodes.velocities, nodes.inv_masses);
    }
}

/// The nodes `rows` (node, anchor now, correcting velocity) bound to the dynamic body `rb`,
/// solved as one: the body's velocity `V` is the unknown, each node takes the velocity `V`
/// gives its anchor plus its correction, and the body the opposite of the nodes' impulses,
/// `V = V₀ − M⁻¹ Σ Jᵀ λ(V)`, linear in `V` (one dense solve). Linear momentum is conserved.
fn solve_bound_body(
    rb: &mut RigidBody,
    rows: &[(usize, Vector, Vector)],
    velocities: &mut [Vector],
    inv_masses: &[Real],
) {
    if rows.is_empty() {
        return;
    }
    let com = rb.center_of_mass();
    let start = math::twist_to_array(rb.linvel(), rb.angvel());
    // The impulse node `i` takes to move with the body at twist `twist`.
    let impulse = |(i, anchor, bias): (usize, Vector, Vector), twist: &[Real; TWIST_DIM]| {
        let (v, w) = math::twist_from_array(twist);
        (v + math::ang_cross(w, anchor - com) + bias - velocities[i]) / inv_masses[i]
    };
    let response = |anchor: Vector, p: Vector| {
        let (dv, dw) = coupling::impulse_response(rb, anchor, p);
        math::twist_to_array(dv, dw)
    };
    // `R(V) = V − V₀ + Σ M⁻¹ Jᵀ λ(V)`: its value at `V₀`, and its (constant) Jacobian by
    // columns.
    let mut residual = [0.0; TWIST_DIM];
    let mut jacobian = [[0.0; TWIST_DIM]; TWIST_DIM];
    for (c, col) in jacobian.iter_mut().enumerate() {
        col[c] = 1.0;
    }
    for &row in rows {
        let (i, anchor, _) = row;
        add(&mut residual, response(anchor, impulse(row, &start)));
        for (c, col) in jacobian.iter_mut().enumerate() {
            let mut unit = [0.0; TWIST_DIM];
            unit[c] = 1.0;
            let (uv, uw) = math::twist_from_array(&unit);
            let moved = (uv + math::ang_cross(uw, anchor - com)) / inv_masses[i];
            add(col, response(anchor, moved));
        }
    }
    let Some(step) = coupling::solve_dense(jacobian, residual) else {
        return;
    };
    let end: [Real; TWIST_DIM] = std::array::from_fn(|k| start[k] - step[k]);
    if !end.iter().all(|x| x.is_finite()) {
        return;
    }
    let impulses: Vec<Vector> = rows.iter().map(|&row| impulse(row, &end)).collect();
    for (&(i, anchor, _), p) in rows.iter().zip(impulses) {
        velocities[i] += p * inv_masses[i];
        coupling::apply_impulse(rb, -p, anchor, 0.0);
    }
}

/// `a += b`.
fn add(a: &mut [Real; TWIST_DIM], b: [Real; TWIST_DIM]) {
    a.iter_mut().zip(b).for_each(|(x, y)| *x += y);
}

/// After the positions moved: nodes on fixed or kinematic bones are put exactly on their
/// targets.
pub(crate) fn place_on_bones(
    bindings: &Bindings,
    targets: &[Option<Vector>],
    positions: &mut [Vector],
) {
    for (a, target) in bindings.list.iter().zip(targets) {
        if let Some(target) = target.filter(|t| t.is_finite()) {
            positions[a.node as usize] = target;
        }
    }
}
