//! Materials as users think of them, and the raw stiffness forms of the papers.

use super::error::BuildError;
use super::math::Real;

/// A material in the units a user thinks in (SI).
///
/// Each element model maps it to its own per-element stiffness `k` and damping `c`; the
/// mapping is written in the model's documentation ([`super::model`]). In short: a term that
/// stands for volume `V` over a rest length `L0` gets `k = s · E · V / L0²` with a per-model
/// calibration constant `s`, and damping `c = 2 ζ √(k m)` with `m` the mass that term moves,
/// so the damping ratio is the same for every element whatever the resolution.
///
/// Poisson's ratio: each spring-like lattice has its own (springs and nonlinear springs 5/31 ≈
/// 0.16 in 3D, 0.2 in 2D; edge repulsion 7/47 ≈ 0.15, 0.2; shape matching ≈ 0.125, 1/7). On
/// simplex cells, springs, nonlinear springs, edge repulsion and shape matching take the one
/// asked for: their terms are scaled and each cell gets a volumetric term
/// ([`super::model::volume`]), so that along a lattice axis the body has this `E` and this `ν`
/// (an affine stretch shows it within 0.01; a bar's free surface adds a bias that shrinks with
/// resolution: `scenes stretch`). Centroid springs and cube cells keep their lattice's ratio.
/// Each model's `s` is derived so that the lattice's Young's modulus along an axis is `E`; the
/// `cantilever` scene checks it against beam theory. Towards `ν = 0.5` the volumetric term
/// stiffens the body: the explicit step takes more substeps (5 → 7 at ν = 0.3 → 0.45 for the
/// default jelly), the implicit step does not.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Material {
    /// Mass density, kg/m³ (kg/m² in 2D). Must be positive.
    pub density: Real,
    /// Young's modulus, Pa. Must be non-negative.
    pub young_modulus: Real,
    /// Damping ratio of each element's own oscillation (0 = undamped, 1 = critical).
    ///
    /// It is not the damping ratio of the body's slow modes: the damping acts on each
    /// element's stretching rate, so a mode of angular frequency ω is damped by about
    /// `ζ · ω / ω_element`. A free 1 m bar of ten cells along asked for ζ = 0.05 rings in its
    /// first axial mode with ζ = 0.002–0.005 (every model; rapier's soft bodies 0.006–0.013):
    /// `cargo run --release --example scenes -- vibration`. Ask for the ratio a mode needs
    /// scaled by `ω_element / ω`, or damp that mode yourself.
    pub damping_ratio: Real,
    /// Poisson's ratio (see the type's documentation).
    pub poisson_ratio: Real,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            density: 1000.0,
            young_modulus: 1.0e5,
            damping_ratio: 0.05,
            poisson_ratio: 0.3,
        }
    }
}

/// Which strains flow in [`Plasticity`].
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Copy, Clone, Debug, PartialEq, Eq, Default)]
pub enum FlowIn {
    /// Stretching and compression alike (the default).
    #[default]
    Both,
    /// Stretching only (a cell compressed past yield springs back).
    Tension,
    /// Compression only (clay that keeps a dent but not a pull).
    Compression,
}

/// Plastic flow: a cell strained past `yield_strain` along a principal direction has its rest
/// shape stretched along that direction, so that a body bent or crushed past yield keeps a set
/// (edge repulsion and shape matching on simplex cells; `docs/ARCHITECTURE.md` §3.6).
///
/// Strains are logarithmic (Hencky): `ln λ` of a principal stretch `λ` of the cell's elastic
/// deformation (its shape against its current rest shape). A bar stretched to `λ` and
/// released, flowing instantly, keeps `ln λ − yield_strain`.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Plasticity {
    /// The elastic strain a cell bears before it flows (≥ 0).
    pub yield_strain: Real,
    /// How fast the strain past yield flows, 1/s: a step of `dt` flows `1 − e^(−rate·dt)` of it.
    /// `Real::INFINITY` flows it all at once; a small rate creeps.
    pub flow_rate: Real,
    /// The largest plastic strain a cell may take along any direction (> 0, finite): its rest
    /// shape is never stretched past `e^max` nor squashed below `e^(−max)` of its built shape,
    /// so it never goes flat.
    pub max_strain: Real,
    /// Which strains flow.
    pub flow: FlowIn,
}

