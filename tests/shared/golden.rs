//! Golden state hashes: the full node and rigid-body state after a few hundred steps of two
//! scenes, every element model, hashed and compared with the recorded value. A refactor of the
//! step must not change a single bit.
//!
//! * `stack`: [`super::determinism::scene`]: a cube of every model with a dynamic box landing on
//!   it, tissue bound to a turning velocity-based kinematic bone, a lone cube that falls asleep;
//!   `dt = 1/60` s, 240 steps.
//! * `blades`: coarse cubes of every model (and one of box cells) at `dt = 1 ms` struck by what
//!   the facet test handles: a position-based kinematic blade pressed into one, a dynamic ball
//!   and a dynamic capsule dropped on others, a dynamic box bound to a cube's nodes (the two-way
//!   binding), a cube thrown sideways along the ground (friction); 400 steps.
//!
//! The hash is FNV-1a over the bit patterns of every deformable's positions and velocities and
//! every rigid body's pose and velocities, plus the sleep flags. The recorded values hold for
//! this platform's float arithmetic in a default build (x86-64; the `parallel` and
//! `enhanced-determinism` features change rapier's arithmetic, and are excluded).

use crate::dim::math::{Pose, Real, Vector, DIM, UP};
use crate::dim::mesh::CellKind;
use crate::dim::rapier::geometry::{Ball, Capsule, Cuboid, SharedShape};
use crate::dim::rapier::prelude::{ColliderBuilder, RigidBodyBuilder};
use crate::dim::{DeformableBuilder, DeformableWorld, ElementModel, Material};

