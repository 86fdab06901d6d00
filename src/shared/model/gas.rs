//! Gas sealed in a body: chambers whose enclosed volume an isothermal gas holds
//! (`docs/ARCHITECTURE.md` §3.7).
//!
//! A chamber is a closed surface of facets facing out of the gas (into the walls). Its volume
//! `V = Σ_f D_f / DIM!`, `D_f` the signed simplex measure of facet `f` and a reference point
//! (any point: the surface is closed), is affine in each node's position. The gas stores
//! `U(V) = pV₀ ln(V₀/V) + p_a (V − V₀)`, `pV₀` its absolute pressure times its volume at
//! build and `p_a` the ambient pressure: zero at the built volume, `U' = −P` with
//! `P = pV₀/V − p_a` the gauge pressure, `U'' = pV₀/V²`. Node `i` feels `f_i = P g_i`,
//! `g_i = ∂V/∂x_i` (a third of the area vectors of its facets in 3D, half the normals of its
//! two segments in 2D), and the forces sum to zero with zero moment. The Hessian is
//! `U'' ∇V ∇Vᵀ + U' ∇²V`; `∇²V`'s diagonal blocks are zero (`V` is affine in each node), so a
//! node's own block is `U'' g_i g_iᵀ`, positive semi-definite, and one node's move changes
//! `V` by exactly `g_i · Δx_i`.

use super::super::error::BuildError;
use super::super::material::Gas;
use super::super::math::{
    self, Matrix, Real, Vector, DIM, DIM_FACTORIAL, FACET_ARITY, SIMPLEX_ARITY,
};
use super::super::mesh::Mesh;
use super::Accumulator;

/// A chamber's volume is taken as at least this fraction of its built volume, so a chamber
/// crushed flat (or turned inside out by a bone) has a large but finite pressure.
const MIN_VOLUME: Real = 1e-3;

/// One chamber of gas.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Debug)]
pub(crate) struct Chamber {
    /// Its facets, by node, facing out of the gas.
    facets: Vec<[u32; FACET_ARITY]>,
    /// Absolute pressure times volume at build, J (constant under the isothermal law).
    pv: Real,
    /// Volume at build.
    v0: Real,
    /// Ambient pressure, Pa.
    ambient: Real,
}

impl Chamber {
    /// The chamber of `gas` behind `facets` (by node of `mesh`, facing out of the gas);
    /// `index` names it in errors.
    pub fn new(
        index: usize,
        facets: Vec<[u32; FACET_ARITY]>,
        gas: Gas,
        mesh: &Mesh,
    ) -> Result<Chamber, BuildError> {
        gas.validate()?;
        let nodes = mesh.nodes();
        for (f, facet) in facets.iter().enumerate() {
            if let Some(&bad) = facet.iter().find(|&&i| i as usize >= nodes.len()) {
                return Err(BuildError::ChamberIndexOutOfRange {
                    chamber: index,
                    facet: f,
                    index: bad,
                    node_count: nodes.len(),
                });
            }
        }
        if let Some(f) = outside_cells(&facets, mesh) {
            return Err(BuildError::ChamberFacetOutsideCells {
                chamber: index,
                facet: f,
            });
        }
        if let Some(ridge) = open_ridge(&facets) {
            return Err(BuildError::OpenChamber {
                chamber: index,
                ridge,
            });
        }
        let mut chamber = Chamber {
            facets,
            pv: 0.0,
            v0: 0.0,
            ambient: gas.ambient,
        };
        let v0 = chamber.volume(nodes);
        if !(v0.is_finite() && v0 > 0.0) {
            return Err(BuildError::InvertedChamber {
                chamber: index,
                volume: v0,
            });
        }
        chamber.v0 = v0;
        chamber.pv = (gas.pressure + gas.ambient) * v0;
        Ok(chamber)
    }

    /// The enclosed volume at `x` (area in 2D).
    pub fn volume(&self, x: &[Vector]) -> Real {
        Mesh::enclosed_volume(&self.facets, x)
    }

