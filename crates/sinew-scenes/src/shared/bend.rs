//! The `bend` scene.

use super::super::lib::math::{planar_angle, rotation_from_angle, Pose, Real, Vector, DIM};
use super::super::lib::mesh::{CellKind, Mesh};
use super::super::lib::rapier::dynamics::RigidBodyBuilder;
use super::super::lib::{BuildError, DeformableWorld, FlowIn, Material, Plasticity};
use super::fall::FallScene;
use super::sim::{BodySpec, Sim};
use super::Record;

/// A bar `length` long and `thickness` thick (and deep, in 3D), weightless, clamped at one end
/// to a fixed bone and bent a quarter turn over `bend` s by a bone at the other end that
/// follows the arc of a uniform bend, held `hold` s, then let go for `recover` s. A plastic
/// material (`yield_strain`, instant flow) keeps a bend: the direction of the bar's last
/// layer of cells (its mean over the last second, about which a bar still ringing rings)
/// against an elastic–perfectly-plastic beam's, `κ − M(κ)/EI` over the length
/// (`M = 1.5 M_y (1 − (κ_y/κ)²/3)`, `κ_y = 2 ε_y / t`; a rectangular section in pure bending).
///
/// rapier 0.36's body gets the yield on its material (`plastic_yield` for its cells,
/// `edge_plastic_yield` for its edges, instant creep).
///
/// A run fails when it blows up, a cell inverts, or the bend it keeps is over 15 % from the
/// beam's.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct BendScene {
    /// Subject, resolution (nodes across the thickness; along the length in proportion),
    /// step, integrator and material (Young's modulus, Poisson's ratio, damping ratio); its
    /// mass, size, height, friction and restitution are ignored.
    pub cube: FallScene,
    /// The bar's length, m.
    pub length: Real,
    /// Its thickness (and depth in 3D), m.
    pub thickness: Real,
    /// Density, kg/m³.
    pub density: Real,
    /// The yield strain (log).
    pub yield_strain: Real,
    /// Time to bend, s.
    pub bend: Real,
    /// Time held bent, s.
    pub hold: Real,
    /// Time let go, s.
    pub recover: Real,
    /// sinew only: the rate of `DeformableBuilder::deformation_damping`, 1/s.
    pub deformation_damping: Real,
}

impl Default for BendScene {
    /// A 1 m bar, 10 cm thick, 2.5 cm cells (5 nodes across), E = 10⁶ Pa, ν = 0.3, 100 kg/m³,
    /// damping ratio 0.3 (deformation damping 5/s), yield 0.02; bent over 2 s, held 0.5 s, let
    /// go 2 s; 60 Hz, edge repulsion under sinew's default integrator.
    fn default() -> Self {
        BendScene {
            cube: FallScene {
                resolution: 5,
                young_modulus: 1e6,
                poisson_ratio: 0.3,
                damping_ratio: 0.3,
                dt: 1.0 / 60.0,
                ..FallScene::default()
            },
            length: 1.0,
            thickness: 0.1,
            density: 100.0,
            yield_strain: 0.02,
            bend: 2.0,
            hold: 0.5,
            recover: 2.0,
            deformation_damping: 5.0,
        }
    }
}

impl BendScene {
    /// The bend an elastic–perfectly-plastic beam keeps, rad.
    pub fn theory(&self) -> Real {
        let k = std::f32::consts::FRAC_PI_2 / self.length;
        let ky = 2.0 * self.yield_strain / self.thickness;
        let kept = if k > ky {
            k - 1.5 * ky * (1.0 - (ky / k).powi(2) / 3.0)
        } else {
            0.0
        };
        kept * self.length
    }

    fn mesh(&self) -> Result<Mesh, BuildError> {
        let across = self.cube.resolution.max(2);
        let cell = self.thickness / (across - 1) as Real;
        let mut half = Vector::splat(0.5 * self.thickness);
        half[0] = 0.5 * self.length;
        let res: [usize; DIM] = std::array::from_fn(|d| match d {
            0 => (self.length / cell).round() as usize + 1,
            1 => across,
            // Across the bend axis in 3D: no bending there, half as many nodes do.
            _ => across.div_ceil(2).max(2),
        });
        Mesh::cuboid(half, res, CellKind::Simplex)
    }

    /// Runs the scene.
    pub fn run(&self) -> Result<Record, BuildError> {
        self.run_with(|_, _| {})
    }

