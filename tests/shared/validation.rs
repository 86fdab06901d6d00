//! Validation beyond single cells (issue 7): overlapping and duplicate cells, mesh warnings and
//! their repairs, a material too stiff for the step.

use crate::dim::math::{self, Real, Vector, DIM};
use crate::dim::{
    BuildError, CellKind, DeformableBuilder, DeformableWorld, Mesh, MeshWarning, Stiffness,
};

/// The unit simplex (origin and the unit axes): nodes `0..=DIM`.
fn simplex() -> (Vec<Vector>, Vec<u32>) {
    let mut nodes = vec![Vector::ZERO];
    for d in 0..DIM {
        let mut e = Vector::ZERO;
        e[d] = 1.0;
        nodes.push(e);
    }
    (nodes, (0..=DIM as u32).collect())
}

/// Two unit simplices, the second the first turned half a turn about the x axis (3D) or the
/// origin (2D): they share the nodes on that axis (`[0, 1]` in 3D, `[0]` in 2D) and nothing
/// else, so the surface pinches there.
fn bow_tie() -> Mesh {
    let (mut nodes, mut cells) = simplex();
    let half_turn = if DIM == 3 {
        math::rotation_from_angle(math::ang_from_components([std::f32::consts::PI, 0.0, 0.0]))
    } else {
        math::rotation_from_angle(math::planar_angle(std::f32::consts::PI))
    };
    let shared = if DIM == 3 { 2 } else { 1 };
    let mut map: Vec<u32> = (0..shared as u32).collect();
    for p in &nodes.clone()[shared..] {
        map.push(nodes.len() as u32);
        nodes.push(half_turn * *p);
    }
    cells.extend(map);
    Mesh::new(nodes, cells, CellKind::Simplex).expect("two simplices touching")
}

#[test]
fn a_face_of_three_cells_is_an_error() {
    // The simplex and two more beyond its face opposite the origin: that face is taken by
    // three cells (two of which overlap).
    let (mut nodes, mut cells) = simplex();
    let face: Vec<u32> = (1..=DIM as u32).collect();
    for apex in [Vector::splat(1.0), Vector::splat(2.0)] {
        nodes.push(apex);
        let mut c = face.clone();
        c.push(nodes.len() as u32 - 1);
        let p: Vec<Vector> = c.iter().map(|&i| nodes[i as usize]).collect();
        if crate::dim::mesh::cell_volume(CellKind::Simplex, &p) < 0.0 {
            c.swap(0, 1);
        }
        cells.extend(c);
    }
    let e = Mesh::new(nodes, cells, CellKind::Simplex).unwrap_err();
    assert!(
        matches!(&e, BuildError::OverlappingCells { cells: 3, face } if face.len() == DIM),
        "{e}"
    );
    assert!(e.to_string().contains("belongs to 3 cells"), "{e}");
}

#[test]
fn a_repeated_cell_is_an_error() {
    let (nodes, mut cells) = simplex();
    let again = cells.clone();
    cells.extend(again);
    let e = Mesh::new(nodes, cells, CellKind::Simplex).unwrap_err();
    assert_eq!(e, BuildError::DuplicateCell { cell: 1, first: 0 });
    assert!(e.to_string().contains("same vertices as cell 0"), "{e}");
}

#[test]
fn a_lattice_has_no_warnings() {
    for kind in [CellKind::Simplex, CellKind::Cube] {
        let m = Mesh::cuboid(Vector::splat(0.5), [4; DIM], kind).unwrap();
        assert_eq!(m.diagnose(), vec![], "{kind:?}");
    }
}

