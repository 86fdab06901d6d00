//! Tearing (issue 31, acceptance 2 and 4): a slab pulled apart by two bones tears at its tear
//! strain, and its pieces fall separately and rest on the ground.

use std::sync::mpsc::channel;

use crate::dim::math::{Pose, Real, Vector, DIM, UP};
use crate::dim::rapier::geometry::{Cuboid, Ray, SharedShape};
use crate::dim::rapier::prelude::{ColliderBuilder, RigidBodyBuilder, RigidBodyHandle};
use crate::dim::{
    BuildError, ChannelEventCollector, DeformableBuilder, DeformableHandle, DeformableQueryFilter,
    DeformableWorld, ElementModel, FlowIn, Gas, Integrator, Material, Plasticity, Tearing,
};

const TEAR: Real = 0.1;

/// The ground's top, 2 cm below the slab (a fall from higher strains the landing piece past
/// the tear strain: `v/c` is 0.28 from 0.4 m).
const GROUND: Real = -0.12;

/// A 1 m slab along the first axis, 0.2 m high (0.1 m deep in 3D), 10 cm cells, its end
/// faces bound to two kinematic bones (left, right), over a ground.
fn slab(
    model: ElementModel,
    integrator: Integrator,
) -> (DeformableWorld, DeformableHandle, [RigidBodyHandle; 2]) {
    let mut world = DeformableWorld::new();
    world.set_dt(1.0 / 60.0);
    // Weightless while it is pulled: a sagging slab would be strained by its weight.
    world.physics.gravity = Vector::ZERO;
    world.pipeline.settings.integrator = integrator;
    let mut half = Vector::splat(0.05);
    half[0] = 0.5;
    half[1] = 0.1;
    let mut res = [2; DIM];
    res[0] = 11;
    res[1] = 3;
    let body = DeformableBuilder::cuboid(half, res)
        .model(model)
        .material(Material {
            density: 1000.0,
            young_modulus: 1e5,
            damping_ratio: 0.3,
            ..Default::default()
        })
        .tearing(Tearing::at(TEAR))
        .build()
        .unwrap();
    let mut ground = Vector::splat(2.0);
    ground[1] = 0.1;
    world.physics.insert(
        RigidBodyBuilder::fixed().translation(UP * (GROUND - 0.1)),
        ColliderBuilder::new(SharedShape::new(Cuboid::new(ground))),
    );
    let h = world.insert(body);
    let bones = [-0.5, 0.5].map(|x: Real| {
        let bone = world
            .physics
            .insert_body(RigidBodyBuilder::kinematic_position_based());
        let d = &world.deformables[h];
        let ends: Vec<u32> = (0..d.num_nodes() as u32)
            .filter(|&i| (d.positions()[i as usize][0] - x).abs() < 1e-4)
            .collect();
        world.attach_nodes(h, bone, &ends).unwrap();
        bone
    });
    (world, h, bones)
}

/// The body's pieces: each cell's piece (cells joined through shared nodes), numbered in
/// order of their first cell, and how many pieces there are.
fn pieces(world: &DeformableWorld, h: DeformableHandle) -> (Vec<usize>, usize) {
    let mesh = world.deformables[h].mesh();
    let mut piece_of_node = vec![usize::MAX; mesh.nodes().len()];
    let mut piece = vec![usize::MAX; mesh.num_cells()];
    let mut count = 0;
    for start in 0..mesh.num_cells() {
        if piece[start] != usize::MAX {
            continue;
        }
        let mut stack = vec![start];
        piece[start] = count;
        while let Some(c) = stack.pop() {
            for &i in mesh.cell(c) {
                piece_of_node[i as usize] = count;
            }
            for (other, p) in piece.iter_mut().enumerate() {
                if *p == usize::MAX
                    && mesh
                        .cell(other)
                        .iter()
                        .any(|&i| piece_of_node[i as usize] == count)
                {
                    *p = count;
                    stack.push(other);
                }
            }
        }
        count += 1;
    }
    (piece, count)
}

