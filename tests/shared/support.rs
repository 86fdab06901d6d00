//! Helpers for the shared tests.

use crate::dim::math::{Real, Vector, DIM};
use crate::dim::rapier::dynamics::RigidBodyHandle;
use crate::dim::rapier::prelude::RigidBodyBuilder;
use crate::dim::{CellKind, DeformableWorld, Mesh};

/// A world at 60 Hz without gravity, with one kinematic (position-based) bone at the origin.
pub fn weightless_with_bone() -> (DeformableWorld, RigidBodyHandle) {
    let mut world = DeformableWorld::new();
    world.set_dt(1.0 / 60.0);
    world.physics.gravity = Vector::ZERO;
    let bone = world
        .physics
        .insert_body(RigidBodyBuilder::kinematic_position_based());
    (world, bone)
}

/// A deterministic random source (SplitMix64), so failures replay.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[lo, hi)`.
    pub fn uniform(&mut self, lo: Real, hi: Real) -> Real {
        let u = (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        lo + (hi - lo) * u as Real
    }

    pub fn vector(&mut self, amplitude: Real) -> Vector {
        let c: Vec<Real> = (0..DIM)
            .map(|_| self.uniform(-amplitude, amplitude))
            .collect();
        crate::dim::math::vector_from_slice(&c)
    }

    /// A random angular vector (an angle in 2D, a scaled axis in 3D) of size up to `max`.
    pub fn angle(&mut self, max: Real) -> crate::dim::math::AngVector {
        random_ang(self, max)
    }
}

fn random_ang(rng: &mut Rng, max: Real) -> crate::dim::math::AngVector {
    let v = rng.vector(1.0);
    let s = rng.uniform(-max, max);
    // In 2D the cross product of two vectors is a scalar; in 3D a vector: both give a random
    // angular quantity from the same code.
    let e = rng.vector(1.0);
    let w = crate::dim::math::cross(v, e);
    let n = crate::dim::math::ang_norm(w);
    if n < 1e-3 {
        return crate::dim::math::ANG_ZERO;
    }
    w * (s / n)
}

/// One rest simplex: the origin and the unit vectors.
pub fn unit_simplex() -> Mesh {
    let mut nodes = vec![Vector::ZERO];
    for d in 0..DIM {
        let mut e = Vector::ZERO;
        e[d] = 1.0;
        nodes.push(e);
    }
    let cells: Vec<u32> = (0..=DIM as u32).collect();
    Mesh::new(nodes, cells, CellKind::Simplex).expect("unit simplex is valid")
}

/// One rest box cell of edge 1.
pub fn unit_box() -> Mesh {
    Mesh::cuboid(Vector::splat(0.5), [2; DIM], CellKind::Cube).expect("unit box is valid")
}
