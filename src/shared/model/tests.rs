//! Feature `parallel`: the two-pass evaluation against the serial loop, on deformed lattices.

use super::super::body::DeformableBuilder;
use super::super::math::{Real, Vector, DIM};
use super::super::mesh::{CellKind, Mesh};
use super::parallel::Split;
use super::{Accumulator, ElementModel, ModelState, RotationFit, ShapeDamping};

/// Every model on simplices, the models that take them on cubes, and the shape-based element's
/// other options.
fn cases() -> Vec<(ElementModel, CellKind)> {
    let mut cases: Vec<_> = ElementModel::ALL
        .into_iter()
        .map(|m| (m, CellKind::Simplex))
        .collect();
    for m in ElementModel::ALL {
        if m != ElementModel::EdgeRepulsion {
            cases.push((m, CellKind::Cube));
        }
    }
    for fit in [RotationFit::Polar, RotationFit::Iterative(1)] {
        for damping in [ShapeDamping::RigidMotion, ShapeDamping::Centroid] {
            cases.push((
                ElementModel::ShapeMatching { fit, damping },
                CellKind::Simplex,
            ));
        }
    }
    cases
}

/// A lattice with a few hundred nodes (enough for several rayon tasks), stretched by 10%,
/// every node jittered by up to a fifth of the spacing and moving with a random velocity.
fn deformed(model: ElementModel, kind: CellKind) -> (ModelState, Mesh, Vec<Vector>, Vec<Vector>) {
    deformed_at(model, kind, if DIM == 2 { 20 } else { 7 })
}

/// [`deformed`] with `res` nodes an edge.
fn deformed_at(
    model: ElementModel,
    kind: CellKind,
    res: usize,
) -> (ModelState, Mesh, Vec<Vector>, Vec<Vector>) {
    let body = DeformableBuilder::cuboid(Vector::splat(0.5), [res; DIM])
        .cells(kind)
        .model(model)
        .build()
        .expect("lattice builds");
    let spacing = 1.0 / (res - 1) as Real;
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut random = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 40) as Real / (1u64 << 24) as Real - 0.5
    };
    let mut x = body.state.positions.clone();
    let mut v = body.state.velocities.clone();
    for (x, v) in x.iter_mut().zip(&mut v) {
        *x *= 1.1;
        for d in 0..DIM {
            x[d] += 0.2 * spacing * random();
            v[d] = random();
        }
    }
    (body.state.elements, body.rest.mesh, x, v)
}

fn bits(acc: &Accumulator, limit: Real) -> Vec<u32> {
    let mut out: Vec<u32> = acc
        .force
        .iter()
        .flat_map(|f| f.to_array())
        .map(Real::to_bits)
        .collect();
    out.extend(acc.stiffness.iter().map(|k| k.to_bits()));
    out.extend(acc.damping.iter().map(|c| c.to_bits()));
    out.push(limit.to_bits());
    out
}

/// The serial loop and the split evaluation over three substeps (so the shape-based
/// element's warm-started rotations evolve in both), run inside `pool` for the split one.
fn serial_and_split(
    model: ElementModel,
    kind: CellKind,
    pool: &rayon::ThreadPool,
) -> (Vec<Vec<u32>>, Vec<Vec<u32>>) {
    let (mut serial, mesh, mut x, v) = deformed(model, kind);
    let mut parallel = serial.clone();
    let mut split = Split::build(&*parallel.elements, &mesh);
    let n = x.len();
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for _ in 0..3 {
        let mut acc = Accumulator::new(n);
        let limit = serial.accumulate_serial(&x, &v, &mut acc);
        a.push(bits(&acc, limit));
        let mut acc = Accumulator::new(n);
        let limit = pool.install(|| {
            let volume = parallel.volume.as_ref();
            split.accumulate(
                &mut *parallel.elements,
                volume,
                &parallel.bounds,
                &x,
                &v,
                &mut acc,
            )
        });
        b.push(bits(&acc, limit));
        for (x, v) in x.iter_mut().zip(&v) {
            *x += *v * 1e-3;
        }
    }
    (a, b)
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool")
}

