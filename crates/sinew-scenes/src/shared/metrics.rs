//! Accuracy metrics, each a pure function of node states (issue 6). The scenes and the chart
//! command (`examples/chart.rs`) compute every error they plot with these.
//!
//! | metric | function | used by |
//! |---|---|---|
//! | trajectory error against a converged reference | [`trajectory_error`] | `fall` |
//! | shape error after crush and release | [`shape_error`] | `crush` |
//! | volume error under static load | [`volume_ratio`], [`uniaxial_volume_change`] | `crush` (hold) |
//! | spurious rotation | [`super::spurious_acceleration`] | `rotation-error` |
//! | a surface inside itself | [`self_interpenetration`] | `fold`, `limb` |

use super::super::lib::math::{self, Real, Vector, FACET_ARITY, SIMPLEX_ARITY};
use super::super::lib::mesh::{cell_volume, CellKind, Mesh};
use super::super::lib::rapier::geometry::{Aabb, BoundingVolume};
use super::super::lib::rapier::parry::partitioning::{Bvh, BvhBuildStrategy};
use super::super::lib::rapier::parry::query::PointQuery;

/// Root-mean-square distance between two trajectories sampled at the same instants, over
/// `size` (so 0.01 is 1 % of the body). Compares the common prefix when one is shorter (a run
/// stopped by an explosion); `NaN` when either is empty.
pub fn trajectory_error(samples: &[Vector], reference: &[Vector], size: Real) -> Real {
    let n = samples.len().min(reference.len());
    if n == 0 {
        return Real::NAN;
    }
    let sum: Real = samples
        .iter()
        .zip(reference)
        .map(|(a, b)| a.distance_squared(*b))
        .sum();
    (sum / n as Real).sqrt() / size
}

/// Largest node distance from the rest shape `rest` moved by the best rigid fit of `x`
/// (mass-weighted centroid, polar rotation of the mass-weighted covariance), over `size`.
/// Zero for any rigid motion of the rest shape.
pub fn shape_error(x: &[Vector], rest: &[Vector], masses: &[Real], size: Real) -> Real {
    let m: Real = masses.iter().sum();
    let centroid = |p: &[Vector]| p.iter().zip(masses).map(|(p, m)| *p * *m).sum::<Vector>() / m;
    let (c, c0) = (centroid(x), centroid(rest));
    let mut a = math::outer(Vector::ZERO, Vector::ZERO);
    for ((x, x0), m) in x.iter().zip(rest).zip(masses) {
        a += math::outer((*x - c) * *m, *x0 - c0);
    }
    let r = math::polar_rotation(a);
    x.iter()
        .zip(rest)
        .map(|(x, x0)| (*x - c - r * (*x0 - c0)).length())
        .fold(0.0, Real::max)
        / size
}

/// Current volume (area in 2D) of `mesh` at `x` over its rest volume.
pub fn volume_ratio(mesh: &Mesh, x: &[Vector]) -> Real {
    let rest = mesh.total_volume();
    let mut p = Vec::with_capacity(mesh.kind().arity());
    let mut now: Real = 0.0;
    for cell in mesh.cells() {
        p.clear();
        p.extend(cell.iter().map(|&i| x[i as usize]));
        now += cell_volume(mesh.kind(), &p);
    }
    now / rest
}

/// Linear elasticity's relative volume change `ΔV/V = −(1 − 2ν) σ / E` of a bar under a
/// uniaxial compressive stress `σ` (Pa; free to expand sideways).
pub fn uniaxial_volume_change(stress: Real, young_modulus: Real, poisson_ratio: Real) -> Real {
    -(1.0 - 2.0 * poisson_ratio) * stress / young_modulus
}

/// A simplex body at a state, for asking how deep points are inside it: BVHs over its cells
/// and over its boundary facets (parry's).
struct Solid<'m> {
    mesh: &'m Mesh,
    x: &'m [Vector],
    cells: Bvh,
    facets: Vec<[Vector; FACET_ARITY]>,
    surface: Bvh,
}

