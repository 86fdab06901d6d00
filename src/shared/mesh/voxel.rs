//! Lattices cut from parry shapes: [`Mesh::from_shape`] (and the shape checks the 3D
//! isosurface stuffing shares).
//!
//! The shape is sampled on a grid: a lattice box (square in 2D, cube in 3D) is kept when its
//! centre is inside the shape (`PointQuery::contains_local_point`). Of the boxes kept, the
//! largest set connected through shared facets is the mesh; smaller islands (and boxes
//! touching the rest only at an edge or a corner) are dropped.
//!
//! Why not parry's own voxeliser (`VoxelSet::voxelize`)? It takes a triangle mesh (a ball
//! or a capsule would first be tessellated, losing volume) and marks every voxel that
//! touches the surface as filled, which biases the volume upwards by about half a voxel
//! layer. The centre test works on the exact shape, any shape that answers point queries,
//! and its volume error shrinks with the cell size with no bias.

use super::super::error::BuildError;
use super::super::math::{Real, Vector, DIM};
use super::super::rapier::parry::shape::{Shape, TriMesh, TriMeshFlags};
use super::{CellKind, Mesh};

/// Largest number of lattice boxes [`Mesh::from_shape`] samples.
const MAX_BOXES: usize = 1 << 27;

impl Mesh {
    /// A lattice of boxes of side `cell_size` filling `shape` (in the shape's local frame):
    /// the boxes whose centre is inside the shape, split into simplices with
    /// [`CellKind::Simplex`] exactly as [`Mesh::cuboid`] splits them. The surface is
    /// staircased at the lattice spacing; only the largest facet-connected part is kept. Its
    /// nodes, the boxes' corners, reach up to half a box diagonal (`√DIM / 2 · cell_size`) past
    /// the shape: place the body by its nodes' extent, not the shape's, next to a two-sided
    /// surface (a trimesh, a polyline, a heightfield), which keeps a node started on its far
    /// side there.
    ///
    /// Any bounded shape that answers point queries works: balls, capsules, cuboids, convex
    /// polygons and polyhedra, compounds. A triangle mesh must be closed and oriented
    /// outwards in 3D; it is given `TriMeshFlags::ORIENTED` (pseudo-normals, for the inside
    /// test) if it lacks it.
    ///
    /// Errors: [`BuildError::InvalidParameter`] for a cell size that is not positive and
    /// finite, an unbounded shape, a lattice of more than 2^27 boxes, a shape that no box
    /// centre falls into, or a triangle mesh whose topology parry rejects.
    ///
    /// ```
    /// use sinew::dim3::{CellKind, Mesh};
    /// use sinew::dim3::rapier::parry::shape::Ball;
    ///
    /// let mesh = Mesh::from_shape(&Ball::new(0.5), 0.05, CellKind::Simplex).unwrap();
    /// let exact = 4.0 / 3.0 * std::f32::consts::PI * 0.125;
    /// assert!((mesh.total_volume() - exact).abs() < 0.02 * exact);
    /// ```
    pub fn from_shape(
        shape: &dyn Shape,
        cell_size: Real,
        kind: CellKind,
    ) -> Result<Mesh, BuildError> {
        check_cell_size(cell_size)?;
        let oriented = oriented(shape)?;
        let shape: &dyn Shape = oriented.as_ref().map_or(shape, |t| t as &dyn Shape);
        let (centre, counts) = boxes_over(shape, cell_size, 0)?;
        let total: usize = counts.iter().product();
        let mut half = Vector::ZERO;
        for d in 0..DIM {
            half[d] = 0.5 * counts[d] as Real * cell_size;
        }
        let origin = centre - half;

        // Flat box index i + n_x (j + n_y k), as in `Mesh::cuboid`.
        let coords = |mut flat: usize| {
            let mut c = [0usize; DIM];
            for (d, cd) in c.iter_mut().enumerate() {
                *cd = flat % counts[d];
                flat /= counts[d];
            }
            c
        };
        let flat_of = |c: [usize; DIM]| {
            let mut flat = 0;
            for d in (0..DIM).rev() {
                flat = flat * counts[d] + c[d];
            }
            flat
        };
        let inside: Vec<bool> = (0..total)
            .map(|flat| {
                let c = coords(flat);
                let mut p = origin;
                for d in 0..DIM {
                    p[d] += (c[d] as Real + 0.5) * cell_size;
                }
                shape.contains_local_point(p)
            })
            .collect();

        // Largest facet-connected component.
        let mut component = vec![usize::MAX; total];
        let mut best = (0usize, usize::MAX);
        let mut stack = Vec::new();
        for start in 0..total {
            if !inside[start] || component[start] != usize::MAX {
                continue;
            }
            component[start] = start;
            stack.push(start);
            let mut size = 0;
            while let Some(b) = stack.pop() {
                size += 1;
                let c = coords(b);
                for d in 0..DIM {
                    for step in [-1isize, 1] {
                        let v = c[d] as isize + step;
                        if v < 0 || v >= counts[d] as isize {
                            continue;
                        }
                        let mut nc = c;
                        nc[d] = v as usize;
                        let nb = flat_of(nc);
                        if inside[nb] && component[nb] == usize::MAX {
                            component[nb] = start;
                            stack.push(nb);
                        }
                    }
                }
            }
            if size > best.0 {
                best = (size, start);
            }
        }
        if best.0 == 0 {
            return Err(BuildError::InvalidParameter {
                name: "cell_size",
                value: cell_size,
                expected:
                    "a cell size small enough that some lattice box centre is inside the shape",
            });
        }

        let mut resolution = [0usize; DIM];
        for (r, n) in resolution.iter_mut().zip(counts) {
            *r = n + 1;
        }
        let lattice = Mesh::cuboid(half, resolution, kind)?;
        let mut mesh = lattice.retain_cells(|cell| {
            // The cell's centroid lies inside its lattice box (also for the simplices).
            let centroid = cell.iter().copied().sum::<Vector>() / cell.len() as Real;
            let mut c = [0usize; DIM];
            for d in 0..DIM {
                let v = ((centroid[d] + half[d]) / cell_size).floor();
                c[d] = (v.max(0.0) as usize).min(counts[d] - 1);
            }
            component[flat_of(c)] == best.1
        })?;
        for p in &mut mesh.nodes {
            *p += centre;
        }
        Ok(mesh)
    }
}

