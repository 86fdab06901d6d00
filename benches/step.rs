//! One step of the `fall` scene's box, resting on the ground, per model, 2D and 3D, at
//! resolutions 5, 9, 17 and 33 nodes per edge (up to 32³·6 = 196 608 tetrahedra), for each of
//! sinew's element models and rapier's own soft-body models on the same mesh.
//!
//! Three groups per dimension:
//! - `fall_step_{2d,3d}`: one 1 ms step, each solver choosing its own substeps (sinew: from
//!   the stability bound; rapier: its defaults, 4 solver iterations). Throughput is elements,
//!   so criterion's `elem/s` is element-steps per second at equal dt.
//! - `element_forces_{2d,3d}`: sinew's models only, one evaluation of every element's force
//!   on the settled box (`Deformable::element_forces`): the force law alone, the comparison
//!   the shape-based paper makes ("1.05 times the cost of a spring element").
//! - `element_update_{2d,3d}`: sinew's models only, one step of exactly one substep, with dt
//!   small enough for every model to be stable (`0.4 ms / (res − 1)`). Throughput is elements,
//!   so `elem/s` is element-updates per second: the same work for every model, contacts and
//!   the step's diagnostics included.
//!
//! ```text
//! cargo bench --bench step                          # everything (~30 min)
//! cargo bench --bench step -- --quick               # a shorter pass
//! SINEW_BENCH_RES=5,9 cargo bench --bench step      # only these resolutions
//! cargo bench --bench step -- 'element_update_3d/'  # one group
//! ```
//!
//! A fourth group, `scaling_3d`, steps a resting cube of 1 296 to 998 250 tetrahedra (7, 11,
//! 21 and 56 nodes per edge; `SINEW_BENCH_SCALING` to choose) for edge repulsion, shape
//! matching and springs (one explicit substep of `0.4 ms / (res − 1)`) and for edge repulsion
//! under `Integrator::Implicit { iterations: 2 }` at 60 Hz: `elem/s` is cells per second, and
//! each world's heap per cell and per node is printed as it is built.
//!
//! With `--features parallel`, a fifth group, `threads_3d`, steps a resting res-17 cube
//! (`SINEW_BENCH_THREADS_RES` to choose) on rayon pools of 1 and 2 threads: edge repulsion and
//! shape matching, explicit at 1 ms and implicit (2 sweeps) at 60 Hz.
//!
//! Under `cargo test --benches` (criterion's test mode) only resolution 5 (scaling: 6) is built
//! and each benchmark runs once.

use std::time::Duration;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};

/// The resolutions in the environment variable `var` (comma separated), else `test` in
/// criterion's test mode (no `--bench` argument, as under `cargo test --benches`), else `bench`.
fn resolutions_from(var: &str, test: &[usize], bench: &[usize]) -> Vec<usize> {
    if let Ok(list) = std::env::var(var) {
        return list
            .split(',')
            .map(|s| {
                s.trim()
                    .parse()
                    .unwrap_or_else(|_| panic!("{var}: comma-separated integers"))
            })
            .collect();
    }
    if std::env::args().any(|a| a == "--bench") {
        bench.to_vec()
    } else {
        test.to_vec()
    }
}

/// The resolutions to run: `SINEW_BENCH_RES`, else 5 in test mode, else 5, 9, 17, 33.
fn resolutions() -> Vec<usize> {
    resolutions_from("SINEW_BENCH_RES", &[5], &[5, 9, 17, 33])
}

/// The scaling group's resolutions: `SINEW_BENCH_SCALING`, else 6 in test mode, else 7, 11,
/// 21, 56 (1 296 to 998 250 tetrahedra: 10³ to 10⁶).
fn scaling_resolutions() -> Vec<usize> {
    resolutions_from("SINEW_BENCH_SCALING", &[6], &[7, 11, 21, 56])
}

/// Heap bytes in use (glibc's `mallinfo2`; 0 elsewhere): unlike the resident size, it does not
/// count memory freed by earlier worlds and kept by the allocator.
fn heap_bytes() -> u64 {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        #[repr(C)]
        struct MallInfo2 {
            arena: usize,
            ordblks: usize,
            smblks: usize,
            hblks: usize,
            hblkhd: usize,
            usmblks: usize,
            fsmblks: usize,
            uordblks: usize,
            fordblks: usize,
            keepcost: usize,
        }
        extern "C" {
            fn mallinfo2() -> MallInfo2;
        }
        // SAFETY: `mallinfo2` only reads the allocator's statistics.
        let info = unsafe { mallinfo2() };
        (info.uordblks + info.hblkhd) as u64
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    {
        0
    }
}

