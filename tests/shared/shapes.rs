//! Lattices cut from parry shapes (`Mesh::from_shape`, issue 7): volumes against the analytic
//! ones, connectivity, and the errors.

use std::collections::HashMap;

use crate::dim::math::{Pose, Real, Vector, DIM};
use crate::dim::mesh::cube::{bits_to_vtk, faces};
use crate::dim::rapier::parry::query::PointQuery;
use crate::dim::rapier::parry::shape::{Ball, Capsule, Shape, SharedShape};
use crate::dim::{BuildError, CellKind, Mesh};

const PI: Real = std::f32::consts::PI;

/// Relative error of the voxelised volume at a few cell sizes, printed and checked against
/// the staircase bound (the boxes misclassified lie within half a cell diagonal of the
/// surface: |ΔV| ≤ surface · h·√DIM / 2); the error at the finest size is returned.
fn volume_errors(
    name: &str,
    shape: &dyn Shape,
    exact: Real,
    surface: Real,
    sizes: &[Real],
) -> Real {
    let mut last = Real::NAN;
    for &h in sizes {
        let mesh = Mesh::from_shape(shape, h, CellKind::Cube).unwrap();
        last = (mesh.total_volume() - exact) / exact;
        let bound = surface * h * (DIM as Real).sqrt() / 2.0 / exact;
        println!(
            "{name} ({DIM}D): cell {h}: volume error {:+.3}% (bound {:.1}%)",
            100.0 * last,
            100.0 * bound
        );
        assert!(
            last.abs() <= bound,
            "{name}: cell {h}: error {last} beyond {bound}"
        );
    }
    last
}

