//! Several cells at once, one in each lane of a SIMD vector: the element kernels' arithmetic
//! on [`LANES`] cells for the price of one.
//!
//! Every operation is lanewise and rounds as its scalar form does (no fused multiply–add, no
//! horizontal sums), so a cell's result does not depend on the lane it is evaluated in nor on
//! the cells beside it: a run of cells cut anywhere (the threads' slabs) gives the same values.

use std::ops::{Add, AddAssign, Div, Mul, Neg, Sub};

use super::super::math::{Real, Vector, DIM, SIMPLEX_ARITY};

/// One value per lane.
pub(crate) type Lane = wide::f32x4;

/// Cells evaluated together.
pub(crate) const LANES: usize = 4;

/// `[f(0), f(1), …]`: [`std::array::from_fn`] in a loop the optimiser unrolls, so that the
/// kernels' many small arrays stay in registers (`from_fn` was left a call in some builds).
#[inline(always)]
pub(crate) fn each<T: Copy + Default, const N: usize>(mut f: impl FnMut(usize) -> T) -> [T; N] {
    let mut out = [T::default(); N];
    for (i, o) in out.iter_mut().enumerate() {
        *o = f(i);
    }
    out
}

/// A vector per lane, stored by component.
#[derive(Copy, Clone, Debug, Default)]
pub(crate) struct LaneVector(pub [Lane; DIM]);

impl LaneVector {
    pub const ZERO: LaneVector = LaneVector([Lane::ZERO; DIM]);

    /// Lane `l` holds `p(l)`.
    #[inline(always)]
    pub fn gather(p: impl Fn(usize) -> Vector) -> Self {
        let points: [Vector; LANES] = each(p);
        LaneVector(each(|d| Lane::new(each(|l| points[l][d]))))
    }

    /// The vector of each lane.
    #[inline(always)]
    pub fn lanes(self) -> [Vector; LANES] {
        let c: [[Real; LANES]; DIM] = each(|d| self.0[d].to_array());
        each(|l| {
            let mut v = Vector::ZERO;
            for d in 0..DIM {
                v[d] = c[d][l];
            }
            v
        })
    }

    #[inline(always)]
    pub fn dot(self, o: LaneVector) -> Lane {
        let mut s = self.0[0] * o.0[0];
        for d in 1..DIM {
            s += self.0[d] * o.0[d];
        }
        s
    }

    #[inline(always)]
    pub fn length_squared(self) -> Lane {
        self.dot(self)
    }

    /// Each lane's vector where `mask` is set, else zero.
    #[inline(always)]
    pub fn or_zero(self, mask: Lane) -> LaneVector {
        LaneVector(each(|d| mask.select(self.0[d], Lane::ZERO)))
    }
}

impl Add for LaneVector {
    type Output = LaneVector;
    #[inline(always)]
    fn add(self, o: LaneVector) -> LaneVector {
        LaneVector(each(|d| self.0[d] + o.0[d]))
    }
}

impl AddAssign for LaneVector {
    #[inline(always)]
    fn add_assign(&mut self, o: LaneVector) {
        *self = *self + o;
    }
}

impl Sub for LaneVector {
    type Output = LaneVector;
    #[inline(always)]
    fn sub(self, o: LaneVector) -> LaneVector {
        LaneVector(each(|d| self.0[d] - o.0[d]))
    }
}

impl Neg for LaneVector {
    type Output = LaneVector;
    #[inline(always)]
    fn neg(self) -> LaneVector {
        LaneVector(each(|d| -self.0[d]))
    }
}

impl Div<Lane> for LaneVector {
    type Output = LaneVector;
    #[inline(always)]
    fn div(self, s: Lane) -> LaneVector {
        LaneVector(each(|d| self.0[d] / s))
    }
}

impl Mul<Lane> for LaneVector {
    type Output = LaneVector;
    #[inline(always)]
    fn mul(self, s: Lane) -> LaneVector {
        LaneVector(each(|d| self.0[d] * s))
    }
}

/// [`math::simplex_gradients`](super::super::math::simplex_gradients) of each lane's cell: its
/// `D` and the gradients of `D` at its vertices, with the same operations.
#[inline(always)]
pub(crate) fn simplex_gradients(
    p: &[LaneVector; SIMPLEX_ARITY],
) -> (Lane, [LaneVector; SIMPLEX_ARITY]) {
    let e: [LaneVector; DIM] = each(|k| p[k + 1] - p[0]);
    // 3D: g₁ = e₂ × e₃, g₂ = e₃ × e₁, g₃ = e₁ × e₂; 2D: g₁ = −e₂⊥, g₂ = e₁⊥ (⊥: a quarter
    // turn to the left). The indices wrap at `DIM` so that both forms index within bounds.
    let cross = |a: LaneVector, b: LaneVector| {
        LaneVector(each(|d| {
            let (i, j) = ((d + 1) % DIM, (d + 2) % DIM);
            a.0[i] * b.0[j] - a.0[j] * b.0[i]
        }))
    };
    let perp = |a: LaneVector| LaneVector(each(|d| if d == 0 { -a.0[1 % DIM] } else { a.0[0] }));
    let g: [LaneVector; DIM] = each(|k| {
        if DIM == 3 {
            cross(e[(k + 1) % DIM], e[(k + 2) % DIM])
        } else if k == 0 {
            -perp(e[1 % DIM])
        } else {
            perp(e[0])
        }
    });
    let mut sum = g[0];
    for gk in &g[1..] {
        sum += *gk;
    }
    let d = e[0].dot(g[0]);
    (d, each(|a| if a == 0 { -sum } else { g[a - 1] }))
}

#[cfg(test)]
mod tests {
    use super::super::super::math;
    use super::*;

    #[test]
    fn each_lane_gets_its_cells_gradients_whatever_its_neighbours() {
        let cell = |s: Real| -> [Vector; SIMPLEX_ARITY] {
            std::array::from_fn(|a| {
                let mut p = Vector::splat(0.1 * s * a as Real);
                if a > 0 {
                    p[a - 1] += 1.0 + s;
                }
                p
            })
        };
        let cells: [[Vector; SIMPLEX_ARITY]; LANES] = std::array::from_fn(|l| cell(l as Real));
        let p: [LaneVector; SIMPLEX_ARITY] =
            std::array::from_fn(|a| LaneVector::gather(|l| cells[l][a]));
        let (d, g) = simplex_gradients(&p);
        let g: [[Vector; LANES]; SIMPLEX_ARITY] = g.map(|v| v.lanes());
        for (l, c) in cells.iter().enumerate() {
            let (d1, g1) = math::simplex_gradients(c);
            assert_eq!(d.to_array()[l], d1, "lane {l}");
            for a in 0..SIMPLEX_ARITY {
                assert_eq!(g[a][l], g1[a], "lane {l} vertex {a}");
            }
        }
    }
}
