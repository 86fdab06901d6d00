//! Contact events between deformables and colliders, and tear events, the rapier way: a trait with a no-op
//! implementation for `()`, and a collector that sends events down a channel.

use std::sync::mpsc::Sender;

use super::rapier::geometry::ColliderHandle;
use super::set::DeformableHandle;

/// A deformable started or stopped touching a collider (any of its nodes or surface facets), or
/// another deformable.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum DeformableContactEvent {
    /// The first step with a contact after a step without.
    Started {
        /// The deformable.
        deformable: DeformableHandle,
        /// The collider.
        collider: ColliderHandle,
    },
    /// The first step without a contact after a step with (also when the collider was
    /// removed). Removing the deformable sends none: its handle is gone with it.
    Stopped {
        /// The deformable.
        deformable: DeformableHandle,
        /// The collider.
        collider: ColliderHandle,
    },
    /// Two deformables touch (a node of either on a facet of the other) for the first step
    /// after a step they did not; sent once per pair, after every body's events.
    PairStarted {
        /// The one with the smaller handle.
        deformable: DeformableHandle,
        /// The other.
        other: DeformableHandle,
    },
    /// Two deformables stopped touching (also when one was removed); sent once per pair.
    PairStopped {
        /// The one with the smaller handle.
        deformable: DeformableHandle,
        /// The other.
        other: DeformableHandle,
    },
}

/// A deformable tore ([`DeformableBuilder::tearing`](super::DeformableBuilder::tearing)): the
/// faces that opened in one step, each as the two cells it joined. Sent after the body's
/// contact events.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct DeformableTearEvent {
    /// The deformable.
    pub deformable: DeformableHandle,
    /// The two cells each side of each face that tore open.
    pub faces: Vec<[u32; 2]>,
}

/// Receives contact and tear events during [`DeformablePipeline::step_with_events`].
///
/// [`DeformablePipeline::step_with_events`]: super::DeformablePipeline::step_with_events
pub trait DeformableEventHandler {
    /// Called once per event, in a deterministic order.
    fn handle_contact_event(&self, event: DeformableContactEvent) {
        let _ = event;
    }

    /// Called once per body that tore in the step, in a deterministic order.
    fn handle_tear_event(&self, event: DeformableTearEvent) {
        let _ = event;
    }
}

impl DeformableEventHandler for () {}

/// Sends every contact event down a channel, and every tear event down another if given one.
#[derive(Clone, Debug)]
pub struct ChannelEventCollector {
    sender: Sender<DeformableContactEvent>,
    tears: Option<Sender<DeformableTearEvent>>,
}

impl ChannelEventCollector {
    /// A collector sending contact events to `sender` (tear events are dropped).
    pub fn new(sender: Sender<DeformableContactEvent>) -> Self {
        ChannelEventCollector {
            sender,
            tears: None,
        }
    }

    /// A collector sending contact events to `sender` and tear events to `tears`.
    pub fn with_tears(
        sender: Sender<DeformableContactEvent>,
        tears: Sender<DeformableTearEvent>,
    ) -> Self {
        ChannelEventCollector {
            sender,
            tears: Some(tears),
        }
    }
}

impl DeformableEventHandler for ChannelEventCollector {
    fn handle_contact_event(&self, event: DeformableContactEvent) {
        // A dropped receiver means nobody listens any more: not an error for the simulation.
        let _ = self.sender.send(event);
    }

    fn handle_tear_event(&self, event: DeformableTearEvent) {
        if let Some(tears) = &self.tears {
            let _ = tears.send(event);
        }
    }
}
