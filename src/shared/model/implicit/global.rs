//! A Newton step over the whole body, before the sweeps (`docs/ARCHITECTURE.md` §4.2): the
//! incremental potential's Newton system `H Δ = f` over every free node at once, `H` the sum
//! of the same positive semi-definite term blocks the sweeps use ([`super::hessian`]) with
//! their couplings between nodes (shape-based cells: see [`ShapeCells`]), solved by conjugate
//! gradients with a two-level preconditioner — the nodes' own blocks, plus an exact solve in a
//! coarse space of node clusters moving affinely ([`Coarse`]) — then cut back (halving) until
//! every cell keeps the sweeps' line-search rule.
//!
//! Gauss–Seidel corrects a node against its neighbours, so a mode of the whole body much
//! softer than its cells (a slender beam's bending) converges by about
//! `1 − (m/h² + k_mode)/(m/h² + k_cell)` a sweep; the coarse space holds such modes.

use super::super::super::math::{self, AngVector, Matrix, Real, Vector, DIM, SIMPLEX_ARITY};
use super::hessian;
use super::{
    barrier, cell_geometry, cell_positions, cell_upright, height_ratio, invert, unit, Hold, Law,
    Solve, MIN_STEP_VOLUME,
};

/// An edge-repulsion term's Gauss–Newton Hessian `k (s ⊗ g)(s ⊗ g)ᵀ`: at each vertex `a` of
/// its cell, `∇_a h = s_a g / |g|`.
struct Repulsion {
    g: Vector,
    k: Real,
    shares: [Real; SIMPLEX_ARITY],
}

/// The incremental potential's Hessian at a state, kept as its terms for products.
struct Terms<'a> {
    inertia: Vec<Real>,
    /// Spring pairs and their blocks (`[B −B; −B B]`), dashpots included.
    springs: Vec<(usize, usize, Matrix)>,
    /// Simplex cells of the repulsions and the volumetric term.
    cells: &'a [u32],
    /// [`SIMPLEX_ARITY`] per cell (edge repulsion only).
    repulsions: Vec<Repulsion>,
    /// Per cell: `∇D` and the volumetric term's `κ V0 / D0²`.
    volumes: Vec<([Vector; SIMPLEX_ARITY], Real)>,
    /// Shape-based cells (see [`ShapeCells`]).
    shape: Option<ShapeCells<'a>>,
    /// Per gas chamber: `U''` and each of its nodes' `∂V/∂x` (the rank-one `U'' ∇V ∇Vᵀ`; the
    /// Newton step leaves out `U' ∇²V`, which is not definite).
    gas: Vec<(Real, Vec<(usize, Vector)>)>,
}

/// Shape-based cells for the Newton step: each cell's stiffness `k + c/h` on its vertices'
/// offsets from the centroid, less the cell's infinitesimal rotations. The sweeps hold each
/// cell's rotation over the step, which makes a turn of the cell cost like a strain; near its
/// fit the true energy `k/2 Σ |r_a − R(x) R0_a|²` does not resist a turn (the fit follows
/// it), so the Newton step takes `k (C − W (WᵀW)⁻¹ Wᵀ)`, `C` the centring and `W` the cell's
/// turns `ω × r_a` (a slender beam's bending is mostly its cells turning).
struct ShapeCells<'a> {
    cells: &'a [u32],
    arity: usize,
    k: Vec<Real>,
    /// Each vertex's offset from its cell's centroid, `arity` per cell.
    offsets: Vec<Vector>,
    /// `(WᵀW)⁻¹`'s columns, [`ANG_DIM`] per cell: the turn a unit moment about each axis gives.
    turns: Vec<AngVector>,
}

/// Unit angular vectors, one per axis of rotation.
fn turns() -> Vec<AngVector> {
    (0..ANG_DIM)
        .map(|d| {
            let mut c = [0.0; 3];
            c[d] = 1.0;
            math::ang_from_components(c)
        })
        .collect()
}

/// Axes of rotation.
const ANG_DIM: usize = math::TWIST_DIM - DIM;

/// Component `e` of an angular vector.
fn ang_component(w: AngVector, e: usize) -> Real {
    math::twist_to_array(Vector::ZERO, w)[DIM + e]
}

/// Unit masses for a cell's turn (its vertices weigh the same in the shape-based energy).
const ONES: [Real; 8] = [1.0; 8];

