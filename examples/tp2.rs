// Probe: the tower, every 0.5 s: each cube's centre offset, max node speed, energy.
use sinew::dim2::math::{Real, Vector};
use sinew::dim2::*;
use sinew_scenes::dim2::{Subject, TowerScene};
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let model = a.get(1).map_or("er", |s| s.as_str());
    let dt: f64 = a.get(2).map_or(1.0 / 60.0, |s| s.parse().unwrap());
    let gap: f64 = a.get(3).map_or(0.1, |s| s.parse().unwrap());
    let integ = a.get(4).map_or("explicit", |s| s.as_str());
    let offset: f64 = a.get(5).map_or(0.03, |s| s.parse().unwrap());
    let scene = TowerScene {
        subject: Subject::Sinew(if model == "er" {
            ElementModel::EdgeRepulsion
        } else {
            ElementModel::SHAPE_MATCHING
        }),
        dt: dt as Real,
        gap: gap as Real,
        offset: offset as Real,
        integrator: if integ == "explicit" {
            Integrator::Explicit
        } else {
            Integrator::Implicit { iterations: 10 }
        },
        ..Default::default()
    };
    let mut next = 0.0;
    let r = scene
        .run_with(|w, _| {
            if w.time()
                > std::env::var("FROM")
                    .ok()
                    .and_then(|v| v.parse().ok())
                    .unwrap_or(4.0)
            {
                for (k, (_, b)) in w.deformables.iter().enumerate() {
                    let v = b.velocities();
                    let (i, s) = v
                        .iter()
                        .enumerate()
                        .map(|(i, v)| (i, v.length()))
                        .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
                    if s > 0.06 {
                        let x = b.positions()[i];
                        let _ = x;
                        println!("  t {:.3} cube {k} node {i} speed {:.3}", w.time(), s);
                    }
                }
            }
            if (w.time() as f64) + 1e-9 < next {
                return;
            }
            next += std::env::var("EVERY")
                .ok()
                .and_then(|v| v.parse().ok())
                .unwrap_or(0.5);
            let rep = w.report();
            let mut e = 0.0;
            let mut line = String::new();
            for (_, d) in rep.deformables.iter() {
                e += (d.kinetic_energy + d.elastic_energy + d.gravity_energy) as f64;
            }
            for (_, b) in w.deformables.iter() {
                let x = b.positions();
                let v = b.velocities();
                let n = x.len() as f64;
                let c = x.iter().fold(Vector::ZERO, |s, p| s + *p) / n as Real;
                let vmax = v.iter().map(|v| v.length()).fold(0.0, Real::max);
                line += &format!(
                    " [{:+.0} {:+.0} {:.0}{}]",
                    c.x * 1000.0,
                    0.0,
                    vmax * 1000.0,
                    if b.is_sleeping() { "z" } else { "" }
                );
            }
            println!("t {:.1} E {e:.1}{line}", w.time());
        })
        .unwrap();
    println!(
        "scatter {:?} top {:?} asleep {:?}",
        r.scatter, r.top_height_ratio, r.asleep
    );
}
