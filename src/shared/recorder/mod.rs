//! Logging to the [Rerun](https://rerun.io) viewer (feature `rerun`).
//!
//! [`RerunRecorder`] logs one frame of a world — its deformables, its rapier colliders and the
//! step report — on two timelines, `step` (step index) and `sim_time` (simulated seconds).
//! What never changes is logged once, as static data: the view's axes, the surface topology
//! (on the timeline, each time it changes, for a body that tears),
//! each collider's shape (in its own frame; its pose is logged when it changes).
//!
//! Entity paths (stable; script against them):
//!
//! | path | what | when |
//! |---|---|---|
//! | `world` | view coordinates (3D: right-handed, y up) | static |
//! | `world/deformables/<name>/surface` | 3D: `Mesh3D` of the boundary (vertex `j` is node `mesh.boundary_nodes()[j]`), coloured by the chosen field; 2D: `LineStrips2D`, one two-point strip per boundary segment (`mesh.boundary_facets()` order) | every logged frame |
//! | `world/deformables/<name>/render` | the body's render mesh ([`Deformable::set_render_mesh`]), 3D: `Mesh3D` with its normals, grey; 2D: `LineStrips2D`, one strip per segment | every logged frame while it has one |
//! | `world/deformables/<name>/nodes` | all nodes as points, coloured by the field | if `nodes` |
//! | `world/deformables/<name>/edges` | every cell's vertex pairs as segments | if `edges` |
//! | `world/deformables/<name>/attachments` | segment node → its anchor on the bone | if `attachments` |
//! | `world/deformables/<name>/contacts/points`, `.../contacts/normals` | last step's contact points and normals | if `contacts` |
//! | `world/colliders/<index>_<generation>` | the collider's shape (static) and pose; grey fixed, orange kinematic (bones), blue dynamic | the pose when it changes |
//! | `world/deformables/<name>/torn` | the faces a tear opened, both sides, as red outlines (the surface's facets that meet another one at rest) | every logged frame once the body has torn |
//! | `world/deformables/<name>/wireframe` | 3D: the surface's edges as thin dark lines | if `wireframe` |
//! | `world/deformables/<name>/focus` | 3D: two invisible points, the corners of the surface's box grown 1.2 times about its centre: what the eye follows (the viewer keeps a followed entity at 1.5 times its bounding radius, which for the surface itself is too close to see where it touches) | if `blueprint` |
//! | `stats/<name>/<metric>` | `Scalars` (each [`METRICS`] entry; sent 32 frames at a time, and by `flush`): `kinetic_energy`, `elastic_energy`, `gravity_energy`, `total_energy` (their sum), `inverted_elements`, `min_volume_ratio`, `max_penetration`, `contacts`, `substeps`, `ms_forces`, `ms_contacts`, `ms_integrate`, `frozen` (0/1), `log_ms` | every logged frame |
//! | `stats/<name>/gas_pressure/<k>`, `stats/<name>/gas_volume/<k>` | `Scalars`: gas chamber `k`'s gauge pressure (Pa) and its volume (m³; area in 2D), as [`Deformable::chambers`] gives them; sent with the metrics | every logged frame, for a body with gas |
//! | `events/<name>` | `TextLog`: a warning when the body is frozen (why: non-finite state or a blow-up), info when it resumes | when it changes |
//! | `legend` | `TextDocument` (markdown): what the colours and lines mean, with the colour range | static |
//!
//! `<name>` is what [`RerunRecorder::set_name`] gave the deformable, else `d<index>`.
//!
//! Colours: [`ColorField::VolumeRatio`] shades each surface vertex by the smallest volume ratio
//! `r` of its cells: white at rest, red as it is compressed (full red at
//! `r ≤ 1 − color_range`), blue as it is stretched (full blue at `r ≥ 1 + color_range`);
//! [`ColorField::Strain`] by the mean `|L/L0 − 1|` of its incident vertex pairs (white 0 → full
//! red at `color_range`; a stress proxy is this times Young's modulus, so it is drawn the same);
//! [`ColorField::PlasticStrain`] by the largest plastic strain of its cells (white 0 → full
//! orange at `color_range`; white everywhere on a body that does not flow).
//! A vertex of a collapsed or inverted cell is magenta in either case. The range is
//! [`RecorderOptions::color_range`], 0.1 by default: the main demo's impact (smallest volume
//! ratio about 0.95) shows half red. The `legend` entity says all this in the recording.
//!
//! Layout: with [`RecorderOptions::blueprint`] (the default) the first frame sends a blueprint
//! (see the `blueprint` module): the world view framed on the deformables (the eye follows a
//! lone 3D body), the legend under it, and every `stats/` series in one of three plot groups
//! (energy, quality, cost). It is sent again when deformables are added or removed.

