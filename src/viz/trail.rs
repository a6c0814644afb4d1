//! Things left behind along a run, shown up to the time cursor by a viewer
//! that draws, per entity, only the latest row at the cursor (Rerun's
//! latest-at). Logging every item again at every row would grow with the
//! square of the run; instead the items kept so far are split into
//! power-of-two blocks, the binary digits of their count, and the block of
//! size 2^L lives on its own entity, level L. Adding the n-th item replaces
//! level tz(n) (trailing zeros of n) by the last 2^tz(n) items and empties
//! the levels below it; at every cursor the latest rows of all levels
//! together are exactly the items kept so far. Each item is logged about
//! log2(n)/2 times, in ⌊log2 cap⌋ + 1 entities.
//!
//! At most `cap` items are kept: when one more arrives, every other kept item
//! is dropped and from then on only every 2k-th item is taken (the stride
//! doubles), the levels being logged again from the thinned items.

/// One level's new content (empty: nothing shown at that level from now).
#[derive(Debug, Clone, PartialEq)]
pub struct TrailUpdate<T> {
    /// The level (its block holds 2^level items when not empty).
    pub level: usize,
    /// The items shown at that level from now on.
    pub items: Vec<T>,
}

/// The items kept along a run and the rows that show them (module doc).
#[derive(Debug, Clone)]
pub struct Trail<T> {
    kept: Vec<T>,
    stride: usize,
    seen: usize,
    cap: usize,
}

impl<T: Clone> Trail<T> {
    /// A trail keeping at most `cap` items (rounded up to a power of two ≥ 2).
    pub fn new(cap: usize) -> Self {
        Self {
            kept: Vec::new(),
            stride: 1,
            seen: 0,
            cap: cap.max(2).next_power_of_two(),
        }
    }

    /// How many level entities the trail may use: ⌊log2 cap⌋ + 1.
    pub fn levels(&self) -> usize {
        self.cap.trailing_zeros() as usize + 1
    }

    /// Every k-th item offered is kept (1 until the cap was reached).
    pub fn stride(&self) -> usize {
        self.stride
    }

    /// Items offered so far.
    pub fn seen(&self) -> usize {
        self.seen
    }

    /// Items shown now.
    pub fn kept(&self) -> usize {
        self.kept.len()
    }

    /// Offers the next item; returns the levels whose rows change (none when
    /// the item is skipped by the stride).
    pub fn push(&mut self, item: T) -> Vec<TrailUpdate<T>> {
        let take = self.seen.is_multiple_of(self.stride);
        self.seen += 1;
        if !take {
            return Vec::new();
        }
        self.kept.push(item);
        if self.kept.len() > self.cap {
            // cap is even, so the item just kept (index cap) stays.
            self.kept = self.kept.iter().step_by(2).cloned().collect();
            self.stride *= 2;
            return self.all_levels();
        }
        let n = self.kept.len();
        let top = n.trailing_zeros() as usize;
        let mut ups: Vec<TrailUpdate<T>> = (0..top)
            .map(|level| TrailUpdate {
                level,
                items: Vec::new(),
            })
            .collect();
        ups.push(TrailUpdate {
            level: top,
            items: self.kept[n - (1 << top)..].to_vec(),
        });
        ups
    }

    /// Every level's content for the kept items: the binary digits of their
    /// count, the largest block holding the earliest items.
    fn all_levels(&self) -> Vec<TrailUpdate<T>> {
        let n = self.kept.len();
        let mut start = 0;
        let mut ups = Vec::with_capacity(self.levels());
        for level in (0..self.levels()).rev() {
            let items = if n & (1 << level) != 0 {
                start += 1 << level;
                self.kept[start - (1 << level)..start].to_vec()
            } else {
                Vec::new()
            };
            ups.push(TrailUpdate { level, items });
        }
        ups
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    /// What a latest-at viewer shows after applying `ups` in order.
    fn apply(shown: &mut BTreeMap<usize, Vec<usize>>, ups: Vec<TrailUpdate<usize>>) {
        for u in ups {
            shown.insert(u.level, u.items);
        }
    }

    fn union(shown: &BTreeMap<usize, Vec<usize>>) -> Vec<usize> {
        let mut all: Vec<usize> = shown.values().flatten().copied().collect();
        all.sort_unstable();
        all
    }

    #[test]
    fn the_levels_show_every_item_so_far() {
        let mut t = Trail::new(1 << 10);
        let mut shown = BTreeMap::new();
        let mut logged = 0;
        for i in 0..1000 {
            let ups = t.push(i);
            logged += ups.iter().map(|u| u.items.len()).sum::<usize>();
            assert!(ups.iter().all(|u| u.level < t.levels()));
            apply(&mut shown, ups);
            assert_eq!(union(&shown), (0..=i).collect::<Vec<_>>(), "after {i}");
        }
        // About n log2(n) / 2 items logged in all, not n² / 2.
        assert!(logged < 1000 * 10 / 2 + 1000, "{logged}");
        assert_eq!(t.stride(), 1);
    }

    #[test]
    fn past_the_cap_every_other_item_is_dropped() {
        let mut t = Trail::new(8);
        let mut shown = BTreeMap::new();
        for i in 0..40 {
            apply(&mut shown, t.push(i));
            let all = union(&shown);
            assert!(all.len() <= 8, "{all:?}");
            // What is shown is evenly spaced from the first item on.
            let s = t.stride();
            assert!(all.iter().enumerate().all(|(k, &v)| v == k * s), "{all:?}");
            assert_eq!(all.len(), i / s + 1);
        }
        assert_eq!(t.stride(), 8);
        assert_eq!(t.seen(), 40);
        assert_eq!(t.kept(), 5);
    }
}
