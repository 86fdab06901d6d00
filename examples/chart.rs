//! Speed against accuracy: runs the accuracy sweeps for every model (sinew's and rapier's soft
//! bodies, 3D) and charts cost (wall seconds per simulated second, log) against error (log),
//! one chart per metric, one series per model, points over dt and resolution.
//!
//! ```text
//! cargo run --release --example chart              # all sweeps (~15 min), writes docs/
//! cargo run --release --example chart -- --quick   # fewer points, into target/charts
//! cargo run --release --example chart -- --only fall --out /tmp/charts
//! # the fall's common reference (rapier's FEM, minutes on two threads), then the charts:
//! cargo run --release --features sinew-scenes/fem --example chart -- --fresh-reference
//! ```
//!
//! The fall is measured against one common reference for every model
//! ([`FallReference`], kept in `docs/charts/fall-reference.json`): it is computed when that file
//! is missing or with `--fresh-reference` (which needs `--features sinew-scenes/fem`).
//!
//! Writes `<out>/charts/<metric>.svg`, every point as JSON lines in
//! `<out>/charts/points.jsonl`, and `<out>/ACCURACY.md` (the Pareto-best points per metric and
//! the commands); with the default `--out docs` and every metric it also refreshes the Pareto
//! tables in `docs/PERFORMANCE.md` between its `chart:pareto` markers. Every point comes from
//! this run.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use clap::Parser;
use plotters::prelude::*;
use serde_json::json;
use sinew::dim3::math::Real;
use sinew::dim3::{ElementModel, Integrator, RotationFit, ShapeDamping};
use sinew_scenes::dim3::advise::FALL_SECONDS;
use sinew_scenes::dim3::metrics::uniaxial_volume_change;
use sinew_scenes::dim3::{
    CantileverScene, FallReference, FallScene, Record, RotationErrorScene, StretchScene, Subject,
    Trial, VibrationScene, FALL_REFERENCE_PATH,
};

#[derive(Parser, Debug)]
#[command(about = "Charts cost against error for every model")]
struct Args {
    /// Fewer, cheaper points (a smoke run; not for docs).
    #[arg(long)]
    quick: bool,
    /// Output folder (charts go to <out>/charts).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Only these metrics: fall, crush, heavy (crush 1000 kg and limb), vibration, stretch, sag
    /// (the cantilever's sag and first bending frequency), rotation; `reference` computes the
    /// fall's reference afresh (and is not part of the default set).
    #[arg(long, num_args = 1..)]
    only: Vec<String>,
    /// Compute the fall's reference again (needs `--features sinew-scenes/fem`).
    #[arg(long)]
    fresh_reference: bool,
    /// Run nothing: draw the charts and write the tables again from `<out>/charts/points.jsonl`
    /// (the points of the last run).
    #[arg(long)]
    redraw: bool,
}

/// One run's place on a chart.
#[derive(Clone, Debug)]
struct Point {
    metric: &'static str,
    model: String,
    res: usize,
    dt: f64,
    /// Wall seconds per simulated second.
    cost: f64,
    error: f64,
    failed: Option<String>,
}

impl Point {
    fn json(&self) -> serde_json::Value {
        json!({
            "metric": self.metric, "model": self.model, "res": self.res, "dt": self.dt,
            "wall_per_sim_s": self.cost, "error": self.error, "failed": self.failed,
        })
    }

    /// A point written by [`Point::json`], on one of `metrics`.
    fn from_json(v: &serde_json::Value, metrics: &[&Metric]) -> Option<Point> {
        let metric = metrics.iter().find(|m| v["metric"] == m.key)?.key;
        let num = |k: &str| v[k].as_f64().unwrap_or(f64::NAN);
        Some(Point {
            metric,
            model: v["model"].as_str()?.to_string(),
            res: v["res"].as_u64()? as usize,
            dt: num("dt"),
            cost: num("wall_per_sim_s"),
            error: num("error"),
            failed: v["failed"].as_str().map(str::to_string),
        })
    }
}

/// A chart's axis text.
struct Metric {
    /// The sweep that makes its points (`--only`'s name).
    group: &'static str,
    key: &'static str,
    title: &'static str,
    y: &'static str,
}

const FALL: Metric = Metric {
    group: "fall",
    key: "fall-trajectory",
    title: "fall: centre-of-mass trajectory error vs the common reference (rapier FEM, fine)",
    y: "RMS error / size",
};

