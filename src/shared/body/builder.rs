//! [`DeformableBuilder`]: a named constructor, `mut self -> Self` setters, a validating build.

use super::super::attach::Bindings;
use super::super::contact::ContactMaterial;
use super::super::error::BuildError;
use super::super::material::{Gas, Material, Plasticity, Resolved, Stiffness, Tearing};
use super::super::math::{Real, Rotation, Vector, DIM, FACET_ARITY};
use super::super::mesh::{CellKind, Mesh};
use super::super::model::{gas, Accumulator, ElementModel, ModelState};
use super::super::rapier::dynamics::CoefficientCombineRule;
use super::super::rapier::geometry::InteractionGroups;
use super::super::report::DeformableReport;
use super::{Activation, Deformable, LastStep, Rest, State, StepBuffers, Surface};

enum Source {
    Mesh(Mesh),
    Cuboid {
        half_extents: Vector,
        resolution: [usize; DIM],
    },
}

/// Builds a [`Deformable`], rapier-style: a named constructor, then `mut self -> Self`
/// setters, then [`DeformableBuilder::build`], which validates everything and returns a
/// typed [`BuildError`] instead of panicking.
#[must_use = "a builder does nothing until `.build()` is called"]
pub struct DeformableBuilder {
    source: Source,
    cells: CellKind,
    model: ElementModel,
    material: Material,
    stiffness: Stiffness,
    plasticity: Option<Plasticity>,
    tearing: Option<Tearing>,
    /// Gas in the mesh's own chambers, then in chambers given by their facets.
    gas: Option<Gas>,
    chambers: Vec<(Vec<[u32; FACET_ARITY]>, Gas)>,
    translation: Vector,
    rotation: Rotation,
    linvel: Vector,
    friction: Real,
    restitution: Real,
    friction_combine_rule: CoefficientCombineRule,
    restitution_combine_rule: CoefficientCombineRule,
    gravity_scale: Real,
    deformation_damping: Real,
    groups: InteractionGroups,
    ignore_attached_bodies: bool,
    can_sleep: bool,
    self_contact: bool,
    deny_warnings: bool,
    user_data: u128,
}

impl DeformableBuilder {
    /// A deformable over an existing rest mesh.
    pub fn new(mesh: Mesh) -> Self {
        Self::with_source(Source::Mesh(mesh))
    }

    /// A box lattice `[-half_extents, half_extents]` with `resolution[d]` nodes along axis `d`
    /// (see [`Mesh::cuboid`]); simplex cells unless [`DeformableBuilder::cells`] says otherwise.
    pub fn cuboid(half_extents: Vector, resolution: [usize; DIM]) -> Self {
        Self::with_source(Source::Cuboid {
            half_extents,
            resolution,
        })
    }

    fn with_source(source: Source) -> Self {
        DeformableBuilder {
            source,
            cells: CellKind::Simplex,
            model: ElementModel::EdgeRepulsion,
            material: Material::default(),
            stiffness: Stiffness::FromMaterial,
            plasticity: None,
            tearing: None,
            gas: None,
            chambers: Vec::new(),
            translation: Vector::ZERO,
            rotation: Rotation::IDENTITY,
            linvel: Vector::ZERO,
            friction: 0.5,
            restitution: 0.0,
            friction_combine_rule: CoefficientCombineRule::Average,
            restitution_combine_rule: CoefficientCombineRule::Average,
            gravity_scale: 1.0,
            deformation_damping: 0.0,
            groups: InteractionGroups::all(),
            ignore_attached_bodies: true,
            can_sleep: true,
            self_contact: false,
            deny_warnings: false,
            user_data: 0,
        }
    }

    /// Cell kind of a [`DeformableBuilder::cuboid`] lattice (ignored for an explicit mesh).
    pub fn cells(mut self, kind: CellKind) -> Self {
        self.cells = kind;
        self
    }

    /// The element model (default: [`ElementModel::EdgeRepulsion`]).
    pub fn model(mut self, model: ElementModel) -> Self {
        self.model = model;
        self
    }

