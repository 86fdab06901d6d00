//! How far the per-node Gershgorin bounds overestimate a body's highest frequencies: the
//! [`Slack`] the explicit step's substep divides them by, measured once per body by power
//! iteration at rest (`docs/ARCHITECTURE.md` §4.1 tells why and what it guarantees).

use super::super::math::{Real, Rotation, Vector, DIM};
use super::{Accumulator, ModelState};

/// Power iterations per matrix: the Rayleigh quotient (below the top eigenvalue but for the
/// finite differences' error, so the slack is overestimated) is within 3 % of its limit after
/// 30 on the lattices measured (res 5 and 9 cubes, every model, both dimensions).
const ITERATIONS: usize = 30;

/// Divides the measured ratio: covers the power iteration's remaining overestimate.
const MARGIN: Real = 1.1;

/// Strain of the probing displacement (largest node displacement over the smallest cell's
/// size).
const PROBE_STRAIN: f64 = 1e-3;

/// The factors by which a body's Gershgorin bounds overestimate the highest eigenvalue of
/// `M⁻¹K` and `M⁻¹D` at rest (each at least 1).
#[derive(Copy, Clone, Debug, PartialEq)]
pub(crate) struct Slack {
    pub stiffness: Real,
    pub damping: Real,
    /// The calibrated stable substep at rest (s), before the pipeline's safety factor.
    pub at_rest: Real,
    /// The smallest cell's size (m) it was measured with.
    pub cell_size: Real,
}

impl Slack {
    /// No calibration: the bounds as they are.
    pub const NONE: Slack = Slack {
        stiffness: 1.0,
        damping: 1.0,
        at_rest: Real::INFINITY,
        cell_size: 0.0,
    };

    /// Measures the slack of `state` at the rest positions `rest` (every model's forces vanish
    /// there) with lumped `masses`; `cell_size` sets the probing displacement.
    pub fn measure(state: &ModelState, rest: &[Vector], masses: &[Real], cell_size: Real) -> Slack {
        let n = rest.len();
        if n == 0 || cell_size.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Slack::NONE;
        }
        let mut state = state.clone();
        // Every evaluation fits its rotations afresh from the rest orientation: the measure
        // depends on the rest mesh alone (a body restored from a snapshot gets the same one),
        // and each probe linearises the same map.
        let identity = vec![Rotation::IDENTITY; state.warm_start().len()];
        let mut evaluate = |x: &[Vector], v: &[Vector], acc: &mut Accumulator| {
            let _ = state.set_warm_start(&identity);
            acc.clear();
            state.accumulate(x, v, acc);
        };
        // About the centroid, so that a small probe is not lost to the rounding of large
        // coordinates (the forces do not depend on where the body is).
        let centre = rest.iter().copied().sum::<Vector>() / n as Real;
        let rest: Vec<Vector> = rest.iter().map(|p| *p - centre).collect();
        let rest = &rest[..];
        let zero = vec![Vector::ZERO; n];
        let mut acc = Accumulator::new(n);
        evaluate(rest, &zero, &mut acc);
        let f0 = acc.force.clone();
        let bound = |rows: &[Real]| {
            rows.iter()
                .zip(masses)
                .map(|(s, m)| f64::from(*s) / f64::from(*m))
                .fold(0.0, f64::max)
        };
        let (stiffness_bound, damping_bound) = (bound(&acc.stiffness), bound(&acc.damping));
        let inv_sqrt_m: Vec<f64> = masses.iter().map(|m| 1.0 / f64::from(*m).sqrt()).collect();

        // K y ≈ −(f(x0 + s y) − f0)/s, with s so that the largest displacement is a small
        // strain of a cell.
        let stiffness = top_eigenvalue(n, &inv_sqrt_m, |y, out| {
            let largest = y.iter().map(|a| a.length()).fold(0.0, Real::max);
            if largest <= 0.0 {
                out.fill(Vector::ZERO);
                return;
            }
            let s = (PROBE_STRAIN * f64::from(cell_size) / f64::from(largest)) as Real;
            let x: Vec<Vector> = rest.iter().zip(y).map(|(p, d)| *p + *d * s).collect();
            evaluate(&x, &zero, &mut acc);
            for ((o, f), f0) in out.iter_mut().zip(&acc.force).zip(&f0) {
                *o = (*f0 - *f) / s;
            }
        });
        // D y = f(x0, 0) − f(x0, y): the damping forces are linear in the velocities (none to
        // measure for an undamped material).
        let damping = if damping_bound <= 0.0 {
            0.0
        } else {
            top_eigenvalue(n, &inv_sqrt_m, |y, out| {
                evaluate(rest, y, &mut acc);
                for ((o, f), f0) in out.iter_mut().zip(&acc.force).zip(&f0) {
                    *o = *f0 - *f;
                }
            })
        };
        let ratio = |bound: f64, top: f64| {
            if top > 0.0 && bound.is_finite() {
                ((bound / top) as Real / MARGIN).max(1.0)
            } else {
                1.0
            }
        };
        let mut slack = Slack {
            stiffness: ratio(stiffness_bound, stiffness),
            damping: ratio(damping_bound, damping),
            at_rest: Real::INFINITY,
            cell_size,
        };
        evaluate(rest, &zero, &mut acc);
        slack.at_rest = super::stable_substeps(masses, &acc.stiffness, &acc.damping, slack).0;
        slack
    }
}

/// The largest eigenvalue of `M^{-1/2} A M^{-1/2}` (`A` symmetric positive semi-definite,
/// applied by `apply(y, A y)`), estimated by the Rayleigh quotient of [`ITERATIONS`] power
/// iterations from a fixed pseudo-random start.
fn top_eigenvalue(
    n: usize,
    inv_sqrt_m: &[f64],
    mut apply: impl FnMut(&[Vector], &mut [Vector]),
) -> f64 {
    // A fixed xorshift sequence: every mode present, the same start on every run.
    let mut seed: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let mut u: Vec<[f64; DIM]> = (0..n).map(|_| std::array::from_fn(|_| next())).collect();
    let mut y = vec![Vector::ZERO; n];
    let mut ay = vec![Vector::ZERO; n];
    let mut top = 0.0;
    for _ in 0..ITERATIONS {
        let norm = u.iter().flatten().map(|c| c * c).sum::<f64>().sqrt();
        if norm.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) || !norm.is_finite() {
            return 0.0;
        }
        for ((yi, ui), w) in y.iter_mut().zip(&u).zip(inv_sqrt_m) {
            *yi = Vector::from_array(std::array::from_fn(|d| (ui[d] / norm * w) as Real));
        }
        apply(&y, &mut ay);
        // With û = u/|u| and y = M^{-1/2} û: the quotient ûᵀ M^{-1/2} A y = yᵀ A y, and the
        // next iterate M^{-1/2} A y.
        let mut quotient = 0.0;
        for (((ui, ayi), w), yi) in u.iter_mut().zip(&ay).zip(inv_sqrt_m).zip(&y) {
            for d in 0..DIM {
                quotient += f64::from(ayi[d]) * f64::from(yi[d]);
                ui[d] = f64::from(ayi[d]) * w;
            }
        }
        top = quotient;
    }
    top
}