    /// Pumps gas in or out so that at volume `v` its gauge pressure is `gas.pressure` against
    /// `gas.ambient`; the built volume (the energy's zero) stays.
    pub fn refill(&mut self, gas: Gas, v: Real) -> Result<(), BuildError> {
        gas.validate()?;
        let v = v.max(MIN_VOLUME * self.v0);
        self.pv = (gas.pressure + gas.ambient) * v;
        self.ambient = gas.ambient;
        Ok(())
    }

    /// The gauge pressure `P` and the curvature `U''` of the gas at volume `v`.
    pub fn law(&self, v: Real) -> (Real, Real) {
        let v = v.max(MIN_VOLUME * self.v0);
        (self.pv / v - self.ambient, self.pv / (v * v))
    }

    /// The energy the gas stores at volume `v` (zero at the built volume).
    pub fn energy(&self, v: Real) -> Real {
        let v = v.max(MIN_VOLUME * self.v0);
        self.pv * (self.v0 / v).ln() + self.ambient * (v - self.v0)
    }

    /// Whether the chamber's nodes are among `nodes` and its numbers in range (a restored
    /// snapshot's).
    #[cfg_attr(not(feature = "serde"), allow(dead_code))]
    pub fn fits(&self, mesh: &Mesh) -> bool {
        let finite = |v: Real| v.is_finite() && v > 0.0;
        let nodes = mesh.nodes().len();
        self.facets.iter().flatten().all(|&i| (i as usize) < nodes)
            && outside_cells(&self.facets, mesh).is_none()
            && finite(self.pv)
            && finite(self.v0)
            && self.ambient.is_finite()
            && self.ambient >= 0.0
            && open_ridge(&self.facets).is_none()
    }

    /// The built volume.
    pub fn built_volume(&self) -> Real {
        self.v0
    }
}

/// The sign that turns the simplex of a point and a facet, as [`math::simplex_gradients`]
/// measures it, into the measure under the facet's normal ([`math::facet_normal`], which
/// points out of a mesh's cells): the same in 3D; in 2D the normal is the edge turned to the
/// left, so a boundary runs clockwise and the simplex measures it negative.
const ORIENTATION: Real = if DIM == 3 { 1.0 } else { -1.0 };

/// `DIM!` times the signed measure of the simplex of `reference` and facet `p`, positive when
/// the facet faces away from `reference`.
fn measure(reference: Vector, p: [Vector; FACET_ARITY]) -> Real {
    let q: [Vector; SIMPLEX_ARITY] =
        std::array::from_fn(|k| if k == 0 { reference } else { p[k - 1] });
    ORIENTATION * math::simplex_gradients(&q).0
}

/// `DIM!` times the gradient of facet `p`'s measure with respect to its vertex `slot`, taken
/// from the vertex itself (in 3D the facet's area vector, twice its area long; in 2D its
/// normal, its length long): with the other vertices fixed, the sum over a node's facets of a
/// closed surface does not depend on the point the measures are taken from.
fn facet_gradient(p: [Vector; FACET_ARITY], slot: usize) -> Vector {
    let q: [Vector; SIMPLEX_ARITY] =
        std::array::from_fn(|k| if k == 0 { p[slot] } else { p[k - 1] });
    math::simplex_gradients(&q).1[slot + 1] * ORIENTATION
}

