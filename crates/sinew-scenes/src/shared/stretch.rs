//! The `stretch` scene: Poisson's ratio measured on a bar pulled along its axis (issue 15).

use super::super::lib::math::{Real, Vector, DIM};
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
use super::Record;

/// A bar 6 m long and 1 m across (1 × 1 m in 3D), cells `spacing` apart, no gravity, its end
/// faces bound to two bones: one fixed, the other pulled along the bar's axis to `strain` over
/// `ramp` s (smoothly), then held `hold` s. At the end, in the middle of the bar (two widths
/// from either clamp), the axial strain between the sections at ±1.5 m and the lateral strain
/// of the middle section's width give `measured_poisson = −ε_lateral / ε_axial`; for sinew's
/// models the element forces on the pulled end's nodes give the tension `T`, and
/// `measured_young_modulus = T / (A ε_axial)` with `A` the bar's rest section (1 m², 1 m of
/// unit depth in 2D) — the stress is uniaxial in the middle, where the section is free.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct StretchScene {
    /// What is simulated.
    pub subject: Subject,
    /// Poisson's ratio asked for.
    pub poisson_ratio: Real,
    /// Young's modulus, Pa.
    pub young_modulus: Real,
    /// Density, kg/m³ (kg/m² in 2D).
    pub density: Real,
    /// Damping ratio.
    pub damping_ratio: Real,
    /// Lattice spacing, m.
    pub spacing: Real,
    /// The stretch, as a fraction of the length.
    pub strain: Real,
    /// Time over which the stretch is applied, s.
    pub ramp: Real,
    /// Time it is held before the measurement, s.
    pub hold: Real,
    /// Step length, s.
    pub dt: Real,
    /// sinew's integrator.
    pub integrator: Integrator,
}

impl Default for StretchScene {
    /// ν = 0.3, E = 10⁴ Pa, 10 kg/m³ (its first axial mode at 2.6 Hz: the hold is static),
    /// damping ratio 1, 0.25 m cells, 2 % over 1 s, held 2 s,
    /// dt 1/60 s, edge repulsion.
    fn default() -> Self {
        StretchScene {
            subject: Subject::Sinew(ElementModel::EdgeRepulsion),
            poisson_ratio: 0.3,
            young_modulus: 1.0e4,
            density: 10.0,
            damping_ratio: 1.0,
            spacing: 0.25,
            strain: 0.02,
            ramp: 1.0,
            hold: 2.0,
            dt: 1.0 / 60.0,
            integrator: Integrator::Explicit,
        }
    }
}

/// Half the bar's length, m.
const HALF_LENGTH: Real = 3.0;

