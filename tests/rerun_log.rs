//! Writes `.rrd` files of a short fall and bounce (2D and 3D) and reads them back with the real
//! Python client (`rerun-sdk==0.36.3`): `tests/rerun/check_rrd.py` checks the entity paths, that
//! the surface vertices at each logged step equal the simulated node positions, that the
//! inverted-elements series has one value per logged frame, and `rerun rrd verify` the file;
//! `tests/rerun/check_blueprint.py` that the layout sent with it shows the deformables in a
//! world view framed on them and every `stats/` series in some plot.
//!
//! Needs a Python with `rerun-sdk==0.36.3`: `SINEW_PYTHON=/path/to/python` (`.ci/run` makes a
//! venv under `target/rerun-venv`); the `rerun` CLI is taken from the same `bin/` folder.
#![cfg(feature = "rerun")]

use std::path::PathBuf;
use std::process::Command;

fn python() -> PathBuf {
    PathBuf::from(
        std::env::var("SINEW_PYTHON")
            .unwrap_or_else(|_| "target/rerun-venv/bin/python".to_string()),
    )
}

fn check(dim: &str, rrd: &PathBuf, expected: &PathBuf) {
    run_check("tests/rerun/check_rrd.py", dim, rrd, expected);
}

/// Runs one of the Python checks on a recording and the JSON of what it must hold.
fn run_check(script: &str, dim: &str, rrd: &PathBuf, expected: &PathBuf) {
    let py = python();
    let out = Command::new(&py)
        .arg(script)
        .arg(rrd)
        .arg(expected)
        .output()
        .unwrap_or_else(|e| panic!("cannot run {} ({e}); set SINEW_PYTHON to a Python with rerun-sdk==0.36.3 (see .ci/run)", py.display()));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "{dim}: the Python check failed:\n{stdout}\n{stderr}"
    );
    assert!(stdout.contains("checked"), "{dim}: {stdout}");
}

fn json_vec(v: &[f32]) -> String {
    format!(
        "[{}]",
        v.iter()
            .map(|x| format!("{x:e}"))
            .collect::<Vec<_>>()
            .join(",")
    )
}

macro_rules! fall_to_rrd {
    ($name:ident, $dim:ident, $label:expr, $component:expr) => {
        #[test]
        fn $name() {
            use sinew_scenes::$dim::FallScene;
            use sinew::$dim::{ElementModel, RecorderOptions, RerunRecorder};
            let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("rerun");
            let rrd = dir.join(format!("fall-{}.rrd", $label));
            let expected = dir.join(format!("fall-{}.json", $label));
            let _ = std::fs::remove_file(&rrd);
            let scene = FallScene { subject: ElementModel::EdgeRepulsion.into(), resolution: 3, seconds: 0.9, ..FallScene::default() };
            let sim = scene.sim().unwrap();
            let h = sim.handle().unwrap();
            let mut world = sim.world;
            let (lo, hi) = bounds(world.deformables[h].positions().iter().map(|x| x.to_array().to_vec()));
            let ground = world.physics.colliders.iter().map(|(_, c)| {
                let b = c.compute_aabb();
                (b.maxs - b.mins).max_element()
            }).fold(0.0f32, f32::max);
            let options = RecorderOptions { every_n_steps: 50, nodes: true, contacts: true, ..Default::default() };
            let mut recorder = RerunRecorder::save("sinew-test", &rrd, options).unwrap();
            recorder.set_name(h, "jelly");
            let steps = (scene.seconds / scene.dt).round() as usize;
            let mut frames = Vec::new();
            for _ in 0..steps {
                world.step();
                if recorder.log_world(&world).unwrap() {
                    let d = &world.deformables[h];
                    let x = d.positions();
                    // What the surface entity must hold, computed from the nodes directly.
                    let surface: Vec<f32> = if $component == "Mesh3D:vertex_positions" {
                        d.mesh().boundary_nodes().iter().flat_map(|&i| x[i as usize].to_array()).collect()
                    } else {
                        d.mesh().boundary_facets().iter().flat_map(|f| f.iter().flat_map(|&i| x[i as usize].to_array())).collect()
                    };
                    frames.push(format!("{{\"step\":{},\"surface\":{}}}", world.steps(), json_vec(&surface)));
                }
            }
            recorder.flush().unwrap();
            drop(recorder);
            assert_eq!(frames.len(), steps.div_ceil(50));
            let json = format!(
                "{{\"component\":\"{}\",\"surface\":\"/world/deformables/jelly/surface\",\"nodes\":\"/world/deformables/jelly/nodes\",\"inverted\":\"/stats/jelly/inverted_elements\",\"colliders\":\"/world/colliders/\",\"frames\":[{}]}}",
                $component,
                frames.join(",")
            );
            std::fs::write(&expected, json).unwrap();
            check($label, &rrd, &expected);
            let layout = dir.join(format!("fall-{}-layout.json", $label));
            let class = if $component == "Mesh3D:vertex_positions" { "3D" } else { "2D" };
            std::fs::write(&layout, format!(
                "{{\"class\":\"{class}\",\"bodies\":[\"jelly\"],\"box\":[{},{}],\"ground\":{ground}}}",
                json_vec(&lo), json_vec(&hi)
            )).unwrap();
            run_check("tests/rerun/check_blueprint.py", $label, &rrd, &layout);
        }
    };
}