/// Each piece's nodes' first coordinates: (least, most), by piece.
fn spans(world: &DeformableWorld, h: DeformableHandle) -> Vec<(Real, Real)> {
    let (piece, count) = pieces(world, h);
    let d = &world.deformables[h];
    let mut spans = vec![(Real::INFINITY, Real::NEG_INFINITY); count];
    for (c, &p) in piece.iter().enumerate() {
        for &i in d.mesh().cell(c) {
            let x = d.positions()[i as usize][0];
            spans[p] = (spans[p].0.min(x), spans[p].1.max(x));
        }
    }
    spans
}

/// A ray straight down through `x` (the depth's middle).
fn down_at(x: Real) -> Ray {
    let mut origin = Vector::ZERO;
    origin[0] = x;
    origin[1] = 2.0;
    Ray::new(origin, -UP)
}

#[test]
fn a_slab_pulled_apart_tears_at_its_tear_strain_and_its_pieces_fall_apart() {
    for model in [ElementModel::EdgeRepulsion, ElementModel::SHAPE_MATCHING] {
        for integrator in [Integrator::Explicit, Integrator::Implicit { iterations: 2 }] {
            let name = format!("{} {integrator:?}", model.name());
            let (mut world, h, [_, right]) = slab(model, integrator);
            let (contacts, _contact_events) = channel();
            let (tears, tear_events) = channel();
            let collector = ChannelEventCollector::with_tears(contacts, tears);
            assert!(
                world
                    .deformables
                    .cast_ray(&down_at(0.05), 10.0, DeformableQueryFilter::default())
                    .is_some(),
                "{name}: the whole slab stops a ray"
            );
            // Pulled at 0.12 m/s: a log strain of 0.12 a second.
            let mut torn_at = None;
            let mut steps = 0;
            while steps < 240 {
                steps += 1;
                let pulled = 0.002 * steps as Real;
                let mut at = Vector::ZERO;
                at[0] = pulled;
                world.physics.bodies[right].set_next_kinematic_position(Pose::from_translation(at));
                world.step_with_events(&collector);
                let d = &world.deformables[h];
                assert!(d.positions().iter().all(|p| p.is_finite()), "{name}");
                assert_eq!(d.inverted_elements(), 0, "{name} at step {steps}");
                if torn_at.is_none() && !d.last_tears().is_empty() {
                    torn_at = Some((1.0 + pulled).ln());
                }
                // Pulled on 0.1 m past the first tear.
                if torn_at.is_some_and(|s| (1.0 + pulled).ln() > s + 0.1) {
                    break;
                }
            }
            let strain = torn_at.unwrap_or_else(|| panic!("{name}: never tore"));
            assert!(
                (strain - TEAR).abs() <= 0.1 * TEAR,
                "{name}: tore at a pulled log strain of {strain}, the tear strain is {TEAR}"
            );
            let events: Vec<_> = tear_events.try_iter().collect();
            assert!(!events.is_empty(), "{name}: no tear event");
            let cells = world.deformables[h].mesh().num_cells() as u32;
            for e in &events {
                assert_eq!(e.deformable, h, "{name}");
                assert!(
                    e.faces.iter().flatten().all(|&c| c < cells),
                    "{name}: {:?}",
                    e.faces
                );
            }
            let torn = spans(&world, h);
            assert_eq!(torn.len(), 2, "{name}: pieces {torn:?}");
            // The crack is open: a ray down its middle meets no surface.
            let (left, right_piece) = if torn[0].0 < torn[1].0 {
                (torn[0], torn[1])
            } else {
                (torn[1], torn[0])
            };
            assert!(left.1 < right_piece.0, "{name}: pieces {torn:?}");
            let gap = 0.5 * (left.1 + right_piece.0);
            assert!(
                world
                    .deformables
                    .cast_ray(&down_at(gap), 10.0, DeformableQueryFilter::default())
                    .is_none(),
                "{name}: a ray through the crack at {gap} ({torn:?}) hits the slab"
            );
            // Let go under gravity: the pieces fall and rest on the ground, apart, with no energy gained.
            world.deformables[h].detach_all();
            world.physics.gravity = -UP * 9.81;
            let energy = |w: &DeformableWorld| {
                let r = w.deformables[h].report();
                r.kinetic_energy + r.elastic_energy + r.gravity_energy
            };
            world.step();
            let start = energy(&world);
            for _ in 0..180 {
                world.step();
                let d = &world.deformables[h];
                assert!(d.positions().iter().all(|p| p.is_finite()), "{name}");
                assert_eq!(d.inverted_elements(), 0, "{name}");
                assert!(
                    energy(&world) <= start + 1e-3 * start.abs(),
                    "{name}: energy {} above {start} after the release",
                    energy(&world)
                );
            }
            let d = &world.deformables[h];
            let lowest = d
                .positions()
                .iter()
                .map(|p| p[1])
                .fold(Real::INFINITY, Real::min);
            assert!(
                (lowest - GROUND).abs() < 0.01,
                "{name}: lowest node at {lowest}"
            );
            let fastest = d
                .velocities()
                .iter()
                .map(|v| v.length())
                .fold(0.0, Real::max);
            assert!(
                fastest < 0.05,
                "{name}: a node still moves at {fastest} m/s"
            );
            let rest = spans(&world, h);
            assert_eq!(rest.len(), 2, "{name}: pieces at rest {rest:?}");
        }
    }
}

