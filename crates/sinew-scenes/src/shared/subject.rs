//! What a scene simulates: one of sinew's element models, or one of rapier's own soft-body
//! models built on the same mesh, masses and material.

use super::super::lib::math::{Real, Vector};
use super::super::lib::model::{ElementModel, RotationFit, ShapeDamping};
use super::super::lib::rapier::dynamics::{
    SoftBodyCellModel, SoftBodyMaterial, SpringCoefficients,
};
use super::super::lib::Material;

/// A model of rapier 0.36's soft bodies (`rapier::dynamics::SoftBody`), the peers sinew is
/// measured against.
///
/// The material maps as follows: the elastic models (`Corotational`, `NeoHookean`) take the
/// Young's modulus, Poisson's ratio and damping ratio as they are. `Volume` has no Young's
/// modulus: its edges and per-cell volume constraints are given a natural frequency (rapier
/// normalises it by each constraint's effective mass) of `√2·c/(2π·L)`, `c = √(E/ρ)` the bar
/// wave speed and `L` the mean edge length — the frequency of one edge between two particles
/// of a chain whose wave speed is `c` — with the material's damping ratio.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum RapierModel {
    /// `SoftBodyCellModel::Volume`: edge constraints plus one volume constraint per cell.
    Volume,
    /// `SoftBodyCellModel::Corotational`: corotational linear elasticity plus an exact volume
    /// constraint.
    Corotational,
    /// `SoftBodyCellModel::NeoHookean`: stable Neo-Hookean hyperelasticity.
    NeoHookean,
    /// The corotational cells on rapier's implicit `SoftBodySolver::Fem` (feature `fem`).
    #[cfg(feature = "fem")]
    FemCorotational,
    /// The Neo-Hookean cells on rapier's implicit `SoftBodySolver::Fem` (feature `fem`).
    #[cfg(feature = "fem")]
    FemNeoHookean,
}

impl RapierModel {
    /// Every rapier model this build has.
    pub const ALL: &'static [RapierModel] = &[
        RapierModel::Volume,
        RapierModel::Corotational,
        RapierModel::NeoHookean,
        #[cfg(feature = "fem")]
        RapierModel::FemCorotational,
        #[cfg(feature = "fem")]
        RapierModel::FemNeoHookean,
    ];

    /// `rapier-volume`, `rapier-corotational`, …
    pub fn name(&self) -> &'static str {
        match self {
            RapierModel::Volume => "rapier-volume",
            RapierModel::Corotational => "rapier-corotational",
            RapierModel::NeoHookean => "rapier-neo-hookean",
            #[cfg(feature = "fem")]
            RapierModel::FemCorotational => "rapier-fem-corotational",
            #[cfg(feature = "fem")]
            RapierModel::FemNeoHookean => "rapier-fem-neo-hookean",
        }
    }

    pub(crate) fn cell_model(&self) -> SoftBodyCellModel {
        match self {
            RapierModel::Volume => SoftBodyCellModel::Volume,
            RapierModel::Corotational => SoftBodyCellModel::Corotational,
            RapierModel::NeoHookean => SoftBodyCellModel::NeoHookean,
            #[cfg(feature = "fem")]
            RapierModel::FemCorotational => SoftBodyCellModel::Corotational,
            #[cfg(feature = "fem")]
            RapierModel::FemNeoHookean => SoftBodyCellModel::NeoHookean,
        }
    }

    #[cfg(feature = "fem")]
    pub(crate) fn solver(&self) -> super::super::lib::rapier::dynamics::SoftBodySolver {
        use super::super::lib::rapier::dynamics::SoftBodySolver;
        match self {
            RapierModel::FemCorotational | RapierModel::FemNeoHookean => SoftBodySolver::Fem,
            _ => SoftBodySolver::Constraints,
        }
    }

    /// rapier's material for sinew's `material` on a mesh of mean edge length `edge` (see the
    /// type's docs for the mapping).
    pub fn material(&self, material: &Material, edge: Real) -> SoftBodyMaterial {
        let wave_speed = (material.young_modulus / material.density).sqrt();
        let hz = std::f64::consts::SQRT_2 as Real * wave_speed
            / (2.0 * std::f64::consts::PI as Real * edge);
        let softness = SpringCoefficients::new(hz, material.damping_ratio);
        SoftBodyMaterial {
            edge_softness: softness,
            bend_softness: softness,
            volume_softness: softness,
            shape_matching_softness: softness,
            young_modulus: material.young_modulus,
            poisson_ratio: material.poisson_ratio,
            elastic_damping_ratio: material.damping_ratio,
            ..SoftBodyMaterial::default()
        }
    }
}

/// What a scene simulates.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Subject {
    /// One of sinew's element models.
    Sinew(ElementModel),
    /// One of rapier's soft-body models.
    Rapier(RapierModel),
}

impl From<ElementModel> for Subject {
    fn from(model: ElementModel) -> Self {
        Subject::Sinew(model)
    }
}

impl From<RapierModel> for Subject {
    fn from(model: RapierModel) -> Self {
        Subject::Rapier(model)
    }
}

impl Subject {
    /// sinew's five models (the shape-based one with 2 iterations), then every rapier model.
    pub fn all() -> Vec<Subject> {
        ElementModel::ALL
            .iter()
            .map(|&m| Subject::Sinew(m))
            .chain(RapierModel::ALL.iter().map(|&m| Subject::Rapier(m)))
            .collect()
    }

    /// The model's name (`springs`, …, `shape-matching`, `rapier-volume`, …).
    pub fn name(&self) -> &'static str {
        match self {
            Subject::Sinew(m) => m.name(),
            Subject::Rapier(m) => m.name(),
        }
    }

    /// The shape-based model's rotation fit as text (`1`, `2`, `3`, `polar`), else `None`.
    pub fn iterations(&self) -> Option<String> {
        match self {
            Subject::Sinew(ElementModel::ShapeMatching { fit, .. }) => Some(match fit {
                RotationFit::Iterative(n) => n.to_string(),
                RotationFit::Polar => "polar".to_string(),
            }),
            _ => None,
        }
    }

    /// The subject called `name`; `fit` sets the shape-based model's rotation fit. The names
    /// are those of [`Subject::name`].
    pub fn parse(name: &str, fit: RotationFit) -> Option<Subject> {
        if let Some(&m) = ElementModel::ALL.iter().find(|m| m.name() == name) {
            return Some(Subject::Sinew(match m {
                ElementModel::ShapeMatching { .. } => ElementModel::ShapeMatching {
                    fit,
                    damping: ShapeDamping::RigidMotion,
                },
                other => other,
            }));
        }
        RapierModel::ALL
            .iter()
            .find(|m| m.name() == name)
            .map(|&m| Subject::Rapier(m))
    }
}

/// Mean edge length of the cells of `nodes`.
pub(crate) fn mean_edge(nodes: &[Vector], cells: &[[u32; 2]]) -> Real {
    let total: Real = cells
        .iter()
        .map(|[a, b]| nodes[*a as usize].distance(nodes[*b as usize]))
        .sum();
    total / cells.len().max(1) as Real
}