#[test]
fn parallel_forces_equal_serial_forces_bit_for_bit() {
    let pool = pool(2);
    for (model, kind) in cases() {
        let (serial, split) = serial_and_split(model, kind, &pool);
        assert!(
            serial[0].iter().any(|&b| b != 0),
            "{} on {kind:?}: no force at all",
            model.name()
        );
        for (step, (a, b)) in serial.iter().zip(&split).enumerate() {
            let differ = a.iter().zip(b).filter(|(a, b)| a != b).count();
            assert_eq!(
                differ,
                0,
                "{} on {kind:?}, substep {step}: {differ} of {} values differ",
                model.name(),
                a.len()
            );
        }
    }
}

#[test]
fn parallel_forces_do_not_depend_on_the_thread_count() {
    let pools = [pool(1), pool(2), pool(3)];
    for (model, kind) in cases() {
        let (_, one) = serial_and_split(model, kind, &pools[0]);
        for pool in &pools[1..] {
            let (_, more) = serial_and_split(model, kind, pool);
            assert!(
                one == more,
                "{} on {kind:?}: {} threads differ from one",
                model.name(),
                pool.current_num_threads()
            );
        }
    }
}

/// Nodes an edge of a lattice large enough to split.
const LARGE: usize = if DIM == 2 { 48 } else { 10 };

#[test]
fn small_models_stay_serial_and_large_ones_split() {
    let (small, ..) = deformed(ElementModel::EdgeRepulsion, CellKind::Simplex);
    assert!(small.split.is_none() && small.slabs.is_none());
    let large = |model| {
        DeformableBuilder::cuboid(Vector::splat(0.5), [LARGE; DIM])
            .model(model)
            .build()
            .expect("lattice builds")
            .state
            .elements
    };
    let shape = large(ElementModel::SHAPE_MATCHING);
    assert!(shape.split.is_some() && shape.slabs.is_none());
    // Edge repulsion goes by slabs instead.
    let er = large(ElementModel::EdgeRepulsion);
    assert!(er.split.is_none() && er.slabs.is_some());
}

#[test]
fn edge_repulsion_by_slabs_is_the_same_on_any_thread_count_and_equals_the_serial_loop() {
    // The slabs' order is the body's: every thread count sums each node's terms in it, so the
    // forces agree bit for bit; the serial loop's order differs, so they agree with it to
    // rounding.
    let (mut state, _, x, v) = deformed_at(ElementModel::EdgeRepulsion, CellKind::Simplex, LARGE);
    let n = x.len();
    let mut serial = Accumulator::new(n);
    let serial_limit = state.accumulate_serial(&x, &v, &mut serial);
    let largest = serial.force.iter().map(|f| f.length()).fold(0.0, Real::max);
    assert!(largest > 0.0);
    let mut one = Accumulator::new(n);
    let one_limit = pool(1).install(|| state.accumulate_elements(&x, &v, &mut one));
    let slabs = state.slabs.as_ref().expect("a large lattice goes by slabs");
    assert!(slabs.count() >= 4, "{} slabs", slabs.count());
    for (a, b) in one.force.iter().zip(&serial.force) {
        assert!((*a - *b).length() <= 1e-5 * largest, "{a:?} against {b:?}");
    }
    for (a, b) in one.stiffness.iter().zip(&serial.stiffness) {
        assert!((a - b).abs() <= 1e-5 * b.abs().max(1e-6), "{a} against {b}");
    }
    assert_eq!(one_limit, serial_limit);
    for threads in [2, 3, 16] {
        let mut acc = Accumulator::new(n);
        let limit = pool(threads).install(|| state.accumulate_elements(&x, &v, &mut acc));
        assert!(
            bits(&one, one_limit) == bits(&acc, limit),
            "{threads} threads differ from one"
        );
    }
}
