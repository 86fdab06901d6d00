//! The `balloon` scene.

use super::super::lib::math::{Real, Vector, DIM};
use super::super::lib::mesh::{CellKind, Mesh};
use super::super::lib::rapier::dynamics::RigidBodyBuilder;
use super::super::lib::rapier::geometry::ColliderBuilder;
use super::super::lib::{BuildError, DeformableWorld, Gas, Material};
use super::fall::{cuboid, FallScene};
use super::sim::{BodySpec, Sim};
use super::Record;

/// A hollow rubber ball (no gravity) inflated by a gas at `pressure` Pa over the atmosphere
/// for `inflate` s, then squeezed between two plates closing at `speed` m/s each until its
/// cavity holds `squeeze` of its inflated volume (the plates stop where it does, and close
/// again if it bulges back out), held there `hold` s, and let go for `recover` s.
///
/// sinew's body holds the gas in its cavity (`DeformableBuilder::gas`); rapier 0.36's soft
/// bodies have no gas, only a volume target per piece of material (`volume_factor`), so
/// rapier's body is given the target `(p + p_a)/p_a`, the volume the gas would take
/// unconfined, on its material. The cavity's volume is measured the same way for both, from
/// the positions of its facets' nodes.
///
/// A run fails when it blows up, a cell inverts, the plates never bring the cavity to
/// `squeeze`, or (sinew) `pV` strays over 2 % from its value before the squeeze, or the
/// cavity ends over 1 % from its inflated volume.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct BalloonScene {
    /// Subject, resolution (nodes across the ball), step, integrator and material (Young's
    /// modulus, Poisson's ratio, damping ratio); its mass, size, height, friction and
    /// restitution are ignored.
    pub cube: FallScene,
    /// Outer radius, m.
    pub radius: Real,
    /// Wall thickness, m.
    pub wall: Real,
    /// Density, kg/m³.
    pub density: Real,
    /// Gauge pressure of the gas at the built shape, Pa.
    pub pressure: Real,
    /// The cavity's volume the plates squeeze it to, over its inflated volume.
    pub squeeze: Real,
    /// Closing speed of each plate, m/s.
    pub speed: Real,
    /// Time to inflate, s.
    pub inflate: Real,
    /// Time held at the squeeze, s.
    pub hold: Real,
    /// Time left to recover, s.
    pub recover: Real,
    /// sinew only: the rate of `DeformableBuilder::deformation_damping`, 1/s.
    pub deformation_damping: Real,
}

impl Default for BalloonScene {
    /// A 40 cm ball with 7 cm walls of rubber (E = 3·10⁵ Pa, ν = 0.45, 1100 kg/m³, damping
    /// ratio 0.1, deformation damping 5/s), 13 nodes across (21 in 2D), 20 kPa, squeezed to
    /// 70 % at 0.15 m/s a plate, 60 Hz, edge repulsion under the implicit step with 4 sweeps;
    /// inflate 1 s, hold 0.5 s, recover 2 s.
    fn default() -> Self {
        BalloonScene {
            cube: FallScene {
                resolution: if DIM == 3 { 13 } else { 21 },
                young_modulus: 3e5,
                poisson_ratio: 0.45,
                damping_ratio: 0.1,
                dt: 1.0 / 60.0,
                integrator: super::super::lib::Integrator::Implicit { iterations: 4 },
                ..FallScene::default()
            },
            radius: 0.2,
            wall: 0.07,
            density: 1100.0,
            pressure: 2e4,
            squeeze: 0.7,
            speed: 0.15,
            inflate: 1.0,
            hold: 0.5,
            recover: 2.0,
            deformation_damping: 5.0,
        }
    }
}

impl BalloonScene {
    /// The hollow ball: a lattice ball less the cells whose centre is inside the cavity.
    fn mesh(&self) -> Result<Mesh, BuildError> {
        let inner = self.radius - self.wall;
        Mesh::ball(self.radius, self.cube.resolution, CellKind::Simplex)?.retain_cells(|c| {
            let centre = c.iter().copied().sum::<Vector>() / c.len() as Real;
            centre.length() > inner
        })
    }