use std::collections::HashMap;
use std::time::Instant;

mod blueprint;

use super::body::Deformable;
use super::math::{Pose, Real, Vector, FACET_ARITY};
use super::rapier::dynamics::RigidBodySet;
use super::rapier::geometry::{ColliderHandle, ColliderSet};
use super::render;
use super::set::{DeformableHandle, DeformableSet};
use super::world::DeformableWorld;
use rerun::log::TimeColumn;
use rerun::{
    Color, RecordingStreamError, Scalars, SeriesLines, TextDocument, TextLog, TextLogLevel,
};
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
    /// Largest plastic strain of the vertex's cells ([`Deformable::plastic_strains`]): the
    /// set a plastic body keeps.
    PlasticStrain,
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
    /// How far the coloured field goes from rest before the colour is full (volume ratio
    /// `1 ± color_range`, strain `color_range`); 0.1 by default.
    pub color_range: Real,
    /// Log the surface's edges (3D) as thin dark lines over the coloured mesh. Off by default:
    /// on the res-9 cube it doubles the logging cost (0.07 → 0.15 ms a frame, release); the
    /// examples, which log every 10th step, turn it on.
    pub wireframe: bool,
    /// Send sinew's layout (a Rerun blueprint) with the recording.
    pub blueprint: bool,
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
            color_range: 0.1,
            wireframe: false,
            blueprint: true,
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

/// Every `stats/<name>/<metric>` series, in the order they are logged.
pub const METRICS: &[&str] = &[
    "kinetic_energy",
    "elastic_energy",
    "gravity_energy",
    "total_energy",
    "inverted_elements",
    "min_volume_ratio",
    "max_penetration",
    "contacts",
    "substeps",
    "ms_forces",
    "ms_contacts",
    "ms_integrate",
    "frozen",
    "log_ms",
];

/// Frames of `stats/` values kept before they are sent, one chunk per series: 14 calls into
/// Rerun's batcher every 32 frames instead of 14 a frame (each call hands a row to the
/// batcher's thread). Sent sooner by [`RerunRecorder::flush`] and when the recorder is
/// dropped.
const STATS_BATCH: usize = 32;

struct DeformableLog {
    name: String,
    /// Logged frames whose `stats/` values are not sent yet: (step, sim time, one value per
    /// [`METRICS`] entry).
    pending: Vec<(i64, f64, [f64; METRICS.len()])>,
    /// `stats/<name>/<metric>` for each of [`METRICS`].
    stats: Vec<String>,
    /// `stats/<name>/gas_pressure/<k>` and `stats/<name>/gas_volume/<k>` for each gas chamber.
    gas: Vec<[String; 2]>,
    /// Each frame of `pending`: each chamber's gauge pressure and volume.
    gas_pending: Vec<Vec<[f64; 2]>>,
    surface: Vec<u32>,
    /// The surface's edges chained into polylines (surface vertex slots), for the wireframe:
    /// one strip per edge cost 0.23 ms a frame on the 3D limb, 4 times the surface itself.
    wire_strips: Vec<Vec<u32>>,
    /// Cells with a node on the surface: the ones the surface colours read.
    surface_cells: Vec<u32>,
    /// Quality of each cell at the last frame (of the surface cells only, unless every node is
    /// coloured).
    quality: Vec<Real>,
    /// Each cell's plastic strain at the last frame (empty unless the plastic field is drawn
    /// and the body flows).
    plastic: Vec<Real>,
    facets: Vec<[u32; FACET_ARITY]>,
    /// The torn faces, both sides (node indices; [`torn_facets`]).
    torn: Vec<[u32; FACET_ARITY]>,
    /// Per node (CSR): incident cells.
    cell_start: Vec<u32>,
    cells: Vec<u32>,
    /// Per node (CSR): incident vertex pairs (other node, rest length).
    pair_start: Vec<u32>,
    pairs: Vec<(u32, Real)>,
    topology_logged: bool,
    /// The facets of the render mesh last logged (its topology is logged when they change).
    render_facets: Option<Vec<[u32; FACET_ARITY]>>,
    /// Whether the body was frozen at the last logged frame.
    was_frozen: bool,
    /// Whether the body had bindings at the last logged frame.
    bound: bool,
}

