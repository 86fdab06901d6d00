//! Logging to the [Rerun](https://rerun.io) viewer (feature `rerun`).
//!
//! [`RerunRecorder`] logs one frame of a world — its deformables, its rapier colliders and the
//! step report — on two timelines, `step` (step index) and `sim_time` (simulated seconds).
//! What never changes is logged once, as static data: the view's axes, the surface topology,
//! each collider's shape (in its own frame; only its pose is logged per frame).
//!
//! Entity paths (stable; script against them):
//!
//! | path | what | when |
//! |---|---|---|
//! | `world` | view coordinates (3D: right-handed, y up) | static |
//! | `world/deformables/<name>/surface` | 3D: `Mesh3D` of the boundary (vertex `j` is node `mesh.boundary_nodes()[j]`), coloured by the chosen field; 2D: `LineStrips2D`, one two-point strip per boundary segment (`mesh.boundary_facets()` order) | every logged frame |
//! | `world/deformables/<name>/nodes` | all nodes as points, coloured by the field | if `nodes` |
//! | `world/deformables/<name>/edges` | every cell's vertex pairs as segments | if `edges` |
//! | `world/deformables/<name>/attachments` | segment node → its anchor on the bone | if `attachments` |
//! | `world/deformables/<name>/contacts/points`, `.../contacts/normals` | last step's contact points and normals | if `contacts` |
//! | `world/colliders/<index>_<generation>` | the collider's shape (static) and pose (per frame); grey fixed, orange kinematic (bones), blue dynamic | every logged frame |
//! | `stats/<name>/<metric>` | `Scalars`: `kinetic_energy`, `elastic_energy`, `inverted_elements`, `min_volume_ratio`, `max_penetration`, `contacts`, `substeps`, `ms_forces`, `ms_contacts`, `ms_integrate`, `frozen` (0/1), `log_ms` | every logged frame |
//! | `events/<name>` | `TextLog`: a warning when the body is frozen (why: non-finite state or a blow-up), info when it resumes | when it changes |
//!
//! `<name>` is what [`RerunRecorder::set_name`] gave the deformable, else `d<index>`.
//!
//! Colours: [`ColorField::VolumeRatio`] shades each surface vertex by the smallest volume ratio
//! of its cells (red compressed, white at rest, blue stretched); [`ColorField::Strain`] by the
//! mean `|L/L0 − 1|` of its incident vertex pairs (white 0 → red 0.25 and beyond; a stress
//! proxy is this times Young's modulus, so it is drawn the same). A vertex of a collapsed or
//! inverted cell is magenta in either case.

use std::collections::HashMap;
use std::time::Instant;

use super::body::Deformable;
use super::math::{Real, Vector, FACET_ARITY};
use super::rapier::dynamics::RigidBodySet;
use super::rapier::geometry::{ColliderHandle, ColliderSet};
use super::render;
use super::set::{DeformableHandle, DeformableSet};
use super::world::DeformableWorld;
use rerun::{Color, Scalars, TextLog, TextLogLevel};
pub use rerun::{RecordingStream, RecordingStreamBuilder};

/// Which field colours the surface.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Default)]
pub enum ColorField {
    /// One colour, magenta where cells are inverted.
    Uniform,
    /// Smallest volume ratio of the vertex's cells.
    #[default]
    VolumeRatio,
    /// Mean relative length change of the vertex's incident vertex pairs.
    Strain,
}

/// What to log.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct RecorderOptions {
    /// Surface colouring.
    pub color_field: ColorField,
    /// Log every node as a point.
    pub nodes: bool,
    /// Log every cell edge.
    pub edges: bool,
    /// Log bindings to bones.
    pub attachments: bool,
    /// Log contact points and normals.
    pub contacts: bool,
    /// Log every n-th call of [`RerunRecorder::log_frame`] (1 = every step).
    pub every_n_steps: u64,
}

impl Default for RecorderOptions {
    fn default() -> Self {
        RecorderOptions {
            color_field: ColorField::VolumeRatio,
            nodes: false,
            edges: false,
            attachments: true,
            contacts: false,
            every_n_steps: 1,
        }
    }
}

