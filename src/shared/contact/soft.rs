//! Contact between deformables: the surface nodes of each body against the surface facets of
//! the others.
//!
//! **Groups.** Bodies whose boxes, swept over the step, overlap (and whose collision groups let
//! them meet) step together, as one island (`pipeline/islands.rs`): every substep of the group has the size the most demanding of
//! them needs, every body advances its velocities (forces, bones, rigid contacts), then the
//! nodes of each meet the facets of the others on those velocities, then all positions move.
//! Both sides of a contact are live, so one impulse acts on both at once: equal and opposite
//! between the node and the facet's nodes (barycentric shares), so momentum is conserved, and
//! never more than stops the approach, so no energy is created. (Stepping the bodies one after
//! another, each meeting the others as obstacles whose reactions waited for their next step,
//! created energy: a node stopped against a facet that could not give way this step, of a
//! lighter body, gained `½ m₁u² (m₁/m₂ − 1)`.) A sleeping member is still: its facets and its
//! nodes give no way (its nodes meet the live members' facets too: tested from the live side
//! only, a live body's facets crept into a sleeping one's nodes), and a push faster than the
//! sleep speed wakes it. A frozen (blown-up) body meets no other.
//!
//! **A contact**, each substep, for a node (moving from `p0` to `p1 = p0 + h v`) and a facet of
//! another body (from `q0` to `q1 = q0 + h v`): the node ends the substep within a skin of the
//! facet's plane or behind it, inside the facet's prism, having started in front of it or less
//! than half the facet body's shortest rest surface edge behind (deeper, a node is not this
//! facet's business); a node that crosses the plane within the substep is tested at the
//! crossing, so a fast one cannot pass beside the prism it ends in. Every facet a node meets is
//! solved, in turn, the one it is most in front of (the face it comes through) first: a node
//! in a crease meets both sides. Behind facets of another body, a node meets only the nearest
//! (its way out), and none when it is on or in front of another facet of that body; nor does
//! it meet a facet that faces the way its own surface faces (flush side faces of stacked
//! cubes). A node found behind starts the substep on the plane. Its
//! target is the normal relative velocity that closes the gap down to a skin, leaves the skin
//! a tenth of the way per substep once within it, or is `−e · approach` for a bounce; friction
//! is Coulomb's. The pair's `μ` and `e` combine both bodies' coefficients by rapier's rules.
//!
//! **Self contact** ([`DeformableBuilder::self_contact`](super::super::DeformableBuilder::self_contact)):
//! a body's nodes meet its own facets in the same way, all but the facets a node lies on
//! ([`NearFacets`]), with its own coefficients. The facets next to a node's own are met: the
//! crushed inner side of a fold buckles into wrinkles a cell wide whose nodes pass into their
//! neighbours' facets (a sausage folded double went 4 mm into itself when they were left
//! out); the depth limit keeps a node at a sharp corner of the rest shape from being pushed
//! through the face beside it.
//!
//! **Broad phase.** Each body's facet boxes swept over the step go into a BVH (parry's),
//! refitted each step; each surface node of the others (and of itself, with self contact) queries
//! it with its own swept box. (Boxes widened by the speed in every direction, so that a body
//! turned by a collision within the step is still seen, changed nothing measurable in a pile
//! and made a resting stack sway faster; not kept.)
//!
//! Not covered yet: edges of two coarse 3D meshes crossing with no node through a facet. A
//! soft cube resting on another keeps a slow sway (1–6 cm/s after 4 s in
//! `tests/shared/soft.rs`, total energy constant): the stuck contact and the bodies' damping,
//! which leaves a cell's rigid motion alone, take nothing from the upper body rocking as a
//! whole, so the pair does not fall asleep.

use super::super::body::{Deformable, SurfaceTree};
use super::super::coupling::Substep;
use super::super::math::{self, Real, Vector, FACET_ARITY, SIMPLEX_ARITY};
use super::super::mesh::{CellKind, Mesh};
use super::super::rapier::dynamics::CoefficientCombineRule;
use super::super::rapier::geometry::{Aabb, BoundingVolume};