/// The first of `facets` whose nodes are not all nodes of one cell of `mesh`, if any (the
/// implicit step's slabs see a node's cell neighbours only). Every node index must be in range.
fn outside_cells(facets: &[[u32; FACET_ARITY]], mesh: &Mesh) -> Option<usize> {
    use std::collections::HashSet;
    let mut within: HashSet<[u32; FACET_ARITY]> = HashSet::new();
    for cell in mesh.cells() {
        // Every choice of FACET_ARITY of the cell's vertices, sorted.
        let n = cell.len();
        let mut pick = [0usize; FACET_ARITY];
        fn choose(
            cell: &[u32],
            from: usize,
            depth: usize,
            pick: &mut [usize; FACET_ARITY],
            out: &mut HashSet<[u32; FACET_ARITY]>,
        ) {
            if depth == FACET_ARITY {
                let mut key = pick.map(|k| cell[k]);
                key.sort_unstable();
                out.insert(key);
                return;
            }
            for k in from..cell.len() {
                pick[depth] = k;
                choose(cell, k + 1, depth + 1, pick, out);
            }
        }
        if n >= FACET_ARITY {
            choose(cell, 0, 0, &mut pick, &mut within);
        }
    }
    facets.iter().position(|f| {
        let mut key = *f;
        key.sort_unstable();
        !within.contains(&key)
    })
}

/// The first ridge of `facets` not met once each way, if any: an edge `(a, b)` in 3D whose
/// directed uses `a → b` and `b → a` differ in number, a node in 2D that starts and ends
/// different numbers of segments.
fn open_ridge(facets: &[[u32; FACET_ARITY]]) -> Option<Vec<u32>> {
    use std::collections::BTreeMap;
    let mut balance: BTreeMap<Vec<u32>, i64> = BTreeMap::new();
    for f in facets {
        for s in 0..FACET_ARITY {
            let (a, b) = (f[s], f[(s + 1) % FACET_ARITY]);
            if DIM == 3 {
                let (key, sign) = if a < b {
                    (vec![a, b], 1)
                } else {
                    (vec![b, a], -1)
                };
                *balance.entry(key).or_default() += sign;
            } else if s == 0 {
                *balance.entry(vec![a]).or_default() += 1;
                *balance.entry(vec![b]).or_default() -= 1;
            }
        }
    }
    balance.into_iter().find(|(_, n)| *n != 0).map(|(k, _)| k)
}

/// The chambers of a body, and which chamber facets touch each node.
#[derive(Clone, Debug)]
pub(crate) struct Chambers {
    chambers: Vec<Chamber>,
    /// Per node `i`, `touches[start[i]..start[i + 1]]`: `(chamber, facet, slot)`, by chamber.
    start: Vec<u32>,
    touches: Vec<(u32, u32, u8)>,
    /// The nodes that border a chamber, in order.
    nodes: Vec<u32>,
}

impl Chambers {
    /// The chambers of a body of `nodes` nodes.
    pub fn new(chambers: Vec<Chamber>, nodes: usize) -> Chambers {
        let mut lists: Vec<Vec<(u32, u32, u8)>> = vec![Vec::new(); nodes];
        for (c, chamber) in chambers.iter().enumerate() {
            for (f, facet) in chamber.facets.iter().enumerate() {
                for (slot, &i) in facet.iter().enumerate() {
                    lists[i as usize].push((c as u32, f as u32, slot as u8));
                }
            }
        }
        let mut start = Vec::with_capacity(nodes + 1);
        let mut touches = Vec::new();
        start.push(0);
        for list in lists {
            touches.extend(list);
            start.push(touches.len() as u32);
        }
        let nodes = (0..nodes as u32)
            .filter(|&i| start[i as usize] != start[i as usize + 1])
            .collect();
        Chambers {
            chambers,
            start,
            touches,
            nodes,
        }
    }

    /// The chambers.
    pub fn list(&self) -> &[Chamber] {
        &self.chambers
    }

    /// The chambers, to refill.
    pub fn list_mut(&mut self) -> &mut [Chamber] {
        &mut self.chambers
    }

    /// Each chamber's volume at `x`.
    pub fn volumes(&self, x: &[Vector]) -> Vec<Real> {
        self.chambers.iter().map(|c| c.volume(x)).collect()
    }

    /// The energy the gas stores at `x`.
    pub fn energy(&self, x: &[Vector]) -> Real {
        self.chambers.iter().map(|c| c.energy(c.volume(x))).sum()
    }

