//! Energy derivatives of the element terms, for an implicit integrator (issue 15).
//!
//! Backward Euler is the minimisation of the incremental potential `½/h² ‖x − y‖²_M + E(x)`
//! (`y` the inertial prediction); Vertex Block Descent (Chen, Liu, Yang, Yuksel 2024) minimises
//! it one vertex at a time, each a `DIM × DIM` Newton step that needs, per vertex `i`, the force
//! `−∂E/∂x_i` and the block `∂²E/∂x_i²` summed over the terms that touch `i`. This module gives
//! both for each kind of term, as pure functions, each block positive semi-definite so the
//! Newton step goes downhill:
//!
//! | term | energy | block for a vertex |
//! |---|---|---|
//! | linear spring (eq. 1) | `k/2 (L − L0)²` | `k n nᵀ + k (1 − L0/L)₊ (I − n nᵀ)` |
//! | nonlinear spring (eq. 4) | `k [(L² − L0²)/2 − L0² ln(L/L0)]` | `k (1 + L0²/L²) n nᵀ + k (1 − L0²/L²)₊ (I − n nᵀ)` |
//! | ER repulsion (eq. 5) | the nonlinear law in the height `h` | vertex: `U''(h) n nᵀ`; facet vertex `j`: `w_j² U''(h) n nᵀ` |
//! | shape-based cell | `k/2 Σ_i ‖r_i − R R0_i‖²`, `R` held | `k (1 − 1/N) I` |
//!
//! `(·)₊` is the projection: a compressed spring's transverse stiffness `U'(L)/L` is negative,
//! and is dropped. The repulsion's facet blocks are Gauss–Newton (`U''(h) ∇h ∇hᵀ`, with
//! `∇_j h = −w_j n`): they leave out `U'(h) ∂²h/∂x_j²`, which vanishes at the rest height. The
//! shape-based block holds the rotation fixed, as corotational methods do. The tests check
//! each gradient against finite differences of its energy, and each exact block against
//! finite differences of its gradient.

use super::super::math::{self, Matrix, Real, Vector, SIMPLEX_ARITY};

/// The block `U'' n nᵀ + max(U'/L, 0) (I − n nᵀ)` of a term whose energy `U(L)` depends on
/// the distance `L = |d|` between two nodes (`d = x_i − x_j`), for either node; zero when the
/// nodes coincide.
#[inline]
pub fn radial_block(d: Vector, du: Real, ddu: Real) -> Matrix {
    let l = d.length();
    if l <= Real::MIN_POSITIVE {
        return Matrix::ZERO;
    }
    let n = d / l;
    let nn = math::outer(n, n);
    let transverse = (du / l).max(0.0);
    nn * ddu.max(0.0) + (Matrix::IDENTITY - nn) * transverse
}

/// `U'(L)` and `U''(L)` of a linear spring `k/2 (L − L0)²`.
#[inline]
pub fn linear_spring(length: Real, rest_length: Real, k: Real) -> (Real, Real) {
    (k * (length - rest_length), k)
}

/// `U'(L)` and `U''(L)` of a nonlinear spring (eq. 4,
/// [`energy`](super::nonlinear_springs::energy)), evaluated where its force is (at
/// `max(L, 10⁻⁶ L0)`).
#[inline]
pub fn nonlinear_spring(length: Real, rest_length: Real, k: Real) -> (Real, Real) {
    let l = length.max(1e-6 * rest_length);
    let r = rest_length * rest_length / (l * l);
    (
        -super::nonlinear_springs::magnitude(length, rest_length, k),
        k * (1.0 + r),
    )
}

/// The blocks of an edge-repulsion term ([`repulsion`](super::edge_repulsion::repulsion)) for
/// its vertex `C` (first) and the vertices of the opposite facet (Gauss–Newton).
#[inline]
pub fn repulsion_blocks(r: &super::edge_repulsion::Repulsion) -> [Matrix; SIMPLEX_ARITY] {
    let nn = math::outer(r.normal, r.normal) * r.stiffness;
    std::array::from_fn(|a| {
        if a == 0 {
            nn
        } else {
            let w = r.weights[a - 1];
            nn * (w * w)
        }
    })
}

