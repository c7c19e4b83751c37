//! Undo and redo of a document's states, shared by the 2D and 3D documents: a
//! bounded stack of earlier states and one of undone ones, and gestures — edits
//! with the same key in a row (one drag, one slider) make one undo step until the
//! gesture ends.

/// Undo steps kept.
const UNDO_LIMIT: usize = 256;

pub struct History<T> {
    undo: Vec<T>,
    redo: Vec<T>,
    gesture: Option<String>,
}

impl<T> Default for History<T> {
    fn default() -> Self {
        History {
            undo: Vec::new(),
            redo: Vec::new(),
            gesture: None,
        }
    }
}

impl<T> History<T> {
    /// Remember `current` (the state before a change) as an undo step, dropping
    /// what was undone.
    pub fn push(&mut self, current: T) {
        self.undo.push(current);
        if self.undo.len() > UNDO_LIMIT {
            self.undo.remove(0);
        }
        self.redo.clear();
    }

    /// An edit with `key` is about to replace `current`: a new undo step unless it
    /// continues the gesture of the same key.
    pub fn edit(&mut self, key: &str, current: impl FnOnce() -> T) {
        if self.gesture.as_deref() != Some(key) {
            self.push(current());
            self.gesture = Some(key.to_string());
        }
    }

    /// The current gesture ended: the next edit is a new undo step.
    pub fn end_gesture(&mut self) {
        self.gesture = None;
    }

    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }

    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }

    /// The state to go back to, with `current` kept for redo.
    pub fn undo(&mut self, current: T) -> Option<T> {
        self.end_gesture();
        let prev = self.undo.pop()?;
        self.redo.push(current);
        Some(prev)
    }

    /// The undone state to go forward to, with `current` kept for undo.
    pub fn redo(&mut self, current: T) -> Option<T> {
        self.end_gesture();
        let next = self.redo.pop()?;
        self.undo.push(current);
        Some(next)
    }
}

#[cfg(test)]
mod tests {
    use super::History;

    #[test]
    fn gestures_make_one_step_and_undo_redo_round_trip() {
        let mut h = History::default();
        let mut state = 0;
        for v in [1, 2, 3] {
            h.edit("drag", || state);
            state = v;
        }
        h.end_gesture();
        h.edit("other", || state);
        state = 10;
        assert_eq!(h.undo(state), Some(3));
        assert_eq!(h.undo(3), Some(0), "the drag was one step");
        assert!(!h.can_undo() && h.undo(0).is_none());
        assert_eq!(h.redo(0), Some(3));
        assert_eq!(h.redo(3), Some(10));
        h.push(10);
        assert!(!h.can_redo(), "a new step drops what was undone");
    }
}
