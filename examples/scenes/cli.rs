//! The scene runner's command line: parses the arguments, runs the scenes for each dimension
//! and model, prints a table or JSON lines. `tests/scenes.rs` calls [`run`] directly, so the
//! test and the example go through the same code.

use std::ffi::OsString;
use std::io::Write;
use std::time::{Duration, Instant};

use clap::{Parser, ValueEnum};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde_json::{json, Value};
use sinew_scenes::record::Record;

/// The scenes.
#[derive(Copy, Clone, Debug, PartialEq, Eq, ValueEnum)]
pub enum Scene {
    /// A soft cube dropped on the ground.
    Fall,
    /// A 10 cm silicone ball (E = 1 MPa, 2 cm cells) dropped on the ground at 60 Hz.
    Ball,
    /// A bar stretched 2 %: Poisson's ratio measured (`--poisson` asks for one).
    Stretch,
    /// Cooper & Maddock's limb, bent to 110°.
    Limb,
    /// A heavy box crushing a soft cube, then lifted away.
    Crush,
    /// A kinematic paddle striking a soft cube again and again.
    Manipulator,
    /// The fall at dt = 0.5 … 16.7 ms, one substep per step, then each solver's own substeps.
    DtSweep,
    /// The shape-based element's spurious angular acceleration (shape paper, Table 1).
    RotationError,
    /// A clamped beam sagging under its own weight, against Euler–Bernoulli.
    Cantilever,
    /// A soft cube dropped on another on the ground.
    Stack,
    /// Soft cubes dropped into a trimesh bowl (`--bodies`, default 10).
    Pile,
    /// A tower of soft cubes (`--bodies`, default 6) built at rest, or dropped from `--gap`
    /// (m) above each other.
    Tower,
    /// A soft ball squeezed between two soft pads by a box (`--mass`, default 10 kg).
    Squeeze,
    /// Soft pads on two kinematic fingers pinch a dynamic box and lift it 0.2 m (`--mass`,
    /// default 0.2 kg; one run per mass).
    Pinch,
    /// A soft ball rolled down a trimesh ramp into a wall of dynamic boxes (`--mass`: each
    /// box, default 0.2 kg).
    Roll,
    /// A hollow rubber ball inflated by a gas (20 kPa), squeezed between two plates until its
    /// cavity holds 70 % of its volume, and let go (rapier's body: a volume target instead).
    Balloon,
    /// A slab pulled apart by two bones until it tears (tear strain 0.1), then let fall into
    /// its pieces (rapier's body: its `tear_strain`)
    Tear,
    /// A plastic bar bent a quarter turn by a bone and let go: the bend it keeps against an
    /// elastic–perfectly-plastic beam's (rapier's body: its `plastic_yield`)
    Bend,
    /// A 20 cm steel box dropped on a soft plastic plate, then taken away: the dent it leaves
    /// (rapier's body: its `plastic_yield`)
    Dent,
    /// A sausage folded double on a table, self contact on (`--self-contact off` to compare);
    /// `--seconds` is the fold and the hold together.
    Fold,
    /// A free bar ringing axially: its first frequency against beam theory, its decay against
    /// the damping ratio (`--res`: nodes across; `--damping`).
    Vibration,
    /// A clamped beam released straight under its weight, ringing: its first bending
    /// frequency against Euler–Bernoulli (`--res`: nodes across, default 3; `--seconds`,
    /// default 0.8).
    Bending,
    /// The cheapest sinew model and integrator inside the bounds, for each `--trial` (fall,
    /// limb, crush; default all three) at `--res` and `--dt` (default 1/60 s), crush under
    /// `--mass` (default 1000 kg); `--max-error`, `--min-volume` set the bounds.
    Advise,
}

/// The trials of `scenes advise`.
#[derive(Copy, Clone, Debug, PartialEq, Eq, ValueEnum)]
pub enum TrialArg {
    /// The fall cube against the common fall reference.
    Fall,
    /// The limb bent to 110°.
    Limb,
    /// The cube crushed by `--mass` and released.
    Crush,
}

/// sinew's integrators.
#[derive(Copy, Clone, Debug, PartialEq, Eq, ValueEnum)]
pub enum IntegratorArg {
    /// Symplectic Euler under the stability bound (default).
    Explicit,
    /// Backward Euler by Vertex Block Descent (`--sweeps`).
    Implicit,
    /// Implicit midpoint by Vertex Block Descent (`--sweeps`): keeps a free body's energy and
    /// angular momentum; backward Euler in steps with contacts or bones.
    Midpoint,
    /// Per body: explicit where it takes few substeps, midpoint (`--sweeps`) otherwise.
    Auto,
}

/// On or off.
#[derive(Copy, Clone, Debug, PartialEq, Eq, ValueEnum)]
pub enum Switch {
    /// On.
    On,
    /// Off.
    Off,
}

