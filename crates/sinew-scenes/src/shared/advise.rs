//! The cheapest model that passes (issue 17): given a scene — its mesh, material, dt and the
//! load it will see — run every sinew model under each integrator through it and recommend the
//! cheapest whose run stays inside the error and stability bounds.
//!
//! "Model no more than a scene needs": the answer depends on the scene. A fall at 60 Hz, a limb
//! bent to 110° and a cube under 1000 kg each rule out different models, and which of the rest
//! is cheapest depends on the resolution and the step. [`advise`] measures instead of guessing:
//! every candidate runs the whole trial scene once on one thread, and its cost is its wall
//! seconds per simulated second in that run.
//!
//! What each trial measures:
//!
//! | trial | error | fails when |
//! |---|---|---|
//! | [`Trial::Fall`] | centre-of-mass trajectory against the common [`FallReference`], RMS over the size | the fall's own criteria (explodes, ends inverted, sinks) |
//! | [`Trial::Limb`] | `1 −` the smallest cell volume ratio over the bend | a cell inverts |
//! | [`Trial::Crush`] | shape error after the load is lifted and the cube recovers, over the size | the crush's own criteria (inverts, reaches the ground) |
//!
//! and every trial also fails a run whose smallest cell volume ratio falls below
//! [`Bounds::min_volume_ratio`].

use super::super::lib::math::Real;
use super::super::lib::model::ElementModel;
use super::super::lib::BuildError;
use super::super::lib::Integrator;
use super::crush::CrushScene;
use super::fall::FallScene;
use super::fall_reference::FallReference;
use super::limb::LimbScene;
use super::metrics::trajectory_error;
use super::subject::Subject;
use crate::record::Record;

/// The scene a model is picked for, with the subject and integrator left to the advisor.
#[derive(Clone, Debug)]
pub enum Trial {
    /// A fall onto the ground, against `reference` (a fall without one is judged on stability
    /// alone).
    Fall {
        /// The fall (its `subject` and `integrator` are the advisor's).
        scene: FallScene,
        /// The common reference of that fall.
        reference: Option<FallReference>,
    },
    /// Tissue bent by a bone to its final angle.
    Limb(LimbScene),
    /// A mass pressed on the cube, held, lifted.
    Crush(CrushScene),
}

/// The bounds a run must stay inside.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Bounds {
    /// Largest error (the trial's, see the module's table).
    pub max_error: f64,
    /// Smallest cell volume over rest volume allowed at any step (0: no cell inverts).
    pub min_volume_ratio: f64,
}

/// The fall trial's duration, s: the drop, the impact and the first bounce's apex.
pub const FALL_SECONDS: Real = 1.5;

impl Trial {
    /// The default fall cube at `resolution` and `dt` for [`FALL_SECONDS`], against
    /// `reference` (the `chart` example's fall).
    pub fn fall(resolution: usize, dt: Real, reference: Option<FallReference>) -> Trial {
        Trial::Fall {
            scene: FallScene {
                resolution,
                dt,
                seconds: FALL_SECONDS,
                ..FallScene::default()
            },
            reference,
        }
    }

    /// The default limb (`spacing` 0.1 m: 11 nodes along it) bent to 110° at `dt`.
    pub fn limb(spacing: Real, dt: Real) -> Trial {
        Trial::Limb(LimbScene {
            spacing,
            dt,
            ..LimbScene::default()
        })
    }

    /// The default cube at `resolution` and `dt` under `mass`: settled 0.5 s, loaded over
    /// 0.5 s, held to 1.5 s, lifted over 0.5 s, recovering 1 s (the `chart` example's crush).
    pub fn crush(resolution: usize, dt: Real, mass: Real) -> Trial {
        Trial::Crush(CrushScene {
            cube: FallScene {
                resolution,
                dt,
                ..FallScene::default()
            },
            mass,
            settle: 0.5,
            ramp: 0.5,
            hold: 1.5,
            lift: 0.5,
            recover: 1.0,
            guided: true,
        })
    }

