//! Speed against accuracy: runs the accuracy sweeps for every model (sinew's and rapier's soft
//! bodies, 3D) and charts cost (wall seconds per simulated second, log) against error (log),
//! one chart per metric, one series per model, points over dt and resolution.
//!
//! ```text
//! cargo run --release --example chart              # all sweeps (~15 min), writes docs/
//! cargo run --release --example chart -- --quick   # fewer points, into target/charts
//! cargo run --release --example chart -- --only fall --out /tmp/charts
//! ```
//!
//! Writes `<out>/charts/<metric>.svg`, every point as JSON lines in
//! `<out>/charts/points.jsonl`, and `<out>/ACCURACY.md` (the Pareto-best points per metric and
//! the commands); with the default `--out docs` it also refreshes the Pareto table in
//! `README.md` between its `chart:pareto` markers. Every point comes from this run.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use clap::Parser;
use plotters::prelude::*;
use serde_json::json;
use sinew::dim3::math::Real;
use sinew::dim3::{ElementModel, Integrator, RotationFit, ShapeDamping};
use sinew_scenes::dim3::metrics::{trajectory_error, uniaxial_volume_change};
use sinew_scenes::dim3::{CantileverScene, CrushScene, FallScene, RotationErrorScene, Subject};

#[derive(Parser, Debug)]
#[command(about = "Charts cost against error for every model")]
struct Args {
    /// Fewer, cheaper points (a smoke run; not for docs).
    #[arg(long)]
    quick: bool,
    /// Output folder (charts go to <out>/charts).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Only these metrics: fall, crush, sag, rotation.
    #[arg(long, num_args = 1..)]
    only: Vec<String>,
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
}

/// A chart's axis text.
struct Metric {
    key: &'static str,
    title: &'static str,
    y: &'static str,
}

const FALL: Metric = Metric {
    key: "fall-trajectory",
    title: "fall: centre-of-mass trajectory error vs the same model at res 9, dt 0.5 ms",
    y: "RMS error / size",
};
const CRUSH_SHAPE: Metric = Metric {
    key: "crush-shape",
    title: "crush 10 kg and release: shape error after recovery",
    y: "shape error / size",
};
const CRUSH_VOLUME: Metric = Metric {
    key: "crush-volume",
    title: "static load 10 kg: |ΔV/V − (−(1−2ν)σ/E)|",
    y: "volume error",
};
const ROTATION: Metric = Metric {
    key: "rotation",
    title: "rotation-error drop (k/m 1e4): spurious angular acceleration",
    y: "mean spurious acceleration, rad/s²",
};

const SAG: Metric = Metric {
    key: "cantilever-sag",
    title: "cantilever (10:1, clamped by a bone): |static tip sag / Euler-Bernoulli − 1|",
    y: "relative sag error",
};

/// The cantilever: static sag under gravity against beam theory, at a few resolutions
/// (nodes across the thickness).
fn sag(quick: bool) -> Vec<Point> {
    let resolutions: &[usize] = if quick { &[3] } else { &[3, 5] };
    let mut out = Vec::new();
    for subject in Subject::all() {
        for &res in resolutions {
            progress(&format!("cantilever {} res {res}", subject.name()));
            let scene = CantileverScene {
                subject,
                resolution: res,
                ..CantileverScene::default()
            };
            let r = scene.run().expect("the cantilever scene builds");
            out.push(Point {
                metric: SAG.key,
                model: subject.name().to_string(),
                res,
                dt: scene.dt as f64,
                cost: r.wall_per_sim_s(),
                error: r.sag_error.map_or(f64::NAN, f64::abs),
                failed: r.failure.clone(),
            });
        }
    }
    out
}

fn progress(what: &str) {
    eprintln!("[chart] {what}");
}

