//! A soft ball rolled down a trimesh ramp into a wall of dynamic boxes.

use super::super::level;
use super::super::lib::math::{Real, Vector, DIM, UP};
use super::super::lib::mesh::{CellKind, Mesh};
use super::super::lib::model::ElementModel;
use super::super::lib::rapier::dynamics::{RigidBodyBuilder, RigidBodyHandle};
use super::super::lib::rapier::geometry::{Ball, ColliderBuilder};
use super::super::lib::BuildError;
use super::super::lib::DeformableWorld;
use super::super::lib::Integrator;
use super::super::lib::Material;
use super::fall::cuboid;
use super::flock::{Flock, Watch};
use super::sim::BodySpec;
use super::subject::Subject;
use super::Record;

/// Half the edge of a box of the wall, m.
const BOX_HALF: Real = 0.05;

/// A soft ball of `radius` released at rest at the top of a ramp (`length` long at `slope`
/// radians, a trimesh in 3D, a polyline in 2D) rolls down it and along the floor into a wall of
/// dynamic boxes `distance` from the ramp's foot (3 wide by 2 high in 3D, a column of 3 in 2D,
/// each a 10 cm cube of `box_mass`), `seconds` long. Records the deepest a node of the ball went
/// into a collider (sinew; rapier's soft bodies do not say), the largest rise of the total
/// energy (ball and boxes) above its lowest so far and above its start, how far the farthest box
/// was knocked, and the cost.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct RollScene {
    /// What the ball is.
    pub subject: Subject,
    /// Ball radius, m.
    pub radius: Real,
    /// Lattice spacing of the ball's mesh, m.
    pub spacing: Real,
    /// The ball's material.
    pub material: Material,
    /// The ramp's length, m.
    pub length: Real,
    /// The ramp's slope, radians.
    pub slope: Real,
    /// From the ramp's foot to the wall, m.
    pub distance: Real,
    /// Each box's mass, kg.
    pub box_mass: Real,
    /// Friction of the ball, the ramp and the boxes.
    pub friction: Real,
    /// Step length, s.
    pub dt: Real,
    /// Simulated time, s.
    pub seconds: Real,
    /// sinew's integrator.
    pub integrator: Integrator,
    /// [`PipelineSettings::global_iterations`](sinew::dim3::PipelineSettings::global_iterations)
    /// of the implicit steps.
    pub global_iterations: Option<usize>,
}

impl Default for RollScene {
    /// An edge-repulsion ball of 10 cm radius on a 2.5 cm lattice, 400 kg/m³, E = 10⁵ Pa,
    /// ν = 0.3, ζ = 0.3; a 1.5 m ramp at 30°; the wall 0.6 m on, 0.2 kg boxes; friction 0.5;
    /// 60 Hz, 3 s. (On a 4 cm lattice the ball's staircase has a bottom face too wide to tip
    /// over at 30°: it rocks on it and stays.)
    fn default() -> Self {
        RollScene {
            subject: Subject::Sinew(ElementModel::EdgeRepulsion),
            radius: 0.1,
            spacing: 0.025,
            material: Material {
                density: 400.0,
                young_modulus: 1e5,
                poisson_ratio: 0.3,
                damping_ratio: 0.3,
            },
            length: 1.5,
            slope: 30.0_f64.to_radians() as Real,
            distance: 0.6,
            box_mass: 0.2,
            friction: 0.5,
            dt: 1.0 / 60.0,
            seconds: 3.0,
            integrator: Integrator::Explicit,
            global_iterations: None,
        }
    }
}

impl RollScene {
    /// The wall's boxes: their centres.
    fn wall(&self) -> Vec<Vector> {
        let (across, high) = if DIM == 3 { (3, 2) } else { (1, 3) };
        let mut out = Vec::new();
        for level in 0..high {
            for k in 0..across {
                let mut at = UP * (BOX_HALF + 2.0 * BOX_HALF * level as Real);
                at[0] = self.distance + BOX_HALF;
                if DIM == 3 {
                    at[DIM - 1] = (k as Real - 0.5 * (across - 1) as Real) * 2.0 * BOX_HALF;
                }
                out.push(at);
            }
        }
        out
    }

    /// Runs the roll.
    pub fn run(&self) -> Result<Record, BuildError> {
        self.run_with(|_, _| {})
    }

    /// [`Self::run`], calling `observe` after every step with the world and the fraction done.
    pub fn run_with(
        &self,
        mut observe: impl FnMut(&DeformableWorld, f64),
    ) -> Result<Record, BuildError> {
        let mut world = DeformableWorld::new();
        world.set_dt(self.dt);
        world.pipeline.settings.integrator = self.integrator;
        world.pipeline.settings.global_iterations = self.global_iterations;
        let run = self.distance + 5.0;
        world.physics.insert(
            RigidBodyBuilder::fixed(),
            level::ramp(self.length, self.slope, run).friction(self.friction),
        );
        let volume = (2.0 * BOX_HALF).powi(DIM as i32);
        let boxes: Vec<(RigidBodyHandle, Vector)> = self
            .wall()
            .into_iter()
            .map(|at| {
                let (h, _) = world.physics.insert(
                    RigidBodyBuilder::dynamic().translation(at),
                    ColliderBuilder::new(cuboid(Vector::splat(BOX_HALF)))
                        .density(self.box_mass / volume)
                        .friction(self.friction),
                );
                (h, at)
            })
            .collect();
        let mesh = Mesh::from_shape(&Ball::new(self.radius), self.spacing, CellKind::Simplex)?;
        // The lattice's nodes reach past the radius: a node started on the far side of the
        // two-sided ramp stays there and holds the ball.
        let reach = mesh
            .nodes()
            .iter()
            .map(|p| p.length())
            .fold(self.radius, Real::max);
        // On the ramp's top, a radius down it, a few millimetres above it.
        let (s, c) = (self.slope.sin(), self.slope.cos());
        let mut top = UP * (self.length * s);
        top[0] = -self.length * c;
        let mut down = -UP * s;
        down[0] = c;
        let mut normal = UP * c;
        normal[0] = s;
        let centre = top + down * reach + normal * (reach + 0.005);
        let mut spec = BodySpec::new(mesh, centre, self.material);
        spec.friction = self.friction;
        spec.restitution = 0.0;
        let mut flock = Flock::new(world, self.subject, vec![spec])?;
        let mut deepest: Option<Real> = None;
        let deepest_of = |f: &Flock| {
            if let Some(d) = f.deepest_node_penetration() {
                deepest = Some(deepest.unwrap_or(0.0).max(d));
            }
        };
        let timing = (self.dt, self.seconds);
        let watch = Watch::run(&mut flock, timing, 1, deepest_of, &mut observe);
        let mut r = flock.record("roll", (2.0 * self.radius / self.spacing).round() as usize);
        r.young = self.material.young_modulus as f64;
        r.poisson = self.material.poisson_ratio as f64;
        r.mass = Some(self.box_mass as f64);
        r.max_penetration = deepest.map(|d| d as f64);
        let bodies = &flock.world.physics.bodies;
        let knocked = boxes
            .iter()
            .filter_map(|(h, at)| Some((bodies.get(*h)?.translation() - *at).length()))
            .fold(0.0, Real::max);
        r.scatter = Some(knocked as f64);
        watch.fill(&mut r, &flock, 2.0 * self.radius);
        Ok(r)
    }
}