/// The fall's sampling period, s.
const FALL_EVERY: Real = 0.01;

/// The reference's runs (resolution, dt): its own convergence, the finest last.
const REFERENCE_GRID: [(usize, Real); 4] =
    [(9, 0.25e-3), (13, 0.25e-3), (17, 0.5e-3), (17, 0.25e-3)];

/// The fall's common reference: read from `path`, or computed (and written there) when the
/// file is missing or `fresh` asks.
fn fall_reference(path: &Path, fresh: bool) -> Result<FallReference, Box<dyn std::error::Error>> {
    if !fresh {
        if let Ok(r) = FallReference::load(path) {
            return Ok(r);
        }
    }
    // rapier's FEM is there only with `--features sinew-scenes/fem`.
    let Some(subject) = Subject::parse("rapier-fem-neo-hookean", RotationFit::Polar) else {
        return Err(format!(
            "{} is missing and the reference is rapier's FEM: run with \
             `--features sinew-scenes/fem`",
            path.display()
        )
        .into());
    };
    let scene = FallScene {
        seconds: FALL_SECONDS,
        ..FallScene::default()
    };
    let r = FallReference::compute(&scene, subject, &REFERENCE_GRID, FALL_EVERY, 2, progress)?;
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)?;
    }
    std::fs::write(path, serde_json::to_string(&r.to_json())?)?;
    Ok(r)
}

const CRUSH_SHAPE: Metric = Metric {
    group: "crush",
    key: "crush-shape",
    title: "crush 10 kg and release: shape error after recovery",
    y: "shape error / size",
};
const CRUSH_VOLUME: Metric = Metric {
    group: "crush",
    key: "crush-volume",
    title: "static load 10 kg: |ΔV/V − (−(1−2ν)σ/E)|",
    y: "volume error",
};
const CRUSH_HEAVY: Metric = Metric {
    group: "heavy",
    key: "crush-heavy",
    title: "crush 1000 kg and release: shape error after recovery",
    y: "shape error / size",
};
const LIMB: Metric = Metric {
    group: "heavy",
    key: "limb",
    title: "limb bent to 110°: 1 − smallest cell volume ratio (inverted runs: failed)",
    y: "1 − min volume ratio",
};
const FREQUENCY: Metric = Metric {
    group: "vibration",
    key: "vibration-frequency",
    title: "free bar (10:1) ringing: |first axial frequency / beam theory − 1|",
    y: "relative frequency error",
};
const DAMPING: Metric = Metric {
    group: "vibration",
    key: "vibration-damping",
    title: "free bar ringing: |damping ratio of its decay / the ratio asked for (0.05) − 1|",
    y: "relative damping error",
};
const STRETCH: Metric = Metric {
    group: "stretch",
    key: "stretch-poisson",
    title: "bar pulled 2 %: |Poisson's ratio measured − 0.3|",
    y: "|ν measured − ν|",
};
const YOUNG: Metric = Metric {
    group: "stretch",
    key: "stretch-young",
    title: "bar pulled 2 %: |Young's modulus (end tension / section / strain) / E − 1|",
    y: "relative Young's modulus error",
};
const ROTATION: Metric = Metric {
    group: "rotation",
    key: "rotation",
    title: "rotation-error drop (k/m 1e4): spurious angular acceleration",
    y: "mean spurious acceleration, rad/s²",
};

const SAG: Metric = Metric {
    group: "sag",
    key: "cantilever-sag",
    title: "cantilever (10:1, clamped by a bone): |tip sag / (Euler–Bernoulli + shear) − 1|",
    y: "relative sag error",
};

const BENDING: Metric = Metric {
    group: "sag",
    key: "cantilever-frequency",
    title: "cantilever (10:1) released under its weight: |first bending frequency / Euler–Bernoulli − 1|",
    y: "relative frequency error",
};

/// The default cantilever at `res` nodes across, stepped at `dt` by `subject`.
fn beam(res: usize, dt: Real, subject: Subject, integrator: Integrator) -> CantileverScene {
    CantileverScene {
        subject,
        resolution: res,
        dt,
        integrator,
        ..CantileverScene::default()
    }
}

