//! Gas sealed in a body (issue 31, acceptance 3 and 4).

use crate::dim::math::{Pose, Real, Vector, DIM, FACET_ARITY};
use crate::dim::mesh::CellKind;
use crate::dim::rapier::prelude::{
    ColliderBuilder, Cuboid, RigidBodyBuilder, RigidBodyHandle, SharedShape,
};
use crate::dim::{
    BuildError, DeformableBuilder, DeformableHandle, DeformableWorld, ElementModel, Gas,
    Integrator, Material, Mesh,
};

/// Outer and inner radius of the hollow ball.
const OUTER: Real = 0.2;
const INNER: Real = 0.13;

const MODELS: [ElementModel; 2] = [ElementModel::EdgeRepulsion, ElementModel::SHAPE_MATCHING];
const INTEGRATORS: [Integrator; 2] = [Integrator::Explicit, Integrator::Implicit { iterations: 4 }];

/// A hollow rubber ball, 40 cm across with 7 cm walls, two or more cells thick.
fn hollow_ball() -> Mesh {
    hollow_ball_of(if DIM == 3 { 13 } else { 21 })
}

/// [`hollow_ball`] with `across` lattice nodes across its diameter.
fn hollow_ball_of(across: usize) -> Mesh {
    let mesh = Mesh::ball(OUTER, across, CellKind::Simplex)
        .unwrap()
        .retain_cells(|c| {
            let centre = c.iter().copied().sum::<Vector>() / c.len() as Real;
            centre.length() > INNER
        })
        .unwrap();
    assert_eq!(mesh.diagnose(), vec![], "one manifold piece");
    mesh
}

fn rubber() -> Material {
    Material {
        density: 1100.0,
        young_modulus: 3e5,
        damping_ratio: 0.1,
        poisson_ratio: 0.45,
    }
}

/// A world without gravity at 60 Hz under `integrator`.
fn weightless(integrator: Integrator) -> DeformableWorld {
    let mut world = DeformableWorld::new();
    world.set_dt(1.0 / 60.0);
    world.physics.gravity = Vector::ZERO;
    world.pipeline.settings.integrator = integrator;
    world
}

/// The hollow ball, inflated to `pressure` Pa over the atmosphere, at the origin, between two
/// kinematic plates (below, above) clear of it.
fn balloon(
    model: ElementModel,
    integrator: Integrator,
    pressure: Real,
) -> (DeformableWorld, DeformableHandle, [RigidBodyHandle; 2]) {
    let mut world = weightless(integrator);
    let body = DeformableBuilder::new(hollow_ball())
        .model(model)
        .material(rubber())
        .deformation_damping(5.0)
        .gas(Gas::gauge(pressure))
        .build()
        .unwrap();
    let h = world.insert(body);
    let mut plates = [RigidBodyHandle::invalid(); 2];
    for (plate, side) in plates.iter_mut().zip([-1.0, 1.0]) {
        let mut at = Vector::ZERO;
        at[1] = side * 0.55;
        *plate = world
            .physics
            .insert_body(RigidBodyBuilder::kinematic_position_based().translation(at));
        let mut half = Vector::splat(0.5);
        half[1] = 0.05;
        let collider = ColliderBuilder::new(SharedShape::new(Cuboid::new(half)));
        world.physics.insert_collider(collider, Some(*plate));
    }
    (world, h, plates)
}

