//! Several soft bodies in one world, sinew's or rapier's (issue 14's contact scenes): two cubes
//! stacked, a pile dropped into a trimesh bowl, a ball squeezed between two pads.

use std::time::Instant;

use super::super::level;
use super::super::lib::math::{Real, Vector, DIM, UP};
use super::super::lib::mesh::{CellKind, Mesh};
use super::super::lib::model::ElementModel;
use super::super::lib::rapier::dynamics::RigidBodyBuilder;
use super::super::lib::rapier::geometry::{Ball, ColliderBuilder};
use super::super::lib::BuildError;
use super::super::lib::DeformableWorld;
use super::super::lib::Integrator;
use super::super::lib::Material;
use super::fall::{self, cuboid};
use super::metrics::interpenetration;
use super::sim::{
    self, drive_pins, insert_soft, lumped_masses, pins_of, read_state, rest_positions, BodySpec,
    Pin, Soft, RAPIER_SKIN,
};
use super::subject::Subject;
use super::Record;

/// One body of a [`Flock`].
struct Member {
    soft: Soft,
    pins: Vec<Pin>,
    mesh: Mesh,
    masses: Vec<Real>,
    x: Vec<Vector>,
    v: Vec<Vector>,
}

/// Several soft bodies of one [`Subject`] in a world, stepped and measured alike.
pub(crate) struct Flock {
    pub world: DeformableWorld,
    subject: Subject,
    members: Vec<Member>,
    steps: usize,
    substeps: usize,
    max_substeps: usize,
    wall: f64,
    pairs_wall: f64,
    exploded: bool,
    nan: bool,
}

impl Flock {
    pub fn new(
        mut world: DeformableWorld,
        subject: Subject,
        specs: Vec<BodySpec>,
    ) -> Result<Flock, BuildError> {
        let mut members = Vec::with_capacity(specs.len());
        for spec in &specs {
            let masses = lumped_masses(&spec.mesh, &spec.material);
            let rest = rest_positions(spec);
            let pins = pins_of(&world, spec, &rest)?;
            let pinned: Vec<u32> = pins.iter().map(|p| p.node).collect();
            let soft = insert_soft(&mut world, subject, spec, &rest, &masses, &pinned, None)?;
            members.push(Member {
                soft,
                pins,
                mesh: spec.mesh.clone(),
                masses,
                v: vec![Vector::ZERO; rest.len()],
                x: rest,
            });
        }
        Ok(Flock {
            world,
            subject,
            members,
            steps: 0,
            substeps: 0,
            max_substeps: 0,
            wall: 0.0,
            pairs_wall: 0.0,
            exploded: false,
            nan: false,
        })
    }

    /// One step of the world; returns its wall time, s.
    pub fn step(&mut self) -> f64 {
        let iterations = self
            .world
            .physics
            .integration_parameters
            .num_solver_iterations;
        for m in &self.members {
            drive_pins(&mut self.world, m.soft, &m.pins);
        }
        let t0 = Instant::now();
        let report = self.world.step();
        let wall = t0.elapsed().as_secs_f64();
        let substeps = match self.subject {
            Subject::Sinew(_) => report.max_substeps(),
            Subject::Rapier(_) => iterations,
        };
        self.pairs_wall += report.pairs_time;
        self.wall += wall;
        self.steps += 1;
        self.substeps += substeps;
        self.max_substeps = self.max_substeps.max(substeps);
        self.read_back();
        wall
    }

    fn read_back(&mut self) {
        for m in &mut self.members {
            let (nan, exploded) = read_state(&self.world, m.soft, &mut m.x, &mut m.v);
            self.nan |= nan;
            self.exploded |= exploded;
        }
    }

    /// The deepest any body's surface node is inside another body (pairs whose boxes overlap).
    pub fn interpenetration(&self) -> Real {
        let boxes: Vec<(Vector, Vector)> = self
            .members
            .iter()
            .map(|m| {
                let lo =
                    m.x.iter()
                        .fold(Vector::splat(Real::INFINITY), |a, p| a.min(*p));
                let hi =
                    m.x.iter()
                        .fold(Vector::splat(Real::NEG_INFINITY), |a, p| a.max(*p));
                (lo, hi)
            })
            .collect();
        let mut deepest: Real = 0.0;
        for (a, ma) in self.members.iter().enumerate() {
            for (b, mb) in self.members.iter().enumerate() {
                let overlap = (0..DIM)
                    .all(|d| boxes[a].0[d] <= boxes[b].1[d] && boxes[b].0[d] <= boxes[a].1[d]);
                if a != b && overlap {
                    let d = interpenetration((&ma.mesh, &ma.x), (&mb.mesh, &mb.x));
                    deepest = deepest.max(d);
                }
            }
        }
        deepest
    }

