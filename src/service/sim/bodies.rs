//! What the daemon knows about each live body beyond the engine's state (name, colour, wire
//! shape), by slot, checked against the body's generation so a reused slot never inherits
//! its predecessor's description.

use crate::physics::{Body, BodyId};
use crate::protocol::Colour;
use crate::service::wire::BodyMeta;

/// Per slot: the generation of the body described, and its description.
#[derive(Clone, Debug, Default)]
pub(crate) struct BodyRegistry {
    slots: Vec<Option<(u32, BodyMeta)>>,
}

impl BodyRegistry {
    /// A registry as a checkpoint stored it.
    pub(crate) fn from_slots(slots: Vec<Option<(u32, BodyMeta)>>) -> BodyRegistry {
        BodyRegistry { slots }
    }

    /// What a checkpoint stores.
    pub(crate) fn slots(&self) -> &[Option<(u32, BodyMeta)>] {
        &self.slots
    }

    /// Describe the body `id`.
    pub(crate) fn set(&mut self, id: BodyId, meta: BodyMeta) {
        let i = id.index() as usize;
        if self.slots.len() <= i {
            self.slots.resize(i + 1, None);
        }
        self.slots[i] = Some((id.generation(), meta));
    }

    /// Forget the body `id` (removed).
    pub(crate) fn remove(&mut self, id: BodyId) {
        if let Some(slot) = self.slots.get_mut(id.index() as usize) {
            *slot = None;
        }
    }

    /// Forget every body (the scene is reloaded).
    pub(crate) fn clear(&mut self) {
        self.slots.clear();
    }

    /// The description of `body`. Every live body has one; should one not, it is shown
    /// nameless and black.
    pub(crate) fn meta_of(&self, body: &Body) -> BodyMeta {
        let id = body.id();
        match self.slots.get(id.index() as usize) {
            Some(Some((generation, m))) if *generation == id.generation() => m.clone(),
            _ => BodyMeta::of(body, String::new(), Colour::new(0, 0, 0)),
        }
    }
}
