//! The `cantilever` scene: the static sag of a clamped beam under its own weight, against
//! Euler–Bernoulli beam theory ([`crate::beam`]) for the material's Young's modulus.

use super::super::lib::math::{Real, Vector, DIM, UP};
use super::super::lib::mesh::{CellKind, Mesh};
use super::super::lib::model::ElementModel;
use super::super::lib::rapier::dynamics::RigidBodyBuilder;
use super::super::lib::rapier::geometry::ColliderBuilder;
use super::super::lib::BuildError;
use super::super::lib::DeformableWorld;
use super::super::lib::Integrator;
use super::super::lib::Material;
use super::fall::cuboid;
use super::sim::{BodySpec, Sim};
use super::subject::Subject;
use super::vibration::Ring;
use super::Record;
use crate::beam;

/// A beam along +x, clamped at `x = 0` by a fixed bone and sagging under gravity until it is
/// static; its tip sag is compared with Euler–Bernoulli's `δ = q L⁴ / (8 E I)`.
///
/// **Geometry.** The free part spans `x ∈ [0, length]`, with a square section of side
/// `thickness` in 3D (a strip of unit depth in 2D, density per unit area), centred on `y = 0`.
/// The lattice continues `(res − 1)/2` cells (at least one, about half the thickness) into the
/// bone, at `x < 0`: every node inside or on the bone's collider (a sensor) is pinned to it,
/// so the section at `x = 0` is fully clamped, as in [`super::LimbScene`].
///
/// **Resolution.** `res` is the number of nodes across the thickness (and the width in 3D);
/// along the free length the lattice has `round((res − 1) · length/thickness)` cells, so the
/// cells are (nearly) cubes. At the default aspect ratio 10, res 9 is 8 × 8 × 80 cubes of
/// 6 tetrahedra (6 885 nodes with the clamp) in 3D, 8 × 80 squares of 2 triangles in 2D.
///
/// **Reaching the static state.** A slender beam's first bending mode is far slower than the
/// elements' own frequencies, so the elements' damping (a fixed ratio of each element's own
/// frequency) hardly damps it. After every step the scene therefore scales every node's
/// velocity by `exp(−α dt)` — a drag proportional to mass, i.e. dynamic relaxation — with
/// `α = relaxation · ω₁` and `ω₁` the beam's first bending frequency from theory
/// ([`beam::cantilever_first_frequency`]). The default 1.5 damps that mode at a ratio 0.75
/// when the body is as stiff as the theory, critically when it is 1.8 times softer, so that a
/// body too soft by as much is not overdamped into a slow creep; every underdamped mode decays
/// as `exp(−α t/2)`. The drag vanishes at rest, so it does not change the static sag. The run lasts `seconds`; `sag_wobble` is the range of the tip sag
/// over the last first-mode period (at most half the run) over the sag, and a run whose
/// wobble exceeds [`SETTLED_WOBBLE`] fails as not settled.
///
/// **Measures.** `sag` is the mean downward displacement of the free end's nodes (the
/// section's rotation moves them symmetrically about the neutral axis), `sag_theory` is
/// [`beam::euler_bernoulli_tip_sag`] with `q = ρ g A` plus Timoshenko's shear sag
/// ([`beam::shear_sag_fraction`]: 1.0 % more at the default aspect ratio 10 and ν = 0.3, more
/// for a shorter beam), and `sag_error` is [`beam::sag_error`] of the two. The default sag is 1.5 % of the length, inside linear
/// theory's range.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct CantileverScene {
    /// What is simulated.
    pub subject: Subject,
    /// Nodes across the thickness (see the type's docs).
    pub resolution: usize,
    /// Cell kind of the lattice (rapier's models need simplices).
    pub cells: CellKind,
    /// Free length, m.
    pub length: Real,
    /// Thickness (and width in 3D), m.
    pub thickness: Real,
    /// Young's modulus, Pa.
    pub young_modulus: Real,
    /// Poisson's ratio (sinew's models on simplex cells but centroid springs, and rapier's).
    pub poisson_ratio: Real,
    /// Density, kg/m³ (kg/m² in 2D).
    pub density: Real,
    /// Damping ratio of the elements.
    pub damping_ratio: Real,
    /// Gravity, m/s² (downwards).
    pub gravity: Real,
    /// Drag rate in units of the first bending frequency `ω₁` (2 = critical for that mode).
    pub relaxation: Real,
    /// Step length, s.
    pub dt: Real,
    /// Simulated duration, s.
    pub seconds: Real,
    /// A fixed substep count instead of each solver's own choice.
    pub fixed_substeps: Option<usize>,
    /// sinew's integrator.
    pub integrator: Integrator,
    /// [`PipelineSettings::global_iterations`](sinew::dim3::PipelineSettings::global_iterations)
    /// of sinew's implicit steps.
    pub global_iterations: Option<usize>,
}