/// Runs the paper's scenes with sinew's models and rapier's soft bodies.
#[derive(Debug, Parser)]
#[command(name = "scenes", about, long_about = None)]
pub struct Args {
    /// The scene.
    #[arg(value_enum)]
    pub scene: Scene,
    /// Dimensions to run (default: 3 then 2).
    #[arg(long, num_args = 1.., value_parser = clap::value_parser!(u8).range(2..=3))]
    pub dim: Vec<u8>,
    /// Models (default: all): springs, centroid-springs, nonlinear-springs, edge-repulsion,
    /// shape-matching, rapier-volume, rapier-corotational, rapier-neo-hookean (and
    /// rapier-fem-* with `--features sinew-scenes/fem`); `sinew` or `rapier` for each family.
    #[arg(long, num_args = 1..)]
    pub model: Vec<String>,
    /// Rotation fits of shape-matching: 1, 2, 3 or polar (default: 2).
    #[arg(long, num_args = 1..)]
    pub iterations: Vec<String>,
    /// Nodes per edge of the cube (limb: nodes along the limb; cantilever: nodes across the
    /// beam's thickness).
    #[arg(long)]
    pub res: Option<usize>,
    /// Step length, s.
    #[arg(long)]
    pub dt: Option<f64>,
    /// Simulated time, s (crush, manipulator: the whole timeline is scaled to it).
    #[arg(long)]
    pub seconds: Option<f64>,
    /// Young's modulus, Pa.
    #[arg(long)]
    pub young: Option<f64>,
    /// Poisson's ratio.
    #[arg(long)]
    pub poisson: Option<f64>,
    /// Crushing masses, kg (default: 1 10 100 1000).
    #[arg(long, num_args = 1..)]
    pub mass: Vec<f64>,
    /// Strikes of the manipulator (default 20).
    #[arg(long)]
    pub strikes: Option<usize>,
    /// sinew's integrator (every scene but rotation-error, squeeze, fold and advise; default:
    /// explicit, but for ball sinew's own default, auto with 2 sweeps).
    #[arg(long, value_enum)]
    pub integrator: Option<IntegratorArg>,
    /// Gauss–Seidel sweeps per step of the implicit integrator (default 10). (`--iterations`
    /// is the shape-based element's rotation fit.)
    #[arg(long)]
    pub sweeps: Option<usize>,
    /// Conjugate-gradient iterations of the implicit steps' Newton step over each whole body,
    /// before the sweeps (`PipelineSettings::global_iterations`; fall, cantilever, bending and roll;
    /// default: automatic, 0: none).
    #[arg(long)]
    pub global: Option<usize>,
    /// Bodies of the pile, one run per count (default: 10).
    #[arg(long, num_args = 1..)]
    pub bodies: Vec<usize>,
    /// Self contact of sinew's bodies in the fold (default on) and the limb (default off).
    #[arg(long, value_enum)]
    pub self_contact: Option<Switch>,
    /// k/m of the rotation-error element, 1/s² (default: 1e4 1e5 1e6).
    #[arg(long, num_args = 1..)]
    pub k_over_m: Vec<f64>,
    /// Log every run to a Rerun file in this folder (needs `--features rerun`).
    #[arg(long)]
    pub rrd: Option<std::path::PathBuf>,
    /// One JSON object per line per run instead of a table.
    #[arg(long)]
    pub json: bool,
    /// The trials of `advise` (default: fall limb crush).
    #[arg(long, value_enum, num_args = 1..)]
    pub trial: Vec<TrialArg>,
    /// `advise`: the largest error allowed (default: the trial's own, see
    /// `sinew_scenes::dim3::advise`).
    #[arg(long)]
    pub max_error: Option<f64>,
    /// Damping ratio (vibration, tower, pinch).
    #[arg(long)]
    pub damping: Option<f64>,
    /// Gap below each cube of the tower as built, m (default 0: at rest).
    #[arg(long)]
    pub gap: Option<f64>,
    /// Tower: the rate sinew's cubes' deformation is damped toward their rigid motion, 1/s
    /// (`DeformableBuilder::deformation_damping`, default 0).
    #[arg(long)]
    pub deformation_damping: Option<f64>,
    /// Tower, pile: sinew's deformables resting on each other do not damp their motion against
    /// each other (`PipelineSettings::damp_held` off).
    #[arg(long)]
    pub no_damp_held: bool,
    /// `advise`: the smallest cell volume ratio allowed (default 0: no inverted cell).
    #[arg(long)]
    pub min_volume: Option<f64>,
}

/// Parses `args` (the first is the program name). A request for help or the version comes
/// back as an error too, which clap's `Error::exit` prints to stdout with status 0; a bad
/// argument exits with status 2, as clap's own parsers do.
pub fn parse<I, T>(args: I) -> Result<Args, clap::Error>
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    Args::try_parse_from(args)
}

/// Parses `args` (the first is the program name), runs, and writes the output to `out`.
pub fn run<I, T>(args: I, out: &mut dyn Write) -> Result<Vec<Record>, String>
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let args = parse(args).map_err(|e| e.to_string())?;
    if args.rrd.is_some() && !cfg!(feature = "rerun") {
        return Err("--rrd needs the rerun feature: cargo run --release --features rerun --example scenes -- ...".into());
    }
    let dims = if args.dim.is_empty() {
        vec![3, 2]
    } else {
        args.dim.clone()
    };
    let mut records = Vec::new();
    if args.scene == Scene::Advise {
        for dim in dims {
            records.extend(match dim {
                2 => dim2::advise(&args, out)?,
                _ => dim3::advise(&args, out)?,
            });
        }
        return Ok(records);
    }
    let mut header = false;
    for dim in dims {
        let mut emit = |r: Record| -> Result<(), String> {
            let line = if args.json {
                to_json(&r).to_string()
            } else {
                let mut s = String::new();
                if !header {
                    s.push_str(&table_header(args.scene));
                    s.push('\n');
                    header = true;
                }
                s.push_str(&table_row(args.scene, &r));
                s
            };
            writeln!(out, "{line}").map_err(|e| e.to_string())?;
            records.push(r);
            Ok(())
        };
        match dim {
            2 => dim2::run(&args, &mut emit)?,
            _ => dim3::run(&args, &mut emit)?,
        }
    }
    Ok(records)
}

/// A progress bar on stderr that shows itself only once a run has lasted a second.
pub struct Progress {
    bar: ProgressBar,
    start: Instant,
    shown: bool,
}