/// A body's surface as the other members of its group meet it during a step.
#[derive(Clone, Debug, Default)]
pub(crate) struct SoftSurface {
    /// The facets' boxes swept over the step (leaf = boundary facet index), refitted step
    /// after step.
    tree: SurfaceTree,
    /// Deeper than this behind a facet, a node is not pushed out through it: half the body's
    /// shortest surface edge at rest.
    depth_limit: Real,
    /// Per node (zero inside), the outward surface normal at the start of the step: the
    /// area-weighted mean of its boundary facets' normals.
    normals: Vec<Vector>,
}

impl SoftSurface {
    /// How far a node's box is widened when it looks for this surface's facets: a quarter of
    /// the body's shortest surface edge (forces can turn a node within the step).
    pub fn margin(&self) -> Real {
        0.5 * self.depth_limit
    }

    /// The outward surface normal at `node` at the start of the step (zero inside).
    pub fn facing(&self, node: usize) -> Vector {
        self.normals.get(node).copied().unwrap_or(Vector::ZERO)
    }

    /// The surface of `body` swept over the step under `gravity` (staying put if `still`).
    pub fn build(&mut self, body: &Deformable, gravity: Vector, dt: Real, still: bool) {
        let x = &body.state.positions;
        let v = &body.state.velocities;
        let g = gravity * body.gravity_scale;
        let mut shortest = Real::INFINITY;
        let boxes: Vec<Aabb> = body
            .rest
            .mesh
            .boundary_facets()
            .iter()
            .map(|f| {
                let mut b = Aabb::new_invalid();
                for a in 0..FACET_ARITY {
                    let i = f[a] as usize;
                    b.take_point(x[i]);
                    if !still {
                        b.take_point(x[i] + v[i] * dt + g * (0.5 * dt * dt));
                    }
                    // At rest: a crushed fold's short edges must not shrink the limit.
                    let rest = body.rest.mesh.nodes();
                    shortest =
                        shortest.min(rest[i].distance(rest[f[(a + 1) % FACET_ARITY] as usize]));
                }
                b
            })
            .collect();
        self.tree.set(&boxes);
        self.normals.clear();
        self.normals.resize(x.len(), Vector::ZERO);
        for f in body.rest.mesh.boundary_facets() {
            let q: [Vector; FACET_ARITY] = std::array::from_fn(|a| x[f[a] as usize]);
            let n = math::facet_normal(&q);
            for &i in f {
                self.normals[i as usize] += n;
            }
        }
        for n in &mut self.normals {
            *n = n.normalize_or_zero();
        }
        self.depth_limit = if shortest.is_finite() {
            0.5 * shortest
        } else {
            0.0
        };
    }
}

/// Per surface node (in the order of [`Mesh::boundary_nodes`]): the surface facets it does not
/// meet in self contact, ascending: its own (it lies on them). A facet next to its own is met:
/// the crushed inner side of a fold buckles into wrinkles a cell wide, whose nodes pass into
/// the neighbouring facets; a node behind a facet by more than half an edge is never met, so a
/// node at a sharp corner of the rest shape is not pushed through the face beside it.
///
/// Also, per boundary facet, the cells around it (those with a node of it), ascending.
#[derive(Clone, Debug, Default)]
pub(crate) struct NearFacets {
    start: Vec<u32>,
    facets: Vec<u32>,
    cells_start: Vec<u32>,
    cells: Vec<u32>,
    /// Per surface node, the cells it is a vertex of.
    node_cells_start: Vec<u32>,
    node_cells: Vec<u32>,
}

