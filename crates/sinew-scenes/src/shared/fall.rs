//! The `fall` scene and the `dt-sweep` built on it.

use super::super::lib::math::{Real, Vector, DIM, UP};
use super::super::lib::mesh::{CellKind, Mesh};
use super::super::lib::model::ElementModel;
use super::super::lib::rapier::dynamics::RigidBodyBuilder;
use super::super::lib::rapier::geometry::{ColliderBuilder, Cuboid, SharedShape};
use super::super::lib::BuildError;
use super::super::lib::DeformableWorld;
use super::super::lib::Integrator;
use super::super::lib::Material;
use super::sim::{BodySpec, Bounce, Sim};
use super::subject::Subject;
use super::Record;

/// A soft box (cube in 3D, square in 2D) dropped on a fixed ground whose top is at height 0.
///
/// Measures the bounce apex (highest centre of mass between the first impact's lowest point
/// and the next turn downwards), the rest height at the end, the deepest node below the
/// ground, inverted cells. A run fails when it explodes, ends with an inverted cell or sinks
/// deeper than a quarter of the box into the ground.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct FallScene {
    /// What is simulated.
    pub subject: Subject,
    /// Nodes per edge.
    pub resolution: usize,
    /// Cell kind of the lattice (rapier's models need simplices).
    pub cells: CellKind,
    /// Edge length of the box, m.
    pub size: Real,
    /// Mass of the box, kg (sets the density).
    pub mass: Real,
    /// Young's modulus, Pa.
    pub young_modulus: Real,
    /// Poisson's ratio (sinew's models on simplex cells but centroid springs, and rapier's).
    pub poisson_ratio: Real,
    /// Damping ratio.
    pub damping_ratio: Real,
    /// Height of the box's bottom at the start, m.
    pub drop_height: Real,
    /// Friction coefficient of both the box and the ground.
    pub friction: Real,
    /// Restitution coefficient of both the box and the ground.
    pub restitution: Real,
    /// Step length, s.
    pub dt: Real,
    /// Simulated duration, s.
    pub seconds: Real,
    /// A fixed substep count instead of each solver's own choice.
    pub fixed_substeps: Option<usize>,
    /// sinew's integrator.
    pub integrator: Integrator,
    /// [`PipelineSettings::global_iterations`](sinew::dim3::PipelineSettings::global_iterations)
    /// under the implicit steps (0: the sweeps alone).
    pub global_iterations: Option<usize>,
}

impl Default for FallScene {
    /// The `fall` scene: 1 m, 1 kg, E = 10⁴ Pa, ν = 0.3, bottom at 2 m (centre of mass at
    /// 2.5 m), damping ratio 0.1, friction 0.5, restitution 0.5, dt 1 ms, 3 s, 5 nodes per
    /// edge, simplex cells, edge-repulsion.
    fn default() -> Self {
        FallScene {
            subject: Subject::Sinew(ElementModel::EdgeRepulsion),
            resolution: 5,
            cells: CellKind::Simplex,
            size: 1.0,
            mass: 1.0,
            young_modulus: 1.0e4,
            poisson_ratio: 0.3,
            damping_ratio: 0.1,
            drop_height: 2.0,
            friction: 0.5,
            restitution: 0.5,
            dt: 1.0e-3,
            seconds: 3.0,
            fixed_substeps: None,
            integrator: Integrator::Explicit,
            global_iterations: None,
        }
    }
}

/// A fixed ground, top at height 0, 40 m wide.
pub(crate) fn ground(world: &mut DeformableWorld, friction: Real, restitution: Real) {
    ground_at(world, 0.0, friction, restitution);
}

/// A fixed ground, top at height `top`, 40 m wide.
pub(crate) fn ground_at(world: &mut DeformableWorld, top: Real, friction: Real, restitution: Real) {
    let mut half = Vector::splat(20.0);
    half[1] = 0.5;
    world.physics.insert(
        RigidBodyBuilder::fixed().translation(UP * (top - 0.5)),
        ColliderBuilder::new(cuboid(half))
            .friction(friction)
            .restitution(restitution),
    );
}

pub(crate) fn cuboid(half: Vector) -> SharedShape {
    SharedShape::new(Cuboid::new(half))
}

impl FallScene {
    /// An empty world stepped as this cube's runs are: its step, integrator and Newton
    /// iterations (the scenes that borrow a cube's settings start from it).
    pub(crate) fn world(&self) -> DeformableWorld {
        let mut world = DeformableWorld::new();
        world.set_dt(self.dt);
        world.pipeline.settings.integrator = self.integrator;
        world.pipeline.settings.global_iterations = self.global_iterations;
        world
    }

    /// The material of the box.
    pub fn material(&self) -> Material {
        Material {
            density: self.mass / self.size.powi(DIM as i32),
            young_modulus: self.young_modulus,
            damping_ratio: self.damping_ratio,
            poisson_ratio: self.poisson_ratio,
        }
    }

    /// A world of this scene's dt with the fixed ground (top at height 0), nothing else.
    pub(crate) fn ground_world(&self) -> DeformableWorld {
        let mut world = DeformableWorld::new();
        world.set_dt(self.dt);
        world.pipeline.settings.integrator = self.integrator;
        world.pipeline.settings.global_iterations = self.global_iterations;
        ground(&mut world, self.friction, self.restitution);
        world
    }

