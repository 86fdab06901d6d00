//! Soak: every scene of the scene runner stretched to 10⁵ steps, watching what a long run can
//! break (issue 7).
//!
//! ```text
//! cargo run --release --example soak [-- --steps 100000 --dim 3 --model edge-repulsion shape-matching]
//! ```
//!
//! Per run, from the step reports and node positions after every step:
//! - `E10%`, `Emax`, `Eend`: the deformable's total energy (kinetic + elastic + gravity, J) at
//!   10 % of the run, its largest after that, and at the end — bounded energy means `Emax`
//!   does not run away from `E10%` (driven scenes put energy in and take it out again);
//! - `drift mm`: how far the centre of mass moved over the second half of the run, for the
//!   scenes where the body ends at rest (fall, crush hold, cantilever);
//! - `pen mm`: the deepest node penetration reported; `inv`: most inverted cells at any step;
//! - `asleep`: the share of steps the body slept; `frozen`: whether it was frozen.
//!
//! The scenes, each set up for `--steps` steps: `fall` (dropped, then resting, 1 ms steps;
//! `fall (awake)` the same with sleep off),
//! `crush` (10 kg on the cube, the hold stretched), `manipulator` (strikes repeated),
//! `limb` (the bend slowed down), `rotation-error` (the spinning element), `cantilever`
//! (res 3, holding its sag).

use std::time::Instant;

use clap::Parser;

#[derive(Parser, Debug)]
struct Args {
    /// Steps per run.
    #[arg(long, default_value_t = 100_000)]
    steps: usize,
    /// Dimensions to run (2, 3).
    #[arg(long, num_args = 1.., default_values_t = [3, 2])]
    dim: Vec<usize>,
    /// sinew models.
    #[arg(long, num_args = 1.., default_values_t = ["springs".to_string(), "edge-repulsion".to_string(), "shape-matching".to_string()])]
    model: Vec<String>,
    /// Scenes (default: all).
    #[arg(long, num_args = 1..)]
    scene: Vec<String>,
}

/// What one run measured.
#[derive(Default)]
struct Soak {
    steps: usize,
    energy: Vec<f64>,
    com_half: Option<[f64; 3]>,
    com_end: [f64; 3],
    penetration: f64,
    inverted: usize,
    asleep: usize,
    frozen: bool,
}

impl Soak {
    fn row(&self, dim: usize, scene: &str, model: &str, resting: bool, wall: f64) -> String {
        let n = self.energy.len().max(1);
        let e10 = self.energy.get(n / 10).copied().unwrap_or(f64::NAN);
        let emax = self.energy[n / 10..]
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max);
        let eend = self.energy.last().copied().unwrap_or(f64::NAN);
        let drift = match (resting, self.com_half) {
            (true, Some(h)) => {
                let d: f64 = (0..3).map(|k| (self.com_end[k] - h[k]).powi(2)).sum();
                format!("{:9.3}", d.sqrt() * 1e3)
            }
            _ => format!("{:>9}", "—"),
        };
        format!(
            "{dim}D  {scene:<15} {model:<18} {:>7} {e10:>10.4} {emax:>10.4} {eend:>10.4} {drift} {:>8.2} {:>4} {:>6.1}% {:>6} {wall:>7.1}",
            self.steps,
            self.penetration * 1e3,
            self.inverted,
            100.0 * self.asleep as f64 / self.steps.max(1) as f64,
            if self.frozen { "yes" } else { "no" },
        )
    }
}