impl NearFacets {
    pub fn new(mesh: &Mesh) -> Self {
        let n = mesh.nodes().len();
        let mut facets_of: Vec<Vec<u32>> = vec![Vec::new(); n];
        for (f, facet) in mesh.boundary_facets().iter().enumerate() {
            for &i in facet {
                facets_of[i as usize].push(f as u32);
            }
        }
        let mut cells_of: Vec<Vec<u32>> = vec![Vec::new(); n];
        for (c, cell) in mesh.cells().enumerate() {
            for &i in cell {
                cells_of[i as usize].push(c as u32);
            }
        }
        let mut out = NearFacets {
            start: vec![0],
            facets: Vec::new(),
            cells_start: vec![0],
            cells: Vec::new(),
            node_cells_start: vec![0],
            node_cells: Vec::new(),
        };
        for &i in mesh.boundary_nodes() {
            out.facets.extend_from_slice(&facets_of[i as usize]);
            out.start.push(out.facets.len() as u32);
            out.node_cells.extend_from_slice(&cells_of[i as usize]);
            out.node_cells_start.push(out.node_cells.len() as u32);
        }
        let mut around = Vec::new();
        for facet in mesh.boundary_facets() {
            around.clear();
            for &i in facet {
                around.extend_from_slice(&cells_of[i as usize]);
            }
            around.sort_unstable();
            around.dedup();
            out.cells.extend_from_slice(&around);
            out.cells_start.push(out.cells.len() as u32);
        }
        out
    }

    /// The cells around boundary facet `f` (those with a node of it).
    pub fn cells_around(&self, f: usize) -> &[u32] {
        &self.cells[self.cells_start[f] as usize..self.cells_start[f + 1] as usize]
    }

    /// The cells surface node `k` (an index into the boundary nodes) is a vertex of.
    pub fn cells_of_node(&self, k: usize) -> &[u32] {
        let (a, b) = (self.node_cells_start[k], self.node_cells_start[k + 1]);
        &self.node_cells[a as usize..b as usize]
    }

    /// The facets surface node `k` (an index into the boundary nodes) leaves alone.
    pub fn of(&self, k: usize) -> &[u32] {
        &self.facets[self.start[k] as usize..self.start[k + 1] as usize]
    }
}

/// Per surface node of `body` (CSR): the facets of the other members' surfaces its box swept
/// over the step meets, as `(member, facet)`, ascending; with `own` (the body's member index
/// and surface, for self contact), its own facets too, but for those it leaves alone.
pub(crate) fn node_tables<'s>(
    body: &Deformable,
    others: impl Iterator<Item = (usize, &'s SoftSurface)>,
    own: Option<(usize, &SoftSurface)>,
    dt: Real,
    widen: Real,
    start: &mut Vec<u32>,
    cands: &mut Vec<(u32, u32)>,
) {
    start.clear();
    cands.clear();
    start.push(0);
    let near = own.map(|_| body.rest.near_facets());
    let node_box = |i: u32| {
        let (x, v) = (
            body.state.positions[i as usize],
            body.state.velocities[i as usize],
        );
        let mut b = Aabb::new_invalid();
        b.take_point(x);
        b.take_point(x + v * dt);
        b.loosened(widen)
    };
    // The other surfaces any of its nodes' boxes may reach: in a pile each body is near a few
    // of the island's, and a tree query costs more than its root box's test.
    let mut region = Aabb::new_invalid();
    for &i in body.rest.mesh.boundary_nodes() {
        if !body.is_attached(i) {
            region.merge(&node_box(i));
        }
    }
    let near_others: Vec<(usize, &SoftSurface)> = others
        .filter(|(_, surface)| {
            !surface.tree.bvh().is_empty() && surface.tree.bvh().root_aabb().intersects(&region)
        })
        .collect();
    for (k, &i) in body.rest.mesh.boundary_nodes().iter().enumerate() {
        if !body.is_attached(i) {
            let b = node_box(i);
            let begin = cands.len();
            for &(m, surface) in &near_others {
                if surface.tree.bvh().root_aabb().intersects(&b) {
                    cands.extend(surface.tree.bvh().intersect_aabb(&b).map(|f| (m as u32, f)));
                }
            }
            if let (Some((m, surface)), Some(near)) = (own, near) {
                let skip = near.of(k);
                cands.extend(
                    surface
                        .tree
                        .bvh()
                        .intersect_aabb(&b)
                        .filter(|f| skip.binary_search(f).is_err())
                        .map(|f| (m as u32, f)),
                );
            }
            cands[begin..].sort_unstable();
        }
        start.push(cands.len() as u32);
    }
}