impl Terms<'_> {
    /// `out = H v`.
    fn product(&self, v: &[Vector], out: &mut [Vector]) {
        for (o, (v, m)) in out.iter_mut().zip(v.iter().zip(&self.inertia)) {
            *o = *v * *m;
        }
        for &(i, j, b) in &self.springs {
            let d = b * (v[i] - v[j]);
            out[i] += d;
            out[j] -= d;
        }
        let a = SIMPLEX_ARITY;
        for (c, ids) in self.cells.chunks_exact(a).enumerate() {
            for r in self.repulsions.get(c * a..(c + 1) * a).unwrap_or(&[]) {
                let t: Real = (0..a)
                    .map(|k| r.shares[k] * r.g.dot(v[ids[k] as usize]))
                    .sum();
                for k in 0..a {
                    out[ids[k] as usize] += r.g * (r.k * r.shares[k] * t);
                }
            }
            if let Some((g, k)) = self.volumes.get(c) {
                let t: Real = (0..a).map(|b| g[b].dot(v[ids[b] as usize])).sum();
                for b in 0..a {
                    out[ids[b] as usize] += g[b] * (k * t);
                }
            }
        }
        for (curvature, nodes) in &self.gas {
            let t: Real = nodes.iter().map(|(i, g)| g.dot(v[*i])).sum();
            for (i, g) in nodes {
                out[*i] += *g * (curvature * t);
            }
        }
        if let Some(shape) = &self.shape {
            let n = shape.arity;
            for (c, ids) in shape.cells.chunks_exact(n).enumerate() {
                let r = &shape.offsets[c * n..(c + 1) * n];
                let mean = ids.iter().map(|&i| v[i as usize]).sum::<Vector>() / n as Real;
                let moment = ids
                    .iter()
                    .zip(r)
                    .map(|(&i, r)| math::cross(*r, v[i as usize]))
                    .fold(math::ANG_ZERO, |s, m| s + m);
                let inverse = &shape.turns[c * ANG_DIM..(c + 1) * ANG_DIM];
                let turn = inverse
                    .iter()
                    .enumerate()
                    .fold(math::ANG_ZERO, |w, (d, col)| {
                        w + *col * ang_component(moment, d)
                    });
                for (&i, r) in ids.iter().zip(r) {
                    let u = v[i as usize] - mean - math::ang_cross(turn, *r);
                    out[i as usize] += u * shape.k[c];
                }
            }
        }
    }
}

fn dot(a: &[Vector], b: &[Vector]) -> Real {
    a.iter().zip(b).map(|(a, b)| a.dot(*b)).sum()
}

/// Coarse unknowns per cluster: a translation and a linear map (`u = t + L x̃`).
const COARSE: usize = DIM + DIM * DIM;

/// Nodes per cluster of the coarse space, about.
const CLUSTER_NODES: usize = 50;

/// Most clusters.
const MAX_CLUSTERS: usize = 32;

/// A node's coarse row for a direction `g`: `Pᵢᵀ g` over its cluster's unknowns.
fn coarse_row(g: Vector, offset: Vector) -> [f64; COARSE] {
    let mut row = [0.0; COARSE];
    for r in 0..DIM {
        row[r] = g[r] as f64;
        for c in 0..DIM {
            row[DIM + r * DIM + c] = (g[r] * offset[c]) as f64;
        }
    }
    row
}

/// Most clusters a term's nodes fall in.
const TERM_CLUSTERS: usize = 8;

/// A coarse vector touching a few clusters (at most [`TERM_CLUSTERS`]: a term's nodes).
#[derive(Clone)]
struct Sparse {
    len: usize,
    parts: [(usize, [f64; COARSE]); TERM_CLUSTERS],
}

impl Sparse {
    fn new() -> Self {
        Sparse {
            len: 0,
            parts: [(0, [0.0; COARSE]); TERM_CLUSTERS],
        }
    }

    fn clear(&mut self) {
        self.len = 0;
    }

    fn parts(&self) -> &[(usize, [f64; COARSE])] {
        &self.parts[..self.len]
    }

    /// Adds `scale · other`.
    fn add_scaled(&mut self, other: &Sparse, scale: f64) {
        for &(cluster, row) in other.parts() {
            self.add(cluster, row, scale);
        }
    }

    fn add(&mut self, cluster: usize, row: [f64; COARSE], scale: f64) {
        debug_assert!(self.len < TERM_CLUSTERS || self.parts().iter().any(|p| p.0 == cluster));
        if let Some((_, r)) = self.parts[..self.len]
            .iter_mut()
            .find(|(c, _)| *c == cluster)
        {
            r.iter_mut().zip(row).for_each(|(a, b)| *a += b * scale);
        } else if self.len < TERM_CLUSTERS {
            self.parts[self.len] = (cluster, row.map(|b| b * scale));
            self.len += 1;
        }
    }
}