/// The block of a shape-based cell of `n` vertices and stiffness `k` (each vertex's
/// `r_i = x_i − centroid`), its rotation held: the same for every vertex.
#[inline]
pub fn shape_block(n: usize, k: Real) -> Matrix {
    Matrix::IDENTITY * (k * (1.0 - 1.0 / n as Real))
}

#[cfg(test)]
mod tests {
    use super::super::super::math::{Matrix, Real, Vector, DIM, FACET_ARITY, SIMPLEX_ARITY};
    use super::super::{edge_repulsion, nonlinear_springs};
    use super::*;

    /// Central differences of `f` at `x` along each axis.
    fn gradient(f: impl Fn(Vector) -> Real, x: Vector, eps: Real) -> Vector {
        let mut g = Vector::ZERO;
        for d in 0..DIM {
            let mut e = Vector::ZERO;
            e[d] = eps;
            g[d] = (f(x + e) - f(x - e)) / (2.0 * eps);
        }
        g
    }

    /// Central differences of the vector field `g` at `x`: column `d` is `∂g/∂x_d`.
    fn jacobian(g: impl Fn(Vector) -> Vector, x: Vector, eps: Real) -> Matrix {
        let mut m = Matrix::ZERO;
        for d in 0..DIM {
            let mut e = Vector::ZERO;
            e[d] = eps;
            let col = (g(x + e) - g(x - e)) / (2.0 * eps);
            *m.col_mut(d) = col;
        }
        m
    }

    fn max_diff(a: Matrix, b: Matrix) -> Real {
        (0..DIM)
            .flat_map(|c| (0..DIM).map(move |r| (c, r)))
            .map(|(c, r)| (a.col(c)[r] - b.col(c)[r]).abs())
            .fold(0.0, Real::max)
    }

    fn point(seed: u32) -> Vector {
        let f = |k: u32| ((seed * 7 + k * 13) % 17) as Real / 17.0 - 0.5;
        let mut p = Vector::ZERO;
        for d in 0..DIM {
            p[d] = f(d as u32);
        }
        p
    }

    #[test]
    fn spring_gradients_and_blocks_match_finite_differences() {
        let (l0, k) = (0.7, 3.0);
        let xj = point(1);
        // Stretched (every block exact) and compressed (the transverse part projected).
        for (scale, stretched) in [(1.6, true), (0.4, false)] {
            let dir = (point(2) - xj).normalize();
            let xi = xj + dir * (l0 * scale);
            for nonlinear in [false, true] {
                let energy = |x: Vector| {
                    let l = x.distance(xj);
                    if nonlinear {
                        nonlinear_springs::energy(l, l0, k)
                    } else {
                        0.5 * k * (l - l0) * (l - l0)
                    }
                };
                let derivs = |l: Real| {
                    if nonlinear {
                        nonlinear_spring(l, l0, k)
                    } else {
                        linear_spring(l, l0, k)
                    }
                };
                let grad = |x: Vector| {
                    let d = x - xj;
                    d / d.length() * derivs(d.length()).0
                };
                // `Real` may be f32: steps of 1 % keep rounding under the truncation error.
                let eps = 1e-2;
                let fd = gradient(energy, xi, eps);
                assert!(
                    (fd - grad(xi)).length() < 1e-2 * grad(xi).length().max(1.0),
                    "{fd} {}",
                    grad(xi)
                );
                let (du, ddu) = derivs(xi.distance(xj));
                let block = radial_block(xi - xj, du, ddu);
                let exact = jacobian(grad, xi, eps);
                if stretched {
                    assert!(max_diff(block, exact) < 1e-2 * k, "{block:?} {exact:?}");
                } else {
                    // The projected block keeps the axial part and is positive semi-definite.
                    let n = (xi - xj).normalize();
                    assert!((n.dot(block * n) - n.dot(exact * n)).abs() < 1e-2 * ddu);
                    let axis = if n.x.abs() < 0.9 {
                        Vector::X
                    } else {
                        Vector::Y
                    };
                    let t = (axis - n * n.dot(axis)).normalize();
                    let (bent, kept) = (t.dot(exact * t), t.dot(block * t));
                    assert!(bent < 0.0 && kept.abs() < 1e-5 * ddu, "{bent} {kept}");
                }
            }
        }
    }