    /// The material (default: [`Material::default`]).
    pub fn material(mut self, material: Material) -> Self {
        self.material = material;
        self
    }

    /// The stiffness form (default: from the material).
    pub fn stiffness(mut self, stiffness: Stiffness) -> Self {
        self.stiffness = stiffness;
        self
    }

    /// Plastic flow (default: none, a purely elastic body): every model, on simplex cells;
    /// [`DeformableBuilder::build`] refuses it for other cells and for bad parameters.
    pub fn plasticity(mut self, plasticity: Plasticity) -> Self {
        self.plasticity = Some(plasticity);
        self
    }

    /// Tearing (default: none): the body splits along the faces between its cells stretched
    /// across past the tear strain (`docs/ARCHITECTURE.md` §3.8), any model and cell kind.
    /// [`DeformableBuilder::build`] refuses a bad strain or smallest piece, a tear strain at or
    /// below the plastic yield strain ([`BuildError::TearBelowYield`]), and a body with gas
    /// ([`BuildError::TearingWithGas`]).
    pub fn tearing(mut self, tearing: Tearing) -> Self {
        self.tearing = Some(tearing);
        self
    }

    /// Seals `gas` in the body (`docs/ARCHITECTURE.md` §3.7): in each cavity of the mesh (a
    /// closed inner piece of its boundary: a hollow ball's hole, a tyre's tube), or, in a body
    /// without one, behind the outer surface of each of its pieces (the body's own volume
    /// holds the gas). [`Gas::pressure`] is the gauge pressure at the built shape; the body
    /// inflates from there until its walls carry it. Any model; every integrator.
    /// [`Deformable::chambers`] reports each chamber's volume and pressure.
    ///
    /// A ball that holds its shape by gas: a hollow ball, its walls two or more cells thick.
    ///
    /// ```
    /// use sinew::dim3::math::{Real, Vector};
    /// use sinew::dim3::mesh::CellKind;
    /// use sinew::dim3::{DeformableBuilder, Gas, Mesh};
    ///
    /// let hollow = Mesh::ball(0.2, 13, CellKind::Simplex)?.retain_cells(|cell| {
    ///     let centre = cell.iter().copied().sum::<Vector>() / cell.len() as Real;
    ///     centre.length() > 0.13
    /// })?;
    /// let ball = DeformableBuilder::new(hollow).gas(Gas::gauge(2e4)).build()?;
    /// assert_eq!(ball.chambers().len(), 1);
    /// assert_eq!(ball.chambers()[0].pressure, 2e4);
    /// # Ok::<(), sinew::dim3::BuildError>(())
    /// ```
    pub fn gas(mut self, gas: Gas) -> Self {
        self.gas = Some(gas);
        self
    }

    /// Seals `gas` in a chamber of its own behind `facets` (node indices of the rest mesh,
    /// each facet facing out of the gas as the mesh's boundary faces out of its cells:
    /// counter-clockwise seen from the walls in 3D; a 2D segment `[a, b]` has the gas on its
    /// right): a pneumatic pad's chambers, each at its own
    /// pressure. The facets need not be on the boundary, but must lie in the cells (each
    /// facet's nodes share a cell) and close around a positive volume:
    /// [`BuildError::ChamberFacetOutsideCells`], [`BuildError::OpenChamber`],
    /// [`BuildError::InvertedChamber`] and [`BuildError::ChamberIndexOutOfRange`] name the
    /// chamber (counted from 0 in the order given, after the [`DeformableBuilder::gas`] ones)
    /// otherwise.
    pub fn chamber(mut self, facets: Vec<[u32; FACET_ARITY]>, gas: Gas) -> Self {
        self.chambers.push((facets, gas));
        self
    }

    /// Translation applied to the rest mesh.
    pub fn translation(mut self, translation: Vector) -> Self {
        self.translation = translation;
        self
    }

    /// Rotation applied to the rest mesh (about the mesh origin, before the translation).
    pub fn rotation(mut self, rotation: Rotation) -> Self {
        self.rotation = rotation;
        self
    }

