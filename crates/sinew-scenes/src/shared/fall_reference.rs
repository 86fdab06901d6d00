//! The fall's common reference (issue 17): one converged trajectory of the [`FallScene`] cube
//! that every model's fall is measured against, computed by a model that is not under test.
//!
//! A model's error against its *own* converged run says how far it is from where it
//! converges, not whether it converges to the right motion; it also cannot rank the models
//! against each other. The reference here is a continuum: rapier 0.36's implicit FEM with
//! stable Neo-Hookean cells (feature `fem`) at a fine lattice and a short step, the same
//! cube, material, friction and restitution as every model's run. Its own convergence is kept
//! with it: the same model at coarser resolutions and longer steps, each against the finest.

use std::time::Instant;

use serde_json::{json, Value};

use super::super::lib::math::{Real, Vector, DIM};
use super::super::lib::BuildError;
use super::fall::FallScene;
use super::metrics::trajectory_error;
use super::subject::Subject;

/// One run of the reference model.
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceRun {
    /// Nodes per edge.
    pub resolution: usize,
    /// Step length, s.
    pub dt: Real,
    /// Wall seconds per simulated second (the runs share the machine's cores).
    pub wall_per_sim_s: f64,
    /// Highest centre of mass after the first impact, m.
    pub apex: Option<f64>,
    /// Why the run failed, if it did.
    pub failure: Option<String>,
    /// The centre of mass every [`FallReference::every`] seconds.
    pub samples: Vec<Vector>,
}

/// The fall's reference: runs of one model, the last the finest.
#[derive(Clone, Debug, PartialEq)]
pub struct FallReference {
    /// The reference model's name.
    pub model: String,
    /// Sampling period of the trajectories, s.
    pub every: Real,
    /// The scene's duration, s.
    pub seconds: Real,
    /// The runs, coarsest first; the last is the reference.
    pub runs: Vec<ReferenceRun>,
}

/// Where `scenes` and `chart` keep the reference, relative to the repository's root.
pub const FALL_REFERENCE_PATH: &str = "docs/charts/fall-reference.json";

impl FallReference {
    /// Runs `scene` with `subject` at each `(resolution, dt)` of `grid` (the finest last) on
    /// `threads` threads, sampling the centre of mass every `every` seconds.
    pub fn compute(
        scene: &FallScene,
        subject: Subject,
        grid: &[(usize, Real)],
        every: Real,
        threads: usize,
        progress: impl Fn(&str) + Sync,
    ) -> Result<FallReference, BuildError> {
        let next = std::sync::atomic::AtomicUsize::new(0);
        let results = std::sync::Mutex::new(vec![None; grid.len()]);
        // The costliest runs first, so that the threads end together.
        let mut order: Vec<usize> = (0..grid.len()).collect();
        order.sort_by(|&a, &b| {
            let cost = |i: usize| (grid[i].0 as f64).powi(DIM as i32 + 1) / grid[i].1 as f64;
            cost(b).total_cmp(&cost(a))
        });
        std::thread::scope(|s| {
            for _ in 0..threads.max(1) {
                s.spawn(|| loop {
                    let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(&i) = order.get(k) else { break };
                    let (resolution, dt) = grid[i];
                    progress(&format!(
                        "fall reference {} res {resolution} dt {dt}",
                        subject.name()
                    ));
                    let run = FallScene {
                        subject,
                        resolution,
                        dt,
                        ..*scene
                    };
                    let start = Instant::now();
                    let result = run.run_sampled(every).map(|(r, samples)| ReferenceRun {
                        resolution,
                        dt,
                        wall_per_sim_s: start.elapsed().as_secs_f64() / r.sim_s.max(1e-9),
                        apex: r.bounce_apex_com,
                        failure: r.failure.clone(),
                        samples,
                    });
                    results.lock().unwrap()[i] = Some(result);
                });
            }
        });
        let runs = results
            .into_inner()
            .unwrap()
            .into_iter()
            .map(|r| r.expect("every run was taken"))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(FallReference {
            model: subject.name().to_string(),
            every,
            seconds: scene.seconds,
            runs,
        })
    }