impl StretchScene {
    /// Runs the scene.
    pub fn run(&self) -> Result<Record, BuildError> {
        let mut world = DeformableWorld::new();
        world.set_dt(self.dt);
        world.pipeline.settings.integrator = self.integrator;
        world.physics.gravity = Vector::ZERO;
        // Measured at rest, not where a body too slow to notice fell asleep.
        world.pipeline.settings.time_until_sleep = Real::INFINITY;
        let mut half = Vector::splat(0.5);
        half[0] = HALF_LENGTH;
        let res: [usize; DIM] =
            std::array::from_fn(|d| (2.0 * half[d] / self.spacing).round() as usize + 1);
        let mesh = Mesh::cuboid(half, res, CellKind::Simplex)?;
        let end = |side: Real| -> Vec<u32> {
            (0..mesh.nodes().len() as u32)
                .filter(|&i| (mesh.nodes()[i as usize][0] - side * HALF_LENGTH).abs() < 1e-4)
                .collect()
        };
        let (left, right) = (end(-1.0), end(1.0));
        let pulled_nodes = right.clone();
        let mut pins = Vec::new();
        let mut puller = None;
        for (side, nodes) in [(-1.0, left), (1.0, right)] {
            let builder = if side < 0.0 {
                RigidBodyBuilder::fixed()
            } else {
                RigidBodyBuilder::kinematic_position_based()
            };
            let body = world
                .physics
                .insert_body(builder.translation(Vector::X * (side * HALF_LENGTH)));
            let mut bone = Vector::splat(0.6);
            bone[0] = 0.05;
            world
                .physics
                .insert_collider(ColliderBuilder::new(cuboid(bone)).sensor(true), Some(body));
            if side > 0.0 {
                puller = Some(body);
            }
            pins.push((body, nodes));
        }
        let material = Material {
            density: self.density,
            young_modulus: self.young_modulus,
            damping_ratio: self.damping_ratio,
            poisson_ratio: self.poisson_ratio,
        };
        let mut spec = BodySpec::new(mesh, Vector::ZERO, material);
        spec.pins = pins;
        let mut sim = Sim::new(world, self.subject, spec, 1.0, None)?;
        let steps = ((self.ramp + self.hold) / self.dt).round() as usize;
        for k in 0..steps {
            let t = (k + 1) as Real * self.dt;
            let s = (t / self.ramp).min(1.0);
            let pulled = self.strain * 2.0 * HALF_LENGTH * s * s * (3.0 - 2.0 * s);
            if let Some(b) = puller.and_then(|p| sim.world.physics.bodies.get_mut(p)) {
                b.set_next_kinematic_translation(Vector::X * (HALF_LENGTH + pulled));
            }
            sim.step();
            if sim.exploded() {
                break;
            }
        }
        let mut r = sim.record("stretch", res[0]);
        let axial = axial_strain(sim.rest_positions(), sim.positions());
        r.measured_poisson = measured_poisson(sim.rest_positions(), sim.positions());
        // The elastic forces on the pulled end's nodes pull it back: their sum is −T.
        let tension = sim
            .handle()
            .and_then(|h| sim.world.deformables.get_mut(h))
            .map(|body| {
                let f = body.element_forces();
                -pulled_nodes.iter().map(|&i| f[i as usize][0]).sum::<Real>() as f64
            });
        // The rest section: 1 m² in 3D, 1 m of unit depth in 2D.
        let area: f64 = (1..DIM).map(|d| 2.0 * half[d] as f64).product();
        r.measured_young_modulus = tension
            .zip(axial)
            .filter(|(_, e)| e.abs() > 1e-6)
            .map(|(t, e)| t / (area * e));
        Ok(r)
    }
}

/// The section at `at` along the bar: its nodes.
fn section(rest: &[Vector], at: Real) -> Vec<usize> {
    (0..rest.len())
        .filter(|&i| (rest[i][0] - at).abs() < 1e-4)
        .collect()
}

/// The axial strain between the sections at ±1.5 m (see [`StretchScene`]).
fn axial_strain(rest: &[Vector], x: &[Vector]) -> Option<f64> {
    let mean_x =
        |nodes: &[usize]| nodes.iter().map(|&i| x[i][0]).sum::<Real>() / nodes.len() as Real;
    let (a, b) = (
        section(rest, -0.5 * HALF_LENGTH),
        section(rest, 0.5 * HALF_LENGTH),
    );
    if a.is_empty() || b.is_empty() {
        return None;
    }
    Some(((mean_x(&b) - mean_x(&a)) / HALF_LENGTH - 1.0) as f64)
}

/// `−ε_lateral / ε_axial` in the middle of the bar (see [`StretchScene`]).
fn measured_poisson(rest: &[Vector], x: &[Vector]) -> Option<f64> {
    let axial = axial_strain(rest, x)?;
    let mid = section(rest, 0.0);
    if mid.is_empty() {
        return None;
    }
    let lateral = (1..DIM)
        .map(|d| {
            let (lo, hi) = mid
                .iter()
                .fold((Real::INFINITY, -Real::INFINITY), |(lo, hi), &i| {
                    (lo.min(x[i][d]), hi.max(x[i][d]))
                });
            hi - lo - 1.0
        })
        .sum::<Real>()
        / (DIM - 1) as Real;
    (axial.abs() > 1e-6).then(|| -(lateral as f64 / axial))
}
