//! Feature `serde` (issue 7): a world saved mid-run and restored continues bit for bit, and
//! bad snapshots are errors, not panics.

#![cfg(feature = "serde")]

use super::determinism::{scene, state_hash};
use crate::dim::math::Real;
use crate::dim::{
    Deformable, DeformableBuilder, DeformableSet, DeformableWorld, ElementModel, Mesh, RotationFit,
    ShapeDamping,
};

fn save<T: serde::Serialize>(value: &T) -> Vec<u8> {
    bincode::serialize(value).expect("a snapshot serializes")
}

fn node_bits(world: &DeformableWorld) -> Vec<u32> {
    world
        .deformables
        .iter()
        .flat_map(|(_, d)| d.positions().iter().chain(d.velocities()))
        .flat_map(|v| v.to_array())
        .map(Real::to_bits)
        .collect()
}

/// Every model, and the shape-based element's other fit and damping (warm-started iterative
/// fit: its per-cell rotations must come back exactly).
fn models() -> Vec<ElementModel> {
    let mut m = ElementModel::ALL.to_vec();
    m.push(ElementModel::ShapeMatching {
        fit: RotationFit::Polar,
        damping: ShapeDamping::Centroid,
    });
    m.push(ElementModel::ShapeMatching {
        fit: RotationFit::Iterative(1),
        damping: ShapeDamping::RigidMotion,
    });
    m
}

#[test]
fn a_restored_world_continues_bit_for_bit_for_every_model() {
    let before = 40;
    let after = 200;
    for model in models() {
        let s = scene(&[model], 4);
        let mut world = s.world;
        for _ in 0..before {
            world.step();
        }
        let bytes = save(&world);
        let mut restored: DeformableWorld = bincode::deserialize(&bytes).expect("it restores");
        assert_eq!(restored.time().to_bits(), world.time().to_bits());
        assert_eq!(restored.steps(), world.steps());
        assert_eq!(node_bits(&restored), node_bits(&world));
        let mut touched = 0;
        let mut slept = 0;
        for k in 0..after {
            world.step();
            restored.step();
            let (a, b) = (node_bits(&world), node_bits(&restored));
            let first = a.iter().zip(&b).position(|(x, y)| x != y);
            assert!(
                first.is_none() && state_hash(&world) == state_hash(&restored),
                "{}: the restored run differs {} step(s) after the restore (value {first:?})",
                model.name(),
                k + 1,
            );
            let cube = &world.deformables[s.cubes[0]];
            let landed = cube
                .contacts()
                .iter()
                .any(|c| world.physics.colliders[c.collider].parent() == Some(s.boxes[0]));
            touched += landed as usize;
            slept += world.deformables[s.lone].is_sleeping() as usize;
        }
        // Rapier's side, byte for byte (its own snapshot contract).
        assert!(
            save(&world.physics) == save(&restored.physics),
            "{}: rapier's state differs",
            model.name()
        );
        assert!(
            touched > 0,
            "{}: the box rests on the cube after the restore",
            model.name()
        );
        eprintln!(
            "{}: box contact in {touched} steps, asleep in {slept}",
            model.name()
        );
    }
}

#[test]
fn a_set_alone_round_trips_with_its_handles() {
    let s = scene(&[ElementModel::SHAPE_MATCHING], 3);
    let mut world = s.world;
    for _ in 0..20 {
        world.step();
    }
    // A removed body leaves a hole whose generation the handles remember.
    world.deformables.remove(s.tissue);
    let set: DeformableSet = bincode::deserialize(&save(&world.deformables)).expect("restores");
    assert_eq!(set.len(), world.deformables.len());
    assert!(!set.contains(s.tissue));
    for (h, d) in world.deformables.iter() {
        let r = set.get(h).expect("same handle");
        assert_eq!(r.positions(), d.positions());
        assert_eq!(r.velocities(), d.velocities());
        assert_eq!(r.masses(), d.masses());
        assert_eq!(r.attachments(), d.attachments());
        assert_eq!(r.report(), d.report());
        assert_eq!(r.model(), d.model());
        assert_eq!(r.mesh().boundary_facets(), d.mesh().boundary_facets());
    }
}

#[test]
fn truncated_or_garbled_snapshots_are_errors() {
    let s = scene(&[ElementModel::EdgeRepulsion], 3);
    let mut world = s.world;
    for _ in 0..10 {
        world.step();
    }
    let bytes = save(&world);
    for len in [0, 1, 7, bytes.len() / 3, bytes.len() / 2, bytes.len() - 1] {
        let r: Result<DeformableWorld, _> = bincode::deserialize(&bytes[..len]);
        assert!(r.is_err(), "{len} of {} bytes restored", bytes.len());
    }
    let one = &world.deformables[s.cubes[0]];
    let bytes = save(one);
    for len in [0, bytes.len() / 2, bytes.len() - 1] {
        assert!(bincode::deserialize::<Deformable>(&bytes[..len]).is_err());
    }
    // Garbled: every byte in turn set to 0xff must give an error or a valid deformable,
    // never a panic (checked on a small body; a length prefix of 0xff.. is an error).
    let small = DeformableBuilder::new(super::support::unit_simplex())
        .build()
        .expect("one simplex");
    let bytes = save(&small);
    for k in 0..bytes.len() {
        let mut b = bytes.clone();
        b[k] = 0xff;
        let _ = bincode::deserialize::<Deformable>(&b);
    }
}