impl<'m> Solid<'m> {
    /// `None` for box cells. Facets farther than `reach` from a point are not looked at.
    fn new(mesh: &'m Mesh, x: &'m [Vector], reach: Real) -> Option<Self> {
        if mesh.kind() != CellKind::Simplex {
            return None;
        }
        let cell_boxes: Vec<Aabb> = mesh
            .cells()
            .map(|c| {
                let mut b = Aabb::new_invalid();
                c.iter().for_each(|&i| b.take_point(x[i as usize]));
                b
            })
            .collect();
        let facets: Vec<[Vector; FACET_ARITY]> = mesh
            .boundary_facets()
            .iter()
            .map(|f| std::array::from_fn(|a| x[f[a] as usize]))
            .collect();
        let facet_boxes: Vec<Aabb> = facets
            .iter()
            .map(|q| {
                let mut b = Aabb::new_invalid();
                q.iter().for_each(|p| b.take_point(*p));
                b.loosened(reach)
            })
            .collect();
        Some(Solid {
            mesh,
            x,
            cells: Bvh::from_leaves(BvhBuildStrategy::Binned, &cell_boxes),
            facets,
            surface: Bvh::from_leaves(BvhBuildStrategy::Binned, &facet_boxes),
        })
    }

    /// How deep `p` is inside the body, if it is strictly inside a cell (one `own` node is not
    /// a vertex of): its distance to the nearest boundary facet (not one `own` is on), the
    /// plane's distance where `p` is over the facet, else the nearest corner's.
    fn depth(&self, p: Vector, own: Option<u32>) -> Option<Real> {
        let point = Aabb::new(p, p);
        let mesh = self.mesh;
        let inside = self.cells.intersect_aabb(&point).any(|c| {
            let c = mesh.cell(c as usize);
            if own.is_some_and(|i| c.contains(&i)) {
                return false;
            }
            let q: [Vector; SIMPLEX_ARITY] = std::array::from_fn(|a| self.x[c[a] as usize]);
            let whole = math::simplex_volume(&q);
            whole > 0.0
                && (0..SIMPLEX_ARITY).all(|k| {
                    let mut r = q;
                    r[k] = p;
                    math::simplex_volume(&r) / whole > 1e-6
                })
        });
        if !inside {
            return None;
        }
        let facets = mesh.boundary_facets();
        let depth = self
            .surface
            .intersect_aabb(&point)
            .filter(|&f| !own.is_some_and(|i| facets[f as usize].contains(&i)))
            .map(|f| math::facet_shape(&self.facets[f as usize]).distance_to_local_point(p, true))
            .fold(Real::INFINITY, Real::min);
        Some(depth)
    }
}

/// How deep the surface of `mesh` at `x` lies inside itself: for each surface node strictly
/// inside a cell it is not a vertex of, its distance to the nearest boundary facet it is not
/// a vertex of (the plane's distance where the node is over the facet, else the nearest
/// corner's), counting only depths under `reach`; the deepest. Zero for any shape of a body
/// whose surface does not pass into itself, however folded (a node in a crease's valley,
/// under an overhanging lip, is outside every cell); a crease pressed shut without self
/// contact gives the depth its sides overlap by. Simplex meshes only (`NaN` for box cells).
pub fn self_interpenetration(mesh: &Mesh, x: &[Vector], reach: Real) -> Real {
    let Some(solid) = Solid::new(mesh, x, reach) else {
        return Real::NAN;
    };
    mesh.boundary_nodes()
        .iter()
        .filter_map(|&i| solid.depth(x[i as usize], Some(i)))
        .filter(|&d| d < reach)
        .fold(0.0, Real::max)
}

/// How deep the surface nodes of body `a` (mesh and state) are inside body `b`: for each one
/// strictly inside a cell of `b`, its distance to `b`'s nearest boundary facet; the deepest
/// (zero when none is inside). Simplex meshes only (`NaN` for box cells).
pub fn interpenetration(a: (&Mesh, &[Vector]), b: (&Mesh, &[Vector])) -> Real {
    let Some(solid) = Solid::new(b.0, b.1, Real::INFINITY) else {
        return Real::NAN;
    };
    let d =
        a.0.boundary_nodes()
            .iter()
            .filter_map(|&i| solid.depth(a.1[i as usize], None))
            .fold(0.0, Real::max);
    d
}
