//! Checks of a valid mesh for what is legal but probably a mistake ([`MeshWarning`]), and the
//! repairs that go with them.

use std::collections::HashMap;

use super::super::error::{BuildError, MeshWarning};
use super::super::math::{Real, Vector, DIM, FACET_ARITY};
use super::{CellKind, Mesh};

impl Mesh {
    /// What is legal in this mesh but probably a mistake: coincident nodes, a surface that is
    /// not manifold, pieces that share no node (in this order, each kind sorted by node).
    pub fn diagnose(&self) -> Vec<MeshWarning> {
        let mut out = Vec::new();
        for (first, second) in coincident_pairs(self.nodes(), self.tolerance()) {
            out.push(MeshWarning::CoincidentNodes {
                first,
                second,
                distance: self.nodes()[first as usize].distance(self.nodes()[second as usize]),
            });
        }
        out.extend(self.non_manifold_ridges());
        let pieces = self.pieces();
        if pieces > 1 {
            out.push(MeshWarning::Disconnected { pieces });
        }
        out
    }

    /// The mesh with every group of coincident nodes (closer than `tolerance`, absolute)
    /// welded into its lowest-numbered node, and the nodes renumbered; cells that weld into a
    /// degenerate one are an error ([`BuildError::DegenerateElement`]).
    pub fn merge_coincident_nodes(&self, tolerance: Real) -> Result<Mesh, BuildError> {
        if !(tolerance.is_finite() && tolerance >= 0.0) {
            return Err(BuildError::InvalidParameter {
                name: "tolerance",
                value: tolerance,
                expected: "non-negative and finite",
            });
        }
        let n = self.nodes().len();
        let mut root: Vec<u32> = (0..n as u32).collect();
        fn find(root: &mut [u32], mut i: u32) -> u32 {
            while root[i as usize] != i {
                root[i as usize] = root[root[i as usize] as usize];
                i = root[i as usize];
            }
            i
        }
        for (a, b) in coincident_pairs(self.nodes(), tolerance) {
            let (ra, rb) = (find(&mut root, a), find(&mut root, b));
            let (lo, hi) = (ra.min(rb), ra.max(rb));
            root[hi as usize] = lo;
        }
        let cells: Vec<u32> = self
            .cell_indices()
            .iter()
            .map(|&i| find(&mut root, i))
            .collect();
        Mesh::compact(self.nodes().to_vec(), cells, self.kind()).map(|(mesh, _)| mesh)
    }

    /// A mesh from nodes and cells after dropping the nodes no cell uses (which
    /// [`Mesh::new`] refuses, [`BuildError::UnreferencedNode`]), and the new index of each
    /// old node (`u32::MAX` for a dropped one). Other errors as [`Mesh::new`].
    pub fn compact(
        nodes: Vec<Vector>,
        cells: Vec<u32>,
        kind: CellKind,
    ) -> Result<(Mesh, Vec<u32>), BuildError> {
        let mut used = vec![false; nodes.len()];
        for (cell, c) in cells.chunks(kind.arity()).enumerate() {
            for &i in c {
                match used.get_mut(i as usize) {
                    Some(u) => *u = true,
                    None => {
                        return Err(BuildError::IndexOutOfRange {
                            cell,
                            index: i,
                            node_count: nodes.len(),
                        })
                    }
                }
            }
        }
        let mut map = vec![u32::MAX; nodes.len()];
        let mut kept = Vec::with_capacity(nodes.len());
        for (i, p) in nodes.into_iter().enumerate() {
            if used[i] {
                map[i] = kept.len() as u32;
                kept.push(p);
            }
        }
        let cells = cells.into_iter().map(|i| map[i as usize]).collect();
        Ok((Mesh::new(kept, cells, kind)?, map))
    }

    /// `1e-6` of the mesh's largest extent: coordinates closer than this coincide.
    fn tolerance(&self) -> Real {
        let (mut lo, mut hi) = (self.nodes()[0], self.nodes()[0]);
        for p in self.nodes() {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        1e-6 * (hi - lo).max_element()
    }

    fn non_manifold_ridges(&self) -> Vec<MeshWarning> {
        let mut count: HashMap<Vec<u32>, usize> = HashMap::new();
        for f in self.boundary_facets() {
            for skip in 0..FACET_ARITY {
                let mut ridge: Vec<u32> = (0..FACET_ARITY)
                    .filter(|&k| k != skip)
                    .map(|k| f[k])
                    .collect();
                ridge.sort_unstable();
                *count.entry(ridge).or_default() += 1;
            }
        }
        let mut bad: Vec<(Vec<u32>, usize)> = count.into_iter().filter(|(_, c)| *c != 2).collect();
        bad.sort();
        bad.into_iter()
            .map(|(nodes, facets)| MeshWarning::NonManifoldSurface { nodes, facets })
            .collect()
    }

    /// Number of pieces of cells connected through shared nodes.
    fn pieces(&self) -> usize {
        let n = self.nodes().len();
        let mut root: Vec<usize> = (0..n).collect();
        fn find(root: &mut [usize], mut i: usize) -> usize {
            while root[i] != i {
                root[i] = root[root[i]];
                i = root[i];
            }
            i
        }
        for c in self.cells() {
            let a = find(&mut root, c[0] as usize);
            for &i in &c[1..] {
                let b = find(&mut root, i as usize);
                root[b] = a;
            }
        }
        (0..n).filter(|&i| find(&mut root, i) == i).count()
    }
}

/// Pairs `(a, b)`, `a < b`, of nodes closer than `tolerance`, sorted; a hash grid of cells of
/// the tolerance's size keeps it linear.
fn coincident_pairs(nodes: &[Vector], tolerance: Real) -> Vec<(u32, u32)> {
    let cell = tolerance.max(Real::MIN_POSITIVE);
    let key = |p: Vector| -> [i64; DIM] { std::array::from_fn(|d| (p[d] / cell).floor() as i64) };
    let mut grid: HashMap<[i64; DIM], Vec<u32>> = HashMap::new();
    for (i, p) in nodes.iter().enumerate() {
        grid.entry(key(*p)).or_default().push(i as u32);
    }
    let mut out = Vec::new();
    for (i, p) in nodes.iter().enumerate() {
        let k = key(*p);
        for offset in 0..3usize.pow(DIM as u32) {
            let mut probe = k;
            let mut o = offset;
            for c in probe.iter_mut() {
                *c += (o % 3) as i64 - 1;
                o /= 3;
            }
            for &j in grid.get(&probe).map_or(&[][..], |v| v.as_slice()) {
                if (j as usize) > i && nodes[j as usize].distance(*p) <= tolerance {
                    out.push((i as u32, j));
                }
            }
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}
