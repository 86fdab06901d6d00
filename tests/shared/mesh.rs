//! Meshes: lattices, boundary extraction.

use crate::dim::math::{self, Real, Vector, DIM, FACET_ARITY};
use crate::dim::{CellKind, Mesh};

/// Σ over boundary facets of (facet centroid · outward normal) · measure / DIM is the enclosed
/// volume (divergence theorem) when the boundary is closed and consistently oriented outwards.
fn enclosed_volume(mesh: &Mesh) -> Real {
    let mut v = 0.0;
    for f in mesh.boundary_facets() {
        let p: Vec<Vector> = f.iter().map(|&i| mesh.nodes()[i as usize]).collect();
        let c = p.iter().copied().sum::<Vector>() / FACET_ARITY as Real;
        // |facet_normal| is (DIM−1)! times the facet measure.
        let factorial = if DIM == 3 { 2.0 } else { 1.0 };
        v += c.dot(math::facet_normal(&p)) / factorial / DIM as Real;
    }
    v
}

#[test]
fn lattice_boundary_is_closed_and_outward() {
    for kind in [CellKind::Simplex, CellKind::Cube] {
        for res in [2, 3, 5] {
            let half = Vector::splat(0.5) + Vector::X * 0.25;
            let mesh = Mesh::cuboid(half, [res; DIM], kind).unwrap();
            let volume: Real = (0..DIM).map(|d| 2.0 * half[d]).product();
            assert!(
                (mesh.total_volume() - volume).abs() < 1e-4,
                "{kind:?} res {res}: cells sum to {}",
                mesh.total_volume()
            );
            let enclosed = enclosed_volume(&mesh);
            assert!(
                (enclosed - volume).abs() < 1e-4,
                "{kind:?} res {res}: boundary encloses {enclosed}, expected {volume}"
            );
            // Simplicial boundary facets: 2(res−1) per side in 2D... counted per box face.
            let per_face = (res - 1).pow(DIM as u32 - 1) * if DIM == 3 { 2 } else { 1 };
            assert_eq!(
                mesh.boundary_facets().len(),
                2 * DIM * per_face,
                "{kind:?} res {res}"
            );
            // Boundary nodes: all lattice nodes minus the interior ones.
            let interior = (res - 2).pow(DIM as u32);
            assert_eq!(mesh.boundary_nodes().len(), res.pow(DIM as u32) - interior);
        }
    }
}

#[test]
fn lattice_cells_are_positively_oriented_and_counted() {
    let res = 4;
    let simplex = Mesh::cuboid(Vector::splat(1.0), [res; DIM], CellKind::Simplex).unwrap();
    let factorial: usize = (1..=DIM).product();
    assert_eq!(simplex.num_cells(), (res - 1).pow(DIM as u32) * factorial);
    assert!(simplex.rest_volumes().iter().all(|v| *v > 0.0));
    let boxes = Mesh::cuboid(Vector::splat(1.0), [res; DIM], CellKind::Cube).unwrap();
    assert_eq!(boxes.num_cells(), (res - 1).pow(DIM as u32));
    for c in 0..boxes.num_cells() {
        assert!((boxes.cell_quality(c, boxes.nodes()) - 1.0).abs() < 1e-5);
    }
}