/// Why logging failed.
#[derive(Debug, thiserror::Error)]
pub enum RecorderError {
    /// The Rerun SDK refused (file, connection).
    #[error("rerun: {0}")]
    Rerun(#[from] rerun::RecordingStreamError),
    /// Creating the output folder failed.
    #[error("cannot create {path}: {source}")]
    Io {
        /// The path.
        path: String,
        /// The error.
        source: std::io::Error,
    },
}

struct DeformableLog {
    name: String,
    surface: Vec<u32>,
    facets: Vec<[u32; FACET_ARITY]>,
    /// Per node (CSR): incident cells.
    cell_start: Vec<u32>,
    cells: Vec<u32>,
    /// Per node (CSR): incident vertex pairs (other node, rest length).
    pair_start: Vec<u32>,
    pairs: Vec<(u32, Real)>,
    topology_logged: bool,
    /// Whether the body was frozen at the last logged frame.
    was_frozen: bool,
}

/// Logs worlds to Rerun. See the module documentation for the entity paths.
pub struct RerunRecorder {
    rec: RecordingStream,
    /// What to log.
    pub options: RecorderOptions,
    deformables: HashMap<DeformableHandle, DeformableLog>,
    names: HashMap<DeformableHandle, String>,
    shapes_logged: HashMap<ColliderHandle, bool>,
    view_logged: bool,
    calls: u64,
    frames: u64,
    log_seconds: f64,
}

const FIXED: [u8; 3] = [150, 150, 150];
const KINEMATIC: [u8; 3] = [230, 140, 40];
const DYNAMIC: [u8; 3] = [70, 130, 220];
const INVERTED: [u8; 3] = [255, 0, 255];
const ATTACHMENT: [u8; 3] = [240, 200, 40];
const CONTACT: [u8; 3] = [40, 200, 90];

fn rgb(c: [u8; 3]) -> Color {
    Color::from_rgb(c[0], c[1], c[2])
}

fn lerp(a: [f32; 3], b: [f32; 3], t: f32) -> Color {
    let t = t.clamp(0.0, 1.0);
    let c = |i: usize| (a[i] + (b[i] - a[i]) * t).round() as u8;
    Color::from_rgb(c(0), c(1), c(2))
}

impl RerunRecorder {
    /// A recorder over an existing recording stream.
    pub fn new(rec: RecordingStream, options: RecorderOptions) -> Self {
        RerunRecorder {
            rec,
            options,
            deformables: HashMap::new(),
            names: HashMap::new(),
            shapes_logged: HashMap::new(),
            view_logged: false,
            calls: 0,
            frames: 0,
            log_seconds: 0.0,
        }
    }

    /// A recorder saving to an `.rrd` file (its folder is created).
    pub fn save(
        application: &'static str,
        path: impl AsRef<std::path::Path>,
        options: RecorderOptions,
    ) -> Result<Self, RecorderError> {
        let path = path.as_ref();
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|source| RecorderError::Io {
                path: dir.display().to_string(),
                source,
            })?;
        }
        let rec = RecordingStreamBuilder::new(application)
            .enabled(true)
            .save(path)?;
        Ok(Self::new(rec, options))
    }

    /// A recorder streaming to a running viewer (`None`: the default local address).
    pub fn connect(
        application: &'static str,
        address: Option<&str>,
        options: RecorderOptions,
    ) -> Result<Self, RecorderError> {
        let builder = RecordingStreamBuilder::new(application).enabled(true);
        let rec = match address {
            Some(url) => builder.connect_grpc_opts(url.to_string())?,
            None => builder.connect_grpc()?,
        };
        Ok(Self::new(rec, options))
    }

    /// The underlying stream, for logging your own data beside sinew's.
    pub fn stream(&self) -> &RecordingStream {
        &self.rec
    }

    /// Names a deformable's entities (`world/deformables/<name>/...`, `stats/<name>/...`).
    /// Call before its first frame.
    pub fn set_name(&mut self, handle: DeformableHandle, name: &str) {
        self.names.insert(handle, name.to_string());
    }

    /// Frames logged so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Mean wall time spent in [`RerunRecorder::log_frame`] per logged frame, s.
    pub fn seconds_per_frame(&self) -> f64 {
        self.log_seconds / self.frames.max(1) as f64
    }

    /// Logs a [`DeformableWorld`] at its current step and time.
    pub fn log_world(&mut self, world: &DeformableWorld) -> Result<bool, RecorderError> {
        self.log_frame(
            world.steps(),
            world.time(),
            &world.physics.bodies,
            &world.physics.colliders,
            &world.deformables,
        )
    }

    /// Logs one frame (every `options.every_n_steps`-th call; returns whether it logged).
    pub fn log_frame(
        &mut self,
        step: u64,
        time: Real,
        bodies: &RigidBodySet,
        colliders: &ColliderSet,
        deformables: &DeformableSet,
    ) -> Result<bool, RecorderError> {
        let call = self.calls;
        self.calls += 1;
        if !call.is_multiple_of(self.options.every_n_steps.max(1)) {
            return Ok(false);
        }
        let start = Instant::now();
        let rec = self.rec.clone();
        if !self.view_logged {
            render::view_coordinates(&rec)?;
            self.view_logged = true;
        }
        rec.set_time_sequence("step", step as i64);
        rec.set_duration_secs("sim_time", time as f64);

        for (handle, co) in colliders.iter() {
            let (index, generation) = handle.into_raw_parts();
            let path = format!("world/colliders/{index}_{generation}");
            let color = match co.parent().and_then(|p| bodies.get(p)) {
                Some(b) if b.is_dynamic() => rgb(DYNAMIC),
                Some(b) if b.is_kinematic() => rgb(KINEMATIC),
                _ => rgb(FIXED),
            };
            if let std::collections::hash_map::Entry::Vacant(slot) =
                self.shapes_logged.entry(handle)
            {
                slot.insert(render::shape(&rec, &path, co.shape(), color)?);
            }
            render::pose(&rec, &path, co.position())?;
        }

        for (handle, body) in deformables.iter() {
            if !self.deformables.contains_key(&handle) {
                let name = self
                    .names
                    .get(&handle)
                    .cloned()
                    .unwrap_or_else(|| format!("d{}", handle.into_raw_parts().0));
                self.deformables
                    .insert(handle, DeformableLog::new(name, body));
            }
            let log = self.deformables.get_mut(&handle).expect("inserted above");
            log.log(&rec, body, bodies, &self.options)?;
        }
        let seconds = start.elapsed().as_secs_f64();
        self.log_seconds += seconds;
        self.frames += 1;
        for (handle, _) in deformables.iter() {
            if let Some(log) = self.deformables.get(&handle) {
                rec.log(
                    format!("stats/{}/log_ms", log.name),
                    &Scalars::single(seconds * 1e3),
                )?;
            }
        }
        Ok(true)
    }

    /// Flushes everything to the sink.
    pub fn flush(&self) {
        // A failed flush leaves the data in the buffer; the next flush or drop retries.
        let _ = self.rec.flush_blocking();
    }
}