/// The per-axis box of some points.
fn bounds(points: impl Iterator<Item = Vec<f32>>) -> (Vec<f32>, Vec<f32>) {
    let mut lo: Vec<f32> = Vec::new();
    let mut hi: Vec<f32> = Vec::new();
    for p in points {
        if lo.is_empty() {
            lo = p.clone();
            hi = p;
            continue;
        }
        for (a, v) in p.into_iter().enumerate() {
            lo[a] = lo[a].min(v);
            hi[a] = hi[a].max(v);
        }
    }
    (lo, hi)
}

/// Several bodies: one plot per metric, a series per body, every series shown, the view framed
/// on the bodies and the ground right under them, not on the whole ground.
#[test]
fn several_bodies_get_a_plot_per_metric() {
    use sinew::dim3::math::Vector;
    use sinew::dim3::rapier::prelude::{ColliderBuilder, RigidBodyBuilder};
    use sinew::dim3::{DeformableBuilder, DeformableWorld, RecorderOptions, RerunRecorder};
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("rerun");
    let rrd = dir.join("several.rrd");
    let _ = std::fs::remove_file(&rrd);
    let mut world = DeformableWorld::new();
    world.physics.insert(
        RigidBodyBuilder::fixed().translation(Vector::new(0.0, -0.1, 0.0)),
        ColliderBuilder::cuboid(20.0, 0.1, 20.0),
    );
    let names = ["left", "right", "top"];
    let mut recorder = RerunRecorder::save("sinew-test", &rrd, RecorderOptions::default()).unwrap();
    let mut all = Vec::new();
    for (k, name) in names.iter().enumerate() {
        let body = DeformableBuilder::cuboid(Vector::splat(0.25), [3, 3, 3])
            .translation(Vector::new(k as f32 - 1.0, 1.0 + 0.5 * k as f32, 0.0))
            .build()
            .unwrap();
        all.extend(body.positions().iter().map(|x| x.to_array().to_vec()));
        let h = world.insert(body);
        recorder.set_name(h, name);
    }
    let (lo, hi) = bounds(all.into_iter());
    for _ in 0..20 {
        world.step();
        recorder.log_world(&world).unwrap();
    }
    recorder.flush().unwrap();
    drop(recorder);
    let layout = dir.join("several-layout.json");
    std::fs::write(
        &layout,
        format!(
            "{{\"class\":\"3D\",\"bodies\":[\"left\",\"right\",\"top\"],\"box\":[{},{}],\"ground\":40}}",
            json_vec(&lo),
            json_vec(&hi)
        ),
    )
    .unwrap();
    run_check("tests/rerun/check_blueprint.py", "several", &rrd, &layout);
}

fall_to_rrd!(
    fall_and_bounce_3d_reads_back,
    dim3,
    "3d",
    "Mesh3D:vertex_positions"
);
fall_to_rrd!(
    fall_and_bounce_2d_reads_back,
    dim2,
    "2d",
    "LineStrips2D:strips"
);