/// The cantilever: static sag under gravity against beam theory, at a few resolutions
/// (nodes across the thickness); explicit at 1 ms, implicit at 60 Hz.
fn sag(quick: bool) -> Vec<Point> {
    let steps = Steps {
        dts: &[1.0e-3],
        implicit: &[1.0 / 60.0],
        fem: &[4.0e-3],
        midpoint: false,
    };
    sweep_with(
        SAG.key,
        if quick { &[3] } else { &[3, 5] },
        &steps,
        if quick { &[2] } else { &[2, 10] },
        |res, dt, subject, integrator| {
            let r = beam(res, dt, subject, integrator)
                .run()
                .expect("the cantilever scene builds");
            let e = r.sag_error.map(f64::abs);
            (r, e)
        },
    )
}

/// The cantilever released straight under its weight: its first bending frequency against
/// Euler–Bernoulli.
fn bending(quick: bool) -> Vec<Point> {
    let steps = Steps {
        dts: if quick {
            &[1.0 / 60.0]
        } else {
            &[1.0e-3, 1.0 / 60.0]
        },
        implicit: if quick {
            &[1.0 / 60.0]
        } else {
            &[1.0 / 120.0, 1.0 / 60.0]
        },
        fem: if quick {
            &[1.0 / 60.0]
        } else {
            &[4.0e-3, 1.0 / 60.0]
        },
        midpoint: false,
    };
    sweep_with(
        BENDING.key,
        if quick { &[3] } else { &[3, 5] },
        &steps,
        if quick { &[2] } else { &[2, 10] },
        |res, dt, subject, integrator| {
            let scene = CantileverScene {
                // Four periods of theory's 5.1 Hz.
                seconds: 0.8,
                ..beam(res, dt, subject, integrator)
            };
            let r = scene.ring().expect("the cantilever scene builds");
            let e = r
                .measured_frequency
                .zip(r.theory_frequency)
                .map(|(f, t)| (f / t - 1.0).abs());
            (r, e)
        },
    )
}

fn progress(what: &str) {
    eprintln!("[chart] {what}");
}

/// Who runs a sweep: every subject explicitly (rapier's bodies step their own way), and
/// sinew's models but centroid springs implicitly with each of `sweeps` (by backward Euler, and
/// with `midpoint` by the midpoint step too).
fn entrants(sweeps: &[usize], midpoint: bool) -> Vec<(Subject, Integrator, String)> {
    let mut out: Vec<_> = Subject::all()
        .into_iter()
        .map(|s| (s, Integrator::Explicit, s.name().to_string()))
        .collect();
    for &iterations in sweeps {
        for s in Subject::all() {
            if matches!(s, Subject::Sinew(m) if m != ElementModel::CentroidSprings) {
                let label = format!("{} implicit {iterations}", s.name());
                out.push((s, Integrator::Implicit { iterations }, label));
                if midpoint {
                    let label = format!("{} midpoint {iterations}", s.name());
                    out.push((s, Integrator::Midpoint { iterations }, label));
                }
            }
        }
    }
    out
}

/// The steps a sweep takes: `dts` for explicit runs, `implicit` for the implicit step's, `fem`
/// for rapier's FEM bodies (seconds per simulated second below 4 ms).
struct Steps<'a> {
    dts: &'a [Real],
    implicit: &'a [Real],
    fem: &'a [Real],
    /// Whether the implicit entrants also run as `Integrator::Midpoint` (where the bounce or
    /// the ring is what the sweep measures).
    midpoint: bool,
}

impl Steps<'_> {
    fn of(&self, subject: Subject, integrator: Integrator) -> &[Real] {
        if subject.name().starts_with("rapier-fem") {
            self.fem
        } else if integrator == Integrator::Explicit {
            self.dts
        } else {
            self.implicit
        }
    }
}

/// Runs `trial(res, dt)` for every entrant at every resolution and step; one point each, the
/// trial's error as y.
fn sweep(
    metric: &'static str,
    resolutions: &[usize],
    steps: &Steps,
    sweeps: &[usize],
    trial: impl Fn(usize, Real) -> Trial,
) -> Vec<Point> {
    sweep_with(
        metric,
        resolutions,
        steps,
        sweeps,
        |res, dt, subject, integrator| {
            trial(res, dt)
                .measure(subject, integrator)
                .expect("the scene builds")
        },
    )
}