/// FNV-1a, 64 bits: a hash whose value is fixed by its definition (unlike `DefaultHasher`).
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
    fn word(&mut self, w: u64) {
        for b in w.to_le_bytes() {
            self.0 ^= b as u64;
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
    fn real(&mut self, x: Real) {
        self.word(x.to_bits() as u64);
    }
    fn vector(&mut self, v: Vector) {
        for c in v.to_array() {
            self.real(c);
        }
    }
}

/// The hash of everything that moves in `world` (see the module docs).
pub fn golden_hash(world: &DeformableWorld) -> u64 {
    let mut h = Fnv::new();
    for (handle, d) in world.deformables.iter() {
        let (i, g) = handle.into_raw_parts();
        h.word(((i as u64) << 32) | g as u64);
        for v in d.positions().iter().chain(d.velocities()) {
            h.vector(*v);
        }
        h.word(d.is_sleeping() as u64 | (d.is_frozen() as u64) << 1);
    }
    for (_, b) in world.physics.bodies.iter() {
        let pose: &Pose = b.position();
        h.vector(pose.translation);
        // The rotation's components, through its `Debug` text in both dimensions (a float's
        // `Debug` is its shortest round-trip form: distinct bits, distinct text).
        for byte in format!("{:?}", pose.rotation).bytes() {
            h.word(byte as u64);
        }
        h.vector(b.linvel());
        for byte in format!("{:?}", b.angvel()).bytes() {
            h.word(byte as u64);
        }
        h.word(b.is_sleeping() as u64);
    }
    h.0
}

fn cuboid(half: Vector) -> ColliderBuilder {
    ColliderBuilder::new(SharedShape::new(Cuboid::new(half)))
}

fn along(x: Real) -> Vector {
    let mut v = Vector::ZERO;
    v[0] = x;
    v
}

fn stack() -> DeformableWorld {
    super::determinism::scene(&ElementModel::ALL, 4).world
}

fn blades() -> DeformableWorld {
    let mut world = DeformableWorld::new();
    world.set_dt(1e-3);
    let mut half = Vector::splat(20.0);
    half[1] = 0.5;
    world.physics.insert(
        RigidBodyBuilder::fixed().translation(-UP * 0.5),
        cuboid(half),
    );
    let material = Material {
        density: 500.0,
        young_modulus: 3e4,
        damping_ratio: 0.1,
        ..Default::default()
    };
    let mut cubes = Vec::new();
    for (k, model) in ElementModel::ALL.iter().enumerate() {
        let cube = DeformableBuilder::cuboid(Vector::splat(0.25), [3; DIM])
            .model(*model)
            .material(material)
            .friction(0.6)
            .restitution(0.3)
            .translation(along(k as Real * 2.0) + UP * 0.26)
            .build()
            .expect("a valid cube");
        cubes.push(world.insert(cube));
    }
    let boxed = DeformableBuilder::cuboid(Vector::splat(0.25), [3; DIM])
        .cells(CellKind::Cube)
        .model(ElementModel::Springs)
        .material(material)
        .translation(along(-2.0) + UP * 0.4)
        .linvel(along(1.5))
        .build()
        .expect("a valid box-cell cube");
    world.insert(boxed);
    // A thin kinematic blade pressed down into the first cube, between its nodes.
    let blade = world
        .physics
        .insert_body(RigidBodyBuilder::kinematic_position_based().translation(UP * 0.62));
    let mut blade_half = Vector::splat(0.3);
    blade_half[0] = 0.01;
    blade_half[1] = 0.1;
    world
        .physics
        .insert_collider(cuboid(blade_half).friction(0.2), Some(blade));
    // A ball on the second cube, a capsule on the third.
    world.physics.insert(
        RigidBodyBuilder::dynamic().translation(along(2.05) + UP * 0.8),
        ColliderBuilder::new(SharedShape::new(Ball::new(0.12))).density(800.0),
    );
    world.physics.insert(
        RigidBodyBuilder::dynamic().translation(along(3.95) + UP * 0.8),
        ColliderBuilder::new(SharedShape::new(Capsule::new_x(0.2, 0.05))).density(800.0),
    );
    // A dynamic box bound to the top nodes of the fourth cube (the two-way binding).
    let (weight, _) = world.physics.insert(
        RigidBodyBuilder::dynamic().translation(along(6.0) + UP * 0.62),
        cuboid(Vector::splat(0.1)).density(200.0),
    );
    let top: Vec<u32> = world.deformables[cubes[3]]
        .positions()
        .iter()
        .enumerate()
        .filter(|(_, p)| p.dot(UP) > 0.45)
        .map(|(i, _)| i as u32)
        .collect();
    world
        .attach_nodes(cubes[3], weight, &top)
        .expect("the box binds");
    world.pipeline.settings.time_until_sleep = 0.2;
    world
}

/// Runs the blades scene; also returns how many facet contacts (rigid features pressing soft
/// faces) the steps reported, so the test can check the scene exercised them.
fn run_blades(steps: usize) -> (DeformableWorld, usize) {
    let mut world = blades();
    let blade = world
        .physics
        .bodies
        .iter()
        .find(|(_, b)| b.is_kinematic())
        .map(|(h, _)| h)
        .expect("the blade");
    let mut facet_contacts = 0;
    // The blade moves down 2 mm per step for the first 100 steps, then holds.
    for k in 0..steps {
        let y = 0.62 - 0.002 * (k.min(100) as Real);
        world.physics.bodies[blade].set_next_kinematic_position(Pose::from_translation(UP * y));
        facet_contacts += world
            .step()
            .deformables
            .iter()
            .map(|(_, r)| r.facet_contacts)
            .sum::<usize>();
    }
    (world, facet_contacts)
}

fn run_stack(steps: usize) -> DeformableWorld {
    let mut world = stack();
    for _ in 0..steps {
        world.step();
    }
    world
}

/// The values recorded for the present physics, (2D, 3D). A change of the physics on purpose
/// re-records them, and its commit says why.
const STACK: (u64, u64) = (0xf64d1bef078ae160, 0xe84116f1a46dee6e);
const BLADES: (u64, u64) = (0xd87315e7b7f6cfb5, 0xcb6110118b9535d6);

fn expected(pair: (u64, u64)) -> u64 {
    if DIM == 2 {
        pair.0
    } else {
        pair.1
    }
}

#[test]
fn the_state_after_hundreds_of_steps_matches_the_recorded_hash() {
    let stack = golden_hash(&run_stack(240));
    let (blades_world, facet_contacts) = run_blades(400);
    // The scene did what it claims: rigid features pressed soft faces, nothing froze.
    assert!(facet_contacts > 100, "facet contacts: {facet_contacts}");
    for (_, d) in blades_world.deformables.iter() {
        assert!(!d.is_frozen(), "no body froze");
    }
    let blades = golden_hash(&blades_world);
    println!("golden hashes ({DIM}D): stack {stack:#018x}, blades {blades:#018x}");
    assert_eq!(
        (stack, blades),
        (expected(STACK), expected(BLADES)),
        "the state after the recorded steps changed"
    );
}
