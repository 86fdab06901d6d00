//! The `tear` scene.

use super::super::lib::math::{Real, Vector, DIM, UP};
use super::super::lib::mesh::{CellKind, Mesh};
use super::super::lib::rapier::dynamics::RigidBodyBuilder;
use super::super::lib::{BuildError, DeformableWorld, Material, Tearing};
use super::fall::{ground_at, FallScene};
use super::sim::{BodySpec, Sim};
use super::Record;

/// A slab `length` long, 0.2 m high (0.1 m deep in 3D), weightless, its end faces bound to two
/// bones that pull it apart at `speed` m/s until it tears, and for `after` s more; then it is
/// let go under gravity over a ground 2 cm below, for `fall` s.
///
/// The pulled strain at the first tear is `ln(L/L₀)` of the bones' distance. rapier 0.36's
/// body gets the tear strain as its material's `tear_strain` (a nominal strain, `e^s − 1`) and
/// the smallest piece as its `min_piece`; a tear splits its pieces into new soft bodies and
/// renumbers its particles, so it is let go at its first tear, and its pieces are counted as
/// its soft bodies.
///
/// A run fails when it blows up, a cell inverts (sinew; rapier's up to its first tear), it
/// never tears, it tears over 10 % from the tear strain, or it does not end in two pieces.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct TearScene {
    /// Subject, resolution (nodes along the slab's height; along its length in proportion),
    /// step, integrator and material (Young's modulus, Poisson's ratio, damping ratio); its
    /// mass, size, height, friction and restitution are ignored.
    pub cube: FallScene,
    /// The slab's length, m.
    pub length: Real,
    /// Density, kg/m³.
    pub density: Real,
    /// The tear strain (log).
    pub tear_strain: Real,
    /// The fewest cells a torn-off piece may have.
    pub smallest_piece: usize,
    /// How fast the right bone moves away, m/s.
    pub speed: Real,
    /// How long the pull goes on after the first tear, s.
    pub after: Real,
    /// How long the pieces fall and settle, s.
    pub fall: Real,
}

impl Default for TearScene {
    /// A 1 m slab, 10 cm cells (3 nodes across its height), E = 10⁵ Pa, ν = 0.3, 1000 kg/m³,
    /// damping ratio 0.3, tear strain 0.1, pulled at 0.12 m/s and 0.25 s past the tear, 60 Hz,
    /// edge repulsion under sinew's default integrator; 3 s to fall and settle.
    fn default() -> Self {
        TearScene {
            cube: FallScene {
                resolution: 3,
                young_modulus: 1e5,
                poisson_ratio: 0.3,
                damping_ratio: 0.3,
                dt: 1.0 / 60.0,
                ..FallScene::default()
            },
            length: 1.0,
            density: 1000.0,
            tear_strain: 0.1,
            smallest_piece: 4,
            speed: 0.12,
            after: 0.25,
            fall: 3.0,
        }
    }
}

/// Half the slab's height, m.
const HALF_HEIGHT: Real = 0.1;
/// The ground's top, 2 cm below the slab: a piece landing from 0.4 m in the default scene was
/// strained `v/c ≈ 0.28` by the impact, past the tear strain, and tore again.
const GROUND: Real = -HALF_HEIGHT - 0.02;

impl TearScene {
    fn half_extents(&self) -> Vector {
        let mut half = Vector::splat(0.05);
        half[0] = 0.5 * self.length;
        half[1] = HALF_HEIGHT;
        half
    }

    fn mesh(&self) -> Result<Mesh, BuildError> {
        let half = self.half_extents();
        let across = self.cube.resolution.max(2);
        let cell = 2.0 * HALF_HEIGHT / (across - 1) as Real;
        let res: [usize; DIM] = std::array::from_fn(|d| match d {
            0 => (2.0 * half[0] / cell).round() as usize + 1,
            1 => across,
            _ => ((2.0 * half[d] / cell).round() as usize + 1).max(2),
        });
        Mesh::cuboid(half, res, CellKind::Simplex)
    }

    /// Runs the scene.
    pub fn run(&self) -> Result<Record, BuildError> {
        self.run_with(|_, _| {})
    }

