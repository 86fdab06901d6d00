//! The `dent` scene.

use super::super::lib::math::{Real, Vector, DIM, UP};
use super::super::lib::mesh::{CellKind, Mesh};
use super::super::lib::rapier::dynamics::RigidBodyBuilder;
use super::super::lib::rapier::geometry::ColliderBuilder;
use super::super::lib::{BuildError, DeformableWorld, FlowIn, Material, Plasticity};
use super::fall::{cuboid, ground_at, FallScene};
use super::sim::{BodySpec, Sim};
use super::Record;

/// A soft plastic plate (`width` wide, `thickness` thick) resting on the ground, and a steel
/// box (`box_size` on a side, 7800 kg/m³) dropped flat on its middle from `drop` m above it.
/// The box rests on the plate for `press` s, is taken away, and the plate settles for `settle`
/// s: the dent it keeps is how far the middle of its top stays below where it was built.
///
/// rapier 0.36's body gets the yield on its material (`plastic_yield` for its cells,
/// `edge_plastic_yield` for its edges, instant creep).
///
/// A run fails when it blows up, a cell inverts, the box goes through the plate, or no dent
/// of at least 1 mm stays.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct DentScene {
    /// Subject, resolution (nodes across the thickness; across the width in proportion),
    /// step, integrator and material (Young's modulus, Poisson's ratio, damping ratio); its
    /// mass, size, height, friction and restitution are ignored.
    pub cube: FallScene,
    /// The plate's width (and depth in 3D), m.
    pub width: Real,
    /// Its thickness, m.
    pub thickness: Real,
    /// Its density, kg/m³.
    pub density: Real,
    /// Its yield strain (log).
    pub yield_strain: Real,
    /// The box's side, m.
    pub box_size: Real,
    /// The height the box falls from (its bottom over the plate's top), m.
    pub drop: Real,
    /// How long the box rests on the plate, s.
    pub press: Real,
    /// How long the plate settles after the box is taken away, s.
    pub settle: Real,
}

impl Default for DentScene {
    /// A 0.8 m plate, 10 cm thick, 5 cm cells (3 nodes across), E = 10⁶ Pa, ν = 0.3,
    /// 1000 kg/m³, damping ratio 0.3, yield 0.02; a 20 cm steel box dropped from 0.3 m; 1.5 s
    /// pressed, 1 s to settle; 60 Hz, edge repulsion under sinew's default integrator.
    fn default() -> Self {
        DentScene {
            cube: FallScene {
                resolution: 3,
                young_modulus: 1e6,
                poisson_ratio: 0.3,
                damping_ratio: 0.3,
                dt: 1.0 / 60.0,
                ..FallScene::default()
            },
            width: 0.8,
            thickness: 0.1,
            density: 1000.0,
            yield_strain: 0.02,
            box_size: 0.2,
            drop: 0.3,
            press: 1.5,
            settle: 1.0,
        }
    }
}

/// Steel, kg/m³.
const STEEL: Real = 7800.0;

impl DentScene {
    fn mesh(&self) -> Result<Mesh, BuildError> {
        let across = self.cube.resolution.max(2);
        let cell = self.thickness / (across - 1) as Real;
        let mut half = Vector::splat(0.5 * self.width);
        half[1] = 0.5 * self.thickness;
        let res: [usize; DIM] = std::array::from_fn(|d| {
            if d == 1 {
                across
            } else {
                (self.width / cell).round() as usize + 1
            }
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
        ground_at(&mut world, 0.0, 0.5, 0.0);
        let top = self.thickness;
        let half_box = Vector::splat(0.5 * self.box_size);
        let (steel, _) = world.physics.insert(
            RigidBodyBuilder::dynamic().translation(UP * (top + self.drop + half_box[1])),
            ColliderBuilder::new(cuboid(half_box))
                .density(STEEL)
                .friction(0.5),
        );
        let mesh = self.mesh()?;
        let mut spec = BodySpec::new(
            mesh.clone(),
            UP * (0.5 * self.thickness),
            Material {
                density: self.density,
                young_modulus: c.young_modulus,
                poisson_ratio: c.poisson_ratio,
                damping_ratio: c.damping_ratio,
            },
        );
        spec.restitution = 0.0;
        spec.plasticity = Some(Plasticity {
            yield_strain: self.yield_strain,
            flow_rate: Real::INFINITY,
            max_strain: 1.0,
            flow: FlowIn::Both,
        });
        let mut sim = Sim::new(world, c.subject, spec, self.width, c.fixed_substeps)?;
        // The top's nodes under the middle of the box.
        let middle: Vec<usize> = (0..mesh.nodes().len())
            .filter(|&i| {
                let p = mesh.nodes()[i];
                (p[1] - 0.5 * self.thickness).abs() < 1e-4
                    && (0..DIM)
                        .filter(|&d| d != 1)
                        .all(|d| p[d].abs() <= 0.25 * self.box_size + 1e-4)
            })
            .collect();
        let steps = |t: Real| (t / c.dt).round() as usize;
        let fall = ((2.0 * self.drop / 9.81).sqrt() / c.dt).ceil() as usize;
        let total = (fall + steps(self.press) + steps(self.settle)) as f64;
        let mut done = 0;
        let mut lowest_box = Real::INFINITY;
        for k in 0..fall + steps(self.press) + steps(self.settle) {
            if k == fall + steps(self.press) {
                sim.world.remove_body(steel);
            }
            sim.step();
            done += 1;
            observe(&sim.world, done as f64 / total);
            if let Some(b) = sim.world.physics.bodies.get(steel) {
                lowest_box = lowest_box.min(b.translation()[1] - half_box[1]);
            }
            if sim.exploded() {
                break;
            }
        }
        let height = middle.iter().map(|&i| sim.positions()[i][1]).sum::<Real>()
            / middle.len().max(1) as Real;
        let dent = top - height;
        let mut r = sim.record("dent", c.resolution);
        r.dent = Some(dent as f64);
        r.failure = crate::record::failure(&[
            (r.nan, "non-finite state"),
            (r.exploded, "exploded"),
            (r.max_inverted_elements > 0, "inverted cells"),
            (lowest_box < 0.0, "the box went through"),
            (dent < 1e-3, "no dent"),
        ]);
        r.failed = r.failure.is_some();
        Ok(r)
    }
}