/// A node's contact with another member's facet, found at the start of a substep.
pub(crate) struct SoftHit {
    /// The member whose facet it is.
    pub other: usize,
    pub(super) facet: [u32; FACET_ARITY],
    pub(super) weights: [Real; FACET_ARITY],
    /// Outward normal of the facet at the end of the substep.
    pub(super) normal: Vector,
    /// Signed distance of the node from the facet's plane at the start (negative: behind).
    d0: Real,
    /// The facet's plane at the start: a point and the normal.
    plane: (Vector, Vector),
    /// The facet body's depth limit.
    pub(super) depth_limit: Real,
}

impl SoftHit {
    /// The contact's effective inverse mass along its normal, `1/m_i + Σ w_j²/m_j`, from the
    /// node's and the facet nodes' inverse masses.
    fn inverse_mass(&self, node: Real, facet: &[Real; FACET_ARITY]) -> Real {
        node + (0..FACET_ARITY)
            .map(|a| self.weights[a] * self.weights[a] * facet[a])
            .sum::<Real>()
    }
}

/// The facets of the candidates `cands` that `node` of `body_of(i)` meets in this substep (see
/// the module docs), into `out`: the one it is most in front of first (the face it comes
/// through), then the others it would end behind; `body_of(j)` gives member `j`'s body and
/// surface; `exits` is a buffer for the node's ways out of the bodies it is near.
pub(crate) fn find<'b>(
    body_of: impl Fn(usize) -> (&'b Deformable, &'b SoftSurface),
    i: usize,
    node: u32,
    cands: &[(u32, u32)],
    at: &Substep<'_>,
    (out, exits): (&mut Vec<SoftHit>, &mut Vec<(u32, Real)>),
) {
    out.clear();
    let h = at.h;
    let (body, own) = body_of(i);
    let n_i = node as usize;
    let facing = own.facing(n_i);
    let p0 = body.state.positions[n_i];
    let p1 = p0 + body.state.velocities[n_i] * h;
    let skin = at.skin;
    nearest_exits(&body_of, (i, facing), p0, cands, exits);
    for &(m, f) in cands {
        let (other, surface) = body_of(m as usize);
        let facet = other.rest.mesh.boundary_facets()[f as usize];
        let (x, v) = (&other.state.positions, &other.state.velocities);
        let q0: [Vector; FACET_ARITY] = std::array::from_fn(|a| x[facet[a] as usize]);
        let q1: [Vector; FACET_ARITY] = std::array::from_fn(|a| q0[a] + v[facet[a] as usize] * h);
        let n1 = math::facet_normal(&q1).normalize_or_zero();
        if n1 == Vector::ZERO || faces_away(i, facing, m, n1) {
            continue;
        }
        let d1 = (p1 - q1[0]).dot(n1);
        if d1 >= skin {
            continue;
        }
        let n0 = math::facet_normal(&q0).normalize_or(n1);
        let d0 = (p0 - q0[0]).dot(n0);
        if d0 < -surface.depth_limit {
            continue;
        }
        // Behind the plane, a node is inside the body only if it is inside a cell around the
        // facet (near a corner, a point outside the body is behind the plane of a facet beside
        // it, and stepping it out onto that plane threw it sideways: a pile of ten coarse
        // cubes gained 20 J in one step).
        if d0 < 0.0 && !inside_near_facet(other, f as usize, p0) {
            continue;
        }
        // Behind, it leaves through the nearest facet only.
        let exit = exits.iter().find(|e| e.0 == m).map_or(d0, |e| e.1);
        if d0 < 0.0 && d0 < exit {
            continue;
        }
        // Where the node meets the facet: at the plane crossing when it crosses it within the
        // substep (so a fast node cannot pass beside the prism it ends in), else at its end.
        let tau = if d0 > 0.0 && d1 < 0.0 {
            d0 / (d0 - d1)
        } else {
            1.0
        };
        let q: [Vector; FACET_ARITY] = std::array::from_fn(|a| q0[a] + (q1[a] - q0[a]) * tau);
        let w = math::facet_barycentric(&q, p0 + (p1 - p0) * tau);
        if w.iter().any(|&w| w < -1e-3) {
            continue;
        }
        let w = w.map(|w| w.max(0.0));
        let total: Real = w.iter().sum();
        out.push(SoftHit {
            other: m as usize,
            facet,
            weights: w.map(|w| w / total),
            normal: n1,
            d0,
            plane: (q0[0], n0),
            depth_limit: surface.depth_limit,
        });
    }
    out.sort_unstable_by(|a, b| b.d0.total_cmp(&a.d0));
}

