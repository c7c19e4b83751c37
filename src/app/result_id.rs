//! Which result a texture or cached number was made from.
//!
//! A result's address alone is not its identity: once the result is dropped, the
//! allocator may hand the same address to the next one (a progressive job's final
//! gradient grid landed where its partial grid had been, and the canvas kept
//! drawing the partial grid's 4 arrows). A `Weak` keeps the allocation reserved
//! while the key lives, so an equal address always means the same result.

use std::sync::{Arc, Weak};

/// The identity of one `Arc`'d result, without keeping its contents alive.
pub struct ResultId<T>(Weak<T>);

impl<T> ResultId<T> {
    pub fn of(result: &Arc<T>) -> Self {
        ResultId(Arc::downgrade(result))
    }

    pub fn is(&self, result: &Arc<T>) -> bool {
        std::ptr::eq(self.0.as_ptr(), Arc::as_ptr(result))
    }
}

impl<T> PartialEq for ResultId<T> {
    fn eq(&self, other: &Self) -> bool {
        Weak::ptr_eq(&self.0, &other.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_new_result_is_never_taken_for_a_dropped_one() {
        // Allocate and drop repeatedly: plain addresses repeat, identities do not.
        let first = Arc::new([7u64; 4]);
        let id = ResultId::of(&first);
        assert!(id.is(&first));
        drop(first);
        for _ in 0..1000 {
            let next = Arc::new([8u64; 4]);
            assert!(!id.is(&next));
            assert!(ResultId::of(&next) != id);
        }
    }
}
