//! Tearing ([`Tearing`]): after each step, the faces between cells stretched across past the
//! tear strain open, and the body is rebuilt on its torn mesh (`docs/ARCHITECTURE.md` §3.8).
//!
//! **Which faces tear.** Each cell's deformation gradient `F` is the least-squares affine map
//! from its rest vertices (its plastic rest shape, if it flows) to its vertices now (exact on
//! a simplex). A face between cells `a` and `b` with rest unit normal `n` is stretched across
//! by `λ = ½ (|F_a n| + |F_b n|)`; it tears when `ln λ` passes the tear strain.
//!
//! **How the mesh splits.** The cells around a node (its star) stay joined through the faces
//! around it that did not tear. A node whose star the torn faces cut apart keeps its index
//! for the part holding its first cell, and gets a copy (same rest position, position and
//! velocity, appended after the existing nodes) for each other part, whose cells then use the
//! copy; a star already in parts (cells meeting at the node or an edge only) stays as built.
//! A torn face whose nodes all keep their stars whole (a crack front inside the body) opens
//! nothing, and is tried again at the next step; a crack wholly inside a 3D body that cuts
//! interior nodes apart opens a closed slit. Nodes keep their
//! indices, so contacts, bindings and a user's node lists stay valid; copies of a bound node
//! are bound with it. The lumped masses follow the cells, so each copy carries its part's
//! mass: momentum and kinetic energy are unchanged, and since every model's energy is a sum
//! over cells of terms of their own vertices, so is the elastic energy. A tear never creates
//! energy; the pieces' stored stretch is then released by their motion. The rebuilt body keeps
//! its measured stability slack (`model/slack.rs`) and its step's carried state.
//!
//! **Smallest piece.** A tear that would leave a piece (cells joined through shared nodes)
//! smaller than [`Tearing::smallest_piece`] cells is not made: its faces stay whole.
//!
//! **Pieces stay in one body.** The body keeps its handle, its bindings and its events; its
//! pieces fall, collide with colliders and rest on them independently. They collide with each
//! other only under self contact, as any two parts of one body do.

use std::collections::HashMap;

use super::super::attach::{Attachment, Bindings};
use super::super::math::{self, Matrix, Real, Rotation, Vector};
use super::super::mesh::{local_faces, Mesh};
use super::super::model::{Accumulator, ModelState};
use super::{Deformable, Rest, State, StepBuffers, Surface};

/// A face between two cells, at rest.
#[derive(Clone, Debug)]
pub(crate) struct Face {
    /// The two cells (the first is the lower index).
    pub cells: [u32; 2],
    /// Its nodes (the first `len`).
    nodes: [u32; 4],
    len: u8,
    /// Its unit normal at rest (either side).
    normal: Vector,
}

impl Face {
    fn nodes(&self) -> &[u32] {
        &self.nodes[..self.len as usize]
    }
}

/// The interior faces of a mesh, found once per rest mesh ([`Rest::faces`]).
#[derive(Clone, Debug, Default)]
pub(crate) struct Faces(pub Vec<Face>);

impl Faces {
    pub fn of(mesh: &Mesh) -> Faces {
        let local = local_faces(mesh.kind());
        let mut first: HashMap<[u32; 4], u32> = HashMap::new();
        let mut faces = Vec::new();
        for (cell, ids) in mesh.cells().enumerate() {
            for f in &local {
                let mut key = [u32::MAX; 4];
                for (k, &l) in f.iter().enumerate() {
                    key[k] = ids[l];
                }
                key[..f.len()].sort_unstable();
                match first.get(&key) {
                    Some(&other) => {
                        let p: Vec<Vector> =
                            f.iter().map(|&l| mesh.nodes()[ids[l] as usize]).collect();
                        faces.push(Face {
                            cells: [other, cell as u32],
                            nodes: key,
                            len: f.len() as u8,
                            normal: math::facet_normal(&p).normalize_or_zero(),
                        });
                    }
                    None => {
                        first.insert(key, cell as u32);
                    }
                }
            }
        }
        Faces(faces)
    }
}

