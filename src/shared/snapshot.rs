//! Snapshots (feature `serde`): save a running simulation and continue it later, bit for bit.
//!
//! With the `serde` feature, [`DeformableWorld`](super::DeformableWorld),
//! [`DeformableSet`](super::DeformableSet), [`Deformable`](super::Deformable),
//! [`Mesh`](super::Mesh), the pipeline, its settings and reports, and every plain type they
//! hold implement serde's `Serialize` and `Deserialize`; rapier's own sets serialize through
//! rapier's `serde-serialize` feature, which `serde` turns on. Pick any serde format that
//! restores every `f32` exactly: `bincode` 1.x stores the bits; `serde_json` writes the
//! shortest decimal that reads back to the same `f32`, and reads it back exactly with its
//! `float_roundtrip` feature (the tests run both). No saved value is infinite (a missing
//! crossing limit is saved as `None`), so JSON, which has no infinity, can hold a snapshot.
//!
//! The whole [`DeformableWorld`](super::DeformableWorld) is the natural unit: one value holds
//! both sides, rapier's bodies, colliders, joints, broad and narrow phases, islands and
//! parameters, and every deformable, so one call saves everything a step reads:
//!
//! ```
//! # #[cfg(feature = "serde")] {
//! use sinew::dim3::{DeformableBuilder, DeformableWorld};
//! use sinew::dim3::math::Vector;
//! use sinew::dim3::rapier::prelude::{ColliderBuilder, RigidBodyBuilder};
//!
//! let mut world = DeformableWorld::new();
//! world.physics.insert(RigidBodyBuilder::fixed(), ColliderBuilder::cuboid(5.0, 0.1, 5.0));
//! let cube = DeformableBuilder::cuboid(Vector::splat(0.25), [3, 3, 3])
//!     .translation(Vector::new(0.0, 0.5, 0.0))
//!     .build()
//!     .expect("a valid lattice");
//! let cube = world.insert(cube);
//! for _ in 0..5 {
//!     world.step();
//! }
//! let bytes = bincode::serialize(&world).expect("serializable");
//! let mut restored: DeformableWorld = bincode::deserialize(&bytes).expect("a valid snapshot");
//! world.step();
//! restored.step();
//! assert_eq!(world.deformables[cube].positions(), restored.deformables[cube].positions());
//! # }
//! ```
//!
//! A [`DeformableSet`](super::DeformableSet) can be saved alone beside rapier's sets (handles
//! keep their index and generation), but the continuation is exact only if everything the
//! pipeline reads — bodies, colliders and rapier's broad phase — is restored with it.
//!
//! # What is saved, what is rebuilt
//!
//! Saved, per deformable: the rest mesh's nodes, cells and cell kind; the element model,
//! material and stiffness form; node positions and velocities; the shape-based element's
//! per-cell warm-start rotations; a plastic body's flow parameters and each cell's rest
//! vertices (the rest data derived from them is rebuilt); the gas chambers (facets, the gas's
//! `pV` and built volume, the ambient pressure); the element forces and stiffness/damping bounds of the last
//! evaluation with the flag that says whether they are still current, and the crossing
//! limiter; the contact material (coefficients, combine rules, collision groups); gravity
//! scale; deformation damping rate; bindings to rigid bodies; contacts and touched colliders of the last step (they
//! drive contact events and waking); frozen, sleep flag, still time and `can_sleep`; the
//! last report; `user_data`. For the world also rapier's `PhysicsWorld` (as rapier serializes
//! it), the pipeline's settings and last report, the simulated time and step count.
//!
//! Rebuilt on restore, by the code that built them first (so they come back bit for bit):
//! the mesh's rest volumes and boundary (through [`Mesh::new`](super::Mesh::new), which also
//! validates the snapshot's mesh), node masses, the element model's rest data and constant
//! bounds (and, with `parallel`, its two-pass buffers), the node → binding index.
//!
//! Not saved: the pipeline's scratch buffers and each deformable's step-start copies of its
//! state (filled at the start of every step before anything reads them), and rapier's own
//! workspaces (`physics_pipeline`, `collision_pipeline`, `ccd_solver`: rapier skips them).
//! Wall-clock timings in the reports are saved as they were, but never influence the physics.
//!
//! # Errors
//!
//! Deserializing never panics on bad input: truncated or garbled bytes are the format's
//! error, and a snapshot that decodes but is inconsistent (a mesh that does not validate,
//! a state array of the wrong length, non-finite node state, a binding to a node that does
//! not exist, a material out of range) is a `serde` error naming what is wrong. Rapier's
//! parts are checked only as far as rapier's own `Deserialize` checks them.
//!
//! # Versions
//!
//! A snapshot is tied to the version of sinew (and of rapier) that wrote it: the layout is
//! the in-memory one, with no version tag and no migration. Restore it with the same
//! versions, the same features and the same dimension; anything else may fail to decode or,
//! worse, decode into a different state. Keep scene descriptions, not snapshots, for the
//! long term.