    /// Calls `each(chamber, g)` with `g = ∂V/∂x_i` for each chamber node `i` borders, the
    /// others' positions read through `at`.
    #[inline]
    pub fn gradients_at(
        &self,
        i: usize,
        at: impl Fn(usize) -> Vector,
        mut each: impl FnMut(usize, Vector),
    ) {
        let touches = &self.touches[self.start[i] as usize..self.start[i + 1] as usize];
        let mut k = 0;
        while k < touches.len() {
            let chamber = touches[k].0;
            let mut g = Vector::ZERO;
            while k < touches.len() && touches[k].0 == chamber {
                let (_, f, slot) = touches[k];
                let facet = &self.chambers[chamber as usize].facets[f as usize];
                g += facet_gradient(facet.map(|j| at(j as usize)), slot as usize);
                k += 1;
            }
            each(chamber as usize, g / DIM_FACTORIAL);
        }
    }

    /// Node `i`'s force `Σ P g_i` and block `Σ U'' g_i g_iᵀ` with the chambers at `volumes`.
    #[inline]
    pub fn node_terms(
        &self,
        i: usize,
        at: impl Fn(usize) -> Vector,
        volumes: &[Real],
    ) -> (Vector, Matrix) {
        let (mut f, mut block) = (Vector::ZERO, Matrix::ZERO);
        self.gradients_at(i, at, |c, g| {
            let (p, curvature) = self.chambers[c].law(volumes[c]);
            f += g * p;
            block += math::outer(g, g) * curvature;
        });
        (f, block)
    }

    /// Whether node `i` borders a chamber.
    #[inline]
    pub fn touches(&self, i: usize) -> bool {
        self.start[i] != self.start[i + 1]
    }

    /// Adds the gas's forces at `x` into `acc`, with their stiffness bounds: the rank-one part
    /// `U'' |g_i| Σ_j |g_j|`, and `|P|` times a bound on `∇²V`'s row (per 3D facet at `i`,
    /// `(|x_b − x_i| + |x_c − x_i|)/6`; per 2D segment, `1/2`).
    pub fn accumulate(&self, x: &[Vector], acc: &mut Accumulator) {
        let laws: Vec<(Real, Real)> = self.chambers.iter().map(|c| c.law(c.volume(x))).collect();
        let mut gradients = Vec::new();
        for &i in &self.nodes {
            self.gradients_at(i as usize, |j| x[j], |c, g| gradients.push((c, i, g)));
        }
        let mut total = vec![0.0; self.chambers.len()];
        for &(c, _, g) in &gradients {
            total[c] += g.length();
        }
        for &(c, i, g) in &gradients {
            let (p, curvature) = laws[c];
            acc.force[i as usize] += g * p;
            acc.stiffness[i as usize] += curvature * g.length() * total[c];
        }
        for (chamber, (p, _)) in self.chambers.iter().zip(laws) {
            for facet in &chamber.facets {
                for (slot, &i) in facet.iter().enumerate() {
                    let bound = if DIM == 3 {
                        let me = x[i as usize];
                        let (b, c) = (
                            facet[(slot + 1) % FACET_ARITY],
                            facet[(slot + 2) % FACET_ARITY],
                        );
                        ((x[b as usize] - me).length() + (x[c as usize] - me).length())
                            / DIM_FACTORIAL
                    } else {
                        0.5
                    };
                    acc.stiffness[i as usize] += p.abs() * bound;
                }
            }
        }
    }
}

impl Mesh {
    /// The chambers [`DeformableBuilder::gas`](super::super::DeformableBuilder::gas) seals
    /// its gas behind, each as facets facing out of the gas: each cavity of the mesh (a closed
    /// piece of its boundary enclosing negative volume as the mesh orients it), or, in a mesh
    /// with none, each piece's outer surface.
    pub fn chambers(&self) -> Vec<Vec<[u32; FACET_ARITY]>> {
        mesh_chambers(self.boundary_facets(), self.nodes())
    }