/// As [`sweep`], with `run(res, dt, subject, integrator)` giving the record and the error.
fn sweep_with(
    metric: &'static str,
    resolutions: &[usize],
    steps: &Steps,
    sweeps: &[usize],
    run: impl Fn(usize, Real, Subject, Integrator) -> (Record, Option<f64>),
) -> Vec<Point> {
    let mut out = Vec::new();
    for (subject, integrator, label) in entrants(sweeps, steps.midpoint) {
        for &res in resolutions {
            for &dt in steps.of(subject, integrator) {
                progress(&format!("{metric} {label} res {res} dt {dt}"));
                let (r, error) = run(res, dt, subject, integrator);
                out.push(Point {
                    metric,
                    model: label.clone(),
                    res,
                    dt: dt as f64,
                    cost: r.wall_per_sim_s(),
                    error: error.unwrap_or(f64::NAN),
                    failed: r.failure.clone(),
                });
            }
        }
    }
    out
}

/// The fall: every model's centre-of-mass trajectory against the common `reference`.
fn fall(quick: bool, reference: &FallReference) -> Vec<Point> {
    let (resolutions, dts): (&[usize], &[Real]) = if quick {
        (&[3, 4], &[2.0e-3, 4.0e-3])
    } else {
        (
            &[3, 5, 7],
            &[1.0e-3, 2.0e-3, 4.0e-3, 8.0e-3, 1.0 / 60.0, 1.0 / 30.0],
        )
    };
    let steps = Steps {
        dts,
        implicit: if quick {
            &[1.0 / 60.0]
        } else {
            &[1.0 / 120.0, 1.0 / 60.0, 1.0 / 30.0]
        },
        fem: if quick {
            &[1.0 / 60.0]
        } else {
            &[4.0e-3, 8.0e-3, 1.0 / 60.0, 1.0 / 30.0]
        },
        midpoint: true,
    };
    let sweeps: &[usize] = if quick { &[2] } else { &[2, 10] };
    sweep(FALL.key, resolutions, &steps, sweeps, |res, dt| {
        Trial::fall(res, dt, Some(reference.clone()))
    })
}

/// The reference's own convergence as a markdown table.
fn reference_table(reference: &FallReference) -> String {
    let mut s = format!(
        "The reference is {} on the same cube, material, friction and restitution, sampled \
         every {} s over {} s; its runs, each against the finest (the last):\n\n\
         | res | dt (ms) | wall s / sim s (two at once) | bounce apex (m) | error vs finest |\n\
         |---|---|---|---|---|\n",
        reference.model, reference.every, reference.seconds
    );
    for (r, e) in reference.convergence(1.0) {
        let _ = writeln!(
            s,
            "| {} | {:.2} | {:.1} | {} | {:.2e} |",
            r.resolution,
            r.dt * 1e3,
            r.wall_per_sim_s,
            r.apex.map_or("-".into(), |a| format!("{a:.3}")),
            e
        );
    }
    s
}

/// The crush: a 10 kg press on the fall cube, held, lifted; the volume under the load against
/// linear elasticity, the shape after recovery against the rest shape.
fn crush(quick: bool) -> Vec<Point> {
    let (resolutions, dts): (&[usize], &[Real]) = if quick {
        (&[3], &[2.0e-3])
    } else {
        (&[3, 5, 7], &[2.0e-3, 4.0e-3, 1.0 / 60.0, 1.0 / 30.0])
    };
    let steps = Steps {
        dts,
        implicit: if quick {
            &[1.0 / 60.0]
        } else {
            &[1.0 / 60.0, 1.0 / 30.0]
        },
        fem: if quick {
            &[1.0 / 60.0]
        } else {
            &[1.0 / 60.0, 1.0 / 30.0]
        },
        midpoint: false,
    };
    let sweeps: &[usize] = if quick { &[2] } else { &[2, 10] };
    let mass: Real = 10.0;
    let mut out = Vec::new();
    for (subject, integrator, label) in entrants(sweeps, steps.midpoint) {
        for &res in resolutions {
            for &dt in steps.of(subject, integrator) {
                progress(&format!("crush {label} res {res} dt {dt}"));
                let trial = Trial::crush(res, dt, mass);
                let Trial::Crush(scene) = &trial else {
                    unreachable!()
                };
                let cube = scene.cube;
                let (r, shape) = trial
                    .measure(subject, integrator)
                    .expect("the crush scene builds");
                let stress = mass * 9.81 / (cube.size * cube.size);
                let theory =
                    uniaxial_volume_change(stress, cube.young_modulus, cube.poisson_ratio) as f64;
                let base = Point {
                    metric: CRUSH_SHAPE.key,
                    model: label.clone(),
                    res,
                    dt: dt as f64,
                    cost: r.wall_per_sim_s(),
                    error: shape.unwrap_or(f64::NAN),
                    failed: r.failure.clone(),
                };
                let volume = r
                    .loaded_volume_ratio
                    .map_or(f64::NAN, |v| (v - 1.0 - theory).abs());
                out.push(Point {
                    metric: CRUSH_VOLUME.key,
                    error: volume,
                    ..base.clone()
                });
                out.push(base);
            }
        }
    }
    out
}

