//! Determinism (issue 7): the same inputs give the same state, bit for bit — run twice in one
//! process, and (feature `parallel`) whatever rayon's thread count.
//!
//! The scene ([`scene`]) is shared with the snapshot tests: a cube of each element model
//! dropped on the ground with a dynamic box landing on it, a piece of tissue bound to a
//! turning kinematic bone, sleeping on (the default).

use std::hash::{DefaultHasher, Hash, Hasher};

use crate::dim::math::{self, Real, Vector, DIM, UP};
use crate::dim::rapier::dynamics::RigidBodyHandle;
use crate::dim::rapier::geometry::{Cuboid, SharedShape};
use crate::dim::rapier::prelude::{ColliderBuilder, RigidBodyBuilder};
use crate::dim::{DeformableBuilder, DeformableHandle, DeformableWorld, ElementModel, Material};

fn cuboid(half: Vector) -> ColliderBuilder {
    ColliderBuilder::new(SharedShape::new(Cuboid::new(half)))
}

fn horizontal(x: Real) -> Vector {
    let mut v = Vector::ZERO;
    v[0] = x;
    v
}

/// The scene's handles.
pub struct Scene {
    pub world: DeformableWorld,
    /// One cube per model, in the order given.
    pub cubes: Vec<DeformableHandle>,
    /// The dynamic box dropped on each cube.
    pub boxes: Vec<RigidBodyHandle>,
    /// The tissue bound to the turning bone.
    pub tissue: DeformableHandle,
    /// A cube with nothing on it, which falls asleep (a dynamic body resting on a deformable
    /// is woken by its contact impulses every step, so the others stay awake).
    pub lone: DeformableHandle,
}

/// The ground; per model a cube of `resolution` nodes per edge resting just above it and a
/// dynamic box a little above the cube; a tissue cube bound to a kinematic bone turning at
/// 1 rad/s; and a lone edge-repulsion cube that comes to rest and sleeps. `dt = 1/60` s.
pub fn scene(models: &[ElementModel], resolution: usize) -> Scene {
    let mut world = DeformableWorld::new();
    world.set_dt(1.0 / 60.0);
    let mut half = Vector::splat(10.0);
    half[1] = 0.5;
    world.physics.insert(
        RigidBodyBuilder::fixed().translation(-UP * 0.5),
        cuboid(half),
    );
    let mut cubes = Vec::new();
    let mut boxes = Vec::new();
    for (k, model) in models.iter().enumerate() {
        let x = horizontal(k as Real * 1.2);
        let cube = DeformableBuilder::cuboid(Vector::splat(0.25), [resolution; DIM])
            .model(*model)
            .material(Material {
                density: 400.0,
                young_modulus: 2e4,
                damping_ratio: 0.2,
                ..Default::default()
            })
            .translation(x + UP * 0.3)
            .build()
            .expect("a valid cube");
        cubes.push(world.insert(cube));
        let (body, _) = world.physics.insert(
            RigidBodyBuilder::dynamic().translation(x + UP * 0.75 + horizontal(0.03)),
            cuboid(Vector::splat(0.1)).density(300.0),
        );
        boxes.push(body);
    }
    let (bone, bone_collider) = world.physics.insert(
        RigidBodyBuilder::kinematic_velocity_based()
            .translation(horizontal(-1.5) + UP * 1.0)
            .angvel(math::planar_angle(1.0)),
        cuboid(Vector::splat(0.1)),
    );
    let tissue = DeformableBuilder::cuboid(Vector::splat(0.3), [4; DIM])
        .model(ElementModel::EdgeRepulsion)
        .material(Material {
            density: 200.0,
            young_modulus: 5e3,
            damping_ratio: 0.1,
            ..Default::default()
        })
        .translation(horizontal(-1.5) + UP * 1.0)
        .build()
        .expect("a valid tissue");
    let tissue = world.insert(tissue);
    let bound = world
        .attach_nodes_inside(tissue, bone_collider, 0.05)
        .expect("the bone binds");
    assert!(bound > 0, "the bone binds some nodes");
    let _ = bone;
    let lone = DeformableBuilder::cuboid(Vector::splat(0.25), [3; DIM])
        .material(Material {
            density: 1000.0,
            young_modulus: 2e4,
            damping_ratio: 0.3,
            ..Default::default()
        })
        .translation(horizontal(-3.5) + UP * 0.3)
        .build()
        .expect("a valid cube");
    let lone = world.insert(lone);
    Scene {
        world,
        cubes,
        boxes,
        tissue,
        lone,
    }
}