/// Steps run before measuring, so the box rests on the ground and contacts are in the step.
const SETTLE_STEPS: usize = 20;

macro_rules! bench_dimension {
    ($c:expr, $dim:ident, $label:expr) => {{
        use sinew::$dim::mesh::CellKind;
        use sinew::$dim::DeformableWorld;
        use sinew_scenes::$dim::{FallScene, Subject};
        let resolutions = resolutions();
        // Cells of the lattice at `res` (the scene's mesh, without building a world).
        let elements = |res: usize| -> u64 {
            let half = sinew::$dim::math::Vector::splat(0.5);
            let dims = [res; sinew::$dim::math::DIM];
            sinew::$dim::Mesh::cuboid(half, dims, CellKind::Simplex)
                .expect("lattice")
                .num_cells() as u64
        };
        // The scene's world after it settled on the ground.
        let settled = |scene: &FallScene| -> DeformableWorld {
            let mut world = scene.sim().expect("scene builds").world;
            for _ in 0..SETTLE_STEPS {
                world.step();
            }
            assert!(
                world.report().deformables.iter().all(|(_, r)| !r.frozen),
                "{scene:?} blew up while settling"
            );
            world
        };

        // One group: every subject (or sinew's only) at every resolution, the scene from
        // `scene(subject, res)`, timing a step or one force evaluation.
        let mut group_of =
            |name: &str,
             samples: usize,
             seconds: u64,
             sinew_only: bool,
             forces_only: bool,
             scene: &dyn Fn(Subject, usize) -> FallScene| {
                let mut group = $c.benchmark_group(format!("{name}_{}", $label));
                group.sample_size(samples);
                group.warm_up_time(Duration::from_millis(500));
                group.measurement_time(Duration::from_secs(seconds));
                for &res in &resolutions {
                    for subject in Subject::all() {
                        if sinew_only && !matches!(subject, Subject::Sinew(_)) {
                            continue;
                        }
                        let scene = scene(subject, res);
                        group.throughput(Throughput::Elements(elements(res)));
                        // Built on first use: criterion calls the routine only for benchmarks
                        // that pass the command line's filter.
                        let mut world = None;
                        group.bench_with_input(
                            BenchmarkId::new(subject.name(), res),
                            &res,
                            |b, _| {
                                let world = world.get_or_insert_with(|| settled(&scene));
                                if forces_only {
                                    let (_, body) =
                                        world.deformables.iter_mut().next().expect("one body");
                                    b.iter(|| body.element_forces()[0])
                                } else {
                                    b.iter(|| world.step().wall_time)
                                }
                            },
                        );
                    }
                }
                group.finish();
            };
        let resting = |subject: Subject, res: usize| FallScene {
            subject,
            resolution: res,
            drop_height: 0.0,
            ..FallScene::default()
        };
        group_of("fall_step", 10, 3, false, false, &resting);
        group_of("element_forces", 20, 2, true, true, &resting);
        group_of("element_update", 10, 3, true, false, &|subject, res| {
            FallScene {
                dt: 4.0e-4 / (res - 1) as sinew::$dim::math::Real,
                fixed_substeps: Some(1),
                ..resting(subject, res)
            }
        });
    }};
}

