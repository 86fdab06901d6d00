//! Poisson's ratio (issue 15): the volumetric term and the material mapping give each model the
//! ratio asked for.

use crate::dim::math::{Real, Vector, DIM};
use crate::dim::{CellKind, DeformableBuilder, ElementModel, Material};

/// The lateral strain at which a lattice stretched `axial` along x is free of lateral stress
/// (each lateral axis strained alike): the root of the virtual work of the element forces on a
/// lateral strain, `Σ_i Σ_lateral f_i[d] X_i[d]`, between two strains. Under an affine strain
/// every cell is strained alike, so this is the lattice's own (Cauchy–Born) ratio, times
/// `−axial`.
fn relaxed_lateral(model: ElementModel, nu: Real, axial: Real) -> Real {
    let mut body = DeformableBuilder::cuboid(Vector::splat(0.5), [5; DIM])
        .cells(CellKind::Simplex)
        .model(model)
        .material(Material {
            poisson_ratio: nu,
            ..Default::default()
        })
        .build()
        .unwrap();
    let rest = body.positions().to_vec();
    let mut work = |lateral: Real| {
        let x: Vec<Vector> = rest
            .iter()
            .map(|p| {
                let mut q = *p * (1.0 + lateral);
                q[0] = p[0] * (1.0 + axial);
                q
            })
            .collect();
        body.set_positions(&x).unwrap();
        let f = body.element_forces();
        (0..rest.len())
            .map(|i| (1..DIM).map(|d| f[i][d] * rest[i][d]).sum::<Real>())
            .sum::<Real>()
    };
    let s = axial.abs();
    let (a, b) = (work(-s), work(s));
    -s + 2.0 * s * a / (a - b)
}

#[test]
fn a_stretched_lattice_contracts_by_the_ratio_asked_for() {
    let models = [
        ElementModel::Springs,
        ElementModel::NonlinearSprings,
        ElementModel::EdgeRepulsion,
        ElementModel::SHAPE_MATCHING,
    ];
    for model in models {
        for nu in [0.0, 0.3, 0.45] {
            let axial = 1e-3;
            let measured = -relaxed_lateral(model, nu, axial) / axial;
            assert!(
                (measured - nu).abs() < 0.01,
                "{}: ν {nu} asked, {measured} shown",
                model.name()
            );
        }
    }
}

#[test]
fn without_the_term_each_lattice_shows_its_own_ratio() {
    // Centroid springs take no volumetric term: their lattice's ratio whatever is asked.
    let a = -relaxed_lateral(ElementModel::CentroidSprings, 0.0, 1e-3) / 1e-3;
    let b = -relaxed_lateral(ElementModel::CentroidSprings, 0.45, 1e-3) / 1e-3;
    assert!((a - b).abs() < 1e-3 && a > 0.1, "{a} {b}");
}
