//! Rest topology and geometry of a deformable: nodes, cells, validation, boundary.
//!
//! A mesh holds one kind of cell: simplices (triangles in 2D, tetrahedra in 3D) or boxes
//! (quads in 2D, hexahedra in 3D, VTK vertex order). Every cell must be positively oriented
//! at rest (counter-clockwise triangles, right-handed tetrahedra, every box corner
//! right-handed). The boundary is the set of cell facets that belong to exactly one cell,
//! oriented outwards and split into simplices (segments in 2D, triangles in 3D): the surface
//! that contact and rendering use.

pub mod cube;
mod diagnose;
pub mod io;
mod lattice;
pub(crate) mod voxel;

pub use super::error::MeshWarning;

use std::collections::HashMap;

use super::error::BuildError;
use super::math::{self, Real, Vector, DIM, DIM_FACTORIAL, FACET_ARITY, SIMPLEX_ARITY};
use cube::{bits_to_vtk, faces, kuhn_simplices, vtk_to_bits, CUBE_ARITY};

/// The kind of cell a mesh is made of.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, Default)]
pub enum CellKind {
    /// Triangles (2D) or tetrahedra (3D).
    #[default]
    Simplex,
    /// Quads (2D) or hexahedra (3D), vertices in VTK order.
    Cube,
}

impl CellKind {
    /// Vertices per cell.
    pub const fn arity(self) -> usize {
        match self {
            CellKind::Simplex => SIMPLEX_ARITY,
            CellKind::Cube => CUBE_ARITY,
        }
    }

    /// A human name for messages ("triangle", "tetrahedron", ...).
    pub const fn name(self) -> &'static str {
        match (self, DIM) {
            (CellKind::Simplex, 2) => "triangle",
            (CellKind::Simplex, _) => "tetrahedron",
            (CellKind::Cube, 2) => "quad",
            (CellKind::Cube, _) => "hexahedron",
        }
    }
}

/// A validated rest mesh.
#[derive(Clone, Debug)]
pub struct Mesh {
    nodes: Vec<Vector>,
    cells: Vec<u32>,
    kind: CellKind,
    rest_volumes: Vec<Real>,
    /// Per cell, per corner: the rest measure whose ratio is the cell's quality (the volume
    /// for simplices; the corner volume for boxes).
    rest_corners: Vec<Real>,
    boundary_facets: Vec<[u32; FACET_ARITY]>,
    boundary_nodes: Vec<u32>,
}

impl Mesh {
    /// Builds and validates a mesh from node positions and a flat list of cell vertex
    /// indices (`kind.arity()` per cell).
    ///
    /// Errors: [`BuildError::EmptyMesh`], [`BuildError::MalformedCells`],
    /// [`BuildError::NonFiniteCoordinate`], [`BuildError::IndexOutOfRange`],
    /// [`BuildError::DegenerateElement`], [`BuildError::InvertedElement`],
    /// [`BuildError::UnreferencedNode`], [`BuildError::DuplicateCell`],
    /// [`BuildError::OverlappingCells`]. What is legal but
    /// probably a mistake (coincident nodes, a surface that is not manifold, separate pieces)
    /// is listed by [`Mesh::diagnose`].
    pub fn new(nodes: Vec<Vector>, cells: Vec<u32>, kind: CellKind) -> Result<Mesh, BuildError> {
        let arity = kind.arity();
        if nodes.is_empty() || cells.is_empty() {
            return Err(BuildError::EmptyMesh {
                nodes: nodes.len(),
                cells: cells.len() / arity,
            });
        }
        if !cells.len().is_multiple_of(arity) {
            return Err(BuildError::MalformedCells {
                len: cells.len(),
                arity,
                kind: kind.name(),
            });
        }
        if let Some((node, p)) = nodes.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return Err(BuildError::NonFiniteCoordinate {
                node,
                coordinates: (0..DIM).map(|d| p[d]).collect(),
            });
        }
        let mut referenced = vec![false; nodes.len()];
        for (cell, c) in cells.chunks_exact(arity).enumerate() {
            for &index in c {
                if index as usize >= nodes.len() {
                    return Err(BuildError::IndexOutOfRange {
                        cell,
                        index,
                        node_count: nodes.len(),
                    });
                }
                referenced[index as usize] = true;
            }
        }
        if let Some(node) = referenced.iter().position(|r| !r) {
            return Err(BuildError::UnreferencedNode { node });
        }