impl Plasticity {
    /// Checks the parameters.
    pub(crate) fn validate(&self) -> Result<(), BuildError> {
        let check = |name, value: Real, ok: bool, expected| {
            if ok {
                Ok(())
            } else {
                Err(BuildError::InvalidParameter {
                    name,
                    value,
                    expected,
                })
            }
        };
        let y = self.yield_strain;
        check(
            "yield_strain",
            y,
            y.is_finite() && y >= 0.0,
            "a finite strain of at least 0",
        )?;
        let r = self.flow_rate;
        check(
            "flow_rate",
            r,
            r > 0.0,
            "a rate above 0 (1/s; infinite: instant)",
        )?;
        let m = self.max_strain;
        check(
            "max_strain",
            m,
            m.is_finite() && m > 0.0,
            "a finite strain above 0",
        )
    }
}

/// Tearing: a body splits along the faces between its cells where it is stretched past
/// `strain` (`docs/ARCHITECTURE.md` §3.8). The nodes of a face that tears are duplicated where
/// the crack has cut the cells around them apart, so the pieces move on independently, within
/// the one body.
///
/// The strain is logarithmic, as [`Plasticity`]'s: `ln λ` of the stretch `λ` across the face
/// (each of its two cells' deformation applied to the face's rest normal, the two lengths
/// averaged), against the cells' current rest shapes.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Tearing {
    /// The log strain across a face at which it tears (> 0, finite; above a plastic body's
    /// yield strain).
    pub strain: Real,
    /// The fewest cells a piece torn off may have (≥ 1): a tear that would leave a smaller
    /// piece does not happen, so a body does not shed dust.
    pub smallest_piece: usize,
}

impl Tearing {
    /// Tears past `strain`, leaving pieces of at least 4 cells.
    pub fn at(strain: Real) -> Tearing {
        Tearing {
            strain,
            smallest_piece: 4,
        }
    }

    /// Checks the parameters, against the body's plastic flow if it has one.
    pub(crate) fn validate(&self, plasticity: Option<&Plasticity>) -> Result<(), BuildError> {
        let s = self.strain;
        if !(s.is_finite() && s > 0.0) {
            return Err(BuildError::InvalidParameter {
                name: "Tearing::strain",
                value: s,
                expected: "a finite log strain above 0",
            });
        }
        if self.smallest_piece == 0 {
            return Err(BuildError::InvalidParameter {
                name: "Tearing::smallest_piece",
                value: 0.0,
                expected: "at least 1 cell",
            });
        }
        match plasticity {
            Some(p) if s <= p.yield_strain => Err(BuildError::TearBelowYield {
                tear: s,
                yield_strain: p.yield_strain,
            }),
            _ => Ok(()),
        }
    }
}

/// A gas sealed in a body's chambers, held by the isothermal law `p V = const`: balls, balloons,
/// tyres, pneumatic pads (`docs/ARCHITECTURE.md` §3.7). The gas pushes each chamber's walls out
/// with its pressure over the ambient one.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Gas {
    /// Pressure over the ambient one (gauge), Pa, at the chamber's built volume. Negative: a
    /// chamber under suction; the absolute pressure `pressure + ambient` must be above 0.
    pub pressure: Real,
    /// The ambient (absolute) pressure outside, Pa, ≥ 0: what the gas pushes against.
    pub ambient: Real,
}

impl Gas {
    /// Sea-level atmospheric pressure, Pa.
    pub const ATMOSPHERE: Real = 101_325.0;

    /// A gas at `pressure` Pa over the atmosphere ([`Gas::ATMOSPHERE`]) at the built volume.
    pub fn gauge(pressure: Real) -> Gas {
        Gas {
            pressure,
            ambient: Gas::ATMOSPHERE,
        }
    }

    /// Checks the parameters.
    pub(crate) fn validate(&self) -> Result<(), BuildError> {
        let a = self.ambient;
        if !(a.is_finite() && a >= 0.0) {
            return Err(BuildError::InvalidParameter {
                name: "Gas::ambient",
                value: a,
                expected: "a finite pressure of at least 0 (Pa)",
            });
        }
        let p = self.pressure;
        if !(p.is_finite() && p + a > 0.0) {
            return Err(BuildError::InvalidParameter {
                name: "Gas::pressure",
                value: p,
                expected: "a finite gauge pressure above minus the ambient one (Pa)",
            });
        }
        Ok(())
    }
}