/// The heavy crush (1000 kg, a load near E on the cube's top) and the limb bent to 110°:
/// every model under both integrators, down to game steps — the runs `scenes advise` picks
/// from.
fn heavy(quick: bool) -> (Vec<Point>, Vec<Point>) {
    let dts: &[Real] = if quick {
        &[1.0 / 60.0]
    } else {
        &[1.0e-2, 1.0 / 60.0, 1.0 / 30.0]
    };
    let steps = Steps {
        dts,
        implicit: dts,
        fem: if quick {
            &[1.0 / 60.0]
        } else {
            &[1.0 / 60.0, 1.0 / 30.0]
        },
        midpoint: false,
    };
    let sweeps: &[usize] = if quick { &[2] } else { &[2, 10] };
    let crush = sweep(
        CRUSH_HEAVY.key,
        if quick { &[3] } else { &[3, 5] },
        &steps,
        sweeps,
        |res, dt| Trial::crush(res, dt, 1000.0),
    );
    // The limb's "resolution" is its nodes along it (spacing 2 m / (n − 1)).
    let limb = sweep(
        LIMB.key,
        &[if quick { 11 } else { 21 }],
        &steps,
        sweeps,
        |n, dt| Trial::limb(2.0 / (n - 1) as Real, dt),
    );
    (crush, limb)
}

/// The free bar's ringing: its first axial frequency against beam theory and its decay
/// against the damping ratio asked for (two charts from the same runs).
fn vibration(quick: bool) -> (Vec<Point>, Vec<Point>) {
    let dts: &[Real] = if quick {
        &[1.0 / 60.0]
    } else {
        &[1.0e-3, 4.0e-3, 1.0 / 60.0, 1.0 / 30.0]
    };
    let steps = Steps {
        dts,
        implicit: if quick {
            &[1.0 / 60.0]
        } else {
            &[1.0 / 60.0, 1.0 / 30.0]
        },
        fem: if quick {
            &[1.0 / 60.0]
        } else {
            &[4.0e-3, 1.0 / 60.0, 1.0 / 30.0]
        },
        midpoint: true,
    };
    let sweeps: &[usize] = if quick { &[2] } else { &[2, 10] };
    let damping = std::cell::RefCell::new(Vec::new());
    let frequency = sweep_with(
        FREQUENCY.key,
        if quick { &[2] } else { &[2, 3, 4] },
        &steps,
        sweeps,
        |res, dt, subject, integrator| {
            let scene = VibrationScene {
                subject,
                resolution: res,
                dt,
                integrator,
                ..VibrationScene::default()
            };
            let r = scene.run().expect("the bar builds");
            let asked = scene.damping_ratio as f64;
            damping
                .borrow_mut()
                .push(r.measured_damping_ratio.map(|z| (z / asked - 1.0).abs()));
            let e = r
                .measured_frequency
                .zip(r.theory_frequency)
                .map(|(f, t)| (f / t - 1.0).abs());
            (r, e)
        },
    );
    let damping: Vec<Point> = frequency
        .iter()
        .zip(damping.into_inner())
        .map(|(p, e)| Point {
            metric: DAMPING.key,
            error: e.unwrap_or(f64::NAN),
            ..p.clone()
        })
        .collect();
    (frequency, damping)
}

