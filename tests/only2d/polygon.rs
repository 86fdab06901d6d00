//! 2D-only meshes: polygons triangulated (`Mesh::polygon`) and a 2D triangle mesh voxelised
//! (issue 7).

use sinew::dim2::math::{Real, Vector};
use sinew::dim2::rapier::parry::shape::TriMesh;
use sinew::dim2::{CellKind, Mesh, PolygonError};

fn v(x: Real, y: Real) -> Vector {
    Vector::new(x, y)
}

fn boundary_length(mesh: &Mesh) -> Real {
    mesh.boundary_facets()
        .iter()
        .map(|f| mesh.nodes()[f[0] as usize].distance(mesh.nodes()[f[1] as usize]))
        .sum()
}

fn perimeter(ring: &[Vector]) -> Real {
    (0..ring.len())
        .map(|k| ring[k].distance(ring[(k + 1) % ring.len()]))
        .sum()
}

/// Distance from `p` to the closest edge of `ring`.
fn distance_to_ring(ring: &[Vector], p: Vector) -> Real {
    (0..ring.len())
        .map(|k| {
            let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
            let t = ((p - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
            p.distance(a + (b - a) * t)
        })
        .fold(Real::INFINITY, Real::min)
}

fn l_shape() -> Vec<Vector> {
    vec![
        v(0.0, 0.0),
        v(2.0, 0.0),
        v(2.0, 1.0),
        v(1.0, 1.0),
        v(1.0, 2.0),
        v(0.0, 2.0),
    ]
}

/// The mesh covers the polygon exactly (area, boundary length, boundary nodes on the
/// polygon's edges) and respects the area limit; the input orientation does not matter.
#[test]
fn polygon_area_boundary_and_refinement() {
    for ring in [l_shape(), l_shape().into_iter().rev().collect()] {
        let max_area = 0.01;
        let mesh = Mesh::polygon(&ring, max_area).unwrap();
        assert!(
            (mesh.total_volume() - 3.0).abs() < 1e-4,
            "{}",
            mesh.total_volume()
        );
        let largest = mesh.rest_volumes().iter().copied().fold(0.0, Real::max);
        assert!(largest <= max_area * 1.0001, "largest triangle {largest}");
        assert!(mesh.num_cells() >= 300, "{} triangles", mesh.num_cells());
        assert!((boundary_length(&mesh) - perimeter(&ring)).abs() < 1e-4);
        for &i in mesh.boundary_nodes() {
            let d = distance_to_ring(&ring, mesh.nodes()[i as usize]);
            assert!(d < 1e-5, "boundary node {i} is {d} off the polygon");
        }
        // Every input vertex is a node (constraint edges kept, corners not cut).
        for p in &ring {
            assert!(
                mesh.nodes().iter().any(|n| n.distance(*p) < 1e-6),
                "corner {p:?} lost"
            );
        }
    }
}

#[test]
fn polygon_with_holes() {
    let outer = vec![v(-2.0, -2.0), v(2.0, -2.0), v(2.0, 2.0), v(-2.0, 2.0)];
    // A square hole (counter-clockwise) and a triangular one (clockwise).
    let square = vec![v(-1.5, -1.5), v(-0.5, -1.5), v(-0.5, -0.5), v(-1.5, -0.5)];
    let triangle = vec![v(0.5, 0.5), v(1.0, 1.5), v(1.5, 0.5)];
    let holes = vec![square.clone(), triangle.clone()];
    let mesh = Mesh::polygon_with_holes(&outer, &holes, 0.05).unwrap();
    let area = 16.0 - 1.0 - 0.5;
    assert!(
        (mesh.total_volume() - area).abs() < 1e-3,
        "{}",
        mesh.total_volume()
    );
    let length = perimeter(&outer) + perimeter(&square) + perimeter(&triangle);
    assert!((boundary_length(&mesh) - length).abs() < 1e-3);
    // No triangle inside a hole.
    for c in mesh.cells() {
        let centroid = c.iter().map(|&i| mesh.nodes()[i as usize]).sum::<Vector>() / 3.0;
        assert!(
            !(centroid.x > -1.5 && centroid.x < -0.5 && centroid.y > -1.5 && centroid.y < -0.5)
        );
    }
}

#[test]
fn polygon_errors() {
    let max_area = 0.1;
    let e = Mesh::polygon(&[v(0.0, 0.0), v(1.0, 0.0)], max_area).unwrap_err();
    assert_eq!(e, PolygonError::TooFewVertices { ring: 0, count: 2 });
    let e = Mesh::polygon(&[v(0.0, 0.0), v(1.0, 0.0), v(Real::NAN, 1.0)], max_area).unwrap_err();
    assert!(
        matches!(
            e,
            PolygonError::NonFinite {
                ring: 0,
                vertex: 2,
                ..
            }
        ),
        "{e}"
    );
    let e = Mesh::polygon(
        &[v(0.0, 0.0), v(1.0, 0.0), v(1.0, 0.0), v(0.0, 1.0)],
        max_area,
    )
    .unwrap_err();
    assert_eq!(e, PolygonError::RepeatedVertex { ring: 0, vertex: 1 });
    let e = Mesh::polygon(&[v(0.0, 0.0), v(1.0, 0.0), v(2.0, 0.0)], max_area).unwrap_err();
    assert_eq!(e, PolygonError::ZeroArea { ring: 0 });
    // A bow-tie.
    let e = Mesh::polygon(
        &[v(0.0, 0.0), v(2.0, 2.0), v(2.0, 0.0), v(0.0, 1.0)],
        max_area,
    )
    .unwrap_err();
    assert!(matches!(e, PolygonError::SelfIntersecting { .. }), "{e}");
    assert!(e.to_string().contains("intersects itself"), "{e}");
    // A ring folding back along its own edge, and one touching itself at a vertex.
    let e = Mesh::polygon(
        &[v(0.0, 0.0), v(2.0, 0.0), v(1.0, 0.0), v(1.0, 1.0)],
        max_area,
    )
    .unwrap_err();
    assert!(
        matches!(
            e,
            PolygonError::SelfIntersecting {
                edge_a: 0,
                edge_b: 1,
                ..
            }
        ),
        "{e}"
    );
    let touching = [
        v(0.0, 0.0),
        v(2.0, 0.0),
        v(1.0, 1.0),
        v(2.0, 2.0),
        v(0.0, 2.0),
        v(1.0, 1.0),
    ];
    let e = Mesh::polygon(&touching, max_area).unwrap_err();
    assert!(matches!(e, PolygonError::SelfIntersecting { .. }), "{e}");
    // Holes: outside, crossing the outer ring, nested.
    let outer = [v(0.0, 0.0), v(4.0, 0.0), v(4.0, 4.0), v(0.0, 4.0)];
    let square =
        |x: Real, y: Real, s: Real| vec![v(x, y), v(x + s, y), v(x + s, y + s), v(x, y + s)];
    let e = Mesh::polygon_with_holes(&outer, &[square(5.0, 5.0, 1.0)], max_area).unwrap_err();
    assert_eq!(e, PolygonError::HoleOutside { ring: 1 });
    let e = Mesh::polygon_with_holes(&outer, &[square(3.0, 3.0, 2.0)], max_area).unwrap_err();
    assert!(
        matches!(
            e,
            PolygonError::SelfIntersecting {
                ring_a: 0,
                ring_b: 1,
                ..
            }
        ),
        "{e}"
    );
    let e = Mesh::polygon_with_holes(
        &outer,
        &[square(1.0, 1.0, 2.0), square(1.5, 1.5, 0.5)],
        max_area,
    )
    .unwrap_err();
    assert_eq!(e, PolygonError::NestedHole { ring: 2, outer: 1 });
    // Area limits.
    for bad in [0.0, -1.0, Real::NAN] {
        let e = Mesh::polygon(&outer, bad).unwrap_err();
        assert!(matches!(e, PolygonError::InvalidMaxArea { .. }), "{e}");
    }
    let e = Mesh::polygon(&outer, 1e-9).unwrap_err();
    assert!(matches!(e, PolygonError::TooFine { .. }), "{e}");
}

/// A 2D triangle mesh is solid: the square [-1, 1]² of two triangles, aligned with the
/// lattice, is voxelised exactly.
#[test]
fn voxelised_2d_trimesh_area() {
    let vertices = vec![v(-1.0, -1.0), v(1.0, -1.0), v(1.0, 1.0), v(-1.0, 1.0)];
    let trimesh = TriMesh::new(vertices, vec![[0, 1, 2], [0, 2, 3]]).unwrap();
    let mesh = Mesh::from_shape(&trimesh, 0.1, CellKind::Simplex).unwrap();
    assert!(
        (mesh.total_volume() - 4.0).abs() < 1e-4,
        "{}",
        mesh.total_volume()
    );
    assert_eq!(mesh.num_cells(), 2 * 400);
}

/// A 2D read takes meshes in the x-y plane: a point with z ≠ 0 is an error at its line,
/// in every format that writes z.
#[test]
fn reading_2d_requires_z_zero() {
    use sinew::dim2::mesh::io::gmsh::{self, GmshVersion};
    use sinew::dim2::mesh::io::{vtk, ReadError};
    let mesh = Mesh::cuboid(Vector::splat(0.5), [2, 2], CellKind::Simplex).unwrap();
    let text = vtk::to_string(&mesh);
    // Line 6 is the first point.
    let bad: Vec<String> = text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i == 5 {
                l.replace(" 0", " 0.25")
            } else {
                l.to_owned()
            }
        })
        .collect();
    let e = vtk::read_str(&bad.join("\n")).unwrap_err();
    assert!(
        matches!(e, ReadError::OutOfPlane { z, .. } if z == 0.25),
        "{e}"
    );
    assert!(e.to_string().contains("line 6"), "{e}");
    let text = gmsh::to_string(&mesh, GmshVersion::V2_2);
    let e = gmsh::read_str(&text.replacen("1 -0.5 -0.5 0", "1 -0.5 -0.5 1", 1)).unwrap_err();
    assert!(matches!(e, ReadError::OutOfPlane { .. }), "{e}");
    assert!(e.to_string().contains("line 6"), "{e}");
}