        let mut seen = HashMap::with_capacity(cells.len() / arity);
        for (cell, c) in cells.chunks_exact(arity).enumerate() {
            let mut key = [u32::MAX; 8];
            key[..arity].copy_from_slice(c);
            key[..arity].sort_unstable();
            if let Some(first) = seen.insert(key, cell) {
                return Err(BuildError::DuplicateCell { cell, first });
            }
        }

        let mut rest_volumes = Vec::with_capacity(cells.len() / arity);
        let mut rest_corners = Vec::with_capacity(cells.len());
        let mut pts = Vec::with_capacity(arity);
        for (cell, c) in cells.chunks_exact(arity).enumerate() {
            pts.clear();
            pts.extend(c.iter().map(|&i| nodes[i as usize]));
            let scale = max_edge_length(&pts).powi(DIM as i32);
            let repeated = (1..c.len()).any(|i| c[..i].contains(&c[i]));
            let volume = cell_volume(kind, &pts);
            let corners = corner_measures(kind, &pts);
            let worst = corners.iter().copied().fold(Real::INFINITY, Real::min);
            if repeated
                || worst.abs() <= 1e-7 * scale
                || scale.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
            {
                return Err(BuildError::DegenerateElement {
                    cell,
                    volume: worst,
                });
            }
            if worst < 0.0 {
                return Err(BuildError::InvertedElement {
                    cell,
                    volume: worst,
                });
            }
            rest_volumes.push(volume);
            rest_corners.extend_from_slice(&corners);
        }