impl Progress {
    /// A hidden bar for the run called `label`.
    pub fn new(label: String) -> Progress {
        let bar = ProgressBar::with_draw_target(Some(1000), ProgressDrawTarget::hidden());
        bar.set_style(
            ProgressStyle::with_template("{msg:40} [{bar:30}] {percent:>3}% {elapsed}/{eta}")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        bar.set_message(label);
        Progress {
            bar,
            start: Instant::now(),
            shown: false,
        }
    }

    /// Fraction `done` of the run is done.
    pub fn update(&mut self, done: f64) {
        if !self.shown && self.start.elapsed() > Duration::from_secs(1) {
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
            self.shown = true;
        }
        self.bar
            .set_position((done.clamp(0.0, 1.0) * 1000.0) as u64);
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
    }
}

/// The record as a JSON object: every key always present, `null` where it does not apply.
pub fn to_json(r: &Record) -> Value {
    let spurious = r.spurious;
    let mut object = json!({
        "scene": r.scene,
        "dim": r.dim,
        "model": r.model,
        "iterations": r.iterations,
        "res": r.res,
        "nodes": r.nodes,
        "elements": r.elements,
        "dt": r.dt,
        "substep_mode": r.substep_mode,
        "substeps": r.substeps,
        "max_substeps": r.max_substeps,
        "sim_s": r.sim_s,
        "wall_s": r.wall_s,
        "wall_per_sim_s": r.wall_per_sim_s(),
        "mass": r.mass,
        "young": r.young,
        "poisson": r.poisson,
        "k_over_m": r.k_over_m,
        "bounce_apex_com": r.bounce_apex_com,
        "rest_com": r.rest_com,
        "max_penetration": r.max_penetration,
        "min_vol_ratio": r.min_vol_ratio,
        "max_inverted_elements": r.max_inverted_elements,
        "final_inverted_elements": r.final_inverted_elements,
        "failed": r.failed,
        "failure": r.failure,
        "first_failure": r.first_failure,
        "shape_error": r.shape_error,
        "loaded_volume_ratio": r.loaded_volume_ratio,
        "spurious_mean": spurious.map(|s| s.mean),
        "spurious_std": spurious.map(|s| s.std),
        "spurious_max": spurious.map(|s| s.max),
        "max_anchor_error": r.max_anchor_error,
        "max_self_penetration": r.max_self_penetration,
        "sag": r.sag,
        "sag_theory": r.sag_theory,
        "sag_error": r.sag_error,
        "sag_wobble": r.sag_wobble,
        "final_kinetic_energy": r.final_kinetic_energy,
        "nan": r.nan,
        "exploded": r.exploded,
    });
    // The integrator's and the contact scenes' keys (one `json!` of every key passes the
    // macro's recursion limit).
    let contact = json!({
        "integrator": r.integrator,
        "sweeps": r.sweeps,
        "bodies": r.bodies,
        "max_interpenetration": r.max_interpenetration,
        "rest_interpenetration": r.rest_interpenetration,
        "energy_gain": r.energy_gain,
        "final_speed": r.final_speed,
        "pairs_wall_s": r.pairs_wall_s,
        "measured_poisson": r.measured_poisson,
        "measured_young_modulus": r.measured_young_modulus,
        "measured_frequency": r.measured_frequency,
        "theory_frequency": r.theory_frequency,
        "measured_damping_ratio": r.measured_damping_ratio,
        "energy_over_start": r.energy_over_start,
        "energy_change": r.energy_change,
        "scatter": r.scatter,
        "top_height_ratio": r.top_height_ratio,
        "asleep": r.asleep,
        "slip": r.slip,
        "overspeed": r.overspeed,
        "step_spike": r.step_spike,
    });
    if let (Some(all), Value::Object(more)) = (object.as_object_mut(), contact) {
        all.extend(more);
    }
    // The balloon's and the tear's measures (one `json!` of every field would pass its
    // recursion limit).
    if let Some(all) = object.as_object_mut() {
        for (key, value) in [
            ("inflation", r.inflation),
            ("gas_volume_ratio", r.gas_volume_ratio),
            ("boyle_error", r.boyle_error),
            ("recovery_error", r.recovery_error),
            ("torn_at_strain", r.torn_at_strain),
            ("kept_bend", r.kept_bend),
            ("kept_bend_theory", r.kept_bend_theory),
            ("dent", r.dent),
        ] {
            all.insert(key.to_string(), json!(value));
        }
        all.insert("pieces".to_string(), json!(r.pieces));
    }
    object
}

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map_or("—".to_string(), |v| format!("{v:.digits$}"))
}

fn table_header(scene: Scene) -> String {
    let extra = match scene {
        Scene::Fall => "  apex m  rest m   pen mm",
        Scene::Ball => "  apex m  rest m   pen mm  ms/step",
        Scene::Stretch => "  ν asked  ν measured",
        Scene::Limb => " failure°  anchor m  self mm",
        Scene::Crush => "    mass kg  pen mm  shape err  failure kg",
        Scene::Manipulator => "  rest m  shape err  failure strike",
        Scene::DtSweep => "  mode   dt ms  apex m  rest m   pen mm  failure ms",
        Scene::RotationError => "  k/m      dt ms  mean rad/s²  std rad/s²  max rad/s²",
        Scene::Cantilever => "  sag mm  theory mm  ratio   error  wobble",
        Scene::Stack | Scene::Pile | Scene::Squeeze => {
            " bodies  inside mm  at rest mm  E gain   speed  rest m  pairs ms/s"
        }
        Scene::Pinch => "  mass kg  slip mm  overspeed  floor mm  box m  spike",
        Scene::Roll => "  box kg  pen mm  E>start  E gain  knocked m",
        Scene::Tower => {
            " bodies  inside mm  at rest mm  E>start  E end  top/built  scatter mm  asleep"
        }
        Scene::Fold => "  self mm",
        Scene::Balloon => "  inflated  squeezed    pV err  back err",
        Scene::Tear => "  torn at  pieces  end m/s",
        Scene::Bend => "  kept rad  beam rad",
        Scene::Dent => "  dent mm",
        Scene::Vibration => "   f Hz  theory Hz  ζ measured",
        Scene::Bending => "   f Hz  theory Hz   mean sag mm",
        Scene::Advise => "",
    };
    format!(
        "dim {:<23} {:>5} {:>6} {:>6} {:>9} {:>9} {:>9} {:>7}{extra}  flags",
        "model", "iter", "nodes", "cells", "substeps", "wall/sim", "min vol", "inv max/end"
    )
}

