//! What each step reports (`docs/ARCHITECTURE.md` §8).

use super::math::Real;
use super::set::DeformableHandle;

/// Diagnostics of one deformable over the last step.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DeformableReport {
    /// Kinetic energy `Σ ½ m v²` at the end of the step, J.
    pub kinetic_energy: Real,
    /// Elastic energy stored in the elements at the end of the step, J.
    pub elastic_energy: Real,
    /// Gravitational potential energy `−Σ m g·x` (zero at the origin), J.
    pub gravity_energy: Real,
    /// Elastic energy released by plastic flow at the end of the step (the stored energy at
    /// the step's end positions before the flow, less after), J: energy the body dissipated.
    pub plastic_dissipation: Real,
    /// Faces torn open at the end of the step ([`Deformable::last_tears`](super::Deformable::last_tears)).
    #[cfg_attr(feature = "serde", serde(default))]
    pub torn_faces: usize,
    /// Number of nodes.
    pub nodes: usize,
    /// Number of cells.
    pub elements: usize,
    /// Cells whose quality (volume ratio; smallest corner ratio for boxes) is ≤ 0 at the end of
    /// the step: collapsed or inverted.
    pub inverted_elements: usize,
    /// Smallest cell quality (volume ratio `V/V0`) at the end of the step.
    pub min_volume_ratio: Real,
    /// Deepest node penetration into any collider at the end of the step, m.
    pub max_penetration: Real,
    /// Surface nodes that touched a collider during the step.
    pub contacts: usize,
    /// Facet contacts (a rigid feature pushing a surface facet) summed over the substeps.
    pub facet_contacts: usize,
    /// Contacts of its surface nodes with other deformables' surface facets, over the step's
    /// substeps.
    #[cfg_attr(feature = "serde", serde(default))]
    pub soft_contacts: usize,
    /// Contacts of its surface nodes with its own surface facets (self contact), over the
    /// step's substeps.
    #[cfg_attr(feature = "serde", serde(default))]
    pub self_contacts: usize,
    /// Nodes bound to rigid bodies.
    pub attached_nodes: usize,
    /// Bindings dropped at the start of the step because their body was removed.
    pub detached: usize,
    /// Substeps taken.
    pub substeps: usize,
    /// Whether the step was implicit (one solve, `substeps` 1) rather than explicit substeps
    /// ([`Integrator::Auto`](super::Integrator::Auto) chooses per body).
    #[cfg_attr(feature = "serde", serde(default))]
    pub implicit: bool,
    /// Substeps whose size the edge-repulsion crossing limiter chose (tighter than the
    /// stability bound).
    pub limiter_substeps: usize,
    /// Whether the substep cap ([`PipelineSettings::max_substeps`]) was reached; the rest of
    /// the step was then skipped for this body ([`DeformableReport::lost_time`]).
    ///
    /// [`PipelineSettings::max_substeps`]: super::PipelineSettings::max_substeps
    pub substep_cap_hit: bool,
    /// Simulated time skipped because the substep cap was reached, s.
    pub lost_time: Real,
    /// Whether the state turned non-finite (or beyond 1e8 in position or velocity) during this
    /// step: the body was rolled back to the start of the step (and the rigid bodies it pushed
    /// during it too) and frozen.
    pub non_finite: bool,
    /// Whether a cell grew past [`PipelineSettings::max_stretch`] during this step (a
    /// blow-up while still finite): the body was rolled back to the start of the step, the
    /// rigid bodies it pushed during it were given their state back, and it was frozen.
    ///
    /// [`PipelineSettings::max_stretch`]: super::PipelineSettings::max_stretch
    pub exploded: bool,
    /// Whether the body is frozen (not simulated).
    pub frozen: bool,
    /// Whether bones it is bound to jumped this step and the body was carried along with them
    /// rigidly ([`PipelineSettings::teleport_speed`](super::PipelineSettings::teleport_speed)).
    pub teleported: bool,
    /// Whether the body is asleep (not simulated this step; see
    /// [`Deformable::is_sleeping`](super::Deformable::is_sleeping)). The other fields keep
    /// the values of its last simulated step, but `substeps` and the times, which are zero.
    pub sleeping: bool,
    /// Wall time spent on element forces, s.
    pub time_forces: f64,
    /// Wall time spent on contacts (broad phase and node tests), s.
    pub time_contacts: f64,
    /// Wall time spent on integration and diagnostics, s.
    pub time_integrate: f64,
}

/// Diagnostics of one pipeline step.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Debug, Default)]
pub struct StepReport {
    /// The step's duration, s.
    pub dt: Real,
    /// Per deformable, in set order.
    pub deformables: Vec<(DeformableHandle, DeformableReport)>,
    /// Wall time of the whole step, s.
    pub wall_time: f64,
    /// Wall time of finding the deformables that may touch each other and grouping them (the
    /// broad phase between deformables), s.
    #[cfg_attr(feature = "serde", serde(default))]
    pub pairs_time: f64,
}

impl StepReport {
    /// The report of one deformable, if it was stepped.
    pub fn get(&self, handle: DeformableHandle) -> Option<&DeformableReport> {
        self.deformables
            .iter()
            .find(|(h, _)| *h == handle)
            .map(|(_, r)| r)
    }

    /// Largest substep count over all deformables.
    pub fn max_substeps(&self) -> usize {
        self.deformables
            .iter()
            .map(|(_, r)| r.substeps)
            .max()
            .unwrap_or(0)
    }
}
