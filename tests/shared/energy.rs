//! Energy (issue 17): undamped free motion gains no energy beyond 0.1 % over 10 s, for every
//! element model under the explicit step and every model the implicit step takes.
//!
//! Two motions, no gravity, no collider, damping 0: a box of three different sides spun about
//! an axis off its principal ones (a tumble: in 3D the spin axis wanders), and the same box let
//! go from a 5 % affine stretch (a free vibration). The energy is kinetic plus elastic, as the
//! bodies report them, sampled after every 60 Hz step.
//!
//! What "gains" means: symplectic Euler (the explicit step) conserves a *modified* energy, so
//! the energy it reports oscillates about a constant by O(h·ω) without drifting. The check is
//! on the drift: the least-squares slope of E(t) over the 10 s, times 10 s, as a fraction of
//! the starting energy. A step that pumps energy in (an unstable or inconsistent force) shows
//! as a rising trend; the largest rise after any step is printed beside it.
//!
//! The midpoint step (`Integrator::Midpoint`) is held to more, at two sweeps as users run it
//! (issue 28's bound): over 10 s a free body keeps its angular momentum within 0.1 %, its
//! energy within 0.1 % above and 2 % below its start, with a trend under 0.1 %; the same
//! box made stiff (E = 10⁸ Pa, its sweeps far from converged) keeps its angular momentum and
//! stays within 10 % above its starting energy. Solved whole
//! (`PipelineSettings::global_iterations` 10), the soft box keeps its energy to 0.1 % over
//! 10 s, its trend included (issue 28's bound).
//!
//! The implicit step (backward Euler) at two sweeps keeps a stiff box's spin (E = 10⁶ Pa,
//! off every principal axis and about one) to 1 % of its angular momentum over 5 s, its energy
//! no more than 1 % above its start.
//!
//! The explicit step runs 10 fixed substeps per 60 Hz step (h = 1/600 s): at its automatic
//! substep (safety 0.5, one or two substeps per 60 Hz step on this box) the oscillation is
//! 5–14 % and its beats swamp a 0.1 % trend; the trend itself is measured there in issue 17's
//! note. The implicit step runs once per 60 Hz step, as users run it.

use crate::dim::math::{
    ang_cross, ang_from_components, ang_norm, cross, AngVector, Real, Vector, ANG_ZERO, DIM,
};
use crate::dim::rapier::dynamics::{IntegrationParameters, RigidBodySet};
use crate::dim::rapier::geometry::{BroadPhaseBvh, ColliderSet};
use crate::dim::{
    CellKind, DeformableBuilder, DeformableHandle, DeformablePipeline, DeformableSet, ElementModel,
    Integrator, Material,
};

const DT: Real = 1.0 / 60.0;
const SECONDS: Real = 10.0;
/// The largest drift allowed, as a fraction of the starting energy.
const DRIFT: Real = 1e-3;

/// How the energy of one run moved.
#[derive(Debug)]
struct Energy {
    /// The least-squares trend of the energy over the run / starting energy.
    drift: Real,
    /// Largest (E − E₀)/E₀ after any step.
    peak: Real,
    /// Smallest (E − E₀)/E₀ after any step.
    low: Real,
    /// Largest change of the angular momentum about the centre of mass over its start,
    /// `|L − L₀|/|L₀|` (zero without a spin).
    momentum: Real,
}

/// Runs `model` free (no gravity, no collider, no damping) for [`SECONDS`] from a `stretch`
/// along x and a rigid `spin`, and measures its energy.
fn run(model: ElementModel, integrator: Integrator, spin: AngVector, stretch: Real) -> Energy {
    run_stiff(model, integrator, spin, stretch, 1e4, SECONDS)
}

/// [`run`] with Young's modulus `young`.
fn run_stiff(
    model: ElementModel,
    integrator: Integrator,
    spin: AngVector,
    stretch: Real,
    young: Real,
    seconds: Real,
) -> Energy {
    run_with(model, integrator, (spin, stretch), young, seconds, None)
}