impl Default for CantileverScene {
    /// A 1 m beam of 0.1 m square section (aspect ratio 10), E = 10⁸ Pa, ν = 0.3,
    /// 1000 kg/m³, element damping ratio 0.1, g = 9.81 m/s², relaxation 1.5, dt = 1 ms,
    /// 0.5 s, res 9, simplex cells, shape matching (2 iterations). Theory: sag 14.7 mm
    /// (1.5 % of the length), `ω₁` = 32.1 rad/s (5.1 Hz), so the run lasts 16 `1/ω₁`.
    fn default() -> Self {
        CantileverScene {
            subject: Subject::Sinew(ElementModel::SHAPE_MATCHING),
            resolution: 9,
            cells: CellKind::Simplex,
            length: 1.0,
            thickness: 0.1,
            young_modulus: 1.0e8,
            poisson_ratio: 0.3,
            density: 1000.0,
            damping_ratio: 0.1,
            gravity: 9.81,
            relaxation: 1.5,
            dt: 1.0e-3,
            seconds: 0.5,
            fixed_substeps: None,
            integrator: Integrator::Explicit,
            global_iterations: None,
        }
    }
}

/// Largest tip-sag range over the settling window, relative to the sag, of a settled run.
pub const SETTLED_WOBBLE: f64 = 0.01;

/// The beam's cross-section as beam theory sees it: area `A` and second moment `I` (per unit
/// depth in 2D).
fn section(thickness: f64) -> (f64, f64) {
    let width = if DIM == 3 { thickness } else { 1.0 };
    (width * thickness, width * thickness.powi(3) / 12.0)
}

fn invalid(name: &'static str, value: Real, expected: &'static str) -> BuildError {
    BuildError::InvalidParameter {
        name,
        value,
        expected,
    }
}

impl CantileverScene {
    /// The material of the beam.
    pub fn material(&self) -> Material {
        Material {
            density: self.density,
            young_modulus: self.young_modulus,
            damping_ratio: self.damping_ratio,
            poisson_ratio: self.poisson_ratio,
        }
    }