/// Cost per cell from 10³ to 10⁶ cells (3D).
fn scaling(c: &mut Criterion) {
    use sinew::dim3::math::Real;
    use sinew::dim3::{ElementModel, Integrator};
    use sinew_scenes::dim3::{FallScene, Subject};
    let mut group = c.benchmark_group("scaling_3d");
    group.sample_size(10);
    group.warm_up_time(Duration::from_millis(200));
    group.measurement_time(Duration::from_secs(3));
    let runs = [
        ("edge-repulsion", ElementModel::EdgeRepulsion, None),
        ("shape-matching", ElementModel::SHAPE_MATCHING, None),
        ("springs", ElementModel::Springs, None),
        (
            "edge-repulsion-implicit",
            ElementModel::EdgeRepulsion,
            Some(Integrator::Implicit { iterations: 2 }),
        ),
    ];
    for res in scaling_resolutions() {
        for (name, model, implicit) in runs {
            let scene = match implicit {
                Some(integrator) => FallScene {
                    subject: Subject::Sinew(model),
                    resolution: res,
                    drop_height: 0.0,
                    dt: 1.0 / 60.0,
                    integrator,
                    ..FallScene::default()
                },
                None => FallScene {
                    subject: Subject::Sinew(model),
                    resolution: res,
                    drop_height: 0.0,
                    dt: 4.0e-4 / (res - 1) as Real,
                    fixed_substeps: Some(1),
                    ..FallScene::default()
                },
            };
            let mut world = None;
            group.throughput(Throughput::Elements(((res - 1).pow(3) * 6) as u64));
            group.bench_with_input(BenchmarkId::new(name, res), &res, |b, _| {
                let world = world.get_or_insert_with(|| {
                    let before = heap_bytes();
                    let mut world = scene.sim().expect("scene builds").world;
                    // Awake throughout: a resting cube would fall asleep and cost nothing.
                    world.pipeline.settings.time_until_sleep = Real::INFINITY;
                    for _ in 0..3 {
                        world.step();
                    }
                    let bytes = heap_bytes().saturating_sub(before) as f64;
                    let (_, body) = world.deformables.iter().next().expect("one body");
                    let (cells, nodes) = (body.mesh().num_cells(), body.positions().len());
                    println!(
                        "scaling_3d/{name}/{res}: {cells} cells, {nodes} nodes, heap \
                         {:.0} bytes per cell, {:.0} per node",
                        bytes / cells as f64,
                        bytes / nodes as f64
                    );
                    world
                });
                b.iter(|| world.step().wall_time)
            });
        }
    }
    group.finish();
}

/// One step of a resting res-17 cube (24 576 tetrahedra, awake) on rayon pools of 1 and 2
/// threads (feature `parallel`): edge repulsion and shape matching, explicit at 1 ms and
/// `Integrator::Implicit { iterations: 2 }` at 60 Hz.
#[cfg(feature = "parallel")]
fn threads(c: &mut Criterion) {
    use sinew::dim3::math::Real;
    use sinew::dim3::{ElementModel, Integrator};
    use sinew_scenes::dim3::{FallScene, Subject};
    let res = resolutions_from("SINEW_BENCH_THREADS_RES", &[5], &[17])[0];
    let mut group = c.benchmark_group("threads_3d");
    group.sample_size(10);
    group.warm_up_time(Duration::from_millis(500));
    group.measurement_time(Duration::from_secs(4));
    group.throughput(Throughput::Elements(((res - 1).pow(3) * 6) as u64));
    let runs = [
        ("edge-repulsion-explicit", ElementModel::EdgeRepulsion, None),
        (
            "shape-matching-explicit",
            ElementModel::SHAPE_MATCHING,
            None,
        ),
        (
            "edge-repulsion-implicit",
            ElementModel::EdgeRepulsion,
            Some(Integrator::Implicit { iterations: 2 }),
        ),
        (
            "shape-matching-implicit",
            ElementModel::SHAPE_MATCHING,
            Some(Integrator::Implicit { iterations: 2 }),
        ),
    ];
    for (name, model, implicit) in runs {
        let scene = FallScene {
            subject: Subject::Sinew(model),
            resolution: res,
            drop_height: 0.0,
            dt: if implicit.is_some() { 1.0 / 60.0 } else { 1e-3 },
            integrator: implicit.unwrap_or(Integrator::Explicit),
            ..FallScene::default()
        };
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a thread pool");
            let mut world = None;
            group.bench_with_input(BenchmarkId::new(name, threads), &threads, |b, _| {
                let world = world.get_or_insert_with(|| {
                    let mut world = scene.sim().expect("scene builds").world;
                    world.pipeline.settings.time_until_sleep = Real::INFINITY;
                    for _ in 0..SETTLE_STEPS {
                        pool.install(|| world.step());
                    }
                    world
                });
                b.iter(|| pool.install(|| world.step().wall_time))
            });
        }
    }
    group.finish();
}

fn steps(c: &mut Criterion) {
    bench_dimension!(c, dim3, "3d");
    bench_dimension!(c, dim2, "2d");
    scaling(c);
    #[cfg(feature = "parallel")]
    threads(c);
}

criterion_group!(benches, steps);
criterion_main!(benches);
