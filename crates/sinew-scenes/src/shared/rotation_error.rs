//! The `rotation-error` scene (shape-based elasticity paper, §4, Table 1).

use super::super::lib::math::{self, Real, Vector, DIM, UP};
use super::super::lib::mesh::{CellKind, Mesh};
use super::super::lib::model::{ElementModel, RotationFit, ShapeDamping};
use super::super::lib::BuildError;
use super::super::lib::DeformableWorld;
use super::super::lib::{Material, Stiffness};
use super::fall::ground;
use super::sim::{BodySpec, Sim};
use super::subject::Subject;
use super::{Record, Spread};

/// One shape-based cube element (a square in 2D), 1 m and 1 kg, dropped tumbling from ten times
/// its size onto the ground — tilted by 0.5 rad and spinning at 5 rad/s about skew axes in 3D,
/// about the plane's normal in 2D — with one substep per step of `dt = period / divisions`, `period =
/// 2π/√(k/m)`; after every step the spurious angular acceleration of its element forces,
/// `|Σ rᵢ × fᵢ| / I` about the centroid (`I` the moment of inertia about the torque's axis),
/// is sampled. An exact rotation fit gives none: the element forces of a rotated rest shape
/// have no net torque.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct RotationErrorScene {
    /// The rotation fit.
    pub fit: RotationFit,
    /// Stiffness per unit mass, 1/s².
    pub k_over_m: Real,
    /// Steps per oscillation period.
    pub divisions: Real,
    /// Simulated duration, s.
    pub seconds: Real,
    /// Damping ratio.
    pub damping_ratio: Real,
}

impl Default for RotationErrorScene {
    /// Two iterations, k/m = 10⁴, 10 steps per period, 10 s, ζ = 0.1.
    fn default() -> Self {
        RotationErrorScene {
            fit: RotationFit::Iterative(2),
            k_over_m: 1.0e4,
            divisions: 10.0,
            seconds: 10.0,
            damping_ratio: 0.1,
        }
    }
}

impl RotationErrorScene {
    /// The rows of the paper's table for one `k/m`: 1, 2, 3 iterations and the polar fit at 10
    /// steps per period, 1 iteration at 100.
    pub fn table_rows(k_over_m: Real) -> Vec<RotationErrorScene> {
        let base = RotationErrorScene {
            k_over_m,
            ..Default::default()
        };
        let mut rows: Vec<RotationErrorScene> = [
            RotationFit::Iterative(1),
            RotationFit::Iterative(2),
            RotationFit::Iterative(3),
            RotationFit::Polar,
        ]
        .into_iter()
        .map(|fit| RotationErrorScene { fit, ..base })
        .collect();
        rows.push(RotationErrorScene {
            fit: RotationFit::Iterative(1),
            divisions: 100.0,
            ..base
        });
        rows
    }

    /// Step length, s.
    pub fn dt(&self) -> Real {
        2.0 * std::f64::consts::PI as Real / self.k_over_m.sqrt() / self.divisions
    }

    /// Runs the drop, calling `observe` after every step with the world and the fraction done.
    pub fn run_with(
        &self,
        mut observe: impl FnMut(&DeformableWorld, f64),
    ) -> Result<Record, BuildError> {
        let dt = self.dt();
        let mut world = DeformableWorld::new();
        world.set_dt(dt);
        ground(&mut world, 0.5, 0.5);
        let mesh = Mesh::cuboid(Vector::splat(0.5), [2; DIM], CellKind::Cube)?;
        let mut spec = BodySpec::new(
            mesh,
            UP * 10.5,
            Material {
                density: 1.0,
                ..Default::default()
            },
        );
        spec.stiffness = Stiffness::PerMass {
            k_over_m: self.k_over_m,
            damping_ratio: self.damping_ratio,
        };
        let subject = Subject::Sinew(ElementModel::ShapeMatching {
            fit: self.fit,
            damping: ShapeDamping::RigidMotion,
        });
        spec.rotation = math::rotation_from_angle(tilt());
        let mut sim = Sim::new(world, subject, spec, 1.0, Some(1))?;
        let c = sim.center_of_mass();
        let spin = spin();
        let v: Vec<Vector> = sim
            .positions()
            .iter()
            .map(|p| math::ang_cross(spin, *p - c))
            .collect();
        sim.set_velocities(&v)?;
        let steps = (self.seconds / dt).round().max(1.0) as usize;
        let mut samples = Vec::with_capacity(steps);
        let mut before: Vec<Vector> = sim.positions().to_vec();
        for k in 0..steps {
            before.copy_from_slice(sim.positions());
            sim.step();
            // Asleep, the body has no new forces to measure.
            if let Some(body) = sim.deformable().filter(|b| !b.is_sleeping()) {
                samples.push(spurious_acceleration(
                    &before,
                    body.masses(),
                    body.last_element_forces(),
                ) as f64);
            }
            observe(&sim.world, (k + 1) as f64 / steps as f64);
            if sim.exploded() {
                break;
            }
        }
        let mut r = sim.record("rotation-error", 2);
        r.k_over_m = Some(self.k_over_m as f64);
        r.spurious = Some(Spread::of(&samples));
        r.rest_com = Some(sim.center_of_mass().dot(UP) as f64);
        Ok(r)
    }

    /// Runs the drop.
    pub fn run(&self) -> Result<Record, BuildError> {
        self.run_with(|_, _| {})
    }
}

/// `|Σ rᵢ × fᵢ| / I` about the mass centre of `x`, with `I = Σ mᵢ |rᵢ × n|²` the moment of
/// inertia about the torque's axis `n` (about the plane's normal in 2D).
pub fn spurious_acceleration(x: &[Vector], masses: &[Real], forces: &[Vector]) -> Real {
    let m: Real = masses.iter().sum();
    let c = x.iter().zip(masses).map(|(p, m)| *p * *m).sum::<Vector>() / m;
    let mut torque = math::ANG_ZERO;
    for (p, f) in x.iter().zip(forces) {
        torque += math::cross(*p - c, *f);
    }
    let t = math::ang_norm(torque);
    if t == 0.0 {
        return 0.0;
    }
    let axis = torque / t;
    let inertia: Real = x
        .iter()
        .zip(masses)
        .map(|(p, m)| m * math::ang_cross(axis, *p - c).length_squared())
        .sum();
    t / inertia
}

/// The initial tilt: 0.5 rad about a skew axis (the plane's normal in 2D).
fn tilt() -> math::AngVector {
    scaled(math::ang_from_components([0.6, 0.7, 0.4]), 0.5)
}

/// The initial spin: 5 rad/s about another skew axis (the plane's normal in 2D).
fn spin() -> math::AngVector {
    scaled(math::ang_from_components([0.3, -0.5, 0.8]), 5.0)
}

fn scaled(axis: math::AngVector, length: Real) -> math::AngVector {
    axis * (length / math::ang_norm(axis))
}
