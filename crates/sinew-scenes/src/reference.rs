//! Physics references that no model under test computes: linear elasticity, vibration and
//! contact in closed form (issue 17). Each chart's error is measured against one of these, or
//! against the cantilever formulas of [`crate::beam`].
//!
//! - Uniaxial stress `σ` on an isotropic solid of Young's modulus `E` and Poisson's ratio `ν`:
//!   axial strain `σ/E`, lateral strain `−ν σ/E`; read backwards, the pair of strains gives
//!   `E` and `ν` ([`uniaxial_strains`], [`young_and_poisson`]).
//! - Hydrostatic pressure `p`: volume change `ΔV/V = −p/K` with the bulk modulus
//!   `K = E / (3 (1 − 2ν))` ([`bulk_modulus`], [`volume_strain`]).
//! - A bar clamped at one end, free at the other: axial angular frequencies
//!   `ω_n = (2n − 1) π/(2L) · √(E/ρ)` ([`bar_axial_frequency`]).
//! - Free vibration with damping ratio `ζ`: successive peaks fall by the logarithmic decrement
//!   `δ = 2πζ/√(1 − ζ²)`, and `ζ = δ/√(4π² + δ²)` ([`log_decrement`], [`damping_ratio`]).
//! - Hertz: an elastic sphere of radius `R` pressed by `d` on a rigid flat touches over a disc
//!   of radius `a = √(R d)` and pushes back with `F = (4/3) E* √R d^{3/2}`,
//!   `E* = E/(1 − ν²)` ([`hertz_force`], [`hertz_indentation`], [`hertz_contact_radius`]). Valid
//!   while `a ≪ R`.
//!
//! All values are `f64` and SI.

use std::f64::consts::PI;

/// Axial and lateral strains of an isotropic solid under a uniaxial stress `stress` (Pa).
pub fn uniaxial_strains(stress: f64, young_modulus: f64, poisson_ratio: f64) -> (f64, f64) {
    let axial = stress / young_modulus;
    (axial, -poisson_ratio * axial)
}

/// Young's modulus and Poisson's ratio from a uniaxial test: the stress (Pa), and the axial
/// and lateral strains it caused.
pub fn young_and_poisson(stress: f64, axial_strain: f64, lateral_strain: f64) -> (f64, f64) {
    (stress / axial_strain, -lateral_strain / axial_strain)
}

/// Bulk modulus `K = E / (3 (1 − 2ν))`, Pa (infinite at ν = 0.5).
pub fn bulk_modulus(young_modulus: f64, poisson_ratio: f64) -> f64 {
    young_modulus / (3.0 * (1.0 - 2.0 * poisson_ratio))
}

/// Volume strain `ΔV/V = −p/K` under a hydrostatic pressure `pressure` (Pa, positive
/// compressing); small strains.
pub fn volume_strain(pressure: f64, young_modulus: f64, poisson_ratio: f64) -> f64 {
    -pressure * (1.0 - 2.0 * poisson_ratio) * 3.0 / young_modulus
}

/// The `mode`-th (1, 2, …) axial angular frequency (rad/s) of a bar of length `length` clamped
/// at one end and free at the other: `(2n − 1) π/(2L) · √(E/ρ)`.
pub fn bar_axial_frequency(mode: u32, length: f64, young_modulus: f64, density: f64) -> f64 {
    (2.0 * mode as f64 - 1.0) * PI / (2.0 * length) * (young_modulus / density).sqrt()
}

/// The `mode`-th (1, 2, …) axial angular frequency (rad/s) of a bar of length `length` free
/// at both ends: `n π/L · √(E/ρ)`.
pub fn free_bar_axial_frequency(mode: u32, length: f64, young_modulus: f64, density: f64) -> f64 {
    mode as f64 * PI / length * (young_modulus / density).sqrt()
}

/// Logarithmic decrement `ln(x_k / x_{k+1})` of successive peaks of a free vibration with
/// damping ratio `ζ` (`0 ≤ ζ < 1`).
pub fn log_decrement(damping_ratio: f64) -> f64 {
    2.0 * PI * damping_ratio / (1.0 - damping_ratio * damping_ratio).sqrt()
}

/// The damping ratio a logarithmic decrement `δ` measures: `δ/√(4π² + δ²)`.
pub fn damping_ratio(log_decrement: f64) -> f64 {
    log_decrement / (4.0 * PI * PI + log_decrement * log_decrement).sqrt()
}

/// Hertz's contact modulus of an elastic body on a rigid one: `E/(1 − ν²)`.
pub fn contact_modulus(young_modulus: f64, poisson_ratio: f64) -> f64 {
    young_modulus / (1.0 - poisson_ratio * poisson_ratio)
}

/// Hertz: the force (N) of an elastic sphere of radius `radius` pressed by `indentation` (m)
/// on a rigid flat, `(4/3) E* √R d^{3/2}`.
pub fn hertz_force(radius: f64, indentation: f64, young_modulus: f64, poisson_ratio: f64) -> f64 {
    4.0 / 3.0
        * contact_modulus(young_modulus, poisson_ratio)
        * radius.sqrt()
        * indentation.max(0.0).powf(1.5)
}

