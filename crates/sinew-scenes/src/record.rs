//! One run of a scene as a flat row, the same type in 2D and 3D: what the scene runner
//! (`examples/scenes`) prints as a table or as one JSON object per line.
//!
//! Values are `f64` whatever the simulation's precision; a quantity a scene does not measure
//! is `None` (JSON `null`).

/// Mean, standard deviation and largest value of a sampled quantity.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct Spread {
    /// Mean.
    pub mean: f64,
    /// Population standard deviation.
    pub std: f64,
    /// Largest sample.
    pub max: f64,
}

impl Spread {
    /// The spread of `samples` (all zero when empty).
    pub fn of(samples: &[f64]) -> Spread {
        if samples.is_empty() {
            return Spread::default();
        }
        let n = samples.len() as f64;
        let mean = samples.iter().sum::<f64>() / n;
        let var = samples.iter().map(|s| (s - mean) * (s - mean)).sum::<f64>() / n;
        let max = samples.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Spread {
            mean,
            std: var.sqrt(),
            max,
        }
    }
}

/// What one run of one scene with one model measured.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Record {
    /// Scene name (`fall`, `limb`, `crush`, `manipulator`, `dt-sweep`, `rotation-error`,
    /// `cantilever`).
    pub scene: String,
    /// 2 or 3.
    pub dim: usize,
    /// Model name: one of sinew's (`springs`, …, `shape-matching`) or rapier's (`rapier-…`).
    pub model: String,
    /// Rotation fit of the shape-based model (`1`, `2`, `3` iterations or `polar`).
    pub iterations: Option<String>,
    /// sinew's integrator, `explicit` or `implicit` (`None` for rapier's bodies).
    pub integrator: Option<String>,
    /// Sweeps per step of the implicit integrator.
    pub sweeps: Option<usize>,
    /// Nodes per edge of the lattice (cantilever: nodes across the beam's thickness).
    pub res: usize,
    /// Soft bodies in the scene (the multi-body scenes: stack, pile, squeeze).
    pub bodies: Option<usize>,
    /// Nodes (particles) of the body (of all bodies).
    pub nodes: usize,
    /// Cells of the body.
    pub elements: usize,
    /// Step length, s.
    pub dt: f64,
    /// `auto` (each solver's own choice) or `fixed` (a fixed count, see `substeps`).
    pub substep_mode: String,
    /// Mean substeps per step (rapier: its solver substeps).
    pub substeps: f64,
    /// Most substeps in one step.
    pub max_substeps: usize,
    /// Simulated time, s.
    pub sim_s: f64,
    /// Wall time of the stepping loop only, s.
    pub wall_s: f64,
    /// Load on the body: the crushing box's mass (crush), kg.
    pub mass: Option<f64>,
    /// Young's modulus, Pa.
    pub young: f64,
    /// Poisson's ratio (used by rapier's elastic models; sinew's spring-like models ignore it).
    pub poisson: f64,
    /// Stiffness per unit mass `k/m` of the rotation-error element, 1/s².
    pub k_over_m: Option<f64>,
    /// Highest centre of mass height after the first impact's lowest point, m.
    pub bounce_apex_com: Option<f64>,
    /// Centre of mass height at the end, m.
    pub rest_com: Option<f64>,
    /// Deepest node below the ground's top over the run, m.
    pub max_penetration: Option<f64>,
    /// Smallest signed cell volume over its rest volume, over the run.
    pub min_vol_ratio: f64,
    /// Most inverted (or collapsed) cells at any step.
    pub max_inverted_elements: usize,
    /// Inverted (or collapsed) cells at the end.
    pub final_inverted_elements: usize,
    /// Whether this run failed by the scene's criterion (see the scene's docs).
    pub failed: bool,
    /// Why the run failed, in a few words (`None` when it did not).
    pub failure: Option<String>,
    /// The scene's failure point (see the scene's docs): an angle, a mass, a strike number, a
    /// step length in ms.
    pub first_failure: Option<f64>,
    /// Largest node distance from the rest shape after removing rigid motion, over the body
    /// size.
    pub shape_error: Option<f64>,
    /// Volume over rest volume at the end of a static load (the crush hold).
    pub loaded_volume_ratio: Option<f64>,
    /// The cavity's inflated volume over its built one (balloon).
    pub inflation: Option<f64>,
    /// The cavity's smallest volume under the plates over its inflated one (balloon).
    pub gas_volume_ratio: Option<f64>,
    /// `|pV/(pV)₀ − 1|` of the gas at the end (balloon; sinew only: rapier has no gas).
    pub boyle_error: Option<f64>,
    /// `|V/V_inflated − 1|` of the cavity at the end (balloon).
    pub recovery_error: Option<f64>,
    /// The pulled log strain `ln(L/L₀)` at the first tear (tear).
    pub torn_at_strain: Option<f64>,
    /// The pieces the body ended in (tear).
    pub pieces: Option<usize>,
    /// The bend the bar kept after it was let go, rad (bend).
    pub kept_bend: Option<f64>,
    /// The bend an elastic–perfectly-plastic beam keeps, rad (bend).
    pub kept_bend_theory: Option<f64>,
    /// How far the middle of the plate's top stays below where it was built, m (dent).
    pub dent: Option<f64>,
    /// Deepest a surface node went inside the body's own surface over the run
    /// (`metrics::self_interpenetration`, up to half a cell deep), m (fold, limb).
    pub max_self_penetration: Option<f64>,
    /// Deepest a surface node of one body went inside another over the run
    /// (`metrics::interpenetration`), m (stack, pile, squeeze).
    pub max_interpenetration: Option<f64>,
    /// The same over the run's last second, m.
    pub rest_interpenetration: Option<f64>,
    /// Largest rise of the total energy (kinetic, gravitational, and for sinew elastic) above
    /// its lowest value so far, over the energy at the start (stack, pile, squeeze; the box's
    /// energy not counted): energy the contacts created.
    pub energy_gain: Option<f64>,
    /// Largest total energy (as `energy_gain` counts it) above the energy at the start, over
    /// the start (tower): whatever the run lost first, energy it later gained back counts.
    pub energy_over_start: Option<f64>,
    /// Total energy at the end less at the start, over the start (tower).
    pub energy_change: Option<f64>,
    /// Largest horizontal distance of a body's centre of mass from the vertical axis through
    /// the origin at the end, m (tower).
    pub scatter: Option<f64>,
    /// The top body's centre height at the end over its height in the tower stacked at rest
    /// (tower; dropped or not).
    pub top_height_ratio: Option<f64>,
    /// Whether every body was asleep at the end (sinew only: rapier's soft bodies do not say).
    pub asleep: Option<bool>,
    /// Largest vertical slip of the held box against the fingers over the lift and the hold,
    /// m (pinch).
    pub slip: Option<f64>,
    /// Most the box's speed ever exceeded the fingers', m/s (pinch).
    pub overspeed: Option<f64>,
    /// The slowest step's wall time over the median step's (pinch).
    pub step_spike: Option<f64>,
    /// Fastest node at the end, m/s.
    pub final_speed: Option<f64>,
    /// Wall time spent finding the pairs of deformables that may touch, s (sinew only: rapier's
    /// is inside its step).
    pub pairs_wall_s: Option<f64>,
    /// Largest distance of a pinned node from its anchor on its bone, m (limb).
    pub max_anchor_error: Option<f64>,
    /// Spurious angular acceleration of the element forces, rad/s² (rotation-error).
    pub spurious: Option<Spread>,
    /// Static tip sag of the cantilever: mean downward displacement of its free end's nodes, m
    /// (`cantilever-ring`: that displacement's mean over the run, about which it rings).
    pub sag: Option<f64>,
    /// Euler–Bernoulli tip sag of the same beam ([`crate::beam::euler_bernoulli_tip_sag`]), m.
    pub sag_theory: Option<f64>,
    /// `(sag − sag_theory) / sag_theory` ([`crate::beam::sag_error`]).
    pub sag_error: Option<f64>,
    /// Range (max − min) of the tip sag over the cantilever's settling window, over the sag: how
    /// far from static the measurement is.
    pub sag_wobble: Option<f64>,
    /// `stretch`: Poisson's ratio measured, `−ε_lateral / ε_axial` in the bar's middle.
    pub measured_poisson: Option<f64>,
    /// `stretch`: Young's modulus measured, the pulled end's tension over the bar's section
    /// over the middle's axial strain, Pa (sinew's models: rapier's expose no node forces).
    pub measured_young_modulus: Option<f64>,
    /// `vibration`: the first axial frequency measured, Hz (`cantilever-ring`: the first
    /// bending frequency).
    pub measured_frequency: Option<f64>,
    /// `vibration`: the first axial frequency of beam theory, Hz (`cantilever-ring`:
    /// Euler–Bernoulli's first bending frequency).
    pub theory_frequency: Option<f64>,
    /// `vibration`: the damping ratio measured from the ringing's decay.
    pub measured_damping_ratio: Option<f64>,
    /// Kinetic energy at the end, J.
    pub final_kinetic_energy: f64,
    /// Whether the state turned non-finite.
    pub nan: bool,
    /// Whether the state blew up: non-finite, a node farther than [`EXPLODED_DISTANCE`] from
    /// the origin or faster than [`EXPLODED_SPEED`].
    pub exploded: bool,
}

/// A node farther than this from the origin (m) means the run exploded.
pub const EXPLODED_DISTANCE: f64 = 100.0;
/// A node faster than this (m/s) means the run exploded.
pub const EXPLODED_SPEED: f64 = 100.0;

impl Record {
    /// Wall seconds per simulated second.
    pub fn wall_per_sim_s(&self) -> f64 {
        self.wall_s / self.sim_s.max(f64::MIN_POSITIVE)
    }
}

/// The reason for a failure from the conditions that make one, first true wins.
pub fn failure(conditions: &[(bool, &str)]) -> Option<String> {
    conditions
        .iter()
        .find(|(hit, _)| *hit)
        .map(|(_, why)| why.to_string())
}