        let mut mesh = Mesh {
            nodes,
            cells,
            kind,
            rest_volumes,
            rest_corners,
            boundary_facets: Vec::new(),
            boundary_nodes: Vec::new(),
        };
        mesh.extract_boundary()?;
        Ok(mesh)
    }

    /// Rest node positions.
    pub fn nodes(&self) -> &[Vector] {
        &self.nodes
    }

    /// The cell kind.
    pub fn kind(&self) -> CellKind {
        self.kind
    }

    /// Number of cells.
    pub fn num_cells(&self) -> usize {
        self.rest_volumes.len()
    }

    /// The flat cell index list.
    pub fn cell_indices(&self) -> &[u32] {
        &self.cells
    }

    /// Iterates over the cells' vertex index lists.
    pub fn cells(&self) -> std::slice::ChunksExact<'_, u32> {
        self.cells.chunks_exact(self.kind.arity())
    }

    /// The vertex indices of cell `i`.
    pub fn cell(&self, i: usize) -> &[u32] {
        let a = self.kind.arity();
        &self.cells[i * a..(i + 1) * a]
    }

    /// Rest volume (area in 2D) of each cell.
    pub fn rest_volumes(&self) -> &[Real] {
        &self.rest_volumes
    }

    /// Total rest volume (area in 2D).
    pub fn total_volume(&self) -> Real {
        self.rest_volumes.iter().sum()
    }

    /// Boundary facets (segments in 2D, triangles in 3D), oriented outwards.
    pub fn boundary_facets(&self) -> &[[u32; FACET_ARITY]] {
        &self.boundary_facets
    }

    /// Nodes on the boundary, ascending.
    pub fn boundary_nodes(&self) -> &[u32] {
        &self.boundary_nodes
    }

    /// Quality of cell `i` at `positions`: the volume ratio `V / V0` for simplices, the
    /// smallest corner-volume ratio for boxes. Zero or negative means collapsed or inverted.
    pub fn cell_quality(&self, i: usize, positions: &[Vector]) -> Real {
        self.cell_quality_with(i, |n| positions[n as usize])
    }

    /// [`Self::cell_quality`] with each vertex's position given by `position` (of its node
    /// index).
    pub(crate) fn cell_quality_with(&self, i: usize, position: impl Fn(u32) -> Vector) -> Real {
        let c = self.cell(i);
        let a = c.len();
        match self.kind {
            CellKind::Simplex => {
                let mut p = [Vector::ZERO; SIMPLEX_ARITY];
                for (pj, &n) in p.iter_mut().zip(c) {
                    *pj = position(n);
                }
                math::simplex_volume(&p) / self.rest_volumes[i]
            }
            CellKind::Cube => {
                let mut p = [Vector::ZERO; CUBE_ARITY];
                for (pj, &n) in p.iter_mut().zip(c) {
                    *pj = position(n);
                }
                let rest = &self.rest_corners[i * a..(i + 1) * a];
                (0..CUBE_ARITY)
                    .map(|k| corner_measure(&p, vtk_to_bits(k)) / rest[k])
                    .fold(Real::INFINITY, Real::min)
            }
        }
    }

    /// All distinct vertex pairs that share a cell (edges and, for boxes, face and body
    /// diagonals), each with the volume it stands for: the sum over the cells containing it
    /// of `V_cell / pairs_per_cell`. Each pair lowest node first, in order of their nodes (a
    /// loop over them walks the nodes in order, and the pairs of a run of nodes are a run).
    pub fn vertex_pairs(&self) -> Vec<([u32; 2], Real)> {
        let a = self.kind.arity();
        let per_cell = (a * (a - 1) / 2) as Real;
        let mut index: HashMap<[u32; 2], usize> = HashMap::new();
        let mut out: Vec<([u32; 2], Real)> = Vec::new();
        for (cell, c) in self.cells().enumerate() {
            let share = self.rest_volumes[cell] / per_cell;
            for i in 0..a {
                for j in i + 1..a {
                    let key = if c[i] < c[j] {
                        [c[i], c[j]]
                    } else {
                        [c[j], c[i]]
                    };
                    match index.get(&key) {
                        Some(&k) => out[k].1 += share,
                        None => {
                            index.insert(key, out.len());
                            out.push((key, share));
                        }
                    }
                }
            }
        }
        out.sort_unstable_by_key(|(key, _)| *key);
        out
    }

    fn extract_boundary(&mut self) -> Result<(), BuildError> {
        let local_faces = local_faces(self.kind);
        // Key: sorted node ids (padded). Value: (count, cell, local face).
        let mut seen: HashMap<[u32; 4], usize> = HashMap::new();
        let mut faces_found: Vec<(u32, usize, usize)> = Vec::new();
        let arity = self.kind.arity();
        for cell in 0..self.num_cells() {
            let c = &self.cells[cell * arity..(cell + 1) * arity];
            for (lf, f) in local_faces.iter().enumerate() {
                let mut key = [u32::MAX; 4];
                for (k, &l) in f.iter().enumerate() {
                    key[k] = c[l];
                }
                key[..f.len()].sort_unstable();
                match seen.get(&key) {
                    Some(&k) => faces_found[k].0 += 1,
                    None => {
                        seen.insert(key, faces_found.len());
                        faces_found.push((1, cell, lf));
                    }
                }
            }
        }
        if let Some(&(count, cell, lf)) = faces_found.iter().find(|f| f.0 > 2) {
            let c = &self.cells[cell * arity..(cell + 1) * arity];
            return Err(BuildError::OverlappingCells {
                face: local_faces[lf].iter().map(|&l| c[l]).collect(),
                cells: count as usize,
            });
        }
        let mut on_boundary = vec![false; self.nodes.len()];
        for &(count, cell, lf) in &faces_found {
            if count != 1 {
                continue;
            }
            let c = &self.cells[cell * arity..(cell + 1) * arity];
            let mut ids: Vec<u32> = local_faces[lf].iter().map(|&l| c[l]).collect();
            let centroid_cell =
                c.iter().map(|&i| self.nodes[i as usize]).sum::<Vector>() / arity as Real;
            let centroid_face =
                ids.iter().map(|&i| self.nodes[i as usize]).sum::<Vector>() / ids.len() as Real;
            let pts: Vec<Vector> = ids.iter().map(|&i| self.nodes[i as usize]).collect();
            if math::facet_normal(&pts).dot(centroid_face - centroid_cell) < 0.0 {
                ids.reverse();
            }
            for &i in &ids {
                on_boundary[i as usize] = true;
            }
            // Fan-split polygons into simplicial facets (a quad face into two triangles).
            for k in 0..=ids.len() - FACET_ARITY {
                let mut f = [0u32; FACET_ARITY];
                f[0] = ids[0];
                f[1..].copy_from_slice(&ids[k + 1..k + FACET_ARITY]);
                self.boundary_facets.push(f);
            }
        }
        self.boundary_nodes = (0..self.nodes.len() as u32)
            .filter(|&i| on_boundary[i as usize])
            .collect();
        Ok(())
    }
}

