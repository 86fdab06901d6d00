//! A generational arena of deformables, like rapier's `RigidBodySet`.

use std::ops::{Index, IndexMut};

use super::body::Deformable;
use super::rapier::data::arena::{Arena, Index as ArenaIndex};

/// The handle of a deformable in a [`DeformableSet`]. A handle of a removed deformable never
/// aliases a later one (generational index).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "serde", serde(transparent))]
#[repr(transparent)]
pub struct DeformableHandle(pub ArenaIndex);

impl DeformableHandle {
    /// The raw `(index, generation)` parts.
    pub fn into_raw_parts(self) -> (u32, u32) {
        self.0.into_raw_parts()
    }

    /// A handle from raw parts.
    pub fn from_raw_parts(index: u32, generation: u32) -> Self {
        DeformableHandle(ArenaIndex::from_raw_parts(index, generation))
    }
}

/// The set of all deformables of a world.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Debug, Default)]
#[cfg_attr(feature = "serde", serde(transparent))]
pub struct DeformableSet {
    arena: Arena<Deformable>,
}

impl DeformableSet {
    /// An empty set.
    pub fn new() -> Self {
        Self::default()
    }

    /// Inserts a deformable and returns its handle.
    pub fn insert(&mut self, deformable: Deformable) -> DeformableHandle {
        DeformableHandle(self.arena.insert(deformable))
    }

    /// Removes a deformable; `None` if the handle is stale.
    pub fn remove(&mut self, handle: DeformableHandle) -> Option<Deformable> {
        self.arena.remove(handle.0)
    }

    /// The deformable, if the handle is live.
    pub fn get(&self, handle: DeformableHandle) -> Option<&Deformable> {
        self.arena.get(handle.0)
    }

    /// The deformable, mutably, if the handle is live.
    pub fn get_mut(&mut self, handle: DeformableHandle) -> Option<&mut Deformable> {
        self.arena.get_mut(handle.0)
    }

    /// Whether the handle is live.
    pub fn contains(&self, handle: DeformableHandle) -> bool {
        self.arena.contains(handle.0)
    }

    /// Number of deformables.
    pub fn len(&self) -> usize {
        self.arena.len()
    }

    /// Whether the set is empty.
    pub fn is_empty(&self) -> bool {
        self.arena.is_empty()
    }

    /// Iterates over `(handle, deformable)` in a fixed order.
    pub fn iter(&self) -> impl Iterator<Item = (DeformableHandle, &Deformable)> {
        self.arena.iter().map(|(i, d)| (DeformableHandle(i), d))
    }

    /// Iterates mutably over `(handle, deformable)` in a fixed order.
    pub fn iter_mut(&mut self) -> impl Iterator<Item = (DeformableHandle, &mut Deformable)> {
        self.arena.iter_mut().map(|(i, d)| (DeformableHandle(i), d))
    }
}

impl Index<DeformableHandle> for DeformableSet {
    type Output = Deformable;

    /// Panics on a stale handle, like rapier's sets; use [`DeformableSet::get`] for a check.
    fn index(&self, handle: DeformableHandle) -> &Deformable {
        &self.arena[handle.0]
    }
}

impl IndexMut<DeformableHandle> for DeformableSet {
    fn index_mut(&mut self, handle: DeformableHandle) -> &mut Deformable {
        &mut self.arena[handle.0]
    }
}