#[test]
fn bad_tearing_parameters_are_refused() {
    let build = |tearing: Tearing| {
        DeformableBuilder::cuboid(Vector::splat(0.5), [3; DIM])
            .tearing(tearing)
            .build()
    };
    for strain in [0.0, -0.1, Real::NAN, Real::INFINITY] {
        assert!(
            matches!(
                build(Tearing::at(strain)),
                Err(BuildError::InvalidParameter {
                    name: "Tearing::strain",
                    ..
                })
            ),
            "strain {strain}"
        );
    }
    let none = Tearing {
        smallest_piece: 0,
        ..Tearing::at(0.1)
    };
    assert!(matches!(
        build(none),
        Err(BuildError::InvalidParameter {
            name: "Tearing::smallest_piece",
            ..
        })
    ));
    let plastic = Plasticity {
        yield_strain: 0.2,
        flow_rate: Real::INFINITY,
        max_strain: 1.0,
        flow: FlowIn::Both,
    };
    let below = DeformableBuilder::cuboid(Vector::splat(0.5), [3; DIM])
        .plasticity(plastic)
        .tearing(Tearing::at(0.1))
        .build();
    assert!(
        matches!(below, Err(BuildError::TearBelowYield { .. })),
        "{below:?}"
    );
    let above = DeformableBuilder::cuboid(Vector::splat(0.5), [3; DIM])
        .plasticity(plastic)
        .tearing(Tearing::at(0.3))
        .build();
    assert!(above.is_ok(), "{above:?}");
    let gas = DeformableBuilder::cuboid(Vector::splat(0.5), [3; DIM])
        .gas(Gas::gauge(1e3))
        .tearing(Tearing::at(0.3))
        .build();
    assert!(matches!(gas, Err(BuildError::TearingWithGas)), "{gas:?}");
}

/// A snapshot taken just after a tear (the split mesh, the crack still releasing) continues
/// bit for bit, and so does one taken while the crack is still growing.
#[cfg(feature = "serde")]
#[test]
fn a_snapshot_after_a_tear_continues_bit_for_bit() {
    let (mut world, h, [_, right]) = slab(ElementModel::EdgeRepulsion, Integrator::Explicit);
    let pull = |world: &mut DeformableWorld, k: usize| {
        let mut at = Vector::ZERO;
        at[0] = 0.002 * k as Real;
        world.physics.bodies[right].set_next_kinematic_position(Pose::from_translation(at));
        world.step();
    };
    let mut k = 0;
    while world.deformables[h].last_tears().is_empty() {
        k += 1;
        assert!(k < 240, "never tore");
        pull(&mut world, k);
    }
    let built = world.deformables[h].num_nodes();
    let bytes = bincode::serialize(&world).expect("a snapshot serializes");
    let mut restored: DeformableWorld = bincode::deserialize(&bytes).expect("it restores");
    assert_eq!(restored.deformables[h].num_nodes(), built);
    assert_eq!(
        restored.deformables[h].last_tears(),
        world.deformables[h].last_tears()
    );
    for w in [&mut world, &mut restored] {
        for j in 1..=30 {
            pull(w, k + j);
        }
    }
    let (a, b) = (&world.deformables[h], &restored.deformables[h]);
    assert_eq!(a.mesh().cell_indices(), b.mesh().cell_indices());
    assert_eq!(a.positions(), b.positions());
}