/// Moves the plates so that their inner faces are `gap` apart, about the origin.
fn set_gap(world: &mut DeformableWorld, plates: [RigidBodyHandle; 2], gap: Real) {
    for (plate, side) in plates.into_iter().zip([-1.0, 1.0]) {
        let mut at = Vector::ZERO;
        at[1] = side * (gap / 2.0 + 0.05);
        world.physics.bodies[plate].set_next_kinematic_position(Pose::from_translation(at));
    }
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

/// Whether `err` refuses the parameter `name`.
fn invalid(err: &BuildError, name: &str) -> bool {
    matches!(err, BuildError::InvalidParameter { name: n, .. } if *n == name)
}

/// `(pressure + ambient) × volume` of the body's one chamber now.
fn boyle(world: &DeformableWorld, h: DeformableHandle) -> Real {
    let c = world.deformables[h].chambers()[0];
    (c.pressure + Gas::ATMOSPHERE) * c.volume
}

#[test]
fn a_balloon_squeezed_to_70_percent_follows_boyle_and_springs_back() {
    // Inflated, then squeezed between two plates until its gas has 70 % of its volume, held,
    // and let go: `pV` stays within 2 % of its value before the squeeze, the walls stay upright,
    // and the ball comes back to its inflated volume within 1 %. Both models, both
    // integrators.
    for model in MODELS {
        for integrator in INTEGRATORS {
            let name = format!("{} {integrator:?}", model.name());
            let (mut world, h, plates) = balloon(model, integrator, 2e4);
            for _ in 0..40 {
                world.step();
            }
            let inflated = world.deformables[h].chambers()[0];
            assert!(
                inflated.volume > 1.02 * inflated.built_volume,
                "{name}: the gas inflated the ball: {inflated:?}"
            );
            let pv = boyle(&world, h);
            let top = world.deformables[h]
                .positions()
                .iter()
                .map(|p| p[1])
                .fold(Real::MIN, Real::max);
            let mut gap = 2.0 * top;
            let mut worst: Real = 0.0;
            // The plates close at 0.3 m/s while the gas has more than 70 % of its volume, and
            // stop where it has less: a squeezed ball bulges out sideways as it settles, so
            // they close on it until it stays below.
            let mut below = 0;
            for steps in 0.. {
                assert!(steps < 240, "{name}: never squeezed to 70 %");
                if world.deformables[h].chambers()[0].volume > 0.7 * inflated.volume {
                    gap -= 0.3 / 60.0;
                    set_gap(&mut world, plates, gap);
                    below = 0;
                } else {
                    below += 1;
                }
                if below == 20 {
                    break;
                }
                world.step();
                worst = worst.max((boyle(&world, h) / pv - 1.0).abs());
            }
            let squeezed = world.deformables[h].chambers()[0];
            assert!(worst < 0.02, "{name}: pV off by {worst}");
            assert!(
                squeezed.volume < 0.72 * inflated.volume,
                "{name}: the gas pushed the plates back: {squeezed:?}"
            );
            assert!(
                squeezed.pressure > 1.3 * inflated.pressure,
                "{name}: {squeezed:?}"
            );
            assert_eq!(world.deformables[h].inverted_elements(), 0, "{name}");
            set_gap(&mut world, plates, 1.0);
            for _ in 0..90 {
                world.step();
            }
            let back = world.deformables[h].chambers()[0];
            let off = (back.volume / inflated.volume - 1.0).abs();
            assert!(off < 0.01, "{name}: back to {off} off: {back:?}");
            assert!(world.deformables[h]
                .positions()
                .iter()
                .all(|p| p.is_finite()));
        }
    }
}

#[test]
fn gas_in_a_solid_body_dilates_it_by_its_gauge_pressure_over_the_bulk_modulus() {
    // A solid body with no cavity holds the gas in its own volume: the gas pulls every face
    // out with its gauge pressure, a uniform hydrostatic tension, so the body dilates by
    // `P/K` whatever its shape (`K = E/(3(1 − 2ν))`; in 2D, plane stress, `E/(2(1 − ν))`).
    // This checks the force's size, not only its sign.
    let material = Material {
        density: 1000.0,
        young_modulus: 1e6,
        damping_ratio: 0.3,
        poisson_ratio: 0.3,
    };
    let nu = material.poisson_ratio;
    let bulk = if DIM == 3 {
        material.young_modulus / (3.0 * (1.0 - 2.0 * nu))
    } else {
        material.young_modulus / (2.0 * (1.0 - nu))
    };
    for model in MODELS {
        for integrator in INTEGRATORS {
            let name = format!("{} {integrator:?}", model.name());
            let mut world = weightless(integrator);
            let body = DeformableBuilder::cuboid(Vector::splat(0.1), [5; DIM])
                .model(model)
                .material(material)
                .deformation_damping(10.0)
                .gas(Gas::gauge(2e4))
                .build()
                .unwrap();
            let h = world.insert(body);
            for _ in 0..120 {
                world.step();
            }
            let c = world.deformables[h].chambers()[0];
            let strain = c.volume / c.built_volume - 1.0;
            // Small-strain elasticity, read at the strain reached: within 10 %.
            let expected = c.pressure / bulk;
            assert!(
                (strain / expected - 1.0).abs() < 0.1,
                "{name}: dilated by {strain}, expected {expected} ({c:?})"
            );
        }
    }
}

#[test]
fn bad_gas_and_chambers_that_leak_or_face_inwards_are_refused() {
    let mesh = hollow_ball();
    let build = |b: DeformableBuilder| b.build().map(|_| ()).unwrap_err();
    let vacuum = Gas {
        pressure: -2.0 * Gas::ATMOSPHERE,
        ambient: Gas::ATMOSPHERE,
    };
    let err = build(DeformableBuilder::new(mesh.clone()).gas(vacuum));
    assert!(invalid(&err, "Gas::pressure"), "{err}");
    let nan = Gas {
        pressure: 0.0,
        ambient: Real::NAN,
    };
    let err = build(DeformableBuilder::new(mesh.clone()).gas(nan));
    assert!(invalid(&err, "Gas::ambient"), "{err}");
    // The ball's inner surface, given as a chamber of its own with one facet missing: open.
    let cavity: Vec<_> = mesh
        .boundary_facets()
        .iter()
        .filter(|f| {
            f.iter()
                .all(|&i| mesh.nodes()[i as usize].length() < 0.5 * (INNER + OUTER))
        })
        .copied()
        .collect();
    let cavity = flipped(&cavity);
    assert!(cavity.len() > 10);
    let mut open = cavity.clone();
    open.pop();
    let err = build(DeformableBuilder::new(mesh.clone()).chamber(open, Gas::gauge(1e3)));
    assert!(
        matches!(err, BuildError::OpenChamber { chamber: 0, .. }),
        "{err}"
    );
    // As the mesh orients it, it faces into the gas.
    let inwards = flipped(&cavity);
    let err = build(
        DeformableBuilder::new(mesh.clone())
            .gas(Gas::gauge(1e3))
            .chamber(inwards, Gas::gauge(1e3)),
    );
    assert!(
        matches!(err, BuildError::InvertedChamber { chamber: 1, .. }),
        "{err}"
    );
    // A facet between nodes that share no cell (a node of the outer surface in a facet of
    // the cavity).
    let outer = (0..mesh.nodes().len())
        .find(|&i| mesh.nodes()[i].length() > 0.95 * OUTER)
        .unwrap() as u32;
    let mut across = cavity.clone();
    across[2][0] = outer;
    let err = build(DeformableBuilder::new(mesh.clone()).chamber(across, Gas::gauge(1e3)));
    assert!(
        matches!(
            err,
            BuildError::ChamberFacetOutsideCells {
                chamber: 0,
                facet: 2
            }
        ),
        "{err}"
    );
    let mut far = cavity.clone();
    far[3][1] = mesh.nodes().len() as u32;
    let err = build(DeformableBuilder::new(mesh.clone()).chamber(far, Gas::gauge(1e3)));
    assert!(
        matches!(
            err,
            BuildError::ChamberIndexOutOfRange {
                chamber: 0,
                facet: 3,
                ..
            }
        ),
        "{err}"
    );
    // Given right, the same facets are the cavity `gas` finds.
    let given = DeformableBuilder::new(mesh.clone())
        .chamber(cavity, Gas::gauge(1e3))
        .build()
        .unwrap();
    let found = DeformableBuilder::new(mesh)
        .gas(Gas::gauge(1e3))
        .build()
        .unwrap();
    assert_eq!(given.chambers(), found.chambers());
}

#[test]
fn a_chamber_pumped_up_swells_and_let_out_shrinks() {
    // A pneumatic valve: the chamber's gas set to a new gauge pressure at its volume now. The
    // ball swells to a new rest where its walls carry the higher pressure (at most the pumped
    // one, since it falls as the ball swells), and shrinks when let out.
    let mut world = weightless(INTEGRATORS[1]);
    let body = DeformableBuilder::new(hollow_ball())
        .material(rubber())
        .deformation_damping(5.0)
        .gas(Gas::gauge(1e4))
        .build()
        .unwrap();
    let h = world.insert(body);
    let settle = |world: &mut DeformableWorld| {
        for _ in 0..60 {
            world.step();
        }
        world.deformables[h].chambers()[0]
    };
    let low = settle(&mut world);
    world.deformables[h]
        .set_chamber_pressure(0, Gas::gauge(3e4))
        .unwrap();
    assert_eq!(world.deformables[h].chambers()[0].pressure, 3e4);
    let high = settle(&mut world);
    assert!(high.volume > 1.05 * low.volume, "{low:?} → {high:?}");
    assert!(
        high.pressure > low.pressure && high.pressure < 3e4,
        "{high:?}"
    );
    // Let out to suction: less gas than it started with, so it ends smaller than then.
    world.deformables[h]
        .set_chamber_pressure(0, Gas::gauge(-2e4))
        .unwrap();
    let out = settle(&mut world);
    assert!(out.volume < low.volume, "{out:?}");
    // Refused, and the body unchanged.
    let d = &mut world.deformables[h];
    let err = d.set_chamber_pressure(1, Gas::gauge(1e3)).unwrap_err();
    assert!(invalid(&err, "chamber"), "{err}");
    let bad = Gas {
        pressure: Real::NAN,
        ambient: Gas::ATMOSPHERE,
    };
    let err = d.set_chamber_pressure(0, bad).unwrap_err();
    assert!(invalid(&err, "Gas::pressure"), "{err}");
    assert_eq!(d.chambers()[0], out);
}

/// A snapshot of a squeezed balloon continues bit for bit, its gas with it.
#[cfg(feature = "serde")]
#[test]
fn a_snapshot_of_a_squeezed_balloon_continues_bit_for_bit() {
    let (mut world, h, plates) = balloon(ElementModel::EdgeRepulsion, INTEGRATORS[1], 2e4);
    for k in 0..40 {
        set_gap(&mut world, plates, 0.5 - 0.005 * k as Real);
        world.step();
    }
    let bytes = bincode::serialize(&world).expect("a snapshot serializes");
    let mut restored: DeformableWorld = bincode::deserialize(&bytes).expect("it restores");
    assert_eq!(
        world.deformables[h].chambers(),
        restored.deformables[h].chambers()
    );
    for w in [&mut world, &mut restored] {
        set_gap(w, plates, 1.0);
        for _ in 0..30 {
            w.step();
        }
    }
    let (a, b) = (&world.deformables[h], &restored.deformables[h]);
    assert_eq!(a.positions(), b.positions());
    assert!(a.chambers()[0].pressure > 0.0);
}

/// Feature `parallel`: a balloon large enough for the implicit sweeps to go by slabs, pumped
/// and squeezed, steps the same, bit for bit, on 1, 2 and 16 threads (each slab follows the
/// chambers' volume from where its kind of slab started).
#[cfg(feature = "parallel")]
#[test]
fn a_squeezed_balloon_steps_the_same_on_any_thread_count() {
    let state = |threads: usize| -> Vec<u32> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool");
        pool.install(|| {
            let mesh = hollow_ball_of(if DIM == 3 { 13 } else { 49 });
            assert!(mesh.nodes().len() >= 1024, "slabs need 4 × 256 nodes");
            let (mut world, h, plates) = balloon(ElementModel::EdgeRepulsion, INTEGRATORS[1], 2e4);
            let body = DeformableBuilder::new(mesh)
                .material(rubber())
                .gas(Gas::gauge(2e4))
                .build()
                .unwrap();
            world.deformables.remove(h);
            let h = world.insert(body);
            for k in 0..20 {
                set_gap(&mut world, plates, 0.4 - 0.004 * k as Real);
                world.step();
            }
            let d = &world.deformables[h];
            d.positions()
                .iter()
                .chain(d.velocities())
                .flat_map(|p| p.to_array())
                .map(Real::to_bits)
                .collect()
        })
    };
    let one = state(1);
    for threads in [2, 16] {
        assert!(one == state(threads), "1 and {threads} threads differ");
    }
}