/// Into `out`, per member among `cands` but `i` (the node's own), the largest signed distance
/// of `p` from the plane of one of its facets whose prism holds `p` (facets facing away left
/// out): the nearest way out of that body when negative; when zero or positive, `p` is outside
/// it, on or in front of a facet (`docs/ARCHITECTURE.md` §6.6).
pub(crate) fn nearest_exits<'b>(
    body_of: &impl Fn(usize) -> (&'b Deformable, &'b SoftSurface),
    (i, facing): (usize, Vector),
    p: Vector,
    cands: &[(u32, u32)],
    out: &mut Vec<(u32, Real)>,
) {
    out.clear();
    // Self contact is left out: a node lies on its own surface, in front of its own facets.
    for &(m, f) in cands.iter().filter(|c| c.0 as usize != i) {
        let (other, _) = body_of(m as usize);
        let facet = other.rest.mesh.boundary_facets()[f as usize];
        let q: [Vector; FACET_ARITY] =
            std::array::from_fn(|a| other.state.positions[facet[a] as usize]);
        let n = math::facet_normal(&q).normalize_or_zero();
        if n == Vector::ZERO
            || faces_away(i, facing, m, n)
            || math::facet_barycentric(&q, p).iter().any(|&w| w < -1e-3)
        {
            continue;
        }
        let d = (p - q[0]).dot(n);
        match out.iter_mut().find(|e| e.0 == m) {
            Some(e) => e.1 = e.1.max(d),
            None => out.push((m, d)),
        }
    }
}

/// Whether a facet of member `m` with unit normal `n` faces the same way as the surface of
/// member `i` at a node whose outward normal is `facing`: two surfaces in contact face each
/// other, so such a facet is not the node's to meet (`docs/ARCHITECTURE.md` §6.6). Within one
/// body a crumpled surface's node normals say little: self contact does not use this test.
fn faces_away(i: usize, facing: Vector, m: u32, n: Vector) -> bool {
    m as usize != i && facing.dot(n) > 0.0
}

/// Whether `p` is inside (or on) a cell of `body` around its boundary facet `f` (one that
/// has a node of it), at the current positions; with box cells, always.
fn inside_near_facet(body: &Deformable, f: usize, p: Vector) -> bool {
    let mesh = &body.rest.mesh;
    if mesh.kind() != CellKind::Simplex {
        return true;
    }
    let x = &body.state.positions;
    body.rest.near_facets().cells_around(f).iter().any(|&c| {
        let cell = mesh.cell(c as usize);
        let q: [Vector; SIMPLEX_ARITY] = std::array::from_fn(|a| x[cell[a] as usize]);
        let whole = math::simplex_volume(&q);
        whole > 0.0
            && (0..SIMPLEX_ARITY).all(|k| {
                let mut r = q;
                r[k] = p;
                math::simplex_volume(&r) >= -1e-6 * whole
            })
    })
}

/// Which sides of a contact are still (asleep): they give no way.
#[derive(Copy, Clone, Debug)]
pub(crate) struct Still {
    pub node: bool,
    pub facet: bool,
}