impl DeformableLog {
    fn new(name: String, body: &Deformable) -> Self {
        let mesh = body.mesh();
        let n = mesh.nodes().len();
        let surface = mesh.boundary_nodes().to_vec();
        let mut slot = vec![u32::MAX; n];
        for (k, &i) in surface.iter().enumerate() {
            slot[i as usize] = k as u32;
        }
        let facets = mesh
            .boundary_facets()
            .iter()
            .map(|f| std::array::from_fn(|a| slot[f[a] as usize]))
            .collect();
        let mut count = vec![0u32; n + 1];
        for c in mesh.cells() {
            for &i in c {
                count[i as usize + 1] += 1;
            }
        }
        for i in 0..n {
            count[i + 1] += count[i];
        }
        let mut cells = vec![0u32; count[n] as usize];
        let mut fill = count.clone();
        for (ci, c) in mesh.cells().enumerate() {
            for &i in c {
                cells[fill[i as usize] as usize] = ci as u32;
                fill[i as usize] += 1;
            }
        }
        let all_pairs = mesh.vertex_pairs();
        let mut pcount = vec![0u32; n + 1];
        for ([a, b], _) in &all_pairs {
            pcount[*a as usize + 1] += 1;
            pcount[*b as usize + 1] += 1;
        }
        for i in 0..n {
            pcount[i + 1] += pcount[i];
        }
        let mut pairs = vec![(0u32, 0.0); pcount[n] as usize];
        let mut pfill = pcount.clone();
        for ([a, b], _) in &all_pairs {
            let l0 = mesh.nodes()[*a as usize].distance(mesh.nodes()[*b as usize]);
            pairs[pfill[*a as usize] as usize] = (*b, l0);
            pfill[*a as usize] += 1;
            pairs[pfill[*b as usize] as usize] = (*a, l0);
            pfill[*b as usize] += 1;
        }
        DeformableLog {
            name,
            surface,
            facets,
            cell_start: count,
            cells,
            pair_start: pcount,
            pairs,
            topology_logged: false,
            was_frozen: false,
        }
    }

    fn color(&self, node: usize, body: &Deformable, quality: &[Real], field: ColorField) -> Color {
        let cells = &self.cells[self.cell_start[node] as usize..self.cell_start[node + 1] as usize];
        let worst = cells
            .iter()
            .map(|&c| quality[c as usize])
            .fold(Real::INFINITY, Real::min);
        if worst <= 0.0 {
            return rgb(INVERTED);
        }
        const REST: [f32; 3] = [235.0, 235.0, 235.0];
        match field {
            ColorField::Uniform => Color::from_rgb(200, 200, 210),
            ColorField::VolumeRatio => {
                if worst < 1.0 {
                    lerp(REST, [220.0, 40.0, 40.0], (1.0 - worst) / 0.7)
                } else {
                    lerp(REST, [40.0, 90.0, 220.0], (worst - 1.0) / 0.5)
                }
            }
            ColorField::Strain => {
                let pairs =
                    &self.pairs[self.pair_start[node] as usize..self.pair_start[node + 1] as usize];
                let x = body.positions();
                let strain: Real = pairs
                    .iter()
                    .map(|(other, l0)| (x[node].distance(x[*other as usize]) / l0 - 1.0).abs())
                    .sum::<Real>()
                    / pairs.len().max(1) as Real;
                lerp(REST, [220.0, 40.0, 40.0], strain / 0.25)
            }
        }
    }