/// The body's nodes grouped by a grid over their positions, each group moving affinely: the
/// coarse space in which a body's soft modes (bending, twisting, its motion as a whole) live.
struct Coarse {
    cluster: Vec<usize>,
    offset: Vec<Vector>,
    clusters: usize,
    /// The coarse operator, row-major; symmetric, so only its lower triangle (column ≤ row)
    /// is assembled: the factor reads no other entry, and every `add_*` skips the rest.
    matrix: Vec<f64>,
    factor: Option<Vec<f64>>,
    /// Per row of the matrix, its first non-zero column: the factor's rows start there too
    /// (a cluster couples only its neighbours; how much of each row this skips depends on how
    /// close neighbouring clusters' numbers are, which follow the nodes' order).
    first: Vec<usize>,
}

impl Coarse {
    fn new(x: &[Vector], free: &[bool]) -> Self {
        let n = x.len();
        let (mut lo, mut hi) = (x[0], x[0]);
        for p in x {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        let extent = (hi - lo).max(Vector::splat(1e-9));
        let target = (n / CLUSTER_NODES).clamp(1, MAX_CLUSTERS);
        let volume: Real = (0..DIM).map(|d| extent[d]).product();
        let mut size = (volume / target as Real).powf(1.0 / DIM as Real);
        let mut cluster = vec![0; n];
        let mut clusters;
        loop {
            let cells: Vec<usize> = (0..DIM)
                .map(|d| ((extent[d] / size).ceil() as usize).max(1))
                .collect();
            let mut ids = std::collections::HashMap::new();
            for (i, p) in x.iter().enumerate() {
                let mut key = 0;
                for d in (0..DIM).rev() {
                    let k = (((p[d] - lo[d]) / size) as usize).min(cells[d] - 1);
                    key = key * cells[d] + k;
                }
                let next = ids.len();
                cluster[i] = *ids.entry(key).or_insert(next);
            }
            clusters = ids.len();
            if clusters <= MAX_CLUSTERS {
                break;
            }
            size *= 1.25;
        }
        let mut centre = vec![Vector::ZERO; clusters];
        let mut count = vec![0.0; clusters];
        for i in 0..n {
            centre[cluster[i]] += x[i];
            count[cluster[i]] += 1.0;
        }
        for (c, k) in centre.iter_mut().zip(&count) {
            *c /= (*k as Real).max(1.0);
        }
        let offset = (0..n)
            .map(|i| {
                if free[i] {
                    x[i] - centre[cluster[i]]
                } else {
                    Vector::ZERO
                }
            })
            .collect();
        let size = clusters * COARSE;
        Coarse {
            cluster,
            offset,
            clusters,
            matrix: vec![0.0; size * size],
            factor: None,
            first: Vec::new(),
        }
    }

    fn size(&self) -> usize {
        self.clusters * COARSE
    }

    /// Adds `scale · u uᵀ` (its lower triangle, as every `add_*`).
    fn add_outer(&mut self, u: &Sparse, scale: f64) {
        let size = self.size();
        for (ca, ra) in u.parts() {
            for (cb, rb) in u.parts() {
                if ca < cb {
                    continue;
                }
                for (a, va) in ra.iter().enumerate() {
                    let row = (ca * COARSE + a) * size + cb * COARSE;
                    let s = va * scale;
                    let columns = if ca == cb { a + 1 } else { COARSE };
                    for (b, vb) in rb[..columns].iter().enumerate() {
                        self.matrix[row + b] += s * vb;
                    }
                }
            }
        }
    }

    /// Adds `Pᵢᵀ B Pⱼ` for free nodes `i`, `j`: with `Pᵢ = [I, I ⊗ oᵢᵀ]` (a translation, then
    /// the linear map's rows), its blocks are `B`, `B ⊗ oⱼᵀ`, `B ⊗ oᵢ` and `B ⊗ oᵢ oⱼᵀ`.
    fn add_block(&mut self, (i, j): (usize, usize), b: Matrix) {
        let (ci, cj) = (self.cluster[i], self.cluster[j]);
        if ci < cj {
            return;
        }
        let size = self.size();
        let (oi, oj) = (self.offset[i], self.offset[j]);
        let (row0, col0) = (ci * COARSE, cj * COARSE);
        let m = &mut self.matrix;
        // Within one cluster's diagonal block, its lower triangle only.
        let mut put = |row: usize, col: usize, v: f64| {
            if ci != cj || col <= row {
                m[(row0 + row) * size + col0 + col] += v;
            }
        };
        for r in 0..DIM {
            for s in 0..DIM {
                let brs = b.col(s)[r] as f64;
                if brs == 0.0 {
                    continue;
                }
                put(r, s, brs);
                for c in 0..DIM {
                    let (ic, jc) = (oi[c] as f64, oj[c] as f64);
                    put(r, DIM + s * DIM + c, brs * jc);
                    put(DIM + r * DIM + c, s, brs * ic);
                    for d in 0..DIM {
                        put(
                            DIM + r * DIM + c,
                            DIM + s * DIM + d,
                            brs * ic * oj[d] as f64,
                        );
                    }
                }
            }
        }
    }

    /// Adds `(Pᵢ − Pⱼ)ᵀ B (Pᵢ − Pⱼ)` for two free nodes of one cluster, `δ = oᵢ − oⱼ`: the
    /// translations cancel, leaving `B ⊗ δ δᵀ` on the linear map.
    fn add_linear(&mut self, (i, j): (usize, usize), b: Matrix) {
        let size = self.size();
        let base = self.cluster[i] * COARSE + DIM;
        let delta: [f64; DIM] =
            std::array::from_fn(|c| self.offset[i][c] as f64 - self.offset[j][c] as f64);
        let m = &mut self.matrix;
        for r in 0..DIM {
            for s in 0..DIM {
                let brs = b.col(s)[r] as f64;
                if brs == 0.0 {
                    continue;
                }
                for c in 0..DIM {
                    let row = (base + r * DIM + c) * size + base + s * DIM;
                    let bc = brs * delta[c];
                    for d in 0..DIM {
                        if s * DIM + d <= r * DIM + c {
                            m[row + d] += bc * delta[d];
                        }
                    }
                }
            }
        }
    }

    /// `Pᵀ g` of node `i` (nothing for a held node).
    fn row(&self, i: usize, g: Vector, free: &[bool], scale: Real, into: &mut Sparse) {
        if free[i] {
            into.add(self.cluster[i], coarse_row(g, self.offset[i]), scale as f64);
        }
    }

    /// Factors the matrix (Cholesky, with a small ridge for unknowns no free node moves).
    /// Each row's entries before its first non-zero stay zero in the factor, so the sums skip
    /// them: the same factor, at the cost of the matrix's envelope rather than its size cubed.
    fn factor(&mut self) {
        let size = self.size();
        let mut a = self.matrix.clone();
        let ridge = (0..size).map(|i| a[i * size + i]).fold(0.0, f64::max) * 1e-9;
        for i in 0..size {
            a[i * size + i] += ridge.max(1e-300);
        }
        self.first = (0..size)
            .map(|i| (0..i).find(|&k| a[i * size + k] != 0.0).unwrap_or(i))
            .collect();
        let first = &self.first;
        for j in 0..size {
            let row_j = j * size;
            let lj = &a[row_j + first[j]..row_j + j];
            let d = a[row_j + j] - dot64(lj, lj);
            if d.is_nan() || d <= 0.0 {
                self.factor = None;
                return;
            }
            let d = d.sqrt();
            a[row_j + j] = d;
            for i in j + 1..size {
                if first[i] > j {
                    continue;
                }
                let row_i = i * size;
                let from = first[i].max(first[j]);
                let s =
                    a[row_i + j] - dot64(&a[row_i + from..row_i + j], &a[row_j + from..row_j + j]);
                a[row_i + j] = s / d;
            }
        }
        self.factor = Some(a);
    }

    /// `b ← A_c⁻¹ b` by the factor `l` ([`Self::factor`]).
    fn solve(&self, l: &[f64], b: &mut [f64]) {
        let size = self.size();
        let first = &self.first;
        for i in 0..size {
            let s = b[i] - dot64(&l[i * size + first[i]..i * size + i], &b[first[i]..i]);
            b[i] = s / l[i * size + i];
        }
        // `Lᵀ`, by columns of `L`'s rows: once `b[i]` is known, it leaves the rows above.
        for i in (0..size).rev() {
            b[i] /= l[i * size + i];
            let bi = b[i];
            for k in first[i]..i {
                b[k] -= l[i * size + k] * bi;
            }
        }
    }

    /// `out += P A_c⁻¹ Pᵀ r`.
    fn correct(&self, r: &[Vector], free: &[bool], out: &mut [Vector]) {
        let Some(l) = &self.factor else {
            return;
        };
        let size = self.size();
        let mut b = vec![0.0f64; size];
        for (i, ri) in r.iter().enumerate() {
            if free[i] {
                let row = coarse_row(*ri, self.offset[i]);
                let base = self.cluster[i] * COARSE;
                for (k, v) in row.iter().enumerate() {
                    b[base + k] += v;
                }
            }
        }
        self.solve(l, &mut b);
        for (i, o) in out.iter_mut().enumerate() {
            if free[i] {
                let base = self.cluster[i] * COARSE;
                let off = self.offset[i];
                let mut u = Vector::ZERO;
                for r in 0..DIM {
                    let mut v = b[base + r];
                    for c in 0..DIM {
                        v += b[base + DIM + r * DIM + c] * off[c] as f64;
                    }
                    u[r] = v as Real;
                }
                *o += u;
            }
        }
    }
}

impl Terms<'_> {
    /// The coarse operator `Pᵀ H P` of these terms.
    fn coarse(&self, coarse: &mut Coarse, free: &[bool]) {
        let mut u = Sparse::new();
        for (i, m) in self.inertia.iter().enumerate() {
            if free[i] {
                coarse.add_block((i, i), Matrix::IDENTITY * *m);
            }
        }
        for &(i, j, b) in &self.springs {
            // `(Pᵢ − Pⱼ)ᵀ B (Pᵢ − Pⱼ)`, a held node's `P` zero.
            match (free[i], free[j]) {
                (true, true) if coarse.cluster[i] == coarse.cluster[j] => {
                    coarse.add_linear((i, j), b);
                }
                (true, true) => {
                    coarse.add_block((i, i), b);
                    coarse.add_block((j, j), b);
                    coarse.add_block((i, j), -b);
                    coarse.add_block((j, i), -b);
                }
                (true, false) => coarse.add_block((i, i), b),
                (false, true) => coarse.add_block((j, j), b),
                (false, false) => {}
            }
        }
        let a = SIMPLEX_ARITY;
        for (c, ids) in self.cells.chunks_exact(a).enumerate() {
            for r in self.repulsions.get(c * a..(c + 1) * a).unwrap_or(&[]) {
                u.clear();
                for (&i, &share) in ids.iter().zip(&r.shares) {
                    coarse.row(i as usize, r.g, free, share, &mut u);
                }
                coarse.add_outer(&u, r.k as f64);
            }
            if let Some((g, k)) = self.volumes.get(c) {
                u.clear();
                for b in 0..a {
                    coarse.row(ids[b] as usize, g[b], free, 1.0, &mut u);
                }
                coarse.add_outer(&u, *k as f64);
            }
        }
        if let Some(shape) = &self.shape {
            let n = shape.arity;
            let axes = turns();
            let mut modes: Vec<Sparse> = vec![Sparse::new(); ANG_DIM];
            for (c, ids) in shape.cells.chunks_exact(n).enumerate() {
                let k = shape.k[c] as f64;
                let r = &shape.offsets[c * n..(c + 1) * n];
                // The centring `Σ_a P_aᵀ P_a − (Σ_a P_a)ᵀ (Σ_a P_a) / n`, axis by axis.
                for &i in ids {
                    if free[i as usize] {
                        coarse.add_block((i as usize, i as usize), Matrix::IDENTITY * k as Real);
                    }
                }
                for d in 0..DIM {
                    let mut sum = Sparse::new();
                    for &i in ids {
                        coarse.row(i as usize, unit(d), free, 1.0, &mut sum);
                    }
                    coarse.add_outer(&sum, -k / n as f64);
                }
                for (mode, axis) in modes.iter_mut().zip(&axes) {
                    mode.clear();
                    for (&i, r) in ids.iter().zip(r) {
                        coarse.row(i as usize, math::ang_cross(*axis, *r), free, 1.0, mode);
                    }
                }
                // `−k Σ_de M_de mode_d mode_eᵀ` as `−k Σ_d mode_d (Σ_e M_de mode_e)ᵀ`.
                for d in 0..ANG_DIM {
                    let inverse = shape.turns[c * ANG_DIM + d];
                    let mut mixed = Sparse::new();
                    for (e, mode) in modes.iter().enumerate() {
                        let m = ang_component(inverse, e) as f64;
                        if m != 0.0 && m.is_finite() {
                            mixed.add_scaled(mode, -k * m);
                        }
                    }
                    add_cross(coarse, &modes[d], &mixed, 1.0);
                }
            }
        }
    }
}

