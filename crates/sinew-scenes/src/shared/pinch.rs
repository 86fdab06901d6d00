//! Pinch and lift: two kinematic fingers, each with a soft pad bound to it, squeeze a dynamic
//! box resting on the ground and lift it.

use super::super::lib::math::{Real, Vector, DIM, UP};
use super::super::lib::mesh::{CellKind, Mesh};
use super::super::lib::model::ElementModel;
use super::super::lib::rapier::dynamics::{RigidBodyBuilder, RigidBodyHandle};
use super::super::lib::rapier::geometry::ColliderBuilder;
use super::super::lib::BuildError;
use super::super::lib::DeformableWorld;
use super::super::lib::Integrator;
use super::super::lib::Material;
use super::fall::{cuboid, ground};
use super::flock::Flock;
use super::sim::{BodySpec, RAPIER_SKIN};
use super::subject::Subject;
use super::Record;

/// Half the box's edge, m.
const BOX_HALF: Real = 0.05;
/// The pads: thickness (across the grip), height and (3D) depth, m.
const PAD: [Real; 3] = [0.03, 0.1, 0.08];
/// Gap between each pad and the box before the fingers close, m.
const OPENING: Real = 0.01;

/// Two kinematic fingers carrying soft pads (their outer faces bound to the fingers) close on a
/// dynamic box of `mass` on the ground, squeezing each pad by `squeeze`, lift it `lift` and hold
/// it. Records the box's slip against the fingers over the lift and the hold, how much faster
/// than the fingers it ever moved, its deepest below the ground, and how uneven the steps' costs
/// are.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct PinchScene {
    /// What the pads are.
    pub subject: Subject,
    /// The box's mass, kg.
    pub mass: Real,
    /// The pads' material.
    pub material: Material,
    /// Friction of the pads, the box and the ground.
    pub friction: Real,
    /// How far each finger presses past first touch, m.
    pub squeeze: Real,
    /// Lift height, m.
    pub lift: Real,
    /// Seconds: the box settles, the fingers close, lift, hold.
    pub timeline: [Real; 4],
    /// Step length, s.
    pub dt: Real,
    /// sinew's integrator.
    pub integrator: Integrator,
}

impl Default for PinchScene {
    /// Edge-repulsion pads 3 × 10 × 8 cm at 1100 kg/m³, E = 2·10⁵ Pa, ν = 0.3, ζ = 0.3; a 10 cm
    /// box of 0.2 kg; friction 1; squeezed 5 mm a side, lifted 0.2 m in 1 s and held 1 s, after
    /// 0.25 s to settle and 0.5 s to close; 60 Hz.
    fn default() -> Self {
        PinchScene {
            subject: Subject::Sinew(ElementModel::EdgeRepulsion),
            mass: 0.2,
            material: Material {
                density: 1100.0,
                young_modulus: 2e5,
                poisson_ratio: 0.3,
                damping_ratio: 0.3,
            },
            friction: 1.0,
            squeeze: 0.005,
            lift: 0.2,
            timeline: [0.25, 0.5, 1.0, 1.0],
            dt: 1.0 / 60.0,
            integrator: Integrator::Explicit,
        }
    }
}

/// Where the fingers are at time `t` of a [`PinchScene`]: how far each has closed, and how
/// high it has lifted. Each motion starts and stops smoothly (a smoothstep in time), as a
/// gripper's does: a finger that jumps to speed leaves any held box a step behind.
fn finger_motion(scene: &PinchScene, t: Real) -> (Real, Real) {
    let [settle, close, lift, _] = scene.timeline;
    let ramp = |t: Real, start: Real, length: Real| {
        let u = ((t - start) / length).clamp(0.0, 1.0);
        u * u * (3.0 - 2.0 * u)
    };
    let closed = ramp(t, settle, close) * (OPENING + scene.squeeze);
    let lifted = ramp(t, settle + close, lift) * scene.lift;
    (closed, lifted)
}

impl PinchScene {
    /// The pads' mesh: nodes about 1.5 cm apart.
    fn pad_mesh() -> Result<Mesh, BuildError> {
        let half = Vector::from_slice(&PAD[..DIM]) * 0.5;
        let res = std::array::from_fn(|d| ((2.0 * half[d] / 0.015).round() as usize).max(2) + 1);
        Mesh::cuboid(half, res, CellKind::Simplex)
    }