    /// Kinetic plus gravitational energy of all soft bodies (height from 0), plus the elastic
    /// energy of sinew's (rapier's soft bodies do not say theirs), plus the kinetic and
    /// gravitational energy of the dynamic rigid bodies, J.
    pub fn energy(&self) -> Real {
        let physics = &self.world.physics;
        let g = -physics.gravity.dot(UP);
        let rigid: Real = physics
            .bodies
            .iter()
            .filter(|(_, b)| b.is_dynamic())
            .map(|(_, b)| b.kinetic_energy() + b.mass() * g * b.center_of_mass().dot(UP))
            .sum();
        let report = self.world.report();
        rigid
            + self
                .members
                .iter()
                .map(|m| {
                    let elastic = match m.soft {
                        Soft::Sinew(h) => report.get(h).map_or(0.0, |r| r.elastic_energy),
                        Soft::Rapier(_) => 0.0,
                    };
                    elastic
                        + m.x
                            .iter()
                            .zip(&m.v)
                            .zip(&m.masses)
                            .map(|((x, v), mass)| mass * (0.5 * v.length_squared() + g * x.dot(UP)))
                            .sum::<Real>()
                })
                .sum::<Real>()
    }

    /// The deepest a node of sinew's bodies is inside a collider after the last step (the
    /// steps' reports), m; `None` for rapier's soft bodies, which do not say.
    pub fn deepest_node_penetration(&self) -> Option<Real> {
        let report = self.world.report();
        let sinew: Vec<Real> = self
            .members
            .iter()
            .filter_map(|m| match m.soft {
                Soft::Sinew(h) => Some(report.get(h).map_or(0.0, |r| r.max_penetration)),
                Soft::Rapier(_) => None,
            })
            .collect();
        (!sinew.is_empty()).then(|| sinew.into_iter().fold(0.0, Real::max))
    }

    /// Whether a body blew up (or turned non-finite).
    pub fn exploded(&self) -> bool {
        self.exploded || self.nan
    }

    /// The fastest node of any body, m/s.
    pub fn fastest(&self) -> Real {
        self.members
            .iter()
            .flat_map(|m| m.v.iter())
            .map(|v| v.length())
            .fold(0.0, Real::max)
    }

    /// The lowest node of any body.
    pub fn lowest(&self) -> Real {
        self.members
            .iter()
            .flat_map(|m| m.x.iter())
            .map(|p| p.dot(UP))
            .fold(Real::INFINITY, Real::min)
    }

    /// Centre of mass height of body `k`.
    pub fn com_height(&self, k: usize) -> Real {
        let m = &self.members[k];
        let total: Real = m.masses.iter().sum();
        m.x.iter()
            .zip(&m.masses)
            .map(|(x, w)| x.dot(UP) * w)
            .sum::<Real>()
            / total
    }

    /// Centre of mass of body `k`.
    pub fn centre(&self, k: usize) -> Vector {
        let m = &self.members[k];
        let total: Real = m.masses.iter().sum();
        m.x.iter()
            .zip(&m.masses)
            .map(|(x, w)| *x * *w)
            .sum::<Vector>()
            / total
    }

    /// Whether every body is asleep (sinew's; `None` for rapier's, which do not say).
    pub fn asleep(&self) -> Option<bool> {
        self.members
            .iter()
            .map(|m| match m.soft {
                Soft::Sinew(h) => self.world.deformables.get(h).map(|b| b.is_sleeping()),
                Soft::Rapier(_) => None,
            })
            .collect::<Option<Vec<bool>>>()
            .map(|all| all.iter().all(|&a| a))
    }

