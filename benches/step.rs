//! One step of the `fall` scene's body per element model, 2D and 3D, at a few resolutions.
//! Throughput is reported in elements, so criterion prints element-updates per second.
//!
//! ```text
//! cargo bench --bench step            # full run
//! cargo bench --bench step -- --quick # a short pass
//! ```

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};

macro_rules! bench_dimension {
    ($c:expr, $dim:ident, $label:expr, $resolutions:expr) => {{
        use sinew::$dim::scenes::FallScene;
        use sinew::$dim::ElementModel;
        let mut group = $c.benchmark_group(concat!("step_", $label));
        group.sample_size(20);
        for res in $resolutions {
            for model in ElementModel::ALL {
                let scene = FallScene {
                    subject: model.into(),
                    resolution: res,
                    ..FallScene::default()
                };
                let sim = scene.sim().expect("scene builds");
                let elements = sim.mesh().num_cells() as u64;
                let mut world = sim.world;
                // Let it land first so contacts are part of the step.
                for _ in 0..700 {
                    world.step();
                }
                group.throughput(Throughput::Elements(elements));
                group.bench_with_input(BenchmarkId::new(model.name(), res), &res, |b, _| {
                    b.iter(|| world.step().wall_time)
                });
            }
        }
        group.finish();
    }};
}

fn steps(c: &mut Criterion) {
    bench_dimension!(c, dim3, "3d", [5usize, 9]);
    bench_dimension!(c, dim2, "2d", [5usize, 17]);
}

criterion_group!(benches, steps);
criterion_main!(benches);