/// Logs worlds to Rerun. See the module documentation for the entity paths.
pub struct RerunRecorder {
    rec: RecordingStream,
    /// What to log.
    pub options: RecorderOptions,
    deformables: HashMap<DeformableHandle, DeformableLog>,
    names: HashMap<DeformableHandle, String>,
    shapes_logged: HashMap<ColliderHandle, bool>,
    /// Each collider's pose as last logged.
    poses: HashMap<ColliderHandle, Pose>,
    view_logged: bool,
    /// Deformables came or went since the last blueprint: send it again.
    layout_stale: bool,
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
const WIRE: [u8; 3] = [60, 60, 70];
const TORN: [u8; 3] = [200, 20, 20];
const REST: [f32; 3] = [235.0, 235.0, 235.0];
const COMPRESSED: [f32; 3] = [215.0, 30.0, 30.0];
const PLASTIC: [f32; 3] = [230.0, 120.0, 20.0];
const STRETCHED: [f32; 3] = [40.0, 90.0, 220.0];

/// The faces a tear opened, both sides: the boundary facets of `mesh` that meet another one
/// at rest (a split copies the crack's nodes to their rest places; a mesh built with no such
/// seam has none).
fn torn_facets(mesh: &super::mesh::Mesh) -> Vec<[u32; FACET_ARITY]> {
    let rest = mesh.nodes();
    let key = |f: &[u32; FACET_ARITY]| {
        let mut k: [[u32; 3]; FACET_ARITY] = std::array::from_fn(|a| {
            let p = rest[f[a] as usize].to_array();
            std::array::from_fn(|d| if d < p.len() { p[d].to_bits() } else { 0 })
        });
        k.sort_unstable();
        k
    };
    let facets = mesh.boundary_facets();
    let mut at: HashMap<[[u32; 3]; FACET_ARITY], usize> = HashMap::new();
    let mut torn = Vec::new();
    for (i, f) in facets.iter().enumerate() {
        if let Some(other) = at.insert(key(f), i) {
            torn.push(facets[other]);
            torn.push(*f);
        }
    }
    torn
}

/// The edges of facet `f` (one for a 2D facet, which is an edge).
fn facet_edges(f: &[u32; FACET_ARITY]) -> impl Iterator<Item = [u32; 2]> + '_ {
    let n = if FACET_ARITY > 2 { FACET_ARITY } else { 1 };
    (0..n).map(move |a| [f[a], f[(a + 1) % FACET_ARITY]])
}

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
            poses: HashMap::new(),
            view_logged: false,
            layout_stale: true,
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
            rec.log_static("legend", &TextDocument::from_markdown(self.legend()))?;
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
            // A pose is logged when it changes (a fixed ground's, once).
            let pose = *co.position();
            if self.poses.get(&handle) != Some(&pose) {
                render::pose(&rec, &path, &pose)?;
                self.poses.insert(handle, pose);
            }
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
                self.layout_stale = true;
            }
            let log = self.deformables.get_mut(&handle).expect("inserted above");
            log.log(
                &rec,
                body,
                bodies,
                &self.options,
                (step as i64, time as f64),
            )?;
        }
        for (handle, log) in self.deformables.iter_mut() {
            if deformables.get(*handle).is_none() {
                log.send_stats(&rec)?;
            }
        }
        let before = self.deformables.len();
        self.deformables
            .retain(|handle, _| deformables.get(*handle).is_some());
        self.layout_stale |= self.deformables.len() != before;
        if self.options.blueprint {
            self.send_blueprint_if_new(colliders, deformables)?;
        }
        let seconds = start.elapsed().as_secs_f64();
        self.log_seconds += seconds;
        self.frames += 1;
        for log in self.deformables.values_mut() {
            if let Some(row) = log.pending.last_mut() {
                row.2[METRICS.len() - 1] = seconds * 1e3;
            }
            if log.pending.len() >= STATS_BATCH {
                log.send_stats(&rec)?;
            }
        }
        Ok(true)
    }

    /// Sends the layout if deformables came or went since the last one sent (and there are
    /// some): their series names, then the blueprint framed on them.
    fn send_blueprint_if_new(
        &mut self,
        colliders: &ColliderSet,
        deformables: &DeformableSet,
    ) -> Result<(), RecorderError> {
        if !self.layout_stale || self.deformables.is_empty() {
            return Ok(());
        }
        let mut names: Vec<String> = self.deformables.values().map(|d| d.name.clone()).collect();
        names.sort_unstable();
        let several = names.len() > 1;
        for log in self.deformables.values() {
            for (metric, path) in METRICS.iter().zip(&log.stats) {
                let label = if several {
                    format!("{} {metric}", log.name)
                } else {
                    metric.to_string()
                };
                self.rec
                    .log_static(path.as_str(), &SeriesLines::new().with_names([label]))?;
            }
            for (k, paths) in log.gas.iter().enumerate() {
                for (quantity, path) in ["pressure", "volume"].iter().zip(paths) {
                    let label = if several {
                        format!("{} chamber {k} {quantity}", log.name)
                    } else {
                        format!("chamber {k} {quantity}")
                    };
                    self.rec
                        .log_static(path.as_str(), &SeriesLines::new().with_names([label]))?;
                }
            }
        }
        let gas: Vec<String> = self
            .deformables
            .values()
            .filter(|d| !d.gas.is_empty())
            .map(|d| d.name.clone())
            .collect();
        let mut lo = Vector::splat(Real::INFINITY);
        let mut hi = Vector::splat(Real::NEG_INFINITY);
        for (_, body) in deformables.iter() {
            for &x in body.positions() {
                lo = lo.min(x);
                hi = hi.max(x);
            }
        }
        let boxes = colliders.iter().map(|(_, co)| {
            let aabb = co.compute_aabb();
            (aabb.mins, aabb.maxs)
        });
        // A lone 3D body is followed by the eye: framed alone. Otherwise the view stays put,
        // framed on the bodies and the colliders right under them (where they will land).
        let framing = if names.len() == 1 && render::VIEW_CLASS == "3D" {
            blueprint::Framing {
                lo,
                hi,
                track: Some(format!("world/deformables/{}/focus", names[0])),
            }
        } else {
            let (lo, hi) = blueprint::framing_box((lo, hi), boxes, 1);
            blueprint::Framing {
                lo,
                hi,
                track: None,
            }
        };
        blueprint::send(&self.rec, render::VIEW_CLASS, (&names, &gas), framing)?;
        self.layout_stale = false;
        Ok(())
    }

    /// The `legend` text: what the colours and lines mean, with the range in use.
    fn legend(&self) -> String {
        let r = self.options.color_range;
        let field = match self.options.color_field {
            ColorField::Uniform => "one colour".to_string(),
            ColorField::VolumeRatio => format!(
                "smallest volume ratio of the node's cells: **white** 1 (rest), **red** \
                 compressed (full at {:.2}), **blue** stretched (full at {:.2})",
                1.0 - r,
                1.0 + r
            ),
            ColorField::Strain => {
                format!("mean edge strain at the node: **white** 0, **red** full at {r:.2}")
            }
            ColorField::PlasticStrain => format!(
                "largest plastic strain of the node's cells (the set kept): **white** 0, \
                 **orange** full at {r:.2}"
            ),
        };
        let wire = if self.options.wireframe {
            "Dark lines: surface edges; yellow"
        } else {
            "Yellow lines"
        };
        format!(
            "**Colour**: {field}, **magenta** a collapsed or inverted cell. {wire}: bindings to \
             bones. Red outlines: torn faces. Colliders: grey fixed, orange kinematic, blue \
             dynamic."
        )
    }

    /// Sends the `stats/` values kept so far and flushes everything to the sink.
    pub fn flush(&mut self) -> Result<(), RecorderError> {
        let start = Instant::now();
        for log in self.deformables.values_mut() {
            log.send_stats(&self.rec)?;
        }
        self.log_seconds += start.elapsed().as_secs_f64();
        // A failed flush leaves the data in the buffer; the next flush or drop retries.
        let _ = self.rec.flush_blocking();
        Ok(())
    }
}