    /// A record with what every multi-body scene measures.
    pub fn record(&self, scene: &str, res: usize) -> Record {
        let params = &self.world.physics.integration_parameters;
        let (mut inverted, mut min_ratio) = (0, Real::INFINITY);
        for m in &self.members {
            for c in 0..m.mesh.num_cells() {
                let q = m.mesh.cell_quality(c, &m.x);
                if q.is_nan() || q <= 0.0 {
                    inverted += 1;
                }
                min_ratio = min_ratio.min(q);
            }
        }
        let kinetic: Real = self
            .members
            .iter()
            .map(|m| {
                m.v.iter()
                    .zip(&m.masses)
                    .map(|(v, w)| 0.5 * w * v.length_squared())
                    .sum::<Real>()
            })
            .sum();
        Record {
            scene: scene.to_string(),
            dim: DIM,
            model: self.subject.name().to_string(),
            iterations: self.subject.iterations(),
            integrator: sim::integrator_name(self.subject, self.world.pipeline.settings.integrator),
            sweeps: sim::sweeps(self.subject, self.world.pipeline.settings.integrator),
            res,
            bodies: Some(self.members.len()),
            nodes: self.members.iter().map(|m| m.x.len()).sum(),
            elements: self.members.iter().map(|m| m.mesh.num_cells()).sum(),
            dt: params.dt as f64,
            substep_mode: "auto".to_string(),
            substeps: self.substeps as f64 / self.steps.max(1) as f64,
            max_substeps: self.max_substeps,
            sim_s: self.world.time() as f64,
            wall_s: self.wall,
            pairs_wall_s: matches!(self.subject, Subject::Sinew(_)).then_some(self.pairs_wall),
            min_vol_ratio: min_ratio as f64,
            final_inverted_elements: inverted,
            max_inverted_elements: inverted,
            final_kinetic_energy: kinetic as f64,
            nan: self.nan,
            exploded: self.exploded,
            ..Record::default()
        }
    }
}

/// What the multi-body scenes measure over a run, followed step by step.
#[derive(Default)]
pub(super) struct Watch {
    /// Deepest interpenetration over the whole run and over its last second.
    deepest: Real,
    deepest_at_rest: Real,
    energy_start: Real,
    /// The lowest total energy so far, and the largest rise above it.
    energy_low: Real,
    energy_rise: Real,
    /// The highest total energy so far.
    energy_high: Real,
}

impl Watch {
    fn new(flock: &Flock) -> Self {
        let e = flock.energy();
        Watch {
            energy_start: e,
            energy_low: e,
            energy_high: e,
            ..Default::default()
        }
    }

    /// Steps `flock` for `seconds` of `dt`, measuring the interpenetration every `every` steps
    /// and every step of the last second, calling `each` and then `observe` (with the world and
    /// the fraction done) after every step; stops early on an explosion.
    pub(super) fn run(
        flock: &mut Flock,
        (dt, seconds): (Real, Real),
        every: usize,
        mut each: impl FnMut(&Flock),
        observe: &mut dyn FnMut(&DeformableWorld, f64),
    ) -> Watch {
        let steps = (seconds / dt).round() as usize;
        let rest_from = steps.saturating_sub((1.0 / dt).round() as usize);
        let mut watch = Watch::new(flock);
        for k in 0..steps {
            flock.step();
            watch.observe(flock, k >= rest_from, k % every.max(1) == 0);
            each(flock);
            observe(&flock.world, (k + 1) as f64 / steps as f64);
            if flock.exploded {
                break;
            }
        }
        watch
    }

    fn observe(&mut self, flock: &Flock, last_second: bool, every: bool) {
        let e = flock.energy();
        self.energy_low = self.energy_low.min(e);
        self.energy_rise = self.energy_rise.max(e - self.energy_low);
        self.energy_high = self.energy_high.max(e);
        if every || last_second {
            let d = flock.interpenetration();
            self.deepest = self.deepest.max(d);
            if last_second {
                self.deepest_at_rest = self.deepest_at_rest.max(d);
            }
        }
    }