#[cfg(feature = "serde")]
mod imp {
    use std::borrow::Cow;

    use serde::de::Error as _;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    use super::super::attach::{Attachment, Bindings};
    use super::super::body::tear::Crack;
    use super::super::body::{
        check_state, Activation, Deformable, LastStep, Rest, State, StepBuffers, Surface,
    };
    use super::super::contact::{ContactMaterial, ContactPoint};
    use super::super::embedding::Embedding;
    use super::super::error::BuildError;
    use super::super::integrator::{MidpointCarry, MidpointState};
    use super::super::material::{Material, Plasticity, Resolved, Stiffness, Tearing};
    use super::super::math::{Real, Rotation, Vector};
    use super::super::mesh::{CellKind, Mesh};
    use super::super::model::{gas::Chamber, Accumulator, ElementModel, ModelState};
    use super::super::rapier::geometry::ColliderHandle;
    use super::super::report::DeformableReport;
    use super::super::set::DeformableHandle;

    /// What a mesh is saved as: the inputs of [`Mesh::new`].
    #[derive(Serialize, Deserialize)]
    struct MeshData<'a> {
        kind: CellKind,
        nodes: Cow<'a, [Vector]>,
        cells: Cow<'a, [u32]>,
    }

    impl Serialize for Mesh {
        fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
            MeshData {
                kind: self.kind(),
                nodes: Cow::Borrowed(self.nodes()),
                cells: Cow::Borrowed(self.cell_indices()),
            }
            .serialize(s)
        }
    }

    impl<'de> Deserialize<'de> for Mesh {
        fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
            let m = MeshData::deserialize(d)?;
            Mesh::new(m.nodes.into_owned(), m.cells.into_owned(), m.kind)
                .map_err(|e| D::Error::custom(format_args!("invalid mesh in snapshot: {e}")))
        }
    }

    /// What a deformable is saved as (see the module's docs).
    #[derive(Serialize, Deserialize)]
    struct DeformableData<'a> {
        mesh: Cow<'a, Mesh>,
        model: ElementModel,
        material: Material,
        stiffness: Stiffness,
        positions: Cow<'a, [Vector]>,
        velocities: Cow<'a, [Vector]>,
        warm_start: Cow<'a, [Rotation]>,
        acc: Cow<'a, Accumulator>,
        forces_valid: bool,
        /// The crossing limiter's bound; `None` for none (infinite), so that formats without
        /// infinities (JSON) can hold it.
        limiter: Option<Real>,
        /// The cap below which `limiter` is exact (`None`: exact everywhere; absent in older
        /// snapshots).
        #[serde(default)]
        crossing_cap: Option<Real>,
        contact: ContactMaterial,
        gravity_scale: Real,
        frozen: bool,
        report: Cow<'a, DeformableReport>,
        attachments: Cow<'a, [Attachment]>,
        contacts: Cow<'a, [ContactPoint]>,
        touching: Cow<'a, [ColliderHandle]>,
        /// Deformables touched in the last step (absent in older snapshots).
        #[serde(default)]
        touching_bodies: Cow<'a, [DeformableHandle]>,
        can_sleep: bool,
        sleeping: bool,
        still_time: Real,
        user_data: u128,
        /// The midpoint step's state between steps (absent in older snapshots).
        #[serde(default)]
        midpoint: Option<MidpointCarry>,
        /// The deformation damping rate (absent in older snapshots: none).
        #[serde(default)]
        deformation_damping: Real,
        /// The render mesh (absent in older snapshots: none).
        #[serde(default)]
        render: Option<Cow<'a, Embedding>>,
        /// Plastic flow and each cell's rest vertices (absent in older snapshots: none).
        #[serde(default)]
        plastic: Option<(Plasticity, Cow<'a, [Vector]>)>,
        /// Tearing (absent in older snapshots: none).
        #[serde(default)]
        tearing: Option<Tearing>,
        /// The faces torn open in the last step (absent in older snapshots: none).
        #[serde(default)]
        tears: Cow<'a, [[u32; 2]]>,
        /// The crack torn last, while its release crosses the body (absent: none).
        #[serde(default)]
        crack: Option<Crack>,
        /// Gas chambers (absent in older snapshots: none).
        #[serde(default)]
        gas: Cow<'a, [Chamber]>,
    }

    impl Serialize for Deformable {
        fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
            DeformableData {
                mesh: Cow::Borrowed(&self.rest.mesh),
                model: self.rest.model,
                material: self.rest.params.material,
                stiffness: self.rest.params.stiffness,
                positions: Cow::Borrowed(&self.state.positions),
                velocities: Cow::Borrowed(&self.state.velocities),
                warm_start: Cow::Borrowed(self.state.elements.warm_start()),
                acc: Cow::Borrowed(&self.step.acc),
                forces_valid: self.step.forces_valid,
                limiter: Some(self.step.limiter).filter(|l| l.is_finite()),
                crossing_cap: Some(self.step.crossing_cap).filter(|c| c.is_finite()),
                contact: self.contact,
                gravity_scale: self.gravity_scale,
                deformation_damping: self.deformation_damping,
                render: self.render.as_ref().map(Cow::Borrowed),
                frozen: self.activation.frozen,
                report: Cow::Borrowed(&self.last.report),
                attachments: Cow::Borrowed(self.bindings.list()),
                contacts: Cow::Borrowed(&self.last.contacts),
                touching: Cow::Borrowed(&self.last.touching),
                touching_bodies: Cow::Borrowed(&self.last.touching_bodies),
                can_sleep: self.activation.can_sleep,
                sleeping: self.activation.sleeping,
                still_time: self.activation.still_time,
                user_data: self.user_data,
                midpoint: Some(self.step.midpoint.carry()),
                plastic: self
                    .state
                    .elements
                    .plasticity()
                    .map(|p| (p, Cow::Borrowed(self.state.elements.plastic_rest()))),
                gas: Cow::Borrowed(self.state.elements.chambers()),
                tearing: self.tearing,
                tears: Cow::Borrowed(&self.last.tears),
                crack: self.last.crack,
            }
            .serialize(s)
        }
    }

    impl<'de> Deserialize<'de> for Deformable {
        fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
            DeformableData::deserialize(d)?
                .into_deformable()
                .map_err(|e| D::Error::custom(format_args!("invalid deformable in snapshot: {e}")))
        }
    }

    impl DeformableData<'_> {
        fn into_deformable(self) -> Result<Deformable, String> {
            let mesh = self.mesh.into_owned();
            let n = mesh.nodes().len();
            let params = Resolved::new(self.material, self.stiffness).map_err(|e| e.to_string())?;
            check_state("positions", &self.positions, n).map_err(|e| e.to_string())?;
            check_state("velocities", &self.velocities, n).map_err(|e| e.to_string())?;
            let acc = self.acc.into_owned();
            if acc.force.len() != n || acc.stiffness.len() != n || acc.damping.len() != n {
                return Err(format!(
                    "element force arrays are not one value per node ({n})"
                ));
            }
            let rest = Rest::new(mesh, self.model, params);
            // The initial rotation only seeds the warm start, which the snapshot overwrites.
            let mut elements = ModelState::build(
                self.model,
                &rest.mesh,
                &rest.masses,
                &rest.params,
                Rotation::IDENTITY,
                self.plastic.as_ref().map(|(p, _)| *p),
            )
            .map_err(|e| e.to_string())?;
            if let Some((_, cells)) = &self.plastic {
                elements.set_plastic_rest(cells).map_err(|expected| {
                    format!(
                        "{} plastic rest vertices, expected {expected} (finite)",
                        cells.len()
                    )
                })?;
            }
            let gas = self.gas.into_owned();
            if let Some(k) = gas.iter().position(|c| !c.fits(&rest.mesh)) {
                return Err(format!(
                    "gas chamber {k} does not fit the mesh or is out of range"
                ));
            }
            if let Some(t) = &self.tearing {
                let plasticity = self.plastic.as_ref().map(|(p, _)| p);
                t.validate(plasticity).map_err(|e| e.to_string())?;
                if !gas.is_empty() {
                    return Err(BuildError::TearingWithGas.to_string());
                }
            }
            elements.set_gas(gas, n);
            elements
                .set_warm_start(&self.warm_start)
                .map_err(|expected| {
                    format!(
                        "{} warm-start rotations, expected {expected}",
                        self.warm_start.len()
                    )
                })?;
            let c = &self.contact;
            let coefficients_ok = c.friction.is_finite()
                && c.friction >= 0.0
                && (0.0..=1.0).contains(&c.restitution)
                && self.gravity_scale.is_finite()
                && self.deformation_damping.is_finite()
                && self.deformation_damping >= 0.0
                && self.still_time.is_finite();
            if !coefficients_ok {
                return Err(
                    "friction, restitution, gravity scale, deformation damping or still \
                     time out of range"
                        .into(),
                );
            }
            let bindings = Bindings::from_list(self.attachments.into_owned(), n)?;
            let render = self.render.map(Cow::into_owned);
            if let Some(r) = &render {
                r.check(n)?;
            }
            let state = State {
                positions: self.positions.into_owned(),
                velocities: self.velocities.into_owned(),
                elements,
            };
            let mut step = StepBuffers::new(
                acc,
                self.forces_valid,
                self.limiter.unwrap_or(Real::INFINITY),
                &state,
            );
            step.crossing_cap = self.crossing_cap.unwrap_or(Real::INFINITY);
            if let Some(carry) = self.midpoint {
                step.midpoint = MidpointState::from_carry(carry)?;
            }
            Ok(Deformable {
                step,
                surface: Surface::build(&rest.mesh, &state.positions),
                state,
                rest,
                activation: Activation {
                    can_sleep: self.can_sleep,
                    sleeping: self.sleeping,
                    still_time: self.still_time,
                    frozen: self.frozen,
                    woken: false,
                },
                last: LastStep {
                    report: self.report.into_owned(),
                    contacts: self.contacts.into_owned(),
                    touching: self.touching.into_owned(),
                    touching_bodies: self.touching_bodies.into_owned(),
                    tears: self.tears.into_owned(),
                    crack: self.crack,
                },
                bindings,
                contact: self.contact,
                gravity_scale: self.gravity_scale,
                deformation_damping: self.deformation_damping,
                render,
                tearing: self.tearing,
                user_data: self.user_data,
            })
        }
    }
}