/// Number of facet-connected components of a mesh's cells (union-find over shared facets).
fn components(mesh: &Mesh) -> usize {
    fn find(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    let arity = mesh.kind().arity();
    let local: Vec<Vec<usize>> = match mesh.kind() {
        CellKind::Simplex => (0..arity)
            .map(|skip| (0..arity).filter(|&k| k != skip).collect())
            .collect(),
        CellKind::Cube => faces()
            .into_iter()
            .map(|f| f.into_iter().map(bits_to_vtk).collect())
            .collect(),
    };
    let mut parent: Vec<usize> = (0..mesh.num_cells()).collect();
    let mut seen: HashMap<Vec<u32>, usize> = HashMap::new();
    for (k, c) in mesh.cells().enumerate() {
        for f in &local {
            let mut key: Vec<u32> = f.iter().map(|&l| c[l]).collect();
            key.sort_unstable();
            if let Some(&other) = seen.get(&key) {
                let (a, b) = (find(&mut parent, k), find(&mut parent, other));
                parent[a] = b;
            } else {
                seen.insert(key, k);
            }
        }
    }
    (0..mesh.num_cells())
        .filter(|&k| find(&mut parent, k) == k)
        .count()
}

#[test]
fn voxelised_ball_volume() {
    let r = 1.0;
    let exact = if DIM == 3 {
        4.0 / 3.0 * PI * r * r * r
    } else {
        PI * r * r
    };
    let surface = if DIM == 3 {
        4.0 * PI * r * r
    } else {
        2.0 * PI * r
    };
    let err = volume_errors(
        "ball",
        &Ball::new(r),
        exact,
        surface,
        &[0.2, 0.1, 0.05, 0.025],
    );
    assert!(err.abs() < 0.005, "{err}");
}

#[test]
fn voxelised_capsule_volume() {
    let (a, r) = (0.6, 0.4);
    let exact = if DIM == 3 {
        PI * r * r * 2.0 * a + 4.0 / 3.0 * PI * r * r * r
    } else {
        2.0 * r * 2.0 * a + PI * r * r
    };
    let surface = if DIM == 3 {
        2.0 * PI * r * 2.0 * a + 4.0 * PI * r * r
    } else {
        2.0 * 2.0 * a + 2.0 * PI * r
    };
    let capsule = Capsule::new_y(a, r);
    let err = volume_errors("capsule", &capsule, exact, surface, &[0.1, 0.05, 0.025]);
    assert!(err.abs() < 0.01, "{err}");
}

/// The cross-polytope (octahedron in 3D, diamond in 2D) as a convex hull: volume 2^DIM / DIM!.
#[test]
fn voxelised_convex_hull_volume() {
    let mut points = Vec::new();
    for d in 0..DIM {
        for s in [-1.0, 1.0] {
            let mut p = Vector::ZERO;
            p[d] = s;
            points.push(p);
        }
    }
    let hull = SharedShape::convex_hull(&points).unwrap();
    let exact = if DIM == 3 { 8.0 / 6.0 } else { 2.0 };
    // Cell sizes that do not put box centres on the faces (|x| + |y| = 1 through the centres
    // of a lattice of spacing 1/k counts every boundary box as inside: a +h·perimeter/2 bias).
    let surface = if DIM == 3 {
        4.0 * Real::sqrt(3.0)
    } else {
        4.0 * Real::sqrt(2.0)
    };
    let err = volume_errors(
        "convex hull",
        hull.as_ref(),
        exact,
        surface,
        &[0.07, 0.035, 0.0233],
    );
    assert!(err.abs() < 0.025, "{err}");
}

/// The simplex split covers the same boxes: same volume, `DIM!` simplices per box, a closed
/// boundary, one piece.
#[test]
fn voxelised_simplices_match_boxes() {
    let shape = Capsule::new_y(0.5, 0.3);
    let boxes = Mesh::from_shape(&shape, 0.1, CellKind::Cube).unwrap();
    let simplices = Mesh::from_shape(&shape, 0.1, CellKind::Simplex).unwrap();
    let factorial: usize = (1..=DIM).product();
    assert_eq!(simplices.num_cells(), factorial * boxes.num_cells());
    assert!((simplices.total_volume() - boxes.total_volume()).abs() < 1e-4);
    assert_eq!(simplices.nodes().len(), boxes.nodes().len());
    assert_eq!(components(&boxes), 1);
    assert_eq!(components(&simplices), 1);
    // The mesh is in the shape's frame: every node within a cell diagonal of the shape.
    let diagonal = 0.1 * (DIM as Real).sqrt();
    for p in simplices.nodes() {
        let d = shape.distance_to_local_point(*p, true);
        assert!(d <= diagonal + 1e-5, "node {p:?} is {d} from the shape");
    }
}

/// Two disjoint balls: only the larger one is kept.
#[test]
fn voxelised_islands_are_dropped() {
    let compound = SharedShape::compound(vec![
        (
            Pose::from_translation(Vector::X * -2.0),
            SharedShape::ball(1.0),
        ),
        (
            Pose::from_translation(Vector::X * 2.0),
            SharedShape::ball(0.5),
        ),
    ]);
    let mesh = Mesh::from_shape(compound.as_ref(), 0.1, CellKind::Simplex).unwrap();
    let big = Mesh::from_shape(&Ball::new(1.0), 0.1, CellKind::Simplex).unwrap();
    assert_eq!(components(&mesh), 1);
    assert!((mesh.total_volume() - big.total_volume()).abs() < 0.02 * big.total_volume());
    assert!(
        mesh.nodes().iter().all(|p| p.x < 0.0),
        "the small ball was kept"
    );
}

#[test]
fn from_shape_errors() {
    let ball = Ball::new(1.0);
    for h in [0.0, -1.0, Real::NAN, Real::INFINITY] {
        let e = Mesh::from_shape(&ball, h, CellKind::Simplex).unwrap_err();
        assert!(
            matches!(
                e,
                BuildError::InvalidParameter {
                    name: "cell_size",
                    ..
                }
            ),
            "{e}"
        );
    }
    let e = Mesh::from_shape(&ball, 1e-4, CellKind::Simplex).unwrap_err();
    assert!(e.to_string().contains("2^27"), "{e}");
    let e =
        Mesh::from_shape(&*SharedShape::halfspace(Vector::Y), 0.1, CellKind::Simplex).unwrap_err();
    assert!(
        matches!(e, BuildError::InvalidParameter { name: "shape", .. }),
        "{e}"
    );
    // Two small balls far apart, one cell over both: its centre falls between them.
    let apart = SharedShape::compound(vec![
        (
            Pose::from_translation(Vector::X * -1.0),
            SharedShape::ball(0.1),
        ),
        (Pose::from_translation(Vector::X), SharedShape::ball(0.1)),
    ]);
    let e = Mesh::from_shape(apart.as_ref(), 10.0, CellKind::Cube).unwrap_err();
    assert!(e.to_string().contains("centre is inside"), "{e}");
}

#[test]
fn voxelised_nodes_reach_at_most_half_a_box_diagonal_past_the_shape() {
    // What the docs tell a user placing a voxelised body next to a two-sided surface. The
    // largest reach is taken, so the bound is met, not loose: it is at least half of it.
    let (radius, cell) = (0.1, 0.025);
    let ball = Ball::new(radius);
    let mesh = Mesh::from_shape(&ball, cell, CellKind::Simplex).unwrap();
    let bound = 0.5 * (DIM as Real).sqrt() * cell;
    let reach = mesh
        .nodes()
        .iter()
        .map(|p| p.length() - radius)
        .fold(Real::NEG_INFINITY, Real::max);
    assert!(reach <= bound + 1e-6, "a node {reach} m past the ball");
    assert!(
        reach >= 0.5 * bound,
        "nodes reach only {reach} m past the ball"
    );
}
