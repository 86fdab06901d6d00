//! The body's surface as a bounding-volume hierarchy (parry's `Bvh`) over its boundary
//! facets at their current positions: what queries (ray and shape casts) search. The same
//! refitted hierarchy holds the facets' swept boxes of soft contact and the bodies' boxes the
//! islands are found from.
//!
//! A body's own hierarchy ([`Surface`]) is refitted by the first search after its nodes moved,
//! not by every step: a world stepped without queries never pays for it (on a resting
//! 750-cell cube stepped at one substep, the refit was a ninth of the step).

use std::fmt;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{RwLock, RwLockReadGuard};

use super::super::math::{Vector, FACET_ARITY};
use super::super::mesh::Mesh;
use super::super::rapier::geometry::Aabb;
use super::super::rapier::parry::partitioning::{Bvh, BvhBuildStrategy, BvhWorkspace};

/// A hierarchy of boxes refitted while their count stays; for a body's surface, one leaf per
/// boundary facet (leaf index = the facet's index in [`Mesh::boundary_facets`]), each the
/// facet's box.
#[derive(Clone, Default)]
pub(crate) struct SurfaceTree {
    bvh: Bvh,
    workspace: BvhWorkspace,
}

impl fmt::Debug for SurfaceTree {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SurfaceTree")
            .field("leaves", &self.bvh.leaf_count())
            .finish()
    }
}

pub(crate) fn facet_box(positions: &[Vector], facet: &[u32; FACET_ARITY]) -> Aabb {
    let mut b = Aabb::new_invalid();
    for &i in facet {
        b.take_point(positions[i as usize]);
    }
    b
}

impl SurfaceTree {
    pub fn build(mesh: &Mesh, positions: &[Vector]) -> Self {
        let leaves: Vec<Aabb> = mesh
            .boundary_facets()
            .iter()
            .map(|f| facet_box(positions, f))
            .collect();
        SurfaceTree {
            bvh: Bvh::from_leaves(BvhBuildStrategy::Binned, &leaves),
            workspace: BvhWorkspace::default(),
        }
    }

    /// Sets the leaves' boxes to `boxes` (one per leaf, in order): refitted while the count
    /// stays, built afresh when it changes. A refitted tree keeps its first shape, however the
    /// boxes move, so its queries may slow but never miss a leaf (rebalancing it each step,
    /// `optimize_incremental`, made a pile of fifty cubes 13 % slower).
    pub fn set(&mut self, boxes: &[Aabb]) {
        if self.bvh.leaf_count() as usize != boxes.len() || boxes.is_empty() {
            self.bvh = Bvh::from_leaves(BvhBuildStrategy::Binned, boxes);
            return;
        }
        for (k, b) in boxes.iter().enumerate() {
            self.bvh.insert_or_update_partially(*b, k as u32, 0.0);
        }
        self.bvh.refit(&mut self.workspace);
    }

    /// Brings every leaf to its facet's current box.
    pub fn refit(&mut self, mesh: &Mesh, positions: &[Vector]) {
        for (k, f) in mesh.boundary_facets().iter().enumerate() {
            self.bvh
                .insert_or_update_partially(facet_box(positions, f), k as u32, 0.0);
        }
        self.bvh.refit(&mut self.workspace);
    }

    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }
}

/// A body's surface hierarchy, refitted to its positions when searched after they moved.
pub(crate) struct Surface {
    tree: RwLock<SurfaceTree>,
    /// The nodes moved since the last refit.
    stale: AtomicBool,
}

impl Surface {
    pub fn build(mesh: &Mesh, positions: &[Vector]) -> Self {
        Surface {
            tree: RwLock::new(SurfaceTree::build(mesh, positions)),
            stale: AtomicBool::new(false),
        }
    }

    /// The nodes moved: the next search refits first.
    pub fn moved(&mut self) {
        *self.stale.get_mut() = true;
    }

    /// The hierarchy at `positions` (the body's current ones, over `mesh`), refitted first if
    /// the nodes moved since it last was.
    pub fn search(&self, mesh: &Mesh, positions: &[Vector]) -> RwLockReadGuard<'_, SurfaceTree> {
        if self.stale.load(Ordering::Acquire) {
            let mut tree = self.tree.write().unwrap_or_else(|e| e.into_inner());
            if self.stale.load(Ordering::Acquire) {
                tree.refit(mesh, positions);
                self.stale.store(false, Ordering::Release);
            }
        }
        self.tree.read().unwrap_or_else(|e| e.into_inner())
    }
}

impl Clone for Surface {
    fn clone(&self) -> Self {
        let tree = self.tree.read().unwrap_or_else(|e| e.into_inner()).clone();
        Surface {
            tree: RwLock::new(tree),
            stale: AtomicBool::new(self.stale.load(Ordering::Acquire)),
        }
    }
}

impl fmt::Debug for Surface {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Surface")
            .field("stale", &self.stale.load(Ordering::Relaxed))
            .finish()
    }
}