    /// Runs the scene, calling `observe` after every step with the world and the fraction done.
    pub fn run_with(
        &self,
        mut observe: impl FnMut(&DeformableWorld, f64),
    ) -> Result<Record, BuildError> {
        let c = &self.cube;
        let mut world = c.world();
        world.physics.gravity = Vector::ZERO;
        let mesh = self.mesh()?;
        let mut spec = BodySpec::new(
            mesh.clone(),
            Vector::X * (0.5 * self.length),
            Material {
                density: self.density,
                young_modulus: c.young_modulus,
                poisson_ratio: c.poisson_ratio,
                damping_ratio: c.damping_ratio,
            },
        );
        spec.deformation_damping = self.deformation_damping;
        spec.plasticity = Some(Plasticity {
            yield_strain: self.yield_strain,
            flow_rate: Real::INFINITY,
            max_strain: 1.0,
            flow: FlowIn::Both,
        });
        let end = |x: Real| -> Vec<u32> {
            (0..mesh.nodes().len() as u32)
                .filter(|&i| (mesh.nodes()[i as usize][0] - x).abs() < 1e-4)
                .collect()
        };
        let clamp = world.physics.insert_body(RigidBodyBuilder::fixed());
        let bone = world
            .physics
            .insert_body(RigidBodyBuilder::kinematic_position_based());
        spec.pins.push((clamp, end(-0.5 * self.length)));
        spec.pins.push((bone, end(0.5 * self.length)));
        let mut sim = Sim::new(world, c.subject, spec, self.length, c.fixed_substeps)?;
        let steps = |t: Real| (t / c.dt).round().max(1.0) as usize;
        let (bending, total) = (
            steps(self.bend),
            steps(self.bend) + steps(self.hold) + steps(self.recover),
        );
        let quarter = std::f32::consts::FRAC_PI_2;
        let mut done = 0;
        for k in 1..=bending + steps(self.hold) {
            // The end where a uniform bend by `theta` takes it, turned by `theta`.
            let theta = quarter * (k.min(bending) as Real / bending as Real);
            let mut tip = Vector::ZERO;
            tip[0] = self.length * theta.sin() / theta;
            tip[1] = self.length * (1.0 - theta.cos()) / theta;
            let turn = rotation_from_angle(planar_angle(theta));
            let pose = Pose::from_parts(tip - turn * (Vector::X * self.length), turn);
            if let Some(b) = sim.world.physics.bodies.get_mut(bone) {
                b.set_next_kinematic_position(pose);
            }
            sim.step();
            done += 1;
            observe(&sim.world, done as f64 / total as f64);
            if sim.exploded() {
                break;
            }
        }
        sim.release(bone);
        // The direction of the last layer of cells (the bend kept over the whole length),
        // averaged over the last second: a bar still ringing rings about its set.
        let cell = self.thickness / (self.cube.resolution.max(2) - 1) as Real;
        let layer = |sim: &Sim, x: Real| -> Vector {
            let ids: Vec<usize> = (0..mesh.nodes().len())
                .filter(|&i| (mesh.nodes()[i][0] - x).abs() < 1e-4)
                .collect();
            ids.iter().map(|&i| sim.positions()[i]).sum::<Vector>() / ids.len() as Real
        };
        let tip = 0.5 * self.length;
        let (recovering, last_second) = (steps(self.recover), steps(1.0));
        let (mut sum, mut count) = (0.0, 0);
        for k in 0..recovering {
            if sim.exploded() {
                break;
            }
            sim.step();
            done += 1;
            observe(&sim.world, (done as f64 / total as f64).min(1.0));
            if k + last_second >= recovering {
                let last = layer(&sim, tip) - layer(&sim, tip - cell);
                sum += last[1].atan2(last[0]);
                count += 1;
            }
        }
        let kept = sum / count.max(1) as Real;
        let theory = self.theory();
        let mut r = sim.record("bend", c.resolution);
        r.kept_bend = Some(kept as f64);
        r.kept_bend_theory = Some(theory as f64);
        r.failure = crate::record::failure(&[
            (r.nan, "non-finite state"),
            (r.exploded, "exploded"),
            (r.max_inverted_elements > 0, "inverted cells"),
            ((kept / theory - 1.0).abs() > 0.15, "bend off the beam's"),
        ]);
        r.failed = r.failure.is_some();
        Ok(r)
    }
}