/// The least-squares affine map of `rest` onto `now` (a cell's vertices).
fn deformation(rest: &[Vector], now: &[Vector]) -> Matrix {
    let k = rest.len() as Real;
    let (c0, c1) = (
        rest.iter().copied().sum::<Vector>() / k,
        now.iter().copied().sum::<Vector>() / k,
    );
    let (mut a, mut b) = (Matrix::ZERO, Matrix::ZERO);
    for (r, x) in rest.iter().zip(now) {
        let d = *r - c0;
        a += math::outer(*x - c1, d);
        b += math::outer(d, d);
    }
    a * b.inverse()
}

/// The plane of the crack a body tore along last, while its release crosses the body.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Copy, Clone, Debug, PartialEq)]
pub(crate) struct Crack {
    /// A point of the plane, at rest.
    origin: Vector,
    /// Its unit normal.
    across: Vector,
    /// How far from the plane a face's centre may be and belong to the crack.
    band: Real,
    /// How long the release still takes, s.
    quiet: Real,
}

impl Crack {
    fn holds(&self, p: Vector) -> bool {
        self.across.dot(p - self.origin).abs() <= self.band
    }
}

/// The largest extent of `points` along an axis.
fn extent(points: &[Vector]) -> Real {
    let (lo, hi) = points.iter().fold(
        (
            Vector::splat(Real::INFINITY),
            Vector::splat(Real::NEG_INFINITY),
        ),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    (hi - lo).max_element()
}

/// The longest distance between two of `points`.
fn longest_edge(points: impl Iterator<Item = Vector> + Clone) -> Real {
    points
        .clone()
        .flat_map(|a| points.clone().map(move |b| a.distance(b)))
        .fold(0.0, Real::max)
}

/// Smallest union–find: each element's parent, roots their own.
struct Union(Vec<u32>);

impl Union {
    fn new(n: usize) -> Self {
        Union((0..n as u32).collect())
    }

    fn root(&mut self, mut i: u32) -> u32 {
        while self.0[i as usize] != i {
            let up = self.0[self.0[i as usize] as usize];
            self.0[i as usize] = up;
            i = up;
        }
        i
    }

    fn join(&mut self, a: u32, b: u32) {
        let (a, b) = (self.root(a), self.root(b));
        // The lower root wins: the result does not depend on the order of the joins.
        if a < b {
            self.0[b as usize] = a;
        } else {
            self.0[a as usize] = b;
        }
    }
}

/// The mesh split along the faces `torn` marks: each cell's vertex ids after the split, and
/// for each new node (past the mesh's), the node it copies.
fn split(mesh: &Mesh, faces: &Faces, torn: &[bool]) -> (Vec<u32>, Vec<u32>) {
    let arity = mesh.kind().arity();
    let ids = mesh.cell_indices();
    let slot_of = |cell: u32, node: u32| -> u32 {
        let c = cell as usize * arity;
        let a = ids[c..c + arity]
            .iter()
            .position(|&i| i == node)
            .expect("a face's node is a vertex of its cells");
        (c + a) as u32
    };
    // Cell slots joined around their node through every face (`whole`: a star already in
    // parts, cells meeting at a node or an edge only, stays as it is) and through the faces
    // that hold (`held`).
    let mut whole = Union::new(ids.len());
    let mut held = Union::new(ids.len());
    for (face, &t) in faces.0.iter().zip(torn) {
        for &i in face.nodes() {
            let (a, b) = (slot_of(face.cells[0], i), slot_of(face.cells[1], i));
            whole.join(a, b);
            if !t {
                held.join(a, b);
            }
        }
    }
    // Of each part of a node's star that the torn faces cut apart, the part holding the
    // part's first slot keeps the node; each other gets a copy.
    let n = mesh.nodes().len();
    let mut keeper: HashMap<u32, u32> = HashMap::new();
    let mut copies: HashMap<u32, u32> = HashMap::new();
    let mut parents = Vec::new();
    let mut cells = ids.to_vec();
    for slot in 0..ids.len() {
        let node = ids[slot];
        let root = held.root(slot as u32);
        let first = *keeper.entry(whole.root(slot as u32)).or_insert(root);
        if root != first {
            let copy = *copies.entry(root).or_insert_with(|| {
                parents.push(node);
                (n + parents.len() - 1) as u32
            });
            cells[slot] = copy;
        }
    }
    (cells, parents)
}

/// Each cell's piece (cells joined through shared nodes), as a root cell index, and the
/// number of cells per root.
fn pieces(cells: &[u32], arity: usize, nodes: usize) -> (Vec<u32>, HashMap<u32, usize>) {
    let mut union = Union::new(nodes);
    for c in cells.chunks_exact(arity) {
        for &i in &c[1..] {
            union.join(c[0], i);
        }
    }
    let roots: Vec<u32> = cells
        .chunks_exact(arity)
        .map(|c| union.root(c[0]))
        .collect();
    let mut sizes = HashMap::new();
    for &r in &roots {
        *sizes.entry(r).or_insert(0) += 1;
    }
    (roots, sizes)
}

impl Rest {
    /// The interior faces, found on first use.
    pub fn faces(&self) -> &Faces {
        self.faces.get_or_init(|| Faces::of(&self.mesh))
    }
}

impl Deformable {
    /// Tears the faces stretched past the tear strain ([`Tearing`](super::super::Tearing)),
    /// rebuilding the body on its split mesh; the torn faces' cells are kept in
    /// `last.tears` (empty if nothing tore).
    pub(crate) fn tear(&mut self, dt: Real) {
        self.last.tears.clear();
        if let Some(c) = &mut self.last.crack {
            c.quiet -= dt;
            if c.quiet <= 0.0 {
                self.last.crack = None;
            }
        }
        let Some(tearing) = self.tearing else {
            return;
        };
        let mesh = &self.rest.mesh;
        let arity = mesh.kind().arity();
        let plastic = self.state.elements.plastic_rest();
        let x = &self.state.positions;
        let faces = self.rest.faces();
        // Each cell's deformation, once per check (a cell has at most 8 vertices).
        let gradients: Vec<Matrix> = (0..mesh.num_cells())
            .map(|c| {
                let ids = mesh.cell(c);
                let (mut now, mut built) = ([Vector::ZERO; 8], [Vector::ZERO; 8]);
                for (a, &i) in ids.iter().enumerate() {
                    now[a] = x[i as usize];
                    built[a] = mesh.nodes()[i as usize];
                }
                let rest = if plastic.is_empty() {
                    &built[..arity]
                } else {
                    &plastic[c * arity..(c + 1) * arity]
                };
                deformation(rest, &now[..arity])
            })
            .collect();
        let gradient = |cell: u32| gradients[cell as usize];
        let limit = tearing.strain.exp();
        let stretches: Vec<Real> = faces
            .0
            .iter()
            .map(|f| {
                0.5 * ((gradient(f.cells[0]) * f.normal).length()
                    + (gradient(f.cells[1]) * f.normal).length())
            })
            .collect();
        let rest = mesh.nodes();
        let centre = |f: &Face| -> Vector {
            f.nodes().iter().map(|&i| rest[i as usize]).sum::<Vector>() / f.len as Real
        };
        // While the last crack's release has not crossed the body, only that crack grows.
        let open = self.last.crack.filter(|c| c.quiet > 0.0);
        let on_crack = |f: &Face| open.is_none_or(|c| c.holds(centre(f)));
        // The crack of the step runs through the most stretched face, across its normal.
        let Some(seed) = (0..faces.0.len())
            .filter(|&k| stretches[k] > limit && on_crack(&faces.0[k]))
            .max_by(|&a, &b| stretches[a].total_cmp(&stretches[b]).then(b.cmp(&a)))
        else {
            return;
        };
        let seed_face = &faces.0[seed];
        let crack = open.unwrap_or(Crack {
            origin: centre(seed_face),
            across: seed_face.normal,
            band: 0.5 * longest_edge(seed_face.nodes().iter().map(|&i| rest[i as usize])),
            quiet: 0.0,
        });
        let mut torn: Vec<bool> = faces
            .0
            .iter()
            .zip(&stretches)
            .map(|(f, &s)| s > limit && crack.holds(centre(f)))
            .collect();
        let (cells, parents) = loop {
            let (cells, parents) = split(mesh, faces, &torn);
            if parents.is_empty() {
                return;
            }
            let nodes = mesh.nodes().len() + parents.len();
            let (roots, sizes) = pieces(&cells, arity, nodes);
            let mut kept = false;
            for (face, t) in faces.0.iter().zip(torn.iter_mut()).filter(|(_, t)| **t) {
                let small = face
                    .cells
                    .iter()
                    .any(|&c| sizes[&roots[c as usize]] < tearing.smallest_piece);
                if small {
                    *t = false;
                    kept = true;
                }
            }
            if !kept {
                break (cells, parents);
            }
        };
        // The faces that opened: their two cells no longer share all of the face's nodes.
        let opened: Vec<[u32; 2]> = faces
            .0
            .iter()
            .zip(&torn)
            .filter(|(_, t)| **t)
            .filter(|(f, _)| {
                let side = |c: u32| -> Vec<u32> {
                    let c = c as usize;
                    let (old, new) = (mesh.cell(c), &cells[c * arity..(c + 1) * arity]);
                    let mut v: Vec<u32> = f
                        .nodes()
                        .iter()
                        .map(|i| new[old.iter().position(|j| j == i).expect("a vertex")])
                        .collect();
                    v.sort_unstable();
                    v
                };
                side(f.cells[0]) != side(f.cells[1])
            })
            .map(|(f, _)| f.cells)
            .collect();
        if self.rebuild(cells, &parents).is_ok() {
            self.last.tears = opened;
            // The release travels at the bar wave speed; until it has crossed the body and
            // back, the stretch elsewhere is stale and only this crack may grow.
            let wave = (self.rest.params.material.young_modulus
                / self.rest.params.material.density)
                .sqrt();
            let quiet = 2.0 * extent(self.rest.mesh.nodes()) / wave;
            self.last.crack = Some(Crack {
                quiet: if quiet.is_finite() { quiet } else { 0.0 },
                ..crack
            });
        }
    }

    /// Rebuilds the body on its mesh with cells `cells` and the nodes `parents` copies appended,
    /// carrying its state over; the body is unchanged on an error (a mesh that does not
    /// validate, which a split of a valid one cannot give).
    fn rebuild(&mut self, cells: Vec<u32>, parents: &[u32]) -> Result<(), ()> {
        let old = &self.rest.mesh;
        let copy = |v: &[Vector]| -> Vec<Vector> {
            v.iter()
                .copied()
                .chain(parents.iter().map(|&p| v[p as usize]))
                .collect()
        };
        let mesh = Mesh::new(copy(old.nodes()), cells, old.kind()).map_err(|_| ())?;
        let n = mesh.nodes().len();
        let rest = Rest::new(mesh, self.rest.model, self.rest.params);
        let mut elements = ModelState::build(
            rest.model,
            &rest.mesh,
            &rest.masses,
            &rest.params,
            Rotation::IDENTITY,
            self.state.elements.plasticity(),
        )
        .map_err(|_| ())?;
        elements
            .set_plastic_rest(self.state.elements.plastic_rest())
            .map_err(|_| ())?;
        elements
            .set_warm_start(self.state.elements.warm_start())
            .map_err(|_| ())?;
        let mut list: Vec<Attachment> = self.bindings.list().to_vec();
        for (k, &p) in parents.iter().enumerate() {
            let copies: Vec<Attachment> = list
                .iter()
                .filter(|a| a.node == p)
                .map(|a| Attachment {
                    node: (old.nodes().len() + k) as u32,
                    ..*a
                })
                .collect();
            list.extend(copies);
        }
        let bindings = Bindings::from_list(list, n).map_err(|_| ())?;
        let state = State {
            positions: copy(&self.state.positions),
            velocities: copy(&self.state.velocities),
            elements,
        };
        if let Some(render) = &mut self.render {
            render.rebind(&rest.mesh);
        }
        let mut step = StepBuffers::new(Accumulator::new(n), false, Real::INFINITY, &state);
        step.midpoint = std::mem::take(&mut self.step.midpoint);
        step.soft_memory = std::mem::take(&mut self.step.soft_memory);
        step.auto_implicit = self.step.auto_implicit;
        step.global_iterations = self.step.global_iterations;
        rest.keep_slack(&self.rest);
        self.surface = Surface::build(&rest.mesh, &state.positions);
        self.rest = rest;
        self.state = state;
        self.step = step;
        self.bindings = bindings;
        self.last.report.nodes = n;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::super::material::Tearing;
    use super::super::super::math::{Real, Vector, DIM};
    use super::super::super::model::ElementModel;
    use super::super::DeformableBuilder;

    /// Cells that meet at one node only (a bow tie) are not cut apart by a split that tears
    /// nothing: only the torn faces separate a star.
    #[test]
    fn a_star_already_in_parts_stays_as_built() {
        use super::super::super::math::SIMPLEX_ARITY;
        use super::super::super::mesh::{CellKind, Mesh};
        use super::{split, Faces};
        let mut nodes = vec![Vector::ZERO];
        for sign in [1.0, -1.0] {
            for d in 0..DIM {
                let mut p = Vector::ZERO;
                p[d] = sign;
                nodes.push(p);
            }
        }
        // The second cell's vertices in the first's order, mirrored through the shared node:
        // its orientation flips in 3D (odd), not in 2D.
        let mut second: Vec<u32> = (DIM as u32 + 1..2 * DIM as u32 + 1).collect();
        if DIM == 3 {
            second.swap(0, 1);
        }
        let mut cells: Vec<u32> = (0..SIMPLEX_ARITY as u32).collect();
        cells.push(0);
        cells.extend(second);
        let mesh = Mesh::new(nodes, cells, CellKind::Simplex).unwrap();
        let faces = Faces::of(&mesh);
        assert!(faces.0.is_empty());
        let (cells, parents) = split(&mesh, &faces, &[]);
        assert!(parents.is_empty(), "copies of {parents:?}");
        assert_eq!(cells, mesh.cell_indices());
    }

    /// A tear splits the nodes without changing the body's energy or momentum, for every
    /// model: each model's energy is a sum over cells of terms of their own vertices.
    #[test]
    fn a_tear_keeps_energy_and_momentum() {
        for model in [
            ElementModel::Springs,
            ElementModel::CentroidSprings,
            ElementModel::NonlinearSprings,
            ElementModel::EdgeRepulsion,
            ElementModel::SHAPE_MATCHING,
        ] {
            let mut half = Vector::splat(0.1);
            half[0] = 0.5;
            let mut res = [3; DIM];
            res[0] = 6;
            let mut body = DeformableBuilder::cuboid(half, res)
                .model(model)
                .tearing(Tearing {
                    strain: 0.05,
                    smallest_piece: 1,
                })
                .build()
                .unwrap();
            // Stretched along the first axis, most in the middle, and moving.
            let x: Vec<Vector> = body
                .positions()
                .iter()
                .map(|p| {
                    let mut q = *p;
                    q[0] *= 1.0 + 0.2 * (1.0 - 2.0 * p[0].abs());
                    q[1] += 0.03 * p[0];
                    q
                })
                .collect();
            body.set_positions(&x).unwrap();
            let v: Vec<Vector> = x.iter().map(|p| Vector::splat(0.3) + *p * 2.0).collect();
            body.set_velocities(&v).unwrap();
            let momentum = |b: &super::Deformable| -> Vector {
                b.velocities()
                    .iter()
                    .zip(b.masses())
                    .map(|(v, m)| *v * *m)
                    .sum()
            };
            let (e0, k0, p0, n0) = (
                body.elastic_energy(),
                body.kinetic_energy(),
                momentum(&body),
                body.num_nodes(),
            );
            body.tear(1.0 / 60.0);
            let name = model.name();
            assert!(!body.last_tears().is_empty(), "{name}: nothing tore");
            assert!(body.num_nodes() > n0, "{name}: no node split");
            let close = |a: Real, b: Real| (a - b).abs() <= 1e-5 * a.abs().max(b.abs());
            assert!(
                close(body.elastic_energy(), e0),
                "{name}: {} vs {e0}",
                body.elastic_energy()
            );
            assert!(
                close(body.kinetic_energy(), k0),
                "{name}: {} vs {k0}",
                body.kinetic_energy()
            );
            assert!(
                (momentum(&body) - p0).length() <= 1e-5 * p0.length(),
                "{name}"
            );
        }
    }
}