/// `Σ a_k b_k` in four running sums (so that it vectorises).
fn dot64(a: &[f64], b: &[f64]) -> f64 {
    let mut sums = [0.0f64; 4];
    let (a4, b4) = (a.chunks_exact(4), b.chunks_exact(4));
    let tail: f64 = a4
        .remainder()
        .iter()
        .zip(b4.remainder())
        .map(|(x, y)| x * y)
        .sum();
    for (x, y) in a4.zip(b4) {
        for k in 0..4 {
            sums[k] += x[k] * y[k];
        }
    }
    (sums[0] + sums[1]) + (sums[2] + sums[3]) + tail
}

/// Adds `scale · u wᵀ` (its lower triangle, as every `add_*`).
fn add_cross(coarse: &mut Coarse, u: &Sparse, w: &Sparse, scale: f64) {
    let size = coarse.size();
    for (ca, ra) in u.parts() {
        for (cb, rb) in w.parts() {
            if ca < cb {
                continue;
            }
            for (a, va) in ra.iter().enumerate() {
                let row = (ca * COARSE + a) * size + cb * COARSE;
                let columns = if ca == cb { a + 1 } else { COARSE };
                for (b, vb) in rb[..columns].iter().enumerate() {
                    coarse.matrix[row + b] += scale * va * vb;
                }
            }
        }
    }
}

