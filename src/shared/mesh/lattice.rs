//! Box lattices: the `cuboid` generator.

use super::super::error::BuildError;
use super::super::math::{Real, Vector, DIM};
use super::cube::{kuhn_simplices, vtk_to_bits, CUBE_ARITY};
use super::{CellKind, Mesh};

impl Mesh {
    /// A box `[-half_extents, half_extents]` sampled by `resolution[d]` nodes along axis `d`
    /// (at least 2), centred on the origin.
    ///
    /// With [`CellKind::Simplex`] each lattice box is split into `DIM!` simplices (2 triangles,
    /// 6 tetrahedra) by the Kuhn split, mirrored in alternate boxes so that the diagonals do
    /// not all lean the same way; every simplex is positively oriented. With
    /// [`CellKind::Cube`] the lattice boxes themselves are the cells (VTK vertex order).
    pub fn cuboid(
        half_extents: Vector,
        resolution: [usize; DIM],
        kind: CellKind,
    ) -> Result<Mesh, BuildError> {
        for d in 0..DIM {
            let h = half_extents[d];
            if !(h.is_finite() && h > 0.0) {
                return Err(BuildError::InvalidParameter {
                    name: "half_extents",
                    value: h,
                    expected: "every component positive and finite",
                });
            }
            if resolution[d] < 2 {
                return Err(BuildError::InvalidParameter {
                    name: "resolution",
                    value: resolution[d] as Real,
                    expected: "at least 2 nodes along every axis",
                });
            }
        }
        let total: usize = resolution.iter().product();
        if total > u32::MAX as usize / 2 {
            return Err(BuildError::InvalidParameter {
                name: "resolution",
                value: total as Real,
                expected: "fewer than 2^31 nodes",
            });
        }

        // Node (i, j, k) has index i + n_x (j + n_y k).
        let node_index = |c: [usize; DIM]| -> u32 {
            let mut idx = 0usize;
            for d in (0..DIM).rev() {
                idx = idx * resolution[d] + c[d];
            }
            idx as u32
        };
        let mut nodes = Vec::with_capacity(total);
        for flat in 0..total {
            let mut rem = flat;
            let mut p = Vector::ZERO;
            for d in 0..DIM {
                let c = rem % resolution[d];
                rem /= resolution[d];
                let t = c as Real / (resolution[d] - 1) as Real;
                p[d] = -half_extents[d] + 2.0 * half_extents[d] * t;
            }
            nodes.push(p);
        }

        let boxes: Vec<usize> = resolution.iter().map(|r| r - 1).collect();
        let box_count: usize = boxes.iter().product();
        let simplices = kuhn_simplices();
        let mut cells = Vec::new();
        for flat in 0..box_count {
            let mut rem = flat;
            let mut origin = [0usize; DIM];
            for d in 0..DIM {
                origin[d] = rem % boxes[d];
                rem /= boxes[d];
            }
            // Mirror the split in odd boxes along each axis (keeps the lattice conforming).
            let mut flip = 0usize;
            for (d, o) in origin.iter().enumerate() {
                if o % 2 == 1 {
                    flip |= 1 << d;
                }
            }
            let corner = |bits: usize| -> u32 {
                let mut c = origin;
                for (d, cd) in c.iter_mut().enumerate() {
                    *cd += (bits >> d) & 1;
                }
                node_index(c)
            };
            match kind {
                CellKind::Cube => {
                    for n in 0..CUBE_ARITY {
                        cells.push(corner(vtk_to_bits(n)));
                    }
                }
                CellKind::Simplex => {
                    for s in &simplices {
                        let mut ids: Vec<u32> = s.iter().map(|&b| corner(b ^ flip)).collect();
                        let pts: Vec<Vector> = ids.iter().map(|&i| nodes[i as usize]).collect();
                        if super::super::math::simplex_volume(&pts) < 0.0 {
                            ids.swap(0, 1);
                        }
                        cells.extend_from_slice(&ids);
                    }
                }
            }
        }
        Mesh::new(nodes, cells, kind)
    }
}

impl Mesh {
    /// A ball of the given radius, cut from a [`Mesh::cuboid`] lattice with `resolution` nodes
    /// across its diameter: the cells whose centroid lies inside the ball are kept. The surface
    /// is staircased at the lattice spacing.
    pub fn ball(radius: Real, resolution: usize, kind: CellKind) -> Result<Mesh, BuildError> {
        if !(radius.is_finite() && radius > 0.0) {
            return Err(BuildError::InvalidParameter {
                name: "radius",
                value: radius,
                expected: "a positive finite radius",
            });
        }
        let lattice = Mesh::cuboid(Vector::splat(radius), [resolution; DIM], kind)?;
        lattice.retain_cells(|cell| {
            let c = cell.iter().copied().sum::<Vector>() / cell.len() as Real;
            c.length() <= radius
        })
    }

    /// A new mesh with only the cells for which `keep(cell vertex positions)` is true; nodes
    /// no longer used are dropped and the rest renumbered in order.
    pub fn retain_cells(
        &self,
        mut keep: impl FnMut(&[Vector]) -> bool,
    ) -> Result<Mesh, BuildError> {
        let mut pts = Vec::new();
        let mut kept: Vec<u32> = Vec::new();
        for c in self.cells() {
            pts.clear();
            pts.extend(c.iter().map(|&i| self.nodes()[i as usize]));
            if keep(&pts) {
                kept.extend_from_slice(c);
            }
        }
        let mut remap = vec![u32::MAX; self.nodes().len()];
        let mut nodes = Vec::new();
        for i in kept.iter_mut() {
            if remap[*i as usize] == u32::MAX {
                remap[*i as usize] = nodes.len() as u32;
                nodes.push(self.nodes()[*i as usize]);
            }
            *i = remap[*i as usize];
        }
        Mesh::new(nodes, kept, self.kind())
    }
}
