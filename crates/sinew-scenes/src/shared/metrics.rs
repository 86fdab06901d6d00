//! Accuracy metrics, each a pure function of node states (issue 6). The scenes and the chart
//! command (`examples/chart.rs`) compute every error they plot with these.
//!
//! | metric | function | used by |
//! |---|---|---|
//! | trajectory error against a converged reference | [`trajectory_error`] | `fall` |
//! | shape error after crush and release | [`shape_error`] | `crush` |
//! | volume error under static load | [`volume_ratio`], [`uniaxial_volume_change`] | `crush` (hold) |
//! | spurious rotation | [`super::spurious_acceleration`] | `rotation-error` |

use super::super::lib::math::{self, Real, Vector};
use super::super::lib::mesh::{cell_volume, Mesh};

/// Root-mean-square distance between two trajectories sampled at the same instants, over
/// `size` (so 0.01 is 1 % of the body). Compares the common prefix when one is shorter (a run
/// stopped by an explosion); `NaN` when either is empty.
pub fn trajectory_error(samples: &[Vector], reference: &[Vector], size: Real) -> Real {
    let n = samples.len().min(reference.len());
    if n == 0 {
        return Real::NAN;
    }
    let sum: Real = samples
        .iter()
        .zip(reference)
        .map(|(a, b)| a.distance_squared(*b))
        .sum();
    (sum / n as Real).sqrt() / size
}

/// Largest node distance from the rest shape `rest` moved by the best rigid fit of `x`
/// (mass-weighted centroid, polar rotation of the mass-weighted covariance), over `size`.
/// Zero for any rigid motion of the rest shape.
pub fn shape_error(x: &[Vector], rest: &[Vector], masses: &[Real], size: Real) -> Real {
    let m: Real = masses.iter().sum();
    let centroid = |p: &[Vector]| p.iter().zip(masses).map(|(p, m)| *p * *m).sum::<Vector>() / m;
    let (c, c0) = (centroid(x), centroid(rest));
    let mut a = math::outer(Vector::ZERO, Vector::ZERO);
    for ((x, x0), m) in x.iter().zip(rest).zip(masses) {
        a += math::outer((*x - c) * *m, *x0 - c0);
    }
    let r = math::polar_rotation(a);
    x.iter()
        .zip(rest)
        .map(|(x, x0)| (*x - c - r * (*x0 - c0)).length())
        .fold(0.0, Real::max)
        / size
}

/// Current volume (area in 2D) of `mesh` at `x` over its rest volume.
pub fn volume_ratio(mesh: &Mesh, x: &[Vector]) -> Real {
    let rest = mesh.total_volume();
    let mut p = Vec::with_capacity(mesh.kind().arity());
    let mut now: Real = 0.0;
    for cell in mesh.cells() {
        p.clear();
        p.extend(cell.iter().map(|&i| x[i as usize]));
        now += cell_volume(mesh.kind(), &p);
    }
    now / rest
}

/// Linear elasticity's relative volume change `ΔV/V = −(1 − 2ν) σ / E` of a bar under a
/// uniaxial compressive stress `σ` (Pa; free to expand sideways).
pub fn uniaxial_volume_change(stress: Real, young_modulus: Real, poisson_ratio: Real) -> Real {
    -(1.0 - 2.0 * poisson_ratio) * stress / young_modulus
}
