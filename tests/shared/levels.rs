//! Soft bodies on the shapes levels are built of (issue 14, acceptance 1): open trimeshes of
//! either winding (polylines in 2D), with and without `FIX_INTERNAL_EDGES`, a closed trimesh,
//! a heightfield, a compound, a convex hull and voxels, each holding a dropped body as a
//! cuboid floor does.

use crate::dim::math::{Pose, Real, Vector, DIM, UP};
use crate::dim::mesh::CellKind;
use crate::dim::rapier::geometry::{Cuboid, SharedShape};
use crate::dim::rapier::prelude::{ColliderBuilder, RigidBodyBuilder};
use crate::dim::{DeformableWorld, ElementModel, Material, Mesh};
use crate::levels;
use crate::scenes::testing::DropTest;
use crate::scenes::Record;

/// Half the floor's width; floors have their top at height 0.
const HALF: Real = 2.0;

fn slab(half_height: Real) -> Vector {
    let mut h = Vector::splat(HALF);
    h[1] = half_height;
    h
}

fn cuboid(half: Vector) -> ColliderBuilder {
    ColliderBuilder::new(SharedShape::new(Cuboid::new(half)))
}

/// The floors, by name; every one has its top face at height 0 under the body.
fn floors() -> Vec<(&'static str, ColliderBuilder)> {
    let below = |c: ColliderBuilder| c.translation(-UP * 0.1);
    let corners: Vec<Vector> = (0..1usize << DIM)
        .map(|bits| {
            let mut p = slab(0.1);
            for d in 0..DIM {
                if bits & (1 << d) != 0 {
                    p[d] = -p[d];
                }
            }
            p - UP * 0.1
        })
        .collect();
    // Two slabs meeting under the body (the seam at x = 0.05 is under its middle).
    let mut part = slab(0.1);
    part[0] = 0.5 * HALF;
    let mut left = -UP * 0.1;
    left[0] = 0.05 - 0.5 * HALF;
    let mut right = -UP * 0.1;
    right[0] = 0.05 + 0.5 * HALF;
    let compound = ColliderBuilder::compound(vec![
        (
            Pose::from_translation(left),
            SharedShape::new(Cuboid::new(part)),
        ),
        (
            Pose::from_translation(right),
            SharedShape::new(Cuboid::new(part)),
        ),
    ]);
    // Voxels 0.25 wide filling [-HALF, HALF] × [-0.25, 0] (× [-HALF, HALF]).
    let size = 0.25;
    let per_side = (2.0 * HALF / size) as usize;
    let mut centres = Vec::new();
    for k in 0..per_side.pow(DIM as u32 - 1) {
        let mut p = Vector::splat(0.0);
        let mut rest = k;
        for d in (0..DIM).filter(|&d| d != 1) {
            p[d] = -HALF + size * ((rest % per_side) as Real + 0.5);
            rest /= per_side;
        }
        p[1] = -0.5 * size;
        centres.push(p);
    }
    vec![
        ("cuboid", below(cuboid(slab(0.1)))),
        (
            "open surface, up",
            levels::open_floor(8, HALF, false, false),
        ),
        (
            "open surface, down",
            levels::open_floor(8, HALF, true, false),
        ),
        (
            "open surface, up, fixed edges",
            levels::open_floor(8, HALF, false, true),
        ),
        (
            "open surface, down, fixed edges",
            levels::open_floor(8, HALF, true, true),
        ),
        ("closed trimesh", below(levels::closed_box(slab(0.1)))),
        ("heightfield", levels::heightfield(8, HALF)),
        ("compound", compound),
        (
            "convex hull",
            ColliderBuilder::convex_hull(&corners).unwrap(),
        ),
        (
            "voxels",
            ColliderBuilder::voxels_from_points(Vector::splat(size), &centres),
        ),
    ]
}

/// A soft, damped box dropped from 0.6 m (off the floor's centre, so it lands across
/// triangle edges and vertices) at 60 Hz without restitution, run for 4 s.
fn drop_on(floor: ColliderBuilder, model: ElementModel) -> Record {
    let mut world = DeformableWorld::new();
    world.physics.insert(RigidBodyBuilder::fixed(), floor);
    let mesh = Mesh::cuboid(Vector::splat(0.25), [4; DIM], CellKind::Simplex).unwrap();
    let material = Material {
        density: 400.0,
        young_modulus: 2e4,
        damping_ratio: 0.5,
        ..Default::default()
    };
    let mut at = Vector::splat(0.13);
    at[1] = 0.6;
    DropTest::new(world, mesh)
        .material(material)
        .model(model)
        .restitution(0.0)
        .seconds(4.0)
        .translation(at)
        .run()
        .unwrap()
}

#[test]
fn a_soft_body_rests_on_every_level_shape_as_on_a_cuboid() {
    for model in [ElementModel::EdgeRepulsion, ElementModel::SHAPE_MATCHING] {
        let mut reference = None;
        for (name, floor) in floors() {
            let r = drop_on(floor, model);
            let rest = r.rest_com.unwrap();
            let deepest = r.max_penetration.unwrap();
            assert!(!r.failed, "{} on {name}: {:?}", model.name(), r.failure);
            assert!(
                deepest < 1e-3,
                "{} on {name}: {deepest} m below the floor",
                model.name()
            );
            let cuboid_rest = *reference.get_or_insert(rest);
            assert!(
                (rest - cuboid_rest).abs() < 0.01 * cuboid_rest,
                "{} on {name}: rests at {rest} m, on a cuboid at {cuboid_rest} m",
                model.name()
            );
        }
    }
}
