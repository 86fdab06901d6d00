//! A long soft body folded double (issue 14): the surface meets itself.

use super::super::lib::math::{self, Pose, Real, Vector, DIM, UP};
use super::super::lib::mesh::{CellKind, Mesh};
use super::super::lib::model::ElementModel;
use super::super::lib::rapier::dynamics::RigidBodyBuilder;
use super::super::lib::rapier::geometry::ColliderBuilder;
use super::super::lib::BuildError;
use super::super::lib::DeformableWorld;
use super::super::lib::Integrator;
use super::super::lib::Material;
use super::fall::cuboid;
use super::metrics::self_interpenetration;
use super::sim::{BodySpec, Sim};
use super::subject::Subject;
use super::Record;

/// A sausage folded double on a table: a bar `2 m` long and `2 · spacing` thick (a square
/// section in 3D) lying on a fixed floor, its left end held by a kinematic bone, its right end
/// carried by another along a half turn over the bar until it lies upside down over the left
/// half, just touching it, and held there. Under gravity the upper
/// half lies on the lower one, and the fold's inner sides press together; without self contact
/// they pass into each other.
///
/// The record's `max_self_penetration` is the deepest a surface node went behind a facet of
/// the body's own surface ([`self_interpenetration`], up to half a cell deep), over the run.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct FoldScene {
    /// What is simulated.
    pub subject: Subject,
    /// Whether sinew's body has self contact on.
    pub self_contact: bool,
    /// Lattice spacing, m (the bar is two cells thick).
    pub spacing: Real,
    /// Young's modulus, Pa.
    pub young_modulus: Real,
    /// Density, kg/m³ (kg/m² in 2D).
    pub density: Real,
    /// Damping ratio.
    pub damping_ratio: Real,
    /// Time to fold, s (then as long again held).
    pub fold_seconds: Real,
    /// Step length, s.
    pub dt: Real,
    /// sinew's integrator.
    pub integrator: Integrator,
}

impl Default for FoldScene {
    /// Edge repulsion with self contact, 0.1 m spacing, E = 5·10⁴ Pa, 1000 kg/m³, ζ = 0.3, a
    /// 2 s fold and 2 s hold at 60 Hz, the explicit step.
    fn default() -> Self {
        FoldScene {
            subject: Subject::Sinew(ElementModel::EdgeRepulsion),
            self_contact: true,
            spacing: 0.1,
            young_modulus: 5.0e4,
            density: 1000.0,
            damping_ratio: 0.3,
            fold_seconds: 2.0,
            dt: 1.0 / 60.0,
            integrator: Integrator::Explicit,
        }
    }
}

/// Half the bar's length, m.
const HALF_LENGTH: Real = 1.0;
/// Where the carried end's centre ends, along the bar.
const END_X: Real = -0.7;

impl FoldScene {
    /// Nodes along the bar.
    pub fn resolution(&self) -> usize {
        (2.0 * HALF_LENGTH / self.spacing).round() as usize + 1
    }

    /// The carried end's pose after a fraction `s` of the fold: turned by `π s` about the axis
    /// normal to the x-y plane, along a half circle from the bar's right end to its place
    /// over the left half.
    fn carried_pose(&self, s: Real) -> Pose {
        let thickness = 2.0 * self.spacing;
        let start = Vector::X * HALF_LENGTH;
        let end = Vector::X * END_X + UP * thickness;
        let centre = (start + end) * 0.5;
        let s = s.clamp(0.0, 1.0);
        let smooth = s * s * (3.0 - 2.0 * s);
        let rotation =
            math::rotation_from_angle(math::planar_angle(std::f64::consts::PI as Real * smooth));
        Pose::from_parts(centre + rotation * (start - centre), rotation)
    }

    /// Runs the fold and the hold.
    pub fn run(&self) -> Result<Record, BuildError> {
        let mut world = DeformableWorld::new();
        world.set_dt(self.dt);
        world.pipeline.settings.integrator = self.integrator;
        let mut half = Vector::splat(self.spacing);
        half[0] = HALF_LENGTH;
        let mut res = [3usize; DIM];
        res[0] = self.resolution();
        let mesh = Mesh::cuboid(half, res, CellKind::Simplex)?;
        let tolerance = 1e-3 * self.spacing;
        let end = |side: Real| -> Vec<u32> {
            (0..mesh.nodes().len() as u32)
                .filter(|&i| (mesh.nodes()[i as usize].x - side * HALF_LENGTH).abs() < tolerance)
                .collect()
        };
        let mut floor = Vector::splat(3.0);
        floor[1] = 0.5;
        world.physics.insert(
            RigidBodyBuilder::fixed().translation(-UP * (self.spacing + 0.5)),
            ColliderBuilder::new(cuboid(floor)),
        );
        let held = world.physics.insert_body(
            RigidBodyBuilder::kinematic_position_based().translation(-Vector::X * HALF_LENGTH),
        );
        let carried = world.physics.insert_body(
            RigidBodyBuilder::kinematic_position_based().translation(Vector::X * HALF_LENGTH),
        );
        let mut spec = BodySpec::new(
            mesh.clone(),
            Vector::ZERO,
            Material {
                density: self.density,
                young_modulus: self.young_modulus,
                damping_ratio: self.damping_ratio,
                ..Default::default()
            },
        );
        spec.pins = vec![(held, end(-1.0)), (carried, end(1.0))];
        spec.self_contact = self.self_contact;
        let mut sim = Sim::new(world, self.subject, spec, 2.0 * HALF_LENGTH, None)?;
        let fold_steps = (self.fold_seconds / self.dt).round().max(1.0) as usize;
        let mut deepest: Real = 0.0;
        for k in 0..2 * fold_steps {
            let s = (k + 1) as Real / fold_steps as Real;
            let pose = self.carried_pose(s);
            if let Some(b) = sim.world.physics.bodies.get_mut(carried) {
                b.set_next_kinematic_position(pose);
            }
            sim.step();
            deepest = deepest.max(self_interpenetration(
                sim.mesh(),
                sim.positions(),
                0.5 * self.spacing,
            ));
            if sim.exploded() {
                break;
            }
        }
        let mut r = sim.record("fold", self.resolution());
        r.max_self_penetration = Some(deepest as f64);
        r.failure = crate::record::failure(&[
            (r.nan, "non-finite state"),
            (r.exploded, "exploded"),
            (r.final_inverted_elements > 0, "ended with inverted cells"),
            (
                deepest > 0.01 * self.spacing,
                "surface inside itself by more than 1 % of a cell",
            ),
        ]);
        r.failed = r.failure.is_some();
        Ok(r)
    }
}
