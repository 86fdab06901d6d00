//! Cooper & Maddock's limb (§5): two kinematic bones inside a slab of tissue bound to them
//! with `attach_nodes_inside`; the lower bone turns about the hinge at 10°/s up to 110°. One
//! run per model, 2D and 3D, printing the angle at which each model first inverts an element.
//!
//! ```text
//! cargo run --release --example limb [-- --spacing 0.1 --young 1e4]
//! cargo run --release --example limb -- --advise
//! cargo run --release --features rerun --example limb [-- --rrd DIR | --connect [ADDR]]
//! ```
//!
//! `--advise` runs only the model and integrator that `sinew_scenes::dim3::advise` picks for
//! this very limb (the cheapest that reaches 110° with no cell inverted), after printing every
//! candidate.
//!
//! With the `rerun` feature every run is logged at every step (attachments included) to
//! `out/limb/<dim>-<model>.rrd` and the logging cost per frame is printed beside the step cost.

#[path = "common/sink.rs"]
mod sink;

macro_rules! run_dimension {
    ($dim:ident, $label:expr, $sink:expr, $files:expr) => {{
        use sinew_scenes::$dim::LimbScene;
        use sinew::$dim::ElementModel;
        let base = LimbScene {
            spacing: sink::arg("--spacing", 0.1),
            young_modulus: sink::arg("--young", 1e4),
            ..LimbScene::default()
        };
        // Every model explicitly, or with `--advise` only the cheapest model and integrator
        // that stays inside the trial's bounds on this very scene.
        let picks: Vec<(ElementModel, sinew::$dim::Integrator)> = if sink::flag("--advise") {
            use sinew_scenes::$dim::advise::{advise, candidates, Trial};
            let trial = Trial::Limb(base);
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
            let scene = LimbScene { subject: model.into(), integrator, ..base };
            #[cfg(feature = "rerun")]
            let mut recorder = {
                use sinew::$dim::{RecorderOptions, RerunRecorder};
                let options = RecorderOptions { every_n_steps: 1, attachments: true, ..Default::default() };
                let made = match $sink {
                    sink::Sink::Folder(dir) => {
                        let file = dir.join(format!("{}-{}.rrd", $label.to_lowercase(), model.name()));
                        $files.push(file.clone());
                        RerunRecorder::save("sinew-limb", &file, options).map(Some)
                    }
                    sink::Sink::Connect(addr) => RerunRecorder::connect("sinew-limb", addr.as_deref(), options).map(Some),
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
                        r.set_name(h, "tissue");
                    }
                    if let Err(e) = r.log_world(_world) {
                        eprintln!("logging failed: {e}");
                    }
                }
            });
            match &outcome {
                Ok(o) => println!(
                    "{:<3} {:<18} nodes {:>5} cells {:>5}  first inversion {:>8}  max inverted {:>4}  min volume ratio {:+.3}  anchor error {:.1e} m  wall {:.2} s{}",
                    $label,
                    model.name(),
                    o.nodes,
                    o.elements,
                    o.first_failure.map_or("none".to_string(), |a| format!("{a:.1}°")),
                    o.max_inverted_elements,
                    o.min_vol_ratio,
                    o.max_anchor_error.unwrap_or(0.0),
                    o.wall_s,
                    if o.nan || o.exploded { "  BLEW UP" } else { "" }
                ),
                Err(e) => println!("{:<3} {:<18} failed to build: {e}", $label, model.name()),
            }
            #[cfg(feature = "rerun")]
            if let Some(r) = recorder.as_mut() {
                if let Err(e) = r.flush() {
                    eprintln!("logging failed: {e}");
                }
                if let Ok(o) = &outcome {
                    let steps = (scene.max_degrees / scene.degrees_per_second / scene.dt).round();
                    println!(
                        "    logging: {:.3} ms per frame ({} frames) against {:.3} ms per simulated step",
                        r.seconds_per_frame() * 1e3,
                        r.frames(),
                        o.wall_s * 1e3 / steps as f64
                    );
                }
            }
        }
    }};
}

fn main() {
    let sink = sink::from_args("limb");
    #[allow(unused_mut)]
    let mut files: Vec<std::path::PathBuf> = Vec::new();
    println!("limb: lower bone turned at 10°/s to 110°, tissue E = 1e4 Pa, 1000 kg/m³, no gravity");
    run_dimension!(dim2, "2D", &sink, files);
    run_dimension!(dim3, "3D", &sink, files);
    if cfg!(feature = "rerun") {
        sink::print_how_to_view(&sink, &files);
    } else {
        sink::print_no_feature("limb", "3d-edge-repulsion.rrd");
    }
}
