//! A soft cube (3D) and a soft square (2D) dropped from 2 m onto a fixed ground, one run per
//! element model, one line per run.
//!
//! ```text
//! cargo run --release --example fall_and_bounce [-- --res 5 --seconds 5 --dt 0.001]
//! cargo run --release --example fall_and_bounce -- --advise --dt 0.0166667
//! cargo run --release --features rerun --example fall_and_bounce [-- --rrd DIR | --connect [ADDR]] [--log-every N] [--no-wireframe]
//! ```
//!
//! `--advise` runs only the model and integrator that `sinew_scenes::dim3::advise` picks for
//! this very fall (the cheapest within 5 % of the cube's size of the common fall reference in
//! 3D; 2D has no reference and is judged on stability alone), after printing every candidate.
//!
//! With the `rerun` feature every run is logged (every 10th step, or every `--log-every`-th) to
//! `out/fall_and_bounce/<dim>-<model>.rrd`, or to `--rrd DIR`, or streamed to a viewer with
//! `--connect`, and the logging cost per frame is printed beside the step's.

#[path = "common/sink.rs"]
mod sink;

macro_rules! run_dimension {
    ($dim:ident, $label:expr, $sink:expr, $files:expr) => {{
        use sinew_scenes::$dim::FallScene;
        use sinew::$dim::ElementModel;
        let base = FallScene {
            resolution: sink::arg("--res", 5),
            seconds: sink::arg("--seconds", 5.0),
            dt: sink::arg("--dt", 1e-3),
            ..FallScene::default()
        };
        // Every model explicitly, or with `--advise` only the cheapest model and integrator
        // that stays inside the trial's bounds on this very scene.
        let picks: Vec<(ElementModel, sinew::$dim::Integrator)> = if sink::flag("--advise") {
            use sinew_scenes::$dim::advise::{advise, candidates, Trial};
            let reference = sinew_scenes::$dim::FallReference::load(std::path::Path::new(
                sinew_scenes::$dim::FALL_REFERENCE_PATH,
            ));
            if let Err(e) = &reference {
                // The common reference is 3D: a 2D pick is judged on stability alone.
                println!("{:<3} advise: no fall reference ({e}): judged on stability alone", $label);
            }
            let trial = Trial::Fall {
                scene: base,
                reference: reference.ok(),
            };
            match advise(&trial, trial.default_bounds(), &candidates(), |_| {}) {
                Ok(advice) => {
                    for c in &advice.candidates {
                        println!(
                            "{:<3} advise: {:<32} wall/sim {:.4} s  error {}  {}",
                            $label,
                            c.label(),
                            c.cost(),
                            c.error.map_or("—".to_string(), |e| format!("{e:.2e}")),
                            c.rejected.as_deref().unwrap_or("passes")
                        );
                    }
                    match advice.choice() {
                        Some(c) => {
                            println!("{:<3} advise: cheapest that passes: {}", $label, c.label());
                            vec![(c.model, c.integrator)]
                        }
                        None => {
                            println!("{:<3} advise: no model passes; running edge-repulsion", $label);
                            vec![(ElementModel::EdgeRepulsion, sinew::$dim::Integrator::Explicit)]
                        }
                    }
                }
                Err(e) => {
                    println!("{:<3} advise failed: {e}", $label);
                    Vec::new()
                }
            }
        } else {
            ElementModel::ALL
                .into_iter()
                .map(|m| (m, sinew::$dim::Integrator::Explicit))
                .collect()
        };
        for (model, integrator) in picks {
            let scene = FallScene { subject: model.into(), integrator, ..base };
            #[cfg(feature = "rerun")]
            let mut recorder = {
                use sinew::$dim::{RecorderOptions, RerunRecorder};
                let options = RecorderOptions {
                    every_n_steps: sink::arg("--log-every", 10),
                    wireframe: !std::env::args().any(|a| a == "--no-wireframe"),
                    ..Default::default()
                };
                let made = match $sink {
                    sink::Sink::Folder(dir) => {
                        let file = dir.join(format!("{}-{}.rrd", $label.to_lowercase(), model.name()));
                        $files.push(file.clone());
                        RerunRecorder::save("sinew-fall-and-bounce", &file, options).map(Some)
                    }
                    sink::Sink::Connect(addr) => RerunRecorder::connect("sinew-fall-and-bounce", addr.as_deref(), options).map(Some),
                    sink::Sink::Off => Ok(None),
                };
                made.unwrap_or_else(|e| {
                    eprintln!("not logging: {e}");
                    None
                })
            };
            let outcome = scene.run_with(|_world, _done| {
                #[cfg(feature = "rerun")]
                if let Some(r) = recorder.as_mut() {
                    for (h, _) in _world.deformables.iter() {
                        r.set_name(h, "jelly");
                    }
                    if let Err(e) = r.log_world(_world) {
                        eprintln!("logging failed: {e}");
                    }
                }
            });
            #[cfg(feature = "rerun")]
            if let Some(r) = recorder.as_mut() {
                if let Err(e) = r.flush() {
                    eprintln!("logging failed: {e}");
                }
            }
            #[cfg(feature = "rerun")]
            let logging = recorder.as_ref().map(|r| (r.seconds_per_frame(), r.frames()));
            #[cfg(not(feature = "rerun"))]
            let logging: Option<(f64, u64)> = None;
            match outcome {
                Ok(o) => {
                    println!(
                    "{:<3} {:<18} nodes {:>5}  apex {:>6}  rest {:.3} m  max pen {:.2e} m  inverted max {:>3} end {:>3}  substeps {:>5.1}  wall/sim {:.3} s{}",
                    $label,
                    model.name(),
                    o.nodes,
                    o.bounce_apex_com.map_or("none".to_string(), |a| format!("{a:.3}")),
                    o.rest_com.unwrap_or(f64::NAN),
                    o.max_penetration.unwrap_or(f64::NAN),
                    o.max_inverted_elements,
                    o.final_inverted_elements,
                    o.substeps,
                    o.wall_per_sim_s(),
                    if o.nan || o.exploded { "  BLEW UP" } else { "" }
                    );
                    if let Some((seconds, frames)) = logging {
                        println!(
                            "    logging: {:.3} ms per frame ({frames} frames) against {:.3} ms per step",
                            seconds * 1e3,
                            o.wall_per_sim_s() * base.dt as f64 * 1e3
                        );
                    }
                }
                Err(e) => println!("{:<3} {:<18} failed to build: {e}", $label, model.name()),
            }
        }
    }};
}

fn main() {
    let sink = sink::from_args("fall_and_bounce");
    #[allow(unused_mut)]
    let mut files: Vec<std::path::PathBuf> = Vec::new();
    println!("fall and bounce: 1 m, 1 kg, E = 1e4 Pa, damping ratio 0.1, bottom dropped from 2 m, 5 s (centre-of-mass heights in m)");
    run_dimension!(dim3, "3D", &sink, files);
    run_dimension!(dim2, "2D", &sink, files);
    if cfg!(feature = "rerun") {
        sink::print_how_to_view(&sink, &files);
    } else {
        sink::print_no_feature("fall_and_bounce", "3d-edge-repulsion.rrd");
    }
}
