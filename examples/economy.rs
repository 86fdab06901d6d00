//! "Model no more than a scene needs": what each economy of the pipeline saves, measured on
//! the `fall` cube (3D, edge-repulsion unless `--model` says otherwise; one core).
//!
//! ```text
//! cargo run --release --example economy [-- --res 9 --seconds 8 --model edge-repulsion]
//! ```
//!
//! - **Sleep**: the same run with and without sleeping; wall time of each.
//! - **Adaptive substeps**: the substeps the stability bound chose (mean, largest), against the
//!   same run with a fixed count equal to the largest (what a fixed count safe for the impact
//!   costs at rest too); wall time of each.
//! - **Surface-only contact**: the nodes tested against colliders (the boundary nodes) against
//!   all nodes, and the share of the step spent on contacts.

use std::time::Instant;

use clap::Parser;
use sinew::dim3::math::Real;
use sinew::dim3::RotationFit;
use sinew_scenes::dim3::{CrushScene, FallScene, Subject};

#[derive(Parser, Debug)]
struct Args {
    /// Nodes per edge of the cube.
    #[arg(long, default_value_t = 9)]
    res: usize,
    /// Simulated seconds (the cube lands at 0.64 s and rests from about 2 s).
    #[arg(long, default_value_t = 8.0)]
    seconds: Real,
    /// sinew model name.
    #[arg(long, default_value = "edge-repulsion")]
    model: String,
}

/// Per-run figures.
struct Run {
    wall: f64,
    substeps: Vec<usize>,
    slept_steps: usize,
    contact_time: f64,
    step_time: f64,
    surface: usize,
    nodes: usize,
}

fn run(scene: &FallScene, can_sleep: bool) -> Run {
    let mut sim = scene.sim().expect("the fall scene builds");
    let h = sim.handle().expect("a sinew subject");
    sim.world.deformables[h].set_can_sleep(can_sleep);
    let steps = (scene.seconds / scene.dt).round() as usize;
    let (nodes, surface) = {
        let d = &sim.world.deformables[h];
        (d.num_nodes(), d.mesh().boundary_nodes().len())
    };
    let mut out = Run {
        wall: 0.0,
        substeps: Vec::with_capacity(steps),
        slept_steps: 0,
        contact_time: 0.0,
        step_time: 0.0,
        surface,
        nodes,
    };
    let start = Instant::now();
    for _ in 0..steps {
        let report = sim.world.step();
        let r = report.get(h).expect("stepped");
        out.substeps.push(r.substeps);
        out.slept_steps += r.sleeping as usize;
        out.contact_time += r.time_contacts;
        out.step_time += r.time_forces + r.time_contacts + r.time_integrate;
    }
    out.wall = start.elapsed().as_secs_f64();
    out
}

fn main() {
    let args = Args::parse();
    let Some(subject) = Subject::parse(&args.model, RotationFit::Iterative(2)) else {
        eprintln!("unknown model {}", args.model);
        std::process::exit(2);
    };
    let scene = FallScene {
        subject,
        resolution: args.res,
        seconds: args.seconds,
        ..FallScene::default()
    };
    println!(
        "fall, 3D, {}, res {}, dt {} ms, {} s simulated\n",
        args.model,
        args.res,
        scene.dt * 1e3,
        args.seconds
    );
    let awake = run(&scene, false);
    let asleep = run(&scene, true);
    let max = *awake.substeps.iter().max().unwrap_or(&1);
    let mean = awake.substeps.iter().sum::<usize>() as f64 / awake.substeps.len() as f64;
    let fixed = run(
        &FallScene {
            fixed_substeps: Some(max),
            ..scene
        },
        false,
    );
    // The barrier stiffens under load: the 1000 kg crush needs many more substeps under the
    // press than at rest.
    let crush = CrushScene {
        cube: FallScene {
            resolution: args.res.min(5),
            ..scene
        },
        ..CrushScene::default()
    };
    let crush_auto = crush.run().expect("the crush scene builds");
    let crush_fixed = CrushScene {
        cube: FallScene {
            fixed_substeps: Some(crush_auto.max_substeps),
            ..crush.cube
        },
        ..crush
    }
    .run()
    .expect("the crush scene builds");
    println!("| economy | with | without | saves |\n|---|---|---|---|");
    println!(
        "| sleep (asleep {} of {} steps) | {:.2} s | {:.2} s | {:.0} % |",
        asleep.slept_steps,
        asleep.substeps.len(),
        asleep.wall,
        awake.wall,
        100.0 * (1.0 - asleep.wall / awake.wall)
    );
    println!(
        "| adaptive substeps (mean {:.1}, largest {}) vs {} fixed | {:.2} s | {:.2} s | {:.0} % |",
        mean,
        max,
        max,
        awake.wall,
        fixed.wall,
        100.0 * (1.0 - awake.wall / fixed.wall)
    );
    println!(
        "| adaptive substeps, crush 1000 kg res {} (mean {:.1}, largest {}) vs {} fixed | {:.2} s | {:.2} s | {:.0} % |",
        crush.cube.resolution,
        crush_auto.substeps,
        crush_auto.max_substeps,
        crush_auto.max_substeps,
        crush_auto.wall_s,
        crush_fixed.wall_s,
        100.0 * (1.0 - crush_auto.wall_s / crush_fixed.wall_s)
    );
    println!(
        "| contact on surface nodes only ({} of {} nodes; contacts {:.0} % of the step) | {} nodes | {} nodes | {:.0} % of node tests |",
        awake.surface,
        awake.nodes,
        100.0 * awake.contact_time / awake.step_time.max(1e-12),
        awake.surface,
        awake.nodes,
        100.0 * (1.0 - awake.surface as f64 / awake.nodes as f64)
    );
}