    pub(super) fn fill(&self, r: &mut Record, flock: &Flock, size: Real) {
        r.max_interpenetration = Some(self.deepest as f64);
        r.rest_interpenetration = Some(self.deepest_at_rest as f64);
        let start = self.energy_start.abs().max(1e-9);
        r.energy_gain = Some((self.energy_rise / start) as f64);
        r.energy_over_start = Some(((self.energy_high - self.energy_start) / start) as f64);
        r.energy_change = Some(((flock.energy() - self.energy_start) / start) as f64);
        r.asleep = flock.asleep();
        r.final_speed = Some(flock.fastest() as f64);
        r.failure = crate::record::failure(&[
            (r.nan, "non-finite state"),
            (r.exploded, "exploded"),
            (r.final_inverted_elements > 0, "ended with inverted cells"),
            (
                self.deepest_at_rest > 0.01 * size,
                "bodies inside each other at rest by more than 1 % of their size",
            ),
        ]);
        r.failed = r.failure.is_some();
    }
}

fn ground(world: &mut DeformableWorld, half_width: Real) {
    let mut half = Vector::splat(half_width);
    half[1] = 0.5;
    world.physics.insert(
        RigidBodyBuilder::fixed().translation(-UP * 0.5),
        ColliderBuilder::new(cuboid(half)),
    );
}

/// The scenes' soft material: 400 kg/m³, E = 10⁵ Pa, damping ratio `damping_ratio`.
fn cube_material(damping_ratio: Real) -> Material {
    Material {
        density: 400.0,
        young_modulus: 1e5,
        damping_ratio,
        ..Default::default()
    }
}

fn cube_mesh(size: Real, res: usize) -> Result<Mesh, BuildError> {
    Mesh::cuboid(Vector::splat(0.5 * size), [res; DIM], CellKind::Simplex)
}

/// Two soft cubes of `size` on the ground, the upper one dropped on the lower from `gap` above
/// it, `offset` off its axis; `seconds` long. Records the deepest one went into the other over
/// the run and over its last second, the upper one's rest height, the energy, the cost.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct StackScene {
    /// What is simulated.
    pub subject: Subject,
    /// Cube edge, m.
    pub size: Real,
    /// Nodes per edge.
    pub resolution: usize,
    /// The cubes' material.
    pub material: Material,
    /// Drop height of the upper cube above the lower one, m.
    pub gap: Real,
    /// Sideways offset of the upper cube, m.
    pub offset: Real,
    /// Step length, s.
    pub dt: Real,
    /// Simulated time, s.
    pub seconds: Real,
    /// sinew's integrator.
    pub integrator: Integrator,
}

impl Default for StackScene {
    /// Edge-repulsion cubes of 0.5 m at res 4, 400 kg/m³, E = 10⁵ Pa, ζ = 0.8, dropped 5 cm
    /// and 5 cm off axis, 60 Hz, 4 s.
    fn default() -> Self {
        StackScene {
            subject: Subject::Sinew(ElementModel::EdgeRepulsion),
            size: 0.5,
            resolution: 4,
            material: cube_material(0.8),
            gap: 0.05,
            offset: 0.05,
            dt: 1.0 / 60.0,
            seconds: 4.0,
            integrator: Integrator::Explicit,
        }
    }
}

impl StackScene {
    /// Runs the drop.
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
        ground(&mut world, 5.0);
        let mesh = cube_mesh(self.size, self.resolution)?;
        let lower = BodySpec::new(mesh.clone(), UP * (0.5 * self.size), self.material);
        let mut at = UP * (1.5 * self.size + self.gap);
        at[0] = self.offset;
        let upper = BodySpec::new(mesh, at, self.material);
        let mut flock = Flock::new(world, self.subject, vec![lower, upper])?;
        let watch = Watch::run(&mut flock, (self.dt, self.seconds), 1, |_| {}, &mut observe);
        let mut r = flock.record("stack", self.resolution);
        r.young = self.material.young_modulus as f64;
        r.rest_com = Some(flock.com_height(1) as f64);
        watch.fill(&mut r, &flock, self.size);
        Ok(r)
    }
}