    /// Runs the scene, calling `observe` after every step with the world and the fraction done.
    pub fn run_with(
        &self,
        mut observe: impl FnMut(&DeformableWorld, f64),
    ) -> Result<Record, BuildError> {
        let c = &self.cube;
        let mut world = c.world();
        world.physics.gravity = Vector::ZERO;
        let mut half = Vector::splat(2.0 * self.radius);
        half[1] = 0.05;
        let mut plates = Vec::new();
        for side in [-1.0, 1.0] {
            let mut at = Vector::ZERO;
            at[1] = side * (2.0 * self.radius + half[1]);
            let (plate, _) = world.physics.insert(
                RigidBodyBuilder::kinematic_position_based().translation(at),
                ColliderBuilder::new(cuboid(half)).friction(0.5),
            );
            plates.push((plate, side));
        }
        let mesh = self.mesh()?;
        let cavity = mesh.chambers().into_iter().next().unwrap_or_default();
        let material = Material {
            density: self.density,
            young_modulus: c.young_modulus,
            poisson_ratio: c.poisson_ratio,
            damping_ratio: c.damping_ratio,
        };
        let mut spec = BodySpec::new(mesh, Vector::ZERO, material);
        spec.deformation_damping = self.deformation_damping;
        spec.gas = Some(Gas::gauge(self.pressure));
        let mut sim = Sim::new(world, c.subject, spec, 2.0 * self.radius, c.fixed_substeps)?;
        let volume = |sim: &Sim| Mesh::enclosed_volume(&cavity, sim.positions());
        let built = volume(&sim);
        // sinew's gas: `(P + p_a) V` is constant; the pressure is the law's at the volume.
        let pv = (self.pressure + Gas::ATMOSPHERE) * built;

        let steps = |t: Real| (t / c.dt).round() as usize;
        let total = steps(self.inflate) + steps(self.hold) + steps(self.recover);
        let mut done = 0;
        let mut step = |sim: &mut Sim, done: &mut usize| {
            sim.step();
            *done += 1;
            observe(&sim.world, (*done as f64 / total as f64).min(1.0));
        };
        for _ in 0..steps(self.inflate) {
            step(&mut sim, &mut done);
        }
        let inflated = volume(&sim);
        let top = sim.positions().iter().map(|p| p[1]).fold(0.0, Real::max);
        let bottom = sim.positions().iter().map(|p| -p[1]).fold(0.0, Real::max);
        let mut gap = top + bottom;
        // The plates close while the cavity holds more than the squeeze; the hold counts from
        // the first step it holds less. A run that never gets there stops after as long as
        // closing the whole gap takes.
        let closing = steps(gap / (2.0 * self.speed)) + steps(self.hold);
        let mut held = 0;
        let mut squeezed = None;
        for _ in 0..closing {
            if held >= steps(self.hold) || sim.exploded() {
                break;
            }
            if volume(&sim) > self.squeeze * inflated {
                gap = (gap - 2.0 * self.speed * c.dt).max(0.0);
            } else {
                held += 1;
            }
            move_plates(&mut sim, &plates, gap, half[1]);
            step(&mut sim, &mut done);
            let v = volume(&sim);
            squeezed = Some(squeezed.map_or(v, |s: Real| s.min(v)));
        }
        let at_squeeze = volume(&sim);
        move_plates(&mut sim, &plates, 4.0 * self.radius, half[1]);
        for _ in 0..steps(self.recover) {
            if sim.exploded() {
                break;
            }
            step(&mut sim, &mut done);
        }
        let back = volume(&sim);
        let mut r = sim.record("balloon", c.resolution);
        r.inflation = Some((inflated / built) as f64);
        r.gas_volume_ratio = squeezed.map(|s| (s / inflated) as f64);
        r.recovery_error = Some((back / inflated - 1.0).abs() as f64);
        let gas = sim.deformable().and_then(|d| d.chambers().first().copied());
        r.boyle_error =
            gas.map(|g| ((g.pressure + Gas::ATMOSPHERE) * g.volume / pv - 1.0).abs() as f64);
        let reached = at_squeeze <= (self.squeeze + 0.02) * inflated;
        r.failure = crate::record::failure(&[
            (r.nan, "non-finite state"),
            (r.exploded, "exploded"),
            (r.max_inverted_elements > 0, "inverted cells"),
            (!reached, "never squeezed"),
            (r.boyle_error.is_some_and(|e| e > 0.02), "pV off"),
            (
                r.recovery_error.is_some_and(|e| e > 0.01),
                "did not spring back",
            ),
        ]);
        r.failed = r.failure.is_some();
        Ok(r)
    }

    /// Runs the scene.
    pub fn run(&self) -> Result<Record, BuildError> {
        self.run_with(|_, _| {})
    }
}

/// Moves each plate (`side` −1 below, +1 above) so that their inner faces are `gap` apart.
fn move_plates(
    sim: &mut Sim,
    plates: &[(super::super::lib::rapier::dynamics::RigidBodyHandle, Real)],
    gap: Real,
    half: Real,
) {
    for &(plate, side) in plates {
        let mut at = Vector::ZERO;
        at[1] = side * (0.5 * gap + half);
        if let Some(b) = sim.world.physics.bodies.get_mut(plate) {
            b.set_next_kinematic_translation(at);
        }
    }
}
