//! The `crush` scene.

use super::super::lib::math::{Real, Vector, DIM, UP};
use super::super::lib::rapier::dynamics::{LockedAxes, RigidBodyBuilder, RigidBodyType};
use super::super::lib::rapier::geometry::ColliderBuilder;
use super::super::lib::BuildError;
use super::super::lib::DeformableWorld;
use super::fall::{cuboid, set_first_failure, FallScene};
use super::metrics::volume_ratio;
use super::sim::RAPIER_SKIN;
use super::Record;

/// The `fall` cube resting on the ground, crushed by a dynamic 1.2 m wide, 0.1 m thick rigid
/// box (1.2 × 1.2 × 0.1 m in 3D) laid on top, guided to move vertically only (see
/// [`CrushScene::guided`]): after `settle` seconds the box's gravity scale ramps from 0 to 1
/// over `ramp` s and holds until `hold` s; then the box is lifted away — raised at constant
/// speed back to its starting height over `lift` s, like a press retracting, and removed — and
/// the cube is left `recover` s to spring back. (Removing the box at full load would fling a
/// 1 kg cube holding kilojoules off at ~100 m/s.)
///
/// A run fails when an element inverts at any time or the box's lowest corner comes within
/// 1 % of the cube size of the ground. `shape_error` is measured at the end; `first_failure`
/// (set by [`CrushScene::run_masses`]) is the smallest failing mass.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct CrushScene {
    /// The cube, its material and stepping (its `drop_height` and `seconds` are ignored).
    pub cube: FallScene,
    /// Mass of the box, kg.
    pub mass: Real,
    /// Time the cube is left to settle before the load, s.
    pub settle: Real,
    /// Time over which the load ramps in, s.
    pub ramp: Real,
    /// Time (from the start of the load) at which the lift starts, s.
    pub hold: Real,
    /// Time over which the box is raised back to its starting height before it is removed, s.
    pub lift: Real,
    /// Time left to recover after the removal, s.
    pub recover: Real,
    /// Whether the box is guided like a press plate: it can only move vertically (default).
    /// A free box rides the cube's rebound, tilts and can slide off (see docs/STABILITY.md).
    pub guided: bool,
}

/// The masses of the crush sweep, kg.
pub const CRUSH_MASSES: [Real; 4] = [1.0, 10.0, 100.0, 1000.0];

impl Default for CrushScene {
    /// The default `fall` cube, 1000 kg, settle 1 s, ramp 1.5 s, hold to 3 s, lift 1.5 s,
    /// recover 2 s,
    /// guided box.
    fn default() -> Self {
        CrushScene {
            cube: FallScene::default(),
            mass: 1000.0,
            settle: 1.0,
            ramp: 1.5,
            hold: 3.0,
            lift: 1.5,
            recover: 2.0,
            guided: true,
        }
    }
}

impl CrushScene {
    /// Runs one mass, calling `observe` after every step with the world and the fraction done.
    pub fn run_with(
        &self,
        mut observe: impl FnMut(&DeformableWorld, f64),
    ) -> Result<Record, BuildError> {
        let c = &self.cube;
        let mut world = c.ground_world();
        let mut half = Vector::splat(0.6 * c.size);
        half[1] = 0.05 * c.size;
        let locked = if self.guided {
            LockedAxes::all().difference(LockedAxes::TRANSLATION_LOCKED_Y)
        } else {
            LockedAxes::empty()
        };
        let lid = world.physics.insert(
            RigidBodyBuilder::dynamic()
                .locked_axes(locked)
                .translation(UP * (c.size + 2.0 * RAPIER_SKIN + half[1]))
                .gravity_scale(0.0)
                .can_sleep(false),
            ColliderBuilder::new(cuboid(half))
                .mass(self.mass)
                .friction(c.friction)
                .restitution(0.0),
        );
        let lid = lid.0;
        let start_height = c.size + 2.0 * RAPIER_SKIN + half[1];
        let mut sim = c.sim_in(world, RAPIER_SKIN)?;

        let total = self.settle + self.hold + self.lift + self.recover;
        let steps = (total / c.dt).round() as usize;
        let mut max_penetration: Real = 0.0;
        let mut lowest_lid = Real::INFINITY;
        let mut present = true;
        let mut loaded_volume_ratio = None;
        for k in 0..steps {
            let t = (k as Real + 1.0) * c.dt - self.settle;
            // The load ramps in and holds; then the box is lifted back to where it started, at
            // constant speed, and removed.
            if let Some(b) = sim.world.physics.bodies.get_mut(lid) {
                if t < self.hold {
                    b.set_gravity_scale((t / self.ramp).clamp(0.0, 1.0), true);
                } else if b.is_dynamic() {
                    let rise = (start_height - b.translation().dot(UP)).max(0.0);
                    b.set_body_type(RigidBodyType::KinematicVelocityBased, true);
                    b.set_linvel(UP * (rise / self.lift.max(c.dt)), true);
                }
            }
            if present && t >= self.hold + self.lift {
                sim.world.remove_body(lid);
                present = false;
            }
            sim.step();
            // The static load's last step: the volume under it.
            if t < self.hold && t + c.dt >= self.hold {
                loaded_volume_ratio = Some(volume_ratio(sim.mesh(), sim.positions()) as f64);
            }
            max_penetration = max_penetration.max(-sim.lowest());
            if let Some(b) = sim.world.physics.bodies.get(lid) {
                let pose = b.position();
                let corners = (0..1usize << DIM).map(|bits| {
                    let mut p = half;
                    for d in 0..DIM {
                        if bits & (1 << d) != 0 {
                            p[d] = -p[d];
                        }
                    }
                    pose.transform_point(p).dot(UP)
                });
                lowest_lid = corners.fold(lowest_lid, Real::min);
            }
            observe(&sim.world, (k + 1) as f64 / steps as f64);
            if sim.exploded() {
                break;
            }
        }
        let mut r = sim.record("crush", c.resolution);
        r.mass = Some(self.mass as f64);
        r.rest_com = Some(sim.center_of_mass().dot(UP) as f64);
        r.max_penetration = Some(max_penetration as f64);
        r.shape_error = Some(sim.shape_error() as f64);
        r.loaded_volume_ratio = loaded_volume_ratio;
        r.failure = crate::record::failure(&[
            (r.exploded, "exploded"),
            (r.max_inverted_elements > 0, "inverted cells"),
            (lowest_lid <= 0.01 * c.size, "box reached the ground"),
        ]);
        r.failed = r.failure.is_some();
        Ok(r)
    }

    /// Runs one mass.
    pub fn run(&self) -> Result<Record, BuildError> {
        self.run_with(|_, _| {})
    }

    /// Runs each of `masses` (see [`CRUSH_MASSES`]) and sets every record's `first_failure` to
    /// the smallest failing mass.
    pub fn run_masses(
        &self,
        masses: &[Real],
        mut observe: impl FnMut(&DeformableWorld, f64),
    ) -> Result<Vec<Record>, BuildError> {
        let mut out = Vec::new();
        for (i, &mass) in masses.iter().enumerate() {
            let scene = CrushScene { mass, ..*self };
            out.push(
                scene.run_with(|w, done| observe(w, (i as f64 + done) / masses.len() as f64))?,
            );
        }
        set_first_failure(&mut out, |r| r.mass.unwrap_or(f64::NAN));
        Ok(out)
    }
}