#[test]
fn coincident_nodes_are_a_warning_and_merge() {
    // The simplex and its mirror through the origin, the origin given twice: a cut mesh.
    let (mut nodes, mut cells) = simplex();
    let n = nodes.len() as u32;
    for p in nodes.clone() {
        nodes.push(-p);
    }
    let mut mirrored: Vec<u32> = (n..2 * n).collect();
    if DIM == 3 {
        // A point reflection turns a 3D cell inside out.
        mirrored.swap(0, 1);
    }
    cells.extend(mirrored);
    let cut = Mesh::new(nodes, cells, CellKind::Simplex).unwrap();
    let warnings = cut.diagnose();
    assert!(
        warnings.contains(&MeshWarning::CoincidentNodes {
            first: 0,
            second: n,
            distance: 0.0
        }),
        "{warnings:?}"
    );
    assert!(
        warnings.contains(&MeshWarning::Disconnected { pieces: 2 }),
        "{warnings:?}"
    );
    let e = DeformableBuilder::new(cut.clone())
        .deny_warnings(true)
        .build()
        .unwrap_err();
    assert!(
        matches!(
            e,
            BuildError::MeshWarning(MeshWarning::CoincidentNodes { .. })
        ),
        "{e}"
    );
    assert!(e.to_string().contains("merge_coincident_nodes"), "{e}");
    assert!(
        DeformableBuilder::new(cut.clone()).build().is_ok(),
        "only a warning"
    );
    // Welded: one node fewer, one piece (pinched at the origin in 2D... and 3D alike).
    let welded = cut.merge_coincident_nodes(1e-6).unwrap();
    assert_eq!(welded.nodes().len(), cut.nodes().len() - 1);
    let after = welded.diagnose();
    assert!(
        !after.iter().any(|w| matches!(
            w,
            MeshWarning::CoincidentNodes { .. } | MeshWarning::Disconnected { .. }
        )),
        "{after:?}"
    );
    let e = cut.merge_coincident_nodes(Real::NAN).unwrap_err();
    assert!(
        matches!(
            e,
            BuildError::InvalidParameter {
                name: "tolerance",
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn a_pinched_surface_is_a_warning() {
    let m = bow_tie();
    let ridge: Vec<u32> = if DIM == 3 { vec![0, 1] } else { vec![0] };
    let warnings = m.diagnose();
    assert_eq!(
        warnings,
        vec![MeshWarning::NonManifoldSurface {
            nodes: ridge,
            facets: 4
        }]
    );
    let e = DeformableBuilder::new(m)
        .deny_warnings(true)
        .build()
        .unwrap_err();
    assert!(e.to_string().contains("not manifold"), "{e}");
}

#[test]
fn unreferenced_nodes_can_be_dropped() {
    let (mut nodes, cells) = simplex();
    nodes.insert(1, Vector::splat(7.0));
    let cells: Vec<u32> = cells
        .iter()
        .map(|&i| if i >= 1 { i + 1 } else { i })
        .collect();
    let e = Mesh::new(nodes.clone(), cells.clone(), CellKind::Simplex).unwrap_err();
    assert_eq!(e, BuildError::UnreferencedNode { node: 1 });
    let (m, map) = Mesh::compact(nodes, cells, CellKind::Simplex).unwrap();
    assert_eq!(m.nodes().len(), DIM + 1);
    assert_eq!(map[1], u32::MAX);
    assert_eq!(map[2], 1);
    let e = Mesh::compact(vec![Vector::ZERO], vec![0, 5, 9], CellKind::Simplex).unwrap_err();
    assert!(
        matches!(e, BuildError::IndexOutOfRange { index: 5, .. }),
        "{e}"
    );
}

#[test]
fn a_body_too_stiff_for_the_step_is_refused_by_try_insert() {
    let jelly = |k: Real| {
        DeformableBuilder::cuboid(Vector::splat(0.5), [3; DIM])
            .stiffness(Stiffness::Raw { k, c: 0.0 })
            .build()
            .unwrap()
    };
    let mut world = DeformableWorld::new();
    world.set_dt(1.0 / 60.0);
    let (back, e) = world.try_insert(jelly(1e15)).unwrap_err();
    match e {
        BuildError::TooStiff {
            substeps,
            max_substeps,
            ..
        } => {
            assert!(substeps > max_substeps as f64, "{substeps}");
            assert_eq!(max_substeps, world.pipeline.settings.max_substeps);
        }
        other => panic!("{other}"),
    }
    assert!(world.deformables.is_empty(), "nothing inserted");
    assert!(back.stable_substep() > 0.0);
    let h = world.try_insert(jelly(1e3)).unwrap();
    world.step();
    assert!(world.report().get(h).unwrap().substeps >= 1);
}