    fn log(
        &mut self,
        rec: &RecordingStream,
        body: &Deformable,
        bodies: &RigidBodySet,
        options: &RecorderOptions,
    ) -> Result<(), RecorderError> {
        let base = format!("world/deformables/{}", self.name);
        let surface_path = format!("{base}/surface");
        if !self.topology_logged {
            render::surface_topology(rec, &surface_path, &self.facets)?;
            self.topology_logged = true;
        }
        let mesh = body.mesh();
        let x = body.positions();
        let quality: Vec<Real> = (0..mesh.num_cells())
            .map(|c| mesh.cell_quality(c, x))
            .collect();
        let vertices: Vec<Vector> = self.surface.iter().map(|&i| x[i as usize]).collect();
        let colors: Vec<Color> = self
            .surface
            .iter()
            .map(|&i| self.color(i as usize, body, &quality, options.color_field))
            .collect();
        render::surface(rec, &surface_path, &vertices, &self.facets, &colors)?;
        if options.nodes {
            let colors: Vec<Color> = (0..x.len())
                .map(|i| self.color(i, body, &quality, options.color_field))
                .collect();
            render::points(rec, &format!("{base}/nodes"), x, &colors, 0.005)?;
        }
        if options.edges {
            let segments: Vec<[Vector; 2]> = (0..x.len())
                .flat_map(|a| {
                    self.pairs[self.pair_start[a] as usize..self.pair_start[a + 1] as usize]
                        .iter()
                        .filter(move |(b, _)| (*b as usize) > a)
                        .map(move |(b, _)| [x[a], x[*b as usize]])
                })
                .collect();
            render::segments(
                rec,
                &format!("{base}/edges"),
                &segments,
                Color::from_rgb(120, 120, 130),
                0.002,
            )?;
        }
        if options.attachments {
            let segments: Vec<[Vector; 2]> = body
                .attachments()
                .iter()
                .filter_map(|a| {
                    Some([
                        x[a.node as usize],
                        bodies.get(a.body)?.position().transform_point(a.anchor),
                    ])
                })
                .collect();
            render::segments(
                rec,
                &format!("{base}/attachments"),
                &segments,
                rgb(ATTACHMENT),
                0.003,
            )?;
        }
        if options.contacts {
            let points: Vec<Vector> = body.contacts().iter().map(|c| c.point).collect();
            let normals: Vec<Vector> = body.contacts().iter().map(|c| c.normal * 0.05).collect();
            render::points(
                rec,
                &format!("{base}/contacts/points"),
                &points,
                &vec![rgb(CONTACT); points.len()],
                0.008,
            )?;
            render::arrows(
                rec,
                &format!("{base}/contacts/normals"),
                &points,
                &normals,
                rgb(CONTACT),
            )?;
        }
        let r = body.report();
        let stats = format!("stats/{}", self.name);
        let scalar =
            |metric: &str, v: f64| rec.log(format!("{stats}/{metric}"), &Scalars::single(v));
        scalar("kinetic_energy", r.kinetic_energy as f64)?;
        scalar("elastic_energy", r.elastic_energy as f64)?;
        scalar("inverted_elements", r.inverted_elements as f64)?;
        scalar("min_volume_ratio", r.min_volume_ratio as f64)?;
        scalar("max_penetration", r.max_penetration as f64)?;
        scalar("contacts", r.contacts as f64)?;
        scalar("substeps", r.substeps as f64)?;
        scalar("ms_forces", r.time_forces * 1e3)?;
        scalar("ms_contacts", r.time_contacts * 1e3)?;
        scalar("ms_integrate", r.time_integrate * 1e3)?;
        scalar("frozen", if body.is_frozen() { 1.0 } else { 0.0 })?;
        if body.is_frozen() != self.was_frozen {
            let text = if !body.is_frozen() {
                format!("{} resumed", self.name)
            } else if r.non_finite {
                format!(
                    "{} frozen: its state turned non-finite; rolled back to the start of the step",
                    self.name
                )
            } else if r.exploded {
                format!("{} frozen: a cell stretched past max_stretch (a blow-up); rolled back to the start of the step", self.name)
            } else {
                format!("{} frozen", self.name)
            };
            let level = if body.is_frozen() {
                TextLogLevel::WARN
            } else {
                TextLogLevel::INFO
            };
            rec.log(
                format!("events/{}", self.name),
                &TextLog::new(text).with_level(level),
            )?;
            self.was_frozen = body.is_frozen();
        }
        Ok(())
    }
}