    /// The world: ground, box, the two fingers; the pads' specs, each bound to its finger by
    /// its outer face.
    fn build(&self) -> Result<(Flock, RigidBodyHandle, [RigidBodyHandle; 2]), BuildError> {
        let mut world = DeformableWorld::new();
        world.set_dt(self.dt);
        world.pipeline.settings.integrator = self.integrator;
        ground(&mut world, self.friction, 0.0);
        let volume = (2.0 * BOX_HALF).powi(DIM as i32);
        let (box_body, _) = world.physics.insert(
            RigidBodyBuilder::dynamic().translation(UP * BOX_HALF),
            ColliderBuilder::new(cuboid(Vector::splat(BOX_HALF)))
                .density(self.mass / volume)
                .friction(self.friction),
        );
        let skin = match self.subject {
            Subject::Sinew(_) => 0.0,
            Subject::Rapier(_) => RAPIER_SKIN,
        };
        let mesh = Self::pad_mesh()?;
        let mut specs = Vec::new();
        let mut fingers = [box_body; 2];
        for (k, side) in [-1.0, 1.0].into_iter().enumerate() {
            let inner = BOX_HALF + OPENING + skin;
            let mut centre = UP * (BOX_HALF + 0.01);
            centre[0] = side * (inner + 0.5 * PAD[0]);
            let mut outer = centre;
            outer[0] = side * (inner + PAD[0]);
            let finger = world
                .physics
                .bodies
                .insert(RigidBodyBuilder::kinematic_position_based().translation(outer));
            fingers[k] = finger;
            let bound: Vec<u32> = (0..mesh.nodes().len() as u32)
                .filter(|&i| {
                    let x = mesh.nodes()[i as usize][0] * side;
                    x > 0.5 * PAD[0] - 1e-6
                })
                .collect();
            let mut spec = BodySpec::new(mesh.clone(), centre, self.material);
            spec.friction = self.friction;
            spec.restitution = 0.0;
            spec.pins = vec![(finger, bound)];
            specs.push(spec);
        }
        Ok((Flock::new(world, self.subject, specs)?, box_body, fingers))
    }

    /// Runs the pinch.
    pub fn run(&self) -> Result<Record, BuildError> {
        self.run_with(|_, _| {})
    }

    /// [`Self::run`], calling `observe` after every step with the world and the fraction done.
    pub fn run_with(
        &self,
        mut observe: impl FnMut(&DeformableWorld, f64),
    ) -> Result<Record, BuildError> {
        let (mut flock, box_body, fingers) = self.build()?;
        let start: [Vector; 2] = fingers.map(|f| flock.world.physics.bodies[f].translation());
        let total: Real = self.timeline.iter().sum();
        let steps = (total / self.dt).round() as usize;
        let lift_from = self.timeline[0] + self.timeline[1];
        let mut offset0 = None;
        let (mut slip, mut overspeed, mut lowest): (Real, Real, Real) = (0.0, 0.0, Real::INFINITY);
        let mut walls = Vec::with_capacity(steps);
        for k in 0..steps {
            let t = k as Real * self.dt;
            let (closed, lifted) = finger_motion(self, t + self.dt);
            for (f, (s, side)) in fingers.iter().zip(start.iter().zip([-1.0, 1.0])) {
                let mut at = *s + UP * lifted;
                at[0] -= side * closed;
                if let Some(b) = flock.world.physics.bodies.get_mut(*f) {
                    b.set_next_kinematic_translation(at);
                }
            }
            walls.push(flock.step());
            observe(&flock.world, (k + 1) as f64 / steps as f64);
            let finger_velocity = UP * ((lifted - finger_motion(self, t).1) / self.dt);
            let finger_height = flock.world.physics.bodies[fingers[0]].translation().dot(UP);
            let body = &flock.world.physics.bodies[box_body];
            let height = body.translation().dot(UP);
            lowest = lowest.min(height - BOX_HALF);
            // Faster than the fingers: a box lagging them as they start to lift does not count.
            overspeed = overspeed.max(body.linvel().length() - finger_velocity.length());
            if t + self.dt >= lift_from {
                let offset = height - finger_height;
                let o0 = *offset0.get_or_insert(offset);
                slip = slip.max((offset - o0).abs());
            }
            if flock.exploded() {
                break;
            }
        }
        let mut r = flock.record("pinch", (PAD[0] / 0.015).round() as usize + 1);
        r.young = self.material.young_modulus as f64;
        r.poisson = self.material.poisson_ratio as f64;
        r.mass = Some(self.mass as f64);
        r.slip = Some(slip as f64);
        r.overspeed = Some(overspeed as f64);
        r.max_penetration = Some((-lowest).max(0.0) as f64);
        r.rest_com = Some(flock.world.physics.bodies[box_body].translation().dot(UP) as f64);
        let mut sorted = walls.clone();
        sorted.sort_by(f64::total_cmp);
        let median = sorted.get(sorted.len() / 2).copied().unwrap_or(0.0);
        let worst = sorted.last().copied().unwrap_or(0.0);
        r.step_spike = Some(worst / median.max(1e-9));
        r.failure = crate::record::failure(&[
            (r.nan, "non-finite state"),
            (r.exploded, "exploded"),
            (r.final_inverted_elements > 0, "ended with inverted cells"),
            (slip > 0.05, "the box slipped over 5 cm"),
            (lowest < -0.01, "the box went over 1 cm into the ground"),
        ]);
        r.failed = r.failure.is_some();
        Ok(r)
    }
}
