//! Cooper & Maddock 1999, §3–4, in the paper's local frame: A at the origin, B = (1, 0),
//! rest lengths AB0 = BC0 = 1, CA0 = √2 (C at rest at (1, 1)), k = 1.

use sinew::dim2::math::{Real, Vector};
use sinew::dim2::model::{edge_repulsion, nonlinear_springs, springs};

const A: Vector = Vector::new(0.0, 0.0);
const B: Vector = Vector::new(1.0, 0.0);
const SQRT2: Real = std::f32::consts::SQRT_2;

/// Eq. 3: the standard element's force on C.
fn standard(c: Vector) -> Vector {
    let z = Vector::ZERO;
    springs::linear_force(c, A, z, z, SQRT2, 1.0, 0.0)
        + springs::linear_force(c, B, z, z, 1.0, 1.0, 0.0)
}

/// Eq. 5: the ER element's force on C (edge springs plus repulsion from AB, h0 = 1).
fn edge_repulsion(c: Vector) -> Vector {
    standard(c) + edge_repulsion::repulsion(c, &[A, B], 1.0, 1.0, 1.0).force
}

#[test]
fn standard_element_has_the_three_zeros_of_the_paper() {
    for c in [
        Vector::new(1.0, 1.0),
        Vector::new(SQRT2 / 2.0, 0.0),
        Vector::new(1.0, -1.0),
    ] {
        let f = standard(c);
        assert!(f.length() < 1e-6, "force at {c:?} is {f:?}, expected zero");
    }
    // And it is not zero elsewhere, e.g. halfway up.
    assert!(standard(Vector::new(1.0, 0.5)).length() > 0.1);
}

#[test]
fn edge_repulsion_element_has_no_zero_on_the_x_axis() {
    let mut x = -3.0;
    while x <= 4.0 {
        let f = edge_repulsion(Vector::new(x, 0.0));
        assert!(f.length() > 1.0, "ER force at ({x}, 0) is only {f:?}");
        x += 0.01;
    }
    // Still zero at rest.
    assert!(edge_repulsion(Vector::new(1.0, 1.0)).length() < 1e-6);
}

#[test]
fn edge_repulsion_force_grows_without_bound_towards_the_axis() {
    for x in [-0.5, 0.3, SQRT2 / 2.0, 1.0, 2.0] {
        let mut last: Real = 0.0;
        for y in [1e-1, 1e-2, 1e-3 * 1.5] {
            let f = edge_repulsion(Vector::new(x, y));
            assert!(f.y > 0.0, "ER pushes C away from AB (at ({x}, {y}): {f:?})");
            assert!(
                f.length() > 5.0 * last.max(0.1),
                "force must grow ~1/h: {last} then {}",
                f.length()
            );
            last = f.length();
        }
        assert!(last > 500.0, "near the axis the force is {last}");
    }
}

#[test]
fn nonlinear_spring_is_zero_at_rest_and_infinite_at_zero_length() {
    assert!(nonlinear_springs::magnitude(1.0, 1.0, 1.0).abs() < 1e-7);
    assert!(
        nonlinear_springs::magnitude(2.0, 1.0, 1.0) < 0.0,
        "stretched: pulls back"
    );
    let mut last: Real = 0.0;
    for l in [0.5, 1e-1, 1e-2, 1e-3, 1e-4] {
        let f = nonlinear_springs::magnitude(l, 1.0, 1.0);
        assert!(f > last && f >= 1.0 / l - l - 1e-3, "f({l}) = {f}");
        last = f;
    }
    // The linear spring, by contrast, stays bounded by k L0.
    let z = Vector::ZERO;
    let lin = springs::linear_force(Vector::new(1e-4, 0.0), z, z, z, 1.0, 1.0, 0.0);
    assert!(lin.length() <= 1.0);
}