/// [`run_stiff`] with [`PipelineSettings::global_iterations`](crate::dim::PipelineSettings::global_iterations).
fn run_with(
    model: ElementModel,
    integrator: Integrator,
    (spin, stretch): (AngVector, Real),
    young: Real,
    seconds: Real,
    global_iterations: Option<usize>,
) -> Energy {
    let (mut set, h) = free_box(model, young);
    let centre = set[h].center_of_mass();
    lengthen(&mut set, h, 1.0 + stretch);
    let v: Vec<Vector> = set[h]
        .positions()
        .iter()
        .map(|p| ang_cross(spin, *p - centre))
        .collect();
    set[h].set_velocities(&v).unwrap();
    let mut pipeline = free_pipeline(integrator);
    pipeline.settings.global_iterations = global_iterations;
    if integrator == Integrator::Explicit {
        pipeline.settings.fixed_substeps = Some(10);
    }
    let energy = |set: &DeformableSet| set[h].kinetic_energy() + set[h].elastic_energy();
    let momentum = |set: &DeformableSet| {
        let b = &set[h];
        b.angular_momentum() - cross(b.center_of_mass(), b.linear_momentum())
    };
    let start = energy(&set);
    let l0 = momentum(&set);
    let mut turned: Real = 0.0;
    let steps = (seconds / DT).round() as usize;
    let mut trace = Vec::with_capacity(steps);
    for _ in 0..steps {
        step(&mut pipeline, &mut set, Vector::ZERO);
        assert!(
            !set[h].is_frozen(),
            "{} {integrator:?}: frozen",
            model.name()
        );
        trace.push(energy(&set));
        if ang_norm(l0) > 0.0 {
            turned = turned.max(ang_norm(momentum(&set) - l0) / ang_norm(l0));
        }
    }
    let mean = |s: &[Real]| s.iter().sum::<Real>() / s.len() as Real;
    // Least-squares slope of E over the step index, times the number of steps.
    let n = trace.len() as Real;
    let (k_mean, e_mean) = ((n - 1.0) / 2.0, mean(&trace));
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (k, e) in trace.iter().enumerate() {
        let d = k as Real - k_mean;
        sxy += d * (e - e_mean);
        sxx += d * d;
    }
    Energy {
        drift: sxy / sxx * n / start,
        peak: trace
            .iter()
            .map(|e| (e - start) / start)
            .fold(Real::NEG_INFINITY, Real::max),
        low: trace
            .iter()
            .map(|e| (e - start) / start)
            .fold(Real::INFINITY, Real::min),
        momentum: turned,
    }
}

/// A 1 × 0.6 × 0.4 m box (1 × 0.4 in 2D) of `model`, 1000 kg/m³, Young's modulus `young`,
/// undamped, alone in a set.
fn free_box(model: ElementModel, young: Real) -> (DeformableSet, DeformableHandle) {
    let mut half = Vector::splat(0.2);
    half[0] = 0.5;
    if DIM == 3 {
        half[1] = 0.3;
    }
    let body = DeformableBuilder::cuboid(half, [3; DIM])
        .cells(CellKind::Simplex)
        .model(model)
        .material(Material {
            density: 1000.0,
            young_modulus: young,
            damping_ratio: 0.0,
            ..Default::default()
        })
        .build()
        .unwrap();
    let mut set = DeformableSet::new();
    let h = set.insert(body);
    (set, h)
}

/// Stretches body `h` along x about its centre of mass by `factor`.
fn lengthen(set: &mut DeformableSet, h: DeformableHandle, factor: Real) {
    let centre = set[h].center_of_mass();
    let x: Vec<Vector> = set[h]
        .positions()
        .iter()
        .map(|p| {
            let mut d = *p - centre;
            d[0] *= factor;
            centre + d
        })
        .collect();
    set[h].set_positions(&x).unwrap();
}

/// A pipeline of `integrator` that never puts a body to sleep.
fn free_pipeline(integrator: Integrator) -> DeformablePipeline {
    let mut pipeline = DeformablePipeline::new();
    pipeline.settings.integrator = integrator;
    pipeline.settings.time_until_sleep = Real::INFINITY;
    pipeline
}

/// One 60 Hz step under `gravity`, no rigid body or collider.
fn step(pipeline: &mut DeformablePipeline, set: &mut DeformableSet, gravity: Vector) {
    let params = IntegrationParameters {
        dt: DT,
        ..Default::default()
    };
    let (mut bodies, colliders, bp) = (
        RigidBodySet::new(),
        ColliderSet::new(),
        BroadPhaseBvh::new(),
    );
    pipeline.step(gravity, &params, set, &mut bodies, &colliders, &bp);
}

/// 1.5 rad/s about an axis off every principal axis of the box (3D); about the plane's normal
/// (2D).
fn spin() -> AngVector {
    ang_from_components([1.2, 0.5, 0.8])
}