/// The bar pulled 2 %: Poisson's ratio measured against the one asked for (0.3). Its
/// resolution is the nodes across the 1 m bar.
fn stretch(quick: bool) -> (Vec<Point>, Vec<Point>) {
    let dts: &[Real] = &[1.0 / 60.0, 1.0 / 30.0];
    let steps = Steps {
        dts,
        implicit: dts,
        fem: dts,
        midpoint: false,
    };
    let sweeps: &[usize] = if quick { &[2] } else { &[2, 10] };
    let young = std::cell::RefCell::new(Vec::new());
    let poisson = sweep_with(
        STRETCH.key,
        if quick { &[3] } else { &[3, 5] },
        &steps,
        sweeps,
        |res, dt, subject, integrator| {
            let scene = StretchScene {
                subject,
                spacing: 1.0 / (res - 1) as Real,
                dt,
                integrator,
                ..StretchScene::default()
            };
            let r = scene.run().expect("the bar builds");
            let asked = scene.young_modulus as f64;
            young
                .borrow_mut()
                .push(r.measured_young_modulus.map(|e| (e / asked - 1.0).abs()));
            let asked = scene.poisson_ratio as f64;
            let e = r.measured_poisson.map(|nu| (nu - asked).abs());
            (r, e)
        },
    );
    // Rapier's soft bodies expose no node forces: no tension, no point.
    let young: Vec<Point> = poisson
        .iter()
        .zip(young.into_inner())
        .filter(|(p, _)| !p.model.starts_with("rapier"))
        .map(|(p, e)| Point {
            metric: YOUNG.key,
            error: e.unwrap_or(f64::NAN),
            ..p.clone()
        })
        .collect();
    (poisson, young)
}

/// The rotation-error drop for each of the shape-based element's fits, at several steps per
/// period (a sinew-only metric: rapier's models have no rotation fit to measure).
fn rotation(quick: bool) -> Vec<Point> {
    let divisions: &[Real] = if quick {
        &[10.0]
    } else {
        &[10.0, 20.0, 50.0, 100.0]
    };
    let fits = [
        RotationFit::Iterative(1),
        RotationFit::Iterative(2),
        RotationFit::Iterative(3),
        RotationFit::Polar,
    ];
    let mut out = Vec::new();
    for fit in fits {
        for &d in divisions {
            let scene = RotationErrorScene {
                fit,
                divisions: d,
                seconds: if quick { 1.0 } else { 3.0 },
                ..RotationErrorScene::default()
            };
            let model = Subject::Sinew(ElementModel::ShapeMatching {
                fit,
                damping: ShapeDamping::RigidMotion,
            });
            let name = format!(
                "{} ({})",
                model.name(),
                model.iterations().unwrap_or_default()
            );
            progress(&format!("rotation {name} divisions {d}"));
            let r = scene.run().expect("the rotation scene builds");
            out.push(Point {
                metric: ROTATION.key,
                model: name,
                res: 2,
                dt: scene.dt() as f64,
                cost: r.wall_per_sim_s(),
                error: r.spurious.map_or(f64::NAN, |s| s.mean),
                failed: r.failure.clone(),
            });
        }
    }
    out
}

/// Points that are finite, positive and from runs that did not fail.
fn plottable(points: &[Point]) -> Vec<&Point> {
    points
        .iter()
        .filter(|p| p.failed.is_none() && p.cost.is_finite() && p.cost > 0.0 && p.error.is_finite())
        .collect()
}

fn draw(metric: &Metric, points: &[Point], path: &Path) -> Result<(), Box<dyn std::error::Error>> {
    let pts = plottable(points);
    if pts.is_empty() {
        return Ok(());
    }
    // Errors of exactly zero (the polar fit at the float floor can be) sit on the floor.
    let floor = pts
        .iter()
        .map(|p| p.error)
        .filter(|e| *e > 0.0)
        .fold(f64::INFINITY, f64::min);
    let y_of = |e: f64| e.max(floor);
    let (x0, x1) = pts.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| {
        (a.min(p.cost), b.max(p.cost))
    });
    let (y0, y1) = pts.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| {
        (a.min(y_of(p.error)), b.max(y_of(p.error)))
    });
    let root = SVGBackend::new(path, (1100, 600)).into_drawing_area();
    root.fill(&WHITE)?;
    // The legend has a column of its own: over the plot it would hide points.
    let (plot, side) = root.split_horizontally(880);
    let mut chart = ChartBuilder::on(&plot)
        .caption(metric.title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (x0 / 1.5..x1 * 1.5).log_scale(),
            (y0 / 2.0..y1 * 2.0).log_scale(),
        )?;
    chart
        .configure_mesh()
        .light_line_style(WHITE)
        .x_desc("wall seconds per simulated second (one core)")
        .y_desc(metric.y)
        .x_label_formatter(&|x| format!("{x:.0e}"))
        .y_label_formatter(&|y| format!("{y:.0e}"))
        .draw()?;
    let mut models: Vec<&str> = pts.iter().map(|p| p.model.as_str()).collect();
    models.dedup();
    models.sort();
    models.dedup();
    for (k, model) in models.iter().enumerate() {
        let color = Palette99::pick(k).to_rgba();
        let rapier = model.starts_with("rapier");
        let marker = move |(x, y): (f64, f64)| {
            if rapier {
                TriangleMarker::new((x, y), 6, color.filled()).into_dyn()
            } else {
                Circle::new((x, y), 5, color.filled()).into_dyn()
            }
        };
        chart.draw_series(
            pts.iter()
                .filter(|p| p.model == *model)
                .map(|p| marker((p.cost, y_of(p.error)))),
        )?;
        let y = 60 + 20 * k as i32;
        let legend_marker = if rapier {
            TriangleMarker::new((12, y), 6, color.filled()).into_dyn()
        } else {
            Circle::new((12, y), 5, color.filled()).into_dyn()
        };
        side.draw(&legend_marker)?;
        side.draw(&Text::new(
            model.to_string(),
            (26, y - 7),
            ("sans-serif", 13).into_font(),
        ))?;
    }
    root.present()?;
    Ok(())
}