    /// The trial's name: `fall`, `limb` or `crush`.
    pub fn name(&self) -> &'static str {
        match self {
            Trial::Fall { .. } => "fall",
            Trial::Limb(_) => "limb",
            Trial::Crush(_) => "crush",
        }
    }

    /// What the trial's error is.
    pub fn error_name(&self) -> &'static str {
        match self {
            Trial::Fall { .. } => "trajectory error / size vs the fall reference",
            Trial::Limb(_) => "1 - smallest volume ratio",
            Trial::Crush(_) => "shape error / size after recovery",
        }
    }

    /// The bounds a scene like this one is usually held to: a fall within 5 % of its size of
    /// the reference, a limb that reaches its angle with no cell inverted (the papers'
    /// criterion: error below 1), a crushed cube back within 2 % of its shape; no inverted
    /// cell anywhere.
    pub fn default_bounds(&self) -> Bounds {
        match self {
            Trial::Fall { .. } => Bounds {
                max_error: 0.05,
                min_volume_ratio: 0.0,
            },
            Trial::Limb(_) => Bounds {
                max_error: 1.0,
                min_volume_ratio: 0.0,
            },
            Trial::Crush(_) => Bounds {
                max_error: 0.02,
                min_volume_ratio: 0.0,
            },
        }
    }

    /// Runs the trial with `subject` and (for sinew's models) `integrator`; returns the record
    /// and the error.
    pub fn measure(
        &self,
        subject: Subject,
        integrator: Integrator,
    ) -> Result<(Record, Option<f64>), BuildError> {
        match self {
            Trial::Fall { scene, reference } => {
                let scene = FallScene {
                    subject,
                    integrator,
                    ..*scene
                };
                let Some(reference) = reference else {
                    return Ok((scene.run()?, None));
                };
                let (r, samples) = scene.run_sampled(reference.every)?;
                let e = trajectory_error(&samples, reference.trajectory(), scene.size);
                Ok((r, Some(e as f64)))
            }
            Trial::Limb(scene) => {
                let r = LimbScene {
                    subject,
                    integrator,
                    ..*scene
                }
                .run()?;
                let e = 1.0 - r.min_vol_ratio;
                Ok((r, Some(e)))
            }
            Trial::Crush(scene) => {
                let r = CrushScene {
                    cube: FallScene {
                        subject,
                        integrator,
                        ..scene.cube
                    },
                    ..*scene
                }
                .run()?;
                let e = r.shape_error;
                Ok((r, e))
            }
        }
    }
}

/// The models and integrators tried: every model explicitly, every model the implicit steps
/// take by each of them (backward Euler and midpoint) with 2 and with 10 sweeps, and those
/// models under `Integrator::Auto { iterations: 2 }` (the explicit step or the midpoint step,
/// whichever it takes at the trial's `dt`).
pub fn candidates() -> Vec<(ElementModel, Integrator)> {
    let implicit = || {
        ElementModel::ALL
            .into_iter()
            .filter(|&m| m != ElementModel::CentroidSprings)
    };
    let mut out: Vec<_> = ElementModel::ALL
        .iter()
        .map(|&m| (m, Integrator::Explicit))
        .collect();
    for iterations in [2, 10] {
        for m in implicit() {
            out.push((m, Integrator::Implicit { iterations }));
            out.push((m, Integrator::Midpoint { iterations }));
        }
    }
    out.extend(implicit().map(|m| (m, Integrator::Auto { iterations: 2 })));
    out
}

/// One candidate's run.
#[derive(Clone, Debug)]
pub struct Candidate {
    /// The model.
    pub model: ElementModel,
    /// The integrator.
    pub integrator: Integrator,
    /// The run's record (cost: [`Record::wall_per_sim_s`]).
    pub record: Record,
    /// The trial's error (`None` when the trial has nothing to measure it against).
    pub error: Option<f64>,
    /// Why the run is out of bounds (`None`: it passes).
    pub rejected: Option<String>,
}

impl Candidate {
    /// `edge-repulsion explicit`, `springs implicit 2`, …
    pub fn label(&self) -> String {
        match self.integrator {
            Integrator::Explicit => format!("{} explicit", self.model.name()),
            Integrator::Implicit { iterations } => {
                format!("{} implicit {iterations}", self.model.name())
            }
            Integrator::Midpoint { iterations } => {
                format!("{} midpoint {iterations}", self.model.name())
            }
            Integrator::Auto { iterations } => {
                format!("{} auto {iterations}", self.model.name())
            }
        }
    }

    /// Wall seconds per simulated second.
    pub fn cost(&self) -> f64 {
        self.record.wall_per_sim_s()
    }
}

/// Every candidate of a trial and the advisor's pick.
#[derive(Clone, Debug)]
pub struct Advice {
    /// The trial's name.
    pub trial: &'static str,
    /// The bounds the runs were held to.
    pub bounds: Bounds,
    /// Every candidate, in the order run.
    pub candidates: Vec<Candidate>,
    /// The index in `candidates` of the cheapest that passed (`None`: none did).
    pub chosen: Option<usize>,
}