/// A body with gas: each chamber's gauge pressure and volume are `stats/` series holding the
/// values `Deformable::chambers` gave at each logged step (the cube's pressure changes as it
/// lands), and the layout shows them.
#[test]
fn a_gas_body_logs_its_chambers_pressure_and_volume() {
    use sinew::dim3::math::Vector;
    use sinew::dim3::rapier::prelude::{ColliderBuilder, RigidBodyBuilder};
    use sinew::dim3::{DeformableBuilder, DeformableWorld, Gas, RecorderOptions, RerunRecorder};
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("rerun");
    let rrd = dir.join("gas.rrd");
    let _ = std::fs::remove_file(&rrd);
    let mut world = DeformableWorld::new();
    world.set_dt(1.0 / 60.0);
    world.physics.insert(
        RigidBodyBuilder::fixed().translation(Vector::new(0.0, -0.1, 0.0)),
        ColliderBuilder::cuboid(2.0, 0.1, 2.0),
    );
    let body = DeformableBuilder::cuboid(Vector::splat(0.1), [4, 4, 4])
        .translation(Vector::new(0.0, 0.15, 0.0))
        .gas(Gas::gauge(2e4))
        .build()
        .unwrap();
    let h = world.insert(body);
    let mut recorder = RerunRecorder::save("sinew-test", &rrd, RecorderOptions::default()).unwrap();
    recorder.set_name(h, "ball");
    let (mut pressure, mut volume) = (Vec::new(), Vec::new());
    for _ in 0..40 {
        world.step();
        recorder.log_world(&world).unwrap();
        let step = world.steps();
        let chambers = world.deformables[h].chambers();
        assert_eq!(chambers.len(), 1);
        pressure.push(format!("[{step},{:e}]", chambers[0].pressure));
        volume.push(format!("[{step},{:e}]", chambers[0].volume));
    }
    recorder.flush().unwrap();
    drop(recorder);
    let expected = dir.join("gas-series.json");
    std::fs::write(
        &expected,
        format!(
            "{{\"series\":{{\"/stats/ball/gas_pressure/0\":[{}],\"/stats/ball/gas_volume/0\":[{}]}}}}",
            pressure.join(","),
            volume.join(",")
        ),
    )
    .unwrap();
    run_check("tests/rerun/check_series.py", "gas", &rrd, &expected);
    let lo = [-0.1, 0.05, -0.1];
    let hi = [0.1, 0.25, 0.1];
    let layout = dir.join("gas-layout.json");
    std::fs::write(
        &layout,
        format!(
            "{{\"class\":\"3D\",\"bodies\":[\"ball\"],\"box\":[{},{}],\"ground\":4}}",
            json_vec(&lo),
            json_vec(&hi)
        ),
    )
    .unwrap();
    run_check("tests/rerun/check_blueprint.py", "gas", &rrd, &layout);
}

/// A body that blows up is frozen, and the log says so: a warning text entry at
/// `events/<name>` naming the cause, and the `frozen` series.
#[test]
fn a_frozen_body_is_logged_as_a_warning() {
    use sinew::dim3::math::{Vector, DIM};
    use sinew::dim3::{
        DeformableBuilder, DeformableWorld, Integrator, RecorderOptions, RerunRecorder, Stiffness,
    };
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("rerun");
    let rrd = dir.join("frozen.rrd");
    let _ = std::fs::remove_file(&rrd);
    let mut world = DeformableWorld::new();
    // The explicit step forced to one substep explodes (the implicit one would not).
    world.pipeline.settings.integrator = Integrator::Explicit;
    world.pipeline.settings.fixed_substeps = Some(1);
    let h = world.insert(
        DeformableBuilder::cuboid(Vector::splat(0.25), [3; DIM])
            .stiffness(Stiffness::Raw { k: 1e9, c: 0.0 })
            .build()
            .unwrap(),
    );
    let mut kick = world.deformables[h].positions().to_vec();
    kick[0] += Vector::splat(0.05);
    world.deformables[h].set_positions(&kick).unwrap();
    let mut recorder = RerunRecorder::save("sinew-test", &rrd, RecorderOptions::default()).unwrap();
    recorder.set_name(h, "jelly");
    for _ in 0..60 {
        world.step();
        recorder.log_world(&world).unwrap();
    }
    assert!(world.deformables[h].is_frozen());
    recorder.flush().unwrap();
    drop(recorder);
    let py = python();
    let out = Command::new(&py)
        .args(["tests/rerun/check_events.py"])
        .arg(&rrd)
        .args(["/events/jelly", "frozen", "WARN"])
        .output()
        .unwrap_or_else(|e| panic!("cannot run {} ({e}); see .ci/run", py.display()));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "the Python check failed:\n{stdout}\n{stderr}"
    );
    assert!(stdout.contains("checked"), "{stdout}");
}