/// A contact [`find`] found between a node and a facet (of another body, or of the node's own
/// with self contact), solved on velocities: its normal impulse non-negative and never more
/// than reaches the target, friction in Coulomb's disc of `μ` times it and no more than stops
/// the slip. The impulses accumulate over calls of [`SoftRow::solve`] (projected Gauss–Seidel);
/// a substep solves each row once (more passes fed a tower's sway: `docs/ARCHITECTURE.md`
/// §6.6).
#[derive(Clone, Debug)]
pub(crate) struct SoftRow {
    /// The members of the node and of the facet (the same with self contact).
    pub node_member: usize,
    pub facet_member: usize,
    node: u32,
    /// Inverse masses of the node and of the facet's nodes (zero: still, or held by a bone).
    w_node: Real,
    facet: [u32; FACET_ARITY],
    weights: [Real; FACET_ARITY],
    w_facet: [Real; FACET_ARITY],
    normal: Vector,
    /// Effective inverse mass along any direction, `1/m_i + Σ w_j²/m_j`.
    k: Real,
    /// Normal relative velocity to reach.
    target: Real,
    friction: Real,
    normal_impulse: Real,
    friction_impulse: Vector,
}

/// The contact coefficients of a pair: friction and restitution of `a` and `b` combined by
/// rapier's rules.
pub(super) fn combined(a: &Deformable, b: &Deformable) -> (Real, Real) {
    let (a, b) = (&a.contact, &b.contact);
    let friction = CoefficientCombineRule::combine(
        a.friction,
        b.friction,
        a.friction_combine_rule,
        b.friction_combine_rule,
    );
    let restitution = CoefficientCombineRule::combine(
        a.restitution,
        b.restitution,
        a.restitution_combine_rule,
        b.restitution_combine_rule,
    );
    (friction, restitution)
}

fn inv_mass_of(b: &Deformable, j: u32) -> Real {
    if b.is_attached(j) {
        0.0
    } else {
        b.rest.inv_masses[j as usize]
    }
}

/// The row of a contact [`find`] found between `node` of member `i` (`body`) and a facet of
/// member `hit.other` (`other`; `None` with self contact), a still side giving no way (not
/// both); steps a node found behind the facet out onto its plane. `None` when neither side can
/// move.
pub(crate) fn row(
    (i, body): (usize, &mut Deformable),
    node: u32,
    other: Option<&Deformable>,
    still: Still,
    hit: &SoftHit,
    at: &Substep<'_>,
) -> Option<SoftRow> {
    let n_i = node as usize;
    let w_node = if still.node {
        0.0
    } else {
        inv_mass_of(body, node)
    };
    let facet_body = other.unwrap_or(body);
    let w_facet: [Real; FACET_ARITY] = std::array::from_fn(|a| {
        if still.facet {
            0.0
        } else {
            inv_mass_of(facet_body, hit.facet[a])
        }
    });
    let k = hit.inverse_mass(w_node, &w_facet);
    if k <= 0.0 {
        return None;
    }
    // Self contact: the body's own coefficients (a rule combining them with themselves would
    // square a multiplied friction).
    let (friction, restitution) = match other {
        Some(other) => combined(body, other),
        None => (body.contact.friction, body.contact.restitution),
    };
    let facet_velocity = |vel: &[Vector]| -> Vector {
        (0..FACET_ARITY)
            .map(|a| vel[hit.facet[a] as usize] * hit.weights[a])
            .sum()
    };
    let before = &facet_body.step.scratch_velocities;
    let approach = (body.step.scratch_velocities[n_i] - facet_velocity(before)).dot(hit.normal);
    // A node found behind the facet starts the substep on it (a still one stays: the facet
    // is pushed off it over the next substeps).
    let d0 = if still.node {
        hit_depth(body.state.positions[n_i], hit)
    } else {
        step_out(&mut body.state.positions[n_i], hit)
    };
    // Close the gap down to the skin; within the skin, stop approaching and leave it slowly (a
    // tenth of the way per substep: pushing out at once pumped a stacked pair into rocking).
    let gap = d0 - at.skin;
    let closing = if gap >= 0.0 {
        -gap / at.h
    } else {
        -0.1 * gap / at.h
    };
    let target = super::normal_target(closing, approach, restitution, at.restitution_threshold);
    Some(SoftRow {
        node_member: i,
        facet_member: hit.other,
        node,
        w_node,
        facet: hit.facet,
        weights: hit.weights,
        w_facet,
        normal: hit.normal,
        k,
        target,
        friction,
        normal_impulse: 0.0,
        friction_impulse: Vector::ZERO,
    })
}