const IMPLICIT: Integrator = Integrator::Implicit { iterations: 10 };

/// The models each integrator takes (the implicit step has no centroid springs).
fn runs() -> Vec<(ElementModel, Integrator)> {
    let mut out: Vec<_> = ElementModel::ALL
        .iter()
        .map(|&m| (m, Integrator::Explicit))
        .collect();
    for m in [
        ElementModel::Springs,
        ElementModel::NonlinearSprings,
        ElementModel::EdgeRepulsion,
        ElementModel::SHAPE_MATCHING,
    ] {
        out.push((m, IMPLICIT));
    }
    out
}

/// Runs every model with `spin` and `stretch`; fails listing every run that drifted up.
fn check(motion: &str, spin: AngVector, stretch: Real) {
    let mut failed = Vec::new();
    for (model, integrator) in runs() {
        let e = run(model, integrator, spin, stretch);
        eprintln!(
            "{motion} {} {integrator:?}: drift {:+.2e}, peak rise {:+.2e}",
            model.name(),
            e.drift,
            e.peak
        );
        if e.drift.is_nan() || e.drift > DRIFT {
            failed.push(format!("{} {integrator:?}: {e:?}", model.name()));
        }
    }
    assert!(failed.is_empty(), "{motion} gained energy: {failed:?}");
}

/// The midpoint step as users run it at 60 Hz.
const MIDPOINT: Integrator = Integrator::Midpoint { iterations: 2 };
/// How long the midpoint runs go.
const MIDPOINT_SECONDS: Real = 10.0;
/// Largest trend of a free body's energy under the midpoint step over [`MIDPOINT_SECONDS`].
const MIDPOINT_DRIFT: Real = 1e-3;
/// Most a free body's energy may rise above its start under the midpoint step.
const MIDPOINT_RISE: Real = 1e-3;
/// Largest change of a free body's angular momentum under the midpoint step, over its start.
const MOMENTUM: Real = 1e-3;

/// Runs every model the implicit step takes under [`MIDPOINT`] with `spin`, `stretch` and
/// Young's modulus `young`; fails listing every run whose energy rose above `rise` over its
/// start (or, when `kept`, fell more than 2 % below it or drifted by more than
/// [`MIDPOINT_DRIFT`]) or whose angular momentum moved by more than [`MOMENTUM`].
fn check_midpoint(
    motion: &str,
    (spin, stretch): (AngVector, Real),
    young: Real,
    rise: Real,
    kept: bool,
) {
    let mut failed = Vec::new();
    for model in [
        ElementModel::Springs,
        ElementModel::NonlinearSprings,
        ElementModel::EdgeRepulsion,
        ElementModel::SHAPE_MATCHING,
    ] {
        let e = run_stiff(model, MIDPOINT, spin, stretch, young, MIDPOINT_SECONDS);
        eprintln!(
            "{motion} {} E = {young:e} midpoint: drift {:+.2e}, energy {:+.2e} … {:+.2e}, momentum {:.2e}",
            model.name(),
            e.drift,
            e.low,
            e.peak,
            e.momentum
        );
        let held = e.peak <= rise
            && (!kept || (e.low >= -0.02 && e.drift.abs() <= MIDPOINT_DRIFT))
            && e.momentum <= MOMENTUM;
        if !held {
            failed.push(format!("{} {e:?}", model.name()));
        }
    }
    assert!(
        failed.is_empty(),
        "{motion} under the midpoint step: {failed:?}"
    );
}

#[test]
fn the_midpoint_step_keeps_a_tumble() {
    check_midpoint("tumble", (spin(), 0.0), 1e4, MIDPOINT_RISE, true);
}

#[test]
fn the_midpoint_step_keeps_a_free_vibration() {
    check_midpoint("vibration", (ANG_ZERO, 0.05), 1e4, MIDPOINT_RISE, true);
}

#[test]
fn solved_whole_the_midpoint_step_keeps_energy_to_a_thousandth_over_10_s() {
    // Issue 28's bound, with the Newton step over the whole body (10 iterations): the tumble
    // drifts by at most 2·10⁻⁵ and the free vibration by at most 3.3·10⁻⁴ over 10 s.
    for model in [
        ElementModel::Springs,
        ElementModel::NonlinearSprings,
        ElementModel::EdgeRepulsion,
        ElementModel::SHAPE_MATCHING,
    ] {
        let motions = [("tumble", spin(), 0.0), ("vibration", ANG_ZERO, 0.05)];
        for (motion, spin, stretch) in motions {
            let e = run_with(model, MIDPOINT, (spin, stretch), 1e4, 10.0, Some(10));
            let name = format!("{motion} {}", model.name());
            assert!(e.drift.abs() <= 1e-3, "{name}: {e:?}");
            assert!(e.peak <= 1e-3 && e.low >= -0.02, "{name}: {e:?}");
            assert!(e.momentum <= MOMENTUM, "{name}: {e:?}");
        }
    }
}

