//! Test bodies the models' unit tests share.

use super::super::body::{Deformable, DeformableBuilder};
use super::super::math::{Vector, DIM};
use super::super::mesh::CellKind;
use super::edge_repulsion::EdgeRepulsion;
use super::ElementModel;

/// A lattice of simplex edge-repulsion cells, `half` its half extents and `res` its nodes per
/// axis.
pub(super) fn er_lattice(half: Vector, res: [usize; DIM]) -> Deformable {
    DeformableBuilder::cuboid(half, res)
        .cells(CellKind::Simplex)
        .model(ElementModel::EdgeRepulsion)
        .build()
        .unwrap()
}

/// The edge-repulsion elements of a body built by [`er_lattice`].
pub(super) fn er_of(body: &Deformable) -> &EdgeRepulsion {
    body.state
        .elements
        .elements
        .edge_repulsion()
        .expect("an edge-repulsion body")
}