/// The Pareto-best points: no other point is both cheaper and more accurate.
fn pareto(points: &[Point]) -> Vec<&Point> {
    let mut pts = plottable(points);
    pts.sort_by(|a, b| a.cost.total_cmp(&b.cost));
    let mut best = f64::INFINITY;
    let mut out = Vec::new();
    for p in pts {
        if p.error < best {
            best = p.error;
            out.push(p);
        }
    }
    out
}

fn table(points: &[Point]) -> String {
    let mut s =
        String::from("| model | res | dt (ms) | wall s / sim s | error |\n|---|---|---|---|---|\n");
    for p in pareto(points) {
        let _ = writeln!(
            s,
            "| {} | {} | {:.2} | {:.3} | {:.2e} |",
            p.model,
            p.res,
            p.dt * 1e3,
            p.cost,
            p.error
        );
    }
    s
}

/// Failed runs of a metric, one line each.
fn failures(points: &[Point]) -> String {
    let mut s = String::new();
    for p in points.iter().filter(|p| p.failed.is_some()) {
        let _ = writeln!(
            s,
            "- {} res {} dt {:.2} ms: {}",
            p.model,
            p.res,
            p.dt * 1e3,
            p.failed.as_deref().unwrap_or("")
        );
    }
    if s.is_empty() {
        s.push_str("- none\n");
    }
    s
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = Args::parse();
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(if args.quick { "target" } else { "docs" }));
    let charts = out.join("charts");
    std::fs::create_dir_all(&charts)?;
    let wanted = |name: &str| args.only.is_empty() || args.only.iter().any(|o| o == name);
    let fresh = args.fresh_reference && !args.only.iter().any(|o| o == "reference");

    let mut sections: Vec<(&Metric, Vec<Point>)> = Vec::new();
    let mut preamble = String::new();
    if args.only.iter().any(|o| o == "reference") {
        let reference = fall_reference(Path::new(FALL_REFERENCE_PATH), true)?;
        println!("{}", reference_table(&reference));
    }
    if args.redraw {
        let metrics = [
            &FALL,
            &CRUSH_SHAPE,
            &CRUSH_VOLUME,
            &CRUSH_HEAVY,
            &LIMB,
            &FREQUENCY,
            &DAMPING,
            &STRETCH,
            &YOUNG,
            &SAG,
            &BENDING,
            &ROTATION,
        ];
        let text = std::fs::read_to_string(charts.join("points.jsonl"))?;
        let mut points = Vec::new();
        for line in text.lines().filter(|l| !l.trim().is_empty()) {
            let v: serde_json::Value = serde_json::from_str(line)?;
            points.push(
                Point::from_json(&v, &metrics)
                    .ok_or_else(|| format!("points.jsonl: not a chart point: {line}"))?,
            );
        }
        for metric in metrics {
            let mine: Vec<Point> = points
                .iter()
                .filter(|p| p.metric == metric.key)
                .cloned()
                .collect();
            if !mine.is_empty() && wanted(metric.group) {
                if metric.key == FALL.key {
                    let reference = fall_reference(Path::new(FALL_REFERENCE_PATH), false)?;
                    preamble = reference_table(&reference);
                }
                sections.push((metric, mine));
            }
        }
    } else {
        run_sweeps(&args, &wanted, fresh, &mut sections, &mut preamble)?;
    }

    let mut jsonl = String::new();
    let mut doc = String::from(
        "# Accuracy against cost\n\nGenerated by `cargo run --release --example chart` \
         (3D, one core, release build): every point below and on the charts comes from that \
         one run. x is wall seconds per simulated second, y the metric's error; circles are \
         sinew's models, triangles rapier's soft bodies. Runs that failed (exploded, \
         inverted, sank) are not plotted and are listed under each chart.\n\n",
    );
    let mut readme_tables = String::new();
    for (metric, points) in &sections {
        for p in points {
            jsonl.push_str(&p.json().to_string());
            jsonl.push('\n');
        }
        let svg = charts.join(format!("{}.svg", metric.key));
        draw(metric, points, &svg)?;
        let t = table(points);
        let _ = write!(readme_tables, "**{}**\n\n{}\n", metric.title, t);
        let _ = write!(
            doc,
            "## {}\n\n{}![{}](charts/{}.svg)\n\nPareto-best points (no other point is both \
             cheaper and more accurate):\n\n{}\nFailed runs:\n\n{}\n",
            metric.title,
            if metric.key == FALL.key {
                format!("{preamble}\n")
            } else {
                String::new()
            },
            metric.key,
            metric.key,
            t,
            failures(points)
        );
        println!("{}\n{}", metric.title, t);
    }
    // A part of the sweeps does not overwrite the docs' record of a whole run (it draws its
    // charts and prints its tables); a redraw keeps the run's points as they are.
    if !args.only.is_empty() && args.out.is_none() {
        eprintln!("--only without --out: points.jsonl and ACCURACY.md left as they were");
    } else {
        if !args.redraw {
            std::fs::write(charts.join("points.jsonl"), jsonl)?;
        }
        std::fs::write(out.join("ACCURACY.md"), doc)?;
    }
    if args.out.is_none() && !args.quick && args.only.is_empty() {
        refresh_readme(&readme_tables)?;
    }
    Ok(())
}