/// A hash of everything that moves: every deformable's node positions and velocities (bit
/// patterns) and sleep flag, every rigid body's pose, velocities and sleep flag (`Debug` of a
/// float is its shortest round-trip form: distinct bits, distinct text).
pub fn state_hash(world: &DeformableWorld) -> u64 {
    let mut h = DefaultHasher::new();
    for (handle, d) in world.deformables.iter() {
        handle.hash(&mut h);
        for v in d.positions().iter().chain(d.velocities()) {
            for c in v.to_array() {
                c.to_bits().hash(&mut h);
            }
        }
        d.is_sleeping().hash(&mut h);
    }
    for (handle, b) in world.physics.bodies.iter() {
        handle.hash(&mut h);
        format!(
            "{:?} {:?} {:?} {}",
            b.position(),
            b.linvel(),
            b.angvel(),
            b.is_sleeping()
        )
        .hash(&mut h);
    }
    h.finish()
}

/// What a run did, so a test can check that the scene exercised what it claims to.
#[derive(Debug, Default, PartialEq)]
pub struct Coverage {
    /// Steps in which some cube touched a box (a contact with a dynamic body's collider).
    pub box_contact_steps: usize,
    /// Steps after which the lone cube was asleep.
    pub asleep_steps: usize,
}

/// Steps `steps` times; returns the hash after every step and what the run covered.
pub fn run(mut scene: Scene, steps: usize) -> (Vec<u64>, Coverage) {
    let mut hashes = Vec::with_capacity(steps);
    let mut coverage = Coverage::default();
    let box_colliders: Vec<_> = scene
        .boxes
        .iter()
        .flat_map(|b| scene.world.physics.bodies[*b].colliders().to_vec())
        .collect();
    for _ in 0..steps {
        scene.world.step();
        hashes.push(state_hash(&scene.world));
        let w = &scene.world;
        if scene.cubes.iter().any(|c| {
            w.deformables[*c]
                .contacts()
                .iter()
                .any(|p| box_colliders.contains(&p.collider))
        }) {
            coverage.box_contact_steps += 1;
        }
        if w.deformables[scene.lone].is_sleeping() {
            coverage.asleep_steps += 1;
        }
    }
    assert!(
        !scene.world.deformables[scene.tissue].is_sleeping(),
        "the tissue on the turning bone never sleeps"
    );
    (hashes, coverage)
}

#[test]
fn the_same_scene_twice_gives_the_same_state_bit_for_bit() {
    let steps = 300;
    let (a, coverage) = run(scene(&ElementModel::ALL, 4), steps);
    let (b, coverage_b) = run(scene(&ElementModel::ALL, 4), steps);
    if let Some(k) = a.iter().zip(&b).position(|(x, y)| x != y) {
        panic!("the two runs differ from step {}", k + 1);
    }
    assert_eq!(coverage, coverage_b);
    assert!(
        coverage.box_contact_steps > 0,
        "the boxes land on the cubes: {coverage:?}"
    );
    assert!(
        coverage.asleep_steps > 0,
        "the lone cube falls asleep within {steps} steps: {coverage:?}"
    );
    // The hash sees the state: it changes while things move.
    assert_ne!(a[0], a[1]);
}

/// With `parallel`, bodies large enough to take the two-pass force path (and rapier's own
/// parallel solver) give the same state on 1, 2 and 3 threads, whether the threads poll for
/// the step's work or sleep between its loops.
#[cfg(feature = "parallel")]
#[test]
fn the_state_does_not_depend_on_the_thread_count() {
    use crate::dim::model::PARALLEL_MIN_WORK;
    let resolution = if DIM == 2 { 36 } else { 8 };
    let steps = 40;
    let models = [ElementModel::EdgeRepulsion, ElementModel::SHAPE_MATCHING];
    let runs = [(1, true), (2, true), (3, true), (2, false)];
    let hashes: Vec<Vec<u64>> = runs
        .into_iter()
        .map(|(threads, poll)| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a thread pool");
            pool.install(|| {
                let mut s = scene(&models, resolution);
                s.world.pipeline.settings.poll_threads = poll;
                let cells = s.world.deformables[s.cubes[0]].mesh().num_cells();
                assert!(cells * 20 >= PARALLEL_MIN_WORK, "large enough to split");
                assert!(cells > 1024, "large enough for the threads to poll");
                let (hashes, coverage) = run(s, steps);
                assert!(coverage.box_contact_steps > 0, "{coverage:?}");
                hashes
            })
        })
        .collect();
    for (run, h) in runs[1..].iter().zip(&hashes[1..]) {
        if let Some(k) = hashes[0].iter().zip(h).position(|(x, y)| x != y) {
            panic!(
                "1 thread and {run:?} (threads, polling) differ from step {}",
                k + 1
            );
        }
    }
}