impl SoftRow {
    /// One projected Gauss–Seidel update of the row on the node's velocities `node_v` and the
    /// facet's `facet_v` (`None`: the same body's); returns the impulse it added on the node
    /// (the facet took its reverse).
    pub fn solve(&mut self, node_v: &mut [Vector], facet_v: Option<&mut [Vector]>) -> Vector {
        let n = self.normal;
        let i = self.node as usize;
        let facet_velocity = |vel: &[Vector]| -> Vector {
            (0..FACET_ARITY)
                .map(|a| vel[self.facet[a] as usize] * self.weights[a])
                .sum()
        };
        let relative = |node_v: &[Vector], facet_v: Option<&[Vector]>| {
            node_v[i] - facet_velocity(facet_v.unwrap_or(node_v))
        };
        let rel = relative(node_v, facet_v.as_deref());
        let total = (self.normal_impulse + (self.target - rel.dot(n)) / self.k).max(0.0);
        let mut impulse = n * (total - self.normal_impulse);
        self.normal_impulse = total;
        if self.friction > 0.0 {
            let after = rel + impulse * self.k;
            let slip = after - n * after.dot(n);
            let friction = super::coulomb(
                self.friction_impulse - slip / self.k,
                self.friction * self.normal_impulse,
            );
            impulse += friction - self.friction_impulse;
            self.friction_impulse = friction;
        }
        if impulse == Vector::ZERO {
            return impulse;
        }
        node_v[i] += impulse * self.w_node;
        let facet_side = match facet_v {
            Some(v) => v,
            None => node_v,
        };
        for ((&j, &w), &inv) in self.facet.iter().zip(&self.weights).zip(&self.w_facet) {
            facet_side[j as usize] -= impulse * (w * inv);
        }
        impulse
    }

    /// How the row held after its solves ([`Grip`](super::Grip)).
    pub fn grip(&self) -> Option<super::Grip> {
        super::Grip::of(self.normal, self.normal_impulse)
    }

    /// Whether the impulse of a first [`SoftRow::solve`] would move a still side faster than
    /// `speed` (then that body wakes for the next step): `(node side, facet side)`.
    pub fn wakes(
        &self,
        impulse: Vector,
        node: &Deformable,
        facet: &Deformable,
        speed: Real,
    ) -> (bool, bool) {
        let fast = |b: &Deformable, j: u32| impulse.length() * inv_mass_of(b, j) > speed;
        (fast(node, self.node), fast(facet, self.facet[0]))
    }
}

/// The distance of a node at `x` from the plane of `hit`'s facet at the substep's start
/// (negative: behind).
fn hit_depth(x: Vector, hit: &SoftHit) -> Real {
    let (point, normal) = hit.plane;
    (x - point).dot(normal)
}

/// Moves a node found behind a facet out onto the facet's plane (at most the facet body's
/// depth limit); returns its distance from the plane after, from where it is now: a contact
/// solved before this one (the node's other facets, the facet's other nodes) may have moved it
/// out already, and an old depth would throw it sideways.
pub(super) fn step_out(x: &mut Vector, hit: &SoftHit) -> Real {
    let d = hit_depth(*x, hit);
    if d >= 0.0 {
        return d;
    }
    let shift = (-d).min(hit.depth_limit);
    *x += hit.normal * shift;
    d + shift
}
