//! Feature `parallel`: whole steps of a body large enough to take the parallel force path give
//! the same state, bit for bit, on one thread (serial loop) and on two (split evaluation).

#![cfg(feature = "parallel")]

use crate::dim::math::{Real, DIM};
use crate::dim::model::PARALLEL_MIN_WORK;
use crate::dim::ElementModel;
use crate::scenes::FallScene;

/// Positions and velocities after `steps` steps of the fall scene, run inside a rayon pool of
/// `threads` threads.
fn fall_state(model: ElementModel, resolution: usize, threads: usize, steps: usize) -> Vec<u32> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool");
    pool.install(|| {
        let scene = FallScene {
            subject: model.into(),
            resolution,
            // Start touching the ground so contacts are part of the steps.
            drop_height: 0.0,
            ..FallScene::default()
        };
        let sim = scene.sim().expect("scene builds");
        // Enough cells to take the parallel path (each counts 20 or 30 springs).
        assert!(sim.mesh().num_cells() * 20 >= PARALLEL_MIN_WORK);
        let mut world = sim.world;
        for _ in 0..steps {
            world.step();
        }
        let (_, body) = world.deformables.iter().next().expect("one body");
        body.positions()
            .iter()
            .chain(body.velocities())
            .flat_map(|p| p.to_array())
            .map(Real::to_bits)
            .collect()
    })
}

#[test]
fn steps_do_not_depend_on_the_thread_count() {
    let resolution = if DIM == 2 { 36 } else { 8 };
    for model in [ElementModel::EdgeRepulsion, ElementModel::SHAPE_MATCHING] {
        let one = fall_state(model, resolution, 1, 5);
        let two = fall_state(model, resolution, 2, 5);
        assert!(one == two, "{}: 1 and 2 threads differ", model.name());
    }
}