impl Advice {
    /// The pick.
    pub fn choice(&self) -> Option<&Candidate> {
        self.chosen.map(|i| &self.candidates[i])
    }
}

/// Why a run with `record` and `error` is out of `bounds` (`None`: it is inside).
pub fn rejection(record: &Record, error: Option<f64>, bounds: &Bounds) -> Option<String> {
    if let Some(f) = &record.failure {
        return Some(f.clone());
    }
    // Written so that NaN is out of bounds.
    if record.min_vol_ratio.is_nan() || record.min_vol_ratio < bounds.min_volume_ratio {
        return Some(format!(
            "volume ratio {:.3} below {}",
            record.min_vol_ratio, bounds.min_volume_ratio
        ));
    }
    match error {
        Some(e) if e.is_nan() || e > bounds.max_error => {
            Some(format!("error {e:.3e} over {:.3e}", bounds.max_error))
        }
        _ => None,
    }
}

/// Runs `trial` with every one of `candidates` and picks the cheapest run inside `bounds`,
/// calling `progress` before each run.
pub fn advise(
    trial: &Trial,
    bounds: Bounds,
    candidates: &[(ElementModel, Integrator)],
    mut progress: impl FnMut(&str),
) -> Result<Advice, BuildError> {
    let mut out = Vec::with_capacity(candidates.len());
    for &(model, integrator) in candidates {
        let mut c = Candidate {
            model,
            integrator,
            record: Record::default(),
            error: None,
            rejected: None,
        };
        progress(&format!("{} {}", trial.name(), c.label()));
        let (record, error) = trial.measure(Subject::Sinew(model), integrator)?;
        c.rejected = rejection(&record, error, &bounds);
        c.record = record;
        c.error = error;
        out.push(c);
    }
    let chosen = out
        .iter()
        .enumerate()
        .filter(|(_, c)| c.rejected.is_none())
        .min_by(|(_, a), (_, b)| a.cost().total_cmp(&b.cost()))
        .map(|(i, _)| i);
    Ok(Advice {
        trial: trial.name(),
        bounds,
        candidates: out,
        chosen,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(failure: Option<&str>, min_vol_ratio: f64) -> Record {
        Record {
            failure: failure.map(str::to_string),
            failed: failure.is_some(),
            min_vol_ratio,
            ..Record::default()
        }
    }

    #[test]
    fn a_run_is_rejected_for_its_failure_its_volume_or_its_error() {
        let b = Bounds {
            max_error: 0.1,
            min_volume_ratio: 0.2,
        };
        assert_eq!(rejection(&record(None, 0.5), Some(0.05), &b), None);
        assert_eq!(rejection(&record(None, 0.5), None, &b), None);
        assert!(rejection(&record(Some("sank"), 0.5), Some(0.0), &b)
            .unwrap()
            .contains("sank"));
        assert!(rejection(&record(None, 0.1), Some(0.0), &b)
            .unwrap()
            .contains("volume"));
        assert!(rejection(&record(None, 0.5), Some(0.2), &b)
            .unwrap()
            .contains("error"));
        // NaN is never inside a bound.
        assert!(rejection(&record(None, 0.5), Some(f64::NAN), &b).is_some());
        assert!(rejection(&record(None, f64::NAN), None, &b).is_some());
    }

    #[test]
    fn every_model_is_tried_explicitly_and_all_but_centroid_springs_implicitly() {
        let c = candidates();
        // Every model explicitly; all but centroid springs by both implicit integrators, with
        // 2 and with 10 sweeps, and under Auto (for centroid springs, the explicit step).
        assert_eq!(c.len(), ElementModel::ALL.len() * 6 - 5);
        for m in ElementModel::ALL {
            assert!(c.contains(&(m, Integrator::Explicit)));
            let implicit = m != ElementModel::CentroidSprings;
            assert_eq!(
                c.contains(&(m, Integrator::Auto { iterations: 2 })),
                implicit
            );
            for iterations in [2, 10] {
                assert_eq!(
                    c.contains(&(m, Integrator::Implicit { iterations })),
                    implicit
                );
                assert_eq!(
                    c.contains(&(m, Integrator::Midpoint { iterations })),
                    implicit
                );
            }
        }
    }
}
