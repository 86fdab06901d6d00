//! 3D-only lattices from shapes: a closed triangle mesh (issue 7).

use sinew::dim3::math::{Real, Vector};
use sinew::dim3::rapier::parry::shape::{SharedShape, TriMesh, TriMeshFlags};
use sinew::dim3::{CellKind, Mesh};

/// The octahedron |x| + |y| + |z| ≤ 1 as a closed, outward triangle mesh given without the
/// `ORIENTED` flag (`from_shape` adds it): same volume as the convex hull, 4/3.
#[test]
fn voxelised_closed_trimesh_volume() {
    let points: Vec<Vector> = [
        Vector::X,
        -Vector::X,
        Vector::Y,
        -Vector::Y,
        Vector::Z,
        -Vector::Z,
    ]
    .to_vec();
    let hull = SharedShape::convex_hull(&points).unwrap();
    let (vertices, indices) = hull.as_convex_polyhedron().unwrap().to_trimesh();
    let trimesh = TriMesh::new(vertices, indices).unwrap();
    assert!(!trimesh.flags().contains(TriMeshFlags::ORIENTED));
    let exact: Real = 4.0 / 3.0;
    for h in [0.07, 0.035] {
        let from_mesh = Mesh::from_shape(&trimesh, h, CellKind::Simplex).unwrap();
        let from_hull = Mesh::from_shape(hull.as_ref(), h, CellKind::Simplex).unwrap();
        let err = (from_mesh.total_volume() - exact) / exact;
        let hull_err = (from_hull.total_volume() - exact) / exact;
        println!(
            "closed trimesh (3D): cell {h}: volume error {:+.3}% (convex hull {:+.3}%)",
            100.0 * err,
            100.0 * hull_err
        );
        // The inside test of the mesh (pseudo-normals) agrees with the hull's.
        assert!(
            (from_mesh.total_volume() - from_hull.total_volume()).abs() < 1e-3 * exact,
            "{} vs {}",
            from_mesh.total_volume(),
            from_hull.total_volume()
        );
        let bound = 4.0 * Real::sqrt(3.0) * h * Real::sqrt(3.0) / 2.0 / exact;
        assert!(err.abs() <= bound, "{err} beyond {bound}");
    }
}