/// The fall sweep: each subject at each (res, dt), its centre-of-mass trajectory against the
/// subject's own finest run.
fn fall(quick: bool) -> Vec<Point> {
    // The reference: finer than every point, in resolution and in dt.
    let (resolutions, dts, seconds, fine_res, fine_dt): (&[usize], &[Real], Real, usize, Real) =
        if quick {
            (&[3, 4], &[2.0e-3, 4.0e-3], 1.0, 5, 1.0e-3)
        } else {
            (
                &[3, 5, 7],
                &[1.0e-3, 2.0e-3, 4.0e-3, 8.0e-3, 1.0 / 60.0, 1.0 / 30.0],
                1.5,
                9,
                0.5e-3,
            )
        };
    // The implicit step's points: game frame rates, a cheap and a converging sweep count.
    let (implicit_dts, sweeps): (&[Real], &[usize]) = if quick {
        (&[1.0 / 60.0], &[2])
    } else {
        (&[1.0 / 120.0, 1.0 / 60.0, 1.0 / 30.0], &[2, 10])
    };
    let every: Real = 0.01;
    let mut out = Vec::new();
    for subject in Subject::all() {
        let run = |res: usize, dt: Real, integrator: Integrator| {
            let scene = FallScene {
                subject,
                resolution: res,
                dt,
                seconds,
                integrator,
                ..FallScene::default()
            };
            scene.run_sampled(every).expect("the fall scene builds")
        };
        progress(&format!("fall {} reference", subject.name()));
        let (reference_record, reference) = run(fine_res, fine_dt, Integrator::Explicit);
        // Explicit runs (rapier's bodies are their own), then the implicit step's.
        let mut runs: Vec<(usize, Real, Integrator, String)> = Vec::new();
        for &res in resolutions {
            for &dt in dts {
                runs.push((res, dt, Integrator::Explicit, subject.name().to_string()));
            }
        }
        if matches!(
            subject,
            Subject::Sinew(ElementModel::EdgeRepulsion | ElementModel::ShapeMatching { .. })
        ) {
            for &iterations in sweeps {
                for &res in resolutions {
                    for &dt in implicit_dts {
                        let label = format!("{} implicit {iterations}", subject.name());
                        runs.push((res, dt, Integrator::Implicit { iterations }, label));
                    }
                }
            }
        }
        for (res, dt, integrator, label) in runs {
            {
                progress(&format!("fall {label} res {res} dt {dt}"));
                let (r, samples) = run(res, dt, integrator);
                let failed = r.failure.clone().or_else(|| {
                    reference_record
                        .failure
                        .clone()
                        .map(|f| format!("reference: {f}"))
                });
                out.push(Point {
                    metric: FALL.key,
                    model: label,
                    res,
                    dt: dt as f64,
                    cost: r.wall_per_sim_s(),
                    error: trajectory_error(&samples, &reference, 1.0) as f64,
                    failed,
                });
            }
        }
    }
    out
}