/// `bodies` soft cubes of `size` dropped in a grid of layers into a trimesh bowl (a square
/// floor with four walls sloping out at 45°, `bowl` wide at the floor; a polyline in 2D),
/// `seconds` long. Records the deepest any body went into another (over the run and its last
/// second), the lowest node, the energy, the cost and the time spent finding the pairs of
/// deformables that may touch.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct PileScene {
    /// What is simulated.
    pub subject: Subject,
    /// How many bodies.
    pub bodies: usize,
    /// Cube edge, m.
    pub size: Real,
    /// Nodes per edge.
    pub resolution: usize,
    /// The cubes' material.
    pub material: Material,
    /// Width of the bowl's floor, m (0: sized to the pile).
    pub bowl: Real,
    /// Step length, s.
    pub dt: Real,
    /// Simulated time, s.
    pub seconds: Real,
    /// sinew's integrator (an island of deformables that may touch steps explicitly).
    pub integrator: Integrator,
    /// sinew's `PipelineSettings::damp_held` (default true).
    pub damp_held: bool,
}

impl Default for PileScene {
    /// Ten edge-repulsion cubes of 0.2 m at res 4, 400 kg/m³, E = 10⁵ Pa, ζ = 0.5, 60 Hz, 3 s.
    /// (At res 3, two cells an edge, the cubes' edges cross each other's faces with no node
    /// inside: 3D soft contact has no edge–edge test yet.)
    fn default() -> Self {
        PileScene {
            subject: Subject::Sinew(ElementModel::EdgeRepulsion),
            bodies: 10,
            size: 0.2,
            resolution: 4,
            material: cube_material(0.5),
            bowl: 0.0,
            dt: 1.0 / 60.0,
            seconds: 3.0,
            integrator: Integrator::Explicit,
            damp_held: true,
        }
    }
}

impl PileScene {
    /// Cubes per row of a layer and the bowl's floor width.
    fn layout(&self) -> (usize, Real) {
        let pitch = 1.5 * self.size;
        // About four layers: a row of a layer holds the rest.
        let per_layer = self.bodies.div_ceil(4).max(1);
        let per_row = if DIM == 3 {
            (per_layer as Real).sqrt().ceil() as usize
        } else {
            per_layer
        };
        let width = if self.bowl > 0.0 {
            self.bowl
        } else {
            per_row as Real * pitch
        };
        (per_row.max(1), width)
    }

    /// Runs the drop.
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
        world.pipeline.settings.damp_held = self.damp_held;
        let (per_row, width) = self.layout();
        world.physics.insert(
            RigidBodyBuilder::fixed(),
            level::bowl(width, 2.0 * width.max(0.5)),
        );
        let mesh = cube_mesh(self.size, self.resolution)?;
        let pitch = 1.5 * self.size;
        let per_layer = if DIM == 3 { per_row * per_row } else { per_row };
        let specs: Vec<BodySpec> = (0..self.bodies)
            .map(|k| {
                let (layer, slot) = (k / per_layer, k % per_layer);
                let mut at = UP * (self.size + layer as Real * pitch);
                let centre = |i: usize| (i as Real - 0.5 * (per_row - 1) as Real) * pitch;
                at[0] = centre(slot % per_row);
                if DIM == 3 {
                    at[DIM - 1] = centre(slot / per_row);
                }
                // Alternate layers shifted a little, so the pile does not stand in columns.
                if layer % 2 == 1 {
                    at[0] += 0.25 * self.size;
                }
                BodySpec::new(mesh.clone(), at, self.material)
            })
            .collect();
        let mut flock = Flock::new(world, self.subject, specs)?;
        let mut lowest = Real::INFINITY;
        // The interpenetration of many bodies is costly: every tenth step, then each step of
        // the last second.
        let watch = Watch::run(
            &mut flock,
            (self.dt, self.seconds),
            10,
            |f| lowest = lowest.min(f.lowest()),
            &mut observe,
        );
        let mut r = flock.record("pile", self.resolution);
        r.young = self.material.young_modulus as f64;
        r.max_penetration = Some((-lowest).max(0.0) as f64);
        watch.fill(&mut r, &flock, self.size);
        Ok(r)
    }
}

/// A soft ball of `radius` between two soft pads on the ground, a rigid box of `load` kg on
/// the upper pad squeezing it; `seconds` long. Records the deepest any body went into another,
/// the upper pad's rest height, the energy, the cost.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct SqueezeScene {
    /// What is simulated.
    pub subject: Subject,
    /// Ball radius, m.
    pub radius: Real,
    /// Lattice spacing of the ball and the pads, m.
    pub spacing: Real,
    /// The material of the ball and the pads.
    pub material: Material,
    /// The box's mass, kg.
    pub load: Real,
    /// Step length, s.
    pub dt: Real,
    /// Simulated time, s.
    pub seconds: Real,
}