fn table_row(scene: Scene, r: &Record) -> String {
    let extra = match scene {
        Scene::Fall => format!(
            "  {:>6}  {:>6}  {:>7}",
            opt(r.bounce_apex_com, 3),
            opt(r.rest_com, 3),
            opt(r.max_penetration.map(|p| p * 1e3), 2)
        ),
        Scene::Ball => format!(
            "  {:>6}  {:>6}  {:>7}  {:>7.2}",
            opt(r.bounce_apex_com, 3),
            opt(r.rest_com, 3),
            opt(r.max_penetration.map(|p| p * 1e3), 2),
            r.wall_per_sim_s() * r.dt * 1e3
        ),
        Scene::Stretch => format!("  {:>7.3}  {:>10}", r.poisson, opt(r.measured_poisson, 3)),
        Scene::Limb => format!(
            " {:>9}  {:>8}  {:>7}",
            opt(r.first_failure, 1),
            r.max_anchor_error
                .map_or("—".to_string(), |e| format!("{e:.1e}")),
            opt(r.max_self_penetration.map(|p| p * 1e3), 3)
        ),
        Scene::Stack | Scene::Pile | Scene::Squeeze => format!(
            " {:>6}  {:>9}  {:>10}  {:>6}  {:>6}  {:>6}  {:>10}",
            r.bodies.unwrap_or(0),
            opt(r.max_interpenetration.map(|p| p * 1e3), 2),
            opt(r.rest_interpenetration.map(|p| p * 1e3), 2),
            opt(r.energy_gain.map(|e| e * 100.0), 2) + "%",
            opt(r.final_speed, 3),
            opt(r.rest_com, 3),
            opt(r.pairs_wall_s.map(|p| p * 1e3 / r.sim_s.max(1e-9)), 2)
        ),
        Scene::Pinch => format!(
            "  {:>7}  {:>7}  {:>9}  {:>8}  {:>5}  {:>5}",
            opt(r.mass, 2),
            opt(r.slip.map(|s| s * 1e3), 2),
            opt(r.overspeed, 3),
            opt(r.max_penetration.map(|p| p * 1e3), 2),
            opt(r.rest_com, 3),
            opt(r.step_spike, 1)
        ),
        Scene::Roll => format!(
            "  {:>6}  {:>6}  {:>7}  {:>6}  {:>9}",
            opt(r.mass, 2),
            opt(r.max_penetration.map(|p| p * 1e3), 2),
            opt(r.energy_over_start.map(|e| e * 100.0), 2) + "%",
            opt(r.energy_gain.map(|e| e * 100.0), 2) + "%",
            opt(r.scatter, 3)
        ),
        Scene::Tower => format!(
            " {:>6}  {:>9}  {:>10}  {:>7}  {:>6}  {:>9}  {:>10}  {:>6}",
            r.bodies.unwrap_or(0),
            opt(r.max_interpenetration.map(|p| p * 1e3), 2),
            opt(r.rest_interpenetration.map(|p| p * 1e3), 2),
            opt(r.energy_over_start.map(|e| e * 100.0), 2) + "%",
            opt(r.energy_change.map(|e| e * 100.0), 1) + "%",
            opt(r.top_height_ratio, 3),
            opt(r.scatter.map(|s| s * 1e3), 1),
            r.asleep.map_or("—", |a| if a { "yes" } else { "no" })
        ),
        Scene::Fold => format!("  {:>7}", opt(r.max_self_penetration.map(|p| p * 1e3), 3)),
        Scene::Balloon => format!(
            "  {:>8}  {:>8}  {:>8}  {:>8}",
            opt(r.inflation, 4),
            opt(r.gas_volume_ratio, 4),
            r.boyle_error
                .map_or("—".to_string(), |e| format!("{e:.1e}")),
            r.recovery_error
                .map_or("—".to_string(), |e| format!("{e:.1e}"))
        ),
        Scene::Dent => format!("  {:>7}", opt(r.dent.map(|d| d * 1e3), 2)),
        Scene::Bend => format!(
            "  {:>8}  {:>8}",
            opt(r.kept_bend, 4),
            opt(r.kept_bend_theory, 4)
        ),
        Scene::Tear => format!(
            "  {:>7}  {:>6}  {:>7}",
            opt(r.torn_at_strain, 4),
            r.pieces.map_or("—".to_string(), |p| p.to_string()),
            opt(r.final_speed, 3)
        ),
        Scene::Vibration => format!(
            "  {:>5}  {:>9}  {:>10}",
            opt(r.measured_frequency, 3),
            opt(r.theory_frequency, 3),
            opt(r.measured_damping_ratio, 4)
        ),
        Scene::Bending => format!(
            "  {:>5}  {:>9}  {:>12}",
            opt(r.measured_frequency, 3),
            opt(r.theory_frequency, 3),
            opt(r.sag.map(|s| s * 1e3), 2)
        ),
        Scene::Advise => String::new(),
        Scene::Crush => format!(
            "  {:>9}  {:>6}  {:>9}  {:>10}",
            opt(r.mass, 0),
            opt(r.max_penetration.map(|p| p * 1e3), 2),
            opt(r.shape_error.map(|s| s * 100.0), 2) + "%",
            opt(r.first_failure, 0)
        ),
        Scene::Manipulator => format!(
            "  {:>6}  {:>9}  {:>14}",
            opt(r.rest_com, 3),
            opt(r.shape_error.map(|s| s * 100.0), 2) + "%",
            opt(r.first_failure, 0)
        ),
        Scene::DtSweep => format!(
            "  {:<5} {:>6}  {:>6}  {:>6}  {:>7}  {:>10}",
            r.substep_mode,
            format!("{:.1}", r.dt * 1e3),
            opt(r.bounce_apex_com, 3),
            opt(r.rest_com, 3),
            opt(r.max_penetration.map(|p| p * 1e3), 2),
            opt(r.first_failure, 1)
        ),
        Scene::RotationError => {
            let s = r.spurious.unwrap_or_default();
            format!(
                "  {:<7.0e}  {:>6.3}  {:>11.3e}  {:>10.3e}  {:>10.3e}",
                r.k_over_m.unwrap_or(0.0),
                r.dt * 1e3,
                s.mean,
                s.std,
                s.max
            )
        }
        Scene::Cantilever => format!(
            "  {:>6}  {:>9}  {:>5}  {:>6}  {:>6}",
            opt(r.sag.map(|s| s * 1e3), 2),
            opt(r.sag_theory.map(|s| s * 1e3), 2),
            opt(r.sag.zip(r.sag_theory).map(|(s, t)| s / t), 3),
            opt(r.sag_error.map(|e| e * 100.0), 1) + "%",
            r.sag_wobble.map_or("—".to_string(), |w| format!("{w:.0e}"))
        ),
    };
    let mut flags = Vec::new();
    let why;
    if r.failed {
        why = format!("FAILED: {}", r.failure.as_deref().unwrap_or("?"));
        flags.push(why.as_str());
    }
    if r.nan && !r.failed {
        flags.push("NAN");
    }
    if r.exploded && !r.failed {
        flags.push("EXPLODED");
    }
    format!(
        "{}D  {:<23} {:>5} {:>6} {:>6} {:>9.1} {:>9.3} {:>+9.3} {:>7}{extra}  {}",
        r.dim,
        r.model,
        r.iterations.clone().unwrap_or_default(),
        r.nodes,
        r.elements,
        r.substeps,
        r.wall_per_sim_s(),
        r.min_vol_ratio,
        format!("{}/{}", r.max_inverted_elements, r.final_inverted_elements),
        flags.join(" ")
    )
}

