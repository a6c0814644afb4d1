//! A stream's reorder buffer: samples held sorted by stamp (ties in arrival
//! order) until the stream has gone more than a tolerance past them, after
//! which no sample still to come may be earlier (the time-order check of the
//! decoder refuses one that would be).

use std::collections::VecDeque;

use super::source::Item;

/// One stream's samples not yet released.
#[derive(Default)]
pub(crate) struct Reorder {
    pub(crate) items: VecDeque<Item>,
    latest: Option<f64>,
}

impl Reorder {
    /// Holds `item` in stamp order.
    pub(crate) fn insert(&mut self, item: Item) {
        let t = item.stamp();
        let at = self.items.partition_point(|i| i.stamp() <= t);
        self.items.insert(at, item);
        self.latest = Some(self.latest.map_or(t, |l: f64| l.max(t)));
    }

    /// The front item, if no message still to come can be earlier.
    pub(crate) fn pop_ready(&mut self, tolerance: f64) -> Option<Item> {
        let bound = self.latest? - tolerance;
        if self.items.front()?.stamp() < bound {
            self.items.pop_front()
        } else {
            None
        }
    }
}
