//! Items binned into the square cells of a plane grid and stored cell by
//! cell (compressed rows, filled by a counting sort): the one binning of the
//! simulator's ray-casting grid (segments, each in every cell it crosses)
//! and the scan matcher's point grid (points, each in its own cell). Each
//! grid decides which cells an item falls in; this keeps them.
//!
//! Written here rather than taken from a crate: it is a counting sort of
//! `(cell, item)` pairs into two flat arrays, which the two grids read in
//! their hot loops without indirection.

/// Items stored cell by cell: cell `c` holds `items()[range(c)]`, in the
/// order the pairs were given.
#[derive(Debug, Clone, Default)]
pub struct Bins {
    /// `start[c]..start[c + 1]` is cell `c`'s stretch of `items`.
    start: Vec<u32>,
    items: Vec<u32>,
    /// Next free slot of each cell while filling (scratch).
    fill: Vec<u32>,
}

impl Bins {
    /// Rebuilds the bins of `cells` cells from `(cell, item)` pairs (every
    /// cell below `cells`), keeping each cell's items in the pairs' order.
    /// The buffers are reused from one build to the next.
    pub fn build(&mut self, cells: usize, pairs: &[(u32, u32)]) {
        self.start.clear();
        self.start.resize(cells + 1, 0);
        for &(c, _) in pairs {
            self.start[c as usize + 1] += 1;
        }
        let mut total = 0;
        for s in &mut self.start {
            total += *s;
            *s = total;
        }
        self.fill.clear();
        self.fill.extend_from_slice(&self.start[..cells]);
        self.items.clear();
        self.items.resize(pairs.len(), 0);
        for &(c, item) in pairs {
            let slot = &mut self.fill[c as usize];
            self.items[*slot as usize] = item;
            *slot += 1;
        }
    }

    /// The slots of cell `c` in [`items`](Self::items).
    #[inline(always)]
    pub fn range(&self, c: usize) -> std::ops::Range<usize> {
        self.start[c] as usize..self.start[c + 1] as usize
    }

    /// The slots of the consecutive cells `lo..=hi`.
    #[inline(always)]
    pub fn span(&self, lo: usize, hi: usize) -> std::ops::Range<usize> {
        self.start[lo] as usize..self.start[hi + 1] as usize
    }

    /// The items of every cell, cell after cell.
    #[inline(always)]
    pub fn items(&self) -> &[u32] {
        &self.items
    }

    /// The items of cell `c`.
    #[inline(always)]
    pub fn cell(&self, c: usize) -> &[u32] {
        &self.items[self.range(c)]
    }

    /// Number of cells.
    pub fn cells(&self) -> usize {
        self.start.len().saturating_sub(1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_cell_holds_its_items_in_the_order_given() {
        let mut b = Bins::default();
        // Item 7 in cells 0 and 3 (a segment crossing two), cell 2 empty.
        let pairs = [(3, 1), (0, 7), (3, 7), (1, 2), (3, 0), (1, 9)];
        b.build(4, &pairs);
        assert_eq!(b.cells(), 4);
        assert_eq!(b.cell(0), &[7]);
        assert_eq!(b.cell(1), &[2, 9]);
        assert!(b.cell(2).is_empty());
        assert_eq!(b.cell(3), &[1, 7, 0]);
        assert_eq!(b.items(), &[7, 2, 9, 1, 7, 0]);
        assert_eq!(b.span(1, 3), 1..6);
        // Rebuilt smaller: nothing of the first build is left.
        b.build(2, &[(1, 4)]);
        assert_eq!((b.cells(), b.cell(0), b.cell(1)), (2, &[][..], &[4][..]));
        b.build(0, &[]);
        assert_eq!((b.cells(), b.items().len()), (0, 0));
    }
}