macro_rules! soak_dim {
    ($dim:ident, $n:expr, $args:expr) => {{
        use sinew::$dim::math::Real;
        use sinew::$dim::{DeformableWorld, RotationFit};
        use sinew_scenes::$dim::{
            CantileverScene, CrushScene, FallScene, LimbScene, ManipulatorScene,
            RotationErrorScene, Subject,
        };

        fn observe(out: &mut Soak, world: &DeformableWorld, fraction: f64) {
            let Some((_, r)) = world.report().deformables.first() else {
                return;
            };
            let Some((_, d)) = world.deformables.iter().next() else {
                return;
            };
            out.steps += 1;
            out.energy
                .push((r.kinetic_energy + r.elastic_energy + r.gravity_energy) as f64);
            out.penetration = out.penetration.max(r.max_penetration as f64);
            out.inverted = out.inverted.max(r.inverted_elements);
            out.asleep += r.sleeping as usize;
            out.frozen |= r.frozen;
            let c = d.center_of_mass();
            let mut com = [0.0; 3];
            for k in 0..$n {
                com[k] = c[k] as f64;
            }
            if fraction >= 0.5 && out.com_half.is_none() {
                out.com_half = Some(com);
            }
            out.com_end = com;
        }

        let steps = $args.steps as Real;
        let wanted = |s: &str| $args.scene.is_empty() || $args.scene.iter().any(|x| x == s);
        for name in &$args.model {
            let Some(subject) = Subject::parse(name, RotationFit::Iterative(2)) else {
                eprintln!("unknown model {name}");
                std::process::exit(2);
            };
            let run =
                |scene: &str,
                 resting: bool,
                 f: &mut dyn FnMut(&mut dyn FnMut(&DeformableWorld, f64))| {
                    if !wanted(scene) {
                        return;
                    }
                    let mut out = Soak::default();
                    let start = Instant::now();
                    f(&mut |w, fr| observe(&mut out, w, fr));
                    let wall = start.elapsed().as_secs_f64();
                    println!("{}", out.row($n, scene, name, resting, wall));
                };
            let fall = FallScene {
                subject,
                seconds: steps * FallScene::default().dt,
                ..FallScene::default()
            };
            run("fall", true, &mut |o| {
                fall.run_with(o).expect("builds");
            });
            // The same with sleep off: the resting body is simulated every step.
            run("fall (awake)", true, &mut |o| {
                let mut sim = fall.sim().expect("builds");
                let h = sim.handle().expect("a sinew body");
                sim.world.deformables[h].set_can_sleep(false);
                let n = $args.steps;
                for k in 0..n {
                    sim.world.step();
                    o(&sim.world, (k + 1) as f64 / n as f64);
                }
            });
            let cube = FallScene {
                subject,
                ..FallScene::default()
            };
            let crush = CrushScene {
                mass: 10.0,
                cube,
                ..CrushScene::default()
            };
            let others = crush.settle + crush.ramp + crush.lift + crush.recover;
            let crush = CrushScene {
                hold: (steps * crush.cube.dt - others).max(crush.hold),
                ..crush
            };
            run("crush", false, &mut |o| {
                crush.run_with(o).expect("builds");
            });
            let m = ManipulatorScene {
                cube,
                ..ManipulatorScene::default()
            };
            let strikes = ((steps * m.cube.dt - m.settle) / m.period).max(1.0) as usize;
            let m = ManipulatorScene { strikes, ..m };
            run("manipulator", false, &mut |o| {
                m.run_with(o).expect("builds");
            });
            let limb = LimbScene {
                subject,
                ..LimbScene::default()
            };
            let limb = LimbScene {
                degrees_per_second: limb.max_degrees / (steps * limb.dt),
                stop_at_first_inversion: false,
                ..limb
            };
            run("limb", false, &mut |o| {
                limb.run_with(o).expect("builds");
            });
            if matches!(
                subject,
                Subject::Sinew(sinew::$dim::ElementModel::ShapeMatching { .. })
            ) {
                let r = RotationErrorScene::default();
                let r = RotationErrorScene {
                    seconds: steps * r.dt(),
                    ..r
                };
                run("rotation-error", false, &mut |o| {
                    r.run_with(o).expect("builds");
                });
            }
            let c = CantileverScene {
                subject,
                resolution: 3,
                ..CantileverScene::default()
            };
            let c = CantileverScene {
                seconds: steps * c.dt,
                ..c
            };
            run("cantilever", true, &mut |o| {
                c.run_with(o).expect("builds");
            });
        }
    }};
}

fn main() {
    let args = Args::parse();
    println!(
        "dim scene           model                steps        E10%       Emax       Eend  drift mm   pen mm  inv asleep frozen  wall s"
    );
    for dim in &args.dim {
        match dim {
            3 => soak_dim!(dim3, 3, args),
            2 => soak_dim!(dim2, 2, args),
            _ => eprintln!("no dimension {dim}"),
        }
    }
}