/// The crush sweep: a 10 kg press on the fall cube, held, lifted; the volume under the load
/// against linear elasticity, the shape after recovery against the rest shape.
fn crush(quick: bool) -> Vec<Point> {
    let (resolutions, dts): (&[usize], &[Real]) = if quick {
        (&[3], &[2.0e-3])
    } else {
        (&[3, 5, 7], &[1.0e-3, 2.0e-3, 4.0e-3])
    };
    let mass: Real = 10.0;
    let mut out = Vec::new();
    for subject in Subject::all() {
        for &res in resolutions {
            for &dt in dts {
                progress(&format!("crush {} res {res} dt {dt}", subject.name()));
                let cube = FallScene {
                    subject,
                    resolution: res,
                    dt,
                    ..FallScene::default()
                };
                let scene = CrushScene {
                    cube,
                    mass,
                    settle: 0.5,
                    ramp: 0.5,
                    hold: 1.5,
                    lift: 0.5,
                    recover: if quick { 0.5 } else { 1.0 },
                    guided: true,
                };
                let r = scene.run().expect("the crush scene builds");
                let stress = mass * 9.81 / (cube.size * cube.size);
                let theory =
                    uniaxial_volume_change(stress, cube.young_modulus, cube.poisson_ratio) as f64;
                let base = Point {
                    metric: CRUSH_SHAPE.key,
                    model: subject.name().to_string(),
                    res,
                    dt: dt as f64,
                    cost: r.wall_per_sim_s(),
                    error: r.shape_error.unwrap_or(f64::NAN),
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
    let root = SVGBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
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
        let series: Vec<(f64, f64)> = pts
            .iter()
            .filter(|p| p.model == *model)
            .map(|p| (p.cost, y_of(p.error)))
            .collect();
        let rapier = model.starts_with("rapier");
        chart
            .draw_series(series.iter().map(|&(x, y)| {
                if rapier {
                    TriangleMarker::new((x, y), 6, color.filled()).into_dyn()
                } else {
                    Circle::new((x, y), 5, color.filled()).into_dyn()
                }
            }))?
            .label(*model)
            .legend(move |(x, y)| Circle::new((x, y), 5, color.filled()));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()?;
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

    let mut sections: Vec<(&Metric, Vec<Point>)> = Vec::new();
    if wanted("fall") {
        sections.push((&FALL, fall(args.quick)));
    }
    if wanted("crush") {
        let points = crush(args.quick);
        let (volume, shape): (Vec<Point>, Vec<Point>) = points
            .into_iter()
            .partition(|p| p.metric == CRUSH_VOLUME.key);
        sections.push((&CRUSH_SHAPE, shape));
        sections.push((&CRUSH_VOLUME, volume));
    }
    if wanted("sag") {
        sections.push((&SAG, sag(args.quick)));
    }
    if wanted("rotation") {
        sections.push((&ROTATION, rotation(args.quick)));
    }

    let mut jsonl = String::new();
    let mut doc = String::from(
        "# Accuracy against cost\n\nGenerated by `cargo run --release --example chart` \
         (3D, one core, release build): every point below and on the charts comes from that \
         one run. x is wall seconds per simulated second, y the metric's error; circles are \
         sinew's models, triangles rapier's soft bodies. Runs that failed (exploded, \
         inverted, sank) are not plotted and are listed under each chart.\n\n",
    );
    let mut main_table = String::new();
    for (metric, points) in &sections {
        for p in points {
            jsonl.push_str(&p.json().to_string());
            jsonl.push('\n');
        }
        let svg = charts.join(format!("{}.svg", metric.key));
        draw(metric, points, &svg)?;
        let t = table(points);
        if metric.key == FALL.key {
            main_table = t.clone();
        }
        let _ = write!(
            doc,
            "## {}\n\n![{}](charts/{}.svg)\n\nPareto-best points (no other point is both \
             cheaper and more accurate):\n\n{}\nFailed runs:\n\n{}\n",
            metric.title,
            metric.key,
            metric.key,
            t,
            failures(points)
        );
        println!("{}\n{}", metric.title, t);
    }
    std::fs::write(charts.join("points.jsonl"), jsonl)?;
    std::fs::write(out.join("ACCURACY.md"), doc)?;
    if args.out.is_none() && !args.quick && !main_table.is_empty() {
        refresh_readme(&main_table)?;
    }
    Ok(())
}

/// Replaces the README's text between `<!-- chart:pareto:start -->` and
/// `<!-- chart:pareto:end -->` with this run's Pareto table of the fall sweep.
fn refresh_readme(table: &str) -> Result<(), Box<dyn std::error::Error>> {
    let (start, end) = ("<!-- chart:pareto:start -->", "<!-- chart:pareto:end -->");
    let readme = std::fs::read_to_string("README.md")?;
    let (Some(a), Some(b)) = (readme.find(start), readme.find(end)) else {
        eprintln!("README.md has no chart:pareto markers; not updated");
        return Ok(());
    };
    let updated = format!(
        "{}{}\n{}{}",
        &readme[..a + start.len()],
        "",
        table,
        &readme[b..]
    );
    std::fs::write("README.md", updated)?;
    Ok(())
}