/// Hertz: the indentation (m) under a force `force` (N), inverse of [`hertz_force`].
pub fn hertz_indentation(radius: f64, force: f64, young_modulus: f64, poisson_ratio: f64) -> f64 {
    let e = contact_modulus(young_modulus, poisson_ratio);
    (3.0 * force.max(0.0) / (4.0 * e * radius.sqrt())).powf(2.0 / 3.0)
}

/// Hertz: the contact disc's radius `√(R d)` (m).
pub fn hertz_contact_radius(radius: f64, indentation: f64) -> f64 {
    (radius * indentation.max(0.0)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::close;

    #[test]
    fn steel_under_100_mpa() {
        // E = 200 GPa, ν = 0.3: ε = 5e-4 along, −1.5e-4 across.
        let (axial, lateral) = uniaxial_strains(100e6, 200e9, 0.3);
        assert!(close(axial, 5e-4, 1e-12) && close(lateral, -1.5e-4, 1e-12));
        let (e, nu) = young_and_poisson(100e6, axial, lateral);
        assert!(close(e, 200e9, 1e-12) && close(nu, 0.3, 1e-12));
    }

    #[test]
    fn bulk_modulus_and_volume_change() {
        // ν = 0: K = E/3; ν = 1/3: K = E; ν = 0.5: incompressible.
        assert!(close(bulk_modulus(3.0, 0.0), 1.0, 1e-12));
        assert!(close(bulk_modulus(3.0, 1.0 / 3.0), 3.0, 1e-12));
        assert!(bulk_modulus(3.0, 0.5).is_infinite());
        // 1 kPa on E = 1 MPa, ν = 0.25: ΔV/V = −1e3 · 0.5 · 3 / 1e6 = −1.5e-3.
        assert!(close(volume_strain(1e3, 1e6, 0.25), -1.5e-3, 1e-12));
        assert_eq!(volume_strain(1e3, 1e6, 0.5), 0.0);
        assert!(close(
            volume_strain(1e3, 1e6, 0.25),
            -1e3 / bulk_modulus(1e6, 0.25),
            1e-12
        ));
    }

    #[test]
    fn bar_modes_are_odd_quarter_waves() {
        // E/ρ = 1, L = 1: ω₁ = π/2, ω₂ = 3π/2.
        assert!(close(
            bar_axial_frequency(1, 1.0, 1.0, 1.0),
            PI / 2.0,
            1e-12
        ));
        assert!(close(
            bar_axial_frequency(2, 1.0, 1.0, 1.0),
            3.0 * PI / 2.0,
            1e-12
        ));
        // Steel, 1 m: c = √(200e9/7850) = 5047.5 m/s, f₁ = c/(4L) = 1261.9 Hz.
        let f = bar_axial_frequency(1, 1.0, 200e9, 7850.0) / (2.0 * PI);
        assert!(close(f, 1261.9, 1e-4), "{f}");
    }

    #[test]
    fn a_free_bar_rings_at_twice_the_clamped_one() {
        // Free-free: f₁ = c/(2L); steel, 1 m: 2523.8 Hz, twice the clamped-free bar's.
        let f = free_bar_axial_frequency(1, 1.0, 200e9, 7850.0) / (2.0 * PI);
        assert!(close(f, 2523.8, 1e-4), "{f}");
        assert!(close(
            free_bar_axial_frequency(1, 1.0, 200e9, 7850.0),
            2.0 * bar_axial_frequency(1, 1.0, 200e9, 7850.0),
            1e-12
        ));
        assert!(close(
            free_bar_axial_frequency(3, 2.0, 4.0, 1.0),
            3.0 * PI,
            1e-12
        ));
    }

    #[test]
    fn decrement_and_damping_ratio_are_inverse() {
        // ζ = 0.1: δ = 0.2π/√0.99 = 0.63148.
        assert!(close(log_decrement(0.1), 0.631_484, 1e-5));
        for zeta in [0.0, 0.01, 0.1, 0.5, 0.9] {
            assert!((damping_ratio(log_decrement(zeta)) - zeta).abs() < 1e-12);
        }
        assert_eq!(log_decrement(0.0), 0.0);
    }

    #[test]
    fn hertz_sphere_on_a_flat() {
        // R = 1, E* = 3/4 (ν = 0): F = d^{3/2}; at d = 0.04, F = 0.008 and a = 0.2.
        assert!(close(hertz_force(1.0, 0.04, 0.75, 0.0), 0.008, 1e-12));
        assert!(close(hertz_indentation(1.0, 0.008, 0.75, 0.0), 0.04, 1e-12));
        assert!(close(hertz_contact_radius(1.0, 0.04), 0.2, 1e-12));
        // ν = 0.5 stiffens the contact by 1/(1 − 0.25) = 4/3.
        assert!(close(
            hertz_force(1.0, 0.04, 0.75, 0.5),
            0.008 * 4.0 / 3.0,
            1e-12
        ));
        // A 10 cm silicone ball (R = 5 cm, E = 1 MPa, ν = 0.45) under its own weight
        // (0.5498 kg at 1050 kg/m³, 5.393 N; E* = 1.2539 MPa) sinks
        // d = (3F/(4E*√R))^{2/3} = 0.5926 mm.
        let d = hertz_indentation(0.05, 5.393, 1e6, 0.45);
        assert!(close(d, 5.926e-4, 1e-3), "{d}");
        assert_eq!(hertz_force(1.0, -0.1, 1.0, 0.0), 0.0);
    }
}
