//! Contact events between deformables and colliders, the rapier way: a trait with a no-op
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

/// Receives contact events during [`DeformablePipeline::step_with_events`].
///
/// [`DeformablePipeline::step_with_events`]: super::DeformablePipeline::step_with_events
pub trait DeformableEventHandler {
    /// Called once per event, in a deterministic order.
    fn handle_contact_event(&self, event: DeformableContactEvent) {
        let _ = event;
    }
}

impl DeformableEventHandler for () {}

/// Sends every event down a channel.
#[derive(Clone, Debug)]
pub struct ChannelEventCollector {
    sender: Sender<DeformableContactEvent>,
}

impl ChannelEventCollector {
    /// A collector sending to `sender`.
    pub fn new(sender: Sender<DeformableContactEvent>) -> Self {
        ChannelEventCollector { sender }
    }
}

impl DeformableEventHandler for ChannelEventCollector {
    fn handle_contact_event(&self, event: DeformableContactEvent) {
        // A dropped receiver means nobody listens any more: not an error for the simulation.
        let _ = self.sender.send(event);
    }
}