/// The values a list option was given, or the default alone.
fn or_default<T: Clone>(given: &[T], default: T) -> Vec<T> {
    if given.is_empty() {
        vec![default]
    } else {
        given.to_vec()
    }
}

/// The runner for one dimension, written once and compiled for each.
macro_rules! dimension_runner {
    ($module:ident, $dim:ident) => {
        mod $module {
            use super::{or_default, Args, IntegratorArg, Progress, Scene, Switch, TrialArg};
            use sinew::$dim::math::Real;
            use sinew::$dim::Integrator;
            use sinew::$dim::{DeformableWorld, ElementModel, Material, RotationFit};
            use sinew_scenes::record::Record;
            use sinew_scenes::$dim::{
                dt_sweep, BallScene, BalloonScene, BendScene, DentScene, TearScene, CantileverScene, CrushScene, FallScene, FoldScene, LimbScene,
                ManipulatorScene, PileScene, RapierModel, RotationErrorScene, SqueezeScene,
                PinchScene, RollScene, StackScene, StretchScene, Subject, TowerScene, VibrationScene,
                CRUSH_MASSES,
            };

            fn fits(args: &Args) -> Result<Vec<RotationFit>, String> {
                if args.iterations.is_empty() {
                    return Ok(vec![RotationFit::Iterative(2)]);
                }
                args.iterations
                    .iter()
                    .map(|s| match s.as_str() {
                        "polar" => Ok(RotationFit::Polar),
                        n => match n.parse::<usize>() {
                            Ok(k @ 1..=3) => Ok(RotationFit::Iterative(k)),
                            _ => Err(format!("--iterations takes 1, 2, 3 or polar, not {n}")),
                        },
                    })
                    .collect()
            }

            fn subjects(args: &Args) -> Result<Vec<Subject>, String> {
                let fits = fits(args)?;
                let names: Vec<String> = if args.model.is_empty() {
                    vec!["sinew".into(), "rapier".into()]
                } else {
                    args.model.clone()
                };
                let mut out = Vec::new();
                for name in &names {
                    let expanded: Vec<&str> = match name.as_str() {
                        "sinew" => ElementModel::ALL.iter().map(|m| m.name()).collect(),
                        "rapier" => RapierModel::ALL.iter().map(|m| m.name()).collect(),
                        n => vec![n],
                    };
                    for n in expanded {
                        let per_fit: Vec<RotationFit> = if n == "shape-matching" {
                            fits.clone()
                        } else {
                            vec![RotationFit::Iterative(2)]
                        };
                        for fit in per_fit {
                            let s = Subject::parse(n, fit).ok_or_else(|| {
                                let all: Vec<&str> =
                                    Subject::all().iter().map(|s| s.name()).collect();
                                format!("unknown model {n}; the models are {}", all.join(", "))
                            })?;
                            out.push(s);
                        }
                    }
                }
                Ok(out)
            }

            /// The scene's material with `--young`, `--poisson` and `--damping` applied.
            fn material(args: &Args, d: Material) -> Material {
                Material {
                    young_modulus: args.young.map_or(d.young_modulus, |v| v as Real),
                    poisson_ratio: args.poisson.map_or(d.poisson_ratio, |v| v as Real),
                    damping_ratio: args.damping.map_or(d.damping_ratio, |v| v as Real),
                    ..d
                }
            }

            fn cube(args: &Args, subject: Subject) -> FallScene {
                let d = FallScene::default();
                FallScene {
                    subject,
                    resolution: args.res.unwrap_or(d.resolution),
                    dt: args.dt.map_or(d.dt, |v| v as Real),
                    seconds: args.seconds.map_or(d.seconds, |v| v as Real),
                    young_modulus: args.young.map_or(d.young_modulus, |v| v as Real),
                    poisson_ratio: args.poisson.map_or(d.poisson_ratio, |v| v as Real),
                    integrator: match args.integrator {
                        Some(IntegratorArg::Implicit) => Integrator::Implicit {
                            iterations: args.sweeps.unwrap_or(10),
                        },
                        Some(IntegratorArg::Midpoint) => Integrator::Midpoint {
                            iterations: args.sweeps.unwrap_or(10),
                        },
                        Some(IntegratorArg::Auto) => Integrator::Auto {
                            iterations: args.sweeps.unwrap_or(10),
                        },
                        _ => Integrator::Explicit,
                    },
                    global_iterations: args.global,
                    ..d
                }
            }

            /// A scene's own cube `own` (its resolution, step and material unless the flags set
            /// them), run as `cube` says (the scene's own integrator unless a flag sets one).
            fn scene_cube(args: &Args, cube: &FallScene, own: FallScene) -> FallScene {
                FallScene {
                    subject: cube.subject,
                    resolution: args.res.unwrap_or(own.resolution),
                    dt: args.dt.map_or(own.dt, |v| v as Real),
                    young_modulus: args.young.map_or(own.young_modulus, |v| v as Real),
                    poisson_ratio: args.poisson.map_or(own.poisson_ratio, |v| v as Real),
                    damping_ratio: args.damping.map_or(own.damping_ratio, |v| v as Real),
                    integrator: if args.integrator.is_some() {
                        cube.integrator
                    } else {
                        own.integrator
                    },
                    global_iterations: cube.global_iterations,
                    fixed_substeps: cube.fixed_substeps,
                    ..own
                }
            }

            /// Runs `f` with an observer that drives a progress bar and the Rerun log.
            fn observed<T>(
                args: &Args,
                label: String,
                f: impl FnOnce(&mut dyn FnMut(&DeformableWorld, f64)) -> T,
            ) -> T {
                let mut progress = Progress::new(label.clone());
                #[cfg(feature = "rerun")]
                let mut recorder = args.rrd.as_ref().and_then(|dir| {
                    use sinew::$dim::{RecorderOptions, RerunRecorder};
                    let file = dir.join(format!("{}.rrd", label.replace([' ', '/'], "-")));
                    let options = RecorderOptions {
                        every_n_steps: 10,
                        ..Default::default()
                    };
                    RerunRecorder::save("sinew-scenes", &file, options)
                        .map_err(|e| eprintln!("not logging {label}: {e}"))
                        .ok()
                });
                #[cfg(not(feature = "rerun"))]
                let _ = args;
                let result = f(&mut |_world: &DeformableWorld, done: f64| {
                    progress.update(done);
                    #[cfg(feature = "rerun")]
                    if let Some(r) = recorder.as_mut() {
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
                result
            }

            /// `scenes advise`: each trial's candidates as a table (or JSON lines), then the
            /// pick; returns the candidates' records.
            pub fn advise(
                args: &Args,
                out: &mut dyn std::io::Write,
            ) -> Result<Vec<Record>, String> {
                use sinew_scenes::$dim::advise::{advise, candidates, Trial};
                use sinew_scenes::$dim::{FallReference, FALL_REFERENCE_PATH};
                let dim = sinew::$dim::math::DIM;
                let dt = args.dt.unwrap_or(1.0 / 60.0) as Real;
                let trials = if args.trial.is_empty() {
                    vec![TrialArg::Fall, TrialArg::Limb, TrialArg::Crush]
                } else {
                    args.trial.clone()
                };
                let w = |out: &mut dyn std::io::Write, line: String| {
                    writeln!(out, "{line}").map_err(|e| e.to_string())
                };
                let mut records = Vec::new();
                for t in trials {
                    let trial = match t {
                        TrialArg::Fall => {
                            let reference =
                                FallReference::load(std::path::Path::new(FALL_REFERENCE_PATH));
                            if let Err(e) = &reference {
                                eprintln!("no fall reference ({e}): the fall is judged on stability alone");
                            }
                            Trial::fall(args.res.unwrap_or(5), dt, reference.ok())
                        }
                        TrialArg::Limb => Trial::limb(
                            args.res.map_or(0.1, |n| 2.0 / (n.max(2) - 1) as Real),
                            dt,
                        ),
                        TrialArg::Crush => Trial::crush(
                            args.res.unwrap_or(5),
                            dt,
                            args.mass.first().map_or(1000.0, |m| *m as Real),
                        ),
                    };
                    let mut bounds = trial.default_bounds();
                    if let Some(e) = args.max_error {
                        bounds.max_error = e;
                    }
                    if let Some(v) = args.min_volume {
                        bounds.min_volume_ratio = v;
                    }
                    let advice = advise(&trial, bounds, &candidates(), |what| {
                        eprintln!("[advise {dim}D] {what}")
                    })
                    .map_err(|e| e.to_string())?;
                    if !args.json {
                        w(out, format!(
                            "advise {} {dim}D, dt {:.2} ms: error = {} (at most {}), smallest volume ratio at least {}",
                            advice.trial, dt * 1e3, trial.error_name(), bounds.max_error, bounds.min_volume_ratio
                        ))?;
                        w(out, format!(
                            "  {:<34} {:>9} {:>10} {:>8}  verdict",
                            "model and integrator", "wall/sim", "error", "min vol"
                        ))?;
                    }
                    for (i, c) in advice.candidates.iter().enumerate() {
                        let chosen = advice.chosen == Some(i);
                        if args.json {
                            let mut v = super::to_json(&c.record);
                            v["advise"] = serde_json::json!({
                                "trial": advice.trial,
                                "candidate": c.label(),
                                "error": c.error,
                                "max_error": bounds.max_error,
                                "min_volume_ratio": bounds.min_volume_ratio,
                                "rejected": c.rejected,
                                "chosen": chosen,
                            });
                            w(out, v.to_string())?;
                        } else {
                            w(out, format!(
                                "  {:<34} {:>9.4} {:>10} {:>+8.3}  {}{}",
                                c.label(),
                                c.cost(),
                                c.error.map_or("—".to_string(), |e| format!("{e:.3e}")),
                                c.record.min_vol_ratio,
                                c.rejected.as_deref().unwrap_or("passes"),
                                if chosen { "  <- cheapest that passes" } else { "" }
                            ))?;
                        }
                    }
                    if !args.json {
                        w(out, match advice.choice() {
                            Some(c) => format!(
                                "  => {}: {:.4} wall s per simulated s, error {}\n",
                                c.label(),
                                c.cost(),
                                c.error.map_or("—".to_string(), |e| format!("{e:.3e}"))
                            ),
                            None => "  => no candidate stays inside the bounds\n".to_string(),
                        })?;
                    }
                    records.extend(advice.candidates.into_iter().map(|c| c.record));
                }
                Ok(records)
            }

            pub fn run(
                args: &Args,
                emit: &mut dyn FnMut(Record) -> Result<(), String>,
            ) -> Result<(), String> {
                let dim = sinew::$dim::math::DIM;
                let label = |scene: &str, s: &Subject| {
                    let fit = s.iterations().map_or(String::new(), |i| format!(" {i}"));
                    format!("{scene} {dim}D {}{fit}", s.name())
                };
                let err = |e: sinew::$dim::BuildError| e.to_string();
                if args.scene == Scene::RotationError {
                    let ks = if args.k_over_m.is_empty() {
                        vec![1e4, 1e5, 1e6]
                    } else {
                        args.k_over_m.clone()
                    };
                    for k in ks {
                        for row in RotationErrorScene::table_rows(k as Real) {
                            let row = RotationErrorScene {
                                seconds: args.seconds.map_or(row.seconds, |s| s as Real),
                                ..row
                            };
                            let name = format!("rotation-error {dim}D k/m {k:e} {:?}", row.fit);
                            let r = observed(args, name, |o| row.run_with(o)).map_err(err)?;
                            emit(r)?;
                        }
                    }
                    return Ok(());
                }
                for subject in subjects(args)? {
                    let cube = cube(args, subject);
                    let name = label(&format!("{:?}", args.scene).to_lowercase(), &subject);
                    let records: Vec<Record> = match args.scene {
                        Scene::Fall => {
                            vec![observed(args, name, |o| cube.run_with(o)).map_err(err)?]
                        }
                        Scene::DtSweep => {
                            observed(args, name, |o| dt_sweep(&cube, o)).map_err(err)?
                        }
                        Scene::Stretch => {
                            let d = StretchScene::default();
                            let scene = StretchScene {
                                subject,
                                spacing: args
                                    .res
                                    .map_or(d.spacing, |n| 1.0 / (n.max(2) - 1) as Real),
                                dt: args.dt.map_or(d.dt, |v| v as Real),
                                young_modulus: args.young.map_or(d.young_modulus, |v| v as Real),
                                poisson_ratio: args.poisson.map_or(d.poisson_ratio, |v| v as Real),
                                integrator: cube.integrator,
                                ..d
                            };
                            vec![scene.run().map_err(err)?]
                        }
                        Scene::Ball => {
                            let d = BallScene::default();
                            let scene = BallScene {
                                subject,
                                dt: args.dt.map_or(d.dt, |v| v as Real),
                                seconds: args.seconds.map_or(d.seconds, |v| v as Real),
                                young_modulus: args.young.map_or(d.young_modulus, |v| v as Real),
                                poisson_ratio: args.poisson.map_or(d.poisson_ratio, |v| v as Real),
                                integrator: if args.integrator.is_some() {
                                    cube.integrator
                                } else {
                                    d.integrator
                                },
                                ..d
                            };
                            vec![observed(args, name, |o| scene.run_with(o)).map_err(err)?]
                        }
                        Scene::Limb => {
                            let d = LimbScene::default();
                            let scene = LimbScene {
                                subject,
                                spacing: args
                                    .res
                                    .map_or(d.spacing, |n| 2.0 / (n.max(2) - 1) as Real),
                                dt: args.dt.map_or(d.dt, |v| v as Real),
                                max_degrees: args
                                    .seconds
                                    .map_or(d.max_degrees, |s| s as Real * d.degrees_per_second),
                                young_modulus: args.young.map_or(d.young_modulus, |v| v as Real),
                                poisson_ratio: args.poisson.map_or(d.poisson_ratio, |v| v as Real),
                                self_contact: args.self_contact == Some(Switch::On),
                                integrator: cube.integrator,
                                ..d
                            };
                            vec![observed(args, name, |o| scene.run_with(o)).map_err(err)?]
                        }
                        Scene::Stack => {
                            let d = StackScene::default();
                            let scene = StackScene {
                                subject,
                                integrator: cube.integrator,
                                resolution: args.res.unwrap_or(d.resolution),
                                dt: args.dt.map_or(d.dt, |v| v as Real),
                                seconds: args.seconds.map_or(d.seconds, |v| v as Real),
                                ..d
                            };
                            vec![observed(args, name, |o| scene.run_with(o)).map_err(err)?]
                        }
                        Scene::Pile => {
                            let d = PileScene::default();
                            let mut out = Vec::new();
                            for bodies in or_default(&args.bodies, d.bodies) {
                                let scene = PileScene {
                                    subject,
                                    bodies,
                                    integrator: cube.integrator,
                                    resolution: args.res.unwrap_or(d.resolution),
                                    dt: args.dt.map_or(d.dt, |v| v as Real),
                                    seconds: args.seconds.map_or(d.seconds, |v| v as Real),
                                    damp_held: !args.no_damp_held,
                                    ..d
                                };
                                let run = format!("{name} {bodies} bodies");
                                out.push(observed(args, run, |o| scene.run_with(o)).map_err(err)?);
                            }
                            out
                        }
                        Scene::Tower => {
                            let d = TowerScene::default();
                            let mut out = Vec::new();
                            for bodies in or_default(&args.bodies, d.bodies) {
                                let scene = TowerScene {
                                    subject,
                                    bodies,
                                    integrator: cube.integrator,
                                    resolution: args.res.unwrap_or(d.resolution),
                                    gap: args.gap.map_or(d.gap, |v| v as Real),
                                    deformation_damping: args
                                        .deformation_damping
                                        .map_or(d.deformation_damping, |v| v as Real),
                                    dt: args.dt.map_or(d.dt, |v| v as Real),
                                    seconds: args.seconds.map_or(d.seconds, |v| v as Real),
                                    material: material(args, d.material),
                                    damp_held: !args.no_damp_held,
                                    ..d
                                };
                                let run = format!("{name} {bodies} bodies");
                                out.push(observed(args, run, |o| scene.run_with(o)).map_err(err)?);
                            }
                            out
                        }
                        Scene::Pinch => {
                            let d = PinchScene::default();
                            let mut out = Vec::new();
                            for mass in or_default(&args.mass, d.mass as f64) {
                                let scene = PinchScene {
                                    subject,
                                    mass: mass as Real,
                                    integrator: cube.integrator,
                                    dt: args.dt.map_or(d.dt, |v| v as Real),
                                    material: material(args, d.material),
                                    ..d
                                };
                                let run = format!("{name} {mass} kg");
                                out.push(observed(args, run, |o| scene.run_with(o)).map_err(err)?);
                            }
                            out
                        }
                        Scene::Roll => {
                            let d = RollScene::default();
                            let mut out = Vec::new();
                            for mass in or_default(&args.mass, d.box_mass as f64) {
                                let scene = RollScene {
                                    subject,
                                    box_mass: mass as Real,
                                    integrator: cube.integrator,
                                    global_iterations: args.global,
                                    dt: args.dt.map_or(d.dt, |v| v as Real),
                                    seconds: args.seconds.map_or(d.seconds, |v| v as Real),
                                    material: material(args, d.material),
                                    ..d
                                };
                                let run = format!("{name} {mass} kg");
                                out.push(observed(args, run, |o| scene.run_with(o)).map_err(err)?);
                            }
                            out
                        }
                        Scene::Squeeze => {
                            let d = SqueezeScene::default();
                            let scene = SqueezeScene {
                                subject,
                                load: args.mass.first().map_or(d.load, |&m| m as Real),
                                dt: args.dt.map_or(d.dt, |v| v as Real),
                                seconds: args.seconds.map_or(d.seconds, |v| v as Real),
                                ..d
                            };
                            vec![observed(args, name, |o| scene.run_with(o)).map_err(err)?]
                        }
                        Scene::Vibration => {
                            let d = VibrationScene::default();
                            let scene = VibrationScene {
                                subject,
                                resolution: args.res.unwrap_or(d.resolution),
                                dt: args.dt.map_or(d.dt, |v| v as Real),
                                young_modulus: args.young.map_or(d.young_modulus, |v| v as Real),
                                poisson_ratio: args.poisson.map_or(d.poisson_ratio, |v| v as Real),
                                damping_ratio: args.damping.map_or(d.damping_ratio, |v| v as Real),
                                integrator: cube.integrator,
                                ..d
                            };
                            vec![scene.run().map_err(err)?]
                        }
                        Scene::Balloon => {
                            let d = BalloonScene::default();
                            let scene = BalloonScene {
                                cube: scene_cube(args, &cube, d.cube),
                                ..d
                            };
                            vec![observed(args, name, |o| scene.run_with(o)).map_err(err)?]
                        }
                        Scene::Dent => {
                            let d = DentScene::default();
                            let scene = DentScene {
                                cube: scene_cube(args, &cube, d.cube),
                                ..d
                            };
                            vec![observed(args, name, |o| scene.run_with(o)).map_err(err)?]
                        }
                        Scene::Bend => {
                            let d = BendScene::default();
                            let scene = BendScene {
                                recover: args.seconds.map_or(d.recover, |s| s as Real),
                                cube: scene_cube(args, &cube, d.cube),
                                ..d
                            };
                            vec![observed(args, name, |o| scene.run_with(o)).map_err(err)?]
                        }
                        Scene::Tear => {
                            let d = TearScene::default();
                            let scene = TearScene {
                                cube: scene_cube(args, &cube, d.cube),
                                fall: args.seconds.map_or(d.fall, |s| s as Real),
                                ..d
                            };
                            vec![observed(args, name, |o| scene.run_with(o)).map_err(err)?]
                        }
                        Scene::Fold => {
                            let d = FoldScene::default();
                            let scene = FoldScene {
                                subject,
                                self_contact: args.self_contact != Some(Switch::Off),
                                dt: args.dt.map_or(d.dt, |v| v as Real),
                                fold_seconds: args
                                    .seconds
                                    .map_or(d.fold_seconds, |s| 0.5 * s as Real),
                                ..d
                            };
                            vec![scene.run().map_err(err)?]
                        }
                        Scene::Crush => {
                            let d = CrushScene::default();
                            let scale = args.seconds.map_or(1.0, |s| {
                                s as Real / (d.settle + d.hold + d.lift + d.recover)
                            });
                            let scene = CrushScene {
                                cube,
                                settle: d.settle * scale,
                                ramp: d.ramp * scale,
                                hold: d.hold * scale,
                                lift: d.lift * scale,
                                recover: d.recover * scale,
                                ..d
                            };
                            let masses: Vec<Real> = if args.mass.is_empty() {
                                CRUSH_MASSES.to_vec()
                            } else {
                                args.mass.iter().map(|&m| m as Real).collect()
                            };
                            observed(args, name, |o| scene.run_masses(&masses, o)).map_err(err)?
                        }
                        Scene::Manipulator => {
                            let d = ManipulatorScene::default();
                            let strikes = args.strikes.unwrap_or(d.strikes).max(1);
                            let natural = d.settle + strikes as Real * d.period;
                            let scale = args.seconds.map_or(1.0, |s| s as Real / natural);
                            let scene = ManipulatorScene {
                                cube,
                                strikes,
                                period: d.period * scale,
                                settle: d.settle * scale,
                                ..d
                            };
                            vec![observed(args, name, |o| scene.run_with(o)).map_err(err)?]
                        }
                        Scene::Cantilever => {
                            let d = CantileverScene::default();
                            let scene = CantileverScene {
                                subject,
                                resolution: args.res.unwrap_or(d.resolution),
                                dt: args.dt.map_or(d.dt, |v| v as Real),
                                seconds: args.seconds.map_or(d.seconds, |v| v as Real),
                                young_modulus: args.young.map_or(d.young_modulus, |v| v as Real),
                                poisson_ratio: args.poisson.map_or(d.poisson_ratio, |v| v as Real),
                                integrator: cube.integrator,
                                global_iterations: args.global,
                                ..d
                            };
                            vec![observed(args, name, |o| scene.run_with(o)).map_err(err)?]
                        }
                        Scene::Bending => {
                            let d = CantileverScene::default();
                            let scene = CantileverScene {
                                subject,
                                resolution: args.res.unwrap_or(3),
                                dt: args.dt.map_or(d.dt, |v| v as Real),
                                seconds: args.seconds.map_or(0.8, |v| v as Real),
                                young_modulus: args.young.map_or(d.young_modulus, |v| v as Real),
                                poisson_ratio: args.poisson.map_or(d.poisson_ratio, |v| v as Real),
                                integrator: cube.integrator,
                                global_iterations: args.global,
                                ..d
                            };
                            vec![scene.ring().map_err(err)?]
                        }
                        // Run above: it has one subject of its own.
                        Scene::RotationError | Scene::Advise => Vec::new(),
                    };
                    for r in records {
                        emit(r)?;
                    }
                }
                Ok(())
            }
        }
    };
}

dimension_runner!(dim2, dim2);
dimension_runner!(dim3, dim3);
