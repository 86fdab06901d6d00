//! Feature `parallel`: whole steps of a body large enough to take the parallel paths give the
//! same state, bit for bit, on one thread (serial loops) and on several (the split force
//! evaluation, the implicit sweeps' slabs at once).

#![cfg(feature = "parallel")]

use crate::dim::math::{Real, DIM};
use crate::dim::model::PARALLEL_MIN_WORK;
use crate::dim::{ElementModel, Integrator};
use crate::scenes::FallScene;

/// Positions and velocities after `steps` steps of the fall scene, run inside a rayon pool of
/// `threads` threads.
fn fall_state(model: ElementModel, resolution: usize, threads: usize, steps: usize) -> Vec<u32> {
    let scene = FallScene {
        subject: model.into(),
        resolution,
        // Start touching the ground so contacts are part of the steps.
        drop_height: 0.0,
        ..FallScene::default()
    };
    state_after(scene, threads, steps)
}

/// Positions and velocities after `steps` steps of `scene` in a pool of `threads` threads.
fn state_after(scene: FallScene, threads: usize, steps: usize) -> Vec<u32> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool");
    pool.install(|| {
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
        for threads in [2, 16] {
            let many = fall_state(model, resolution, threads, 5);
            assert!(
                one == many,
                "{}: 1 and {threads} threads differ",
                model.name()
            );
        }
    }
}

#[test]
fn implicit_steps_do_not_depend_on_the_thread_count() {
    // Large enough for the sweeps to go by slabs (at least four slabs of 256 nodes, each
    // wider than a cell's span of node indices): 1 331 nodes in 3D, 1 296 in 2D. Dropped from
    // 5 cm at 60 Hz: free flight, the landing (nodes held by the contact) and rest.
    let resolution = if DIM == 2 { 36 } else { 11 };
    for model in [ElementModel::EdgeRepulsion, ElementModel::SHAPE_MATCHING] {
        for integrator in [
            Integrator::Implicit { iterations: 2 },
            Integrator::Midpoint { iterations: 2 },
        ] {
            let scene = FallScene {
                subject: model.into(),
                resolution,
                drop_height: 0.05,
                dt: 1.0 / 60.0,
                integrator,
                ..FallScene::default()
            };
            let one = state_after(scene, 1, 12);
            for threads in [2, 16] {
                let many = state_after(scene, threads, 12);
                assert!(
                    one == many,
                    "{} {integrator:?}: 1 and {threads} threads differ",
                    model.name()
                );
            }
        }
    }
}
