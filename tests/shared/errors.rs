//! Every `BuildError` variant, fed and checked by its message (issue 2, acceptance 5).

use crate::dim::math::{Real, Vector, DIM};
use crate::dim::{
    BuildError, CellKind, DeformableBuilder, ElementModel, Material, Mesh, Stiffness,
};

fn simplex_nodes() -> Vec<Vector> {
    let mut nodes = vec![Vector::ZERO];
    for d in 0..DIM {
        let mut e = Vector::ZERO;
        e[d] = 1.0;
        nodes.push(e);
    }
    nodes
}

fn simplex_cells() -> Vec<u32> {
    (0..=DIM as u32).collect()
}

fn message(e: &BuildError) -> String {
    e.to_string()
}

#[test]
fn empty_mesh() {
    let e = Mesh::new(vec![], vec![], CellKind::Simplex).unwrap_err();
    assert!(matches!(e, BuildError::EmptyMesh { nodes: 0, cells: 0 }));
    assert!(message(&e).contains("empty mesh"), "{e}");
    let e = Mesh::new(simplex_nodes(), vec![], CellKind::Simplex).unwrap_err();
    assert!(matches!(e, BuildError::EmptyMesh { cells: 0, .. }), "{e}");
}

#[test]
fn malformed_cell_list() {
    let mut cells = simplex_cells();
    cells.pop();
    let e = Mesh::new(simplex_nodes(), cells, CellKind::Simplex).unwrap_err();
    assert!(matches!(e, BuildError::MalformedCells { .. }), "{e}");
    assert!(
        message(&e).contains(&format!("multiple of {}", DIM + 1)),
        "{e}"
    );
}

#[test]
fn index_out_of_range() {
    let mut cells = simplex_cells();
    cells[1] = 99;
    let e = Mesh::new(simplex_nodes(), cells, CellKind::Simplex).unwrap_err();
    assert_eq!(
        e,
        BuildError::IndexOutOfRange {
            cell: 0,
            index: 99,
            node_count: DIM + 1
        }
    );
    assert!(message(&e).contains("cell 0 refers to node 99"), "{e}");
}

#[test]
fn non_finite_coordinate() {
    let mut nodes = simplex_nodes();
    nodes[1][0] = Real::NAN;
    let e = Mesh::new(nodes, simplex_cells(), CellKind::Simplex).unwrap_err();
    assert!(
        matches!(e, BuildError::NonFiniteCoordinate { node: 1, .. }),
        "{e}"
    );
    assert!(
        message(&e).contains("node 1 has a non-finite coordinate"),
        "{e}"
    );
    // Also at run time: the state is refused and unchanged.
    let mut b = DeformableBuilder::new(
        Mesh::new(simplex_nodes(), simplex_cells(), CellKind::Simplex).unwrap(),
    )
    .build()
    .unwrap();
    let before = b.positions().to_vec();
    let mut bad = before.clone();
    bad[2] = Vector::splat(Real::INFINITY);
    assert!(matches!(
        b.set_positions(&bad),
        Err(BuildError::NonFiniteCoordinate { node: 2, .. })
    ));
    assert_eq!(b.positions(), &before[..]);
}

#[test]
fn degenerate_element() {
    let mut nodes = simplex_nodes();
    // Put the last vertex on the facet of the others: zero volume.
    nodes[DIM] = nodes[1] * 0.5;
    let e = Mesh::new(nodes, simplex_cells(), CellKind::Simplex).unwrap_err();
    assert!(
        matches!(e, BuildError::DegenerateElement { cell: 0, .. }),
        "{e}"
    );
    assert!(message(&e).contains("cell 0 is degenerate"), "{e}");
    // A repeated vertex is degenerate too.
    let mut cells = simplex_cells();
    cells[1] = cells[0];
    let mut nodes = simplex_nodes();
    nodes.truncate(DIM + 1);
    let e = Mesh::new(nodes, cells, CellKind::Simplex).unwrap_err();
    assert!(
        matches!(
            e,
            BuildError::DegenerateElement { .. } | BuildError::UnreferencedNode { .. }
        ),
        "{e}"
    );
}

#[test]
fn inverted_element() {
    let mut cells = simplex_cells();
    cells.swap(0, 1);
    let e = Mesh::new(simplex_nodes(), cells, CellKind::Simplex).unwrap_err();
    assert!(
        matches!(e, BuildError::InvertedElement { cell: 0, volume } if volume < 0.0),
        "{e}"
    );
    assert!(message(&e).contains("cell 0 is inverted"), "{e}");
    // A box with two corners swapped is inverted (or twisted) too.
    let good = Mesh::cuboid(Vector::splat(0.5), [2; DIM], CellKind::Cube).unwrap();
    let mut cells = good.cell_indices().to_vec();
    cells.swap(1, 3);
    let e = Mesh::new(good.nodes().to_vec(), cells, CellKind::Cube).unwrap_err();
    assert!(
        matches!(
            e,
            BuildError::InvertedElement { .. } | BuildError::DegenerateElement { .. }
        ),
        "{e}"
    );
}