    /// Initial velocity of every node.
    pub fn linvel(mut self, linvel: Vector) -> Self {
        self.linvel = linvel;
        self
    }

    /// Friction coefficient against colliders (default 0.5), combined with the collider's.
    pub fn friction(mut self, friction: Real) -> Self {
        self.friction = friction;
        self
    }

    /// Restitution coefficient against colliders (default 0), combined with the collider's.
    pub fn restitution(mut self, restitution: Real) -> Self {
        self.restitution = restitution;
        self
    }

    /// Rule combining the friction coefficients (rapier's; default average).
    pub fn friction_combine_rule(mut self, rule: CoefficientCombineRule) -> Self {
        self.friction_combine_rule = rule;
        self
    }

    /// Rule combining the restitution coefficients (rapier's; default average).
    pub fn restitution_combine_rule(mut self, rule: CoefficientCombineRule) -> Self {
        self.restitution_combine_rule = rule;
        self
    }

    /// Multiplier of gravity for this body (default 1).
    pub fn gravity_scale(mut self, scale: Real) -> Self {
        self.gravity_scale = scale;
        self
    }

    /// Rate (1/s) at which the body's velocities are pulled toward its best-fit rigid motion
    /// (default 0: off), as the `deformation_damping` of rapier 0.36's own soft bodies: it damps
    /// every deformation mode by `exp(-rate · t)` and keeps the body's momentum and angular
    /// momentum, so a fall, a throw or a spin go on undamped. The material's damping ratio
    /// damps each element's own oscillation and the body's slow modes far less
    /// ([`Material::damping_ratio`]); this reaches them. It does not damp bodies moving
    /// against each other (a tower's sway, each cube rocking whole on the one below): that is
    /// [`PipelineSettings::damp_held`](super::super::PipelineSettings::damp_held)'s, on by default.
    pub fn deformation_damping(mut self, rate: Real) -> Self {
        self.deformation_damping = rate;
        self
    }

    /// Which colliders this body may touch (rapier's collision groups).
    pub fn collision_groups(mut self, groups: InteractionGroups) -> Self {
        self.groups = groups;
        self
    }

    /// Whether contacts ignore the colliders of the bodies this deformable is bound to
    /// (default `true`: tissue skinned onto a bone overlaps it by construction).
    pub fn ignore_attached_bodies(mut self, ignore: bool) -> Self {
        self.ignore_attached_bodies = ignore;
        self
    }

    /// Whether [`Mesh::diagnose`]'s warnings (coincident nodes, a surface that is not
    /// manifold, separate pieces) are errors ([`BuildError::MeshWarning`], the first one
    /// found); default `false`: they are legal, and a cut mesh may be meant.
    pub fn deny_warnings(mut self, deny: bool) -> Self {
        self.deny_warnings = deny;
        self
    }

    /// Whether the body may fall asleep when it rests (default `true`, as rapier's bodies;
    /// thresholds in [`PipelineSettings`](super::super::PipelineSettings)).
    pub fn can_sleep(mut self, can_sleep: bool) -> Self {
        self.can_sleep = can_sleep;
        self
    }

    /// Whether the body's surface meets itself (default `false`): on, a surface node is kept
    /// out of the body's own surface facets as it is kept out of another deformable's
    /// (`docs/ARCHITECTURE.md` §6.6), except the facets of the nodes it shares a cell with. Turn it on for a body that folds onto itself (a limb's crease,
    /// a long body bent double, a sheet); a compact body under moderate loads cannot fold and
    /// does not need it. It costs about what contact with a second body of the same surface
    /// costs: its facets' hierarchy is rebuilt every step, every surface node queries it, and
    /// every substep tests each node against the facets near it.
    pub fn self_contact(mut self, on: bool) -> Self {
        self.self_contact = on;
        self
    }

    /// Free user data.
    pub fn user_data(mut self, data: u128) -> Self {
        self.user_data = data;
        self
    }

