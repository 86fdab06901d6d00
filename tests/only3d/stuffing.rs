//! Isosurface stuffing (issue 30): `Mesh::stuffed` of a ball, a capsule and a torus (a closed
//! triangle mesh) at a cell size of a tenth of the shape's thickness (its smallest width: the
//! ball's and the capsule's diameter, the torus's tube), held to the bounds:
//! every tetrahedron positive, dihedral angles within [9°, 166°] (the paper's bound for its
//! safe parameters is [9.06°, 160.5°]), volume within 2 % of the shape's, every boundary
//! vertex within 1 % of the cell size of the surface, the boundary a closed manifold.

use sinew::dim3::math::{Real, Vector};
use sinew::dim3::rapier::parry::shape::{Ball, Capsule, Shape};
use sinew::dim3::{BuildError, Mesh, Surface};
use sinew_scenes::dim3::meshing::{dihedral_range, torus};

/// What a stuffed mesh measures.
#[derive(Debug)]
struct Quality {
    cells: usize,
    smallest_dihedral: Real,
    largest_dihedral: Real,
    volume: Real,
    /// Farthest boundary vertex from the shape's surface.
    off_surface: Real,
}

fn measure(mesh: &Mesh, shape: &dyn Shape) -> Quality {
    let x = mesh.nodes();
    let (lo, hi) = dihedral_range(mesh);
    let faces = mesh.boundary_facets().to_vec();
    let surface = Surface::new(x.to_vec(), faces.clone())
        .unwrap_or_else(|e| panic!("the boundary is not a closed manifold: {e}"));
    let mut off: Real = 0.0;
    for v in faces.iter().flatten() {
        let p = x[*v as usize];
        let on = shape.project_local_point(p, false).point;
        off = off.max(p.distance(on));
    }
    assert!((surface.volume() - mesh.total_volume()).abs() < 1e-3 * mesh.total_volume());
    Quality {
        cells: mesh.cell_indices().len() / 4,
        smallest_dihedral: lo,
        largest_dihedral: hi,
        volume: mesh.total_volume(),
        off_surface: off,
    }
}

/// Stuffs `shape` at `cell` and checks the bounds against its `volume`.
fn check(name: &str, shape: &dyn Shape, volume: Real, cell: Real) -> Quality {
    let mesh = Mesh::stuffed(shape, cell).unwrap();
    let q = measure(&mesh, shape);
    println!("{name} at {cell}: {q:?} (shape volume {volume})");
    assert!(q.smallest_dihedral >= 9.0, "{name}: {q:?}");
    assert!(q.largest_dihedral <= 166.0, "{name}: {q:?}");
    assert!(
        (q.volume - volume).abs() <= 0.02 * volume,
        "{name}: {q:?} against {volume}"
    );
    assert!(q.off_surface <= 0.01 * cell, "{name}: {q:?}");
    q
}

#[test]
fn a_ball_is_stuffed_within_the_bounds() {
    let r = 0.5;
    let exact = 4.0 / 3.0 * std::f64::consts::PI as Real * r * r * r;
    check("ball", &Ball::new(r), exact, 0.1 * 2.0 * r);
}

#[test]
fn a_capsule_is_stuffed_within_the_bounds() {
    let (half, r) = (0.4, 0.25);
    let pi = std::f64::consts::PI as Real;
    let exact = pi * r * r * 2.0 * half + 4.0 / 3.0 * pi * r * r * r;
    let capsule = Capsule::new_y(half, r);
    check("capsule", &capsule, exact, 0.1 * 2.0 * r);
}

#[test]
fn a_torus_asset_is_stuffed_within_the_bounds() {
    let surface = torus(0.4, 0.15, 96, 48);
    let exact = surface.volume();
    check("torus", &surface.to_trimesh(), exact, 0.1 * 2.0 * 0.15);
}

#[test]
fn a_fine_ball_keeps_its_angles_and_converges() {
    let r = 0.5;
    let exact = 4.0 / 3.0 * std::f64::consts::PI as Real * r * r * r;
    let coarse = check("ball", &Ball::new(r), exact, 0.1);
    let fine = check("ball", &Ball::new(r), exact, 0.05);
    assert!((fine.volume - exact).abs() < (coarse.volume - exact).abs() + 1e-4);
    assert!(fine.cells > 6 * coarse.cells, "{fine:?} {coarse:?}");
}

#[test]
fn stuffing_errors() {
    let ball = Ball::new(0.5);
    for bad in [0.0, -1.0, Real::NAN, Real::INFINITY] {
        assert!(matches!(
            Mesh::stuffed(&ball, bad),
            Err(BuildError::InvalidParameter {
                name: "cell_size",
                ..
            })
        ));
    }
    // A cell far larger than the shape: no lattice vertex inside.
    assert!(Mesh::stuffed(&Ball::new(0.01), 1.0).is_err());
}

#[test]
fn every_alignment_and_a_box_keep_the_angle_bounds() {
    // Radii and cell sizes that put the lattice at many offsets against the surface, and a
    // box, whose edges and corners the lattice rounds: the angle bounds and a closed
    // manifold boundary hold whatever the surface.
    use sinew::dim3::rapier::parry::shape::Cuboid;
    let mut worst: (Real, Real) = (180.0, 0.0);
    for k in 0..12 {
        let r = 0.3 + 0.037 * k as Real;
        let cell = 0.07 + 0.0113 * k as Real;
        for shape in [
            Box::new(Ball::new(r)) as Box<dyn Shape>,
            Box::new(Cuboid::new(Vector::new(r, 0.7 * r, 0.45 * r))),
        ] {
            let mesh = Mesh::stuffed(&*shape, cell).unwrap();
            let q = measure(&mesh, &*shape);
            assert!(
                q.smallest_dihedral >= 9.0 && q.largest_dihedral <= 166.0,
                "{r} {cell}: {q:?}"
            );
            worst = (
                worst.0.min(q.smallest_dihedral),
                worst.1.max(q.largest_dihedral),
            );
        }
    }
    println!(
        "dihedral angles over every run: {:.1}° … {:.1}°",
        worst.0, worst.1
    );
}