    /// The volume (area in 2D) that `facets`, a closed surface facing out, enclose with the
    /// nodes at `x`: [`Deformable::chambers`](super::super::Deformable::chambers)' measure.
    pub fn enclosed_volume(facets: &[[u32; FACET_ARITY]], x: &[Vector]) -> Real {
        let Some(first) = facets.first() else {
            return 0.0;
        };
        // Measured from a point on the surface, which keeps the sum's terms small.
        let reference = x[first[0] as usize];
        let sum: Real = facets
            .iter()
            .map(|f| measure(reference, f.map(|i| x[i as usize])))
            .sum();
        sum / DIM_FACTORIAL
    }
}

/// The boundary of a mesh split into closed pieces (facets sharing a node), each piece's facets
/// as the mesh orients them (out of the cells), with its signed volume.
fn boundary_pieces(
    facets: &[[u32; FACET_ARITY]],
    nodes: &[Vector],
) -> Vec<(Vec<[u32; FACET_ARITY]>, Real)> {
    let mut parent: Vec<usize> = (0..nodes.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for f in facets {
        for s in 1..FACET_ARITY {
            let (a, b) = (
                root(&mut parent, f[0] as usize),
                root(&mut parent, f[s] as usize),
            );
            if a != b {
                parent[a.max(b)] = a.min(b);
            }
        }
    }
    let mut pieces: Vec<(usize, Vec<[u32; FACET_ARITY]>)> = Vec::new();
    for f in facets {
        let r = root(&mut parent, f[0] as usize);
        match pieces.iter_mut().find(|(k, _)| *k == r) {
            Some((_, list)) => list.push(*f),
            None => pieces.push((r, vec![*f])),
        }
    }
    pieces
        .into_iter()
        .map(|(_, list)| {
            let v = Mesh::enclosed_volume(&list, nodes);
            (list, v)
        })
        .collect()
}

/// `facets` facing the other way (each with its first two nodes swapped).
fn flipped(facets: &[[u32; FACET_ARITY]]) -> Vec<[u32; FACET_ARITY]> {
    facets
        .iter()
        .map(|f| {
            let mut f = *f;
            f.swap(0, 1);
            f
        })
        .collect()
}

/// [`Mesh::chambers`] of a mesh's boundary `facets`.
fn mesh_chambers(facets: &[[u32; FACET_ARITY]], nodes: &[Vector]) -> Vec<Vec<[u32; FACET_ARITY]>> {
    let pieces = boundary_pieces(facets, nodes);
    let cavities: Vec<Vec<[u32; FACET_ARITY]>> = pieces
        .iter()
        .filter(|(_, v)| *v < 0.0)
        .map(|(list, _)| flipped(list))
        .collect();
    if cavities.is_empty() {
        pieces.into_iter().map(|(list, _)| list).collect()
    } else {
        cavities
    }
}

#[cfg(test)]
mod tests {
    use super::super::super::mesh::CellKind;
    use super::*;

    fn hollow() -> Mesh {
        Mesh::ball(0.1, 9, CellKind::Simplex)
            .unwrap()
            .retain_cells(|c| {
                let centre = c.iter().copied().sum::<Vector>() / c.len() as Real;
                centre.length() > 0.05
            })
            .unwrap()
    }

    fn chambers_of(mesh: &Mesh, gas: Gas) -> Chambers {
        let list = mesh
            .chambers()
            .into_iter()
            .enumerate()
            .map(|(k, f)| Chamber::new(k, f, gas, mesh).unwrap())
            .collect();
        Chambers::new(list, mesh.nodes().len())
    }

    #[test]
    fn a_hollow_balls_chamber_is_its_cavity() {
        let full = Mesh::ball(0.1, 9, CellKind::Simplex).unwrap();
        let mesh = hollow();
        let chambers = chambers_of(&mesh, Gas::gauge(1e3));
        assert_eq!(chambers.list().len(), 1);
        let cavity = full.total_volume() - mesh.total_volume();
        let v = chambers.list()[0].volume(mesh.nodes());
        assert!((v - cavity).abs() < 1e-4 * cavity, "{v} against {cavity}");
        // A solid ball holds the gas behind its outer surface.
        let solid = chambers_of(&full, Gas::gauge(1e3));
        let v = solid.list()[0].volume(full.nodes());
        assert!((v - full.total_volume()).abs() < 1e-4 * v);
    }

    #[test]
    fn the_force_is_minus_the_energys_gradient_and_the_block_its_own_curvature() {
        let mesh = hollow();
        let chambers = chambers_of(&mesh, Gas::gauge(3e4));
        // A squashed, sheared state, so that no symmetry hides an error.
        let x = super::super::squashed(mesh.nodes(), 0.8, 0.2);
        let mut acc = Accumulator::new(x.len());
        chambers.accumulate(&x, &mut acc);
        let total: Vector = acc.force.iter().copied().sum();
        let scale = acc.force.iter().map(|f| f.length()).fold(0.0, Real::max);
        assert!(total.length() < 1e-3 * scale, "the forces sum to {total}");
        let volumes = chambers.volumes(&x);
        let mut checked = 0;
        let every = if DIM == 3 { 7 } else { 2 };
        for i in (0..x.len()).filter(|&i| chambers.touches(i)).step_by(every) {
            let (f, block) = chambers.node_terms(i, |j| x[j], &volumes);
            assert!((f - acc.force[i]).length() <= 1e-4 * scale);
            for d in 0..DIM {
                let eps = 1e-4;
                let mut plus = x.clone();
                plus[i][d] += eps;
                let mut minus = x.clone();
                minus[i][d] -= eps;
                let fd = -(chambers.energy(&plus) - chambers.energy(&minus)) / (2.0 * eps);
                assert!(
                    (fd - f[d]).abs() < 2e-2 * scale,
                    "node {i} axis {d}: {} against {fd}",
                    f[d]
                );
                // The force's change along the axis is minus the block's column.
                let (fp, _) = chambers.node_terms(i, |j| plus[j], &chambers.volumes(&plus));
                let (fm, _) = chambers.node_terms(i, |j| minus[j], &chambers.volumes(&minus));
                let column = -(fp - fm) / (2.0 * eps);
                assert!(
                    (column - block.col(d)).length() < 2e-2 * block.col(d).length().max(1.0),
                    "node {i} axis {d}: block {} against {column}",
                    block.col(d)
                );
            }
            checked += 1;
        }
        assert!(checked > 5);
    }

    #[test]
    fn facets_that_do_not_close_or_face_into_the_gas_are_refused() {
        let mesh = hollow();
        let mut facets = mesh.chambers().remove(0);
        let gas = Gas::gauge(1e3);
        let removed = facets.pop().unwrap();
        let err = Chamber::new(0, facets.clone(), gas, &mesh).unwrap_err();
        assert!(
            matches!(err, BuildError::OpenChamber { chamber: 0, .. }),
            "{err}"
        );
        facets.push(removed);
        let inside_out = flipped(&facets);
        let err = Chamber::new(2, inside_out, gas, &mesh).unwrap_err();
        assert!(
            matches!(err, BuildError::InvertedChamber { chamber: 2, .. }),
            "{err}"
        );
        let mut far = facets.clone();
        far[0][0] = 1_000_000;
        let err = Chamber::new(1, far, gas, &mesh).unwrap_err();
        assert!(
            matches!(
                err,
                BuildError::ChamberIndexOutOfRange {
                    chamber: 1,
                    facet: 0,
                    ..
                }
            ),
            "{err}"
        );
        let err = Chamber::new(0, facets, Gas::gauge(-2e5), &mesh).unwrap_err();
        assert!(matches!(
            err,
            BuildError::InvalidParameter {
                name: "Gas::pressure",
                ..
            }
        ));
    }
}