    /// Validates everything and builds the deformable.
    pub fn build(self) -> Result<Deformable, BuildError> {
        let mesh = match self.source {
            Source::Mesh(m) => m,
            Source::Cuboid {
                half_extents,
                resolution,
            } => Mesh::cuboid(half_extents, resolution, self.cells)?,
        };
        if self.deny_warnings {
            if let Some(w) = mesh.diagnose().into_iter().next() {
                return Err(BuildError::MeshWarning(w));
            }
        }
        let params = Resolved::new(self.material, self.stiffness)?;
        let finite = |name, v: Vector| {
            if v.is_finite() {
                Ok(())
            } else {
                Err(BuildError::InvalidParameter {
                    name,
                    value: (0..DIM)
                        .map(|d| v[d])
                        .find(|c| !c.is_finite())
                        .unwrap_or(Real::NAN),
                    expected: "finite components",
                })
            }
        };
        finite("translation", self.translation)?;
        finite("linvel", self.linvel)?;
        let range = |name, v: Real, lo: Real, hi: Real, expected| {
            if v.is_finite() && v >= lo && v <= hi {
                Ok(())
            } else {
                Err(BuildError::InvalidParameter {
                    name,
                    value: v,
                    expected,
                })
            }
        };
        range(
            "friction",
            self.friction,
            0.0,
            Real::MAX,
            "a non-negative finite coefficient",
        )?;
        range("restitution", self.restitution, 0.0, 1.0, "0 ≤ e ≤ 1")?;
        range(
            "gravity_scale",
            self.gravity_scale,
            -Real::MAX,
            Real::MAX,
            "a finite scale",
        )?;
        range(
            "deformation_damping",
            self.deformation_damping,
            0.0,
            Real::MAX,
            "a non-negative finite rate (1/s)",
        )?;
        let rotation = self.rotation.normalize();
        if !rotation.is_finite() {
            return Err(BuildError::InvalidParameter {
                name: "rotation",
                value: Real::NAN,
                expected: "a finite rotation",
            });
        }

        if let Some(t) = &self.tearing {
            t.validate(self.plasticity.as_ref())?;
            if self.gas.is_some() || !self.chambers.is_empty() {
                return Err(BuildError::TearingWithGas);
            }
        }
        let n = mesh.nodes().len();
        let rest = Rest::new(mesh, self.model, params);
        let mut elements = ModelState::build(
            self.model,
            &rest.mesh,
            &rest.masses,
            &rest.params,
            rotation,
            self.plasticity,
        )?;
        let own = self.gas.into_iter().flat_map(|g| {
            rest.mesh
                .chambers()
                .into_iter()
                .map(move |facets| (facets, g))
        });
        let chambers = own
            .chain(self.chambers)
            .enumerate()
            .map(|(k, (facets, g))| gas::Chamber::new(k, facets, g, &rest.mesh))
            .collect::<Result<Vec<_>, _>>()?;
        elements.set_gas(chambers, n);
        let positions: Vec<Vector> = rest
            .mesh
            .nodes()
            .iter()
            .map(|p| rotation * *p + self.translation)
            .collect();
        let state = State {
            positions,
            velocities: vec![self.linvel; n],
            elements,
        };
        let last = LastStep {
            report: DeformableReport {
                nodes: n,
                elements: rest.mesh.num_cells(),
                min_volume_ratio: 1.0,
                ..Default::default()
            },
            ..Default::default()
        };
        Ok(Deformable {
            step: StepBuffers::new(Accumulator::new(n), false, Real::INFINITY, &state),
            surface: Surface::build(&rest.mesh, &state.positions),
            state,
            rest,
            activation: Activation::awake(self.can_sleep),
            last,
            bindings: Bindings::new(n),
            contact: ContactMaterial {
                friction: self.friction,
                restitution: self.restitution,
                friction_combine_rule: self.friction_combine_rule,
                restitution_combine_rule: self.restitution_combine_rule,
                groups: self.groups,
                ignore_attached_bodies: self.ignore_attached_bodies,
                self_contact: self.self_contact,
            },
            gravity_scale: self.gravity_scale,
            deformation_damping: self.deformation_damping,
            render: None,
            tearing: self.tearing,
            user_data: self.user_data,
        })
    }
}
