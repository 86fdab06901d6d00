//! Local topology of box cells (quads in 2D, hexahedra in 3D) in VTK vertex order, written
//! once for any dimension through corner bit patterns: bit `d` of a corner says whether the
//! corner sits at the high end of axis `d`.

use super::super::math::DIM;

/// Number of corners of a box cell: `2^DIM`.
pub const CUBE_ARITY: usize = 1 << DIM;

/// Corner bit pattern of the VTK-ordered local vertex `n` (`0:(0,0,0) 1:(1,0,0) 2:(1,1,0)
/// 3:(0,1,0)`, then the same on top). The map is its own inverse.
#[inline]
pub const fn vtk_to_bits(n: usize) -> usize {
    let low = n & 3;
    (n & !3) | (low ^ (low >> 1))
}

/// VTK-ordered local vertex of a corner bit pattern.
#[inline]
pub const fn bits_to_vtk(b: usize) -> usize {
    vtk_to_bits(b)
}

/// All permutations of the `DIM` axes (2 in 2D, 6 in 3D), in a fixed order.
pub fn axis_permutations() -> Vec<[usize; DIM]> {
    fn rec(prefix: &mut Vec<usize>, out: &mut Vec<[usize; DIM]>) {
        if prefix.len() == DIM {
            let mut p = [0; DIM];
            p.copy_from_slice(prefix);
            out.push(p);
            return;
        }
        for a in 0..DIM {
            if !prefix.contains(&a) {
                prefix.push(a);
                rec(prefix, out);
                prefix.pop();
            }
        }
    }
    let mut out = Vec::new();
    rec(&mut Vec::new(), &mut out);
    out
}

/// The Kuhn (Freudenthal) split of a box into `DIM!` simplices: one per axis permutation,
/// walking from corner `0…0` to corner `1…1` one axis at a time. Returned as corner bit
/// patterns; neighbouring boxes split this way share their facet diagonals, so the result is
/// conforming. Orientation is not fixed here (it alternates with the permutation's parity).
pub fn kuhn_simplices() -> Vec<Vec<usize>> {
    axis_permutations()
        .into_iter()
        .map(|perm| {
            let mut b = 0usize;
            let mut s = vec![b];
            for a in perm {
                b |= 1 << a;
                s.push(b);
            }
            s
        })
        .collect()
}

/// The `2·DIM` faces of a box as lists of corner bit patterns, each face's corners in cyclic
/// order (2 corners in 2D, 4 in 3D).
pub fn faces() -> Vec<Vec<usize>> {
    let mut out = Vec::new();
    for axis in 0..DIM {
        let others: Vec<usize> = (0..DIM).filter(|&a| a != axis).collect();
        for side in 0..2 {
            let base = side << axis;
            let cyc: Vec<usize> = if others.len() == 1 {
                vec![0, 1 << others[0]]
            } else {
                let (a, b) = (1 << others[0], 1 << others[1]);
                vec![0, a, a | b, b]
            };
            out.push(cyc.into_iter().map(|c| c | base).collect());
        }
    }
    out
}