fn max_edge_length(p: &[Vector]) -> Real {
    let mut m: Real = 0.0;
    for i in 0..p.len() {
        for j in i + 1..p.len() {
            m = m.max(p[i].distance(p[j]));
        }
    }
    m
}

/// The faces of a cell of `kind`, each as its vertices' slots in the cell.
pub(crate) fn local_faces(kind: CellKind) -> Vec<Vec<usize>> {
    match kind {
        CellKind::Simplex => (0..SIMPLEX_ARITY)
            .map(|skip| (0..SIMPLEX_ARITY).filter(|&k| k != skip).collect())
            .collect(),
        CellKind::Cube => faces()
            .into_iter()
            .map(|f| f.into_iter().map(bits_to_vtk).collect())
            .collect(),
    }
}

/// Signed volume of a cell (area in 2D) from its vertices in local order.
pub fn cell_volume(kind: CellKind, p: &[Vector]) -> Real {
    match kind {
        CellKind::Simplex => math::simplex_volume(p),
        CellKind::Cube => kuhn_simplices()
            .iter()
            .map(|s| {
                let q: Vec<Vector> = s.iter().map(|&b| p[bits_to_vtk(b)]).collect();
                math::simplex_volume(&q) * parity_sign(s)
            })
            .sum(),
    }
}

// The Kuhn simplex of an odd permutation is negatively oriented on a right-handed box.
fn parity_sign(s: &[usize]) -> Real {
    let axes: Vec<usize> = s
        .windows(2)
        .map(|w| (w[1] ^ w[0]).trailing_zeros() as usize)
        .collect();
    let mut inversions = 0;
    for i in 0..axes.len() {
        for j in i + 1..axes.len() {
            if axes[i] > axes[j] {
                inversions += 1;
            }
        }
    }
    if inversions % 2 == 0 {
        1.0
    } else {
        -1.0
    }
}

/// The volume spanned at corner `bits` by its `DIM` axis edges (oriented along +axes), over
/// `DIM!`: positive for a right-handed corner.
fn corner_measure(p: &[Vector], bits: usize) -> Real {
    let base = p[bits_to_vtk(bits)];
    let mut e = [Vector::ZERO; DIM];
    for (d, ed) in e.iter_mut().enumerate() {
        let nb = p[bits_to_vtk(bits ^ (1 << d))];
        let sign = if bits & (1 << d) == 0 { 1.0 } else { -1.0 };
        *ed = (nb - base) * sign;
    }
    math::det(&e) / DIM_FACTORIAL
}

fn corner_measures(kind: CellKind, p: &[Vector]) -> Vec<Real> {
    match kind {
        CellKind::Simplex => vec![math::simplex_volume(p)],
        CellKind::Cube => (0..CUBE_ARITY)
            .map(|k| corner_measure(p, vtk_to_bits(k)))
            .collect(),
    }
}
