//! Nodes bound to rigid bodies ("bones").
//!
//! A node is bound to a rigid body at a local anchor (its position in the body's frame when it
//! was attached). Every substep:
//! * on a **fixed or kinematic** body the node is placed exactly on its anchor, the body's pose
//!   interpolated between `position()` and `next_position()` (or predicted from its velocity for
//!   a velocity-based kinematic body), and given the anchor's velocity;
//! * on a **dynamic** body the binding is two-way: the node gets the velocity that takes it to
//!   the anchor's predicted position at the end of the substep, and the opposite impulse goes to
//!   the body at the anchor, scaled by the pair's effective mass so a light body is not
//!   over-driven. Linear momentum of node + body is conserved exactly.
//!
//! Bound nodes take no part in contacts. A binding to a body that has been removed from the
//! rigid-body set is dropped at the next step (the step report counts it).

use super::body::Deformable;
use super::math::{Real, Vector};
use super::rapier::dynamics::{RigidBodyHandle, RigidBodySet};
use super::rapier::geometry::{ColliderHandle, ColliderSet};

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

impl Deformable {
    /// The current bindings, in the order they were made.
    pub fn attachments(&self) -> &[Attachment] {
        &self.attachments
    }

    /// Whether a node is bound to a body.
    pub fn is_attached(&self, node: u32) -> bool {
        self.attachment_of
            .get(node as usize)
            .is_some_and(|a| *a != u32::MAX)
    }

    /// Binds `nodes` to `body` at their current positions (re-binding nodes already bound
    /// elsewhere). Returns how many nodes were bound. Nothing changes on error.
    pub fn attach_nodes(
        &mut self,
        bodies: &RigidBodySet,
        body: RigidBodyHandle,
        nodes: &[u32],
    ) -> Result<usize, AttachError> {
        let rb = bodies.get(body).ok_or(AttachError::NoSuchBody(body))?;
        if let Some(&node) = nodes.iter().find(|&&n| n as usize >= self.positions.len()) {
            return Err(AttachError::NodeOutOfRange {
                node,
                nodes: self.positions.len(),
            });
        }
        let pose = *rb.position();
        self.detach_nodes(nodes);
        for &node in nodes {
            let anchor = pose.inverse_transform_point(self.positions[node as usize]);
            self.attachments.push(Attachment { node, body, anchor });
        }
        self.reindex_attachments();
        Ok(nodes.len())
    }

    /// Binds every node inside `collider`, or within `tolerance` of it, to the collider's
    /// parent body — how tissue is skinned onto a bone. Returns how many nodes were bound.
    pub fn attach_nodes_inside(
        &mut self,
        bodies: &RigidBodySet,
        colliders: &ColliderSet,
        collider: ColliderHandle,
        tolerance: Real,
    ) -> Result<usize, AttachError> {
        if !(tolerance.is_finite() && tolerance >= 0.0) {
            return Err(AttachError::BadTolerance(tolerance));
        }
        let co = colliders
            .get(collider)
            .ok_or(AttachError::NoSuchCollider(collider))?;
        let body = co
            .parent()
            .ok_or(AttachError::ColliderWithoutBody(collider))?;
        let pose = co.position();
        let nodes: Vec<u32> = (0..self.positions.len() as u32)
            .filter(|&i| {
                co.shape()
                    .distance_to_point(pose, self.positions[i as usize], true)
                    <= tolerance
            })
            .collect();
        self.attach_nodes(bodies, body, &nodes)
    }

    /// Unbinds the given nodes (those not bound are ignored). Returns how many were unbound.
    pub fn detach_nodes(&mut self, nodes: &[u32]) -> usize {
        let before = self.attachments.len();
        if nodes.is_empty() || before == 0 {
            return 0;
        }
        let mut drop = vec![false; self.positions.len()];
        for &n in nodes {
            if let Some(d) = drop.get_mut(n as usize) {
                *d = true;
            }
        }
        self.attachments.retain(|a| !drop[a.node as usize]);
        self.reindex_attachments();
        before - self.attachments.len()
    }

    /// Unbinds every node bound to `body`. Returns how many were unbound.
    pub fn detach_body(&mut self, body: RigidBodyHandle) -> usize {
        let before = self.attachments.len();
        self.attachments.retain(|a| a.body != body);
        self.reindex_attachments();
        before - self.attachments.len()
    }

    /// Unbinds every node.
    pub fn detach_all(&mut self) {
        self.attachments.clear();
        self.reindex_attachments();
    }

    /// Drops bindings to bodies no longer in the set; returns how many.
    pub(crate) fn prune_attachments(&mut self, bodies: &RigidBodySet) -> usize {
        let before = self.attachments.len();
        self.attachments.retain(|a| bodies.contains(a.body));
        if self.attachments.len() != before {
            self.reindex_attachments();
        }
        before - self.attachments.len()
    }

    pub(crate) fn reindex_attachments(&mut self) {
        self.attachment_of.clear();
        self.attachment_of.resize(self.positions.len(), u32::MAX);
        for (k, a) in self.attachments.iter().enumerate() {
            self.attachment_of[a.node as usize] = k as u32;
        }
        self.forces_valid = false;
        self.wake_up();
    }
}