    /// Runs the scene, calling `observe` after every step with the world and the fraction done
    /// (of the longest the pull may take and the fall).
    pub fn run_with(
        &self,
        mut observe: impl FnMut(&DeformableWorld, f64),
    ) -> Result<Record, BuildError> {
        let c = &self.cube;
        let mut world = c.world();
        world.physics.gravity = Vector::ZERO;
        ground_at(&mut world, GROUND, 0.5, 0.0);
        let mesh = self.mesh()?;
        let half = self.half_extents();
        let mut spec = BodySpec::new(
            mesh.clone(),
            Vector::ZERO,
            Material {
                density: self.density,
                young_modulus: c.young_modulus,
                poisson_ratio: c.poisson_ratio,
                damping_ratio: c.damping_ratio,
            },
        );
        spec.restitution = 0.0;
        spec.tearing = Some(Tearing {
            strain: self.tear_strain,
            smallest_piece: self.smallest_piece,
        });
        let mut bones = Vec::new();
        for side in [-1.0, 1.0] {
            let bone = world
                .physics
                .insert_body(RigidBodyBuilder::kinematic_position_based());
            let end: Vec<u32> = (0..mesh.nodes().len() as u32)
                .filter(|&i| (mesh.nodes()[i as usize][0] - side * half[0]).abs() < 1e-4)
                .collect();
            spec.pins.push((bone, end));
            bones.push(bone);
        }
        let mut sim = Sim::new(world, c.subject, spec, self.length, c.fixed_substeps)?;
        let pulling = (self.tear_strain.exp() * 1.5 - 1.0) * self.length / self.speed;
        let steps = |t: Real| (t / c.dt).round() as usize;
        let mut torn_at = None;
        let mut pulled = 0.0;
        let mut left_pull = steps(self.after);
        let total = (steps(pulling) + steps(self.fall)) as f64;
        let mut done = 0;
        for _ in 0..steps(pulling) {
            if sim.exploded() || left_pull == 0 {
                break;
            }
            pulled += self.speed * c.dt;
            let mut at = Vector::ZERO;
            at[0] = pulled;
            if let Some(b) = sim.world.physics.bodies.get_mut(bones[1]) {
                b.set_next_kinematic_translation(at);
            }
            sim.step();
            done += 1;
            observe(&sim.world, done as f64 / total);
            let tore = match sim.deformable() {
                Some(d) => !d.last_tears().is_empty(),
                None => pieces(&sim) > 1 || rapier_particles(&sim.world) != mesh.nodes().len(),
            };
            if tore && torn_at.is_none() {
                torn_at = Some(((self.length + pulled) / self.length).ln());
            }
            if torn_at.is_some() {
                // rapier's pins are its particle indices, which a tear renumbers.
                left_pull = if sim.deformable().is_some() {
                    left_pull - 1
                } else {
                    0
                };
            }
        }
        release(&mut sim);
        sim.world.physics.gravity = -UP * 9.81;
        for _ in 0..steps(self.fall) {
            if sim.exploded() {
                break;
            }
            sim.step();
            done += 1;
            observe(&sim.world, (done as f64 / total).min(1.0));
        }
        let mut r = sim.record("tear", c.resolution);
        r.torn_at_strain = torn_at.map(|s| s as f64);
        r.pieces = Some(pieces(&sim));
        r.final_speed = Some(fastest(&sim) as f64);
        let off = torn_at.is_some_and(|s| (s - self.tear_strain).abs() > 0.1 * self.tear_strain);
        r.failure = crate::record::failure(&[
            (r.nan, "non-finite state"),
            (r.exploded, "exploded"),
            (r.max_inverted_elements > 0, "inverted cells"),
            (torn_at.is_none(), "never tore"),
            (off, "tore off its tear strain"),
            (r.pieces != Some(2), "not two pieces"),
            (r.final_speed.is_some_and(|v| v > 0.1), "still moving"),
        ]);
        r.failed = r.failure.is_some();
        Ok(r)
    }
}

/// Lets the body go: sinew's bindings are dropped, rapier's particles (in every piece) unpinned.
fn release(sim: &mut Sim) {
    if let Some(h) = sim.handle() {
        if let Some(d) = sim.world.deformables.get_mut(h) {
            d.detach_all();
        }
        return;
    }
    for (_, body) in sim.world.physics.soft_bodies.iter_mut() {
        for i in 0..body.particles().len() {
            body.set_particle_pinned(i, false);
        }
    }
    sim.stop_pins();
}

/// All of rapier's particles, over every piece.
fn rapier_particles(world: &DeformableWorld) -> usize {
    world
        .physics
        .soft_bodies
        .iter()
        .map(|(_, b)| b.particles().len())
        .sum()
}

/// The body's pieces: sinew's cells joined through shared nodes; rapier's soft bodies.
fn pieces(sim: &Sim) -> usize {
    let Some(d) = sim.deformable() else {
        return sim.world.physics.soft_bodies.len();
    };
    let mesh = d.mesh();
    let mut root: Vec<usize> = (0..mesh.nodes().len()).collect();
    fn find(root: &mut [usize], mut i: usize) -> usize {
        while root[i] != i {
            root[i] = root[root[i]];
            i = root[i];
        }
        i
    }
    for c in mesh.cells() {
        for &i in &c[1..] {
            let (a, b) = (find(&mut root, c[0] as usize), find(&mut root, i as usize));
            root[a.max(b)] = a.min(b);
        }
    }
    let mut roots: Vec<usize> = mesh
        .cells()
        .map(|c| find(&mut root, c[0] as usize))
        .collect();
    roots.sort_unstable();
    roots.dedup();
    roots.len()
}

/// The fastest node's speed, over every piece.
fn fastest(sim: &Sim) -> Real {
    match sim.deformable() {
        Some(d) => d
            .velocities()
            .iter()
            .map(|v| v.length())
            .fold(0.0, Real::max),
        None => sim
            .world
            .physics
            .soft_bodies
            .iter()
            .flat_map(|(_, b)| b.particles().iter().map(|p| p.velocity().length()))
            .fold(0.0, Real::max),
    }
}