impl Default for SqueezeScene {
    /// Edge repulsion; a 0.2 m ball and 0.8 × 0.2 m pads on a 0.1 m lattice, 400 kg/m³,
    /// E = 10⁵ Pa, ζ = 0.8; a 10 kg box; 60 Hz, 3 s.
    fn default() -> Self {
        SqueezeScene {
            subject: Subject::Sinew(ElementModel::EdgeRepulsion),
            radius: 0.2,
            spacing: 0.1,
            material: cube_material(0.8),
            load: 10.0,
            dt: 1.0 / 60.0,
            seconds: 3.0,
        }
    }
}

impl SqueezeScene {
    /// Runs the squeeze.
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
        ground(&mut world, 5.0);
        let thickness = 2.0 * self.spacing;
        let mut pad_half = Vector::splat(2.0 * self.radius);
        pad_half[1] = 0.5 * thickness;
        let pad_res = |d: usize| (2.0 * pad_half[d] / self.spacing).round() as usize + 1;
        let pad = Mesh::cuboid(pad_half, std::array::from_fn(pad_res), CellKind::Simplex)?;
        let ball = Mesh::from_shape(&Ball::new(self.radius), self.spacing, CellKind::Simplex)?;
        let gap = 0.01;
        let lower_at = UP * (0.5 * thickness);
        let ball_at = UP * (thickness + gap + self.radius);
        let upper_at = UP * (thickness + 2.0 * (gap + self.radius) + 0.5 * thickness);
        let specs = vec![
            BodySpec::new(pad.clone(), lower_at, self.material),
            BodySpec::new(ball, ball_at, self.material),
            BodySpec::new(pad, upper_at, self.material),
        ];
        let mut box_half = pad_half * 0.5;
        box_half[1] = 0.05;
        let box_volume: Real = (0..DIM).map(|d| 2.0 * box_half[d]).product();
        world.physics.insert(
            RigidBodyBuilder::dynamic().translation(upper_at + UP * (0.5 * thickness + 0.06)),
            ColliderBuilder::new(cuboid(box_half)).density(self.load / box_volume),
        );
        let mut flock = Flock::new(world, self.subject, specs)?;
        let watch = Watch::run(&mut flock, (self.dt, self.seconds), 1, |_| {}, &mut observe);
        let mut r = flock.record(
            "squeeze",
            (2.0 * self.radius / self.spacing).round() as usize,
        );
        r.young = self.material.young_modulus as f64;
        r.mass = Some(self.load as f64);
        r.rest_com = Some(flock.com_height(2) as f64);
        watch.fill(&mut r, &flock, 2.0 * self.radius);
        Ok(r)
    }
}

/// A tower of `bodies` soft cubes of `size` on the ground, each on the one below, alternately
/// `offset / 2` either side of the vertical axis: built at rest (`gap` 0, faces touching, as a
/// stack placed in an editor is) or dropped (each cube `gap` above the one below); `seconds`
/// long. Records the deepest one went into another (over the run and its last second), the
/// total energy's largest rise above its start and its change by the end, how far the cubes
/// end from the axis, how high the top one ends against how high it was built, whether all
/// sleep at the end, the cost.
///
/// Choose towers that physics says must stand: a column of the cubes' material is stable
/// below Greenhill's self-weight buckling height, `(7.84 E I / (ρ g A))^(1/3)`; for the default
/// cubes (E = 2 MPa, 400 kg/m³, 0.4 m) that is 3.8 m, against a 2.4 m tower of six.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct TowerScene {
    /// What is simulated.
    pub subject: Subject,
    /// How many cubes.
    pub bodies: usize,
    /// Cube edge, m.
    pub size: Real,
    /// Nodes per edge.
    pub resolution: usize,
    /// The cubes' material.
    pub material: Material,
    /// The cubes' friction (and the ground's).
    pub friction: Real,
    /// The cubes' restitution.
    pub restitution: Real,
    /// Gap below each cube as built, m: 0 builds the tower at rest.
    pub gap: Real,
    /// Sideways distance between one cube's axis and the next, m.
    pub offset: Real,
    /// sinew's cubes: the rate their deformation is damped toward their rigid motion, 1/s
    /// (`DeformableBuilder::deformation_damping`; rapier's bodies get none).
    pub deformation_damping: Real,
    /// Step length, s.
    pub dt: Real,
    /// Simulated time, s.
    pub seconds: Real,
    /// sinew's integrator.
    pub integrator: Integrator,
    /// sinew's `PipelineSettings::damp_held` (default true).
    pub damp_held: bool,
}