#[test]
fn inconsistent_snapshots_are_errors() {
    // A deformable's bytes start with its mesh: splice in the mesh of a larger body, so the
    // node state no longer matches the mesh.
    let small = DeformableBuilder::cuboid(
        crate::dim::math::Vector::splat(0.5),
        [3; crate::dim::math::DIM],
    )
    .build()
    .expect("valid");
    let large = DeformableBuilder::cuboid(
        crate::dim::math::Vector::splat(0.5),
        [4; crate::dim::math::DIM],
    )
    .build()
    .expect("valid");
    let bytes = save(&small);
    let mesh_len = save(small.mesh()).len();
    assert_eq!(
        bytes[..mesh_len],
        save(small.mesh())[..],
        "the mesh comes first"
    );
    let mut spliced = save(large.mesh());
    spliced.extend_from_slice(&bytes[mesh_len..]);
    let err = bincode::deserialize::<Deformable>(&spliced).expect_err("state does not match");
    assert!(err.to_string().contains("positions"), "{err}");

    // A mesh whose cell points past the nodes fails `Mesh::new`'s validation.
    let mesh = super::support::unit_simplex();
    let mut bytes = save(&mesh);
    let n = bytes.len();
    bytes[n - 4..].copy_from_slice(&99u32.to_le_bytes());
    let err = bincode::deserialize::<Mesh>(&bytes).expect_err("index out of range");
    assert!(err.to_string().contains("invalid mesh"), "{err}");
}

/// JSON (human-readable) works too: `serde_json` writes each `f32` as its shortest
/// round-trip decimal and (with `float_roundtrip`) reads it back exactly, and the snapshot
/// holds no infinity (no crossing limiter is saved as `null`).
#[test]
fn a_json_snapshot_continues_bit_for_bit() {
    for model in models() {
        let s = scene(&[model], 3);
        let mut world = s.world;
        // Before the first step too (every limiter still infinite).
        let fresh = serde_json::to_string(&world).expect("JSON writes");
        let fresh: DeformableWorld = serde_json::from_str(&fresh).expect("JSON restores");
        assert_eq!(node_bits(&fresh), node_bits(&world));
        for _ in 0..30 {
            world.step();
        }
        let json = serde_json::to_string(&world).expect("JSON writes");
        let mut restored: DeformableWorld = serde_json::from_str(&json).expect("JSON restores");
        for k in 0..100 {
            world.step();
            restored.step();
            assert!(
                state_hash(&world) == state_hash(&restored),
                "{}: the run restored from JSON differs {} step(s) after",
                model.name(),
                k + 1
            );
        }
    }
}

#[test]
fn a_render_mesh_round_trips_and_is_checked() {
    use crate::dim::math::Vector;
    use crate::dim::CellKind;
    let mesh = Mesh::ball(0.25, 5, CellKind::Simplex).unwrap();
    let mut body = DeformableBuilder::new(mesh.clone())
        .translation(Vector::Y * 0.5)
        .build()
        .unwrap();
    // The render mesh: the body's own surface, grown by 2 %.
    let vertices: Vec<Vector> = mesh.nodes().iter().map(|p| *p * 1.02).collect();
    body.set_render_mesh(&vertices, mesh.boundary_facets().to_vec())
        .unwrap();
    let mut restored: Deformable = bincode::deserialize(&save(&body)).expect("it restores");
    assert_eq!(restored.render_mesh(), body.render_mesh());
    // It follows the restored body.
    let moved: Vec<Vector> = restored
        .positions()
        .iter()
        .map(|p| *p + Vector::X)
        .collect();
    restored.set_positions(&moved).unwrap();
    let (a, b) = (body.render_mesh().unwrap(), restored.render_mesh().unwrap());
    for (p, q) in a.vertices().iter().zip(b.vertices()) {
        assert!((*q - *p - Vector::X).length() < 1e-5);
    }
    // A render vertex bound to a node the body does not have is refused.
    let mut json: serde_json::Value = serde_json::to_value(&body).unwrap();
    json["render"]["nodes"][0][0] = serde_json::Value::from(1_000_000);
    let err = serde_json::from_value::<Deformable>(json).expect_err("node out of range");
    assert!(err.to_string().contains("render vertex"), "{err}");
}