impl Solve<'_> {
    /// The Hessian's terms at `x`.
    fn terms(&self, x: &[Vector]) -> Terms<'_> {
        let vertex = &self.vertex;
        let h = self.h;
        let inertia = self.masses.iter().map(|m| m / (h * h)).collect();
        let mut springs = Vec::new();
        if let Some(s) = vertex.springs {
            for (k, &[a, b]) in s.pairs.iter().enumerate() {
                let (i, j) = (a as usize, b as usize);
                let d = x[i] - x[j];
                let l = d.length();
                if l <= Real::MIN_POSITIVE {
                    continue;
                }
                let (du, ddu) = match s.law {
                    Law::Linear => hessian::linear_spring(l, s.rest[k], s.k[k]),
                    Law::Nonlinear => hessian::nonlinear_spring(l, s.rest[k], s.k[k]),
                };
                let n = d / l;
                let block = hessian::radial_block(d, du, ddu) + math::outer(n, n) * (s.c[k] / h);
                springs.push((i, j, block));
            }
        }
        let mut cells: &[u32] = &[];
        let mut repulsions = Vec::new();
        let mut volumes = Vec::new();
        if let Some(er) = vertex.er {
            cells = &er.cells;
            for cell in 0..er.cells.len() / SIMPLEX_ARITY {
                let (d, g) = cell_geometry(er, cell, &cell_positions(er, cell, x));
                for (b, gb) in g.iter().enumerate() {
                    let g2 = gb.length_squared();
                    if g2 <= Real::MIN_POSITIVE {
                        repulsions.push(Repulsion {
                            g: Vector::ZERO,
                            k: 0.0,
                            shares: [0.0; SIMPLEX_ARITY],
                        });
                        continue;
                    }
                    let slot = cell * SIMPLEX_ARITY + b;
                    let (h0, k) = (er.h0[slot], er.k[slot]);
                    let height = d / g2.sqrt();
                    let (_, stiffness) = barrier(height, h0, k);
                    let shares =
                        std::array::from_fn(|a| if a == b { 1.0 } else { g[a].dot(*gb) / g2 });
                    repulsions.push(Repulsion {
                        g: *gb,
                        k: stiffness / g2,
                        shares,
                    });
                }
                if let Some(volume) = vertex.volume {
                    volumes.push((g, volume.hessian_scale(cell)));
                }
            }
        } else if let Some(volume) = vertex.volume {
            cells = volume.cells();
            for (cell, ids) in cells.chunks_exact(SIMPLEX_ARITY).enumerate() {
                let p: [Vector; SIMPLEX_ARITY] = std::array::from_fn(|a| x[ids[a] as usize]);
                let (_, g) = math::simplex_gradients(&p);
                volumes.push((g, volume.hessian_scale(cell)));
            }
        }
        let shape = vertex.shape.as_ref().map(|s| {
            let n = s.cells.arity();
            let cells = s.cells.cell_indices();
            let k = (0..cells.len() / n)
                .map(|c| {
                    let (k, c) = s.cells.law(c);
                    k + c / h
                })
                .collect();
            let mut offsets = Vec::with_capacity(cells.len());
            let mut turns = Vec::with_capacity(cells.len() / n * ANG_DIM);
            let axes = self::turns();
            for ids in cells.chunks_exact(n) {
                let centre = ids.iter().map(|&i| x[i as usize]).sum::<Vector>() / n as Real;
                let start = offsets.len();
                offsets.extend(ids.iter().map(|&i| x[i as usize] - centre));
                let r = &offsets[start..];
                turns.extend(axes.iter().map(|a| {
                    let w = math::angular_velocity_for(r, &ONES[..n], *a);
                    if math::ang_norm(w).is_finite() {
                        w
                    } else {
                        math::ANG_ZERO
                    }
                }));
            }
            ShapeCells {
                cells,
                arity: n,
                k,
                offsets,
                turns,
            }
        });
        let mut gas = Vec::new();
        if let Some(chambers) = vertex.gas {
            let list = chambers.list();
            let mut nodes = vec![Vec::new(); list.len()];
            for i in (0..x.len()).filter(|&i| chambers.touches(i)) {
                chambers.gradients_at(i, |j| x[j], |c, g| nodes[c].push((i, g)));
            }
            for (chamber, nodes) in list.iter().zip(nodes) {
                gas.push((chamber.law(chamber.volume(x)).1, nodes));
            }
        }
        Terms {
            inertia,
            springs,
            cells,
            repulsions,
            volumes,
            shape,
            gas,
        }
    }

    /// Whether every edge-repulsion cell (shape-based simplex cell) upright at `from` is
    /// upright at `to`, and none flatter than that ends flatter (the sweeps' line-search
    /// rule).
    fn keeps_cells(&self, from: &[Vector], to: &[Vector]) -> bool {
        let vertex = &self.vertex;
        if let Some(s) = &vertex.shape {
            if s.cells.arity() != SIMPLEX_ARITY {
                return true;
            }
            let cells = s.cells.cell_indices().len() / SIMPLEX_ARITY;
            return (0..cells).all(|c| {
                let (before, after) = (s.cells.volume_ratio(c, from), s.cells.volume_ratio(c, to));
                if before > MIN_STEP_VOLUME {
                    after > MIN_STEP_VOLUME
                } else {
                    after >= before
                }
            });
        }
        let Some(er) = vertex.er else {
            return true;
        };
        (0..er.cells.len() / SIMPLEX_ARITY).all(|c| {
            let (from, to) = (cell_positions(er, c, from), cell_positions(er, c, to));
            if cell_upright(er, c, &from) {
                cell_upright(er, c, &to)
            } else {
                height_ratio(er, c, &to) >= height_ratio(er, c, &from)
            }
        })
    }

    /// One Newton step of the free nodes together from `x`, its linear system solved by at
    /// most `iterations` preconditioned conjugate-gradient iterations (see the module docs).
    /// Held nodes stay where they are.
    pub fn global_step(&self, x: &mut [Vector], iterations: usize) {
        let n = x.len();
        if n == 0 {
            return;
        }
        let h2 = self.h * self.h;
        let free: Vec<bool> = self.held.iter().map(|h| *h == Hold::Free).collect();
        let mut r = vec![Vector::ZERO; n];
        let mut pre = vec![Matrix::ZERO; n];
        let volumes = self.gas_volumes(x);
        for i in 0..n {
            if free[i] {
                let inertia = self.masses[i] / h2;
                let (f, block, _) = self.vertex.newton(i, x, inertia, self.y[i], &volumes);
                r[i] = f;
                pre[i] = invert(block).unwrap_or(Matrix::ZERO);
            }
        }
        let terms = self.terms(x);
        let mut coarse = Coarse::new(x, &free);
        terms.coarse(&mut coarse, &free);
        coarse.factor();
        let precondition = |r: &[Vector], z: &mut Vec<Vector>| {
            z.clear();
            z.extend(r.iter().zip(&pre).map(|(r, p)| *p * *r));
            coarse.correct(r, &free, z);
        };
        let mut z = Vec::with_capacity(n);
        precondition(&r, &mut z);
        let mut p = z.clone();
        let mut rz = dot(&r, &z);
        let start = rz;
        let mut step = vec![Vector::ZERO; n];
        let mut hp = vec![Vector::ZERO; n];
        for _ in 0..iterations {
            if rz.is_nan() || rz <= 1e-12 * start {
                break;
            }
            terms.product(&p, &mut hp);
            for i in 0..n {
                if !free[i] {
                    hp[i] = Vector::ZERO;
                }
            }
            let php = dot(&p, &hp);
            if php.is_nan() || php <= 0.0 {
                break;
            }
            let alpha = rz / php;
            for i in 0..n {
                step[i] += p[i] * alpha;
                r[i] -= hp[i] * alpha;
            }
            precondition(&r, &mut z);
            let next = dot(&r, &z);
            let beta = next / rz;
            rz = next;
            for i in 0..n {
                p[i] = z[i] + p[i] * beta;
            }
        }
        let mut trial = x.to_vec();
        let mut fraction = 1.0;
        for _ in 0..=10 {
            for i in 0..n {
                trial[i] = x[i] + step[i] * fraction;
            }
            if trial.iter().all(|t| t.is_finite()) && self.keeps_cells(x, &trial) {
                x.copy_from_slice(&trial);
                return;
            }
            fraction *= 0.5;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::super::super::body::DeformableBuilder;
    use super::super::super::super::mesh::CellKind;
    use super::super::super::ElementModel;
    use super::super::StepInput;
    use super::*;

    #[test]
    fn the_envelope_factor_solves_the_system() {
        // A symmetric positive definite matrix whose rows start at different columns (a
        // banded part and a few far couplings, as clusters numbered out of order give): the
        // factor's solve must give `x` with `A x = b` (to the factor's ridge, 10⁻⁹ of the
        // largest diagonal entry).
        let nodes: Vec<Vector> = (0..12).map(|i| Vector::splat(i as Real)).collect();
        let mut coarse = Coarse::new(&nodes, &[true; 12]);
        let size = coarse.size();
        let mut a = vec![0.0f64; size * size];
        for i in 0..size {
            a[i * size + i] = 4.0 + (i % 3) as f64;
            for (j, v) in [(i + 1, -1.0), (i + 5, 0.5), (i + 17, -0.25)] {
                if j < size && (i * 7 + j) % 3 != 0 {
                    a[i * size + j] = v;
                    a[j * size + i] = v;
                }
            }
        }
        coarse.matrix.clone_from(&a);
        coarse.factor();
        assert!(coarse
            .first
            .iter()
            .enumerate()
            .any(|(i, f)| *f > 0 && *f < i));
        let l = coarse.factor.clone().expect("positive definite");
        let b: Vec<f64> = (0..size).map(|i| (i as f64 * 0.37).sin()).collect();
        let mut x = b.clone();
        coarse.solve(&l, &mut x);
        for i in 0..size {
            let ax: f64 = (0..size).map(|j| a[i * size + j] * x[j]).sum();
            assert!((ax - b[i]).abs() < 1e-7, "row {i}: {ax} against {}", b[i]);
        }
    }

    #[test]
    fn the_coarse_operator_is_the_projection_of_the_operator() {
        // Column by column, `Pᵀ (H (P e_k))` with `H` applied by the products the conjugate
        // gradients use must equal the coarse matrix assembled term by term, on a sheared,
        // squashed lattice with some nodes held.
        for model in [
            ElementModel::EdgeRepulsion,
            ElementModel::Springs,
            ElementModel::SHAPE_MATCHING,
        ] {
            let body = DeformableBuilder::cuboid(Vector::splat(0.5), [5; DIM])
                .cells(CellKind::Simplex)
                .model(model)
                .build()
                .unwrap();
            let x0 = super::super::super::squashed(&body.state.positions, 0.8, 0.2);
            let n = x0.len();
            let v0 = vec![Vector::ZERO; n];
            let held: Vec<Hold> = (0..n)
                .map(|i| {
                    if i % 7 == 0 {
                        Hold::At(x0[i])
                    } else {
                        Hold::Free
                    }
                })
                .collect();
            let input = StepInput {
                x0: &x0,
                v0: &v0,
                masses: &body.rest.masses,
                held: &held,
                start: None,
                gravity: Vector::ZERO,
                h: 1.0 / 60.0,
                iterations: 1,
                global: 0,
                chords: true,
            };
            let mut x = Vec::new();
            let solve = body.state.elements.begin_implicit(&input, &mut x).unwrap();
            let free: Vec<bool> = held.iter().map(|h| *h == Hold::Free).collect();
            let terms = solve.terms(&x);
            let mut coarse = Coarse::new(&x, &free);
            assert!(coarse.clusters > 1, "{}", model.name());
            terms.coarse(&mut coarse, &free);
            let size = coarse.size();
            let scale = coarse.matrix.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let mut hv = vec![Vector::ZERO; n];
            for k in 0..size {
                let (cluster, j) = (k / COARSE, k % COARSE);
                let v: Vec<Vector> = (0..n)
                    .map(|i| {
                        if !free[i] || coarse.cluster[i] != cluster {
                            return Vector::ZERO;
                        }
                        if j < DIM {
                            unit(j)
                        } else {
                            let (r, c) = ((j - DIM) / DIM, (j - DIM) % DIM);
                            unit(r) * coarse.offset[i][c]
                        }
                    })
                    .collect();
                terms.product(&v, &mut hv);
                let mut column = vec![0.0f64; size];
                for i in (0..n).filter(|&i| free[i]) {
                    let row = coarse_row(hv[i], coarse.offset[i]);
                    for (m, value) in row.iter().enumerate() {
                        column[coarse.cluster[i] * COARSE + m] += value;
                    }
                }
                // The lower triangle, which is all the assembly keeps.
                for (row, expected) in column.iter().enumerate().skip(k) {
                    let got = coarse.matrix[row * size + k];
                    assert!(
                        (got - expected).abs() <= 1e-4 * scale,
                        "{}: entry ({row}, {k}): {got} against {expected}",
                        model.name()
                    );
                }
            }
        }
    }
}
