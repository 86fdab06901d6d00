//! A robot from its URDF file: the two-finger gripper of `assets/gripper/gripper.urdf` is
//! loaded into the rapier world by `rapier3d-urdf`, each of its `*_pad` links is meshed from its
//! collision box by isosurface stuffing into a soft pad bound to the finger carrying it, and the
//! gripper closes on a 10 cm box on the table, lifts it 0.2 m and holds it
//! (`sinew_scenes::dim3::gripper` builds and drives it).
//!
//! ```text
//! cargo run --release --example gripper [-- --mass 0.2 --dt 0.0166667 --cell 0.015
//!     --model er|sm --integrator auto|explicit|implicit]
//! cargo run --release --features rerun --example gripper [-- --rrd DIR | --connect [ADDR]]
//! ```
//!
//! It prints the pads, where the box ends, its slip against the fingers while lifted and held,
//! and the cost of a step; it exits with an error if the box was not held.

#[path = "common/sink.rs"]
mod sink;

use sinew::dim3::math::Real;
use sinew::dim3::model::ElementModel;
use sinew::dim3::Integrator;
use sinew_scenes::dim3::gripper::GripperScene;

fn main() {
    let defaults = GripperScene::default();
    let scene = GripperScene {
        mass: sink::arg("--mass", defaults.mass),
        dt: sink::arg("--dt", defaults.dt),
        cell: sink::arg("--cell", defaults.cell),
        model: match sink::arg::<String>("--model", "er".into()).as_str() {
            "sm" => ElementModel::SHAPE_MATCHING,
            _ => ElementModel::EdgeRepulsion,
        },
        integrator: match sink::arg::<String>("--integrator", "auto".into()).as_str() {
            "explicit" => Integrator::Explicit,
            "implicit" => Integrator::Implicit { iterations: 2 },
            _ => defaults.integrator,
        },
        ..defaults
    };

    let sink = sink::from_args("gripper");
    #[cfg(feature = "rerun")]
    let mut recorder = {
        let options = sinew::dim3::RecorderOptions {
            every_n_steps: 1,
            attachments: true,
            ..Default::default()
        };
        sink::recorder_3d(&sink, "sinew-gripper", "gripper.rrd", options)
    };
    #[cfg(not(feature = "rerun"))]
    let _ = &sink;

    let record = scene
        .run_with(|_world, _| {
            #[cfg(feature = "rerun")]
            if let Some(r) = recorder.as_mut() {
                if let Err(e) = r.log_world(_world) {
                    eprintln!("logging failed: {e}");
                }
            }
        })
        .unwrap_or_else(|e| panic!("{e}"));
    #[cfg(feature = "rerun")]
    if let Some(r) = recorder.as_mut() {
        if let Err(e) = r.flush() {
            eprintln!("logging failed: {e}");
        }
    }

    for (side, pad) in ["left", "right"].iter().zip(&record.pads) {
        println!(
            "{side} pad: {} nodes, {} cells, {} bound to the finger",
            pad.nodes, pad.cells, pad.bound
        );
    }
    let mut sorted = record.step_seconds.clone();
    sorted.sort_by(f64::total_cmp);
    let n = sorted.len();
    let ms = |s: f64| s * 1e3;
    println!(
        "{} kg box: its bottom ends {:.1} mm up (lifted {:.0} mm); slip against the fingers {:.1} mm; lowest {:.1} mm; a step {:.1} ms on average, {:.1} median, {:.1} at most",
        scene.mass,
        record.lifted * 1e3,
        scene.lift * 1e3,
        record.slip * 1e3,
        record.lowest * 1e3,
        ms(sorted.iter().sum::<f64>() / n as f64),
        ms(sorted[n / 2]),
        ms(sorted[n - 1]),
    );
    let held: Real = 0.01;
    if (record.lifted - scene.lift).abs() > held {
        eprintln!("the box was not held");
        std::process::exit(1);
    }
}