#[test]
fn unreferenced_node() {
    let mut nodes = simplex_nodes();
    nodes.push(Vector::splat(5.0));
    let e = Mesh::new(nodes, simplex_cells(), CellKind::Simplex).unwrap_err();
    assert_eq!(e, BuildError::UnreferencedNode { node: DIM + 1 });
    assert!(message(&e).contains("belongs to no cell"), "{e}");
}

fn cube() -> DeformableBuilder {
    DeformableBuilder::cuboid(Vector::splat(0.5), [2; DIM])
}

#[test]
fn non_positive_density() {
    for density in [0.0, -1.0, Real::NAN] {
        let e = cube()
            .material(Material {
                density,
                ..Default::default()
            })
            .build()
            .unwrap_err();
        assert!(matches!(e, BuildError::NonPositiveDensity { .. }), "{e}");
        assert!(message(&e).contains("density must be positive"), "{e}");
    }
}

#[test]
fn negative_stiffness() {
    let e = cube()
        .material(Material {
            young_modulus: -1.0,
            ..Default::default()
        })
        .build()
        .unwrap_err();
    assert!(
        matches!(
            e,
            BuildError::NegativeStiffness {
                what: "young_modulus",
                ..
            }
        ),
        "{e}"
    );
    assert!(
        message(&e).contains("young_modulus must be non-negative"),
        "{e}"
    );
    let e = cube()
        .stiffness(Stiffness::Raw { k: -5.0, c: 0.0 })
        .build()
        .unwrap_err();
    assert!(
        message(&e).contains("raw stiffness k must be non-negative and finite, got -5"),
        "{e}"
    );
    let e = cube()
        .stiffness(Stiffness::PerMass {
            k_over_m: -1e4,
            damping_ratio: 0.0,
        })
        .build()
        .unwrap_err();
    assert!(matches!(e, BuildError::NegativeStiffness { .. }), "{e}");
}

#[test]
fn invalid_parameter() {
    let e = cube().restitution(2.0).build().unwrap_err();
    assert!(message(&e).contains("`restitution` = 2"), "{e}");
    let e = cube().friction(-0.1).build().unwrap_err();
    assert!(
        matches!(
            e,
            BuildError::InvalidParameter {
                name: "friction",
                ..
            }
        ),
        "{e}"
    );
    let e = cube()
        .material(Material {
            damping_ratio: -0.5,
            ..Default::default()
        })
        .build()
        .unwrap_err();
    assert!(
        matches!(
            e,
            BuildError::InvalidParameter {
                name: "damping_ratio",
                ..
            }
        ),
        "{e}"
    );
    let e = DeformableBuilder::cuboid(Vector::splat(0.5), [1; DIM])
        .build()
        .unwrap_err();
    assert!(message(&e).contains("at least 2 nodes"), "{e}");
    let e = DeformableBuilder::cuboid(Vector::splat(-1.0), [2; DIM])
        .build()
        .unwrap_err();
    assert!(
        matches!(
            e,
            BuildError::InvalidParameter {
                name: "half_extents",
                ..
            }
        ),
        "{e}"
    );
    let e = cube()
        .translation(Vector::splat(Real::NAN))
        .build()
        .unwrap_err();
    assert!(
        matches!(
            e,
            BuildError::InvalidParameter {
                name: "translation",
                ..
            }
        ),
        "{e}"
    );
    let e = cube()
        .model(ElementModel::ShapeMatching {
            fit: crate::dim::RotationFit::Iterative(0),
            damping: Default::default(),
        })
        .build()
        .unwrap_err();
    assert!(message(&e).contains("at least one iteration"), "{e}");
}

#[test]
fn unsupported_cells() {
    let e = cube()
        .cells(CellKind::Cube)
        .model(ElementModel::EdgeRepulsion)
        .build()
        .unwrap_err();
    assert!(
        matches!(
            e,
            BuildError::UnsupportedCells {
                model: "edge-repulsion",
                ..
            }
        ),
        "{e}"
    );
    assert!(message(&e).contains("needs simplex cells"), "{e}");
    // Every other model accepts box cells.
    for model in ElementModel::ALL
        .into_iter()
        .filter(|m| *m != ElementModel::EdgeRepulsion)
    {
        assert!(
            cube().cells(CellKind::Cube).model(model).build().is_ok(),
            "{}",
            model.name()
        );
    }
}