/// `shape` ready for inside tests: a triangle mesh without `TriMeshFlags::ORIENTED` gets a
/// copy with it (pseudo-normals); `None` when the shape is fine as it is.
pub(crate) fn oriented(shape: &dyn Shape) -> Result<Option<TriMesh>, BuildError> {
    match shape.as_trimesh() {
        Some(t) if !t.flags().contains(TriMeshFlags::ORIENTED) => {
            let mut t = t.clone();
            t.set_flags(t.flags() | TriMeshFlags::ORIENTED)
                .map_err(|_| BuildError::InvalidParameter {
                    name: "shape",
                    value: 0.0,
                    expected: "a closed, consistently oriented triangle mesh",
                })?;
            Ok(Some(t))
        }
        _ => Ok(None),
    }
}

/// A lattice of boxes of side `cell_size` over `shape`'s bounding box, `margin` boxes wider
/// on every side: its centre and its box count along each axis. Errors for an unbounded
/// shape or more than 2^27 boxes.
pub(crate) fn boxes_over(
    shape: &dyn Shape,
    cell_size: Real,
    margin: usize,
) -> Result<(Vector, [usize; DIM]), BuildError> {
    let aabb = shape.compute_local_aabb();
    let extent = aabb.maxs - aabb.mins;
    let centre = (aabb.maxs + aabb.mins) * 0.5;
    // parry gives unbounded shapes (half-spaces) a box of half the largest real.
    if !(extent.is_finite() && centre.is_finite()) || extent.max_element() >= Real::MAX / 4.0 {
        return Err(BuildError::InvalidParameter {
            name: "shape",
            value: Real::INFINITY,
            expected: "a bounded shape",
        });
    }
    let mut counts = [1usize; DIM];
    let mut total = 1usize;
    for (d, n) in counts.iter_mut().enumerate() {
        let c = (extent[d] / cell_size).ceil().max(1.0) + 2.0 * margin as Real;
        if c > MAX_BOXES as Real {
            total = usize::MAX;
            break;
        }
        *n = c as usize;
        total = total.saturating_mul(*n);
    }
    if total > MAX_BOXES {
        return Err(BuildError::InvalidParameter {
            name: "cell_size",
            value: cell_size,
            expected: "a cell size giving at most 2^27 lattice boxes over the shape",
        });
    }
    Ok((centre, counts))
}

/// A cell size must be positive and finite.
pub(crate) fn check_cell_size(cell_size: Real) -> Result<(), BuildError> {
    if cell_size.is_finite() && cell_size > 0.0 {
        Ok(())
    } else {
        Err(BuildError::InvalidParameter {
            name: "cell_size",
            value: cell_size,
            expected: "a positive finite cell size",
        })
    }
}
