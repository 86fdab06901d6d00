//! Property tests (issue 7): random lattices, materials, deformations and raw mesh input. The
//! force laws never panic, stay finite and conserve linear momentum; building from arbitrary
//! nodes and cells gives a mesh or a typed error, never a panic, and a built body steps without
//! panicking, finite or frozen.

use proptest::prelude::*;

use crate::dim::math::{Real, Vector, DIM};
use crate::dim::{CellKind, DeformableBuilder, DeformableWorld, ElementModel, Material, Mesh};

fn model(i: usize) -> ElementModel {
    ElementModel::ALL[i % ElementModel::ALL.len()]
}

fn vector(c: &[Real]) -> Vector {
    let mut v = Vector::ZERO;
    for d in 0..DIM {
        v[d] = c[d];
    }
    v
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, .. ProptestConfig::default() })]

    /// Σ f = 0 for every model on a randomly deformed lattice (cells may invert), with random
    /// velocities and material; every force finite.
    #[test]
    fn forces_are_finite_and_sum_to_zero(
        res in proptest::collection::vec(2usize..4, DIM),
        m in 0usize..5,
        young in 1e2f32..1e7,
        density in 1f32..1e4,
        damping in 0f32..1.0,
        moves in proptest::collection::vec(-0.4f32..0.4, 64 * 3),
        speeds in proptest::collection::vec(-5f32..5.0, 64 * 3),
    ) {
        let model = model(m);
        let res: [usize; DIM] = std::array::from_fn(|d| res[d]);
        let mut b = DeformableBuilder::cuboid(Vector::splat(0.5), res)
            .model(model)
            .material(Material { density, young_modulus: young, damping_ratio: damping, ..Default::default() })
            .build()
            .unwrap();
        let n = b.num_nodes();
        let spacing = 1.0 / (res.iter().copied().max().unwrap() - 1) as Real;
        let x: Vec<Vector> = b.positions().iter().enumerate()
            .map(|(i, p)| *p + vector(&moves[(i * 3) % moves.len()..]) * spacing)
            .collect();
        let v: Vec<Vector> = (0..n).map(|i| vector(&speeds[(i * 3) % speeds.len()..])).collect();
        b.set_positions(&x).unwrap();
        b.set_velocities(&v).unwrap();
        let f = b.element_forces().to_vec();
        prop_assert!(f.iter().all(|f| f.is_finite()), "{}: non-finite force", model.name());
        let total: Vector = f.iter().copied().sum();
        let scale: Real = f.iter().map(|f| f.length()).sum::<Real>().max(1e-12);
        prop_assert!(total.length() <= 1e-4 * scale, "{}: Σf = {total:?}, Σ|f| = {scale}", model.name());
    }

    /// Arbitrary nodes (NaN, infinities, huge values, duplicates) and cell indices (in and out
    /// of range, repeated) never panic: a mesh or a typed error; a mesh that builds steps in a
    /// world (with a ground) without panicking and ends finite or frozen.
    #[test]
    fn arbitrary_input_is_an_error_or_a_body_that_steps(
        coords in proptest::collection::vec(prop_oneof![
            8 => -2f32..2.0,
            1 => Just(Real::NAN),
            1 => Just(Real::INFINITY),
            1 => Just(1e30f32),
            1 => Just(0.0f32),
        ], 3..40),
        cells in proptest::collection::vec(0u32..16, 0..40),
        cube in any::<bool>(),
        m in 0usize..5,
    ) {
        let nodes: Vec<Vector> = coords.chunks_exact(DIM).map(vector).collect();
        let kind = if cube { CellKind::Cube } else { CellKind::Simplex };
        let Ok(mesh) = Mesh::new(nodes, cells, kind) else {
            return Ok(());
        };
        let _ = mesh.diagnose();
        let Ok(body) = DeformableBuilder::new(mesh).model(model(m)).build() else {
            return Ok(());
        };
        let mut world = DeformableWorld::new();
        let h = world.insert(body);
        for _ in 0..5 {
            world.step();
        }
        let d = &world.deformables[h];
        prop_assert!(d.is_frozen() || d.positions().iter().all(|p| p.is_finite()));
    }
}

/// A valid lattice with one random corruption (a non-finite or huge coordinate, an index out of
/// range, two vertices of a cell swapped, a cell repeated, a node moved onto another, nothing):
/// each gives a typed error or a body that steps; both outcomes occur.
#[test]
fn corrupted_lattices_are_errors_or_bodies_that_step() {
    let mut rng = super::support::Rng::new(11);
    let (mut built, mut refused) = (0, 0);
    for trial in 0..200 {
        let lattice = Mesh::cuboid(Vector::splat(0.5), [3; DIM], CellKind::Simplex).unwrap();
        let mut nodes = lattice.nodes().to_vec();
        let mut cells = lattice.cell_indices().to_vec();
        let arity = DIM + 1;
        let pick = |rng: &mut super::support::Rng, n: usize| (rng.next_u64() % n as u64) as usize;
        match trial % 7 {
            0 => {
                let i = pick(&mut rng, nodes.len());
                nodes[i][0] = Real::NAN;
            }
            1 => {
                let i = pick(&mut rng, nodes.len());
                nodes[i][DIM - 1] = 1e30;
            }
            2 => {
                let k = pick(&mut rng, cells.len());
                cells[k] = nodes.len() as u32 + 3;
            }
            3 => {
                let c = pick(&mut rng, cells.len() / arity);
                cells.swap(c * arity, c * arity + 1);
            }
            4 => {
                let c = pick(&mut rng, cells.len() / arity);
                let again: Vec<u32> = cells[c * arity..(c + 1) * arity].to_vec();
                cells.extend(again);
            }
            5 => {
                let (i, j) = (pick(&mut rng, nodes.len()), pick(&mut rng, nodes.len()));
                nodes[i] = nodes[j];
            }
            _ => {}
        }
        let model = model(trial);
        match Mesh::new(nodes, cells, CellKind::Simplex)
            .and_then(|m| DeformableBuilder::new(m).model(model).build())
        {
            Err(e) => {
                assert!(!e.to_string().is_empty());
                refused += 1;
            }
            Ok(body) => {
                let mut world = DeformableWorld::new();
                let h = world.insert(body);
                for _ in 0..3 {
                    world.step();
                }
                let d = &world.deformables[h];
                assert!(d.is_frozen() || d.positions().iter().all(|p| p.is_finite()));
                built += 1;
            }
        }
    }
    assert!(
        built > 20 && refused > 20,
        "built {built}, refused {refused}"
    );
}