#[test]
fn the_midpoint_step_holds_a_stiff_body_that_its_sweeps_do_not_converge_on() {
    check_midpoint("stiff tumble", (spin(), 0.0), 1e8, 0.1, false);
    check_midpoint("stiff ringing tumble", (spin(), 0.05), 1e8, 0.1, false);
}

#[test]
fn a_tumbling_body_gains_no_energy() {
    check("tumble", spin(), 0.0);
}

#[test]
fn a_free_vibration_gains_no_energy() {
    check("vibration", ANG_ZERO, 0.05);
}

#[test]
fn the_midpoint_step_keeps_the_energy_of_a_fall() {
    // A body falling as a whole: its internal energy about zero, its centre's motion exact.
    // (Rounding once made a tiny excess of such a body read as a diverging step: it fell by
    // backward Euler.)
    let (mut set, h) = free_box(ElementModel::EdgeRepulsion, 1e4);
    let mut pipeline = free_pipeline(MIDPOINT);
    let mut g = Vector::ZERO;
    g[1] = -9.81;
    let energy = |set: &DeformableSet| {
        let b = &set[h];
        let height: Real = b
            .positions()
            .iter()
            .zip(b.masses())
            .map(|(p, m)| -m * g.dot(*p))
            .sum();
        b.kinetic_energy() + b.elastic_energy() + height
    };
    let start = energy(&set);
    let mut worst: Real = 0.0;
    for _ in 0..120 {
        step(&mut pipeline, &mut set, g);
        worst = worst.max((energy(&set) - start).abs());
    }
    // Backward Euler loses `½ M h² g²` a step in a free fall: 256 J over these 2 s (of the
    // 26 kJ the box gains), single precision rounds a few joules at 20 m from the origin.
    let fallen = set[h].kinetic_energy();
    assert!(
        worst <= 1e-3 * fallen,
        "the fall's energy moved by {worst} J (it gained {fallen} J of motion)"
    );
}

#[test]
fn the_midpoint_step_turns_no_cell_inside_out() {
    // A soft box let go from half or one and a half times its length: carried on to the
    // step's end, the motion of a solve that kept every cell upright at its midpoint turned
    // shape-based cells inside out.
    for model in [ElementModel::EdgeRepulsion, ElementModel::SHAPE_MATCHING] {
        for squash in [0.5, 1.5] {
            let (mut set, h) = free_box(model, 1e4);
            lengthen(&mut set, h, squash);
            let mut pipeline = free_pipeline(MIDPOINT);
            for k in 0..300 {
                step(&mut pipeline, &mut set, Vector::ZERO);
                let inverted = set[h].inverted_elements();
                assert_eq!(inverted, 0, "{} from {squash}×, step {k}", model.name());
            }
        }
    }
}

#[test]
fn the_implicit_step_keeps_a_spin() {
    // Carried straight ahead, a spinning body's nodes ended each step farther out, the step
    // pulled them back in, and the body spun slower: at 60 Hz with two sweeps a box kept 54 %
    // of its angular momentum over 5 s.
    let mut failed = Vec::new();
    // Off every principal axis (3D), and about one.
    for spin in [spin(), ang_from_components([3.0, 0.0, 0.0])] {
        for model in [
            ElementModel::Springs,
            ElementModel::NonlinearSprings,
            ElementModel::EdgeRepulsion,
            ElementModel::SHAPE_MATCHING,
        ] {
            let integrator = Integrator::Implicit { iterations: 2 };
            let e = run_stiff(model, integrator, spin, 0.0, 1e6, 5.0);
            eprintln!(
                "spin {spin:?} {}: angular momentum {:.2e} off, energy {:+.2e} … {:+.2e}",
                model.name(),
                e.momentum,
                e.low,
                e.peak
            );
            if e.momentum > 0.01 || e.peak > 0.01 {
                failed.push(format!("{spin:?} {} {e:?}", model.name()));
            }
        }
    }
    assert!(failed.is_empty(), "spin not kept: {failed:?}");
}