    #[test]
    fn repulsion_blocks_match_finite_differences() {
        // A simplex at rest heights, one vertex moved along the facet normal so the barrier is
        // loaded: the vertex block is exact, the facet blocks are Gauss–Newton and exact where
        // U'(h) = 0 (at the rest height).
        let mut cell: [Vector; SIMPLEX_ARITY] = std::array::from_fn(|a| {
            let mut p = Vector::ZERO;
            if a > 0 {
                p[a - 1] = 1.0;
            }
            p
        });
        cell[0] += Vector::splat(0.05);
        let k = 2.0;
        let facet: [Vector; FACET_ARITY] = std::array::from_fn(|m| cell[m + 1]);
        let side = math::facet_normal(&facet).dot(cell[0] - facet[0]).signum();
        let rest = edge_repulsion::repulsion(cell[0], &facet, side, 1.0, k);
        let h0 = rest.height;
        let energy_of = |c: Vector, facet: &[Vector; FACET_ARITY]| {
            let r = edge_repulsion::repulsion(c, facet, side, h0, k);
            nonlinear_springs::energy(r.height, h0, k)
        };
        for push in [0.0, 0.3] {
            let c = cell[0] + rest.normal * (-push * h0);
            let r = edge_repulsion::repulsion(c, &facet, side, h0, k);
            let blocks = repulsion_blocks(&r);
            let eps = 1e-2;
            // The vertex: gradient is −force, block exact.
            let fd = gradient(|x| energy_of(x, &facet), c, eps);
            assert!(
                (fd + r.force).length() < 1e-2 * r.force.length().max(1.0),
                "{fd} {}",
                r.force
            );
            let grad_c = |x: Vector| -edge_repulsion::repulsion(x, &facet, side, h0, k).force;
            assert!(max_diff(blocks[0], jacobian(grad_c, c, eps)) < 1e-2 * r.stiffness);
            // A facet vertex: gradient is the reaction w_j · force.
            let j = 1;
            let moved = |x: Vector| {
                let mut f = facet;
                f[j] = x;
                f
            };
            let fd = gradient(|x| energy_of(c, &moved(x)), facet[j], eps);
            assert!((fd - r.force * r.weights[j]).length() < 1e-2 * r.force.length().max(1.0));
            if push == 0.0 {
                let grad_j = |x: Vector| {
                    let f = moved(x);
                    let r = edge_repulsion::repulsion(c, &f, side, h0, k);
                    let w = math::facet_barycentric(&f, c);
                    r.force * w[j]
                };
                let exact = jacobian(grad_j, facet[j], eps);
                assert!(
                    max_diff(blocks[j + 1], exact) < 1e-2 * r.stiffness,
                    "{:?} {exact:?}",
                    blocks[j + 1]
                );
            }
        }
    }

    #[test]
    fn the_shape_block_is_the_hessian_with_the_rotation_held() {
        // E = k/2 Σ |x_i − c − q_i|² (q_i = R R0_i fixed, c the centroid): ∂²E/∂x_0² is
        // k (1 − 1/N) I.
        let n = SIMPLEX_ARITY;
        let k = 5.0;
        let q: Vec<Vector> = (0..n).map(|a| point(a as u32 + 3)).collect();
        let x: Vec<Vector> = (0..n).map(|a| point(a as u32 + 9)).collect();
        // ∂E/∂x_0 = k [(r_0 − q_0) − (1/N) Σ_j (r_j − q_j)], with Σ_j r_j = 0.
        let grad = |x0: Vector| {
            let mut p = x.clone();
            p[0] = x0;
            let c = p.iter().copied().sum::<Vector>() / n as Real;
            let mean_q = q.iter().copied().sum::<Vector>() / n as Real;
            (p[0] - c - q[0] + mean_q) * k
        };
        let exact = jacobian(grad, x[0], 1e-2);
        assert!(max_diff(shape_block(n, k), exact) < 1e-2 * k);
    }
}
