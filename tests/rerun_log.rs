//! Writes `.rrd` files of a short fall and bounce (2D and 3D) and reads them back with the real
//! Python client (`rerun-sdk==0.36.3`): `tests/rerun/check_rrd.py` checks the entity paths, that
//! the surface vertices at each logged step equal the simulated node positions, that the
//! inverted-elements series has one value per logged frame, and `rerun rrd verify` the file.
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
    let py = python();
    let out = Command::new(&py)
        .arg("tests/rerun/check_rrd.py")
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
            recorder.flush();
            drop(recorder);
            assert_eq!(frames.len(), steps.div_ceil(50));
            let json = format!(
                "{{\"component\":\"{}\",\"surface\":\"/world/deformables/jelly/surface\",\"nodes\":\"/world/deformables/jelly/nodes\",\"inverted\":\"/stats/jelly/inverted_elements\",\"colliders\":\"/world/colliders/\",\"frames\":[{}]}}",
                $component,
                frames.join(",")
            );
            std::fs::write(&expected, json).unwrap();
            check($label, &rrd, &expected);
        }
    };
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

/// A body that blows up is frozen, and the log says so: a warning text entry at
/// `events/<name>` naming the cause, and the `frozen` series.
#[test]
fn a_frozen_body_is_logged_as_a_warning() {
    use sinew::dim3::math::{Vector, DIM};
    use sinew::dim3::{
        DeformableBuilder, DeformableWorld, RecorderOptions, RerunRecorder, Stiffness,
    };
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("rerun");
    let rrd = dir.join("frozen.rrd");
    let _ = std::fs::remove_file(&rrd);
    let mut world = DeformableWorld::new();
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
    recorder.flush();
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
