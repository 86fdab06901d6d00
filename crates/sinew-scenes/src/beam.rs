//! Beam theory: the reference the `cantilever` scene measures a soft body's sag against.
//!
//! A cantilever of length `L`, clamped at one end and loaded by its own weight `q = ρ g A` per
//! unit length (`A` the cross-section's area), sags at its free end by (Euler–Bernoulli)
//!
//! ```text
//! δ = q L⁴ / (8 E I)
//! ```
//!
//! with `E` Young's modulus and `I` the second moment of area of the section about its neutral
//! axis (`w h³/12` for a `w × h` rectangle bent across `h`). For a rectangle, `q/I = 12 ρ g/h²`
//! whatever the width, so `δ = 3 ρ g L⁴ / (2 E h²)`; the 2D case (per unit depth, `A = h`,
//! `I = h³/12`, density per unit area) gives the same number.
//!
//! Euler–Bernoulli ignores shear. Timoshenko's beam adds `q L²/(2 κ G A)` at the tip, a
//! fraction [`shear_sag_fraction`] `= 2(1 + ν)/(3κ) · (h/L)²` of the bending sag (κ = 5/6 for
//! a rectangle): 1.0 % for `L/h = 10`, ν = 0.3. The theory is linear: it holds while `δ/L`
//! is a few percent.
//!
//! All values are `f64` and SI, whatever the simulation's precision.

/// Shear correction factor κ of a rectangular section (Timoshenko).
pub const RECTANGLE_SHEAR_FACTOR: f64 = 5.0 / 6.0;

/// Euler–Bernoulli tip sag `q L⁴ / (8 E I)` of a cantilever of length `length` (m) under the
/// uniform line load `line_load` (N/m), Young's modulus `young_modulus` (Pa) and second moment
/// of area `second_moment` (m⁴). Non-finite when `young_modulus · second_moment` is zero.
pub fn euler_bernoulli_tip_sag(
    line_load: f64,
    length: f64,
    young_modulus: f64,
    second_moment: f64,
) -> f64 {
    line_load * length.powi(4) / (8.0 * young_modulus * second_moment)
}

/// The first bending angular frequency (rad/s) of a uniform cantilever,
/// `β₁² √(E I / (ρ A L⁴))` with `β₁ = 1.8751` (`mass_per_length` = `ρ A`, kg/m).
pub fn cantilever_first_frequency(
    length: f64,
    young_modulus: f64,
    second_moment: f64,
    mass_per_length: f64,
) -> f64 {
    const BETA1: f64 = 1.875_104_068_711_961;
    BETA1 * BETA1 * (young_modulus * second_moment / (mass_per_length * length.powi(4))).sqrt()
}

/// Timoshenko's shear sag over the Euler–Bernoulli sag for a rectangular cantilever of
/// thickness-to-length ratio `thickness / length` under a uniform load:
/// `4 E I / (κ G A L²) = 2 (1 + ν) / (3 κ) · (h/L)²`.
pub fn shear_sag_fraction(thickness: f64, length: f64, poisson_ratio: f64) -> f64 {
    2.0 * (1.0 + poisson_ratio) / (3.0 * RECTANGLE_SHEAR_FACTOR) * (thickness / length).powi(2)
}

/// Relative error of a measured sag against the theory's: `(measured − theory) / theory`.
/// Positive when the body sags more than the theory (it is too soft). Non-finite when `theory`
/// is zero.
pub fn sag_error(measured: f64, theory: f64) -> f64 {
    (measured - theory) / theory
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::close;

    #[test]
    fn tip_sag_matches_a_worked_example() {
        // A 2 m steel cantilever (E = 200 GPa) of I = 8.33e-6 m⁴ under 1 kN/m:
        // δ = 1000·16 / (8·2e11·8.333e-6) = 1.2 mm.
        let i = 0.1 * 0.1_f64.powi(3) / 12.0;
        let d = euler_bernoulli_tip_sag(1000.0, 2.0, 2.0e11, i);
        assert!(close(d, 1.2e-3, 1e-12), "{d}");
    }

    #[test]
    fn rectangular_section_sag_is_independent_of_the_width() {
        // δ = 3 ρ g L⁴ / (2 E h²) for a rectangle loaded by its own weight.
        let (rho, g, l, e, h): (f64, f64, f64, f64, f64) = (1000.0, 9.81, 1.0, 1.0e8, 0.1);
        let expected = 3.0 * rho * g * l.powi(4) / (2.0 * e * h * h);
        for w in [1.0, 0.1, 0.02] {
            let q = rho * g * w * h;
            let d = euler_bernoulli_tip_sag(q, l, e, w * h * h * h / 12.0);
            assert!(close(d, expected, 1e-12), "w = {w}: {d} vs {expected}");
        }
        assert!(close(expected, 0.0147150, 1e-5));
    }

    #[test]
    fn sag_scales_as_the_fourth_power_of_length_and_inverse_stiffness() {
        let d1 = euler_bernoulli_tip_sag(3.0, 1.0, 5.0, 7.0);
        assert!(close(
            euler_bernoulli_tip_sag(3.0, 2.0, 5.0, 7.0),
            16.0 * d1,
            1e-12
        ));
        assert!(close(
            euler_bernoulli_tip_sag(3.0, 1.0, 10.0, 7.0),
            0.5 * d1,
            1e-12
        ));
        assert!(close(
            euler_bernoulli_tip_sag(6.0, 1.0, 5.0, 14.0),
            d1,
            1e-12
        ));
    }

    #[test]
    fn first_frequency_of_a_known_beam() {
        // β₁² = 3.5160; with E I / (ρ A L⁴) = 100, ω₁ = 35.160 rad/s.
        let w = cantilever_first_frequency(1.0, 100.0, 1.0, 1.0);
        assert!(close(w, 35.160_15, 1e-6), "{w}");
    }

    #[test]
    fn shear_correction_of_a_slender_rectangle() {
        // 2·1.3/(3·5/6)·0.01 = 0.0104.
        let f = shear_sag_fraction(0.1, 1.0, 0.3);
        assert!(close(f, 0.0104, 1e-12), "{f}");
    }

    #[test]
    fn sag_error_is_signed_and_relative() {
        assert!(close(sag_error(1.1, 1.0), 0.1, 1e-12));
        assert!(close(sag_error(0.85, 1.0), -0.15, 1e-12));
        assert_eq!(sag_error(2.0, 2.0), 0.0);
        assert!(close(sag_error(-0.01, 0.02), -1.5, 1e-12));
        assert!(!sag_error(1.0, 0.0).is_finite());
    }
}