    fn validate(&self) -> Result<(), BuildError> {
        let positive = |name, v: Real| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(invalid(name, v, "a positive finite value"))
            }
        };
        positive("length", self.length)?;
        positive("thickness", self.thickness)?;
        positive("density", self.density)?;
        positive("young_modulus", self.young_modulus)?;
        positive("dt", self.dt)?;
        positive("seconds", self.seconds)?;
        if !(self.gravity.is_finite() && self.relaxation.is_finite() && self.relaxation >= 0.0) {
            return Err(invalid(
                "relaxation",
                self.relaxation,
                "a finite gravity and a non-negative finite relaxation",
            ));
        }
        if self.resolution < 2 {
            return Err(invalid(
                "resolution",
                self.resolution as Real,
                "at least 2 nodes across the thickness",
            ));
        }
        Ok(())
    }

    /// Euler–Bernoulli's tip sag of this beam, m.
    pub fn theory_sag(&self) -> f64 {
        let (area, second_moment) = section(self.thickness as f64);
        let load = self.density as f64 * self.gravity as f64 * area;
        let bending = beam::euler_bernoulli_tip_sag(
            load,
            self.length as f64,
            self.young_modulus as f64,
            second_moment,
        );
        bending
            * (1.0
                + beam::shear_sag_fraction(
                    self.thickness as f64,
                    self.length as f64,
                    self.poisson_ratio as f64,
                ))
    }

    /// The beam's first bending angular frequency from theory, rad/s.
    pub fn first_frequency(&self) -> f64 {
        let (area, second_moment) = section(self.thickness as f64);
        beam::cantilever_first_frequency(
            self.length as f64,
            self.young_modulus as f64,
            second_moment,
            self.density as f64 * area,
        )
    }

    /// Lattice spacing along the beam, and the cells along it in the free part and in the
    /// clamp.
    fn lattice(&self) -> (Real, usize, usize) {
        let across = (self.resolution - 1) as Real;
        let free = ((self.length / self.thickness * across).round() as usize).max(1);
        let clamp = ((self.resolution - 1) / 2).max(1);
        (self.length / free as Real, free, clamp)
    }

    /// The world (the beam and the fixed clamp), and the beam's free-end nodes.
    pub fn sim(&self) -> Result<(Sim, Vec<u32>), BuildError> {
        self.validate()?;
        let (dx, free, clamp) = self.lattice();
        let depth = clamp as Real * dx;
        let mut res = [self.resolution; DIM];
        res[0] = free + clamp + 1;
        let mut half = Vector::splat(0.5 * self.thickness);
        half[0] = 0.5 * (self.length + depth);
        let mesh = Mesh::cuboid(half, res, self.cells)?;
        // The lattice spans x ∈ [−depth, length].
        let translation = Vector::X * (0.5 * (self.length - depth));

        let mut world = DeformableWorld::new();
        world.set_dt(self.dt);
        world.pipeline.settings.integrator = self.integrator;
        world.pipeline.settings.global_iterations = self.global_iterations;
        world.physics.gravity = -UP * self.gravity;
        let bone = world
            .physics
            .insert_body(RigidBodyBuilder::fixed().translation(Vector::X * (-0.5 * depth)));
        let mut bone_half = Vector::splat(0.5 * self.thickness + dx);
        bone_half[0] = 0.5 * depth;
        let collider = world.physics.insert_collider(
            ColliderBuilder::new(cuboid(bone_half)).sensor(true),
            Some(bone),
        );
        let tolerance = 0.01 * dx;
        let co = &world.physics.colliders[collider];
        let rest = |i: usize| mesh.nodes()[i] + translation;
        let pinned: Vec<u32> = (0..mesh.nodes().len())
            .filter(|&i| co.shape().distance_to_point(co.position(), rest(i), true) <= tolerance)
            .map(|i| i as u32)
            .collect();
        let tip: Vec<u32> = (0..mesh.nodes().len())
            .filter(|&i| rest(i)[0] >= self.length - tolerance)
            .map(|i| i as u32)
            .collect();
        let mut spec = BodySpec::new(mesh, translation, self.material());
        spec.pins = vec![(bone, pinned)];
        let sim = Sim::new(world, self.subject, spec, self.length, self.fixed_substeps)?;
        Ok((sim, tip))
    }

    /// Runs the scene, calling `observe` after every step with the world and the fraction done.
    pub fn run_with(
        &self,
        mut observe: impl FnMut(&DeformableWorld, f64),
    ) -> Result<Record, BuildError> {
        let (mut sim, tip) = self.sim()?;
        let steps = (self.seconds / self.dt).round().max(1.0) as usize;
        let omega = self.first_frequency();
        let period = (std::f64::consts::TAU / omega / self.dt as f64).round() as usize;
        let window = period.clamp(1, (steps / 2).max(1));
        let keep = (-(self.relaxation as f64) * omega * self.dt as f64).exp() as Real;
        let sag = |sim: &Sim| tip_sag(sim, &tip);
        let mut velocities = Vec::new();
        let (mut low, mut high) = (f64::INFINITY, f64::NEG_INFINITY);
        for k in 0..steps {
            sim.step();
            velocities.clear();
            velocities.extend(sim.velocities().iter().map(|v| *v * keep));
            sim.set_velocities(&velocities)?;
            if k + window >= steps {
                let s = sag(&sim);
                low = low.min(s);
                high = high.max(s);
            }
            observe(&sim.world, (k + 1) as f64 / steps as f64);
            if sim.exploded() {
                break;
            }
        }
        let mut r = sim.record("cantilever", self.resolution);
        let measured = sag(&sim);
        let theory = self.theory_sag();
        let wobble = (high - low) / measured.abs();
        r.sag = Some(measured);
        r.sag_theory = Some(theory);
        r.sag_error = Some(beam::sag_error(measured, theory));
        r.sag_wobble = Some(wobble);
        r.failure = crate::record::failure(&[
            (r.nan, "non-finite state"),
            (r.exploded, "exploded"),
            (r.final_inverted_elements > 0, "ended with inverted cells"),
            (wobble.is_nan() || wobble > SETTLED_WOBBLE, "not settled"),
        ]);
        r.failed = r.failure.is_some();
        Ok(r)
    }

    /// Runs the scene.
    pub fn run(&self) -> Result<Record, BuildError> {
        self.run_with(|_, _| {})
    }

    /// The beam released straight under its weight rings about its sag: without the drag
    /// (`relaxation` is not used) the tip's sag is traced for `seconds` and its first bending
    /// frequency, from the zero crossings of the trace less its mean ([`Ring`]), goes to
    /// `measured_frequency` (Hz), Euler–Bernoulli's ([`Self::first_frequency`] over 2π, Hz)
    /// to `theory_frequency`, the trace's mean (about the static sag) to `sag`. Shear and rotary inertia, which lower a short beam's frequency, are
    /// not in the theory. A run under four crossings fails as "did not ring".
    pub fn ring(&self) -> Result<Record, BuildError> {
        let (mut sim, tip) = self.sim()?;
        let steps = (self.seconds / self.dt).round().max(1.0) as usize;
        let mut trace = Vec::with_capacity(steps);
        for k in 0..steps {
            sim.step();
            trace.push(((k + 1) as f64 * self.dt as f64, tip_sag(&sim, &tip)));
            if sim.exploded() {
                break;
            }
        }
        let mean = trace.iter().map(|(_, s)| s).sum::<f64>() / trace.len().max(1) as f64;
        for (_, s) in &mut trace {
            *s -= mean;
        }
        let ring = Ring::of(&trace);
        let mut r = sim.record("cantilever-ring", self.resolution);
        r.measured_frequency = ring.frequency;
        r.theory_frequency = Some(self.first_frequency() / std::f64::consts::TAU);
        r.sag = Some(mean);
        r.failure = crate::record::failure(&[
            (r.nan, "non-finite state"),
            (r.exploded, "exploded"),
            (r.final_inverted_elements > 0, "ended with inverted cells"),
            (ring.frequency.is_none(), "did not ring"),
        ]);
        r.failed = r.failure.is_some();
        Ok(r)
    }
}

/// The mean downward displacement of the `tip` nodes from their rest places, m.
fn tip_sag(sim: &Sim, tip: &[u32]) -> f64 {
    let (x, x0) = (sim.positions(), sim.rest_positions());
    let sum: f64 = tip
        .iter()
        .map(|&i| (x0[i as usize] - x[i as usize]).dot(UP) as f64)
        .sum();
    sum / tip.len().max(1) as f64
}
