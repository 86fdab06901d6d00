//! The body's surface as a bounding-volume hierarchy (parry's `Bvh`) over its boundary
//! facets at their current positions: what queries (ray and shape casts) search. The same
//! refitted hierarchy holds the facets' swept boxes of soft contact and the bodies' boxes the
//! islands are found from.

use std::fmt;

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