    /// `world` with the box added, its bottom at height `bottom`.
    pub(crate) fn sim_in(&self, world: DeformableWorld, bottom: Real) -> Result<Sim, BuildError> {
        let mesh = Mesh::cuboid(
            Vector::splat(0.5 * self.size),
            [self.resolution; DIM],
            self.cells,
        )?;
        let mut spec = BodySpec::new(mesh, UP * (bottom + 0.5 * self.size), self.material());
        spec.friction = self.friction;
        spec.restitution = self.restitution;
        Sim::new(world, self.subject, spec, self.size, self.fixed_substeps)
    }

    /// The world: a fixed ground (top at height 0) and the box above it.
    pub fn sim(&self) -> Result<Sim, BuildError> {
        self.sim_in(self.ground_world(), self.drop_height)
    }

    /// Runs the scene, calling `observe` after every step with the world and the fraction done.
    pub fn run_with(
        &self,
        observe: impl FnMut(&DeformableWorld, f64),
    ) -> Result<Record, BuildError> {
        self.run_inner(observe, None)
    }

    /// Runs the scene and samples the centre of mass every `every` seconds, from `every` on —
    /// the trajectory that [`super::metrics::trajectory_error`] compares across dt and
    /// resolution. A sample falling inside a step is interpolated linearly between the centres
    /// of mass at the step's ends, so the k-th sample is at time k·`every` whatever dt is (a
    /// step longer than `every` yields several). `every` must be positive and finite.
    pub fn run_sampled(&self, every: Real) -> Result<(Record, Vec<Vector>), BuildError> {
        if !(every.is_finite() && every > 0.0) {
            return Err(BuildError::InvalidParameter {
                name: "every",
                value: every,
                expected: "a positive finite sampling interval",
            });
        }
        let mut samples = Vec::new();
        let r = self.run_inner(|_, _| {}, Some((every, &mut samples)))?;
        Ok((r, samples))
    }

    fn run_inner(
        &self,
        mut observe: impl FnMut(&DeformableWorld, f64),
        mut sample: Option<(Real, &mut Vec<Vector>)>,
    ) -> Result<Record, BuildError> {
        let mut sim = self.sim()?;
        let steps = (self.seconds / self.dt).round().max(1.0) as usize;
        let mut bounce = Bounce::new(0.0, self.size);
        let mut before = sim.center_of_mass();
        for k in 0..steps {
            sim.step();
            bounce.observe(&sim);
            if let Some((every, out)) = sample.as_mut() {
                let after = sim.center_of_mass();
                let (t0, dt) = (k as f64 * self.dt as f64, self.dt as f64);
                loop {
                    let next = (out.len() + 1) as f64 * *every as f64;
                    // Up to a rounding of the step's end: a sample on it is taken there.
                    let s = (next - t0) / dt;
                    if s > 1.0 + 1e-6 {
                        break;
                    }
                    out.push(before.lerp(after, s.min(1.0) as Real));
                }
                before = after;
            }
            observe(&sim.world, (k + 1) as f64 / steps as f64);
            if sim.exploded() {
                break;
            }
        }
        let sank = bounce.max_penetration() > 0.25 * self.size;
        Ok(bounce.record(
            &sim,
            "fall",
            self.resolution,
            &[(sank, "sank into the ground")],
        ))
    }

    /// Runs the scene.
    pub fn run(&self) -> Result<Record, BuildError> {
        self.run_with(|_, _| {})
    }
}

/// The step lengths of the dt sweep, ms.
pub const DT_SWEEP_MS: [Real; 5] = [0.5, 1.0, 2.0, 5.0, 16.7];

/// The `dt-sweep` scene: `scene` at each of [`DT_SWEEP_MS`] with one substep per step (the
/// records say `substep_mode: fixed`), then with each solver's own substeps (`auto`). Within a
/// mode every record's `first_failure` is the smallest dt (ms) whose run failed (see
/// [`FallScene`]); larger ones are not assumed to fail and are run too.
pub fn dt_sweep(
    scene: &FallScene,
    mut observe: impl FnMut(&DeformableWorld, f64),
) -> Result<Vec<Record>, BuildError> {
    let mut out = Vec::new();
    let runs = 2 * DT_SWEEP_MS.len();
    for (m, fixed) in [Some(1), None].into_iter().enumerate() {
        let mut mode = Vec::new();
        for (i, ms) in DT_SWEEP_MS.iter().enumerate() {
            let index = m * DT_SWEEP_MS.len() + i;
            let s = FallScene {
                dt: ms * 1e-3,
                fixed_substeps: fixed,
                ..*scene
            };
            let mut r = s.run_with(|w, done| observe(w, (index as f64 + done) / runs as f64))?;
            r.scene = "dt-sweep".to_string();
            mode.push(r);
        }
        set_first_failure(&mut mode, |r| r.dt * 1e3);
        out.extend(mode);
    }
    Ok(out)
}

/// Sets every record's `first_failure` to the smallest `key` of a failed record.
pub(crate) fn set_first_failure(records: &mut [Record], key: impl Fn(&Record) -> f64) {
    let first = records
        .iter()
        .filter(|r| r.failed)
        .map(&key)
        .fold(None, |a: Option<f64>, k| Some(a.map_or(k, |a| a.min(k))));
    for r in records {
        r.first_failure = first;
    }
}