impl Drop for RerunRecorder {
    /// Sends the `stats/` values kept so far (errors cannot be returned from here).
    fn drop(&mut self) {
        for log in self.deformables.values_mut() {
            let _ = log.send_stats(&self.rec);
        }
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
        let facets: Vec<[u32; FACET_ARITY]> = mesh
            .boundary_facets()
            .iter()
            .map(|f| std::array::from_fn(|a| slot[f[a] as usize]))
            .collect();
        let wire_strips = if FACET_ARITY > 2 {
            chain_edges(&facets, surface.len())
        } else {
            Vec::new() // a 2D facet is itself an edge, drawn by the surface
        };
        let stats = METRICS
            .iter()
            .map(|m| format!("stats/{name}/{m}"))
            .collect();
        let gas = (0..body.chambers().len())
            .map(|k| {
                [
                    format!("stats/{name}/gas_pressure/{k}"),
                    format!("stats/{name}/gas_volume/{k}"),
                ]
            })
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
        let mut surface_cells: Vec<u32> = surface
            .iter()
            .flat_map(|&i| &cells[count[i as usize] as usize..count[i as usize + 1] as usize])
            .copied()
            .collect();
        surface_cells.sort_unstable();
        surface_cells.dedup();
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
            stats,
            gas,
            gas_pending: Vec::new(),
            surface,
            wire_strips,
            surface_cells,
            quality: vec![1.0; mesh.num_cells()],
            plastic: Vec::new(),
            facets,
            torn: torn_facets(mesh),
            cell_start: count,
            cells,
            pair_start: pcount,
            pairs,
            pending: Vec::with_capacity(STATS_BATCH),
            topology_logged: false,
            render_facets: None,
            was_frozen: false,
            bound: false,
        }
    }

    /// Keeps this frame's `stats/` values (the metrics and, with gas, each chamber's pressure
    /// and volume) until they are sent.
    fn keep_stats(&mut self, body: &Deformable, (step, time): (i64, f64)) {
        let r = body.report();
        // `log_ms` (the last metric) is set by the recorder once the frame is done.
        let values: [f64; METRICS.len()] = [
            r.kinetic_energy as f64,
            r.elastic_energy as f64,
            r.gravity_energy as f64,
            (r.kinetic_energy + r.elastic_energy + r.gravity_energy) as f64,
            r.inverted_elements as f64,
            r.min_volume_ratio as f64,
            r.max_penetration as f64,
            r.contacts as f64,
            r.substeps as f64,
            r.time_forces * 1e3,
            r.time_contacts * 1e3,
            r.time_integrate * 1e3,
            if body.is_frozen() { 1.0 } else { 0.0 },
            0.0,
        ];
        self.pending.push((step, time, values));
        if !self.gas.is_empty() {
            let chambers = body.chambers();
            let row = chambers
                .iter()
                .map(|c| [c.pressure as f64, c.volume as f64]);
            self.gas_pending.push(row.collect());
        }
    }

    /// Sends the kept `stats/` values, one chunk per series on the `step` and `sim_time`
    /// timelines.
    fn send_stats(&mut self, rec: &RecordingStream) -> Result<(), RecorderError> {
        if self.pending.is_empty() {
            return Ok(());
        }
        let steps: Vec<i64> = self.pending.iter().map(|p| p.0).collect();
        let times: Vec<f64> = self.pending.iter().map(|p| p.1).collect();
        let send = |path: &str, values: Vec<f64>| -> Result<(), RecorderError> {
            let columns = Scalars::new(values)
                .columns_of_unit_batches()
                .map_err(RecordingStreamError::from)?;
            rec.send_columns(
                path,
                [
                    TimeColumn::new_sequence("step", steps.iter().copied()),
                    TimeColumn::new_duration_secs("sim_time", times.iter().copied()),
                ],
                columns,
            )?;
            Ok(())
        };
        for (m, path) in self.stats.iter().enumerate() {
            send(path, self.pending.iter().map(|p| p.2[m]).collect())?;
        }
        if self.gas_pending.len() == self.pending.len() {
            for (k, paths) in self.gas.iter().enumerate() {
                for (q, path) in paths.iter().enumerate() {
                    let at = |row: &Vec<[f64; 2]>| row.get(k).map_or(f64::NAN, |c| c[q]);
                    send(path, self.gas_pending.iter().map(at).collect())?;
                }
            }
        }
        self.pending.clear();
        self.gas_pending.clear();
        Ok(())
    }

    /// The colour of a node from the cells' quality at this frame (`self.quality`).
    fn color(&self, node: usize, body: &Deformable, options: &RecorderOptions) -> Color {
        let range = options.color_range.max(1e-6);
        let cells = &self.cells[self.cell_start[node] as usize..self.cell_start[node + 1] as usize];
        let worst = cells
            .iter()
            .map(|&c| self.quality[c as usize])
            .fold(Real::INFINITY, Real::min);
        if worst <= 0.0 {
            return rgb(INVERTED);
        }
        match options.color_field {
            ColorField::Uniform => Color::from_rgb(200, 200, 210),
            ColorField::VolumeRatio => {
                if worst < 1.0 {
                    lerp(REST, COMPRESSED, (1.0 - worst) / range)
                } else {
                    lerp(REST, STRETCHED, (worst - 1.0) / range)
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
                lerp(REST, COMPRESSED, strain / range)
            }
            ColorField::PlasticStrain => {
                let set = cells
                    .iter()
                    .filter_map(|&c| self.plastic.get(c as usize))
                    .fold(0.0, |a: Real, b| a.max(*b));
                lerp(REST, PLASTIC, set / range)
            }
        }
    }

    /// The cells' quality at this frame: every cell's with `all`, else the surface cells'.
    fn refresh_quality(&mut self, body: &Deformable, all: bool) {
        let (mesh, x) = (body.mesh(), body.positions());
        if all {
            for (c, q) in self.quality.iter_mut().enumerate() {
                *q = mesh.cell_quality(c, x);
            }
        } else {
            for &c in &self.surface_cells {
                self.quality[c as usize] = mesh.cell_quality(c as usize, x);
            }
        }
    }

    /// The body's render mesh, its topology when it changes; cleared when it goes.
    fn log_render_mesh(
        &mut self,
        rec: &RecordingStream,
        body: &Deformable,
        base: &str,
    ) -> Result<(), RecorderError> {
        let path = format!("{base}/render");
        if let Some(mesh) = body.render_mesh() {
            if self.render_facets.as_deref() != Some(mesh.facets()) {
                render::render_mesh_topology(rec, &path, mesh.facets())?;
                self.render_facets = Some(mesh.facets().to_vec());
            }
            render::render_mesh(rec, &path, mesh.vertices(), mesh.normals(), mesh.facets())?;
        } else if self.render_facets.take().is_some() {
            rec.log(path, &rerun::Clear::recursive())?;
        }
        Ok(())
    }

    /// The torn faces' outlines at `x`, once the body has torn.
    fn log_torn(
        &self,
        rec: &RecordingStream,
        base: &str,
        x: &[Vector],
    ) -> Result<(), RecorderError> {
        if !self.torn.is_empty() {
            let segments: Vec<[Vector; 2]> = self
                .torn
                .iter()
                .flat_map(|f| facet_edges(f).map(|[a, b]| [x[a as usize], x[b as usize]]))
                .collect();
            render::segments(rec, &format!("{base}/torn"), &segments, rgb(TORN), 0.004)?;
        }
        Ok(())
    }

    /// Makes the surface and node tables again if a tear split the body's mesh since.
    fn follow_tears(&mut self, body: &Deformable) {
        if self.cell_start.len() != body.positions().len() + 1 {
            let fresh = DeformableLog::new(self.name.clone(), body);
            let pending = std::mem::take(&mut self.pending);
            *self = DeformableLog { pending, ..fresh };
        }
    }

    fn log(
        &mut self,
        rec: &RecordingStream,
        body: &Deformable,
        bodies: &RigidBodySet,
        options: &RecorderOptions,
        (step, time): (i64, f64),
    ) -> Result<(), RecorderError> {
        self.follow_tears(body);
        let base = format!("world/deformables/{}", self.name);
        let surface_path = format!("{base}/surface");
        if !self.topology_logged {
            // A body that may tear logs its topology on the timeline, each time it changes.
            let changes = body.tearing().is_some();
            render::surface_topology(rec, &surface_path, &self.facets, changes)?;
            self.topology_logged = true;
        }
        self.refresh_quality(body, options.nodes);
        if options.color_field == ColorField::PlasticStrain {
            self.plastic = body.plastic_strains();
        }
        let x = body.positions();
        let vertices: Vec<Vector> = self.surface.iter().map(|&i| x[i as usize]).collect();
        let colors: Vec<Color> = self
            .surface
            .iter()
            .map(|&i| self.color(i as usize, body, options))
            .collect();
        render::surface(rec, &surface_path, &vertices, &self.facets, &colors)?;
        self.log_render_mesh(rec, body, &base)?;
        if options.blueprint {
            render::focus(rec, &format!("{base}/focus"), &vertices)?;
        }
        if options.wireframe && !self.wire_strips.is_empty() {
            render::wireframe(
                rec,
                &format!("{base}/wireframe"),
                &vertices,
                &self.wire_strips,
                rgb(WIRE),
            )?;
        }
        self.log_torn(rec, &base, x)?;
        if options.nodes {
            let colors: Vec<Color> = (0..x.len()).map(|i| self.color(i, body, options)).collect();
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
        // Logged while there are bindings, and once more (empty) when the last one goes.
        let bound = !body.attachments().is_empty();
        if options.attachments && (bound || self.bound) {
            self.bound = bound;
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
        self.keep_stats(body, (step, time));
        let r = body.report();
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

/// The edges of `facets` (over `n` vertices) chained into polylines: each edge in exactly one
/// strip, a strip going on while its end vertex has an edge not yet taken.
fn chain_edges(facets: &[[u32; FACET_ARITY]], n: usize) -> Vec<Vec<u32>> {
    let mut edges: Vec<[u32; 2]> = facets
        .iter()
        .flat_map(|f| {
            (0..FACET_ARITY).map(move |a| {
                let (i, j) = (f[a], f[(a + 1) % FACET_ARITY]);
                [i.min(j), i.max(j)]
            })
        })
        .collect();
    edges.sort_unstable();
    edges.dedup();
    // Per vertex (CSR): its edges.
    let mut start = vec![0usize; n + 1];
    for e in &edges {
        start[e[0] as usize + 1] += 1;
        start[e[1] as usize + 1] += 1;
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    let mut incident = vec![0usize; start[n]];
    let mut fill = start.clone();
    for (k, e) in edges.iter().enumerate() {
        for &v in e {
            incident[fill[v as usize]] = k;
            fill[v as usize] += 1;
        }
    }
    let mut taken = vec![false; edges.len()];
    let mut next = start.clone(); // per vertex: the first incident edge not looked at yet
    let mut strips = Vec::new();
    for first in 0..edges.len() {
        if taken[first] {
            continue;
        }
        taken[first] = true;
        let mut strip = vec![edges[first][0], edges[first][1]];
        let mut end = edges[first][1] as usize;
        loop {
            let mut found = None;
            while next[end] < start[end + 1] {
                let k = incident[next[end]];
                next[end] += 1;
                if !taken[k] {
                    found = Some(k);
                    break;
                }
            }
            let Some(k) = found else { break };
            taken[k] = true;
            let e = edges[k];
            let other = if e[0] as usize == end { e[1] } else { e[0] };
            strip.push(other);
            end = other as usize;
        }
        strips.push(strip);
    }
    strips
}

#[cfg(test)]
mod tests {
    use super::super::math::SIMPLEX_ARITY;
    use super::*;

    #[test]
    fn chained_edges_cover_each_edge_once() {
        // 3D: two triangles sharing an edge; 2D: a polyline of three segments.
        let (facets, n, want): (Vec<[u32; FACET_ARITY]>, usize, Vec<[u32; 2]>) = if FACET_ARITY == 3
        {
            let f = |a: [u32; 3]| std::array::from_fn(|k| a[k]);
            let want = vec![[0, 1], [0, 2], [1, 2], [1, 3], [2, 3]];
            (vec![f([0, 1, 2]), f([1, 3, 2])], 4, want)
        } else {
            let f = |a: [u32; 2]| std::array::from_fn(|k| a[k]);
            let want = vec![[0, 1], [1, 2], [2, 3]];
            (vec![f([0, 1]), f([1, 2]), f([2, 3])], 4, want)
        };
        let strips = chain_edges(&facets, n);
        let mut seen: Vec<[u32; 2]> = strips
            .iter()
            .flat_map(|s| s.windows(2).map(|w| [w[0].min(w[1]), w[0].max(w[1])]))
            .collect();
        seen.sort_unstable();
        assert_eq!(seen, want);
        assert!(strips.len() < want.len(), "no chaining: {strips:?}");
    }

    #[test]
    fn the_torn_surface_is_the_boundary_facets_that_meet_at_rest() {
        // Two simplices sharing a facet: none torn; the shared facet's nodes copied for the
        // second cell (what a split does): that facet, once per side.
        let dim = super::super::math::DIM;
        let mut nodes: Vec<Vector> = (0..dim)
            .map(|d| {
                let mut e = Vector::ZERO;
                e[d] = 1.0;
                e
            })
            .collect();
        nodes.push(Vector::ZERO);
        nodes.push(Vector::ONE);
        let n = nodes.len() as u32;
        let simplex = super::super::mesh::CellKind::Simplex;
        // A cell of `ids` at `at`, its first two swapped if it would be inside out.
        let cell = |mut ids: Vec<u32>, at: &[Vector]| {
            let p: [Vector; SIMPLEX_ARITY] = std::array::from_fn(|a| at[ids[a] as usize]);
            if super::super::math::simplex_gradients(&p).0 < 0.0 {
                ids.swap(0, 1);
            }
            ids
        };
        let shared: Vec<u32> = (0..n - 2).collect();
        let first = cell([vec![n - 2], shared.clone()].concat(), &nodes);
        let whole = [
            first.clone(),
            cell([shared.clone(), vec![n - 1]].concat(), &nodes),
        ]
        .concat();
        let mesh = super::super::mesh::Mesh::new(nodes.clone(), whole, simplex).unwrap();
        assert!(torn_facets(&mesh).is_empty());
        let copies: Vec<u32> = (0..shared.len() as u32).map(|k| n + k).collect();
        let mut split_nodes = nodes.clone();
        split_nodes.extend(shared.iter().map(|&i| nodes[i as usize]));
        let second = cell([copies.clone(), vec![n - 1]].concat(), &split_nodes);
        let mesh =
            super::super::mesh::Mesh::new(split_nodes, [first, second].concat(), simplex).unwrap();
        let mut torn: Vec<Vec<u32>> = torn_facets(&mesh)
            .iter()
            .map(|f| {
                let mut f = f.to_vec();
                f.sort_unstable();
                f
            })
            .collect();
        torn.sort();
        assert_eq!(torn, vec![shared, copies]);
    }
}