    /// The reference trajectory: the finest run's.
    pub fn trajectory(&self) -> &[Vector] {
        self.runs.last().map_or(&[], |r| &r.samples)
    }

    /// Each run's trajectory error against the finest (the last is 0), over `size`.
    pub fn convergence(&self, size: Real) -> Vec<(&ReferenceRun, Real)> {
        self.runs
            .iter()
            .map(|r| (r, trajectory_error(&r.samples, self.trajectory(), size)))
            .collect()
    }

    /// As JSON.
    pub fn to_json(&self) -> Value {
        let runs: Vec<Value> = self
            .runs
            .iter()
            .map(|r| {
                json!({
                    "resolution": r.resolution,
                    "dt": r.dt,
                    "wall_per_sim_s": r.wall_per_sim_s,
                    "apex": r.apex,
                    "failure": r.failure,
                    "samples": r.samples.iter().map(|v| v.to_array().to_vec()).collect::<Vec<_>>(),
                })
            })
            .collect();
        json!({
            "model": self.model,
            "dim": DIM,
            "every": self.every,
            "seconds": self.seconds,
            "runs": runs,
        })
    }

    /// From [`FallReference::to_json`]'s JSON; `None` when it is not one (or of the other
    /// dimension).
    pub fn from_json(v: &Value) -> Option<FallReference> {
        if v["dim"].as_u64()? as usize != DIM {
            return None;
        }
        let runs = v["runs"]
            .as_array()?
            .iter()
            .map(|r| {
                let samples = r["samples"]
                    .as_array()?
                    .iter()
                    .map(|s| {
                        let c: Vec<Real> = s
                            .as_array()?
                            .iter()
                            .map(|x| x.as_f64().map(|x| x as Real))
                            .collect::<Option<_>>()?;
                        (c.len() == DIM).then(|| Vector::from_slice(&c))
                    })
                    .collect::<Option<Vec<_>>>()?;
                Some(ReferenceRun {
                    resolution: r["resolution"].as_u64()? as usize,
                    dt: r["dt"].as_f64()? as Real,
                    wall_per_sim_s: r["wall_per_sim_s"].as_f64()?,
                    apex: r["apex"].as_f64(),
                    failure: r["failure"].as_str().map(str::to_string),
                    samples,
                })
            })
            .collect::<Option<Vec<_>>>()?;
        let (every, seconds) = (v["every"].as_f64()? as Real, v["seconds"].as_f64()? as Real);
        let positive = |x: Real| x.is_finite() && x > 0.0;
        (!runs.is_empty() && positive(every) && positive(seconds)).then(|| FallReference {
            model: v["model"].as_str().unwrap_or_default().to_string(),
            every,
            seconds,
            runs,
        })
    }

    /// Reads the reference written at `path`.
    pub fn load(path: &std::path::Path) -> Result<FallReference, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let v: Value =
            serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
        FallReference::from_json(&v)
            .ok_or_else(|| format!("{}: not a {DIM}D fall reference", path.display()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(resolution: usize, offset: Real) -> ReferenceRun {
        ReferenceRun {
            resolution,
            dt: 1e-3,
            wall_per_sim_s: 1.0,
            apex: Some(1.0),
            failure: None,
            samples: (0..10).map(|k| Vector::splat(k as Real + offset)).collect(),
        }
    }

    #[test]
    fn it_round_trips_through_json_and_measures_convergence_against_the_finest() {
        let r = FallReference {
            model: "m".into(),
            every: 0.01,
            seconds: 0.1,
            runs: vec![run(3, 0.5), run(5, 0.0)],
        };
        let back = FallReference::from_json(&r.to_json()).unwrap();
        assert_eq!(back, r);
        let c = r.convergence(1.0);
        // Every sample of the coarse run is off by 0.5 in each coordinate.
        let expected = (DIM as Real).sqrt() * 0.5;
        assert!((c[0].1 - expected).abs() < 1e-6, "{}", c[0].1);
        assert_eq!(c[1].1, 0.0);
        assert!(FallReference::from_json(&json!({"dim": DIM, "runs": []})).is_none());
    }
}
