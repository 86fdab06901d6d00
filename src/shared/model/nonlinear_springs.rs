//! Nonlinear springs that resist collapse (Cooper & Maddock 1999, eq. 4).
//!
//! ```text
//! f(L) = k (L0 − L) + k L0²/L − k L0 = k (L0²/L − L)                   (eq. 4)
//! ```
//!
//! is the magnitude pushing the two nodes apart: zero at rest, `→ +∞` as `L → 0`, and
//! `−k (L − L0²/L)` when stretched. Its stiffness `−df/dL = k (1 + L0²/L²)` is `2k` at rest
//! and grows without bound under compression; the pipeline's substep bound follows it.
//! Damping is linear along the spring, as in eq. 1. Stored energy:
//! `U(L) = k [ (L² − L0²)/2 − L0² ln(L/L0) ]`.
//!
//! Material mapping: as [`super::springs`] but with half the constant
//! ([`MATERIAL_SCALE`]` ≈ 2.21` in 3D, `1.25` in 2D), because the spring is `2k` stiff at rest.
//!
//! The force is kept finite at `L → 0` by evaluating the law at `max(L, 10⁻⁶ L0)`.

use super::super::math::{Real, Vector};

/// Calibration constant of the material mapping `k = s E V_s / L0²`: half the linear springs'
/// (`31/14` in 3D, `5/4` in 2D; `model`'s tests check the two agree).
pub const MATERIAL_SCALE: Real = if super::super::math::DIM == 3 {
    31.0 / 14.0
} else {
    5.0 / 4.0
};

/// The magnitude of eq. 4, `k (L0²/L − L)`, positive when it pushes the nodes apart.
#[inline]
pub fn magnitude(length: Real, rest_length: Real, k: Real) -> Real {
    let l = length.max(1e-6 * rest_length);
    k * (rest_length * rest_length / l - l)
}

/// Stored energy `k [ (L² − L0²)/2 − L0² ln(L/L0) ]` (zero at rest), as
/// `k L0² stored((L − L0)/L0)`.
#[inline]
pub fn energy(length: Real, rest_length: Real, k: Real) -> Real {
    let l = length.max(1e-6 * rest_length);
    k * rest_length * rest_length * stored((l - rest_length) / rest_length)
}

/// Up to this relative change of length `|t|`, [`stored`] is its series.
pub const SERIES_REACH: Real = 0.125;

/// The coefficients of `t³ … t⁸` in the series of [`stored`]: `(−1)ⁿ/n`.
pub const SERIES: [Real; 6] = [
    -1.0 / 3.0,
    1.0 / 4.0,
    -1.0 / 5.0,
    1.0 / 6.0,
    -1.0 / 7.0,
    1.0 / 8.0,
];

/// The law's energy over `k L0²` at the relative length `u = 1 + t`: `(u² − 1)/2 − ln u`,
/// which is `t² − t³/3 + t⁴/4 − …`. Near rest its two terms cancel to `t²` (at `t = 10⁻⁴`,
/// single precision kept none of its digits), so up to [`SERIES_REACH`] it is the series,
/// whose terms past [`SERIES`] are below single precision there.
#[inline]
pub fn stored(t: Real) -> Real {
    if t.abs() < SERIES_REACH {
        t * t * (1.0 + t * SERIES.iter().rev().fold(0.0, |s, c| c + t * s))
    } else {
        let u = 1.0 + t;
        0.5 * (u * u - 1.0) - u.ln()
    }
}

/// The force on node `i` of a damped nonlinear spring, and its current axial stiffness
/// `k (1 + L0²/L²)`.
#[inline]
pub fn force(
    xi: Vector,
    xj: Vector,
    vi: Vector,
    vj: Vector,
    rest_length: Real,
    k: Real,
    c: Real,
) -> (Vector, Real) {
    let d = xi - xj;
    let l = d.length();
    if l <= Real::MIN_POSITIVE {
        return (Vector::ZERO, 2.0 * k);
    }
    let n = d / l;
    let lc = l.max(1e-6 * rest_length);
    let stiffness = k * (1.0 + rest_length * rest_length / (lc * lc));
    (
        n * (magnitude(l, rest_length, k) - c * (vi - vj).dot(n)),
        stiffness,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stored_energy_keeps_its_digits_near_rest_and_joins_the_law_beyond() {
        let exact = |t: f64| t + 0.5 * t * t - t.ln_1p();
        for t in [1e-5, -3e-4, 2e-3, -0.05, 0.1, -0.124, 0.126, 0.3, -0.6, 2.0] {
            let (got, want) = (stored(t as Real) as f64, exact(t));
            assert!(
                (got / want - 1.0).abs() < 1e-5,
                "t = {t}: {got} against {want}"
            );
        }
        // The two forms meet at the series' reach.
        let below = stored(SERIES_REACH * (1.0 - 1e-6));
        let above = stored(SERIES_REACH * (1.0 + 1e-6));
        assert!((above / below - 1.0).abs() < 1e-4, "{below} {above}");
    }
}