impl Default for TowerScene {
    /// Six edge-repulsion cubes of 0.4 m at res 4, 400 kg/m³, E = 2·10⁶ Pa, ν = 0.3, ζ = 0.3,
    /// friction 0.5, restitution 0, built at rest 3 cm apart sideways; 60 Hz, 10 s.
    fn default() -> Self {
        TowerScene {
            subject: Subject::Sinew(ElementModel::EdgeRepulsion),
            bodies: 6,
            size: 0.4,
            resolution: 4,
            material: Material {
                density: 400.0,
                young_modulus: 2e6,
                poisson_ratio: 0.3,
                damping_ratio: 0.3,
            },
            friction: 0.5,
            restitution: 0.0,
            gap: 0.0,
            offset: 0.03,
            deformation_damping: 0.0,
            dt: 1.0 / 60.0,
            seconds: 10.0,
            integrator: Integrator::Explicit,
            damp_held: true,
        }
    }
}

impl TowerScene {
    /// Builds the tower (rapier's bodies a contact skin apart, where they rest) and its world.
    fn flock(&self) -> Result<Flock, BuildError> {
        let mut world = DeformableWorld::new();
        world.set_dt(self.dt);
        world.pipeline.settings.integrator = self.integrator;
        world.pipeline.settings.damp_held = self.damp_held;
        fall::ground(&mut world, self.friction, 0.0);
        let skin = match self.subject {
            Subject::Sinew(_) => 0.0,
            Subject::Rapier(_) => RAPIER_SKIN,
        };
        let mesh = cube_mesh(self.size, self.resolution)?;
        let specs = (0..self.bodies)
            .map(|k| {
                let below = k as Real * (self.size + self.gap + 2.0 * skin);
                let mut at = UP * (skin + self.gap + below + 0.5 * self.size);
                at[0] = if k % 2 == 0 { -0.5 } else { 0.5 } * self.offset;
                let mut spec = BodySpec::new(mesh.clone(), at, self.material);
                spec.friction = self.friction;
                spec.deformation_damping = self.deformation_damping;
                spec.restitution = self.restitution;
                spec
            })
            .collect();
        Flock::new(world, self.subject, specs)
    }

    /// Runs the tower.
    pub fn run(&self) -> Result<Record, BuildError> {
        self.run_with(|_, _| {})
    }

    /// [`Self::run`], calling `observe` after every step with the world and the fraction done.
    pub fn run_with(
        &self,
        mut observe: impl FnMut(&DeformableWorld, f64),
    ) -> Result<Record, BuildError> {
        if self.bodies == 0 {
            return Err(BuildError::InvalidParameter {
                name: "bodies",
                value: 0.0,
                expected: "at least one cube",
            });
        }
        let mut flock = self.flock()?;
        let top = self.bodies.saturating_sub(1);
        // The top's height stacked at rest, whatever the gaps it was dropped from.
        let skin = match self.subject {
            Subject::Sinew(_) => 0.0,
            Subject::Rapier(_) => RAPIER_SKIN,
        };
        let built = skin + top as Real * (self.size + 2.0 * skin) + 0.5 * self.size;
        let watch = Watch::run(&mut flock, (self.dt, self.seconds), 1, |_| {}, &mut observe);
        let mut r = flock.record("tower", self.resolution);
        r.young = self.material.young_modulus as f64;
        r.poisson = self.material.poisson_ratio as f64;
        r.rest_com = Some(flock.com_height(top) as f64);
        r.top_height_ratio = Some((flock.com_height(top) / built) as f64);
        let scatter = (0..self.bodies)
            .map(|k| {
                let c = flock.centre(k);
                (c - UP * c.dot(UP)).length()
            })
            .fold(0.0, Real::max);
        r.scatter = Some(scatter as f64);
        watch.fill(&mut r, &flock, self.size);
        Ok(r)
    }
}