/// Runs the wanted sweeps, each a section of the charts (the fall's with its reference's
/// table as `preamble`).
fn run_sweeps(
    args: &Args,
    wanted: &dyn Fn(&str) -> bool,
    fresh: bool,
    sections: &mut Vec<(&'static Metric, Vec<Point>)>,
    preamble: &mut String,
) -> Result<(), Box<dyn std::error::Error>> {
    if wanted("fall") {
        let reference = fall_reference(Path::new(FALL_REFERENCE_PATH), fresh)?;
        *preamble = reference_table(&reference);
        sections.push((&FALL, fall(args.quick, &reference)));
    }
    if wanted("crush") {
        let points = crush(args.quick);
        let (volume, shape): (Vec<Point>, Vec<Point>) = points
            .into_iter()
            .partition(|p| p.metric == CRUSH_VOLUME.key);
        sections.push((&CRUSH_SHAPE, shape));
        sections.push((&CRUSH_VOLUME, volume));
    }
    if wanted("heavy") {
        let (crush, limb) = heavy(args.quick);
        sections.push((&CRUSH_HEAVY, crush));
        sections.push((&LIMB, limb));
    }
    if wanted("vibration") {
        let (frequency, damping) = vibration(args.quick);
        sections.push((&FREQUENCY, frequency));
        sections.push((&DAMPING, damping));
    }
    if wanted("stretch") {
        let (poisson, young) = stretch(args.quick);
        sections.push((&STRETCH, poisson));
        sections.push((&YOUNG, young));
    }
    if wanted("sag") {
        sections.push((&SAG, sag(args.quick)));
        sections.push((&BENDING, bending(args.quick)));
    }
    if wanted("rotation") {
        sections.push((&ROTATION, rotation(args.quick)));
    }

    Ok(())
}

/// Replaces `docs/PERFORMANCE.md`'s text between `<!-- chart:pareto:start -->` and
/// `<!-- chart:pareto:end -->` with this run's Pareto tables, one per chart.
fn refresh_readme(table: &str) -> Result<(), Box<dyn std::error::Error>> {
    let (start, end) = ("<!-- chart:pareto:start -->", "<!-- chart:pareto:end -->");
    let page = "docs/PERFORMANCE.md";
    let readme = std::fs::read_to_string(page)?;
    let (Some(a), Some(b)) = (readme.find(start), readme.find(end)) else {
        eprintln!("{page} has no chart:pareto markers; not updated");
        return Ok(());
    };
    let updated = format!(
        "{}{}\n{}{}",
        &readme[..a + start.len()],
        "",
        table,
        &readme[b..]
    );
    std::fs::write(page, updated)?;
    Ok(())
}