/// Where element stiffness comes from.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Copy, Clone, Debug, PartialEq, Default)]
pub enum Stiffness {
    /// From the [`Material`]'s Young's modulus and damping ratio (the default).
    #[default]
    FromMaterial,
    /// The papers' raw form: every spring (Cooper & Maddock) or element vertex term
    /// (shape-based, edge repulsion) gets stiffness `k` (N/m) and damping coefficient `c`
    /// (N·s/m), whatever its size.
    Raw {
        /// Stiffness, N/m.
        k: Real,
        /// Damping coefficient, N·s/m.
        c: Real,
    },
    /// The shape-based paper's `k/m` form: each term's stiffness is `k_over_m` times the mass
    /// it moves (the reduced mass of a spring's two nodes; a cell's mass per vertex for a
    /// vertex term), so `√(k_over_m)` is its angular frequency; damping by ratio.
    PerMass {
        /// Stiffness per unit mass, 1/s².
        k_over_m: Real,
        /// Damping ratio.
        damping_ratio: Real,
    },
}

/// Material and stiffness form, validated; resolves each element term's `k` and `c`.
#[derive(Copy, Clone, Debug)]
pub(crate) struct Resolved {
    pub material: Material,
    pub stiffness: Stiffness,
}

impl Resolved {
    pub fn new(material: Material, stiffness: Stiffness) -> Result<Self, BuildError> {
        let m = material;
        if !(m.density.is_finite() && m.density > 0.0) {
            return Err(BuildError::NonPositiveDensity { density: m.density });
        }
        let negative = |what, value: Real| {
            if value.is_finite() && value >= 0.0 {
                Ok(())
            } else {
                Err(BuildError::NegativeStiffness { what, value })
            }
        };
        negative("young_modulus", m.young_modulus)?;
        let damping = |name, value: Real| {
            if value.is_finite() && value >= 0.0 {
                Ok(())
            } else {
                Err(BuildError::InvalidParameter {
                    name,
                    value,
                    expected: "a non-negative finite damping",
                })
            }
        };
        damping("damping_ratio", m.damping_ratio)?;
        if !(m.poisson_ratio.is_finite() && m.poisson_ratio > -1.0 && m.poisson_ratio < 0.5) {
            return Err(BuildError::InvalidParameter {
                name: "poisson_ratio",
                value: m.poisson_ratio,
                expected: "-1 < ν < 0.5",
            });
        }
        match stiffness {
            Stiffness::FromMaterial => {}
            Stiffness::Raw { k, c } => {
                negative("raw stiffness k", k)?;
                damping("raw damping c", c)?;
            }
            Stiffness::PerMass {
                k_over_m,
                damping_ratio,
            } => {
                negative("stiffness per mass k/m", k_over_m)?;
                damping("damping_ratio", damping_ratio)?;
            }
        }
        Ok(Resolved {
            material,
            stiffness,
        })
    }

    /// Whether every element term's damping `c` is zero.
    pub fn undamped(&self) -> bool {
        match self.stiffness {
            Stiffness::FromMaterial => self.material.damping_ratio == 0.0,
            Stiffness::Raw { c, .. } => c == 0.0,
            Stiffness::PerMass { damping_ratio, .. } => damping_ratio == 0.0,
        }
    }

    /// `(k, c)` of one element term, given the material mapping's `k` for it and the mass it
    /// moves.
    #[inline]
    pub fn k_c(&self, material_k: Real, mass: Real) -> (Real, Real) {
        match self.stiffness {
            Stiffness::FromMaterial => (
                material_k,
                2.0 * self.material.damping_ratio * (material_k * mass).sqrt(),
            ),
            Stiffness::Raw { k, c } => (k, c),
            Stiffness::PerMass {
                k_over_m,
                damping_ratio,
            } => {
                let k = k_over_m * mass;
                (k, 2.0 * damping_ratio * (k * mass).sqrt())
            }
        }
    }
}
