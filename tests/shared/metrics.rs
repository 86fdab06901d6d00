//! The accuracy metrics, each on its own (issue 6).

use crate::dim::math::{self, Real, Vector, DIM};
use crate::dim::mesh::{CellKind, Mesh};
use crate::scenes::metrics::{shape_error, trajectory_error, uniaxial_volume_change, volume_ratio};

fn lattice() -> Mesh {
    Mesh::cuboid(Vector::splat(0.5), [3; DIM], CellKind::Simplex).unwrap()
}

#[test]
fn trajectory_error_is_the_rms_distance_over_size() {
    let a: Vec<Vector> = (0..10).map(|k| Vector::splat(k as Real)).collect();
    assert_eq!(trajectory_error(&a, &a, 1.0), 0.0);
    let mut shift = Vector::ZERO;
    shift[0] = 0.3;
    let b: Vec<Vector> = a.iter().map(|p| *p + shift).collect();
    assert!((trajectory_error(&b, &a, 2.0) - 0.15).abs() < 1e-6);
    // A run cut short compares its prefix; half the samples off by 0.3, half exact.
    let mut c = a.clone();
    for p in c.iter_mut().take(5) {
        *p += shift;
    }
    let expected: Real = (0.5 * 0.3 * 0.3_f32).sqrt();
    assert!((trajectory_error(&c, &a, 1.0) - expected).abs() < 1e-6);
    assert!((trajectory_error(&b[..4], &a, 1.0) - 0.3).abs() < 1e-6);
    assert!(trajectory_error(&[], &a, 1.0).is_nan());
}

#[test]
fn shape_error_ignores_rigid_motion_and_sees_a_stretch() {
    let mesh = lattice();
    let rest = mesh.nodes().to_vec();
    let masses = vec![1.0; rest.len()];
    let rot = math::rotation_from_angle(math::planar_angle(0.7));
    let mut t = Vector::ZERO;
    t[0] = 3.0;
    t[1] = -1.0;
    let moved: Vec<Vector> = rest.iter().map(|p| rot * *p + t).collect();
    assert!(shape_error(&moved, &rest, &masses, 1.0) < 1e-5);
    // Stretched 10 % along x: the corner nodes are 0.05 from where the fit puts them.
    let stretched: Vec<Vector> = rest
        .iter()
        .map(|p| {
            let mut q = *p;
            q[0] *= 1.1;
            rot * q + t
        })
        .collect();
    let e = shape_error(&stretched, &rest, &masses, 1.0);
    assert!((e - 0.05).abs() < 1e-4, "stretch error {e}");
}

#[test]
fn volume_ratio_of_a_scaled_mesh() {
    let mesh = lattice();
    assert!((volume_ratio(&mesh, mesh.nodes()) - 1.0).abs() < 1e-6);
    let scaled: Vec<Vector> = mesh.nodes().iter().map(|p| *p * 0.9).collect();
    let expected: Real = 0.9_f32.powi(DIM as i32);
    assert!((volume_ratio(&mesh, &scaled) - expected).abs() < 1e-5);
    let boxes = Mesh::cuboid(Vector::splat(0.5), [3; DIM], CellKind::Cube).unwrap();
    let scaled: Vec<Vector> = boxes.nodes().iter().map(|p| *p * 1.2).collect();
    let expected: Real = 1.2_f32.powi(DIM as i32);
    assert!((volume_ratio(&boxes, &scaled) - expected).abs() < 1e-5);
}

#[test]
fn uniaxial_volume_change_follows_poisson() {
    assert_eq!(uniaxial_volume_change(100.0, 1e4, 0.5), 0.0);
    assert!((uniaxial_volume_change(100.0, 1e4, 0.0) + 0.01).abs() < 1e-9);
    assert!((uniaxial_volume_change(100.0, 1e4, 0.3) + 0.004).abs() < 1e-9);
}
